// A moving mesh collider's features as supports inside the implicit step (collider_supports.hpp).
#include "wetcloth/collider_supports.hpp"

#include "wetcloth/collider_motion.hpp"
#include "wetcloth/floor.hpp"

namespace wc {

double support_stiffness(const Cloth& cloth) {
    double stiffest = 0.0;
    const Index springs = is_mesh(cloth) ? cloth.pair_count : cloth.families * cloth.n;
    const double* k = is_mesh(cloth) ? cloth.pair_stiffness : cloth.stiffness;
    for (Index s = 0; s < springs; ++s) stiffest = k[s] > stiffest ? k[s] : stiffest;
    return SUPPORT_STIFFNESS * stiffest;
}

void place_supports(Supports& supports, const Physics& phys, double h, double scale) {
    const Index count = supports.count();
    supports.normal.resize(3 * static_cast<std::size_t>(count));
    supports.offset.resize(static_cast<std::size_t>(count));
    supports.pressing.assign(static_cast<std::size_t>(count), 0);
    supports.scale = scale;
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

void add_support_forces(Supports& supports, Index n, const double* pos, double* force, double* blocks) {
    const double k = supports.stiffness;
    const double scaled = supports.scale * k;
    for (Index t = 0; t < supports.count(); ++t) {
        const double depth = supports.distance - support_gap(supports, t, n, pos);
        const bool presses = depth > 0.0;
        supports.pressing[static_cast<std::size_t>(t)] = presses;
        if (!presses) continue;
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
