"""A mesh's plane preconditioner (the core's ``mesh_plane.cpp``): the algebraic multigrid V-cycle of
large meshes (smoothed aggregation of the spring graph, Galerkin coarse matrices, Gauss-Seidel sweeps,
band factors on the coarsest level) against the matrices it approximates, assembled here with scipy,
and the band factors alone that small meshes keep."""

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse

import wetcloth
from wetcloth import _core
from wetcloth._core import forces_and_blocks
from wetcloth._core import ALGEBRAIC_SIZE
from wetcloth.model import Model
from wetcloth.preconditioner import make_mesh_plane
from support.rollback import assert_restored_run_repeats

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs"))
import make_meshes  # noqa: E402

EPS = np.finfo(float).eps
#: The step of a 1/30 s BDF2 step (beta = 2/3); 20 rings: ~1260 vertices, more than ALGEBRAIC_SIZE.
SCALE = (2.0 / 3.0 / 30.0) ** 2
RINGS = 20


@pytest.fixture(scope="module")
def disc(tmp_path_factory):
    """(model, unevenly wet masses (n) kg, (band factors alone, algebraic hierarchy)) of an irregular
    triangle disc, both preconditioners factored for those masses and SCALE."""
    points, triangles = make_meshes.round_cloth(rings=RINGS)
    path = tmp_path_factory.mktemp("cloth") / "disc.ply"
    make_meshes.write(path, points, triangles)
    model = Model(wetcloth.load_scene(cloth_mesh=str(path), place_mesh="on"))
    topology = model.topology
    assert topology.n > ALGEBRAIC_SIZE
    mass = model.dry_mass * np.random.default_rng(7).uniform(1.0, 4.0, topology.n)
    planes = []
    for size in (topology.n, ALGEBRAIC_SIZE):
        planes.append(make_mesh_plane(topology.n, topology.pairs, topology.in_plane_count, topology.pair_stiffness,
                                      algebraic_size=size))
        assert _core.refresh(planes[-1], model.cloth, mass, SCALE) == 1
    return model, mass, planes


def system(topology, mass):
    """``M + s L / 2``, L the Laplacian of the in-plane springs weighted by their stiffness: each
    in-plane component's matrix (half of every spring in each), assembled here with scipy."""
    t = topology.in_plane_count
    i, j = topology.pairs[:, :t]
    w = 0.5 * SCALE * topology.pair_stiffness[:t]
    laplacian = scipy.sparse.coo_matrix((np.concatenate([w, w, -w, -w]), (np.concatenate([i, j, i, j]),
                                                                         np.concatenate([i, j, j, i]))),
                                        shape=(topology.n, topology.n))
    return (laplacian + scipy.sparse.diags(mass)).tocsr()


def level_matrices(plane, component):
    """Each level's matrix of ``component`` and each prolongator, as scipy matrices read from the plane."""
    h = plane.algebraic
    matrices, prolongators = [], []
    for level, (size, _, a_rows, p_rows, _) in enumerate(h.levels):
        start = h.a_start[a_rows:a_rows + size + 1]
        entries = slice(start[0], start[-1])
        matrices.append(scipy.sparse.csr_matrix((h.a_value[component, entries], h.a_column[entries], start - start[0]),
                                                shape=(size, size)))
        if level + 1 < len(h.levels):
            start = h.p_start[p_rows:p_rows + size + 1]
            entries = slice(start[0], start[-1])
            prolongators.append(scipy.sparse.csr_matrix((h.p_value[entries], h.p_column[entries], start - start[0]),
                                                        shape=(size, h.levels[level + 1, 0])))
    return matrices, prolongators


def test_coarse_matrices_are_the_galerkin_products(disc):
    """Level 0 is M + s L / 2: the same positive terms (a mass and fewer than 10 springs) added in
    another order, so within 10 eps of the largest entry (measured 1.3 eps).  Each coarser level is
    P^T A P of the one before: a coarse entry sums at most a few hundred products, so its rounding is
    at most that many eps times the sum of their magnitudes, (|P|^T |A| |P|) entrywise: 1e3 eps of it
    (measured 1.7 eps)."""
    model, mass, (_, plane) = disc
    matrices, prolongators = level_matrices(plane, 0)
    assert len(matrices) >= 3 and matrices[-1].shape[0] <= 100
    exact = system(model.topology, mass)
    assert abs(matrices[0] - exact).max() <= 10 * EPS * abs(exact).max()
    for fine, coarse, p in zip(matrices, matrices[1:], prolongators):
        bound = (abs(p).T @ abs(fine) @ abs(p)).toarray()
        assert np.all(np.abs(coarse.toarray() - (p.T @ fine @ p).toarray()) <= 1e3 * EPS * bound)
    second, _ = level_matrices(plane, 1)  # t2's system is t1's
    assert all((a != b).nnz == 0 for a, b in zip(matrices, second))


