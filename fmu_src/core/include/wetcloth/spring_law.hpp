// One spring's law (docs/model.md section 3), shared by the grid's families (springs.cpp) and a mesh's
// listed springs (listed_springs.cpp): its geometry, its tension and the coefficients of its block of
// the system matrix.  Inline, so the grid's loops still vectorise around them.
#pragma once
#include <cmath>
#include <limits>

#include "wetcloth/springs.hpp"

namespace wc::spring_law {

inline constexpr double TINY_LENGTH = 1e-12;  // m; below this a spring has no direction

//: numba's (Python's) max(a, b): b if b > a else a.
inline double py_max(double a, double b) { return b > a ? b : a; }

//: numba's (Python's) min(a, b): b if b < a else a.
inline double py_min(double a, double b) { return b < a ? b : a; }

//: 1 / max(length, TINY_LENGTH) as min(1 / length, 1 / TINY_LENGTH), numba's min: the same value for
//: every length >= 0, inf or NaN (division rounds monotonically; NaN stays NaN), with the division
//: outside the select.  GCC folds 1 / TINY_LENGTH in the select's one branch and then may not
//: speculate the other's division (-ftrapping-math): the loop would not vectorise.
inline constexpr double INV_TINY_LENGTH = 1.0 / TINY_LENGTH;
inline double inverse_length(double length) {
    const double inv = 1.0 / length;
    return INV_TINY_LENGTH < inv ? INV_TINY_LENGTH : inv;
}

//: How a spring pulls: both ways; tension only, through pulling_stretch_clamped (rest length > 0 and
//: finite) or through pulling_stretch itself (any other rest length); buckling (buckled_stretch).
enum class Law { BOTH_WAYS, CLAMPED, EXACT, BUCKLING };

//: pulling_stretch for 0 < width < inf without branches, bit for bit (NaN and inf included): r = s / w
//: clamped to [0, 1] (by comparisons on r itself), then the cubic, which gives s and 1 at r = 1, and
//: +-0 at r = +-0, made +0 by the + 0.0.  Written with its branches (or with literal bounds, which GCC
//: propagates into split copies of the loop's tail), GCC computes the division or the products in
//: one branch only and, -ftrapping-math being its default, may then not execute them
//: unconditionally: the loop does not vectorise.  Hence the bounds 0 and 1 as width - width and
//: width / width, exact for a finite width > 0 and unknown to the compiler.
inline Stretch pulling_stretch_clamped(double stretch, double width) {
    const double zero = width - width, one = width / width;
    const double r = py_min(py_max(stretch / width, zero), one);
    return {stretch * r * (2.0 - r) + 0.0, r * (4.0 - 3.0 * r) + 0.0};
}

//: A buckling spring's stretch and slope for a stretch s (m), width w = TENSION_ROUNDING l0 (0 < w < inf):
//: with c = (BUCKLING_ROUNDING / TENSION_ROUNDING) w, pulling, pulling_stretch_clamped(s, c); compressed, that
//: onset y = pulling_stretch_clamped(-s, c) and, with b = (BUCKLING_STRAIN / TENSION_ROUNDING) w and
//: r = y / (2 b) clamped to [0, 1], the push -b r (2 - r): as a both-ways spring at first, its growth then
//: slowing, from y = 2 b on a constant k b.  Without branches, the bounds as in pulling_stretch_clamped.
inline Stretch buckled_stretch(double stretch, double width) {
    const double zero = width - width, one = width / width;
    const double onset = (BUCKLING_ROUNDING / TENSION_ROUNDING) * width;
    const double bound = (BUCKLING_STRAIN / TENSION_ROUNDING) * width;
    const Stretch pull = pulling_stretch_clamped(py_max(stretch, zero), onset);
    const Stretch push = pulling_stretch_clamped(py_max(-stretch, zero), onset);
    const double r = py_min(push.value / (2.0 * bound), one);
    return {pull.value + py_max(-push.value, -2.0 * bound) + bound * r * r, pull.slope + (one - r) * push.slope};
}

template <Law L>
inline Stretch pulled(double stretch, double width) {
    if (L == Law::BUCKLING) return buckled_stretch(stretch, width);
    if (L == Law::CLAMPED) return pulling_stretch_clamped(stretch, width);
    if (L == Law::EXACT) return pulling_stretch(stretch, width);
    return {stretch, 1.0};
}

//: The law of a spring with rest length l0 (m).
inline Law law_of(bool tension_only, double l0) {
    if (!tension_only) return Law::BOTH_WAYS;
    const double width = TENSION_ROUNDING * l0;
    return width > 0.0 && width <= std::numeric_limits<double>::max() ? Law::CLAMPED : Law::EXACT;
}

//: Separation d = x_i - x_j (m), length L (m), 1 / L (1/m; finite for a spring of no length) and
//: stiffness kf (N/m) scaled by the saturations si, sj of both ends.
struct Geometry {
    double dx, dy, dz, length, inv, stiffness;
};

//: Stiffness (N/m) of a spring of dry stiffness kf (N/m) whose ends' saturations are si, sj: grown by
//: wet_factor times their mean.
inline double wet_stiffness(double kf, double si, double sj, double wet_factor) {
    return kf * (1.0 + wet_factor * 0.5 * (si + sj));
}

inline Geometry spring_geometry(double xi, double yi, double zi, double xj, double yj, double zj, double kf, double si,
                                double sj, double wet_factor) {
    const double dx = xi - xj;
    const double dy = yi - yj;
    const double dz = zi - zj;
    const double length = std::sqrt(dx * dx + dy * dy + dz * dz);
    return {dx, dy, dz, length, inverse_length(length), wet_stiffness(kf, si, sj, wet_factor)};
}

//: The spring's force on its first end is t (x_i - x_j) (plus thesis damping): tension (eq. 3.1)
//: -k (L - l0) / L, for tension-only springs with pulling_stretch's stretch (width = TENSION_ROUNDING
//: l0); projected damping (damp = 1) -c ((v_i - v_j) . d) / L^2, rate = (v_i - v_j) . d.
template <Law L>
inline double tension(const Geometry& g, double l0, double width, double damp, double cf, double rate) {
    double stretch = g.length - l0;
    if (L != Law::BOTH_WAYS) stretch = pulled<L>(stretch, width).value;
    return -(g.stiffness * stretch * g.inv + damp * cf * rate * g.inv * g.inv);
}

//: A spring's force coefficient t (as tension, without thesis damping), unit direction u and system-
//: matrix block along u u^T + across (I - u u^T) (kg) for a step h (s).
struct Coefficients {
    double t, ux, uy, uz, along, across;
};

//: Geometric stiffness k s / L only while pulling, so every block stays positive; a tension-only or
//: buckling spring's slope along itself no less than slack_slope.  dv = v_i - v_j (m/s).
template <Law L>
inline Coefficients coefficients(const Geometry& g, double l0, double width, bool projected, double h,
                                 double slack_slope, double cf, double dvx, double dvy, double dvz) {
    const double damp_along = projected ? 1.0 : 0.0;
    const double damp_across = projected ? 0.0 : 1.0;
    const double ex = g.dx * g.inv;
    const double ey = g.dy * g.inv;
    const double ez = g.dz * g.inv;
    double stretch = g.length - l0;
    double slope = 1.0;
    if (L != Law::BOTH_WAYS) {
        const Stretch s = pulled<L>(stretch, width);
        stretch = s.value;
        slope = py_max(s.slope, slack_slope);
    }
    const double rate = dvx * ex + dvy * ey + dvz * ez;
    return {-(g.stiffness * stretch * g.inv + damp_along * cf * rate * g.inv), ex, ey, ez,
            h * cf + h * h * g.stiffness * slope, damp_across * h * cf + h * h * g.stiffness * py_max(stretch, 0.0) * g.inv};
}

struct Block {
    double xx, yy, zz, xy, xz, yz;
};

//: A spring's block across I + (along - across) u u^T (kg) as its six slots.
inline Block spring_block(double along, double across, double x, double y, double z) {
    const double iso = across;
    const double aniso = along - iso;
    return {iso + aniso * x * x, iso + aniso * y * y, iso + aniso * z * z, aniso * x * y, aniso * x * z, aniso * y * z};
}

}  // namespace wc::spring_law
