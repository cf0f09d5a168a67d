"""A moving mesh collider's vertices and edges as supports inside the implicit step (collider_supports.cpp,
docs/model.md section 6.3 "Supports in the solve"): each term's force is minus the gradient of its energy, its
stiffness the derivative of its force, and a cloth triangle resting on a collider vertex settles where the
penalty carries its weight."""

import numpy as np
import pytest
import trimesh

import wetcloth
from wetcloth import _core
from wetcloth.scene import load_scene

STIFFNESS, DISTANCE, SCALE = 5000.0, 1e-3, 4e-6  # N/m, m, s^2


#: Two terms on 5 particles, a vertex-triangle one (weights -u, -v, -w) and an edge-edge one (two cloth
#: points): their points (SUPPORT_POINTS each, -1 unused), weights, normals and offsets (m).
TWO_TERMS = (np.array([[0, 1, 2, -1], [3, 4, -1, -1]], dtype=np.int64),
             np.array([[-0.2, -0.3, -0.5, 0.0], [0.6, 0.4, 0.0, 0.0]]),
             np.array([[0.36, 0.48, 0.8], [0.0, 0.6, -0.8]]), np.array([0.11, -0.07]))


def _terms(pos, p=None, terms=TWO_TERMS):
    """The terms (TWO_TERMS) at pos: their energy (J), forces (3, n), diagonal blocks (6, n) and the rest of
    their stiffness times p (3, n), the blocks and product times SCALE."""
    n = pos.shape[1]
    force, blocks, product = np.zeros((3, n)), np.zeros((6, n)), np.zeros((3, n))
    energy = _core.support_terms(*terms, STIFFNESS, DISTANCE, SCALE, pos, np.ones(n),
                                 np.zeros((3, n)) if p is None else p, force, blocks, product)
    return energy, force, blocks, product


def _stiffness_against_force_differences(pos, p, terms=TWO_TERMS):
    """The terms' whole stiffness times SCALE applied to p (their blocks and product), and central differences
    of their forces along p times SCALE (steps of 1e-8 m)."""
    _, _, blocks, product = _terms(pos, p, terms)
    xx, yy, zz, xy, xz, yz = blocks
    matrix_times_p = product + np.array([xx * p[0] + xy * p[1] + xz * p[2], xy * p[0] + yy * p[1] + yz * p[2],
                                         xz * p[0] + yz * p[1] + zz * p[2]])
    step = 1e-8
    difference = -(_terms(pos + step * p, terms=terms)[1] - _terms(pos - step * p, terms=terms)[1]) / (2 * step)
    return matrix_times_p, difference * SCALE


def _pressing_place():
    """Positions (3, 5) where both terms press by about a tenth of DISTANCE (their gaps 0.9 DISTANCE)."""
    rng = np.random.default_rng(3)
    pos = rng.normal(scale=0.05, size=(3, 5))
    normals = np.array([[0.36, 0.48, 0.8], [0.0, 0.6, -0.8]])
    # shift the first point of each term along its normal until its gap is 0.9 DISTANCE
    for term, (i, w, offset) in enumerate(((0, -0.2, 0.11), (3, 0.6, -0.07))):
        points = ([0, 1, 2], [3, 4])[term]
        weights = ([-0.2, -0.3, -0.5], [0.6, 0.4])[term]
        gap = offset + sum(wk * normals[term] @ pos[:, k] for k, wk in zip(points, weights))
        pos[:, i] += (0.9 * DISTANCE - gap) / w * normals[term]
    return pos


def _central_differences(function, x, step):
    """The central differences (function(x + step e) - function(x - step e)) / (2 step) of a scalar function
    for each entry e of x, shaped as x."""
    difference = np.zeros_like(x)
    for index in np.ndindex(x.shape):
        up, down = x.copy(), x.copy()
        up[index] += step
        down[index] -= step
        difference[index] = (function(up) - function(down)) / (2 * step)
    return difference


def test_the_force_is_minus_the_gradient_of_the_energy():
    """Central differences of the energy (steps of 1e-7 m, the penalty quadratic: exact but for rounding,
    about 1e-9 of the force) against the forces at a place where both terms press."""
    pos = _pressing_place()
    energy, force, _, _ = _terms(pos)
    assert energy > 0.0 and np.abs(force).max() > 0.1
    difference = -_central_differences(lambda x: _terms(x)[0], pos, 1e-7)
    np.testing.assert_allclose(difference, force, rtol=0, atol=1e-6 * np.abs(force).max())


