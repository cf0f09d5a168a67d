// Spring forces (docs/model.md section 3) and their Jacobians (port of bf41571:fmu_src/wetcloth/kernels/springs.py).
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Tension-only springs pull with the stretch rounded over their first TENSION_ROUNDING of strain (docs/model.md
//: section 3).  Over 6e-4 a swinging sheet's Newton corrections, a few micrometres, spanned the rounding and Newton
//: converged only linearly; over 1.5e-3 the hanging sheet's default takes 13 % fewer Newton and 23 % fewer CG
//: iterations.  (Over 3e-3, 19 % and 38 % fewer, but the fixed-step mode's descent took 18 % more.)
inline constexpr double TENSION_ROUNDING = 1.5e-3;

//: A mesh's triangles' edges (buckling springs) pull, and push back while slightly compressed, as both-ways
//: springs past an onset rounded over BUCKLING_ROUNDING of strain each way, their push rounding off to at most
//: k BUCKLING_STRAIN l0 (spring_law.hpp).
inline constexpr double BUCKLING_ROUNDING = 1e-4;
inline constexpr double BUCKLING_STRAIN = 1e-3;

struct Stretch {
    double value;  // m
    double slope;  // -
};

//: The stretch (m) a tension-only spring pulls with, and its derivative, for a stretch s = L - l0 (m).
inline Stretch pulling_stretch(double stretch, double width) {
    if (stretch >= width) return {stretch, 1.0};
    if (stretch <= 0.0) return {0.0, 0.0};
    const double r = stretch / width;
    return {stretch * r * (2.0 - r), r * (4.0 - 3.0 * r)};
}

//: Add tension (eq. 3.1) and damping (eq. 3.2) of every spring to force (3, n); buf: one row of n scratch.
void spring_forces(const Cloth& cloth, const Physics& phys, const double* saturation, const double* pos,
                   const double* vel, double* force, double* buf);

//: Forces as spring_forces plus one backward-Euler Newton step's pieces: adds to work.force and
//: work.diagonal_blocks; writes work.direction, along, across and their single_blocks; work.buf as scratch.  A
//: tension-only spring's stiffness along itself enters the blocks at no less than slack_slope times k
//: (0: its true slope, nothing while slack).
void spring_forces_and_blocks(const Cloth& cloth, const Physics& phys, const double* saturation, const double* pos,
                              const double* vel, double h, double slack_slope, Work& work);

//: Which copy of the families' blocks a product reads: work.direction, along, across (DOUBLE) or
//: work.single_blocks (SINGLE: the families' product in single precision, p's differences taken in double
//: and rounded to float, summed over the families in work.single_buf, then added to out: four lanes a
//: vector instead of two, what CG's products need at its tolerance).  The listed springs' product stays in
//: double precision.
enum class Precision { DOUBLE, SINGLE };

//: Add the springs' part of the system matrix (work.direction, along, across, or single_blocks) times p
//: (3, n) to out; rows 0 to 2 of work.buf as scratch.
void spring_matvec(const Cloth& cloth, const Work& work, const double* p, double* out,
                   Precision blocks = Precision::DOUBLE);

}  // namespace wc
