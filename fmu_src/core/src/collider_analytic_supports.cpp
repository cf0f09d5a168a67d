// The analytic colliders as supports inside fixed implicit steps (collider_analytic_supports.hpp).
#include "wetcloth/collider_analytic_supports.hpp"

#include <cmath>
#include <vector>

#include "wetcloth/collider_motion.hpp"
#include "wetcloth/collider_supports.hpp"
#include "wetcloth/colliders.hpp"

namespace wc {

namespace {

//: Add the term of particle i alone (weight 1) against collider k's (FLOOR_SUPPORT: the floor's) tangent plane
//: of normal (3) at the step's start, the particle then at q (3, in the collider's frame) and gap (m) off it.
void add_term(Supports& supports, Index i, Index k, const double* normal, const double* q, double gap) {
    for (int j = 0; j < SUPPORT_POINTS; ++j) {
        supports.points.push_back(j == 0 ? i : -1);
        supports.weights.push_back(j == 0 ? 1.0 : 0.0);
    }
    for (int c = 0; c < 3; ++c) {
        supports.table_normal.push_back(normal[c]);
        supports.table_part.push_back(gap * normal[c] - q[c]);  // minus the plane's point (weight -1)
    }
    supports.collider.push_back(k);
}

}  // namespace

Index gather_analytic_supports(const Physics& phys, Index n, const double* pos, const double* vel, const double* free,
                               const Sliding* sliding, double distance, double ahead, Index kept, Supports& supports) {
    keep_terms(supports, kept);
    const double contact = 0.5 * phys.thickness;
    std::vector<char> slides(static_cast<std::size_t>(n), 0);
    if (sliding != nullptr) {
        for (const Index i : sliding->index) slides[static_cast<std::size_t>(i)] = 1;
    }
    const double fall = ahead * ahead * GRAVITY;  // m: how far gravity alone carries a particle in the step
    //: Whether particle i, dist (m) from a surface, may reach it within the step.
    const auto within_reach = [&](Index i, double dist) {
        const double speed = std::hypot(vel[i], vel[n + i], vel[2 * n + i]);
        return dist < 2.0 * contact + ahead * speed + fall;
    };
    for (Index k = 0; k < phys.collider_count; ++k) {
        const double* row = phys.colliders + k * COLLIDER_COLUMNS;
        if (static_cast<Index>(row[C_SHAPE]) == MESH || collider_moves(phys, k)) continue;
        for (Index i = 0; i < n; ++i) {
            if (free[i] == 0.0 || slides[static_cast<std::size_t>(i)]) continue;
            const double a[3] = {pos[i], pos[n + i], pos[2 * n + i]};
            double q[3], normal[3];
            table_point(collider_shift(phys, k), row + C_X, a, true, q);  // (a collider keyed to stand still)
            const double dist = table_distance(phys, row, q, 0.0, normal);
            if (within_reach(i, dist)) add_term(supports, i, k, normal, q, dist - contact + distance);
        }
    }
    const double up[3] = {0.0, 0.0, 1.0};
    const double surface = phys.floor_z - contact;  // m: the floor's own height
    for (Index i = 0; i < n; ++i) {
        if (free[i] == 0.0 || slides[static_cast<std::size_t>(i)]) continue;
        const double dist = pos[2 * n + i] - surface;
        const double q[3] = {pos[i], pos[n + i], pos[2 * n + i]};
        if (within_reach(i, dist)) add_term(supports, i, FLOOR_SUPPORT, up, q, dist - contact + distance);
    }
    return supports.count();
}

}  // namespace wc