def test_the_stiffness_is_the_derivative_of_the_force():
    """The blocks and the product (the whole stiffness times SCALE applied to a direction p) against central
    differences of the forces along p (the force linear while the terms press: exact but for rounding)."""
    pos = _pressing_place()
    p = np.random.default_rng(5).normal(size=pos.shape)
    matrix_times_p, difference = _stiffness_against_force_differences(pos, p)
    assert np.abs(matrix_times_p).max() > 0.0
    np.testing.assert_allclose(matrix_times_p, difference, rtol=0, atol=1e-6 * np.abs(difference).max())
    # off the diagonal blocks: the product is zero at a particle whose term has no other point moving
    product = _terms(pos, p)[3]
    assert np.abs(product[:, 3]).max() > 0.0 and np.abs(product[:, 0]).max() > 0.0


def test_a_pair_of_the_cloth_with_itself_is_a_term_of_four_points():
    """A point of the cloth over one of its triangles (self_contact/supports.hpp: weights 1, -u, -v, -w, offset
    DISTANCE - thickness so that it presses below the thickness): its force is minus the gradient of its energy
    and its stiffness the derivative of its force (central differences, as above), and its forces sum to zero,
    as the pair's own push must (momentum: the weights sum to 0)."""
    assert _core.SUPPORT_POINTS == 4
    thickness = 2e-3
    weights = np.array([1.0, -0.2, -0.3, -0.5])
    normal = np.array([0.36, 0.48, 0.8])
    term = (np.array([[0, 1, 2, 3]], dtype=np.int64), weights[None], normal[None], np.array([DISTANCE - thickness]))
    pos = np.random.default_rng(13).normal(scale=0.05, size=(3, 4))
    pos[:, 0] += (0.8 * thickness - normal @ pos @ weights) * normal  # the point 0.8 thickness over the triangle
    energy, force, _, _ = _terms(pos, terms=term)
    assert energy == pytest.approx(0.5 * STIFFNESS * (0.2 * thickness) ** 2, rel=1e-9)
    np.testing.assert_allclose(force.sum(axis=1), 0.0, rtol=0, atol=1e-12 * np.abs(force).max())
    difference = -_central_differences(lambda x: _terms(x, terms=term)[0], pos, 1e-7)
    np.testing.assert_allclose(difference, force, rtol=0, atol=1e-6 * np.abs(force).max())
    p = np.random.default_rng(17).normal(size=pos.shape)
    matrix_times_p, derivative = _stiffness_against_force_differences(pos, p, term)
    np.testing.assert_allclose(matrix_times_p, derivative, rtol=0, atol=1e-6 * np.abs(derivative).max())


def test_a_term_met_within_the_step_takes_the_normal_force_that_lands_its_pair():
    """A term with friction met within a fixed step (lag_arriving_normal_force) takes the normal force that stops
    its pair's approach within the step and holds its weight, at most its penalty's: N = m (a / h + g n_z), m the
    pair's mass along its gap, 1 / sum_k w_k^2 / m_k, what a force on the gap shared as the weights share it
    accelerates.  Two terms, each moving up at 0.5 m/s onto its normal (0, 0, 1) and sliding at 1 m/s: a cloth
    triangle under a collider's vertex (weights -0.2, -0.3, -0.5 on masses of 10, 20, 30 g) and a term of four
    points, as a cloth point over a cloth triangle would be (weights 1, -0.2, -0.3, -0.5, 10 g each; the cloth's
    own pairs themselves take no friction on arrival), both 1 mm into a stiff
    penalty (1e6 N/m: not the bound).  On the old code the pair's mass was sum_k w_k m_k: -23 g for the first
    (a negative normal force, friction pushing the slide along), 0 for the second."""
    h, normal = 1 / 30, np.array([0.0, 0.0, 1.0])
    points = np.array([[0, 1, 2, -1], [3, 4, 5, 6]], dtype=np.int64)
    weights = np.array([[-0.2, -0.3, -0.5, 0.0], [1.0, -0.2, -0.3, -0.5]])
    mass = np.array([0.01, 0.02, 0.03, 0.01, 0.01, 0.01, 0.01])
    pos = np.random.default_rng(19).normal(scale=0.05, size=(3, 7))
    offsets = np.array([DISTANCE - 1e-3 - normal @ pos[:, p[p >= 0]] @ w[p >= 0] for p, w in zip(points, weights)])
    start_vel = np.zeros((3, 7))
    start_vel[2, :3] = 0.5  # the triangle up onto the vertex above it
    start_vel[2, 3] = -0.5  # the point down onto the triangle below it
    vel = start_vel + np.array([[1.0], [0.0], [0.0]]) * (np.arange(7) % 2)  # a slide across the normal
    forces = _core.support_arrivals(points, weights, np.array([normal, normal]), offsets, 1e6, DISTANCE,
                                    np.array([0.5, 0.5]), mass, start_vel, pos, vel, h)
    for term, force in enumerate(forces):
        present = points[term] >= 0
        w, m = weights[term][present], mass[points[term][present]]
        approach = -(w * start_vel[2, points[term][present]]).sum()
        assert approach == pytest.approx(0.5)
        expected = (approach / h + 9.81) / (w**2 / m).sum()
        assert force == pytest.approx(expected, rel=1e-3), (term, force, expected)


