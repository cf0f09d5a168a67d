// Per-particle update kernels of the integrators and the conjugate-gradient solve of backward Euler
// (port of bf41571:fmu_src/wetcloth/kernels/integration.py).
#pragma once
#include "wetcloth/core.hpp"
#include "wetcloth/springs.hpp"

namespace wc {

//: One Euler step: v+ = v + h F/m; x+ = x + h v+ (symplectic) or x + h v (explicit), into out_pos,
//: out_vel.  Pinned particles (free == 0) keep zero velocity.  Returns max |v+ - v| (m/s).
double euler_update(Index n, const double* pos, const double* vel, const double* force, const double* dry_mass,
                    const double* water, const double* free, double h, bool symplectic, double* out_pos,
                    double* out_vel);

struct SpeedCheck {
    double speed;  // m/s, the fastest particle's
    bool finite;   // whether every value is finite
};
SpeedCheck speed_and_finiteness(Index n, const double* pos, const double* vel, const double* water);

//: Largest coordinate difference (m) between two (3, n) position arrays.
double largest_deviation(Index n, const double* pos, const double* anchor);

//: target[0:count] = source[0:count].
void copy(Index count, const double* source, double* target);

//: Sum of count values, in order.
double total(Index count, const double* a);

//: out = A p with A = M + work.blocks + spring blocks (of the precision `springs`), rows of pinned
//: particles zeroed.
void system_matvec(const Cloth& cloth, const Work& work, const double* mass, const double* p, double* out,
                   Precision springs = Precision::DOUBLE);

//: Sum over 3 n values of a[k] b[k], in DOT_LANES partial sums (lanes.hpp) that do not wait on each other:
//: 4 us a product on the 81 x 81 sheet against 10 us for one running sum (bench/sheet_kernels.py).
inline constexpr Index DOT_LANES = 8;
double dot(Index n, const double* a, const double* b);

//: The adjugate of the symmetric 3x3 matrix [[a, d, e], [d, b, f], [e, f, c]] and its determinant; the
//: inverse is the adjugate over det (an impact zone's inertia, self_contact/response.cpp).
struct Adjugate {
    double c11, c22, c33, c12, c13, c23, det;
};
inline Adjugate symmetric_adjugate(double a, double b, double c, double d, double e, double f) {
    const double c11 = b * c - f * f;
    const double c22 = a * c - e * e;
    const double c33 = a * b - d * d;
    const double c12 = e * f - d * c;
    const double c13 = d * f - b * e;
    const double c23 = d * e - a * f;
    return {c11, c22, c33, c12, c13, c23, a * c11 + d * c12 + e * c13};
}

//: One conjugate-gradient update along p (ap = A p), in place: x += alpha p, r -= alpha A p.
void conjugate_gradient_step(Index n, double alpha, const double* p, const double* ap, double* x, double* r);

//: The next conjugate-gradient search direction, in place: p = z + beta p.
void next_search_direction(Index n, double beta, const double* z, double* p);

}  // namespace wc
