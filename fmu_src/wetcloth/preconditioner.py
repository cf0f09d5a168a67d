"""The arrays of the implicit solves' preconditioner (the compiled core's ``plane.cpp``,
``multigrid.cpp`` and ``band.cpp``; docs/core.md): each particle's frame, the in-plane stiffness as
two scalar systems on the particle grid, a multigrid hierarchy on large grids and the banded
Cholesky factors of its coarsest level.

The system matrix of an implicit step, ``A = M - h C - h^2 K``, is dominated by the stretch springs,
stiff along their own direction only: a flat cloth is stiff in its plane and soft across it.  In
each particle's frame (t1, t2, n) the t1 and t2 components each get a scalar matrix ``M + h^2 L_c``
(``L_c`` the graph Laplacian of the springs weighted by their stiffness times the share of their
direction in that component), factored only when the step or the masses changed much; the normal
component gets the normal-normal entry of each particle's diagonal block of A.  Small grids solve the
two systems exactly with banded factors; on grids whose shorter side exceeds MULTIGRID_SIDE one
multigrid V-cycle approximates their inverse, with the banded factors on its coarsest grid only.  A
mesh's systems (``make_mesh_plane``) are sparse, over its listed springs, and on large meshes an
algebraic multigrid cycle (pyamg's smoothed aggregation of the spring graph) takes the geometric one's
place.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from wetcloth._core import (ALGEBRAIC_COLUMNS, ALGEBRAIC_SIZE, COARSEST_SIDE, COARSEST_SIZE, COMPONENTS,
                            MULTIGRID_SIDE)

#: Share of each stretch-spring family's stiffness in the t1 and t2 components.  The bending springs
#: (1 % of the stretch stiffness in the presets) are left out: they would double the bandwidth
#: (they reach two particles), and leaving them out did not change the iteration counts on the towel.
_SHARE = {"structural_x": (1.0, 0.0), "structural_y": (0.0, 1.0), "shear_up_right": (0.5, 0.5),
          "shear_up_left": (0.5, 0.5)}
#: Stencil slot of the neighbour ``i + offset`` for each family in the preconditioner (slot
#: ``3 (dy + 1) + dx + 1`` of the 9-point stencil; 4 is the centre).
_SLOT = {"structural_x": 5, "structural_y": 7, "shear_up_right": 8, "shear_up_left": 6}

#: The multigrid hierarchy: ``levels`` (L, 4) int64 (nx, ny, first padded index, padded row length),
#: level 0 the particles' grid; ``coef`` (2, 9, size) both components' 9-point stencils;
#: ``inverse_diagonal``, ``x``, ``b`` (2, size); ``row`` (nx + 3) scratch.  Each level is
#: padded by one line of zeros before its first row and column and two after its last.  The V-cycle
#: runs in single precision (float32) on ``single_coef``, ``single_inverse_diagonal``, ``single_x``,
#: ``single_b``, ``single_r``, of the same shapes (``galerkin`` rounds the stencils into them).
Hierarchy = namedtuple("Hierarchy", "levels coef inverse_diagonal x b row single_coef single_inverse_diagonal "
                                    "single_x single_b single_r")

#: ``stiffness`` (F, n) per spring, N/m; ``slots`` (F) int64 each family's stencil slot (-1: left
#: out); ``grid`` the ``Hierarchy`` (one level on small grids); on the coarsest level, ``order``
#: (n_c) the padded index of each band position and ``rank`` its inverse over the level's padded
#: points (-1 off the grid); ``bands`` (2, n_c, kd + 1) the factored band matrices and ``rows`` the
#: same factors by rows; ``reference`` [factored scale (s^2), 1 if factored, 1 if from the Jacobian,
#: 1 if the normal component has its system rather than its diagonal]
#: and ``reference_mass`` (n) kg of the last factorisation with the rest stiffness; ``shares``
#: (2, F) each family's share in t1, t2; ``jacobian_along`` (F, n) kg and ``jacobian_mass`` (n) kg
#: of the last factorisation from the Jacobian; ``frame`` (3, 3, n) each particle's axes t1, t2, n;
#: ``normal`` (n) the normal component's diagonal; ``local`` (2, n_c) scratch of the band solves;
#: ``algebraic`` a mesh's ``Algebraic`` hierarchy (no levels on a grid).  On a mesh ``order`` and
#: ``rank`` are those of its coarsest algebraic level's band.
Plane = namedtuple("Plane", "stiffness slots grid order rank bands rows reference reference_mass shares "
                            "jacobian_along jacobian_mass frame normal local algebraic")

#: A mesh's algebraic multigrid hierarchy (the core's mesh_plane.cpp; core.hpp's Algebraic): ``levels``
#: (L, ALGEBRAIC_COLUMNS) int64 each level's size, first index in the per-level vectors, and first
#: index in ``a_start``, ``p_start``, ``r_start``; every level's matrix in CSR (``a_start`` absolute
#: positions in ``a_column``, level-local columns (int32), ``a_value`` (COMPONENTS, entries));
#: ``diagonal`` each row's diagonal position; the prolongators P and their transposes R in CSR (columns
#: int32); ``spring_entries`` (2, T) the positions of each coupled spring's (i, j) and (j, i) at level 0 (the in-plane
#: springs, then the hinges' terms that fixed steps couple: make_mesh_plane);
#: ``inverse_diagonal``, ``x``, ``b``, ``r`` (COMPONENTS, vectors: r the residuals R restricts; the cycle
#: keeps x, b and r's first two rows as t1 and t2 side by side, ``[2 v + c]``); ``marker`` (n) int64 scratch.
Algebraic = namedtuple("Algebraic", "levels a_start a_column a_value diagonal p_start p_column p_value r_start "
                                    "r_column r_value spring_entries inverse_diagonal x b r marker")


def level_sizes(nx: int, ny: int, coarsest_side: int) -> list[tuple[int, int]]:
    """The grids of the hierarchy, finest first: halved while the shorter side exceeds ``coarsest_side``
    (each coarser grid keeps every other grid line, ``nx // 2 + 1`` of ``nx``)."""
    sizes = [(nx, ny)]
    while min(sizes[-1]) > coarsest_side:
        cx, cy = sizes[-1]
        sizes.append((cx // 2 + 1, cy // 2 + 1))
    return sizes


def make_hierarchy(sizes: list[tuple[int, int]]) -> Hierarchy:
    """Zeroed arrays for the grids ``sizes`` (finest first)."""
    levels = np.zeros((len(sizes), 4), dtype=np.int64)
    start = 0
    for level, (nx, ny) in enumerate(sizes):
        levels[level] = nx, ny, start, nx + 3
        start += (nx + 3) * (ny + 3)
    return _hierarchy(levels, start, sizes[0][0] + 3)


def _hierarchy(levels: np.ndarray, size: int, row: int) -> Hierarchy:
    """Zeroed arrays of a hierarchy of ``size`` padded points over ``levels``, scratch ``row`` long."""
    def vectors(dtype):
        return np.zeros((COMPONENTS, size), dtype=dtype)
    return Hierarchy(levels=levels, coef=np.zeros((COMPONENTS, 9, size)), inverse_diagonal=vectors(np.float64),
                     x=vectors(np.float64), b=vectors(np.float64), row=np.zeros(row),
                     single_coef=np.zeros((COMPONENTS, 9, size), dtype=np.float32),
                     single_inverse_diagonal=vectors(np.float32), single_x=vectors(np.float32),
                     single_b=vectors(np.float32), single_r=vectors(np.float32))


def make_plane(grid_x: int, grid_y: int, family_names: tuple, stiffness: np.ndarray,
               multigrid_side: int | None = None) -> Plane:
    """The preconditioner's arrays for a grid (row-major particles, ``grid_x`` per row); multigrid if
    the shorter side exceeds ``multigrid_side`` (default MULTIGRID_SIDE)."""
    n = grid_x * grid_y
    families = len(family_names)
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
    start, pad = grid.levels[-1, 2], grid.levels[-1, 3]
    order = (start + (row[ordered] + 1) * pad + col[ordered] + 1).astype(np.int64)
    rank = np.full(pad * (cy + 3), -1, dtype=np.int64)
    rank[order - start] = np.arange(n_c)
    shares = np.array([_SHARE.get(name, (0.0, 0.0)) for name in family_names]).reshape(families, 2).T.copy()
    slots = np.array([_SLOT.get(name, -1) for name in family_names], dtype=np.int64)
    return Plane(stiffness=np.ascontiguousarray(stiffness, dtype=float), slots=slots, grid=grid, order=order, rank=rank,
                 bands=np.zeros((COMPONENTS, n_c, kd + 1)), rows=np.zeros((COMPONENTS, n_c, kd + 1)), reference=np.zeros(4),
                 reference_mass=np.zeros(n), shares=shares, jacobian_along=np.zeros((families, n)),
                 jacobian_mass=np.zeros(n), frame=np.repeat(np.eye(3)[:, :, None], n, axis=2), normal=np.ones(n),
                 local=np.zeros((COMPONENTS, n_c)), algebraic=make_algebraic([], []))


def reverse_cuthill_mckee(graph) -> np.ndarray:
    """The reverse Cuthill-McKee order (int64) of the points of sparse ``graph`` (its pattern, made
    symmetric): breadth first from a point of least degree in each component, neighbours by ascending
    degree, ties by index.  (scipy's own breaks ties by numpy's unstable argsort, whose order differs
    between numpy versions: Blender's numpy 1.26 and 2.x gave a mesh cloth different preconditioners.)"""
    pattern = (abs(graph) + abs(graph).T).tocsr()
    indptr, indices = pattern.indptr, pattern.indices
    degree = np.diff(indptr)
    seen = np.zeros(pattern.shape[0], dtype=bool)
    order = []
    for start in np.argsort(degree, kind="stable"):
        if seen[start]:
            continue
        seen[start] = True
        queue, head = [int(start)], 0
        while head < len(queue):
            point = queue[head]
            head += 1
            near = np.unique(indices[indptr[point]:indptr[point + 1]])
            near = near[~seen[near]]
            near = near[np.argsort(degree[near], kind="stable")]
            seen[near] = True
            queue.extend(near.tolist())
        order.extend(queue)
    return np.array(order[::-1], dtype=np.int64)


def _csr_parts(matrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(indptr, indices, data) of a scipy matrix in canonical CSR (sorted, no duplicates)."""
    matrix = matrix.tocsr()
    matrix.sum_duplicates()
    matrix.sort_indices()
    return matrix.indptr.astype(np.int64), matrix.indices.astype(np.int64), matrix.data.astype(float)


def make_algebraic(patterns: list, prolongators: list) -> Algebraic:
    """The hierarchy's arrays for the matrices' ``patterns`` (scipy, finest first, each holding its
    diagonal and every entry of R A P of the one before) and the ``prolongators`` (scipy) between them;
    both empty on a grid."""
    sizes = [pattern.shape[0] for pattern in patterns]
    levels = np.zeros((len(sizes), ALGEBRAIC_COLUMNS), dtype=np.int64)
    a_start, a_column, diagonal, p_start, p_column, p_value, r_start, r_column, r_value = ([] for _ in range(9))
    entries = p_entries = r_entries = vector = a_rows = p_rows = r_rows = 0
    for level, pattern in enumerate(patterns):
        levels[level] = sizes[level], vector, a_rows, p_rows, r_rows
        indptr, indices, _ = _csr_parts(pattern)
        diagonal.append(entries + _positions(indptr, indices, np.arange(sizes[level]), np.arange(sizes[level])))
        a_start.append(entries + indptr)
        a_column.append(indices)
        entries += len(indices)
        vector += sizes[level]
        a_rows += sizes[level] + 1
        if level < len(prolongators):
            for transpose, (starts, columns, values) in ((False, (p_start, p_column, p_value)),
                                                         (True, (r_start, r_column, r_value))):
                indptr, indices, data = _csr_parts(prolongators[level].T if transpose else prolongators[level])
                base = r_entries if transpose else p_entries
                starts.append(base + indptr)
                columns.append(indices)
                values.append(data)
            p_entries += len(p_column[-1])
            r_entries += len(r_column[-1])
            p_rows += sizes[level] + 1
            r_rows += sizes[level + 1] + 1

    def joined(parts, dtype=np.int64):
        return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)

    return Algebraic(levels=levels, a_start=joined(a_start), a_column=joined(a_column, np.int32),
                     a_value=np.zeros((COMPONENTS, entries)), diagonal=joined(diagonal), p_start=joined(p_start),
                     p_column=joined(p_column, np.int32), p_value=joined(p_value, float), r_start=joined(r_start),
                     r_column=joined(r_column, np.int32), r_value=joined(r_value, float),
                     spring_entries=np.zeros((2, 0), dtype=np.int64), inverse_diagonal=np.zeros((COMPONENTS, vector)),
                     x=np.zeros((COMPONENTS, vector)), b=np.zeros((COMPONENTS, vector)), r=np.zeros((COMPONENTS, vector)),
                     marker=np.zeros(max(sizes, default=0), dtype=np.int64))


def aggregation(laplacian, coarsest_size: int = COARSEST_SIZE) -> list:
    """The prolongators (scipy CSR, finest first) of pyamg's smoothed aggregation of a spring graph's
    ``laplacian`` (weighted by the springs' rest stiffness), coarsened until a level has at most
    ``coarsest_size`` points; the constants its near null space.  The prolongators' Jacobi smoothing
    is weighted row by row (Gershgorin): pyamg's default estimates a spectral radius from a random
    vector, which would make each process's hierarchy, and so its runs, differ in the last digits."""
    import pyamg

    hierarchy = pyamg.smoothed_aggregation_solver(laplacian, B=np.ones((laplacian.shape[0], 1)),
                                                  smooth=("jacobi", {"omega": 4.0 / 3.0, "weighting": "local"}),
                                                  max_coarse=coarsest_size)
    return [level.P.tocsr() for level in hierarchy.levels[:-1]]


def make_mesh_plane(n: int, pairs: np.ndarray, in_plane_count: int, stiffness: np.ndarray,
                    algebraic_size: int = ALGEBRAIC_SIZE, hinge_count: int = 0) -> Plane:
    """The preconditioner's arrays for a mesh of n particles whose listed springs join ``pairs`` (2, S),
    the first ``in_plane_count`` in the cloth's plane (tension-only and buckling: Topology.in_plane_count)
    with rest ``stiffness`` (S,) N/m, of them the last ``hinge_count`` hinges' terms that its systems from
    the Jacobian couple too (the core's mesh_plane.cpp).

    Its systems are sparse matrices over the in-plane springs (and those hinges' terms); on more than ``algebraic_size``
    particles (default ALGEBRAIC_SIZE) a smoothed aggregation of their graph (``aggregation``) gives
    the coarser levels.  The coarsest level's matrices are band matrices in the reverse Cuthill-McKee
    order of its graph (scipy), which keeps the band narrow: ``order`` lists its points in band order,
    ``rank`` is each point's band position, ``kd`` the widest entry's reach in that order.
    """
    from scipy.sparse import coo_matrix, identity

    first, second = pairs[:, :in_plane_count]
    k = stiffness[:in_plane_count]
    # the level-0 pattern's pairs: the in-plane springs, then the hinges' terms it couples
    ends = np.concatenate([pairs[:, :in_plane_count], pairs[:, pairs.shape[1] - hinge_count:]], axis=1)
    laplacian = coo_matrix((np.concatenate([k, k, -k, -k]), (np.concatenate([first, second, first, second]),
                                                              np.concatenate([first, second, second, first]))),
                           shape=(n, n)).tocsr()
    ones = coo_matrix((np.ones(2 * ends.shape[1]), (np.concatenate(ends), np.concatenate(ends[::-1]))),
                      shape=(n, n)) + identity(n)
    patterns = [ones.tocsr()]
    prolongators = aggregation(laplacian) if n > algebraic_size else []
    for prolongator in prolongators:
        magnitude = abs(prolongator)
        patterns.append((magnitude.T @ patterns[-1] @ magnitude).tocsr())
    algebraic = make_algebraic(patterns, prolongators)
    indptr, indices, _ = _csr_parts(patterns[0])
    coarsest = patterns[-1]
    n_c = coarsest.shape[0]
    graph = coo_matrix((np.ones(ends.shape[1]), tuple(ends)), shape=(n, n)) if not prolongators else coarsest
    order = reverse_cuthill_mckee(graph)
    rank = np.empty(n_c, dtype=np.int64)
    rank[order] = np.arange(n_c)
    rows, columns = coarsest.nonzero()
    kd = int(np.abs(rank[rows] - rank[columns]).max()) if n_c > 1 else 0
    kd = max(1, min(kd, n_c - 1))
    grid = _hierarchy(np.zeros((0, 4), dtype=np.int64), 0, 0)
    count = pairs.shape[1]
    return Plane(stiffness=np.ascontiguousarray(stiffness, dtype=float), slots=np.zeros(0, dtype=np.int64), grid=grid,
                 order=order, rank=rank, bands=np.zeros((COMPONENTS, n_c, kd + 1)),
                 rows=np.zeros((COMPONENTS, n_c, kd + 1)), reference=np.zeros(4), reference_mass=np.zeros(n),
                 shares=np.zeros((2, 0)), jacobian_along=np.zeros(count), jacobian_mass=np.zeros(n),
                 frame=np.repeat(np.eye(3)[:, :, None], n, axis=2), normal=np.ones(n), local=np.zeros((COMPONENTS, n_c)),
                 algebraic=algebraic._replace(spring_entries=np.vstack([_positions(indptr, indices, *ends),
                                                                        _positions(indptr, indices, *ends[::-1])])))


def _positions(indptr: np.ndarray, indices: np.ndarray, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """Positions of the entries (rows, columns) in a canonical CSR pattern (each present)."""
    size = len(indptr) - 1
    keys = np.repeat(np.arange(size, dtype=np.int64), np.diff(indptr)) * size + indices  # ascending
    return np.searchsorted(keys, np.asarray(rows, dtype=np.int64) * size + columns).astype(np.int64)


def plane_for(topology, fixed_steps: bool = False) -> Plane:
    """The preconditioner's arrays for a cloth ``topology`` (``wetcloth.topology.Topology``): a grid's or a mesh's.
    With ``fixed_steps`` (tolerance 0: systems from the Jacobian at every Newton iteration) a mesh's systems couple
    its hinges' terms too: a hinged 31 x 31 quad sheet at 1/24 s steps took 10x the CG iterations without them;
    with adaptive steps the wider pattern only costs (13 % more time at the same counts)."""
    if not topology.listed:
        return make_plane(topology.nx, topology.ny, topology.spring_family_names, topology.spring_stiffness)
    return make_mesh_plane(topology.n, topology.pairs, topology.in_plane_count, topology.pair_stiffness,
                           hinge_count=topology.hinge_count if fixed_steps else 0)
