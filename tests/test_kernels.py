"""The compiled core's kernels against independent references: a NumPy implementation and finite differences."""

import numpy as np
import pytest

import wetcloth
from wetcloth import _core
from wetcloth._core import _system_matvec, face_drag_and_blocks
from wetcloth.model import Model
from support.reference import NumpyReference
from wetcloth.state import initial_state

VARIANTS = [
    dict(),
    dict(damping_model="thesis", drag_model="stokes", buoyancy_model="thesis"),
    dict(bend_stiffness=0.0, drag_tangential=0.5, drag_linear=7.0),
    dict(air_density=5.0, wind_x=3.0, wind_y=-2.0, wind_z=1.0, drag_tangential=0.5),
]


def disturbed_state(scene, seed=0, spread=3e-3, stretch=1.0):
    """The initial sheet, near the water surface, scaled by ``stretch`` about its centre, with random
    displacements (m), velocities (m/s) and absorbed water (kg)."""
    model = Model(scene)
    state = initial_state(scene, model.topology)
    rng = np.random.default_rng(seed)
    centre = state.pos.mean(axis=1, keepdims=True)
    state.pos = centre + stretch * (state.pos - centre) + rng.normal(scale=spread, size=state.pos.shape)
    state.vel += rng.normal(scale=0.2, size=state.vel.shape)
    state.water += rng.uniform(0, 1, size=state.water.shape) * model.dry_mass
    return model, state


@pytest.mark.parametrize("variant", VARIANTS)
def test_forces_match_numpy_reference(variant):
    """Same forces to round-off (1e-12 of the largest), on a sheet straddling the surface."""
    scene = wetcloth.load_scene(nx=7, ny=9, initial_tilt=3.0, initial_height=0.0, **variant)
    model, state = disturbed_state(scene)
    expected = NumpyReference(model).forces(state.pos, state.vel, state.water)
    got = model.forces(state.pos, state.vel, state.water)
    assert (model.submerged > 0).any() and (model.submerged == 0).any(), "straddles the surface"
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * np.abs(expected).max())


@pytest.mark.parametrize("air", [False, True])
def test_face_drag_skips_only_dry_rows(air):
    """Face drag works out the rows from the highest wet one to the lowest in one run and zeroes
    the rest: on a cloth dry at both ends and in one middle row, called again and again on the same
    buffers with other rows wet, it matches the NumPy reference (to round-off) and, exactly, the
    same kernel computing every row.  The air's drag (the same kernel, above=True) skips the rows
    wholly under water instead (s = 1), and acts relative to the wind."""
    scene = wetcloth.load_scene(nx=7, ny=9, initial_tilt=3.0, initial_height=0.0, drag_tangential=0.5,
                                wind_x=2.0, wind_y=-1.0, wind_z=0.5)
    model, state = disturbed_state(scene)
    reference = NumpyReference(model)
    nx, ny, n = scene.nx, scene.ny, model.topology.n
    physics = model.physics
    fluid = ((physics.air_density, 0.0, physics.wind_x, physics.wind_y, physics.wind_z) if air else
             (physics.water_density, physics.drag_linear, physics.current_x, physics.current_y, 0.0))
    density, linear, flow_x, flow_y, flow_z = fluid
    cells = np.zeros((_core.DRAG_CELL_ROWS, n + nx + 1))
    rng = np.random.default_rng(5)
    for dry_rows in ([], [0, 1, 4, 7, 8], [0, 1, 2, 3, 4, 5, 6, 7, 8], [5, 6, 7, 8], [0, 3]):
        s = rng.uniform(0.1, 1.0, size=n) if not air else rng.uniform(0.0, 0.9, size=n)
        for row in dry_rows:
            s[row * nx:(row + 1) * nx] = 1.0 if air else 0.0
        results = []
        for skip_dry_rows in (True, False):
            force, blocks = np.zeros((3, n)), np.zeros((6, n))
            face_drag_and_blocks(nx, ny, state.pos, state.vel, s, density, physics.drag_normal,
                                 physics.drag_tangential, linear, flow_x, flow_y, 1e-3, force, blocks, cells,
                                 skip_dry_rows, flow_z=flow_z, above=air)
            results.append((force, blocks))
        expected = reference._face_drag(state.pos, state.vel, s, air=air)
        np.testing.assert_allclose(results[0][0], expected, rtol=0, atol=1e-12 * max(np.abs(expected).max(), 1.0))
        for skipped, computed in zip(*results):
            np.testing.assert_array_equal(skipped, computed)


