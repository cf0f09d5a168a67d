"""The frame steps' coarse space (the core's ``coarse_space.cpp``): the Galerkin product P^T A P of the
Newton matrix over aggregate rigid motions (translations, and small turns about each aggregate's centre), and
the correction P (P^T A P)^-1 P^T r it adds to the
plane preconditioner."""

import numpy as np
import pytest

import wetcloth
from wetcloth import _core
from wetcloth._core import forces_and_blocks
from wetcloth.model import Model
from wetcloth.state import initial_state

EPS = np.finfo(float).eps
#: Sides that the aggregates do not divide (a narrower last row and column of aggregates), a pinned edge; at
#: 19 across the last column of aggregates is one particle wide (it does not turn).
GRIDS = (dict(nx=20, ny=23, pinned_edge="y_max"), dict(nx=19, ny=23, pinned_edge="y_max"))
SIDE = 9
BH = 2.0 / 3.0 / 30.0


@pytest.fixture(scope="module", params=GRIDS, ids=lambda grid: f"{grid['nx']}x{grid['ny']}")
def crumpled(request):
    """A stretched, unevenly wet, crumpled sheet moving at random: the Newton matrix's blocks in work."""
    grid = request.param
    scene = wetcloth.load_scene(**grid)
    model = Model(scene)
    rng = np.random.default_rng(11)
    n = model.topology.n
    mass = model.dry_mass * rng.uniform(1.0, 4.0, n)
    state = initial_state(scene.replace(initial_height=0.0, initial_tilt=4.0), model.topology)
    centre = state.pos.mean(axis=1, keepdims=True)
    pos = centre + 1.002 * (state.pos - centre) + rng.normal(scale=1e-3, size=state.pos.shape)
    vel = rng.normal(scale=0.1, size=state.vel.shape)
    forces_and_blocks(model.cloth, model.physics, model.work, pos, vel, mass - model.dry_mass, BH)
    return model, mass, pos, grid


def rigid_motions(model, pos, grid):
    """P (3n, 6 aggregates): column 6 I + c moves aggregate I's free particles by 1 along axis c, column
    6 I + 3 + k turns them about axis k through the aggregate's mean position (e_k x (x_i - centre)); the
    turns are zero for an aggregate one particle wide or tall."""
    nx, ny = grid["nx"], grid["ny"]
    n = nx * ny
    columns, rows = -(-nx // SIDE), -(-ny // SIDE)
    row, column = np.divmod(np.arange(n), nx)
    aggregate = (row // SIDE) * columns + column // SIDE
    count = columns * rows
    free = model.cloth.free
    assert free.min() == 0.0 and free.max() == 1.0  # the pinned edge is in it
    centre = np.stack([np.bincount(aggregate, pos[c], count) / np.bincount(aggregate, None, count) for c in range(3)])
    wide = np.minimum(SIDE, nx - (np.arange(count) % columns) * SIDE)
    tall = np.minimum(SIDE, ny - (np.arange(count) // columns) * SIDE)
    turns = ((wide >= 2) & (tall >= 2)).astype(float)
    arm = (pos - centre[:, aggregate]) * turns[aggregate]
    p = np.zeros((3 * n, 6 * count))
    for c in range(3):
        p[c * n + np.arange(n), 6 * aggregate + c] = free
    for k in range(3):
        turn = np.cross(np.eye(3)[k][:, None], arm, axis=0)
        for c in range(3):
            p[c * n + np.arange(n), 6 * aggregate + 3 + k] = free * turn[c]
    return p


def newton_matrix_times(model, mass, p):
    """A P, column by column, through the steps' own matvec."""
    out = np.zeros((p.shape[1], p.shape[0]))
    for k in range(p.shape[1]):
        _core.system_matvec(model.cloth, model.work, mass, np.ascontiguousarray(p[:, k]), out[k])
    return out.T


def test_coarse_matrix_is_the_galerkin_product(crumpled):
    """The assembled matrix against P^T (A P), A applied by system_matvec.

    Tolerance: each entry sums at most 3 x 81 particles' mass and block entries and 3 x 81 x 8 springs'
    block entries, each rounded once (relative eps), of magnitude at most the largest diagonal entry;
    P^T A P through the matvec rounds as often.  1e-12 of the largest entry is above that (2000 x eps
    = 4.4e-13) and far below a missing spring (its whole stiffness times (beta h)^2)."""
    model, mass, pos, grid = crumpled
    p = rigid_motions(model, pos, grid)
    expected = p.T @ newton_matrix_times(model, mass, p)
    size = p.shape[1]
    assembled = np.zeros((size, size))
    _core.coarse_matrix(model.cloth, model.work, mass, pos, SIDE, assembled)
    scale = np.abs(expected).max()
    assert np.abs(assembled - expected).max() <= 1e-12 * scale
    assert np.abs(assembled - assembled.T).max() == 0.0
    used = np.abs(p).max(axis=0) > 0.0  # (the turns of an aggregate one particle wide: no column)
    assert used.sum() < size if grid["nx"] % SIDE == 1 else used.all()
    assert np.all(assembled[~used] == 0.0)
    # M > 0 on the free particles, which no aggregate has on one line: positive definite
    assert np.linalg.eigvalsh(assembled[np.ix_(used, used)]).min() > 0.0


def test_coarse_correction_solves_the_coarse_system(crumpled):
    """z + P (P^T A P)^-1 P^T r against numpy's dense solve of the assembled matrix, added to z.

    Tolerance: the banded Cholesky and numpy's LU each leave a relative error of about cond x size x
    eps in the coarse solution (a backward-stable solve); 10 times that, relative to its largest entry, times
    P's largest row sum (an error dy moves z by at most that times |dy|)."""
    model, mass, pos, grid = crumpled
    p = rigid_motions(model, pos, grid)
    used = np.abs(p).max(axis=0) > 0.0
    p = p[:, used]
    matrix = np.zeros((len(used), len(used)))
    _core.coarse_matrix(model.cloth, model.work, mass, pos, SIDE, matrix)
    matrix = matrix[np.ix_(used, used)]
    size = p.shape[1]
    rng = np.random.default_rng(3)
    r = rng.normal(size=p.shape[0]) * np.tile(model.cloth.free, 3)
    z0 = rng.normal(size=p.shape[0])
    z = z0.copy()
    coarse = _core.CoarseSpace(model.cloth, SIDE)
    assert coarse.build(model.cloth, model.work, mass, pos)
    coarse.add_correction(model.cloth, r, z)
    y = np.linalg.solve(matrix, p.T @ r)
    tolerance = 10 * np.linalg.cond(matrix) * size * EPS
    assert np.abs(z - z0 - p @ y).max() <= tolerance * np.abs(y).max() * np.abs(p).sum(axis=1).max()
    assert np.array_equal(z[np.tile(model.cloth.free, 3) == 0.0], z0[np.tile(model.cloth.free, 3) == 0.0])