def test_a_released_term_has_no_force_energy_or_stiffness():
    """Where each gap is above DISTANCE the terms are off: no energy, force, blocks or product."""
    pos = _pressing_place()
    pos[:, 0] -= 0.02 * np.array([0.36, 0.48, 0.8]) / 0.2  # the triangle away from the vertex
    pos[:, 3] += 0.02 * np.array([0.0, 0.6, -0.8]) / 0.6
    energy, force, blocks, product = _terms(pos, np.ones(pos.shape))
    assert energy == 0.0 and not force.any() and not blocks.any() and not product.any()


def _spike_scene(tmp_path, friction, keys, **fields):
    """A cloth of one equilateral triangle (0.1 m sides) lying flat 1.5 mm up, its centroid over the tip of a
    thin spike (a mesh collider of the given friction, its tip at 1 mm below the origin, moved by keys)."""
    side = 0.1
    r = side / np.sqrt(3)
    corners = [(r * np.cos(a), r * np.sin(a), 0.0) for a in np.pi / 2 + np.arange(3) * 2 * np.pi / 3]
    cloth = tmp_path / "triangle.obj"
    cloth.write_text("".join("v %.17g %.17g %.17g\n" % c for c in corners) + "f 1 2 3\n")
    spike = trimesh.Trimesh(vertices=[[0, 0, 0], [0.005, 0, -0.05], [-0.0025, 0.0043, -0.05], [-0.0025, -0.0043, -0.05]],
                            faces=[[0, 2, 1], [0, 3, 2], [0, 1, 3], [1, 2, 3]])
    spike.fix_normals()
    spike.export(tmp_path / "spike.stl")
    collider = {"shape": "mesh", "file": str(tmp_path / "spike.stl"), "z": -0.001, "friction": friction}
    return load_scene(cloth_mesh=str(cloth), initial_tilt=0.0, initial_height=0.0015, water_level=-1.0,
                      floor_level=-1.0, colliders=(collider,), collider_keys=keys, **fields)


def test_a_triangle_rests_on_a_keyed_spikes_tip_at_the_penalty_height(tmp_path):
    """A cloth of one equilateral triangle (0.1 m sides) lying flat, its centroid over the tip of a thin
    frictionless spike (a mesh collider keyed to rise 1 mm in 0.1 s, then still): the tip supports it at its
    centroid (weights 1/3), so it settles where the penalty carries its weight, the centroid SUPPORT_DISTANCE
    thickness / 2 less M g / k above the tip (k SUPPORT_STIFFNESS times the stiffest spring), within the
    Newton tolerance (measured 1e-13 m: at rest Newton's solution is the equilibrium).  On the old code the
    edges' pass pushed the triangle back after every step and it rested at its distance, 0.1 mm, in 2091 steps
    (39 now).  (The normal term alone: friction has the tests below.)"""
    scene = _spike_scene(tmp_path, 0.0, (dict(collider=1, time=0.1, z=0.001),))
    sim = wetcloth.Simulation(scene)
    sim.advance(1.0)
    weight = sim.model.dry_mass.sum() * 9.81
    k = _core.SUPPORT_STIFFNESS * sim.model.cloth.pair_stiffness.max()
    expected = _core.SUPPORT_DISTANCE * 0.5 * scene.thickness - weight / k
    assert weight / k > 1e-7  # the compression the test resolves
    pos = sim.state.pos
    assert abs(pos[2].mean() - expected) <= sim._control.newton_tolerance
    assert np.abs(pos[:2].mean(axis=1)).max() < 1e-9  # still over the tip


