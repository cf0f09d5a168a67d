"""The preconditioner of the implicit solves: the cloth's in-plane stiffness, factored once.

The system matrix of an implicit step, ``A = M - h C - h^2 K``, is dominated by the stretch springs,
which are stiff along their own direction only: a flat cloth is stiff in its plane and soft across
it.  In each particle's frame (t1, t2, n) that follows the cloth's surface there (t1 along its row,
n its normal) this preconditioner keeps that structure:

* the t1 and t2 components each get a scalar matrix ``M + h^2 L_c``, with ``L_c`` the graph
  Laplacian of the springs weighted by their rest stiffness times the share of their direction in
  that component (structural springs all in one, shear half in each).  These depend on neither
  the positions nor the taut set, so they are factored only when the step's ``h`` or the masses
  have changed much (``REFACTOR_SCALE``, ``REFACTOR_CHANGE``), not at every step.  Small grids
  solve them exactly with LAPACK's banded Cholesky; on large grids (shorter side above
  MULTIGRID_SIDE) one multigrid V-cycle (``multigrid.py``) approximates their inverse, with the
  banded Cholesky on its coarsest grid only;
* where a solve took many iterations (a sinking cloth: most of its stretch springs slack while
  the rest-stiffness Laplacians assume all taut), small grids refactor the two systems from the
  Jacobian in hand, ``M + L(along)`` with each spring's own coefficient along its direction
  (``refresh_from_jacobian``, JACOBIAN_REFRESH_AFTER);
* the normal component gets the normal-normal entry of each particle's 3x3 diagonal block of A
  (mass, drag, buoyancy, and whatever stiffness the springs have across the plane).

The bands are ordered along the grid's shorter side, so their half-bandwidth is that side plus one
and a band solve costs O(n x shorter side), a factorisation O(n x shorter side^2); the V-cycle
costs O(n) for both (at 81 x 81: 0.36 against 2.7 ms per application, 8 ms against 0.3-1.2 s per
factorisation, measured on the shared machine; docs/benchmarks.md, Large steps).  Conjugate
gradients on A with this preconditioner need a handful of iterations on a floating or sinking
towel at 1/30 s steps, where the isotropic Laplacian of projective dynamics needed hundreds
(docs/benchmarks.md, Simulator step); the V-cycle instead of the exact inverse adds about 8 %.
"""

from __future__ import annotations

from collections import namedtuple

import math

import numpy as np

from wetcloth.kernels import kernel
from wetcloth.kernels.integration import copy
from wetcloth.kernels.lapack import band_arguments, band_factor, band_solve_two
from wetcloth.kernels.multigrid import (CENTRE, NX, NY, PAD_X, START, galerkin, level_sizes, make_hierarchy,
                                        padded_index, v_cycle_down, v_cycle_up)

#: Share of each stretch-spring family's stiffness in the t1 and t2 components.  The bending springs
#: (1 % of the stretch stiffness in the presets) are left out: they would double the bandwidth
#: (they reach two particles), and leaving them out did not change the iteration counts on the towel.
_SHARE = {"structural_x": (1.0, 0.0), "structural_y": (0.0, 1.0), "shear_up_right": (0.5, 0.5),
          "shear_up_left": (0.5, 0.5)}

#: Refactor when (beta h)^2 has changed by more than the factor REFACTOR_SCALE (the step by more
#: than 2x), or any particle's mass by more than REFACTOR_CHANGE, since the last factorisation.  An
#: impact that shrinks and regrows the step over a few frames then costs a few factorisations, not
#: one per step (with the banded factors on a 64 x 64 towel a factorisation cost as much as 20 CG
#: iterations; the multigrid's Galerkin products, 2 ms there, as about 3).
REFACTOR_SCALE = 4.0
REFACTOR_CHANGE = 0.25

