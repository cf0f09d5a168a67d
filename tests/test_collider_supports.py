"""A moving mesh collider's vertices and edges as supports inside the implicit step (collider_supports.cpp,
docs/model.md section 6.3 "Supports in the solve"): each term's force is minus the gradient of its energy, its
stiffness the derivative of its force, and a cloth triangle resting on a collider vertex settles where the
penalty carries its weight."""

import numpy as np
import trimesh

import wetcloth
from wetcloth import _core
from wetcloth.scene import load_scene

STIFFNESS, DISTANCE, SCALE = 5000.0, 1e-3, 4e-6  # N/m, m, s^2


def _terms(pos, p=None):
    """Two terms on 5 particles, a vertex-triangle one (weights -u, -v, -w) and an edge-edge one (two cloth
    points), both pressing at pos: their energy (J), forces (3, n), diagonal blocks (6, n) and the rest of
    their stiffness times p (3, n), the blocks and product times SCALE."""
    n = pos.shape[1]
    points = np.array([[0, 1, 2], [3, 4, -1]], dtype=np.int64)
    weights = np.array([[-0.2, -0.3, -0.5], [0.6, 0.4, 0.0]])
    normals = np.array([[0.36, 0.48, 0.8], [0.0, 0.6, -0.8]])
    offsets = np.array([0.11, -0.07])
    force, blocks, product = np.zeros((3, n)), np.zeros((6, n)), np.zeros((3, n))
    energy = _core.support_terms(points, weights, normals, offsets, STIFFNESS, DISTANCE, SCALE, pos, np.ones(n),
                                 np.zeros((3, n)) if p is None else p, force, blocks, product)
    return energy, force, blocks, product


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


def test_the_force_is_minus_the_gradient_of_the_energy():
    """Central differences of the energy (steps of 1e-7 m, the penalty quadratic: exact but for rounding,
    about 1e-9 of the force) against the forces at a place where both terms press."""
    pos = _pressing_place()
    energy, force, _, _ = _terms(pos)
    assert energy > 0.0 and np.abs(force).max() > 0.1
    step = 1e-7
    for c in range(3):
        for i in range(pos.shape[1]):
            up, down = pos.copy(), pos.copy()
            up[c, i] += step
            down[c, i] -= step
            difference = -(_terms(up)[0] - _terms(down)[0]) / (2 * step)
            assert abs(difference - force[c, i]) <= 1e-6 * np.abs(force).max(), (c, i)


def test_the_stiffness_is_the_derivative_of_the_force():
    """The blocks and the product (the whole stiffness times SCALE applied to a direction p) against central
    differences of the forces along p (the force linear while the terms press: exact but for rounding)."""
    pos = _pressing_place()
    p = np.random.default_rng(5).normal(size=pos.shape)
    _, _, blocks, product = _terms(pos, p)
    xx, yy, zz, xy, xz, yz = blocks
    matrix_times_p = product + np.array([xx * p[0] + xy * p[1] + xz * p[2], xy * p[0] + yy * p[1] + yz * p[2],
                                         xz * p[0] + yz * p[1] + zz * p[2]])
    step = 1e-8
    difference = -(_terms(pos + step * p)[1] - _terms(pos - step * p)[1]) / (2 * step) * SCALE
    assert np.abs(matrix_times_p).max() > 0.0
    np.testing.assert_allclose(matrix_times_p, difference, rtol=0, atol=1e-6 * np.abs(difference).max())
    # off the diagonal blocks: the product is zero at a particle whose term has no other point moving
    assert np.abs(product[:, 3]).max() > 0.0 and np.abs(product[:, 0]).max() > 0.0


def test_a_released_term_has_no_force_energy_or_stiffness():
    """Where each gap is above DISTANCE the terms are off: no energy, force, blocks or product."""
    pos = _pressing_place()
    pos[:, 0] -= 0.02 * np.array([0.36, 0.48, 0.8]) / 0.2  # the triangle away from the vertex
    pos[:, 3] += 0.02 * np.array([0.0, 0.6, -0.8]) / 0.6
    energy, force, blocks, product = _terms(pos, np.ones(pos.shape))
    assert energy == 0.0 and not force.any() and not blocks.any() and not product.any()


def test_a_triangle_rests_on_a_keyed_spikes_tip_at_the_penalty_height(tmp_path):
    """A cloth of one equilateral triangle (0.1 m sides) lying flat, its centroid over the tip of a thin
    spike (a mesh collider keyed to rise 1 mm in 0.1 s, then still): the tip supports it at its centroid
    (weights 1/3), so it settles where the penalty carries its weight, the centroid SUPPORT_DISTANCE
    thickness / 2 less M g / k above the tip (k SUPPORT_STIFFNESS times the stiffest spring), within the
    Newton tolerance (measured 1e-13 m: at rest Newton's solution is the equilibrium).  On the old code the
    edges' pass pushed the triangle back after every step and it rested at its distance, 0.1 mm, in 2091 steps
    (39 now)."""
    side = 0.1
    r = side / np.sqrt(3)
    corners = [(r * np.cos(a), r * np.sin(a), 0.0) for a in np.pi / 2 + np.arange(3) * 2 * np.pi / 3]
    cloth = tmp_path / "triangle.obj"
    cloth.write_text("".join("v %.17g %.17g %.17g\n" % c for c in corners) + "f 1 2 3\n")
    spike = trimesh.Trimesh(vertices=[[0, 0, 0], [0.005, 0, -0.05], [-0.0025, 0.0043, -0.05], [-0.0025, -0.0043, -0.05]],
                            faces=[[0, 2, 1], [0, 3, 2], [0, 1, 3], [1, 2, 3]])
    spike.fix_normals()
    spike.export(tmp_path / "spike.stl")
    scene = load_scene(cloth_mesh=str(cloth), initial_tilt=0.0, initial_height=0.0015, water_level=-1.0,
                       floor_level=-1.0, colliders=({"shape": "mesh", "file": str(tmp_path / "spike.stl"), "z": -0.001},),
                       collider_keys=(dict(collider=1, time=0.1, z=0.001),))
    sim = wetcloth.Simulation(scene)
    sim.advance(1.0)
    weight = sim.model.dry_mass.sum() * 9.81
    k = _core.SUPPORT_STIFFNESS * sim.model.cloth.pair_stiffness.max()
    expected = _core.SUPPORT_DISTANCE * 0.5 * scene.thickness - weight / k
    assert weight / k > 1e-7  # the compression the test resolves
    pos = sim.state.pos
    assert abs(pos[2].mean() - expected) <= sim._control.newton_tolerance
    assert np.abs(pos[:2].mean(axis=1)).max() < 1e-9  # still over the tip