@pytest.mark.parametrize("integrator", ["explicit_euler"])
def test_explicit_step_matches_numpy_reference(integrator):
    """A whole step (forces, update, floor, absorption) agrees with the NumPy step to round-off."""
    scene = wetcloth.load_scene(nx=6, ny=5, initial_tilt=5.0, initial_height=0.0, integrator=integrator,
                                tolerance=0.0, max_step=1e-5)
    sim = wetcloth.Simulation(scene)
    _, state = disturbed_state(scene, seed=3)
    sim.state = state.copy()
    expected = NumpyReference(sim.model).explicit_step(state, 1e-5)
    sim.advance(1e-5)
    for name in ("pos", "vel", "water"):
        np.testing.assert_allclose(getattr(sim.state, name), getattr(expected, name), rtol=1e-12, atol=1e-15)


def _matvec(model, state, p):
    out = np.zeros_like(p)
    w = model.work
    _system_matvec(model.topology.spring_offset, w.direction, w.along, w.across, model.mass(state.water),
                   w.blocks, model.free, p, out, np.zeros((4, model.topology.n)))
    return out


def _derivative(f, x, direction, eps=1e-7):
    """Central difference of f at x along direction; error ~ eps^2 relative, far below 1e-6."""
    return (f(x + eps * direction) - f(x - eps * direction)) / (2 * eps)


def _position_derivative(reference, state, direction):
    """dF/dx along ``direction`` at rest: the Jacobian Baraff and Witkin use keeps the damping and
    drag forces' dependence on positions out (it vanishes at zero velocity)."""
    rest = np.zeros_like(state.vel)
    return _derivative(lambda x: reference.forces(x, rest, state.water), state.pos, direction)


@pytest.mark.parametrize("damping_model", ["projected", "thesis"])
def test_implicit_system_matches_finite_differences(damping_model):
    """The system matrix A = M - h dF/dv - h^2 dF/dx applied to a random direction, against central
    differences of the NumPy forces: springs of all three families (the sheet stretched 2%, so
    every spring is taut and has its full Jacobian), smooth buoyancy in the surface slab, Stokes drag.
    Without the air's face drag (air_density 0): its Jacobian is lumped like the water's face drag, exact
    only for a uniform velocity change (checked in the next test), not along a random direction."""
    scene = wetcloth.load_scene(nx=6, ny=7, initial_tilt=0.0, initial_height=0.0, drag_model="stokes",
                                damping_model=damping_model, air_density=0.0)
    model, state = disturbed_state(scene, seed=1, spread=2e-4, stretch=1.02)
    h = 2e-3
    reference = NumpyReference(model)
    model.forces_and_blocks(state.pos, state.vel, state.water, h)
    assert ((model.submerged > 0) & (model.submerged < 1)).all(), "every particle in the surface slab"
    p = np.random.default_rng(2).normal(size=state.pos.shape)
    dfdv = _derivative(lambda v: reference.forces(state.pos, v, state.water), state.vel, p)
    dfdx = _position_derivative(reference, state, p)
    expected = model.mass(state.water) * p - h * dfdv - h * h * dfdx
    np.testing.assert_allclose(_matvec(model, state, p), expected, rtol=0, atol=1e-6 * np.abs(expected).max())


AIR_ONLY = dict(initial_height=0.5, air_density=5.0, wind_x=3.0, wind_y=-2.0, wind_z=1.0)