#: A banded grid's factors are rebuilt from the Jacobian in hand when the last solve took more CG
#: iterations than JACOBIAN_REFRESH_AFTER times what a factorisation costs (``jacobian_refresh_pays``).
#: A factorisation of the band costs about kd / 4 CG iterations (kd the half-bandwidth; measured
#: idle: 16 us against 9.5 us per CG iteration on 9 x 9, 221 against 39 us on 21 x 29, 543
#: against 67 us on 32 x 32).  On a sinking 9 x 9 cloth the CG iterations per Newton iteration fell
#: from 15 to 5, on the sinking 21 x 29 towel from 14 to 7.  Over the towel's 90 s at 30 Hz
#: (counts): at 0.5, 1, 2 and never, 12 795, 14 321, 22 485 and 25 610 CG iterations with 2091,
#: 484, 93 and 20 factorisations; 1 costs least.  Refactored at every Newton iteration, the floating
#: towel (3 CG iterations per solve) lost more to the factorisations than it gained.
JACOBIAN_REFRESH_AFTER = 1.0

#: Multigrid (``multigrid.py``) on grids whose shorter side exceeds MULTIGRID_SIDE, coarsened until
#: the shorter side is at most COARSEST_SIDE; smaller grids are solved by the banded factors alone.
#: Crossover (``bench/large_steps.py preconditioner``: one application, both alternately, shared
#: machine, two runs at different loads): the multigrid 0.92-0.96x as fast as the banded solve on the
#: 21 x 29 towel, 0.76-0.99x at 24 x 24, 1.16-1.63x at 32 x 32, 1.03-1.59x at 48 x 48, 3.7x at 64 x 64;
#: CG needs about 8 % more iterations with it, so it pays from about 40 across.  Idle, without the
#: dispatcher's typing in each timed call: 0.98x at 21 x 29, 1.02x at 24 x 24, 1.55x at 32 x 32,
#: 1.54x at 48 x 48, 3.0x at 64 x 64 (docs/benchmarks.md, Large steps).
MULTIGRID_SIDE = 40
COARSEST_SIDE = 12

#: Stencil slot (``multigrid``) of the neighbour ``i + offset`` for each family in the preconditioner.
_SLOT = {"structural_x": 5, "structural_y": 7, "shear_up_right": 8, "shear_up_left": 6}

#: ``stiffness`` (F, n) per spring, N/m; ``slots`` (F) int64 each family's stencil slot
#: (-1: not in the preconditioner); ``grid`` the multigrid ``Hierarchy`` (one level on small grids);
#: on the coarsest level, ``order`` (n_c) the padded index of each band position and ``rank`` its
#: inverse over the level's padded points (-1 off the grid); ``bands`` (2, n_c, kd + 1) the factored
#: band matrices and ``rows`` the same factors by rows (``lapack.band_factor``); ``info`` (2, 5)
#: LAPACK arguments; ``reference`` [factored scale (s^2), 1 if factored, 1 if from the Jacobian]
#: and ``reference_mass`` (n) kg of the last factorisation with the rest stiffness; ``shares`` (2, F)
#: each family's share in t1, t2 (0 for the bending springs); ``jacobian_along`` (F, n) kg and
#: ``jacobian_mass`` (n) kg of the last factorisation from the Jacobian; ``frame`` (3, 3, n) each
#: particle's axes t1, t2, n; ``normal`` (n) the normal component's diagonal; ``local`` (2, n_c)
#: scratch of the band solves.
Plane = namedtuple("Plane", "stiffness slots grid order rank bands rows info reference reference_mass shares "
                            "jacobian_along jacobian_mass frame normal local")