FRICTIONS = np.array([0.4, 0.7])
NORMAL_FORCES = np.array([0.5, 0.3])  # N: each term's normal force at the step's start (lagged)


def _friction_terms(pos, vel, collider_velocities, p=None, scale=3e-3, self_pairs=False):
    """The two terms of _terms with friction (FRICTIONS, their normal forces NORMAL_FORCES) against collider
    points moving at collider_velocities (2, 3) m/s, at pos and vel (3, n): their dissipation (W), friction
    forces (3, n: the penalty's forces taken off), and their friction's velocity stiffness times scale (s):
    diagonal blocks (6, n) and the rest times p (3, n).  self_pairs: the terms as pairs of the cloth with itself."""
    n = pos.shape[1]
    force, blocks, product = np.zeros((3, n)), np.zeros((6, n)), np.zeros((3, n))
    dissipation = _core.support_friction_terms(*TWO_TERMS, STIFFNESS, DISTANCE, FRICTIONS,
                                               NORMAL_FORCES, collider_velocities, scale, pos, vel, np.ones(n),
                                               np.zeros((3, n)) if p is None else p, force, blocks, product,
                                               self_pairs=self_pairs)
    return dissipation, force - _terms(pos)[1], blocks, product


def _sliding_and_sticking(pos, slip_speed=_core.SUPPORT_SLIP_SPEED):
    """Velocities (3, 5) and collider velocities (2, 3) at which the first term slips at 0.3 m/s (Coulomb's
    constant force) and the second at 0.4 slip_speed (the smoothed stick), each across its normal."""
    rng = np.random.default_rng(7)
    vel = rng.normal(scale=0.2, size=pos.shape)
    normals = np.array([[0.36, 0.48, 0.8], [0.0, 0.6, -0.8]])
    cloth = [vel[:, :3] @ np.array([-0.2, -0.3, -0.5]), vel[:, 3:] @ np.array([0.6, 0.4])]
    collider_velocities = np.zeros((2, 3))
    for term, slip in enumerate((0.3, 0.4 * slip_speed)):
        across = np.cross(normals[term], [1.0, 0.0, 0.0])
        across /= np.linalg.norm(across)
        collider_velocities[term] = slip * across + 0.05 * normals[term] - cloth[term]
    return vel, collider_velocities


@pytest.mark.parametrize("self_pairs", [False, True])
def test_the_friction_is_minus_the_velocity_gradient_of_its_dissipation(self_pairs):
    """Central differences of the dissipation potential D = mu N f0(|u_t|) (N fixed) in each velocity (steps
    of 1e-8 m/s, f0 a cubic below the slip speed and |u_t| above, both smooth where the terms slip: exact but
    for rounding and the step's square, about 1e-7 of the force) against the friction forces, one term sliding
    and one sticking; as a collider's terms and as pairs of the cloth with itself (their own slip speed).  On the
    old code there is no friction (support_friction_terms is missing)."""
    pos = _pressing_place()
    vel, collider_velocities = _sliding_and_sticking(
        pos, _core.SELF_SLIP_SPEED if self_pairs else _core.SUPPORT_SLIP_SPEED)
    dissipation, force, _, _ = _friction_terms(pos, vel, collider_velocities, self_pairs=self_pairs)
    assert dissipation > 0.0 and np.abs(force[:, :3]).max() > 0.05 and np.abs(force[:, 3:]).max() > 0.01
    difference = -_central_differences(
        lambda v: _friction_terms(pos, v, collider_velocities, self_pairs=self_pairs)[0], vel, 1e-8)
    np.testing.assert_allclose(difference, force, rtol=0, atol=1e-6 * np.abs(force).max())