def test_v_cycle_reduces_the_error_of_its_own_matrix(disc):
    """With flat frames P^-1 = (B^-1, B^-1, 1 / normal) on the t1, t2, n components, B = M + s L / 2.
    The band factors alone invert it to round-off (relative 1e-10: condition number of B 3e3 times
    eps; measured 1e-15); one V-cycle of the hierarchy leaves at most a quarter of the error in the
    B-norm (measured 0.085 and 0.089: a V(1,1) cycle of smoothed aggregation on a 2D Laplacian, as the
    grid's geometric cycle's 0.11-0.13 in test_preconditioner.py)."""
    model, mass, planes = disc
    n = model.topology.n
    matrix = system(model.topology, mass)
    errors = np.random.default_rng(3).standard_normal((2, n))
    r = np.vstack([matrix @ errors[0], matrix @ errors[1], np.ones(n)])
    for plane, bound in zip(planes, (1e-10, 0.25)):
        z = np.zeros_like(r)
        _core.apply(plane, np.ones(n), r, z)
        for c in range(2):
            left = errors[c] - z[c]
            reduction = np.sqrt(left @ matrix @ left / (errors[c] @ matrix @ errors[c]))
            assert reduction <= bound, (len(plane.algebraic.levels), c, reduction)
        assert np.array_equal(z[2], r[2] / plane.normal)


def test_v_cycle_is_symmetric_positive_definite(disc):
    """x^T P^-1 y = y^T P^-1 x for random x, y, and x^T P^-1 x > 0, in crumpled frames with the normal
    component's own system (as the fixed steps set it): what CG needs of a preconditioner.  P^-1 is
    applied in about 100 rounded operations per value (frames, two sweeps, restriction and interpolation
    on each of 3 levels, the band solve), so the products agree within 100 eps |x| |P^-1 y|."""
    model, mass, (_, plane) = disc
    topology, n = model.topology, model.topology.n
    rng = np.random.default_rng(1)
    pos = topology.rest_pos + rng.normal(scale=3e-3, size=(3, n))
    _core.follow_cloth(plane, model.cloth, pos)
    _core.refresh(plane, model.cloth, mass, SCALE)
    h = plane.algebraic
    h.a_value[2] = h.a_value[0]  # the normal component: the in-plane system scaled by a positive diagonal
    h.inverse_diagonal[2] = h.inverse_diagonal[0]
    plane.bands[2], plane.rows[2] = plane.bands[0], plane.rows[0]
    plane.reference[3] = 1.0
    free = np.ones(n)
    for _ in range(5):
        x, y = rng.standard_normal((2, 3, n))
        px, py = np.zeros_like(x), np.zeros_like(y)
        _core.apply(plane, free, x, px)
        _core.apply(plane, free, y, py)
        assert abs(np.sum(x * py) - np.sum(y * px)) <= 100 * EPS * np.linalg.norm(x) * np.linalg.norm(py)
        assert np.sum(x * px) > 0.0


def preconditioned_spread(plane, matrix, free, whole):
    """The condition number of P^-1 B_FF on the free rows (B_FF: the in-plane matrix's rows and columns
    of the free particles, P^-1 the cycle's t1 component with flat frames), which bounds CG's iterations;
    ``whole``: the whole mesh's cycle, its held rows zeroed after it (the cycle before it kept to them)."""
    n = len(free)
    kept = np.flatnonzero(free)
    inverse = np.zeros((len(kept), len(kept)))
    for k, i in enumerate(kept):
        r = np.zeros((3, n))
        r[0, i] = 1.0
        z = np.zeros_like(r)
        _core.apply(plane, np.ones(n) if whole else free, r, z)
        inverse[:, k] = z[0, kept] * free[kept]
    inverse = 0.5 * (inverse + inverse.T)  # symmetric to round-off
    values = scipy.linalg.eigvalsh(matrix[np.ix_(kept, kept)].toarray(), np.linalg.inv(inverse))
    return values.max() / values.min()