def make_plane(grid_x: int, grid_y: int, offsets: np.ndarray, family_names: tuple, stiffness: np.ndarray,
               multigrid_side: int | None = None) -> Plane:
    """The preconditioner's arrays for a grid (row-major particles, ``grid_x`` per row); multigrid if
    the shorter side exceeds ``multigrid_side`` (default MULTIGRID_SIDE)."""
    n = grid_x * grid_y
    multigrid_side = MULTIGRID_SIDE if multigrid_side is None else multigrid_side
    sizes = level_sizes(grid_x, grid_y, COARSEST_SIDE) if min(grid_x, grid_y) > multigrid_side else [(grid_x, grid_y)]
    grid = make_hierarchy(sizes)
    cx, cy = sizes[-1]
    n_c = cx * cy
    col, row = np.arange(n_c) % cx, np.arange(n_c) // cx
    if cx <= cy:
        ordered, kd = np.arange(n_c), cx + 1
    else:  # order along the columns: the shorter side
        ordered, kd = (col * cy + row).argsort(), cy + 1
    kd = min(kd, n_c - 1)
    start, pad = grid.levels[-1, START], grid.levels[-1, PAD_X]
    order = (start + (row[ordered] + 1) * pad + col[ordered] + 1).astype(np.int64)
    rank = np.full(pad * (cy + 3), -1, dtype=np.int64)
    rank[order - start] = np.arange(n_c)
    shares = np.array([_SHARE.get(name, (0.0, 0.0)) for name in family_names]).reshape(len(family_names), 2).T.copy()
    slots = np.array([_SLOT.get(name, -1) for name in family_names], dtype=np.int64)
    info = np.stack([band_arguments(n_c, kd), band_arguments(n_c, kd)])
    return Plane(stiffness=np.ascontiguousarray(stiffness, dtype=float), slots=slots, grid=grid, order=order, rank=rank, bands=np.zeros((2, n_c, kd + 1)),
                 rows=np.zeros((2, n_c, kd + 1)), info=info,
                 reference=np.zeros(3), reference_mass=np.zeros(n), shares=shares,
                 jacobian_along=np.zeros((len(offsets), n)), jacobian_mass=np.zeros(n),
                 frame=np.repeat(np.eye(3)[:, :, None], n, axis=2), normal=np.ones(n), local=np.zeros((2, n_c)))


@kernel
def refresh(plane, offsets, mass, scale):
    """Factor ``M + scale L_c`` (scale = (beta h)^2, s^2) unless the factors in hand are close enough:
    the stencils of every level, and the banded Cholesky factors of the coarsest.
    Returns 1 if it factored, 0 if not, -1 if a matrix was not positive definite."""
    ref = plane.reference
    if ref[1] == 1.0 and 1.0 / REFACTOR_SCALE <= scale / ref[0] <= REFACTOR_SCALE:
        close = True
        for i in range(mass.shape[0]):
            if abs(mass[i] / plane.reference_mass[i] - 1.0) > REFACTOR_CHANGE:
                close = False
                break
        if close:
            return 0
    if _factor(plane, offsets, mass, scale, plane.stiffness) != 0:
        ref[1] = 0.0
        return -1
    ref[0] = scale
    ref[1] = 1.0
    ref[2] = 0.0
    copy(mass, plane.reference_mass)
    return 1


@kernel(inline="always")
def banded(plane):
    """Whether the in-plane systems are solved by the banded factors alone (no multigrid cycle)."""
    return plane.grid.levels.shape[0] == 1


@kernel
def jacobian_refresh_pays(plane, iterations):
    """Whether factoring from the Jacobian (``refresh_from_jacobian``) pays after a solve of
    ``iterations`` CG iterations: on banded grids only (a multigrid hierarchy's Galerkin products
    would cost more), see JACOBIAN_REFRESH_AFTER."""
    kd = plane.bands.shape[2] - 1
    return banded(plane) and iterations > JACOBIAN_REFRESH_AFTER * 0.25 * kd


@kernel
def refresh_from_jacobian(plane, offsets, mass, along):
    """Factor ``M + L(along)``: each spring weighted by its coefficient ``along`` (F, n) kg in the
    system matrix (damping and stiffness along its direction, zero stiffness where slack) times its
    family's share, ``mass`` (n) kg.  Kept in ``jacobian_along`` and ``jacobian_mass`` (a snapshot
    refactors from them).  Returns 1, or -1 if a matrix was not positive definite."""
    copy(along, plane.jacobian_along)
    copy(mass, plane.jacobian_mass)
    if _factor(plane, offsets, mass, 1.0, plane.jacobian_along) != 0:
        plane.reference[1] = 0.0
        return -1
    plane.reference[2] = 1.0
    return 1


