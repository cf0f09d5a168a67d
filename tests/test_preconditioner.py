"""The implicit solves' plane preconditioner (the core's ``plane.cpp``): the multigrid V-cycle of large
grids (``multigrid.cpp``) against the banded Cholesky factors it replaces there."""

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg

import wetcloth
from wetcloth import _core
from wetcloth._core import _system_matvec, forces_and_blocks
from wetcloth.preconditioner import _SHARE, level_sizes, make_hierarchy, make_plane
from wetcloth.model import Model
from wetcloth.state import initial_state

from support.rollback import assert_restored_run_repeats

EPS = np.finfo(float).eps
#: The unit roundoff of the V-cycle's own arithmetic (multigrid.cpp runs in single precision).
EPS_SINGLE = float(np.finfo(np.float32).eps)
#: A grid with uneven sides (an even count leaves a coarse line past the end), three multigrid
#: levels, and the step of a 1/30 s BDF2 step (beta = 2/3).
GRID = dict(nx=36, ny=41)
SCALE = (2.0 / 3.0 / 30.0) ** 2


def make_planes(topology, mass):
    """(banded, multigrid) preconditioners of the same grid, both factored for ``mass`` and SCALE."""
    planes = []
    for side in (max(topology.nx, topology.ny), 0):  # (multigrid from any size on)
        planes.append(make_plane(topology.nx, topology.ny, topology.spring_family_names, topology.spring_stiffness,
                                 multigrid_side=side))
        assert _core.refresh(planes[-1], topology.spring_offset, mass, SCALE) == 1
    banded, multigrid = planes
    assert len(banded.grid.levels) == 1 and len(multigrid.grid.levels) >= 3
    return banded, multigrid