def test_the_friction_force_is_coulombs_across_the_normal():
    """The sliding term's friction on the cloth, summed, is mu N against its slip, across its normal, within
    rounding; the sticking term's is mu N f1(0.4 eps), across its normal too."""
    pos = _pressing_place()
    vel, collider_velocities = _sliding_and_sticking(pos)
    _, force, _, _ = _friction_terms(pos, vel, collider_velocities)
    normals = np.array([[0.36, 0.48, 0.8], [0.0, 0.6, -0.8]])
    on_cloth = [force[:, :3].sum(axis=1), force[:, 3:].sum(axis=1)]
    across = np.cross(normals[0], [1.0, 0.0, 0.0])
    across /= np.linalg.norm(across)
    # the first term's slip (collider minus cloth point) is along `across`: its friction pulls the cloth along it
    np.testing.assert_allclose(on_cloth[0], FRICTIONS[0] * NORMAL_FORCES[0] * across, rtol=0, atol=1e-12)
    stick = np.linalg.norm(on_cloth[1])
    assert abs(on_cloth[1] @ normals[1]) <= 1e-12
    # below the slip speed f1(y) = 2 y / eps - y^2 / eps^2: 0.64 at y = 0.4 eps
    assert abs(stick - 0.64 * FRICTIONS[1] * NORMAL_FORCES[1]) <= 1e-12


def test_layers_stick_ten_times_slower_than_on_a_collider():
    """The cloth's pairs with itself stick below SELF_SLIP_SPEED, 0.1 mm/s, a tenth of a collider's slip speed, so
    that layers held within friction on layers creep at most that fast (at 1 mm/s a crumpled pile crept at 1-7
    mm/s and never fell asleep; docs/model.md 6.3, "Friction on the supports").  Slipping at 0.4 of it, a self
    pair's friction is mu N f1(0.4 eps) = 0.64 mu N; a collider's term at the same slip, 0.04 of its slip speed,
    only 2 (0.04) - 0.04^2 = 0.0784 mu N."""
    assert _core.SELF_SLIP_SPEED == pytest.approx(0.1 * _core.SUPPORT_SLIP_SPEED, rel=1e-12)
    pos = _pressing_place()
    vel, collider_velocities = _sliding_and_sticking(pos, _core.SELF_SLIP_SPEED)
    normal = np.array([0.0, 0.6, -0.8])
    for self_pairs, f1 in ((True, 0.64), (False, 0.0784)):
        _, force, _, _ = _friction_terms(pos, vel, collider_velocities, self_pairs=self_pairs)
        on_cloth = force[:, 3:].sum(axis=1)
        assert abs(on_cloth @ normal) <= 1e-12
        assert abs(np.linalg.norm(on_cloth) - f1 * FRICTIONS[1] * NORMAL_FORCES[1]) <= 1e-12, self_pairs


def test_the_friction_stiffness_is_the_derivative_of_its_force():
    """The friction's blocks and product (its whole velocity stiffness times the scale, applied to a direction
    p) against central differences of the friction forces along p in velocity (steps of 1e-9 m/s: exact but
    for rounding and the step's square)."""
    pos = _pressing_place()
    vel, collider_velocities = _sliding_and_sticking(pos)
    p = np.random.default_rng(11).normal(size=pos.shape)
    scale = 3e-3
    _, _, blocks, product = _friction_terms(pos, vel, collider_velocities, p, scale)
    xx, yy, zz, xy, xz, yz = blocks
    matrix_times_p = product + np.array([xx * p[0] + xy * p[1] + xz * p[2], xy * p[0] + yy * p[1] + yz * p[2],
                                         xz * p[0] + yz * p[1] + zz * p[2]])
    step = 1e-9
    difference = -(_friction_terms(pos, vel + step * p, collider_velocities)[1]
                   - _friction_terms(pos, vel - step * p, collider_velocities)[1]) / (2 * step) * scale
    assert np.abs(product).max() > 0.0
    np.testing.assert_allclose(matrix_times_p, difference, rtol=0, atol=1e-6 * np.abs(difference).max())


SLIDE_START, SLIDE_SPEED, MU = 0.2, 0.05, 0.5  # s, m/s, -
GRAVITY = 9.81


