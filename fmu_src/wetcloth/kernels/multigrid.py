"""Geometric multigrid on the cloth's grid: a symmetric V-cycle for two 9-point stencil matrices at once.

The plane preconditioner (``plane.py``) solves two scalar systems ``M + s L_c`` on the particle grid
(``nx`` x ``ny``, row-major).  A direct banded solve costs O(n x shorter side) per application; a
V-cycle costs O(n):

* **levels**: each coarser grid keeps every other grid line, ``nx // 2 + 1`` of ``nx`` (an even
  count gets one line past the end, which interpolation weighs by 1/2 only);
* **transfer**: bilinear interpolation ``P`` (fine point ``f`` takes its coarse parents
  ``f // 2`` and ``(f + 1) // 2`` along each axis with weight 1/2 each, which is weight 1 on an even
  ``f``), restriction its transpose;
* **coarse matrices**: Galerkin products ``P^T A P``, 9-point stencils again, built in O(n)
  (16 products per fine matrix entry);
* **smoothing**: ``SWEEPS`` lexicographic Gauss-Seidel sweeps before the coarse correction and the
  same sweeps backwards after it, so that the cycle, as a linear map, is symmetric positive
  definite (the post-smoother is the adjoint of the pre-smoother, and Gauss-Seidel converges on
  a symmetric positive definite matrix);
* **coarsest level**: solved exactly by the banded Cholesky factors that ``plane.py`` keeps.

Vectors are stored level after level in one flat array per component, each level padded by one
line of zeros before its first row and column and two after its last (``levels[l, PAD_X]`` =
``nx + 3`` values per padded row), so that stencils, restriction and interpolation read
neighbours without bounds checks.  A level's stencil ``coef[c, k, p]`` holds the matrix entry of
point ``p`` and its neighbour ``p + (dy - 1) * pad_x + (dx - 1)`` for ``k = 3 dy + dx``
(``CENTRE`` = 4 the diagonal), zero where there is no neighbour.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from wetcloth.kernels import kernel

#: Gauss-Seidel sweeps before the coarse correction (and as many backwards after it).
SWEEPS = 1
#: Stencil slot of the centre and of each neighbour direction (dx, dy): 3 (dy + 1) + dx + 1.
CENTRE = 4
#: Columns of ``levels``: the grid's points per row and per column, first padded index, padded row length.
NX, NY, START, PAD_X = range(4)

#: ``levels`` (L + 1, 4) int64, level 0 the particles' grid; ``coef`` (2, 9, size) the stencils of
#: both components' matrices; ``inverse_diagonal`` (2, size); ``x``, ``b``, ``r`` (2, size)
#: solution, right-hand side and residual of each level (ghost points stay zero); ``row`` (nx + 3)
#: scratch of a smoothing sweep.
Hierarchy = namedtuple("Hierarchy", "levels coef inverse_diagonal x b r row")


def level_sizes(nx: int, ny: int, coarsest_side: int) -> list[tuple[int, int]]:
    """The grids of the hierarchy, finest first: halved while the shorter side exceeds ``coarsest_side``."""
    sizes = [(nx, ny)]
    while min(sizes[-1]) > coarsest_side:
        cx, cy = sizes[-1]
        sizes.append((cx // 2 + 1, cy // 2 + 1))
    return sizes


def make_hierarchy(sizes: list[tuple[int, int]]) -> Hierarchy:
    """Zeroed arrays for the grids ``sizes`` (finest first)."""
    levels = np.zeros((len(sizes), 4), dtype=np.int64)
    start = 0
    for l, (nx, ny) in enumerate(sizes):
        levels[l] = nx, ny, start, nx + 3
        start += (nx + 3) * (ny + 3)
    vector = lambda: np.zeros((2, start))  # noqa: E731
    return Hierarchy(levels=levels, coef=np.zeros((2, 9, start)), inverse_diagonal=vector(), x=vector(),
                     b=vector(), r=vector(), row=np.zeros(sizes[0][0] + 3))


@kernel(inline="always")
def padded_index(levels, level, ix, iy):
    """Index in the flat vectors of point (ix, iy) of ``level``."""
    return levels[level, START] + (iy + 1) * levels[level, PAD_X] + ix + 1


@kernel
def galerkin(hierarchy, level):
    """Stencils of ``level + 1``: ``P^T A P`` of those of ``level``, and the inverse diagonals of ``level``."""
    levels, coef = hierarchy.levels, hierarchy.coef
    nx, ny = levels[level, NX], levels[level, NY]
    coarse_start, coarse_pad = levels[level + 1, START], levels[level + 1, PAD_X]
    coarse_end = coarse_start + coarse_pad * (levels[level + 1, NY] + 3)
    for c in range(2):
        for k in range(9):
            for q in range(coarse_start, coarse_end):
                coef[c, k, q] = 0.0
        for iy in range(ny):
            for ix in range(nx):
                p = padded_index(levels, level, ix, iy)
                hierarchy.inverse_diagonal[c, p] = 1.0 / coef[c, CENTRE, p]
                for k in range(9):
                    a = coef[c, k, p]
                    if a == 0.0:
                        continue
                    jx, jy = ix + k % 3 - 1, iy + k // 3 - 1
                    # parents of (ix, iy) and of (jx, jy), each of the four with weight 1/4
                    # (a parent appears twice along an axis where the fine index is even)
                    for a_y in range(2):
                        py = (iy + a_y) // 2
                        for a_x in range(2):
                            px = (ix + a_x) // 2
                            q = coarse_start + (py + 1) * coarse_pad + px + 1
                            for b_y in range(2):
                                qy = (jy + b_y) // 2
                                for b_x in range(2):
                                    qx = (jx + b_x) // 2
                                    coef[c, 3 * (qy - py + 1) + qx - px + 1, q] += 0.0625 * a


@kernel
def _zero_level(hierarchy, level, v):
    levels = hierarchy.levels
    start = levels[level, START]
    for c in range(2):
        for p in range(start, start + levels[level, PAD_X] * (levels[level, NY] + 3)):
            v[c, p] = 0.0


@kernel(inline="always")
def _neighbour_rows(v, base, pad, nx):
    """Views of ``v`` around the row of ``nx`` points from padded index ``base``: the row below, the
    row and the row above, each from one point before the row to one after it (``nx + 2`` values).
    Indexing views from zero, unlike ``v[base + s - pad - 1]``, needs no wraparound check, which
    keeps the loops over a row vectorised (3x faster measured)."""
    return (v[base - pad - 1:base - pad + nx + 1], v[base - 1:base + nx + 1], v[base + pad - 1:base + pad + nx + 1])


@kernel
def _sweep(hierarchy, level, forward, from_zero):
    """One Gauss-Seidel sweep on ``level``, rows and points in grid order (``forward``) or reversed;
    ``from_zero``: x is zero before it (a forward sweep then reads only the rows already done).
    Each row in two passes: what is known before the row's own recurrence (vectorised), then the
    recurrence along the row."""
    levels, coef, inv, x, b, known = (hierarchy.levels, hierarchy.coef, hierarchy.inverse_diagonal, hierarchy.x,
                                      hierarchy.b, hierarchy.row)
    nx, ny, pad = levels[level, NX], levels[level, NY], levels[level, PAD_X]
    for c in range(2):
        for t in range(ny):
            iy = t if forward else ny - 1 - t
            base = padded_index(levels, level, 0, iy)
            end = base + nx
            below, here, above = _neighbour_rows(x[c], base, pad, nx)
            a0, a1, a2, a3 = coef[c, 0, base:end], coef[c, 1, base:end], coef[c, 2, base:end], coef[c, 3, base:end]
            a5, a6, a7, a8 = coef[c, 5, base:end], coef[c, 6, base:end], coef[c, 7, base:end], coef[c, 8, base:end]
            bc, ic, xc = b[c, base:end], inv[c, base:end], x[c, base:end]
            if forward and from_zero:
                for s in range(nx):
                    known[s] = bc[s] - a0[s] * below[s] - a1[s] * below[s + 1] - a2[s] * below[s + 2]
            elif forward:
                for s in range(nx):
                    known[s] = (bc[s] - a0[s] * below[s] - a1[s] * below[s + 1] - a2[s] * below[s + 2]
                                - a5[s] * here[s + 2] - a6[s] * above[s] - a7[s] * above[s + 1] - a8[s] * above[s + 2])
            else:
                for s in range(nx):
                    known[s] = (bc[s] - a0[s] * below[s] - a1[s] * below[s + 1] - a2[s] * below[s + 2]
                                - a3[s] * here[s] - a6[s] * above[s] - a7[s] * above[s + 1] - a8[s] * above[s + 2])
            last = 0.0  # the row's neighbour just updated (none before the first)
            if forward:
                for s in range(nx):
                    last = (known[s] - a3[s] * last) * ic[s]
                    xc[s] = last
            else:
                for s in range(nx - 1, -1, -1):
                    last = (known[s] - a5[s] * last) * ic[s]
                    xc[s] = last


@kernel
def _restrict_residual(hierarchy, level):
    """r = b - A x on ``level``, and b of ``level + 1`` = P^T r (each coarse point gathers its fine
    point with weight 1, the fine points beside it with 1/2 and those diagonal to it with 1/4)."""
    levels, coef, x, b, r = hierarchy.levels, hierarchy.coef, hierarchy.x, hierarchy.b, hierarchy.r
    nx, ny, pad = levels[level, NX], levels[level, NY], levels[level, PAD_X]
    for c in range(2):
        for iy in range(ny):
            base = padded_index(levels, level, 0, iy)
            end = base + nx
            below, here, above = _neighbour_rows(x[c], base, pad, nx)
            a0, a1, a2, a3 = coef[c, 0, base:end], coef[c, 1, base:end], coef[c, 2, base:end], coef[c, 3, base:end]
            a4, a5, a6, a7 = coef[c, 4, base:end], coef[c, 5, base:end], coef[c, 6, base:end], coef[c, 7, base:end]
            a8, bc, rc = coef[c, 8, base:end], b[c, base:end], r[c, base:end]
            for s in range(nx):
                rc[s] = (bc[s] - a0[s] * below[s] - a1[s] * below[s + 1] - a2[s] * below[s + 2]
                         - a3[s] * here[s] - a4[s] * here[s + 1] - a5[s] * here[s + 2]
                         - a6[s] * above[s] - a7[s] * above[s + 1] - a8[s] * above[s + 2])
        coarse_nx = levels[level + 1, NX]
        for iy in range(levels[level + 1, NY]):
            coarse = padded_index(levels, level + 1, 0, iy)
            below, here, above = _neighbour_rows(r[c], padded_index(levels, level, 0, 2 * iy), pad, 2 * coarse_nx)
            bc = b[c, coarse:coarse + coarse_nx]
            for s in range(coarse_nx):
                t = 2 * s
                bc[s] = (here[t + 1] + 0.5 * (here[t] + here[t + 2] + below[t + 1] + above[t + 1])
                         + 0.25 * (below[t] + below[t + 2] + above[t] + above[t + 2]))


@kernel
def _interpolate(hierarchy, level):
    """x of ``level`` += P x of ``level + 1``."""
    levels, x = hierarchy.levels, hierarchy.x
    nx, ny = levels[level, NX], levels[level, NY]
    coarse_nx = levels[level + 1, NX]
    for c in range(2):
        for iy in range(ny):
            low = padded_index(levels, level + 1, 0, iy // 2)
            high = padded_index(levels, level + 1, 0, (iy + 1) // 2)
            base = padded_index(levels, level, 0, iy)
            xc, lc, hc = x[c, base:base + nx], x[c, low:low + coarse_nx], x[c, high:high + coarse_nx]
            for ix in range(nx):
                left, right = ix // 2, (ix + 1) // 2
                xc[ix] += 0.25 * (lc[left] + lc[right] + hc[left] + hc[right])


@kernel
def v_cycle_down(hierarchy):
    """First half of the V-cycle from ``b`` of level 0: on each level but the coarsest, smooth from
    x = 0 and restrict the residual; leaves the coarsest level's right-hand side in ``b``."""
    for level in range(hierarchy.levels.shape[0] - 1):
        _zero_level(hierarchy, level, hierarchy.x)
        for sweep in range(SWEEPS):
            _sweep(hierarchy, level, True, sweep == 0)
        _restrict_residual(hierarchy, level)


@kernel
def v_cycle_up(hierarchy):
    """Second half, once ``x`` of the coarsest level holds its solution: on each finer level,
    add the interpolated correction and smooth backwards.  Leaves the result in ``x`` of level 0."""
    for level in range(hierarchy.levels.shape[0] - 2, -1, -1):
        _interpolate(hierarchy, level)
        for _ in range(SWEEPS):
            _sweep(hierarchy, level, False, False)
