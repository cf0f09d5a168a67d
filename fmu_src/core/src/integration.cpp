// Per-particle update kernels of the integrators, and the conjugate-gradient solve of the implicit one
// (port of bf41571:fmu_src/wetcloth/kernels/integration.py).
#include "wetcloth/integration.hpp"

#include <cmath>

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

void system_matvec(const Cloth& cloth, const Work& work, const double* mass, const double* p, double* out) {
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
    spring_matvec(cloth, work, p, out);
    const double* __restrict free = cloth.free;
    for (Index c = 0; c < 3; ++c) {
        double* __restrict oc = out + c * n;
        for (Index i = 0; i < n; ++i) oc[i] *= free[i];
    }
}

double dot(Index n, const double* a, const double* b) {
    double sum = 0.0;
    for (Index k = 0; k < 3 * n; ++k) sum += a[k] * b[k];
    return sum;
}

void invert_blocks(Index n, const double* blocks, double* inverse) {
    for (Index i = 0; i < n; ++i) {
        Adjugate m = symmetric_adjugate(blocks[i], blocks[n + i], blocks[2 * n + i], blocks[3 * n + i],
                                        blocks[4 * n + i], blocks[5 * n + i]);
        if (!(m.det > 0.0)) m = {1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0};
        const double scale = 1.0 / m.det;
        inverse[i] = m.c11 * scale;
        inverse[n + i] = m.c22 * scale;
        inverse[2 * n + i] = m.c33 * scale;
        inverse[3 * n + i] = m.c12 * scale;
        inverse[4 * n + i] = m.c13 * scale;
        inverse[5 * n + i] = m.c23 * scale;
    }
}

void apply_block_inverse(Index n, const double* inverse, const double* r, double* z) {
    const double* __restrict v0 = inverse;
    const double* __restrict v1 = inverse + n;
    const double* __restrict v2 = inverse + 2 * n;
    const double* __restrict v3 = inverse + 3 * n;
    const double* __restrict v4 = inverse + 4 * n;
    const double* __restrict v5 = inverse + 5 * n;
    const double* __restrict rx = r;
    const double* __restrict ry = r + n;
    const double* __restrict rz = r + 2 * n;
    double* __restrict zx = z;
    double* __restrict zy = z + n;
    double* __restrict zz = z + 2 * n;
    for (Index i = 0; i < n; ++i) {
        const double x = rx[i], y = ry[i], w = rz[i];
        zx[i] = v0[i] * x + v3[i] * y + v4[i] * w;
        zy[i] = v3[i] * x + v1[i] * y + v5[i] * w;
        zz[i] = v4[i] * x + v5[i] * y + v2[i] * w;
    }
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

//: The given guess (the explicit step) is right for smooth motion, which the springs barely resist; the
//: block-Jacobi solve B^-1 b is right for stiff, local motion.  Their best combination is at least as
//: good as either, for two products with A.
void combine_first_guesses(const Cloth& cloth, const Work& work, const double* mass, const double* inverse,
                           const double* b, double* x, double* r, double* z, double* p, double* ap) {
    const Index n = cloth.n;
    const double* free = cloth.free;
    apply_block_inverse(n, inverse, b, z);
    for (Index c = 0; c < 3; ++c) {
        double* __restrict zc = z + c * n;
        for (Index i = 0; i < n; ++i) zc[i] *= free[i];
    }
    system_matvec(cloth, work, mass, x, ap);
    system_matvec(cloth, work, mass, z, p);
    const double a11 = dot(n, x, ap), a12 = dot(n, x, p), a22 = dot(n, z, p);
    const double b1 = dot(n, b, x), b2 = dot(n, b, z);
    const double det = a11 * a22 - a12 * a12;
    double c1 = 0.0, c2 = 0.0;
    if (det > 1e-12 * a11 * a22) {
        c1 = (b1 * a22 - b2 * a12) / det;
        c2 = (a11 * b2 - a12 * b1) / det;
    } else if (a22 > 0.0) {  // the two guesses are (nearly) parallel: the best multiple of the second
        c2 = b2 / a22;
    }  // else no force at all
    for (Index c = 0; c < 3; ++c) {
        double* __restrict xc = x + c * n;
        double* __restrict rc = r + c * n;
        const double* __restrict zc = z + c * n;
        const double* __restrict bc = b + c * n;
        const double* __restrict apc = ap + c * n;
        const double* __restrict pc = p + c * n;
        for (Index i = 0; i < n; ++i) {
            xc[i] = c1 * xc[i] + c2 * zc[i];
            rc[i] = free[i] * bc[i] - c1 * apc[i] - c2 * pc[i];
        }
    }
}

SolveResult solve_pcg(const Cloth& cloth, const Work& work, const double* mass, const double* inverse,
                      const double* b, double* x, double* r, double* z, double* p, double* ap, double rtol,
                      Index max_iterations) {
    const Index n = cloth.n;
    combine_first_guesses(cloth, work, mass, inverse, b, x, r, z, p, ap);
    apply_block_inverse(n, inverse, r, z);
    copy(3 * n, z, p);
    double b_norm = std::sqrt(dot(n, b, b));
    if (b_norm == 0.0) b_norm = 1.0;
    double rz = dot(n, r, z);
    double residual = std::sqrt(dot(n, r, r)) / b_norm;
    Index iterations = 0;
    while (residual > rtol && iterations < max_iterations) {
        system_matvec(cloth, work, mass, p, ap);
        const double p_ap = dot(n, p, ap);
        if (p_ap <= 0.0) break;
        conjugate_gradient_step(n, rz / p_ap, p, ap, x, r);
        apply_block_inverse(n, inverse, r, z);
        const double rz_new = dot(n, r, z);
        next_search_direction(n, rz_new / rz, z, p);
        rz = rz_new;
        residual = std::sqrt(dot(n, r, r)) / b_norm;
        iterations += 1;
    }
    return {iterations, residual};
}

}  // namespace wc
