// Water uptake (Buras law), drying and wicking (port of bf41571:fmu_src/wetcloth/kernels/absorption.py).
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: A particle whose remaining uptake is below this fraction of its capacity counts as saturated.
inline constexpr double SATURATED = 1e-12;

//: Fraction of a step of h s (0..1) that a particle spends touching water, i.e. below `surface` (m).
//: Its height over the step is the cubic Hermite curve through its start and end heights (m) and
//: vertical speeds (m/s): the crossing time is then accurate to the fourth order in h, where a
//: straight line between the ends would misplace it by a fraction of the step whenever the particle
//: brakes on the water.
inline double contact_fraction(double z_start, double z_end, double vz_start, double vz_end, double h,
                               double surface) {
    const bool below_start = z_start < surface;
    const bool below_end = z_end < surface;
    if (below_start && below_end) return 1.0;
    if (!(below_start || below_end)) return 0.0;
    const double a = z_start - surface, b = z_end - surface;
    const double p0 = h * vz_start, p1 = h * vz_end;
    double crossing = a / (a - b);  // the straight line's crossing: the first guess
    for (int k = 0; k < 3; ++k) {   // Newton on the Hermite cubic, kept inside the step
        const double t = crossing;
        const double t2 = t * t;
        const double t3 = t2 * t;
        const double value = (2 * t3 - 3 * t2 + 1) * a + (t3 - 2 * t2 + t) * p0 + (3 * t2 - 2 * t3) * b +
                             (t3 - t2) * p1;
        const double slope = (6 * t2 - 6 * t) * a + (3 * t2 - 4 * t + 1) * p0 + (6 * t - 6 * t2) * b +
                             (3 * t2 - 2 * t) * p1;
        if (slope == 0.0) break;
        // Python's min(1.0, max(0.0, x)): a NaN x gives 0.
        const double x = t - value / slope;
        const double clamped = x > 0.0 ? x : 0.0;
        crossing = clamped < 1.0 ? clamped : 1.0;
    }
    return below_end ? 1.0 - crossing : crossing;
}

//: Absorbed water (kg) after a step of h s into out (may be water); returns particles still absorbing.
Index uptake(Index n, const double* z_start, const double* z_end, const double* vz_start, const double* vz_end,
             double surface, const double* dry_mass, double capacity, double rate, double h, const double* water,
             double* out);

//: Estimate (kg) of the uptake's error from where on its path a particle met the surface.
double uptake_timing_error(Index n, const double* z_start, const double* z_end, const double* vz_start,
                           const double* vz_end, double surface, const double* dry_mass, double capacity,
                           double rate, double h, const double* water);

//: Water arrives at rest: each particle keeps its momentum as its mass goes from mass_before to dry + water.
void keep_momentum(Index n, const double* mass_before, const double* dry_mass, const double* water, double* vel);

//: Drying in air (above surface) during a step of h s, in place; returns how many particles dried.
Index dry(Index n, const double* z_start, const double* z_end, const double* vz_start, const double* vz_end,
          double surface, double rate, double h, double* water);

//: Wicking between neighbours (cloth.wick_offsets, wick_conductance) in `substeps` explicit sub-steps over
//: h s, in place on water (n) and vel (3, n); buffer (6, n) scratch.  Returns the largest flux (kg).
double wick(const Cloth& cloth, Index substeps, double h, double* water, double* vel, double* buffer);

}  // namespace wc