def laplacians(topology, mass, weights=None):
    """``M + L_c`` for t1 and t2, assembled here with scipy from the springs (independently of the
    kernels' stencils), each spring weighted by its family's share in c times its entry of
    ``weights`` (F, n) kg, by default ``SCALE`` times its stiffness."""
    n = topology.n
    weights = SCALE * topology.spring_stiffness if weights is None else weights
    matrices = []
    for c in range(2):
        rows, cols, values = [], [], []
        for f, name in enumerate(topology.spring_family_names):
            share = _SHARE.get(name, (0.0, 0.0))[c]
            i = np.flatnonzero(topology.spring_stiffness[f])
            w = share * weights[f, i]
            j = i + topology.spring_offset[f]
            rows += [i, j, i, j]
            cols += [i, j, j, i]
            values += [w, w, -w, -w]
        laplacian = scipy.sparse.coo_matrix((np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
                                            shape=(n, n))
        matrices.append((laplacian + scipy.sparse.diags(mass)).tocsr())
    return matrices


def random_frames(plane, topology, seed):
    """Frames of a crumpled sheet (so that t1, t2, n are not the axes), and a positive normal diagonal."""
    rng = np.random.default_rng(seed)
    pos = np.vstack([topology.rest_xy, np.zeros(topology.n)]) + rng.normal(scale=3e-3, size=(3, topology.n))
    _core.follow_cloth(plane, topology.nx, pos)
    plane.normal[...] = rng.uniform(0.5, 2.0, topology.n) * 1e-3


@pytest.fixture(scope="module")
def towel():
    scene = wetcloth.load_scene(**GRID)
    model = Model(scene)
    rng = np.random.default_rng(7)
    mass = model.dry_mass * rng.uniform(1.0, 4.0, model.topology.n)  # unevenly wet
    return scene, model, mass


def test_multigrid_is_symmetric_positive_definite(towel):
    """x^T P^-1 y = y^T P^-1 x for random x, y, and x^T P^-1 x > 0, in crumpled frames.

    Tolerance: P^-1 is applied in about 100 rounded operations per value (frames, 1 + 3 + 1
    stencil passes on each of 4 levels, the coarse band solve), each with a relative error of at most
    the single-precision eps of the V-cycle's arithmetic (its stencils are rounded to it too); the
    computed products then differ from the exact, symmetric ones by at most about 100 eps |x| |P^-1 y|
    (Cauchy-Schwarz scale; measured 0.004 eps, 0.03 double-precision eps with the cycle in double)."""
    _, model, mass = towel
    topology = model.topology
    _, plane = make_planes(topology, mass)
    random_frames(plane, topology, seed=1)
    rng = np.random.default_rng(2)
    free = np.ones(topology.n)
    for _ in range(5):
        x, y = rng.standard_normal((2, 3, topology.n))
        px, py = np.zeros_like(x), np.zeros_like(y)
        _core.apply(plane, free, x, px)
        _core.apply(plane, free, y, py)
        scale = np.linalg.norm(x) * np.linalg.norm(py)
        assert abs(np.sum(x * py) - np.sum(y * px)) <= 100 * EPS_SINGLE * scale
        assert np.sum(x * px) > 0.0


def stencil_matrix(grid, level):
    """Component 0's stencils of ``level`` as a sparse matrix over its points (row-major), and their
    padded indices: entry (p, p + (dx, dy)) is coef[0, 3 (dy + 1) + dx + 1, p]."""
    nx, ny, start, pad = grid.levels[level]
    ix, iy = np.meshgrid(np.arange(nx), np.arange(ny))
    ix, iy = ix.ravel(), iy.ravel()
    padded = start + (iy + 1) * pad + ix + 1
    rows, cols, values = [], [], []
    for k in range(9):
        jx, jy = ix + k % 3 - 1, iy + k // 3 - 1
        inside = (0 <= jx) & (jx < nx) & (0 <= jy) & (jy < ny)
        rows.append(np.flatnonzero(inside))
        cols.append((jy * nx + jx)[inside])
        values.append(grid.coef[0, k, padded[inside]])
    matrix = scipy.sparse.coo_matrix((np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
                                     shape=(nx * ny, nx * ny))
    return matrix.tocsr(), padded


def interpolation(fine, coarse):
    """Bilinear interpolation P from the coarse grid (nx // 2 + 1 lines) to the fine one: a fine line at
    2 i takes coarse line i, one at 2 i + 1 half of lines i and i + 1."""
    def along(n, m):
        p = np.zeros((n, m))
        for i in range(n):
            p[i, i // 2] += 0.5 if i % 2 else 1.0
            if i % 2:
                p[i, i // 2 + 1] += 0.5
        return p
    (fx, fy), (cx, cy) = fine, coarse
    return scipy.sparse.csr_matrix(np.kron(along(fy, cy), along(fx, cx)))


def fill_random_stencils(grid, size, rng, diagonal):
    """Random 9-point stencils on ``grid``'s finest level (``size`` = (nx, ny)): entries uniform in [-1, 1],
    the diagonal's then replaced by ``diagonal(entries)``, and none towards points beyond the grid.  Returns
    the level's padded indices."""
    _, padded = stencil_matrix(grid, 0)
    for k in range(9):
        grid.coef[:, k, padded] = rng.uniform(-1.0, 1.0, (grid.coef.shape[0], padded.size))
    grid.coef[:, 4, padded] = diagonal(grid.coef[:, 4, padded])
    nx, ny = size
    ix, iy = np.arange(nx * ny) % nx, np.arange(nx * ny) // nx
    for k in range(9):
        jx, jy = ix + k % 3 - 1, iy + k // 3 - 1
        grid.coef[:, k, padded[(jx < 0) | (jx >= nx) | (jy < 0) | (jy >= ny)]] = 0.0
    return padded


def test_coarse_stencils_are_the_galerkin_products():
    """Each coarser level's stencils are P^T A P of the finer one's (``galerkin``), for random 9-point
    stencils (not symmetric) on a grid with an even and an odd side, two levels down, and the finer
    level's inverse diagonals 1 / A_ii.  Compared with scipy's products: a coarse entry sums at most 49
    terms, each a fine entry times a power of two (the product of the interpolation weights, exact), so
    in any order it errs by at most 49 eps times the sum of their magnitudes, (P^T |A| P)_ij.  The V-cycle's single-precision
    copies of the finer level's stencils and inverse diagonals are those values rounded."""
    sizes = level_sizes(36, 41, 12)[:3]
    grid = make_hierarchy(sizes)
    fill_random_stencils(grid, sizes[0], np.random.default_rng(11), lambda d: d + 10.0)  # a diagonal far from 0
    for level in range(2):
        _core.galerkin(grid, level)
        fine, fine_padded = stencil_matrix(grid, level)
        coarse, coarse_padded = stencil_matrix(grid, level + 1)
        p = interpolation(sizes[level], sizes[level + 1])
        expected = (p.T @ fine @ p).toarray()
        bound = 49 * EPS * (p.T @ abs(fine) @ p).toarray()
        assert np.all(np.abs(coarse.toarray() - expected) <= bound), level
        cx, cy = sizes[level + 1]
        qx, qy = np.arange(cx * cy) % cx, np.arange(cx * cy) // cx
        for k in range(9):  # entries towards points beyond the coarse grid are zero
            beyond = (qx + k % 3 - 1 < 0) | (qx + k % 3 - 1 >= cx) | (qy + k // 3 - 1 < 0) | (qy + k // 3 - 1 >= cy)
            assert np.all(grid.coef[0, k, coarse_padded[beyond]] == 0.0)
        assert np.array_equal(grid.inverse_diagonal[0, fine_padded], 1.0 / fine.diagonal())
        assert np.array_equal(grid.single_coef[:, :, fine_padded], grid.coef[:, :, fine_padded].astype(np.float32))
        assert np.array_equal(grid.single_inverse_diagonal[:, fine_padded],
                              grid.inverse_diagonal[:, fine_padded].astype(np.float32))


def test_the_cycles_way_down_sweeps_and_restricts_the_residual():
    """``v_cycle_down`` on random diagonally dominant 9-point stencils (three levels, coarse ones the
    Galerkin products), whatever x held before: on each level but the coarsest x solves (D + L) x = b
    (a forward Gauss-Seidel sweep from zero, L the neighbours before a point in row-major order), and the
    next level's b is P^T (b - A x), which the core takes as -U x (only the neighbours the sweep had not
    reached).  The cycle runs in single precision (its x and b of the levels in ``single_x`` and
    ``single_b``; the coarsest level's b back in ``b``), on the stencils and level 0's b rounded to it.
    Compared with scipy in double: forward substitution with a diagonal at least 10 against 8 neighbours
    of at most 1 contracts, so each x errs by at most about 10 eps |x|max, eps single precision's (the
    rounded A and b perturb it by eps relative); a coarse b sums at most 9 terms of r per point, each
    within 10 eps (|b| + |A| |x|) of the exact one (measured: at most 1.22 and 0.68 of those units; the
    cycle in double 0.75 and 0.52 of double-precision eps)."""
    sizes = level_sizes(36, 41, 12)[:3]
    grid = make_hierarchy(sizes)
    rng = np.random.default_rng(5)
    padded = fill_random_stencils(grid, sizes[0], rng, lambda d: rng.uniform(10.0, 20.0, d.shape))
    for level in range(2):
        _core.galerkin(grid, level)
    grid.b[:, padded] = rng.standard_normal((grid.b.shape[0], padded.size))
    for level in range(3):  # what an earlier cycle left on the levels' points
        grid.single_x[:, stencil_matrix(grid, level)[1]] = rng.standard_normal((grid.x.shape[0], 1))
    b = grid.b[0, padded].copy()
    _core.v_cycle_down(grid)
    for level in range(2):
        matrix, points = stencil_matrix(grid, level)
        x = grid.single_x[0, points].astype(float)
        expected = scipy.sparse.linalg.spsolve_triangular(scipy.sparse.tril(matrix).tocsr(), b)
        assert np.all(np.abs(x - expected) <= 10 * EPS_SINGLE * np.abs(expected).max()), level
        p = interpolation(sizes[level], sizes[level + 1])
        coarse_points = stencil_matrix(grid, level + 1)[1]
        coarse = (grid.b if level + 1 == 2 else grid.single_b)[0, coarse_points].astype(float)  # 2: the coarsest
        bound = 10 * EPS_SINGLE * (p.T @ (np.abs(b) + abs(matrix) @ np.abs(x)))
        assert np.all(np.abs(coarse - p.T @ (b - matrix @ x)) <= bound), level
        b = coarse.copy()


def test_v_cycle_reduces_the_error_of_its_own_matrix(towel):
    """With flat frames P^-1 = (B_0^-1, B_1^-1, 1 / normal) on the t1, t2, n components, B_c the
    matrices ``M + s L_c`` assembled independently here.  The banded factors invert them to
    round-off (relative 1e-10: condition number of B about 1e4 times eps; measured 2e-15); one
    V-cycle leaves at most a quarter of the error in the B-norm (measured 0.11 and 0.13: the
    textbook rate of a V(1,1) cycle)."""
    _, model, mass = towel
    topology = model.topology
    matrices = laplacians(topology, mass)
    rng = np.random.default_rng(3)
    errors = rng.standard_normal((2, topology.n))
    free = np.ones(topology.n)
    r = np.zeros((3, topology.n))
    for c in range(2):
        r[c] = matrices[c] @ errors[c]
    for plane, bound in zip(make_planes(topology, mass), (1e-10, 0.25)):
        z = np.zeros_like(r)
        _core.apply(plane, free, r, z)
        for c in range(2):
            left = errors[c] - z[c]
            reduction = np.sqrt(left @ matrices[c] @ left / (errors[c] @ matrices[c] @ errors[c]))
            assert reduction <= bound, (len(plane.grid.levels), c, reduction)
        assert np.allclose(z[2], r[2] / plane.normal, rtol=1e-15, atol=0)


def pcg(model, mass, plane, b, rtol):
    """Conjugate gradients on the implicit step's system A x = b preconditioned by ``plane``, stopped
    as the BDF2 solves stop (the core's ``implicit.cpp``): when the largest component of the
    preconditioned residual is at most ``rtol`` times its first value.  Returns (x, iterations)."""
    x, r = np.zeros_like(b), b.copy()
    z = apply(plane, model, r)
    p, rz, first = z.copy(), np.sum(r * z), np.abs(z).max()
    for iterations in range(1, 1000):
        ap = matvec(model, mass, p)
        alpha = rz / np.sum(p * ap)
        x += alpha * p
        r -= alpha * ap
        z = apply(plane, model, r)
        if np.abs(z).max() <= rtol * first:
            return x, iterations
        rz, rz_old = np.sum(r * z), rz
        p = z + rz / rz_old * p
    raise AssertionError("no convergence")


def apply(plane, model, v):
    out = np.zeros_like(v)
    _core.apply(plane, model.cloth.free, v, out)
    return out


def matvec(model, mass, v):
    """A v, A = M - h' dF/dv - h'^2 dF/dx as the implicit steps assemble it."""
    work, out = model.work, np.zeros_like(v)
    _system_matvec(model.cloth.offsets, work.direction, work.along, work.across, mass, work.blocks, model.cloth.free,
                   v, out, work.buf)
    return out


def test_cg_reaches_the_same_solution_with_either_preconditioner(towel):
    """A stretched, wet, crumpled towel straddling the surface: CG on its BDF2 system with the
    multigrid and with the banded preconditioner, each to the stopping rule at 1e-9.

    Tolerance: A = M + (positive semi-definite spring, drag and buoyancy blocks), so A^-1 <= M^-1
    and the error of a solution with residual r is, in the A-norm, at most |r|_{M^-1}
    (``|e|_A^2 = r^T A^-1 r``).  The two solutions then differ by at most the sum of their two
    bounds; and the stopping rule at 1e-9 must have made that sum tiny against the solution (1e-6
    of its A-norm; measured 6e-8, the difference itself 2e-9).  The multigrid's iterations stay within 1.5 times the
    banded ones plus 2, at 1e-9 and at the solver's 1e-2 (a V-cycle is not the exact inverse:
    measured 299 against 313 and 23 against 21 here, 10-20 % more in whole runs)."""
    scene, model, mass = towel
    topology = model.topology
    state = initial_state(scene.replace(initial_height=0.0, initial_tilt=4.0), topology)
    rng = np.random.default_rng(4)
    centre = state.pos.mean(axis=1, keepdims=True)
    pos = centre + 1.002 * (state.pos - centre) + rng.normal(scale=1e-3, size=state.pos.shape)
    vel = rng.normal(scale=0.1, size=state.vel.shape)
    water = mass - model.dry_mass
    bh = np.sqrt(SCALE)
    forces_and_blocks(model.cloth, model.physics, model.work, pos, vel, water, bh)
    b = bh * model.work.force * model.cloth.free
    results = {}
    for name, plane in zip(("banded", "multigrid"), make_planes(topology, mass)):
        _core.follow_cloth(plane, topology.nx, pos)
        _core.set_normal_diagonal(plane, mass, model.work.diagonal_blocks, model.work.blocks)
        (x, iterations), (_, loose) = pcg(model, mass, plane, b, 1e-9), pcg(model, mass, plane, b, 1e-2)
        residual = b - matvec(model, mass, x)
        results[name] = x, np.sqrt(np.sum(residual ** 2 / mass)), iterations, loose
    (banded, banded_bound, banded_iterations, banded_loose) = results["banded"]
    (multigrid, multigrid_bound, multigrid_iterations, multigrid_loose) = results["multigrid"]
    difference = multigrid - banded
    a_norm = lambda v: np.sqrt(np.sum(v * matvec(model, mass, v)))  # noqa: E731
    assert a_norm(difference) <= banded_bound + multigrid_bound <= 1e-6 * a_norm(banded)
    assert multigrid_iterations <= 1.5 * banded_iterations + 2
    assert multigrid_loose <= 1.5 * banded_loose + 2


def test_factors_from_the_jacobian_invert_the_laplacians_of_its_springs(towel):
    """``refresh_from_jacobian`` factors ``M + L_c`` with each spring weighted by its coefficient along
    its direction in the system matrix (here random, half of them zero: slack springs), assembled
    independently with scipy; the banded factors invert it to round-off (relative 1e-10, as the
    rest-stiffness factors above)."""
    _, model, mass = towel
    topology = model.topology
    banded, _ = make_planes(topology, mass)
    rng = np.random.default_rng(4)
    along = rng.uniform(0.0, 2.0, topology.spring_stiffness.shape) * SCALE * topology.spring_stiffness
    along[rng.random(along.shape) < 0.5] = 0.0
    assert _core.refresh_from_jacobian(banded, topology.spring_offset, mass, along) == 1
    matrices = laplacians(topology, mass, along)
    errors = rng.standard_normal((2, topology.n))
    r = np.zeros((3, topology.n))
    for c in range(2):
        r[c] = matrices[c] @ errors[c]
    z = apply(banded, model, r)
    for c in range(2):
        assert np.abs(z[c] - errors[c]).max() <= 1e-10 * np.abs(errors[c]).max()


def test_a_run_restored_after_refactoring_from_the_jacobian_repeats_bit_for_bit():
    """A 9 x 9 cloth sinking edge first refactors its preconditioner from the Jacobian.  A snapshot
    taken while those factors are in use, after a solve too short to refactor again at once (so the
    next step's first solve uses them), restores those very factors: the run repeats exactly."""
    sim = wetcloth.Simulation(wetcloth.load_scene("thesis_fast", nx=9, ny=9, absorption_capacity=5.0,
                                                  absorption_rate=0.4))
    sim.advance(5.0)
    for _ in range(250):
        sim.advance(0.1)
        snapshot = sim.snapshot()
        if snapshot["preconditioner_from_jacobian"] and not _core.jacobian_refresh_pays(
                sim._plane, snapshot["last_solve_iterations"]):
            break
    else:
        pytest.fail("no snapshot with factors from the Jacobian in use")
    assert_restored_run_repeats(sim, snapshot, 1.0)


def test_systems_from_the_jacobian_are_its_projection_on_the_frames():
    """Fixed steps build each frame axis's system from the system matrix A itself
    (``set_systems_from_jacobian``): S_a = V_a^T A' V_a, V_a the particles' axis a (crumpled frames
    here), A' the matrix without the bending springs and with no coupling to the pinned edge.  Assembled
    independently from A's products with unit vectors; the banded factors invert it to round-off:
    applied to V_a S_a e the preconditioner returns V_a e (the frames are orthonormal, so the other
    axes see nothing), relative 1e-10 as the rest-stiffness factors above.  On the multigrid the
    same systems give a symmetric positive definite cycle (as in the test above, to its single
    precision)."""
    scene = wetcloth.load_scene(nx=30, ny=27, pinned_edge="y_max")
    model = Model(scene)
    topology, n = model.topology, model.topology.n
    rng = np.random.default_rng(5)
    mass = model.dry_mass * rng.uniform(1.0, 3.0, n)
    state = initial_state(scene, topology)
    pos = state.pos + rng.normal(scale=2e-3, size=state.pos.shape)
    vel = rng.normal(scale=0.1, size=state.vel.shape)
    forces_and_blocks(model.cloth, model.physics, model.work, pos, vel, mass - model.dry_mass, 1 / 30)
    work, free = model.work, model.cloth.free
    planes = [make_plane(topology.nx, topology.ny, topology.spring_family_names, topology.spring_stiffness,
                         multigrid_side=side) for side in (100, 0)]
    for plane in planes:
        random_frames(plane, topology, seed=6)
        assert _core.set_systems_from_jacobian(plane, model.cloth, mass, work) == 1
    banded, multigrid = planes
    assert len(banded.grid.levels) == 1 and len(multigrid.grid.levels) >= 3
    # A' = A without the bending springs, its products with unit vectors
    stretch = np.array([name in _SHARE for name in topology.spring_family_names])
    along, across = work.along.copy(), work.across.copy()
    work.along[~stretch] = 0.0
    work.across[~stretch] = 0.0
    units = np.eye(3 * n)
    dense = np.column_stack([matvec(model, mass, units[k].reshape(3, n)).ravel() for k in range(3 * n)])
    work.along[...], work.across[...] = along, across
    pinned = free == 0
    frames = banded.frame.reshape(3, 3, n)
    for a in range(3):
        v = np.zeros((3 * n, n))
        for c in range(3):
            v[c * n + np.arange(n), np.arange(n)] = frames[a, c]
        s = v.T @ dense @ v
        s[np.ix_(pinned, ~pinned)] = s[np.ix_(~pinned, pinned)] = 0.0  # the pinned edge holds
        e = rng.standard_normal(n) * free
        z = apply(banded, model, (v @ (s @ e)).reshape(3, n))
        assert np.abs(v.T @ z.ravel() - e).max() <= 1e-10 * np.abs(e).max(), a
    x, y = rng.standard_normal((2, 3, n)) * free
    px, py = apply(multigrid, model, x), apply(multigrid, model, y)
    assert abs(np.sum(x * py) - np.sum(y * px)) <= 100 * EPS_SINGLE * np.linalg.norm(x) * np.linalg.norm(py)
    assert np.sum(x * px) > 0.0


def hanging_sheet(side: int) -> wetcloth.Scene:
    """bench/hanging_sheet.py's sheet, ``side`` x ``side`` particles (multigrid from 41)."""
    return wetcloth.load_scene(nx=side, ny=side, width=1.0, length=1.0, pinned_edge="y_max", initial_tilt=0.0,
                               initial_height=2.0, water_level=-10.0, floor_level=-20.0)


def test_a_run_restored_with_reused_jacobian_systems_repeats_bit_for_bit():
    """Adaptive steps on a multigrid grid solve with in-plane systems built from the Jacobian and reused
    over the steps after (reused_plane.hpp).  A snapshot holds what they were built from: restoring it,
    into the same simulation (whose systems have been rebuilt meanwhile) or into a new one, rebuilds the
    same factors and the run repeats the uninterrupted one exactly."""
    sim = wetcloth.Simulation(hanging_sheet(41))
    sim.advance(0.3)
    snapshot = sim.snapshot()
    rule = snapshot["preconditioner_reused_rule"]
    assert rule[0] == 1.0 and rule[2] > 0, "the reused systems are built and in use"
    families = snapshot["preconditioner_jacobian_along"].shape[0]
    assert snapshot["preconditioner_reused_source"].size == (10 + 5 * families) * 41 * 41
    before = sim.solver_counts["factorisations"]
    sim.advance(0.2)
    assert sim.solver_counts["factorisations"] > before, "rebuilt since the snapshot"
    expected = sim.state.copy()
    for restored in (sim, wetcloth.Simulation(hanging_sheet(41))):
        restored.restore(snapshot)
        restored.advance(0.2)
        for name in ("pos", "vel", "water"):
            np.testing.assert_array_equal(getattr(restored.state, name), getattr(expected, name))


def test_small_grids_have_no_reused_jacobian_systems():
    """Below MULTIGRID_SIDE the banded factors refactor from the Jacobian instead: the snapshot's
    reused source is empty and its rule unbuilt."""
    sim = wetcloth.Simulation(hanging_sheet(9))
    sim.advance(0.1)
    snapshot = sim.snapshot()
    assert snapshot["preconditioner_reused_source"].size == 0
    assert not snapshot["preconditioner_reused_rule"].any()