@pytest.mark.parametrize("where", [dict(), AIR_ONLY], ids=["at the surface", "in wind"])
@pytest.mark.parametrize("drag_tangential", [0.0, 0.5])
def test_face_drag_velocity_jacobian_for_uniform_motion(drag_tangential, where):
    """Face drag's Jacobian is lumped (row sums: exact for a uniform velocity change), with the exact
    derivative of the tangential part (|u_t| u_t: twice its coefficient along the slip, once across
    it); along a uniform direction the block must equal the exact derivative, with and without
    tangential drag, for the water's and the air's drag together at the surface, and for the air's
    alone in a wind (the sheet 0.5 m above the water; air 5 kg/m3 so that its drag is a good part of the
    system).  Buoyancy's and the springs' position Jacobians come in through h^2 dF/dx as always."""
    scene = wetcloth.load_scene(nx=6, ny=7, initial_tilt=3.0, drag_tangential=drag_tangential, drag_linear=7.0,
                                **(dict(initial_height=0.0) | where))
    model, state = disturbed_state(scene, seed=1)
    h = 2e-3
    model.forces_and_blocks(state.pos, state.vel, state.water, h)
    p = np.ones_like(state.pos) * np.array([[0.3], [-0.2], [1.0]])
    reference = NumpyReference(model)
    s = model.submerged.copy()
    assert (s == 0).all() if where else (s > 0).any(), "where the test means the sheet to be"
    dfdv = _derivative(lambda v: reference._face_drag(state.pos, v, s) + reference._face_drag(state.pos, v, s, air=True),
                       state.vel, p)
    if where:  # the air's part is a good part of what is checked
        air = _derivative(lambda v: reference._face_drag(state.pos, v, s, air=True), state.vel, p)
        assert np.abs(h * air).max() > 1e-3 * np.abs(model.mass(state.water) * p).max()
    expected = model.mass(state.water) * p - h * dfdv - h * h * _position_derivative(reference, state, p)
    np.testing.assert_allclose(_matvec(model, state, p), expected, rtol=0, atol=1e-6 * np.abs(expected).max())


