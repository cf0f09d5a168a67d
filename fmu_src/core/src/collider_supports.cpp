// A moving mesh collider's features as supports inside the implicit step (collider_supports.hpp).
#include "wetcloth/collider_supports.hpp"

#include <cmath>

#include "wetcloth/collider_motion.hpp"
#include "wetcloth/floor.hpp"

namespace wc {

namespace {

//: f1(y) / y (1/(m/s)) of the smoothed Coulomb law at slip speed y (m/s): 2 / eps - y / eps^2 below eps, else
//: 1 / y.
double slip_factor(double y) {
    constexpr double eps = SUPPORT_SLIP_SPEED;
    return y < eps ? 2.0 / eps - y / (eps * eps) : 1.0 / y;
}

//: f0(y) (m/s), the smoothed |u_t|: y^2 / eps - y^3 / (3 eps^2) + eps / 3 below eps, else y (f0' = f1).
double smoothed_speed(double y) {
    constexpr double eps = SUPPORT_SLIP_SPEED;
    return y < eps ? y * y / eps - y * y * y / (3.0 * eps * eps) + eps / 3.0 : y;
}

//: Term t's relative velocity across its normal, u_t (3, m/s), at velocities vel (3, n); returns |u_t|.
double slip_velocity(const Supports& supports, Index t, Index n, const double* vel, double* u) {
    const double* nn = supports.normal.data() + 3 * t;
    for (int c = 0; c < 3; ++c) u[c] = supports.collider_velocity[3 * t + c];
    for (int j = 0; j < 3; ++j) {
        const Index i = supports.points[3 * t + j];
        if (i < 0) continue;
        const double w = supports.weights[3 * t + j];
        for (Index c = 0; c < 3; ++c) u[c] += w * vel[c * n + i];
    }
    const double along = nn[0] * u[0] + nn[1] * u[1] + nn[2] * u[2];
    for (int c = 0; c < 3; ++c) u[c] -= along * nn[c];
    return std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
}

//: Term t's friction: its forces (N) into force (3, n) at normal force `normal` (N) and velocities vel, its
//: stiffness in the pair's relative velocity (6, N s/m) into friction_block, and that times velocity_scale
//: w_j^2 into each particle's diagonal blocks (6, n).
void add_friction(Supports& supports, Index t, Index n, double normal, const double* vel, double* force,
                  double* blocks) {
    double u[3];
    const double y = slip_velocity(supports, t, n, vel, u);
    const double mu_n = supports.friction[static_cast<std::size_t>(t)] * normal;
    const double a = slip_factor(y);
    // H = mu N (a (I - n n^T) - b t t^T), t = u_t / |u_t|: b = 1 / y at or above eps (the cone's radial part
    // has no stiffness), y / eps^2 below (f1' = a - b); at y = 0 no direction, b = 0.
    const double b = y >= SUPPORT_SLIP_SPEED ? 1.0 / y : y / (SUPPORT_SLIP_SPEED * SUPPORT_SLIP_SPEED);
    const double* nn = supports.normal.data() + 3 * t;
    double tt[3] = {0.0, 0.0, 0.0};
    if (y > 0.0) for (int c = 0; c < 3; ++c) tt[c] = u[c] / y;
    const int row[6] = {0, 1, 2, 0, 0, 1}, column[6] = {0, 1, 2, 1, 2, 2};
    double* h = supports.friction_block.data() + 6 * t;
    for (int e = 0; e < 6; ++e) {
        const int r = row[e], c = column[e];
        h[e] = mu_n * (a * ((r == c ? 1.0 : 0.0) - nn[r] * nn[c]) - b * tt[r] * tt[c]);
    }
    for (int j = 0; j < 3; ++j) {
        const Index i = supports.points[3 * t + j];
        if (i < 0) continue;
        const double w = supports.weights[3 * t + j];
        for (Index c = 0; c < 3; ++c) force[c * n + i] -= w * mu_n * a * u[c];
        const double scaled = supports.velocity_scale * w * w;
        for (int e = 0; e < 6; ++e) blocks[e * n + i] += scaled * h[e];
    }
}

}  // namespace

double support_stiffness(const Cloth& cloth) {
    double stiffest = 0.0;
    const Index springs = is_mesh(cloth) ? cloth.pair_count : cloth.families * cloth.n;
    const double* k = is_mesh(cloth) ? cloth.pair_stiffness : cloth.stiffness;
    for (Index s = 0; s < springs; ++s) stiffest = k[s] > stiffest ? k[s] : stiffest;
    return SUPPORT_STIFFNESS * stiffest;
}

void place_supports(Supports& supports, const Physics& phys, double h, double bh) {
    const Index count = supports.count();
    supports.normal.resize(3 * static_cast<std::size_t>(count));
    supports.offset.resize(static_cast<std::size_t>(count));
    supports.pressing.assign(static_cast<std::size_t>(count), 0);
    supports.friction.resize(static_cast<std::size_t>(count));
    supports.collider_velocity.assign(3 * static_cast<std::size_t>(count), 0.0);
    supports.friction_block.resize(6 * static_cast<std::size_t>(count));
    supports.scale = bh * bh;
    supports.velocity_scale = bh;
    supports.any_friction = false;
    for (Index t = 0; t < count; ++t) {
        const Index k = supports.collider[t];
        double* normal = supports.normal.data() + 3 * t;
        for (int c = 0; c < 3; ++c) normal[c] = supports.table_normal[3 * t + c];
        world_direction_after(phys, k, h, normal);
        // The collider's points' weighted sum at the step's end, sum_k w_k (c + d + R (q_k - c)) = R part +
        // (sum_k w_k) (c + d - R c), its weights summing to minus the cloth's (the pair's four to 0).
        double cloth_weight = 0.0;
        for (int j = 0; j < 3; ++j) cloth_weight += supports.points[3 * t + j] >= 0 ? supports.weights[3 * t + j] : 0.0;
        const double origin[3] = {0.0, 0.0, 0.0};
        double origin_place[3];  // c + d - R c: where the table frame's origin is
        world_point_after(phys, k, h, origin, origin_place);
        double moved[3];
        for (int c = 0; c < 3; ++c) moved[c] = supports.table_part[3 * t + c];
        world_direction_after(phys, k, h, moved);
        for (int c = 0; c < 3; ++c) moved[c] -= cloth_weight * origin_place[c];
        supports.offset[static_cast<std::size_t>(t)] = normal[0] * moved[0] + normal[1] * moved[1] + normal[2] * moved[2];
        const double mu = phys.colliders[k * COLLIDER_COLUMNS + C_FRICTION];
        supports.friction[static_cast<std::size_t>(t)] = mu;
        const double* shift = collider_shift(phys, k);
        if (!(mu > 0.0) || shift == nullptr) continue;
        supports.any_friction = true;
        // The collider's points' weighted velocity at the step's end, sum_k w_k (u + omega x (p_k - c - d)) =
        // W u + omega x (moved - W (c + d)), W = -cloth_weight their weights' sum.
        double* velocity = supports.collider_velocity.data() + 3 * t;
        for (int c = 0; c < 3; ++c) velocity[c] = -cloth_weight * shift[MOTION_VELOCITY + c];
        if (!turns(shift)) continue;
        double centre_place[3];  // c + d
        world_point_after(phys, k, h, phys.colliders + k * COLLIDER_COLUMNS + C_X, centre_place);
        double arm[3], spin[3];
        for (int c = 0; c < 3; ++c) arm[c] = moved[c] + cloth_weight * centre_place[c];
        cross(shift + MOTION_SPIN, arm, spin);
        for (int c = 0; c < 3; ++c) velocity[c] += spin[c];
    }
}

double support_gap(const Supports& supports, Index term, Index n, const double* pos) {
    const double* normal = supports.normal.data() + 3 * term;
    double g = supports.offset[static_cast<std::size_t>(term)];
    for (int j = 0; j < 3; ++j) {
        const Index i = supports.points[3 * term + j];
        if (i < 0) continue;
        const double w = supports.weights[3 * term + j];
        g += w * (normal[0] * pos[i] + normal[1] * pos[n + i] + normal[2] * pos[2 * n + i]);
    }
    return g;
}

double support_energy(const Supports& supports, Index n, const double* pos) {
    double energy = 0.0;
    for (Index t = 0; t < supports.count(); ++t) {
        const double depth = supports.distance - support_gap(supports, t, n, pos);
        if (depth > 0.0) energy += 0.5 * supports.stiffness * depth * depth;
    }
    return energy;
}

double support_dissipation(const Supports& supports, Index n, const double* pos, const double* vel) {
    double dissipation = 0.0;
    for (Index t = 0; t < supports.count(); ++t) {
        const double depth = supports.distance - support_gap(supports, t, n, pos);
        if (!(depth > 0.0)) continue;
        double u[3];
        const double y = slip_velocity(supports, t, n, vel, u);
        dissipation += supports.friction[static_cast<std::size_t>(t)] * supports.stiffness * depth * smoothed_speed(y);
    }
    return dissipation;
}

void add_support_forces(Supports& supports, Index n, const double* pos, const double* vel, double* force,
                        double* blocks) {
    const double k = supports.stiffness;
    const double scaled = supports.scale * k;
    for (Index t = 0; t < supports.count(); ++t) {
        const double depth = supports.distance - support_gap(supports, t, n, pos);
        const bool presses = depth > 0.0;
        supports.pressing[static_cast<std::size_t>(t)] = presses;
        if (!presses) continue;
        if (supports.any_friction && supports.friction[static_cast<std::size_t>(t)] > 0.0) {
            add_friction(supports, t, n, k * depth, vel, force, blocks);
        }
        const double* nn = supports.normal.data() + 3 * t;
        for (int j = 0; j < 3; ++j) {
            const Index i = supports.points[3 * t + j];
            if (i < 0) continue;
            const double w = supports.weights[3 * t + j];
            for (Index c = 0; c < 3; ++c) force[c * n + i] += k * depth * w * nn[c];
            const double b = scaled * w * w;
            blocks[i] += b * nn[0] * nn[0];
            blocks[n + i] += b * nn[1] * nn[1];
            blocks[2 * n + i] += b * nn[2] * nn[2];
            blocks[3 * n + i] += b * nn[0] * nn[1];
            blocks[4 * n + i] += b * nn[0] * nn[2];
            blocks[5 * n + i] += b * nn[1] * nn[2];
        }
    }
}

void add_support_product(const Supports& supports, Index n, const double* free, const double* p, double* out) {
    const double scaled = supports.scale * supports.stiffness;
    for (Index t = 0; t < supports.count(); ++t) {
        if (!supports.pressing[static_cast<std::size_t>(t)]) continue;
        const double* nn = supports.normal.data() + 3 * t;
        double along[3];  // w_j n . p_j of each point
        double sum = 0.0;
        for (int j = 0; j < 3; ++j) {
            const Index i = supports.points[3 * t + j];
            along[j] = i < 0 ? 0.0 : supports.weights[3 * t + j] * (nn[0] * p[i] + nn[1] * p[n + i] + nn[2] * p[2 * n + i]);
            sum += along[j];
        }
        for (int j = 0; j < 3; ++j) {
            const Index i = supports.points[3 * t + j];
            if (i < 0) continue;
            const double a = scaled * free[i] * supports.weights[3 * t + j] * (sum - along[j]);
            for (Index c = 0; c < 3; ++c) out[c * n + i] += a * nn[c];
        }
        if (!supports.any_friction || !(supports.friction[static_cast<std::size_t>(t)] > 0.0)) continue;
        const double* h = supports.friction_block.data() + 6 * t;  // xx yy zz xy xz yz
        double total[3] = {0.0, 0.0, 0.0};  // sum_j w_j p_j
        for (int j = 0; j < 3; ++j) {
            const Index i = supports.points[3 * t + j];
            if (i < 0) continue;
            for (Index c = 0; c < 3; ++c) total[c] += supports.weights[3 * t + j] * p[c * n + i];
        }
        for (int j = 0; j < 3; ++j) {
            const Index i = supports.points[3 * t + j];
            if (i < 0) continue;
            const double w = supports.weights[3 * t + j];
            const double o[3] = {total[0] - w * p[i], total[1] - w * p[n + i], total[2] - w * p[2 * n + i]};
            const double a = supports.velocity_scale * free[i] * w;
            out[i] += a * (h[0] * o[0] + h[3] * o[1] + h[4] * o[2]);
            out[n + i] += a * (h[3] * o[0] + h[1] * o[1] + h[5] * o[2]);
            out[2 * n + i] += a * (h[4] * o[0] + h[5] * o[1] + h[2] * o[2]);
        }
    }
}

void project_supported(const Supports& supports, Index n, double* a) {
    for (Index t = 0; t < supports.count(); ++t) {
        if (!supports.pressing[static_cast<std::size_t>(t)]) continue;
        const double* nn = supports.normal.data() + 3 * t;
        for (int j = 0; j < 3; ++j) {
            const Index i = supports.points[3 * t + j];
            if (i < 0 || supports.weights[3 * t + j] == 0.0) continue;
            const double along = nn[0] * a[i] + nn[1] * a[n + i] + nn[2] * a[2 * n + i];
            for (Index c = 0; c < 3; ++c) a[c * n + i] -= along * nn[c];
        }
    }
}

void support_history(const Supports& supports, Index n, const double* pos, const double* vel, double* prev_pos,
                     double* prev_vel, double h) {
    for (Index t = 0; t < supports.count(); ++t) {
        if (!supports.pressing[static_cast<std::size_t>(t)]) continue;
        for (int j = 0; j < 3; ++j) {
            const Index i = supports.points[3 * t + j];
            if (i >= 0 && supports.weights[3 * t + j] != 0.0) {
                normal_history(n, i, supports.normal.data() + 3 * t, pos, vel, prev_pos, prev_vel, h);
            }
        }
    }
}

}  // namespace wc