def test_held_particles_are_dirichlet_rows_of_the_v_cycle(disc):
    """Particles held in a step (free 0: at rest on a support, or pinned) are constraints of its solve,
    which the V-cycle keeps to on its finest level: its sweeps leave them at zero and restrict no residual
    from them (its coarse levels stay the whole mesh's).  Free particles whose neighbours are all held
    have a diagonal system, which the cycle then inverts to round-off (a division and a correction:
    within 4 eps, measured 1.9; the whole mesh's cycle, its held rows zeroed after it, as before, was 31
    times the diagonal's inverse off in norm).  With half the disc held, or a random third, the free
    rows' preconditioned matrix is better conditioned than with the whole mesh's cycle (measured 26.1
    against 56.5, 150 against 674: at most 2/3 of it asked), and the cycle stays symmetric positive
    definite there (within 100 eps, as in test_v_cycle_is_symmetric_positive_definite)."""
    model, mass, (_, plane) = disc
    topology, n = model.topology, model.topology.n
    _core.follow_cloth(plane, model.cloth, topology.rest_pos)  # flat frames: t1, t2 the x and y axes
    _core.refresh(plane, model.cloth, mass, SCALE)
    matrix = system(topology, mass)
    rng = np.random.default_rng(5)
    t = topology.in_plane_count
    neighbours = [[] for _ in range(n)]
    for i, j in topology.pairs[:, :t].T:
        neighbours[i].append(j)
        neighbours[j].append(i)
    alone = np.zeros(n)  # free particles no spring joins (chosen greedily), every other particle held
    for i in rng.permutation(n):
        if not any(alone[j] for j in neighbours[i]):
            alone[i] = 1.0
    r = rng.standard_normal((3, n)) * alone
    r[2] = 0.0
    z = np.zeros_like(r)
    _core.apply(plane, alone, r, z)
    exact = r[:2] / matrix.diagonal()
    assert np.all(np.abs(z[:2] - exact) <= 4 * EPS * np.abs(exact))
    half = (topology.rest_pos[0] < 0.0).astype(float)
    third = (rng.uniform(size=n) > 1 / 3).astype(float)
    for free in (half, third):
        spread = preconditioned_spread(plane, matrix, free, whole=False)
        assert spread <= 2 / 3 * preconditioned_spread(plane, matrix, free, whole=True), spread
        for _ in range(3):
            x, y = rng.standard_normal((2, 3, n)) * free
            px, py = np.zeros_like(x), np.zeros_like(y)
            _core.apply(plane, free, x, px)
            _core.apply(plane, free, y, py)
            assert abs(np.sum(x * py) - np.sum(y * px)) <= 100 * EPS * np.linalg.norm(x) * np.linalg.norm(py)
            assert np.sum(x * px) > 0.0


def test_finest_matrices_are_symmetric_to_the_bit(disc):
    """The cycle's forward sweep takes level 0's residual -U x from each row's entries left of the diagonal
    (mesh_plane.cpp: a_ji x_i scattered for a_ij x_i), which gives the same bits only if a_ij and a_ji are
    the same doubles: every spring adds one value to both, at the rest stiffness (refresh) and from the
    Jacobian in crumpled frames with a third of the particles held (set_systems_from_jacobian)."""
    model, mass, (_, plane) = disc
    topology, n = model.topology, model.topology.n
    rng = np.random.default_rng(11)
    pos = topology.rest_pos + rng.normal(scale=3e-3, size=(3, n))
    vel = rng.normal(scale=0.1, size=(3, n))
    _core.follow_cloth(plane, model.cloth, pos)
    _core.refresh(plane, model.cloth, mass, SCALE)
    matrices = [level_matrices(plane, 0)[0][0]]
    free = model.cloth.free.copy()
    model.cloth.free[...] = rng.uniform(size=n) > 1 / 3
    try:
        forces_and_blocks(model.cloth, model.physics, model.work, pos, vel, mass - model.dry_mass, 1 / 30)
        assert _core.set_systems_from_jacobian(plane, model.cloth, mass, model.work) == 1
    finally:
        model.cloth.free[...] = free
    matrices += [level_matrices(plane, c)[0][0] for c in range(3)]
    for matrix in matrices:
        transpose = matrix.T.tocsr()
        transpose.sort_indices()
        assert matrix.nnz > n and np.array_equal(matrix.indices, transpose.indices)
        assert np.array_equal(matrix.data.view(np.int64), transpose.data.view(np.int64))  # the bits, zeros' signs too
    _core.refresh(plane, model.cloth, mass, SCALE)  # the fixture's factors again


