// Closest points of the two kinds of contact pair, and a conservative continuous collision test (port of
// bf41571:fmu_src/wetcloth/kernels/self_contact/geometry.py).
//
// A *pair* is four particles: a point and a triangle (POINT_TRIANGLE: p, a, b, c) or two edges (EDGE_EDGE:
// p1, q1, p2, q2).  Its closest points are given by four *weights* w (the point side positive, the other
// side negative, each side summing to 1), so that sum_k w_k x_k is the vector from the closest point of
// the second element to that of the first, whose length is the pair's distance and whose direction is the
// contact normal.  Positions are Vec3 (m).  The small helpers are inline (numba inlined them).
#pragma once

#include <cmath>

#include "wetcloth/core.hpp"

namespace wc::self_contact {

enum Kind : int { POINT_TRIANGLE = 0, EDGE_EDGE = 1 };

//: Squared lengths (relative to the elements' size squared) below which an edge counts as a point and
//: two edges as parallel.
inline constexpr double DEGENERATE = 1e-14;
//: Additive CCD (Li, Kaufman and Jiang 2021, "Codimensional Incremental Potential Contact", section 4):
//: the pair is cleared once its gap can be shown to stay above zero; a contact is reported when the gap
//: falls below CCD_REPORT of its value at the start.  At most CCD_ITERATIONS advances (then a contact is
//: reported: the answer stays conservative).
inline constexpr double CCD_REPORT = 0.1;
inline constexpr double CCD_ADVANCE = 0.9;
inline constexpr int CCD_ITERATIONS = 200;
//: What time_of_contact returns for a motion that stays clear.
inline constexpr double CLEAR = 2.0;

//: Python's (and numba's) min(a, b) and max(a, b): the first argument unless the second compares
//: smaller (larger), so a NaN second argument is ignored and a NaN first one kept.
inline double py_min(double a, double b) { return b < a ? b : a; }
inline double py_max(double a, double b) { return b > a ? b : a; }

struct Vec3 {
    double x, y, z;
};

struct Weights {
    double w0, w1, w2, w3;
};

inline Vec3 point(const double* x, Index n, Index i) { return {x[i], x[n + i], x[2 * n + i]}; }
inline Vec3 sub(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double clamp01(double v) { return py_min(1.0, py_max(0.0, v)); }
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

//: The point x + t p: where x is after a fraction t of its motion p.
inline Vec3 along(const Vec3& x, double t, const Vec3& p) { return {x.x + t * p.x, x.y + t * p.y, x.z + t * p.z}; }

//: Parameters (s, t) in [0, 1] of the closest points p1 + s (q1 - p1), p2 + t (q2 - p2) (Ericson,
//: "Real-Time Collision Detection", 5.1.9; parallel segments get one of their closest pairs).
inline void segment_segment(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, double& s_out,
                            double& t_out) {
    const Vec3 d1 = sub(q1, p1);
    const Vec3 d2 = sub(q2, p2);
    const Vec3 r = sub(p1, p2);
    const double a = dot(d1, d1);
    const double e = dot(d2, d2);
    const double f = dot(d2, r);
    const double tiny = DEGENERATE * py_max(py_max(a, e), 1e-300);
    if (a <= tiny && e <= tiny) {
        s_out = 0.0, t_out = 0.0;
        return;
    }
    if (a <= tiny) {
        s_out = 0.0, t_out = clamp01(f / e);
        return;
    }
    const double c = dot(d1, r);
    if (e <= tiny) {
        s_out = clamp01(-c / a), t_out = 0.0;
        return;
    }
    const double b = dot(d1, d2);
    const double denom = a * e - b * b;
    const double s = denom > DEGENERATE * a * e ? clamp01((b * f - c * e) / denom) : 0.0;
    const double t = (b * s + f) / e;
    if (t < 0.0) {
        s_out = clamp01(-c / a), t_out = 0.0;
    } else if (t > 1.0) {
        s_out = clamp01((b - c) / a), t_out = 1.0;
    } else {
        s_out = s, t_out = t;
    }
}

//: Parameter in [0, 1] of the point of segment ab closest to p.
inline double point_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
    const Vec3 ab = sub(b, a);
    const double length2 = dot(ab, ab);
    if (length2 <= 0.0) return 0.0;
    return clamp01(dot(sub(p, a), ab) / length2);
}

//: point_triangle's fallback for a triangle of (nearly) no area: the closest of its three edges
//: (geometry.cpp; rare, so out of line).
Vec3 degenerate_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

//: Barycentric weights (u, v, w) of the point of triangle abc closest to p (Ericson 5.1.5; a degenerate
//: triangle is treated through its edges).
inline Vec3 point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = sub(b, a);
    const Vec3 ac = sub(c, a);
    const Vec3 ap = sub(p, a);
    const double d1 = dot(ab, ap);
    const double d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return {1.0, 0.0, 0.0};
    const Vec3 bp = sub(p, b);
    const double d3 = dot(ab, bp);
    const double d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return {0.0, 1.0, 0.0};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double v = d1 / (d1 - d3);
        return {1.0 - v, v, 0.0};
    }
    const Vec3 cp = sub(p, c);
    const double d5 = dot(ab, cp);
    const double d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return {0.0, 0.0, 1.0};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double w = d2 / (d2 - d6);
        return {1.0 - w, 0.0, w};
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return {0.0, 1.0 - w, w};
    }
    const double sum = va + vb + vc;
    if (sum > 0.0) {
        const double v = vb / sum;
        const double w = vc / sum;
        return {1.0 - v - w, v, w};
    }
    return degenerate_triangle(p, a, b, c);
}

