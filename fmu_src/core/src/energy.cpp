// The cloth's mechanical energy and buoyancy's potential, as wetcloth/energy.py weighs them.
#include "wetcloth/energy.hpp"

#include "wetcloth/self_contact/geometry.hpp"
#include "wetcloth/spring_law.hpp"
#include "wetcloth/springs.hpp"

#include <cmath>

namespace wc {

namespace {

//: Energy (J) of a spring of stiffness k (N/m) stretched by s (m): k s^2 / 2 both ways; tension-only, the
//: integral of its law rounded over its first `width` (m) of stretch, nothing when compressed.
double spring_energy(double s, double k, bool tension_only, double width) {
    if (!tension_only) return 0.5 * k * s * s;
    const double p = s > 0.0 ? s : 0.0;
    if (p < width) return k * (2.0 * p * p * p / (3.0 * width) - p * p * p * p / (4.0 * width * width));
    return k * (5.0 / 12.0 * width * width + 0.5 * (p * p - width * width));
}

//: Energy (J) of a buckling spring (spring_law.hpp's buckled_stretch) of stiffness k (N/m) and rest length l
//: (m) stretched by s (m): pulling, the tension-only law rounded over c = BUCKLING_ROUNDING l; compressed by x,
//: the integral of the push b r (2 - r), r = min(R(x) / (2 b), 1), b = BUCKLING_STRAIN l, R(x) the same onset.
double buckling_energy(double s, double k, double l) {
    const double c = BUCKLING_ROUNDING * l, b = BUCKLING_STRAIN * l;
    const double x = s < 0.0 ? -s : 0.0;
    const double onset = x < c ? x : c;
    const double ramp = x < c ? c : (x > 2.0 * b ? 2.0 * b : x);
    const double o2 = onset * onset, o3 = o2 * onset, o4 = o3 * onset;
    const double pushing = 2.0 * o3 / (3.0 * c) - o4 / (4.0 * c * c) -
                           (4.0 * o4 * onset / (5.0 * c * c) - 2.0 * o3 * o3 / (3.0 * c * c * c) +
                            o4 * o3 / (7.0 * c * c * c * c)) / (4.0 * b) +
                           0.5 * (ramp * ramp - c * c) - (ramp * ramp * ramp - c * c * c) / (12.0 * b) +
                           b * (x > 2.0 * b ? x - 2.0 * b : 0.0);
    return spring_energy(s, k, true, c) + k * pushing;
}

//: |x_i - x_j| (m) at pos (3, n).
double distance(const double* pos, Index n, Index i, Index j) {
    using namespace self_contact;
    return norm(sub(point(pos, n, i), point(pos, n, j)));
}

}  // namespace

double mechanical_energy(const Cloth& cloth, double wet_factor, const double* mass, const double* water,
                         const double* pos, const double* vel, double* magnitude) {
    const Index n = cloth.n;
    // A spring's stiffness as the forces take it (saturations as update_saturation's: water / capacity).
    const auto stiffness = [&](double k, Index i, Index j) {
        if (wet_factor == 0.0) return k;
        return spring_law::wet_stiffness(k, water[i] / cloth.capacity[i], water[j] / cloth.capacity[j], wet_factor);
    };
    double energy = 0.0, size = 0.0;  // (size: the sum of the terms' magnitudes)
    for (Index i = 0; i < n; ++i) {
        const double vx = vel[i], vy = vel[n + i], vz = vel[2 * n + i];
        const double kinetic = 0.5 * (vx * vx + vy * vy + vz * vz), height = GRAVITY * pos[2 * n + i];
        energy += mass[i] * (kinetic + height);
        size += mass[i] * (kinetic + std::fabs(height));
    }
    const double gravity_and_motion = energy;
    for (Index f = 0; f < cloth.families; ++f) {
        const Index off = cloth.offsets[f];
        const double rest = cloth.rest[f];
        const double* k = cloth.stiffness + f * n;
        for (Index i = 0; i + off < n; ++i) {
            if (k[i] == 0.0) continue;
            energy += spring_energy(distance(pos, n, i, i + off) - rest, stiffness(k[i], i, i + off), cloth.tension_only[f],
                                    TENSION_ROUNDING * rest);
        }
    }
    const Index tension = cloth.pair_tension_count, buckling = tension + cloth.pair_buckling_count;
    for (Index p = 0; p < cloth.pair_count; ++p) {
        const Index i = cloth.pairs[p], j = cloth.pairs[cloth.pair_count + p];
        const double rest = cloth.pair_rest[p], k = stiffness(cloth.pair_stiffness[p], i, j);
        const double s = distance(pos, n, i, j) - rest;
        energy += p < tension    ? spring_energy(s, k, true, TENSION_ROUNDING * rest)
                  : p < buckling ? buckling_energy(s, k, rest)
                                 : spring_energy(s, k, false, 0.0);
    }
    if (magnitude != nullptr) *magnitude = size + (energy - gravity_and_motion);  // (elastic terms are >= 0)
    return energy;
}

double buoyancy_energy(const Cloth& cloth, const Physics& phys, const double* pos) {
    const Index n = cloth.n;
    const double* z = pos + 2 * n;
    const double e = phys.thickness, level = phys.water_level;
    double energy = 0.0;
    for (Index i = 0; i < n; ++i) {
        // The depth integral of the submerged fraction (water.cpp's submerged_fractions) from z up.
        double depth;
        if (phys.smooth) {
            const double u = level + 0.5 * e - z[i];  // into the surface slab, whose fraction rises as u / e
            depth = u <= 0.0 ? 0.0 : u < e ? 0.5 * u * u / e : u - 0.5 * e;
        } else {
            depth = level > z[i] ? level - z[i] : 0.0;
        }
        energy += cloth.volume[i] * depth;
    }
    return phys.water_density * GRAVITY * energy;
}

}  // namespace wc
