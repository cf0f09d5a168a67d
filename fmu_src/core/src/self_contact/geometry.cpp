// Closest points and the continuous collision test of self-collision's pairs: the parts too long or too
// rare to inline (port of bf41571:fmu_src/wetcloth/kernels/self_contact/geometry.py; the rest is in geometry.hpp).
#include "wetcloth/self_contact/geometry.hpp"

#include <limits>

namespace wc::self_contact {

Vec3 degenerate_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 corners[3] = {a, b, c};
    double best = std::numeric_limits<double>::infinity();
    Vec3 weights = {1.0, 0.0, 0.0};
    for (int k = 0; k < 3; ++k) {
        const Vec3& start = corners[k];
        const Vec3& end = corners[(k + 1) % 3];
        const double t = point_segment(p, start, end);
        const Vec3 d = sub(p, along(start, t, sub(end, start)));
        if (dot(d, d) < best) {
            best = dot(d, d);
            if (k == 0) {
                weights = {1.0 - t, t, 0.0};
            } else if (k == 1) {
                weights = {0.0, 1.0 - t, t};
            } else {
                weights = {t, 0.0, 1.0 - t};
            }
        }
    }
    return weights;
}

double time_of_contact(int kind, const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, const Vec3& p0,
                       const Vec3& p1, const Vec3& p2, const Vec3& p3, double start_distance, double minimum,
                       bool within_step) {
    const double bound = motion_bound(kind, p0, p1, p2, p3);
    double gap = start_distance - minimum;
    if (bound <= 0.0 || gap >= bound) return CLEAR;
    if (gap <= 0.0) return 0.0;
    const double report = CCD_REPORT * gap;
    double t = 0.0;
    double advance = (1.0 - CCD_REPORT) * gap / bound;
    for (int iteration = 0; iteration < CCD_ITERATIONS; ++iteration) {
        const double trial = within_step ? py_min(1.0, t + advance) : t + advance;
        const double d = distance(kind, along(x0, trial, p0), along(x1, trial, p1), along(x2, trial, p2),
                                  along(x3, trial, p3));
        gap = d - minimum;
        if (gap < report) return t;
        t = trial;
        if (t >= 1.0) return CLEAR;
        advance = CCD_ADVANCE * gap / bound;
    }
    return t;
}

}  // namespace wc::self_contact