def _slid(tmp_path, friction, times, **fields):
    """The triangle on the spike's tip (risen 1 mm by 0.1 s, still to SLIDE_START), the tip then moving along x
    at SLIDE_SPEED (air off, so that friction alone moves the cloth; tolerance 5e-7): the centroid's x
    displacement from SLIDE_START (m), its x velocity (m/s), the largest tilt of the triangle (rad) and the
    steps from SLIDE_START, at SLIDE_START + each of times (s); the step's allowed error (m).  fields: the
    scene's others."""
    duration = 0.06
    keys = (dict(collider=1, time=0.1, z=0.001), dict(collider=1, time=SLIDE_START, z=0.001),
            dict(collider=1, time=SLIDE_START + duration, x=SLIDE_SPEED * duration, z=0.001))
    sim = wetcloth.Simulation(_spike_scene(tmp_path, friction, keys, air_density=0.0, tolerance=5e-7,
                                           **fields))
    sim.advance(SLIDE_START)
    start, steps = sim.state.pos[0].mean(), sim.steps
    rows = []
    for t in times:
        sim.advance(SLIDE_START + t - sim.time)
        pos = sim.state.pos
        tilt = np.ptp(pos[2]) / (0.1 * np.sqrt(3) / 2)  # the corners' heights over the triangle's height
        rows.append((pos[0].mean() - start, sim.state.vel[0].mean(), tilt, sim.steps - steps))
    return rows, sim._control.allowed


def test_a_spike_moving_sideways_drags_the_triangle_by_coulombs_law(tmp_path):
    """The tip moves sideways at v = SLIDE_SPEED under the resting triangle (mu 0.5): friction mu M g
    accelerates it at mu g until it moves with the tip, after v / (mu g) = 10.2 ms: x(t) = mu g t^2 / 2, then
    v t - v^2 / (2 mu g) less the smoothing's lag (below the slip speed eps the force is mu M g f1(y), which adds
    eps^2 ln 2 / (mu g) = 1.4e-7 m of slip), within the steps' summed allowed errors (BDF2's estimate; the
    smoothing's lag is within it too); at the end it moves with the tip within eps.  Measured: 8e-9, -2.4e-7
    and -2.5e-7 m off at 5, 20 and 50 ms (after 8, 22 and 27 steps: 4e-7, 1.1e-6 and 1.35e-6 m allowed), its
    velocity 1e-6 m/s below the tip's.  On the old code the supports had no friction: the triangle stays (x 0
    against 6.1e-5 m at 5 ms and 2.2e-3 m at 50 ms)."""
    times = (0.005, 0.02, 0.05)
    rows, allowed = _slid(tmp_path, MU, times)
    reach = SLIDE_SPEED / (MU * GRAVITY)
    lag = _core.SUPPORT_SLIP_SPEED ** 2 * np.log(2.0) / (MU * GRAVITY)
    for t, (x, _, _, steps) in zip(times, rows):
        coulomb = MU * GRAVITY * t * t / 2 if t < reach else SLIDE_SPEED * t - SLIDE_SPEED ** 2 / (2 * MU * GRAVITY)
        assert abs(x - coulomb) <= steps * allowed + (lag if t > reach else 0.0), (t, x, coulomb)
    assert abs(rows[-1][1] - SLIDE_SPEED) <= _core.SUPPORT_SLIP_SPEED


def test_a_frictionless_spike_moving_sideways_leaves_the_triangle(tmp_path):
    """At mu = 0 the tip slides under the triangle and nothing pulls it along: its only horizontal force is
    the support's push along the tilted normal, at most M g tan(tilt), so it moves at most g tilt t^2 / 2 (tilt
    as measured at t: the tip off its centroid tips it slowly, the tilt growing), plus the steps' allowed
    errors: measured 3.9e-6 m at 50 ms (in 25 steps of at most 2 ms), against 5.7e-5 m allowed so and 2.2e-3 m
    with friction.
    The same on the old code (a guard: friction 0 leaves the step as it was, to the bit)."""
    times = (0.02, 0.05)
    rows, allowed = _slid(tmp_path, 0.0, times, max_step=2e-3)  # (unaccelerated, it took steps of 25 ms)
    for t, (x, _, tilt, steps) in zip(times, rows):
        assert abs(x) <= GRAVITY * tilt * t * t / 2 + steps * allowed, (t, x)