//: Weights (w0, w1, w2, w3) of the pair's closest points (see the file's head).
inline Weights closest(int kind, const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
    if (kind == POINT_TRIANGLE) {
        const Vec3 uvw = point_triangle(x0, x1, x2, x3);
        return {1.0, -uvw.x, -uvw.y, -uvw.z};
    }
    double s, t;
    segment_segment(x0, x1, x2, x3, s, t);
    return {1.0 - s, s, t - 1.0, -t};
}

//: sum_k w_k x_k.
inline Vec3 combine(const Weights& w, const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
    return {w.w0 * x0.x + w.w1 * x1.x + w.w2 * x2.x + w.w3 * x3.x,
            w.w0 * x0.y + w.w1 * x1.y + w.w2 * x2.y + w.w3 * x3.y,
            w.w0 * x0.z + w.w1 * x1.z + w.w2 * x2.z + w.w3 * x3.z};
}

//: Distance (m) between the pair's elements.
inline double distance(int kind, const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
    const Vec3 d = combine(closest(kind, x0, x1, x2, x3), x0, x1, x2, x3);
    return std::sqrt(dot(d, d));
}

//: The mean of a pair's four displacements p0..p3 (m).
inline Vec3 mean_motion(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
    return {0.25 * (p0.x + p1.x + p2.x + p3.x), 0.25 * (p0.y + p1.y + p2.y + p3.y), 0.25 * (p0.z + p1.z + p2.z + p3.z)};
}

//: Largest change (m) of the pair's distance over straight-line displacements p0..p3: after the mean
//: displacement is taken out, the largest on one side plus the largest on the other.
inline double motion_bound(int kind, const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
    const Vec3 mean = mean_motion(p0, p1, p2, p3);
    const double n0 = norm(sub(p0, mean)), n1 = norm(sub(p1, mean)), n2 = norm(sub(p2, mean)),
                 n3 = norm(sub(p3, mean));
    if (kind == POINT_TRIANGLE) return n0 + py_max(py_max(n1, n2), n3);
    return py_max(n0, n1) + py_max(n2, n3);
}

//: Additive CCD: the pair moves from x0..x3 by p0..p3 over the step (fraction 0 to 1).  Returns CLEAR if
//: its distance provably stays above `minimum` (m) throughout, else a fraction at which it is still above
//: `minimum` but has lost at least 1 - CCD_REPORT of its starting gap (start_distance - minimum, which
//: must be positive): the moment to treat the contact.  Its last trial may look past the step's end (at a
//: fraction above 1) unless within_step, when it looks at the end instead: a fast approach that stops
//: short of `minimum` at the end is then CLEAR.
double time_of_contact(int kind, const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, const Vec3& p0,
                       const Vec3& p1, const Vec3& p2, const Vec3& p3, double start_distance, double minimum,
                       bool within_step = false);

}  // namespace wc::self_contact
