// Water uptake (docs/model.md section 5): the Buras law, integrated exactly over a step; drying in air
// and wicking between neighbours (port of bf41571:fmu_src/wetcloth/kernels/absorption.py).
#include "wetcloth/absorption.hpp"

#include <cmath>

namespace wc {

namespace {

struct Room {
    double full;     // kg, the water a particle holds when full
    double missing;  // kg, what it can still take (0 once it counts as saturated)
};

inline Room room(double capacity, double dry_mass, double water) {
    const double full = capacity * dry_mass;
    const double missing = full - water;
    return {full, missing <= SATURATED * full ? 0.0 : missing};
}

}  // namespace

//: A particle touches water while its centre is below `surface` (m; where its submerged fraction becomes
//: positive) and absorbs for the part of the step it spent below (contact_fraction), so the moment of
//: contact is not rounded to a whole step.  dq/dt = I (1 - q/Q) over a contact time t is exactly
//: q+ = Q - (Q - q) exp(-I t / Q), Q = capacity * dry_mass, I / Q = rate / capacity (rate 1/s).
Index uptake(Index n, const double* z_start, const double* z_end, const double* vz_start, const double* vz_end,
             double surface, const double* dry_mass, double capacity, double rate, double h, const double* water,
             double* out) {
    Index active = 0;
    const double full_decay = std::exp(-rate * h / capacity);
    for (Index i = 0; i < n; ++i) {
        out[i] = water[i];
        const double touching = contact_fraction(z_start[i], z_end[i], vz_start[i], vz_end[i], h, surface);
        if (touching <= 0.0) continue;
        const Room r = room(capacity, dry_mass[i], water[i]);
        if (r.missing == 0.0) continue;
        active += 1;
        const double decay = touching == 1.0 ? full_decay : std::exp(-rate * touching * h / capacity);
        out[i] = r.full - r.missing * decay;
    }
    return active;
}

//: The difference (kg, summed over the particles that cross the surface during the step) between the
//: uptake with the crossing timed on the Hermite curve (contact_fraction) and on the straight line.
double uptake_timing_error(Index n, const double* z_start, const double* z_end, const double* vz_start,
                           const double* vz_end, double surface, const double* dry_mass, double capacity,
                           double rate, double h, const double* water) {
    double sum = 0.0;
    for (Index i = 0; i < n; ++i) {
        if ((z_start[i] < surface) == (z_end[i] < surface)) continue;
        const double missing = room(capacity, dry_mass[i], water[i]).missing;
        if (missing == 0.0) continue;
        const double curved = contact_fraction(z_start[i], z_end[i], vz_start[i], vz_end[i], h, surface);
        const double straight = contact_fraction(z_start[i], z_end[i], 0.0, 0.0, 0.0, surface);
        sum += missing * std::fabs(std::exp(-rate * straight * h / capacity) - std::exp(-rate * curved * h / capacity));
    }
    return sum;
}

void keep_momentum(Index n, const double* mass_before, const double* dry_mass, const double* water, double* vel) {
    double* __restrict vx = vel;
    double* __restrict vy = vel + n;
    double* __restrict vz = vel + 2 * n;
    for (Index i = 0; i < n; ++i) {
        const double scale = mass_before[i] / (dry_mass[i] + water[i]);
        vx[i] *= scale;
        vy[i] *= scale;
        vz[i] *= scale;
    }
}

//: Particles keep exp(-rate t) of their water after t s in air (above surface) during the step; the
//: water leaves with the particle's velocity, which therefore does not change.
Index dry(Index n, const double* z_start, const double* z_end, const double* vz_start, const double* vz_end,
          double surface, double rate, double h, double* water) {
    Index drying = 0;
    for (Index i = 0; i < n; ++i) {
        const double in_air = 1.0 - contact_fraction(z_start[i], z_end[i], vz_start[i], vz_end[i], h, surface);
        if (in_air > 0.0 && water[i] > 0.0) {
            water[i] *= std::exp(-rate * in_air * h);
            drying += 1;
        }
    }
    return drying;
}

//: The flux from j to i is conductance * (sat_j - sat_i) (kg/s), sat = water / capacity; each flux is
//: added to one end and taken from the other, so the total is conserved to round-off.  Sub-steps
//: short enough that each new saturation is a weighted mean of old ones keep every saturation within
//: the range it had.  Moving water carries its donor's velocity, so momentum is conserved.
double wick(const Cloth& cloth, Index substeps, double h, double* water, double* vel, double* buffer) {
    const Index n = cloth.n;
    const double* capacity = cloth.capacity;
    const double* dry_mass = cloth.dry_mass;
    double* saturation = buffer;
    double* flux = buffer + n;
    double* scratch = buffer + 2 * n;
    double* momentum = buffer + 3 * n;
    for (Index c = 0; c < 3; ++c) {
        double* __restrict mc = momentum + c * n;
        const double* __restrict vc = vel + c * n;
        for (Index i = 0; i < n; ++i) mc[i] = (dry_mass[i] + water[i]) * vc[i];
    }
    const double dt = h / static_cast<double>(substeps);
    double largest = 0.0;
    for (Index step = 0; step < substeps; ++step) {
        for (Index i = 0; i < n; ++i) saturation[i] = water[i] / capacity[i];
        for (Index k = 0; k < cloth.wick_pair_count; ++k) {  // a mesh's listed links, one at a time
            const Index i = cloth.wick_pairs[k], j = cloth.wick_pairs[cloth.wick_pair_count + k];
            const double moved = dt * cloth.wick_pair_conductance[k] * (saturation[j] - saturation[i]);
            const double a = std::fabs(moved);
            largest = a > largest ? a : largest;
            water[i] += moved;
            water[j] -= moved;
            const Index donor = moved > 0.0 ? j : i;
            for (Index c = 0; c < 3; ++c) {
                momentum[c * n + i] += moved * vel[c * n + donor];
                momentum[c * n + j] -= moved * vel[c * n + donor];
            }
        }
        for (Index f = 0; f < cloth.wick_families; ++f) {
            const Index off = cloth.wick_offsets[f];
            const Index m = n - off;
            {  // flux[k] (kg): water moving over dt from link k's second end into its first
                const double* __restrict si = saturation;
                const double* __restrict sj = saturation + off;
                const double* __restrict g = cloth.wick_conductance + f * n;
                double* __restrict fl = flux;
                for (Index k = 0; k < m; ++k) fl[k] = dt * g[k] * (sj[k] - si[k]);
            }
            for (Index k = 0; k < m; ++k) {
                const double a = std::fabs(flux[k]);
                largest = a > largest ? a : largest;
                water[k] += flux[k];
                water[k + off] -= flux[k];
            }
            for (Index c = 0; c < 3; ++c) {
                const double* vc = vel + c * n;
                double* mc = momentum + c * n;
                for (Index k = 0; k < m; ++k) {
                    const Index donor = flux[k] > 0.0 ? k + off : k;
                    scratch[k] = flux[k] * vc[donor];
                }
                for (Index k = 0; k < m; ++k) {
                    mc[k] += scratch[k];
                    mc[k + off] -= scratch[k];
                }
            }
        }
    }
    for (Index c = 0; c < 3; ++c) {
        double* __restrict vc = vel + c * n;
        const double* __restrict mc = momentum + c * n;
        for (Index i = 0; i < n; ++i) vc[i] = mc[i] / (dry_mass[i] + water[i]);
    }
    return largest;
}

}  // namespace wc