def test_the_hierarchy_is_the_same_every_time_it_is_built(disc):
    """pyamg's default smoothing of the prolongators starts a spectral radius estimate from a random
    vector; the weighting preconditioner.aggregation asks for does not, so that every process builds the
    same prolongators and repeats the same run to the bit."""
    model, _, (_, plane) = disc
    topology = model.topology
    np.random.seed(1)  # whatever the global random state
    again = make_mesh_plane(topology.n, topology.pairs, topology.in_plane_count, topology.pair_stiffness)
    for name in ("levels", "a_start", "a_column", "p_start", "p_column", "p_value", "r_value", "spring_entries"):
        assert np.array_equal(getattr(again.algebraic, name), getattr(plane.algebraic, name)), name


def test_the_band_order_of_a_shuffled_chain_and_grid_is_narrow_and_a_permutation():
    """reverse_cuthill_mckee (the coarsest level's band order): a chain of 50 points numbered at random
    gets bandwidth 1; a 6 x 9 grid (one direction of each edge given) at most its shorter side, 6;
    each order a permutation, the same on every call (ties by index, not by numpy's sort)."""
    from wetcloth.preconditioner import reverse_cuthill_mckee

    rng = np.random.default_rng(3)
    label = rng.permutation(50)
    chain = scipy.sparse.coo_matrix((np.ones(49), (label[:-1], label[1:])), shape=(50, 50)).tocsr()
    cols, rows = 6, 9
    number = rng.permutation(cols * rows).reshape(rows, cols)
    ends = [(number[r, c], number[r, c + 1]) for r in range(rows) for c in range(cols - 1)]
    ends += [(number[r, c], number[r + 1, c]) for r in range(rows - 1) for c in range(cols)]
    first, second = np.array(ends).T
    grid = scipy.sparse.coo_matrix((np.ones(len(first)), (first, second)), shape=(cols * rows,) * 2).tocsr()
    for graph, widest in ((chain, 1), (grid, cols)):
        order = reverse_cuthill_mckee(graph)
        assert np.array_equal(np.sort(order), np.arange(graph.shape[0]))
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        rows_, columns = graph.nonzero()
        assert np.abs(rank[rows_] - rank[columns]).max() <= widest
        assert np.array_equal(reverse_cuthill_mckee(graph), order)


def test_a_mesh_run_restored_after_refactoring_from_the_jacobian_repeats_bit_for_bit(tmp_path):
    """A disc of more than ALGEBRAIC_SIZE vertices floating after it landed on water refactors its hierarchy
    from the Jacobian (its buckling springs: a solve of more than MESH_REFRESH_AFTER CG iterations).  A
    snapshot taken while those factors are in use, after a solve too short to refactor again at once,
    restores those very factors: the run repeats exactly."""
    points, triangles = make_meshes.round_cloth(rings=RINGS)
    path = tmp_path / "disc.ply"
    make_meshes.write(path, points, triangles)
    sim = wetcloth.Simulation(wetcloth.load_scene(cloth_mesh=str(path), place_mesh="on", initial_tilt=0.0,
                                                  initial_height=0.05))
    assert sim.model.topology.n > ALGEBRAIC_SIZE and sim.model.topology.pair_buckling_count > 0
    for _ in range(200):
        sim.advance(sim.time + 0.01)  # doubles the simulated time (+10 ms): 0.01, 0.03, ... 1.27, 2.55 s
        snapshot = sim.snapshot()
        if snapshot["preconditioner_from_jacobian"] and snapshot["last_solve_iterations"] <= _core.MESH_REFRESH_AFTER:
            break
    else:
        pytest.fail("no snapshot with factors from the Jacobian in use")
    assert_restored_run_repeats(sim, snapshot, 0.2)
