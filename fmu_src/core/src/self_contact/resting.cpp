// Layers at rest on layers (docs/model.md section 6.2): held for a step the way the floor holds the
// particles lying on it (floor.cpp).
//
// A towel that sank onto the floor with a crease over itself has particles lying on the layer below.
// Left free, gravity pulls them into that layer in every step and the self-collision stage pushes them
// back: a kink in every step, each one restarting BDF2 at a millisecond, for ever.  Held instead, they
// take no part in the step while the force on them presses them onto the layer within the friction
// cone, as the floor's particles do, and the steps grow.
#include <cmath>
#include <vector>

#include "wetcloth/floor.hpp"
#include "wetcloth/self_contact.hpp"
#include "wetcloth/self_contact/geometry.hpp"

namespace wc {

namespace {

using self_contact::Vec3;

bool all_still(const double* free, const Index* support) {
    for (int k = 0; k < 3; ++k) {
        if (support[k] >= 0 && free[support[k]] != 0.0) return false;
    }
    return true;
}

//: Whether particle p is free and its support (up to 3 particles, -1 padding) still: the first condition of
//: hold_if_resting, which needs no distance.
inline bool may_rest(const double* free, Index p, const Index* support) {
    return free[p] != 0.0 && all_still(free, support);
}

//: Hold particle p (free) on a still support (up to 3 particles, -1 padding) lying along `normal` (unit,
//: from the support to p) at `distance` (m), if it is at rest there or coming onto it slowly enough that
//: the self-collision response's inelastic impulse would stop it, and, given the force on the particles
//: (3, n; nullptr: not judged), if that force presses it onto the support within friction.  Returns
//: whether it held it.
bool hold_if_resting(ContactLists& lists, double thickness, double friction, Index n, const double* vel,
                     const double* force, double* free, double* held, Index p, const Index support[3],
                     const Vec3& normal, double distance) {
    if (!may_rest(free, p, support)) return false;
    if (!(distance > 0.0 && distance <= (1.0 + RESTING_SLACK) * thickness)) return false;
    const double v[3] = {vel[p], vel[n + p], vel[2 * n + p]};
    const double up[3] = {normal.x, normal.y, normal.z};
    if (!comes_to_rest(v, up, friction)) return false;
    if (force != nullptr) {
        const double f[3] = {force[p], force[n + p], force[2 * n + p]};
        if (slips(f, up, friction)) return false;
    }
    free[p] = 0.0;
    held[p] = LAYER_HELD;
    const std::size_t i = static_cast<std::size_t>(p);
    for (int k = 0; k < 3; ++k) lists.resting[3 * i + k] = support[k];
    lists.resting_normal[3 * i] = normal.x;
    lists.resting_normal[3 * i + 1] = normal.y;
    lists.resting_normal[3 * i + 2] = normal.z;
    return true;
}

//: RESTING_PASSES passes of hold_if_resting over the candidate pairs (force: as there).  Returns how many
//: it held.  A pair's distance is measured only where one of its particles may rest on the other element
//: (may_rest): no other can be held, so no other changes what the pair's checks find.
Index hold_passes(Contact& contact, double thickness, Index n, const double* pos, const double* vel,
                  const double* force, double* free, double* held) {
    using namespace self_contact;
    ContactLists& lists = *contact.lists;
    const Index points = lists.point_triangle_count();
    const Index edges = lists.edge_edge_count();
    const double friction = contact.friction;
    Index count = 0;
    for (Index pass = 0; pass < RESTING_PASSES; ++pass) {
        Index added = 0;
        for (Index j = 0; j < points; ++j) {  // a particle on a triangle
            const Index p = lists.point_triangle[j];
            const Index* t = contact.triangles + 3 * lists.point_triangle[points + j];
            if (!may_rest(free, p, t)) continue;
            const Vec3 x0 = point(pos, n, p), x1 = point(pos, n, t[0]), x2 = point(pos, n, t[1]),
                       x3 = point(pos, n, t[2]);
            const Vec3 d = combine(closest(POINT_TRIANGLE, x0, x1, x2, x3), x0, x1, x2, x3);
            const double length = norm(d);
            const Vec3 normal = {d.x / length, d.y / length, d.z / length};
            added += hold_if_resting(lists, thickness, friction, n, vel, force, free, held, p, t, normal, length);
        }
        for (Index j = 0; j < edges; ++j) {  // the ends of an edge on an edge
            const Index* a = contact.edges + 2 * lists.edge_edge[j];
            const Index* b = contact.edges + 2 * lists.edge_edge[edges + j];
            const Index on_b[3] = {b[0], b[1], -1};
            const Index on_a[3] = {a[0], a[1], -1};
            if (!(may_rest(free, a[0], on_b) || may_rest(free, a[1], on_b) || may_rest(free, b[0], on_a) ||
                  may_rest(free, b[1], on_a))) {
                continue;
            }
            const Vec3 x0 = point(pos, n, a[0]), x1 = point(pos, n, a[1]), x2 = point(pos, n, b[0]),
                       x3 = point(pos, n, b[1]);
            const Vec3 d = combine(closest(EDGE_EDGE, x0, x1, x2, x3), x0, x1, x2, x3);  // from b to a
            const double length = norm(d);
            const Vec3 up = {d.x / length, d.y / length, d.z / length};
            const Vec3 down = {-up.x, -up.y, -up.z};
            for (int k = 0; k < 2; ++k) {
                added += hold_if_resting(lists, thickness, friction, n, vel, force, free, held, a[k], on_b, up, length);
                added += hold_if_resting(lists, thickness, friction, n, vel, force, free, held, b[k], on_a, down, length);
            }
        }
        count += added;
        if (added == 0) break;
    }
    return count;
}

}  // namespace

Index hold_on_layers(Contact& contact, double thickness, Index n, const double* pos, const double* vel, double* free,
                     double* held) {
    if (!contact.enabled) return 0;
    ContactLists& lists = *contact.lists;
    if (lists.point_triangle_count() + lists.edge_edge_count() == 0) return 0;
    lists.resting.assign(3 * static_cast<std::size_t>(n), -1);
    lists.resting_normal.assign(3 * static_cast<std::size_t>(n), 0.0);
    return hold_passes(contact, thickness, n, pos, vel, nullptr, free, held);
}

Index hold_within_friction(Contact& contact, double thickness, Index n, const double* pos, const double* vel,
                           const double* force, double* free, double* held) {
    if (!contact.enabled) return 0;
    return hold_passes(contact, thickness, n, pos, vel, force, free, held);
}

Index release_unsupported(Contact& contact, Index n, double* free, double* held) {
    if (!contact.enabled) return 0;
    const ContactLists& lists = *contact.lists;
    Index released = 0;
    bool again = true;
    while (again) {  // a particle resting on one just released goes too
        again = false;
        for (Index p = 0; p < n; ++p) {
            if (held[p] != LAYER_HELD || all_still(free, &lists.resting[3 * static_cast<std::size_t>(p)])) continue;
            held[p] = 0.0;
            free[p] = 1.0;
            released += 1;
            again = true;
        }
    }
    return released;
}

Index release_sliding(Contact& contact, Index n, const double* force, double* free, double* held) {
    if (!contact.enabled) return 0;
    const ContactLists& lists = *contact.lists;
    Index released = 0;
    for (Index p = 0; p < n; ++p) {
        if (held[p] != LAYER_HELD) continue;
        const double f[3] = {force[p], force[n + p], force[2 * n + p]};
        if (!slips(f, &lists.resting_normal[3 * static_cast<std::size_t>(p)], contact.friction)) continue;
        held[p] = 0.0;
        free[p] = 1.0;
        released += 1;
    }
    return released + release_unsupported(contact, n, free, held);
}

}  // namespace wc
