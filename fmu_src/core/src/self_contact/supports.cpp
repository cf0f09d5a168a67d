// The cloth's pairs with itself as supports (self_contact/supports.hpp).
#include "wetcloth/self_contact/supports.hpp"

#include <cmath>

#include "wetcloth/collider_supports.hpp"
#include "wetcloth/self_contact/elements.hpp"
#include "wetcloth/self_contact/geometry.hpp"

namespace wc::self_contact {

namespace {

//: Edges closer to parallel than this sine have no cross product to measure a normal against.
constexpr double PARALLEL_SINE = 0.1;

//: How far a pair's contact normal leans from the normal of its elements (the sine of the angle between them):
//: a triangle's own normal, or the cross product of two edges (1 for edges within 0.1 rad of parallel,
//: whose cross product says nothing).  0 for a point over a triangle (its closest point inside, or on its
//: edge or corner straight below) and for crossing edges; up to 1 for a point beside a triangle or an edge
//: beside a parallel one.
template <int KIND>
double tilt(const Vec3& normal, const Vec3 x[4]) {
    const Vec3 a = KIND == POINT_TRIANGLE ? sub(x[2], x[1]) : sub(x[1], x[0]);
    const Vec3 b = KIND == POINT_TRIANGLE ? sub(x[3], x[1]) : sub(x[3], x[2]);
    const Vec3 across = cross(a, b);
    const double size = norm(across);
    if (!(size > PARALLEL_SINE * norm(a) * norm(b))) return 1.0;
    const double along = dot(normal, across) / size;
    return std::sqrt(py_max(0.0, 1.0 - along * along));
}

//: Append the listed pairs of one kind (rows: first elements, then second; count of them).
template <int KIND>
void gather(const Contact& contact, const Index* rows, Index count, Index n, const double* pos, const double* vel,
            double thickness, double distance, double ahead, Supports& supports) {
    for (Index p = 0; p < count; ++p) {
        Index idx[4];
        particles<KIND>(contact, rows[p], rows[count + p], idx);
        const Vec3 x[4] = {point(pos, n, idx[0]), point(pos, n, idx[1]), point(pos, n, idx[2]), point(pos, n, idx[3])};
        const Weights w = closest(KIND, x[0], x[1], x[2], x[3]);
        const Vec3 d = combine(w, x[0], x[1], x[2], x[3]);
        const double gap = norm(d);
        if (!(gap > 0.0)) continue;  // no normal: the stage after the solve takes it
        const Vec3 normal{d.x / gap, d.y / gap, d.z / gap};
        const Vec3 v[4] = {point(vel, n, idx[0]), point(vel, n, idx[1]), point(vel, n, idx[2]), point(vel, n, idx[3])};
        const double closing = -dot(normal, combine(w, v[0], v[1], v[2], v[3]));  // m/s
        if (!(gap < thickness + ahead * py_max(closing, 0.0))) continue;
        if (tilt<KIND>(normal, x) > SUPPORT_TILT) continue;  // (after the gap: most candidates are far)
        const double weights[4] = {w.w0, w.w1, w.w2, w.w3};
        static_assert(SUPPORT_POINTS == 4, "a pair's four particles fill a term");
        supports.points.insert(supports.points.end(), idx, idx + 4);
        supports.weights.insert(supports.weights.end(), weights, weights + 4);
        // g = offset + n . sum_k w_k x_k presses below `distance` where the pair's gap is below the thickness.
        supports.table_normal.insert(supports.table_normal.end(), {normal.x, normal.y, normal.z});
        supports.table_part.insert(supports.table_part.end(), {distance - thickness, 0.0, 0.0});
        supports.collider.push_back(SELF_SUPPORT);
    }
}

}  // namespace

Index gather_self_supports(const Contact& contact, Index n, const double* pos, const double* vel, double thickness,
                           double distance, double ahead, Supports& supports) {
    const ContactLists& lists = *contact.lists;
    gather<POINT_TRIANGLE>(contact, lists.point_triangle.data(), lists.point_triangle_count(), n, pos, vel, thickness,
                           distance, ahead, supports);
    gather<EDGE_EDGE>(contact, lists.edge_edge.data(), lists.edge_edge_count(), n, pos, vel, thickness, distance,
                      ahead, supports);
    supports.self_friction = contact.friction;
    return supports.count();
}

}  // namespace wc::self_contact
