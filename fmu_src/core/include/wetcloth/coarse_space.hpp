// A coarse space for the linear solves of backward Euler's fixed (frame-long) steps on grids: the rigid
// motions of square aggregates of particles (three translations, three small turns about the aggregate's
// centre), coupled through the Galerkin product P^T A P of the step's own Newton matrix A (masses,
// per-particle blocks, springs).  Added to the plane preconditioner (two-level additive Schwarz), it
// supplies the coupling of the components across a curved sheet, and the bending between aggregates,
// that the per-component V-cycles in each particle's frame (t1, t2, normal) miss.
#pragma once
#include <vector>

#include "wetcloth/core.hpp"

namespace wc {

//: Unknowns per aggregate: the translations along x, y, z (m/s), then the turns about x, y, z through the
//: aggregate's centre (rad/s).  Hanging 81 x 81 sheet (below), aggregates of 9: 8.4 CG per Newton iteration
//: against 12.7 with the translations alone, 25 ms a frame against 28 (the coarse build 1.1 ms a Newton
//: iteration against 0.23: the turns' blocks, a band 65 wide instead of 32).
inline constexpr Index COARSE_UNKNOWNS = 6;

//: An aggregate's neighbours in the coarse matrix, itself included (springs reach one aggregate further).
inline constexpr Index COARSE_NEIGHBOURS = 5;

//: Particles per aggregate side, measured with translations alone.  Hanging 81 x 81 sheet, implicit_euler
//: at 1/30 s, 3 s, self-collision on (bench/hanging_sheet.py): CG per Newton iteration 26.2 without, 18.6
//: at 27, 12.7 at 9, 11.5 at 7, 10.8 at 5, 9.0 at 4, 9.2 at 3; 9 and 7 the fastest (27 ms a frame against
//: 38; 3: 52 ms, its band factor dominating).
inline constexpr Index COARSE_SIDE = 9;

//: A step's Newton iterations at which the coarse space is built: the later ones (at most two more) keep the
//: last (a coarse matrix that no longer matches A is still a valid, symmetric positive definite,
//: preconditioner; the step's later corrections move the cloth little).  Hanging 81 x 81 sheet, implicit_euler
//: frame steps, 3 s: 1 build a step: 11.4 CG per Newton iteration against 8.4 (27-28 ms a frame); 2: 8.7
//: CG per Newton iteration, 190 Newton iterations against 197 (23-25 ms a frame against 26-27); the last
//: step's coarse space kept for the next step's first iteration: 13.0 CG per Newton iteration (37 ms).
inline constexpr Index COARSE_BUILDS = 2;

//: The aggregates of a grid (side x side particles, the last row and column of aggregates possibly
//: narrower) and the coarse matrix, COARSE_UNKNOWNS per aggregate (aggregate-major; kg, kg m, kg m^2), in
//: band.hpp's lower band form (half-bandwidth width), factored by build_coarse_space with band_factor (its
//: rows beside it; factored false if it was not positive definite: no correction then).  turns (count) is
//: 0 for an aggregate one particle wide or tall (a line of particles has no turn about itself), else 1;
//: arm (3, n) each particle's position less its aggregate's centre (m; 0 where it does not turn), set at
//: each build.  coarse is scratch (COARSE_UNKNOWNS count).
struct CoarseSpace {
    Index side = 0, columns = 0, count = 0, width = 0;
    std::vector<Index> aggregate;  // (n) each particle's
    std::vector<double> turns, arm;
    std::vector<double> blocks, edge;  // assemble_coarse_matrix's scratch
    std::vector<double> band, rows;
    std::vector<double> coarse;
    bool factored = false;
};

//: Whether a cloth gets a coarse space: a grid (a mesh's listed springs are not assembled).
inline bool has_coarse_space(const Cloth& cloth) { return cloth.grid_x > 0 && cloth.pair_count == 0; }

//: Shape coarse for a grid cloth with aggregates of side x side particles.
void shape_coarse_space(CoarseSpace& coarse, const Cloth& cloth, Index side);

//: Assemble into coarse.band P^T A P for the matrix A that system_matvec applies (masses `mass` kg, work's
//: per-particle blocks and spring coefficients), P's columns the free particles' aggregate rigid motions
//: about the aggregates' centres at positions pos (3, n) m (arm set from them).
void assemble_coarse_matrix(CoarseSpace& coarse, const Cloth& cloth, const double* mass, const Work& work,
                            const double* pos);

//: assemble_coarse_matrix and its Cholesky factor (unknowns nothing couples, of an aggregate of pinned
//: particles alone or one that does not turn, get 1 on their diagonal).
void build_coarse_space(CoarseSpace& coarse, const Cloth& cloth, const double* mass, const Work& work,
                        const double* pos);

//: z += P (P^T A P)^-1 P^T r for a (3, n) residual r (N) into z (m/s), after build_coarse_space.
void add_coarse_correction(CoarseSpace& coarse, const Cloth& cloth, const double* r, double* z);

}  // namespace wc
