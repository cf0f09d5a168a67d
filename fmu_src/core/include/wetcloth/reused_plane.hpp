// The adaptive steps' reused Jacobian preconditioner (core.hpp's ReusedPlane): the in-plane systems t1, t2
// from the Jacobian (plane.hpp's set_systems_from_jacobian), built at one Newton iteration and kept for the
// linear solves of the steps after it, on grids with a multigrid hierarchy.  They are applied in the frame
// the cloth has now and with the normal component's current diagonal (both Core::plane's, updated at each
// step and Newton iteration), so that they follow the cloth as it swings.  The step's error estimate stays
// filtered through Core::plane's rest-stiffness systems, which change only when the step or the masses
// change much: a filter that changed with each rebuild would move the steps (docs/benchmarks.md: +9 %).
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Slots of ReusedPlane::rule: built (1) or not (0); the scale (beta h)^2 (s^2) it was built for; the
//: CG iterations of the first solve with it (0: none yet).
enum ReuseRuleSlot : Index { REUSED_BUILT = 0, REUSED_SCALE, REUSED_FIRST_SOLVE, REUSE_RULE_SIZE };

//: Built before a Newton iteration's solve when the last solve took more than REUSE_FLOOR CG iterations;
//: rebuilt (or, after a solve of at most REUSE_FLOOR, dropped for the rest-stiffness systems) when
//: (beta h)^2 has changed by more than the factor REUSE_SCALE since the build, or when the last solve
//: took more than REUSE_RISE times the CG iterations of the first solve with it (and more than REUSE_FLOOR).
//: Hanging 81 x 81 sheet, 3 s, self-collision on (bench/hanging_sheet.py): 309 builds, CG 18 187 against
//: 31 044 with the rest-stiffness systems, Newton 3127 against 3024, 172 against 251 ms/frame.  Without
//: the floor (always reused): CG 17 314, but the 100 x 100 grid landing of bench/mesh_cost.py took 721 CG
//: instead of 586 (now 496); a rise of 3: 87 builds, CG 21 563; rebuilt every 8 steps instead: CG 19 225;
//: applied in the frame of the build rather than the cloth's current one, rebuilt every 8 steps: CG 8691
//: in the first second against 6305 (every 16 steps: 16 063, more than the rest stiffness's 10 110).
inline constexpr double REUSE_SCALE = 2.0;
inline constexpr double REUSE_RISE = 2.0;
inline constexpr double REUSE_FLOOR = 4.0;

//: Whether a cloth's preconditioner `plane` gets reused Jacobian systems: a grid with a multigrid hierarchy.
inline bool reuses_jacobian(const Plane& plane) { return plane.grid.level_count > 1; }

//: Size ReusedPlane::source takes for n particles and F spring families.
inline Index reused_source_size(Index n, Index families) { return (10 + 5 * families) * n; }

//: Allocate reused's own arrays after the shape of `plane` (reuses_jacobian) and share the rest; not built.
void attach_reused(ReusedPlane& reused, const Plane& plane, Index n);

//: Whether the systems in hand should be rebuilt before a solve at scale (beta h)^2 s^2, the last solve
//: having taken last_solve CG iterations.
bool reuse_expired(const ReusedPlane& reused, double scale, double last_solve);

//: Build from the Jacobian in work (forces_and_blocks's) at positions pos (3, n), masses mass (n), for
//: scale (beta h)^2; keeps its source.  Returns 1, or -1 if a system was not positive definite (its
//: diagonal then stands in, as in set_systems_from_jacobian).
Index build_reused(ReusedPlane& reused, const Cloth& cloth, const double* mass, const Work& work, const double* pos,
                   double scale);

//: Rebuild from reused.source (a restored run), if its rule says it was built.
void rebuild_reused(ReusedPlane& reused, const Cloth& cloth);

//: Whether a solve of `iterations` CG iterations was long enough to build the systems for (REUSE_FLOOR):
//: where the rest-stiffness systems' solves are that short (a cloth floating flat), they are kept.
inline bool long_solve(double iterations) { return iterations > REUSE_FLOOR; }

//: Whether the systems are built and in use; drop them (back to Core::plane's) until a solve is long.
inline bool in_use(const ReusedPlane& reused) { return reused.rule[REUSED_BUILT] != 0.0; }
inline void drop_reused(ReusedPlane& reused) { reused.rule = {0.0, 0.0, 0.0}; }

//: Count a solve of `iterations` CG iterations with it.
void count_reused_solve(ReusedPlane& reused, Index iterations);

}  // namespace wc
