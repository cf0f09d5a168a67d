// The preconditioner of the implicit solves: the cloth's in-plane stiffness, factored once (port of
// bf41571:fmu_src/wetcloth/kernels/plane.py; multigrid.cpp and band.cpp are its parts).
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Refactor when (beta h)^2 has changed by more than the factor REFACTOR_SCALE (the step by more than
//: 2x), or any particle's mass by more than REFACTOR_CHANGE, since the last factorisation: an impact
//: that shrinks and regrows the step over a few frames then costs a few factorisations, not one per step.
inline constexpr double REFACTOR_SCALE = 4.0;
inline constexpr double REFACTOR_CHANGE = 0.25;

//: A banded grid's factors are rebuilt from the Jacobian in hand when the last solve took more CG
//: iterations than JACOBIAN_REFRESH_AFTER times what a factorisation costs (about kd / 4 CG
//: iterations, kd the half-bandwidth; plane.py has the measurements behind 1).
inline constexpr double JACOBIAN_REFRESH_AFTER = 1.0;

//: Multigrid on grids whose shorter side exceeds MULTIGRID_SIDE, coarsened until the shorter side is
//: at most COARSEST_SIDE; smaller grids are solved by the banded factors alone (make_plane, Python).
inline constexpr Index MULTIGRID_SIDE = 40;
inline constexpr Index COARSEST_SIDE = 12;

//: An algebraic multigrid hierarchy on meshes of more than ALGEBRAIC_SIZE particles, coarsened until
//: a level has at most COARSEST_SIZE (make_mesh_plane, Python); smaller meshes are solved by the band
//: factors alone.  Irregular discs landing on water and hanging in air, 1 s (docs/benchmarks.md): at
//: 347 vertices the band took 0.24 / 0.28 s, the hierarchy 0.21 / 0.44 s; at 661 both 0.47 / 1.05 s;
//: at 1076 the band 1.07 / 2.63 s, the hierarchy 0.83 / 2.12 s (bench/mesh_preconditioner.py).
inline constexpr Index ALGEBRAIC_SIZE = 700;
inline constexpr Index COARSEST_SIZE = 100;

//: Factor M + scale L_c (scale = (beta h)^2, s^2) unless the factors in hand are close enough.
//: Returns 1 if it factored, 0 if not, -1 if a matrix was not positive definite.
Index refresh(Plane& plane, const Cloth& cloth, const double* mass, double scale);

//: Whether the in-plane systems are solved by the banded factors alone (no multigrid cycle: a small
//: grid, or a small mesh, whose Plane has no grid levels and one algebraic level).
inline bool banded(const Plane& plane) { return plane.grid.level_count <= 1 && plane.algebraic.level_count <= 1; }

//: Whether factoring from the Jacobian pays after a solve of `iterations` CG iterations.
bool jacobian_refresh_pays(const Plane& plane, double iterations);

//: A mesh's algebraic hierarchy is rebuilt from the Jacobian in hand when its cloth has buckling springs
//: and the last solve took more than MESH_REFRESH_AFTER CG iterations: their slopes near rest vary from
//: 0 to 4k/3 within a strain of BUCKLING_ROUNDING, so the rest-stiffness systems match a floating mesh's
//: Newton matrix poorly (tension-only springs all lie slack there).  The 10k-vertex disc of
//: bench/mesh_cost.py landing on water (0.5 s): CG 906, Newton 451 without, 1.8 s CPU; CG 507, Newton 436
//: with 8, 1.5 s.  Hanging in air by its cap: CG 6511, Newton 1713 with 8 (6329, 1698 without), 2-4 %
//: more time (in turn); with 4 the landing took CG 498, but the hanging disc refactored 315 times
//: instead of 23 with 8 (8 without; 14.1 s against 13.6 s, one run each).
inline constexpr double MESH_REFRESH_AFTER = 8.0;

//: Whether factoring a mesh with buckling springs (algebraic hierarchy) from the Jacobian pays after a solve
//: of `iterations` CG iterations.
bool buckling_mesh_refresh_pays(const Plane& plane, const Cloth& cloth, double iterations);

//: Factor M + L(along) (along (F, n) kg; a mesh's (S)); returns 1, or -1 if a matrix was not positive definite.
Index refresh_from_jacobian(Plane& plane, const Cloth& cloth, const double* mass, const double* along);

//: Set each particle's frame (t1, t2, n) from positions pos (3, n).
void follow_cloth(Plane& plane, const Cloth& cloth, const double* pos);

//: The normal component's preconditioner: its diagonal alone, mass_i + n_i^T (D_i + B_i) n_i (the
//: particle's diagonal block of A, D_i its springs' part).
void set_normal_diagonal(Plane& plane, Index n, const double* mass, const double* diagonal_blocks,
                         const double* blocks);

//: Every component's system from the Jacobian in work: for each frame axis t, the
//: diagonal mass_i + t_i^T (D_i + B_i) t_i and, between neighbours the stencil reaches, each spring's
//: -t_i^T S t_j (S = across I + (along - across) u u^T its block), factored; the diagonal alone where
//: that is not positive definite (round-off on a crumpled cloth).  Across a cloth under tension (a
//: hanging sheet at frame-long steps) the tension's stiffness across the springs makes these far
//: better than the rest stiffness's in-plane systems and the normal's diagonal: on a 41 x 41 sheet
//: hanging at 1/30 s steps, 14 CG iterations to 1e-2 where those took 42.  Call after follow_cloth;
//: it overwrites the rest-stiffness factors.  Returns 1, or -1.  With components == NORMAL (a grid's
//: only) the in-plane systems alone, the normal component left to its diagonal (set_normal_diagonal).
Index set_systems_from_jacobian(Plane& plane, const Cloth& cloth, const double* mass, const Work& work,
                                Index components = COMPONENTS);

//: z = P^-1 r (both (3, n)), rows of held or pinned particles (free == 0) zero; a mesh's cycle keeps
//: them at zero on its finest level too (mesh_plane.cpp).
void apply(Plane& plane, Index n, const double* free, const double* r, double* z);

}  // namespace wc