@pytest.mark.parametrize("damping_model", ["projected", "thesis"])
def test_preconditioner_blocks_are_the_systems_diagonal_blocks(damping_model):
    """The block-Jacobi preconditioner is built from the 3x3 diagonal blocks the springs add up in
    ``diagonal_blocks``, plus the mass and the per-particle blocks: they must equal the diagonal
    blocks of the matrix the conjugate gradients solve with, read off column by column."""
    scene = wetcloth.load_scene(nx=5, ny=6, initial_tilt=20.0, initial_height=0.0, damping_model=damping_model)
    model, state = disturbed_state(scene, seed=7, stretch=1.01)
    model.forces_and_blocks(state.pos, state.vel, state.water, 4e-3)
    mass = model.mass(state.water)
    pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
    blocks = model.work.diagonal_blocks + model.work.blocks
    blocks[:3] += mass
    assert np.abs(blocks[3:]).max() > 1e-3 * np.abs(blocks[:3]).max(), "the blocks are not diagonal"
    for particle in range(model.topology.n):
        for column in range(3):
            unit = np.zeros((3, model.topology.n))
            unit[column, particle] = 1.0
            image = _matvec(model, state, unit)[:, particle]
            for slot, (a, b) in enumerate(pairs):
                if column == b:
                    assert image[a] == pytest.approx(blocks[slot, particle], rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("integrator", ["implicit_euler", "bdf2"])
@pytest.mark.parametrize("stiffness", [2e3, 1e4, 1e5, 1e6])
def test_implicit_fixed_steps_of_a_communication_interval_stay_sane(stiffness, integrator):
    """The implicit scheme's promise: steps far beyond the explicit limits (1/30 s here; symplectic
    Euler needs under 1e-3 s at 1e4 N/m and 6e-5 s at 1e6).  The towel dropped 10 cm lands and
    floats: after 2 s at 30 fixed steps a second it is at the surface (within 2 cm) and slow (under
    0.5 m/s).  Before the linear solve was preconditioned by 3x3 blocks and started from the best
    of two guesses, the unconverged conjugate gradients blew up at 1e6 N/m and flung 1e4 N/m cloth
    about at 200 m/s.  (At 1e8 N/m such steps leave spring forces of 1e6 N whose sum, the cloth's
    net force of a few N, drowns in the solver's relative tolerance: the cloth drifts down.  The
    adaptive mode, the default, takes shorter steps there and floats.)  BDF2 iterates Newton to its
    tolerance at every step, so it holds at 1e6 N/m too; implicit_euler stops after 4 Newton iterations
    but solves each to DESCENT_CG_TOLERANCE: at BDF2's looser 1e-1 its unconverged steps added energy
    at 1e6 N/m and the towel climbed 9 cm out of the water in 2 s."""
    scene = wetcloth.load_scene(integrator=integrator, tolerance=0.0, max_step=1 / 30, stretch_stiffness=stiffness)
    sim = wetcloth.Simulation(scene)
    sim.advance(2.0)
    assert abs(sim.outputs()["depth"]) < 0.02
    assert np.abs(sim.state.vel).max() < 0.5


def test_band_solves_match_a_dense_solve():
    """The preconditioner's band solves (the core's band.cpp: a banded Cholesky factor and
    column-by-column solves of two systems side by side) against numpy.linalg.solve, for bands from 1 to the whole
    matrix.  The matrices are shifted to eigenvalues of at least 1 and at most about 2 kd + 2, so
    both solutions err by under n * kd * 1e-16 relative: 1e-12 leaves a wide margin."""
    from wetcloth._core import band_factor, band_solve_two
    rng = np.random.default_rng(11)
    for n, kd in ((5, 1), (30, 29), (50, 7), (300, 22)):
        bands, dense = np.zeros((2, n, kd + 1)), []
        rows = np.zeros_like(bands)
        for c in range(2):
            a = np.zeros((n, n))
            for d in range(kd + 1):
                a[np.arange(d, n), np.arange(n - d)] = rng.uniform(-1, 1, size=n - d)
            a = a + a.T
            a += (1.0 - np.linalg.eigvalsh(a).min()) * np.eye(n)
            dense.append(a)
            for d in range(kd + 1):
                bands[c, np.arange(n - d), d] = a[np.arange(d, n), np.arange(n - d)]
            assert band_factor(bands[c], rows[c]) == 0
        b = rng.normal(size=(2, n))
        x = b.copy()
        band_solve_two(bands, rows, x)
        for c in range(2):
            expected = np.linalg.solve(dense[c], b[c])
            np.testing.assert_allclose(x[c], expected, rtol=0, atol=1e-12 * np.abs(expected).max())


def _spring_magnitudes(model, p):
    """Per particle (n): the sum over its springs of (|across| + |along - across|) |p_i - p_j|, a bound on
    the size of every spring term the springs' product adds to it."""
    n, w = model.topology.n, model.work
    total = np.zeros(n)
    for f, off in enumerate(model.topology.spring_offset):
        size = (np.abs(w.across[f]) + np.abs(w.along[f] - w.across[f]))[:n - off]
        term = size * np.linalg.norm(p[:, :n - off] - p[:, off:], axis=0)
        total[:n - off] += term
        total[off:] += term
    return total


def test_cgs_single_precision_product_is_the_double_one_to_float_rounding():
    """CG's product reads the families' blocks rounded to float and sums their terms in float: each of a
    particle's components differs from the double product by at most 2^-24 (float's unit roundoff) times
    a few dozen roundings (five rounded block values, three rounded differences, ten operations on a
    spring, twelve terms summed) of the largest terms: 64 u times the sum of their sizes bounds it."""
    from wetcloth import _core

    scene = wetcloth.load_scene(nx=9, ny=11, initial_tilt=0.0, initial_height=0.0)
    model, state = disturbed_state(scene, seed=4, spread=2e-4, stretch=1.02)
    model.forces_and_blocks(state.pos, state.vel, state.water, 2e-3)
    mass = model.mass(state.water)
    for p in (np.random.default_rng(5).normal(size=state.pos.shape), state.pos + 1.0):
        double, single = np.zeros_like(p), np.zeros_like(p)
        _core.system_matvec(model.cloth, model.work, mass, p, double)
        _core._system_matvec_single(model.cloth, model.work, mass, p, single)
        assert (np.abs(single - double) <= 64 * 2.0**-24 * _spring_magnitudes(model, p)).all()
        assert not np.array_equal(single, double)  # the float path is the one taken
