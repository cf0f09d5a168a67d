// Per-particle update kernels of the integrators, and the conjugate-gradient solve of the implicit one
// (port of bf41571:fmu_src/wetcloth/kernels/integration.py).
#include "wetcloth/integration.hpp"

#include <cmath>

#include "wetcloth/lanes.hpp"
#include "wetcloth/springs.hpp"

namespace wc {

double euler_update(Index n, const double* pos, const double* vel, const double* force, const double* dry_mass,
                    const double* water, const double* free, double h, bool symplectic, double* out_pos,
                    double* out_vel) {
    double largest = 0.0;
    for (Index c = 0; c < 3; ++c) {
        const double* x = pos + c * n;
        const double* v = vel + c * n;
        const double* f = force + c * n;
        double* ox = out_pos + c * n;
        double* ov = out_vel + c * n;
        for (Index i = 0; i < n; ++i) {
            const double dv = h * free[i] * f[i] / (dry_mass[i] + water[i]);
            const double v_new = (v[i] + dv) * free[i];
            const double v_old = v[i];
            ov[i] = v_new;
            ox[i] = x[i] + h * (symplectic ? v_new : v_old);
            const double change = std::fabs(v_new - v_old);
            largest = change > largest ? change : largest;
        }
    }
    return largest;
}

SpeedCheck speed_and_finiteness(Index n, const double* pos, const double* vel, const double* water) {
    double fastest = 0.0;
    double sum = 0.0;
    for (Index i = 0; i < n; ++i) {
        const double vx = vel[i], vy = vel[n + i], vz = vel[2 * n + i];
        const double v2 = vx * vx + vy * vy + vz * vz;
        fastest = v2 > fastest ? v2 : fastest;
        sum += v2 + pos[i] + pos[n + i] + pos[2 * n + i] + water[i];
    }
    return {std::sqrt(fastest), std::isfinite(sum)};
}

double largest_deviation(Index n, const double* pos, const double* anchor) {
    double largest = 0.0;
    for (Index k = 0; k < 3 * n; ++k) {
        const double d = std::fabs(pos[k] - anchor[k]);
        largest = d > largest ? d : largest;
    }
    return largest;
}

void copy(Index count, const double* source, double* target) {
    for (Index k = 0; k < count; ++k) target[k] = source[k];
}

double total(Index count, const double* a) {
    double s = 0.0;
    for (Index k = 0; k < count; ++k) s += a[k];
    return s;
}

void system_matvec(const Cloth& cloth, const Work& work, const double* mass, const double* p, double* out,
                   Precision springs) {
    const Index n = cloth.n;
    const double* __restrict b = work.blocks;
    const double* __restrict px = p;
    const double* __restrict py = p + n;
    const double* __restrict pz = p + 2 * n;
    double* __restrict ox = out;
    double* __restrict oy = out + n;
    double* __restrict oz = out + 2 * n;
    const double* __restrict b0 = b;
    const double* __restrict b1 = b + n;
    const double* __restrict b2 = b + 2 * n;
    const double* __restrict b3 = b + 3 * n;
    const double* __restrict b4 = b + 4 * n;
    const double* __restrict b5 = b + 5 * n;
    for (Index i = 0; i < n; ++i) {
        const double x = px[i], y = py[i], z = pz[i];
        ox[i] = mass[i] * x + b0[i] * x + b3[i] * y + b4[i] * z;
        oy[i] = mass[i] * y + b3[i] * x + b1[i] * y + b5[i] * z;
        oz[i] = mass[i] * z + b4[i] * x + b5[i] * y + b2[i] * z;
    }
    spring_matvec(cloth, work, p, out, springs);
    const double* __restrict free = cloth.free;
    for (Index c = 0; c < 3; ++c) {
        double* __restrict oc = out + c * n;
        for (Index i = 0; i < n; ++i) oc[i] *= free[i];
    }
}

double dot(Index n, const double* a, const double* b) {
    double sums[DOT_LANES] = {};
    in_lanes<DOT_LANES>(3 * n, [&](Index l, Index k) { sums[l] += a[k] * b[k]; });
    return sum_of_lanes<DOT_LANES>(sums);
}

void conjugate_gradient_step(Index n, double alpha, const double* p, const double* ap, double* x, double* r) {
    const double* __restrict pp = p;
    const double* __restrict aa = ap;
    double* __restrict xx = x;
    double* __restrict rr = r;
    for (Index k = 0; k < 3 * n; ++k) {
        xx[k] += alpha * pp[k];
        rr[k] -= alpha * aa[k];
    }
}

void next_search_direction(Index n, double beta, const double* z, double* p) {
    const double* __restrict zz = z;
    double* __restrict pp = p;
    for (Index k = 0; k < 3 * n; ++k) pp[k] = zz[k] + beta * pp[k];
}

}  // namespace wc
