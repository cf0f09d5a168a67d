// A mesh collider's features as supports inside the implicit step (collider_supports.hpp).
#include "wetcloth/collider_supports.hpp"

#include <algorithm>
#include <cmath>

#include "wetcloth/collider_motion.hpp"
#include "wetcloth/floor.hpp"

namespace wc {

namespace {

//: f(i, w) for each cloth particle i of term t with its weight w, in slot order (unused slots, -1, passed over).
template <class F>
void each_point(const Supports& supports, Index t, F&& f) {
    for (int j = 0; j < SUPPORT_POINTS; ++j) {
        const Index i = supports.points[SUPPORT_POINTS * t + j];
        if (i >= 0) f(i, supports.weights[SUPPORT_POINTS * t + j]);
    }
}

//: Term t's relative velocity across its normal, u_t (3, m/s), at velocities vel (3, n); returns |u_t|.
double slip_velocity(const Supports& supports, Index t, Index n, const double* vel, double* u) {
    const double* nn = supports.normal.data() + 3 * t;
    for (int c = 0; c < 3; ++c) u[c] = supports.collider_velocity[3 * t + c];
    each_point(supports, t, [&](Index i, double w) {
        for (Index c = 0; c < 3; ++c) u[c] += w * vel[c * n + i];
    });
    const double along = nn[0] * u[0] + nn[1] * u[1] + nn[2] * u[2];
    for (int c = 0; c < 3; ++c) u[c] -= along * nn[c];
    return std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
}

//: start + sum_k w_k normal . x_k over term t's cloth points at pos (3, n), normal (3) its world normal.
double cloth_along(const Supports& supports, Index t, Index n, const double* pos, const double* normal, double start) {
    double g = start;
    each_point(supports, t, [&](Index i, double w) {
        g += w * (normal[0] * pos[i] + normal[1] * pos[n + i] + normal[2] * pos[2 * n + i]);
    });
    return g;
}

//: Term t's slip speed (m/s): below it the term's friction is a stick.
double slip_speed_of(const Supports& supports, Index t) {
    return supports.collider[static_cast<std::size_t>(t)] == SELF_SUPPORT ? SELF_SLIP_SPEED : SUPPORT_SLIP_SPEED;
}

//: Whether term t has friction in the step (a coefficient above 0 and a normal force at the step's start).
bool rubs(const Supports& supports, Index t) {
    const std::size_t u = static_cast<std::size_t>(t);
    return supports.any_friction && supports.friction[u] > 0.0 && supports.normal_force[u] > 0.0;
}

//: Term t's friction at velocities vel (3, n): its forces (N) into force (3, n), its stiffness in the pair's
//: relative velocity (6, N s/m) into friction_block, and that times velocity_scale w_j^2 into each particle's
//: diagonal blocks (6, n).
void add_friction(Supports& supports, Index t, Index n, const double* vel, double* force, double* blocks) {
    double u[3];
    const double y = slip_velocity(supports, t, n, vel, u);
    const std::size_t term = static_cast<std::size_t>(t);
    const double mu_n = supports.friction[term] * supports.normal_force[term];
    const double eps = slip_speed_of(supports, t);
    const double a = slip_factor(y, eps);
    double* h = supports.friction_block.data() + 6 * t;
    slip_stiffness(mu_n, y, u, supports.normal.data() + 3 * t, h, eps);
    each_point(supports, t, [&](Index i, double w) {
        for (Index c = 0; c < 3; ++c) force[c * n + i] -= w * mu_n * a * u[c];
        const double scaled = supports.velocity_scale * w * w;
        for (int e = 0; e < 6; ++e) blocks[e * n + i] += scaled * h[e];
    });
}

//: n . sum_k w_k p_k over term t's collider points where collider k is h s after the step's start (normal (3)
//: the term's world normal; cloth_weight the cloth points' weights' sum): sum_k w_k (c + d + R (q_k - c)) = R
//: part + (sum_k w_k) (c + d - R c), the collider's weights summing to minus the cloth's (the pair's four to 0).
double collider_along(const Supports& supports, const Physics& phys, Index t, double h, const double* normal,
                      double cloth_weight, double* part) {
    const Index k = supports.collider[t];
    const double origin[3] = {0.0, 0.0, 0.0};
    double origin_place[3];  // c + d - R c: where the table frame's origin is
    world_point_after(phys, k, h, origin, origin_place);
    for (int c = 0; c < 3; ++c) part[c] = supports.table_part[3 * t + c];
    world_direction_after(phys, k, h, part);
    for (int c = 0; c < 3; ++c) part[c] -= cloth_weight * origin_place[c];
    return normal[0] * part[0] + normal[1] * part[1] + normal[2] * part[2];
}

//: Term t's friction for the step: its collider points' weighted velocity at the step's end (part their
//: weighted sum there, cloth_weight as collider_along's) and its normal force N at the step's start, the
//: cloth's start pos (3, n) against the collider where it was then, along the step's normal.
void place_friction(Supports& supports, const Physics& phys, Index t, Index n, const double* pos, double h,
                    double cloth_weight, const double* part) {
    const Index k = supports.collider[t];
    const double* shift = collider_shift(phys, k);
    const double* normal = supports.normal.data() + 3 * t;
    double start_part[3];
    const double gap = cloth_along(supports, t, n, pos, normal,
                                   collider_along(supports, phys, t, 0.0, normal, cloth_weight, start_part));
    const double depth = supports.distance - gap;
    supports.normal_force[static_cast<std::size_t>(t)] = depth > 0.0 ? term_stiffness(supports, t) * depth : 0.0;
    // sum_k w_k (u + omega x (p_k - c - d)) = W u + omega x (part - W (c + d)), W = -cloth_weight
    double* velocity = supports.collider_velocity.data() + 3 * t;
    for (int c = 0; c < 3; ++c) velocity[c] = shift != nullptr ? -cloth_weight * shift[MOTION_VELOCITY + c] : 0.0;
    if (!turns(shift)) return;
    double centre_place[3];  // c + d
    world_point_after(phys, k, h, phys.colliders + k * COLLIDER_COLUMNS + C_X, centre_place);
    double arm[3], spin[3];
    for (int c = 0; c < 3; ++c) arm[c] = part[c] + cloth_weight * centre_place[c];
    cross(shift + MOTION_SPIN, arm, spin);
    for (int c = 0; c < 3; ++c) velocity[c] += spin[c];
}

//: Term t of the cloth with itself: its normal and offset as gathered (fixed in the world), its friction
//: Supports::self_friction with its normal force at the cloth's start pos (3, n); no collider to move.
void place_self(Supports& supports, Index t, Index n, const double* pos) {
    const std::size_t term = static_cast<std::size_t>(t);
    supports.offset[term] = supports.table_part[3 * term];
    supports.friction[term] = supports.self_friction;
    if (!(supports.self_friction > 0.0)) return;
    const double depth = supports.distance - support_gap(supports, t, n, pos);
    supports.normal_force[term] = depth > 0.0 ? supports.self_stiffness * depth : 0.0;
    supports.any_friction = true;
}

}  // namespace

void keep_terms(Supports& supports, Index kept) {
    const std::size_t k = static_cast<std::size_t>(kept);
    supports.points.resize(SUPPORT_POINTS * k);
    supports.weights.resize(SUPPORT_POINTS * k);
    supports.table_normal.resize(3 * k);
    supports.table_part.resize(3 * k);
    supports.collider.resize(k);
}

double stiffest_spring(const Cloth& cloth) {
    double stiffest = 0.0;
    const Index springs = is_mesh(cloth) ? cloth.pair_count : cloth.families * cloth.n;
    const double* k = is_mesh(cloth) ? cloth.pair_stiffness : cloth.stiffness;
    for (Index s = 0; s < springs; ++s) stiffest = k[s] > stiffest ? k[s] : stiffest;
    return stiffest;
}

void place_supports(Supports& supports, const Physics& phys, Index n, const double* pos, double h, double bh) {
    const std::size_t count = static_cast<std::size_t>(supports.count());
    supports.normal.resize(3 * count);
    supports.offset.resize(count);
    supports.pressing.assign(count, 0);
    supports.anticipated.assign(count, 0);
    supports.arrived.assign(count, 0);
    supports.stiff.assign(count, 0);
    supports.friction.resize(count);
    supports.normal_force.assign(count, 0.0);
    supports.collider_velocity.assign(3 * count, 0.0);
    supports.friction_block.resize(6 * count);
    supports.scale = bh * bh;
    supports.velocity_scale = bh;
    supports.any_friction = false;
    for (Index t = 0; t < supports.count(); ++t) {
        const Index k = supports.collider[t];
        double* normal = supports.normal.data() + 3 * t;
        for (int c = 0; c < 3; ++c) normal[c] = supports.table_normal[3 * t + c];
        if (k == SELF_SUPPORT) {
            place_self(supports, t, n, pos);
            continue;
        }
        world_direction_after(phys, k, h, normal);
        double cloth_weight = 0.0;
        each_point(supports, t, [&](Index, double w) { cloth_weight += w; });
        double part[3];  // the collider's points' weighted sum at the step's end
        supports.offset[static_cast<std::size_t>(t)] = collider_along(supports, phys, t, h, normal, cloth_weight, part);
        const double mu = k == FLOOR_SUPPORT ? phys.floor_friction : phys.colliders[k * COLLIDER_COLUMNS + C_FRICTION];
        supports.friction[static_cast<std::size_t>(t)] = mu;
        if (!(mu > 0.0)) continue;
        place_friction(supports, phys, t, n, pos, h, cloth_weight, part);
        supports.any_friction = true;
    }
}

double support_gap(const Supports& supports, Index term, Index n, const double* pos) {
    return cloth_along(supports, term, n, pos, supports.normal.data() + 3 * term,
                       supports.offset[static_cast<std::size_t>(term)]);
}

Index lag_arriving_normal_force(Supports& supports, Index n, const double* mass, const double* start_vel,
                                const double* pos, const double* vel, double h, double* force, double* blocks) {
    Index arrived = 0;
    for (Index t = 0; t < supports.count(); ++t) {
        const std::size_t term = static_cast<std::size_t>(t);
        if (!(supports.friction[term] > 0.0) || supports.normal_force[term] > 0.0) continue;
        // (Not the cloth's own pairs: with the friction of those met within the step, the corner-hung sheet of
        // bench/self_contact_energy.py rose in 0-4 frames of seven starts, without it in 0-1.)
        if (supports.collider[term] == SELF_SUPPORT) continue;
        const double depth = supports.distance - support_gap(supports, t, n, pos);
        double u[3];
        if (!(depth > 0.0) || !(slip_velocity(supports, t, n, vel, u) > SUPPORT_SLIP_SPEED)) continue;
        // The pair's mass along its gap (kg): 1 / sum_k w_k^2 / m_k, what a force on the gap, shared as the
        // weights share it, accelerates (a single point's own mass; the sum of signed weights times masses, as
        // before, was negative for a cloth triangle under a collider's vertex, and zero for the cloth's own pairs);
        // and its approach at the start (m/s) against its surface's velocity.
        const double* nn = supports.normal.data() + 3 * t;
        double compliance = 0.0;
        double approach = 0.0;
        for (int c = 0; c < 3; ++c) approach += nn[c] * supports.collider_velocity[3 * t + c];
        each_point(supports, t, [&](Index i, double w) {
            if (mass[i] > 0.0) compliance += w * w / mass[i];
            approach -= w * (nn[0] * start_vel[i] + nn[1] * start_vel[n + i] + nn[2] * start_vel[2 * n + i]);
        });
        const double inertia = compliance > 0.0 ? 1.0 / compliance : 0.0;
        const double landing = inertia * (std::max(approach, 0.0) / h + GRAVITY * std::max(nn[2], 0.0));
        supports.normal_force[term] = std::min(term_stiffness(supports, t) * depth, landing);
        supports.arrived[term] = 1;
        add_friction(supports, t, n, vel, force, blocks);
        arrived += 1;
    }
    return arrived;
}

bool relag_self_normal_force(Supports& supports, Index n, const double* pos) {
    if (!(supports.self_friction > 0.0)) return false;
    const auto force_at = [&](Index t) {
        const double depth = supports.distance - support_gap(supports, t, n, pos);
        return depth > 0.0 ? supports.self_stiffness * depth : 0.0;
    };
    double lagged = 0.0, now = 0.0;
    for (Index t = 0; t < supports.count(); ++t) {
        if (supports.collider[t] != SELF_SUPPORT) continue;
        lagged += supports.normal_force[static_cast<std::size_t>(t)];
        now += force_at(t);
    }
    if (!(std::abs(now - lagged) > SELF_RELAG_CHANGE * lagged)) return false;
    for (Index t = 0; t < supports.count(); ++t) {
        if (supports.collider[t] == SELF_SUPPORT) supports.normal_force[static_cast<std::size_t>(t)] = force_at(t);
    }
    return true;
}

Index drop_departed(Supports& supports, Index n, const double* pos) {
    Index dropped = 0;
    for (Index t = 0; t < supports.count(); ++t) {
        const std::size_t term = static_cast<std::size_t>(t);
        if (!supports.arrived[term] || supports.distance - support_gap(supports, t, n, pos) > 0.0) continue;
        supports.normal_force[term] = 0.0;
        supports.arrived[term] = 0;
        dropped += 1;
    }
    return dropped;
}

double support_energy(const Supports& supports, Index n, const double* pos) {
    double energy = 0.0;
    for (Index t = 0; t < supports.count(); ++t) {
        const double depth = supports.distance - support_gap(supports, t, n, pos);
        if (depth > 0.0) energy += 0.5 * term_stiffness(supports, t) * depth * depth;
    }
    return energy;
}

double support_dissipation(const Supports& supports, Index n, const double* vel) {
    double dissipation = 0.0;
    for (Index t = 0; t < supports.count(); ++t) {
        if (!rubs(supports, t)) continue;
        double u[3];
        const double y = slip_velocity(supports, t, n, vel, u);
        const std::size_t term = static_cast<std::size_t>(t);
        const double eps = slip_speed_of(supports, t);
        dissipation += supports.friction[term] * supports.normal_force[term] * smoothed_speed(y, eps);
    }
    return dissipation;
}

void add_support_forces(Supports& supports, Index n, const double* pos, const double* vel, double* force,
                        double* blocks) {
    for (Index t = 0; t < supports.count(); ++t) {
        const double k = term_stiffness(supports, t);
        const double scaled = supports.scale * k;
        const double depth = supports.distance - support_gap(supports, t, n, pos);
        const bool presses = depth > 0.0;
        const bool stiff = presses || supports.anticipated[static_cast<std::size_t>(t)] != 0;
        supports.pressing[static_cast<std::size_t>(t)] = presses;
        supports.stiff[static_cast<std::size_t>(t)] = stiff;
        if (rubs(supports, t)) add_friction(supports, t, n, vel, force, blocks);
        if (!stiff) continue;
        const double* nn = supports.normal.data() + 3 * t;
        each_point(supports, t, [&](Index i, double w) {
            if (presses) {
                for (Index c = 0; c < 3; ++c) force[c * n + i] += k * depth * w * nn[c];
            }
            const double b = scaled * w * w;
            blocks[i] += b * nn[0] * nn[0];
            blocks[n + i] += b * nn[1] * nn[1];
            blocks[2 * n + i] += b * nn[2] * nn[2];
            blocks[3 * n + i] += b * nn[0] * nn[1];
            blocks[4 * n + i] += b * nn[0] * nn[2];
            blocks[5 * n + i] += b * nn[1] * nn[2];
        });
    }
}

void add_support_product(const Supports& supports, Index n, const double* free, const double* p, double* out) {
    for (Index t = 0; t < supports.count(); ++t) {
        const double scaled = supports.scale * term_stiffness(supports, t);
        const bool stiff = supports.stiff[static_cast<std::size_t>(t)] != 0;
        const bool rubbing = rubs(supports, t);
        if (!stiff && !rubbing) continue;
        const double* nn = supports.normal.data() + 3 * t;
        double along[SUPPORT_POINTS];  // w_j n . p_j of each point, in each_point's order
        int points = 0;
        double sum = 0.0;
        double total[3] = {0.0, 0.0, 0.0};  // sum_j w_j p_j
        each_point(supports, t, [&](Index i, double w) {
            along[points] = w * (nn[0] * p[i] + nn[1] * p[n + i] + nn[2] * p[2 * n + i]);
            sum += along[points++];
            for (Index c = 0; c < 3; ++c) total[c] += w * p[c * n + i];
        });
        const double* h = supports.friction_block.data() + 6 * t;  // xx yy zz xy xz yz
        int j = 0;
        each_point(supports, t, [&](Index i, double w) {
            const double others = sum - along[j++];
            if (stiff) {
                const double a = scaled * free[i] * w * others;
                for (Index c = 0; c < 3; ++c) out[c * n + i] += a * nn[c];
            }
            if (!rubbing) return;
            const double o[3] = {total[0] - w * p[i], total[1] - w * p[n + i], total[2] - w * p[2 * n + i]};
            const double a = supports.velocity_scale * free[i] * w;
            out[i] += a * (h[0] * o[0] + h[3] * o[1] + h[4] * o[2]);
            out[n + i] += a * (h[3] * o[0] + h[1] * o[1] + h[5] * o[2]);
            out[2 * n + i] += a * (h[4] * o[0] + h[5] * o[1] + h[2] * o[2]);
        });
    }
}

void project_supported(const Supports& supports, Index n, double* a) {
    for (Index t = 0; t < supports.count(); ++t) {
        if (!supports.pressing[static_cast<std::size_t>(t)]) continue;
        const double* nn = supports.normal.data() + 3 * t;
        each_point(supports, t, [&](Index i, double w) {
            if (w == 0.0) return;
            const double along = nn[0] * a[i] + nn[1] * a[n + i] + nn[2] * a[2 * n + i];
            for (Index c = 0; c < 3; ++c) a[c * n + i] -= along * nn[c];
        });
    }
}

void support_history(const Supports& supports, Index n, const double* pos, const double* vel, double* prev_pos,
                     double* prev_vel, double h) {
    for (Index t = 0; t < supports.count(); ++t) {
        if (!supports.pressing[static_cast<std::size_t>(t)]) continue;
        each_point(supports, t, [&](Index i, double w) {
            if (w != 0.0) normal_history(n, i, supports.normal.data() + 3 * t, pos, vel, prev_pos, prev_vel, h);
        });
    }
}

}  // namespace wc