@kernel
def _factor(plane, offsets, mass, scale, weights):
    """Build and factor ``M + scale L_c`` for c = t1, t2, with ``L_c`` the Laplacian of the springs
    weighted by ``weights`` (F, n) times each family's share in c (``plane.shares``): the stencils of
    every level and the banded Cholesky factors of the coarsest.  Returns 0, or LAPACK's info if a
    matrix was not positive definite."""
    n = mass.shape[0]
    grid = plane.grid
    levels, coef = grid.levels, grid.coef
    grid_x = levels[0, NX]
    for c in range(2):
        for k in range(9):
            for p in range(levels[0, PAD_X] * (levels[0, NY] + 3)):
                coef[c, k, p] = 0.0
        for i in range(n):
            coef[c, CENTRE, padded_index(levels, 0, i % grid_x, i // grid_x)] = mass[i]
        for f in range(offsets.shape[0]):
            k = plane.slots[f]
            if k < 0:
                continue
            off = offsets[f]
            share = scale * plane.shares[c, f]
            for i in range(n - off):
                w = share * weights[f, i]
                if w == 0.0:
                    continue
                p = padded_index(levels, 0, i % grid_x, i // grid_x)
                q = padded_index(levels, 0, (i + off) % grid_x, (i + off) // grid_x)
                coef[c, CENTRE, p] += w
                coef[c, CENTRE, q] += w
                coef[c, k, p] -= w
                coef[c, 8 - k, q] -= w
    coarsest = levels.shape[0] - 1
    for level in range(coarsest):
        galerkin(grid, level)
    start, pad = levels[coarsest, START], levels[coarsest, PAD_X]
    for c in range(2):
        band = plane.bands[c]
        band[...] = 0.0
        for position in range(plane.order.shape[0]):
            p = plane.order[position]
            band[position, 0] = coef[c, CENTRE, p]
            for k in range(9):
                other = plane.rank[p + (k // 3 - 1) * pad + k % 3 - 1 - start]
                if other > position:
                    band[position, other - position] = coef[c, k, p]
        info = band_factor(band, plane.rows[c], plane.info[c])
        if info != 0:
            return info
    return 0


@kernel
def follow_cloth(plane, grid_x, pos):
    """Set each particle's frame (t1, t2, n): t1 along its row, n normal to its row and column
    (central differences, one-sided at the edges), t2 = n x t1; the axes where that is degenerate."""
    n = pos.shape[1]
    frame = plane.frame
    for i in range(n):
        col = i % grid_x
        right = i + 1 if col + 1 < grid_x else i
        left = i - 1 if col > 0 else i
        up = i + grid_x if i + grid_x < n else i
        down = i - grid_x if i >= grid_x else i
        ax = pos[0, right] - pos[0, left]
        ay = pos[1, right] - pos[1, left]
        az = pos[2, right] - pos[2, left]
        bx = pos[0, up] - pos[0, down]
        by = pos[1, up] - pos[1, down]
        bz = pos[2, up] - pos[2, down]
        cx = ay * bz - az * by
        cy = az * bx - ax * bz
        cz = ax * by - ay * bx
        a_norm = math.sqrt(ax * ax + ay * ay + az * az)
        c_norm = math.sqrt(cx * cx + cy * cy + cz * cz)
        if not (c_norm > 1e-12 * a_norm * a_norm and a_norm > 0.0):  # crumpled past telling: the axes
            for r in range(3):
                for c in range(3):
                    frame[r, c, i] = 1.0 if r == c else 0.0
            continue
        ax /= a_norm
        ay /= a_norm
        az /= a_norm
        cx /= c_norm
        cy /= c_norm
        cz /= c_norm
        frame[0, 0, i] = ax
        frame[0, 1, i] = ay
        frame[0, 2, i] = az
        frame[2, 0, i] = cx
        frame[2, 1, i] = cy
        frame[2, 2, i] = cz
        frame[1, 0, i] = cy * az - cz * ay
        frame[1, 1, i] = cz * ax - cx * az
        frame[1, 2, i] = cx * ay - cy * ax


@kernel
def set_normal_diagonal(plane, mass, diagonal_blocks, blocks):
    """The normal component's diagonal: n^T B_i n for each particle's diagonal block B_i of A."""
    for i in range(mass.shape[0]):
        nx_, ny_, nz_ = plane.frame[2, 0, i], plane.frame[2, 1, i], plane.frame[2, 2, i]
        xx = diagonal_blocks[0, i] + blocks[0, i]
        yy = diagonal_blocks[1, i] + blocks[1, i]
        zz = diagonal_blocks[2, i] + blocks[2, i]
        xy = diagonal_blocks[3, i] + blocks[3, i]
        xz = diagonal_blocks[4, i] + blocks[4, i]
        yz = diagonal_blocks[5, i] + blocks[5, i]
        plane.normal[i] = mass[i] + (xx * nx_ * nx_ + yy * ny_ * ny_ + zz * nz_ * nz_
                                     + 2.0 * (xy * nx_ * ny_ + xz * nx_ * nz_ + yz * ny_ * nz_))


@kernel
def apply(plane, free, r, z):
    """z = P^-1 r, rows of pinned particles zero.  Loops over rows of the grid and views of them
    (see ``multigrid._neighbour_rows``: vectorised loops)."""
    f = plane.frame
    grid = plane.grid
    levels, b, x, local, normal = grid.levels, grid.b, grid.x, plane.local, grid.row
    grid_x, grid_y = levels[0, NX], levels[0, NY]
    for iy in range(grid_y):
        first, base = iy * grid_x, padded_index(levels, 0, 0, iy)
        r0, r1, r2 = r[0, first:first + grid_x], r[1, first:first + grid_x], r[2, first:first + grid_x]
        for c in range(2):
            f0, f1, f2 = f[c, 0, first:first + grid_x], f[c, 1, first:first + grid_x], f[c, 2, first:first + grid_x]
            bc = b[c, base:base + grid_x]
            for s in range(grid_x):
                bc[s] = f0[s] * r0[s] + f1[s] * r1[s] + f2[s] * r2[s]
    v_cycle_down(grid)
    for position in range(plane.order.shape[0]):
        for c in range(2):
            local[c, position] = b[c, plane.order[position]]
    band_solve_two(plane.bands, plane.rows, local)
    for position in range(plane.order.shape[0]):
        for c in range(2):
            x[c, plane.order[position]] = local[c, position]
    v_cycle_up(grid)
    for iy in range(grid_y):
        first, base = iy * grid_x, padded_index(levels, 0, 0, iy)
        r0, r1, r2 = r[0, first:first + grid_x], r[1, first:first + grid_x], r[2, first:first + grid_x]
        n0, n1, n2 = f[2, 0, first:first + grid_x], f[2, 1, first:first + grid_x], f[2, 2, first:first + grid_x]
        diagonal = plane.normal[first:first + grid_x]
        for s in range(grid_x):
            normal[s] = (n0[s] * r0[s] + n1[s] * r1[s] + n2[s] * r2[s]) / diagonal[s]
        x0, x1, weight = x[0, base:base + grid_x], x[1, base:base + grid_x], free[first:first + grid_x]
        for c in range(3):
            t1, t2, zc = f[0, c, first:first + grid_x], f[1, c, first:first + grid_x], z[c, first:first + grid_x]
            u = f[2, c, first:first + grid_x]
            for s in range(grid_x):
                zc[s] = weight[s] * (t1[s] * x0[s] + t2[s] * x1[s] + u[s] * normal[s])
