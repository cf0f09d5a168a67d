// Geometric multigrid on the cloth's grid: a symmetric V-cycle for COMPONENTS 9-point stencil matrices
// at once (port of bf41571:fmu_src/wetcloth/kernels/multigrid.py; level_sizes and make_hierarchy, which allocate, stay
// in Python).
//
// Each coarser grid keeps every other grid line (nx // 2 + 1 of nx); bilinear interpolation P,
// restriction P^T, Galerkin coarse matrices P^T A P; SWEEPS lexicographic Gauss-Seidel sweeps before
// the coarse correction and as many backwards after it (the cycle is then symmetric positive
// definite); the coarsest level is solved by the plane's banded factors.  Vectors are stored level
// after level, each level padded by one line of zeros before its first row and column and two after
// its last (levels[l, PAD_X] = nx + 3 values per padded row); coef[c, k, p] is the entry of point p
// and its neighbour p + (dy - 1) pad_x + dx - 1 for k = 3 dy + dx (CENTRE = 4 the diagonal).
//
// The cycle only approximates A^-1, so it runs in single precision (half the memory traffic of its
// stencils, twice the SIMD lanes): galerkin computes the stencils in double and rounds each level's
// into Hierarchy::single_coef and single_inverse_diagonal; the sweeps, residuals and transfers work on
// single_x, single_b, single_r.  The cycle takes level 0's b and the coarsest level's x (solved in
// double by the band factors) from the double vectors and gives back its results there.
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Gauss-Seidel sweeps before the coarse correction (and as many backwards after it).
inline constexpr Index SWEEPS = 1;
//: Stencil slot of the centre; neighbour (dx, dy) is 3 (dy + 1) + dx + 1.
inline constexpr Index CENTRE = 4;

//: Column `column` (LevelColumn) of row `level` of levels (L, 4).
inline Index level_value(const Index* levels, Index level, Index column) { return levels[level * 4 + column]; }

//: Index in the flat vectors of point (ix, iy) of `level`.
inline Index padded_index(const Index* levels, Index level, Index ix, Index iy) {
    return levels[level * 4 + START] + (iy + 1) * levels[level * 4 + PAD_X] + ix + 1;
}

//: Stencils of level + 1: P^T A P of those of `level`, and the inverse diagonals of `level`, for the
//: components first .. end - 1.
void galerkin(Hierarchy& hierarchy, Index level, Index first = 0, Index end = COMPONENTS);

//: One Gauss-Seidel sweep on `level`, in grid order (forward) or reversed; from_zero: x is zero before it.
//: The V-cycle's functions work on the first `components` components (2: t1 and t2; 3: and the normal).
void sweep(Hierarchy& hierarchy, Index level, bool forward, bool from_zero, Index components = COMPONENTS);

//: r = b - A x on `level` after one forward sweep from x = 0 (then -U x: only the neighbours the sweep
//: had not reached), and b of level + 1 = P^T r.
void restrict_swept_residual(Hierarchy& hierarchy, Index level, Index components = COMPONENTS);

//: x of `level` += P x of level + 1.
void interpolate(Hierarchy& hierarchy, Index level, Index components = COMPONENTS);

//: First half of the V-cycle from b of level 0: on each level but the coarsest, smooth from x = 0 and
//: restrict the residual; leaves the coarsest level's right-hand side in b.
void v_cycle_down(Hierarchy& hierarchy, Index components = COMPONENTS);

//: Second half, once x of the coarsest level holds its solution: on each finer level add the
//: interpolated correction and smooth backwards.  Leaves the result in x of level 0.
void v_cycle_up(Hierarchy& hierarchy, Index components = COMPONENTS);

}  // namespace wc
