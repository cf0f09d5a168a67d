// Colliders moved by keys (collider_motion.hpp; docs/model.md section 6.3).
#include "wetcloth/collider_motion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "wetcloth/collider_mesh.hpp"
#include "wetcloth/colliders.hpp"

namespace wc {

namespace {

//: The key every collider starts from: at t = 0, no displacement.
constexpr double START_KEY[COLLIDER_KEY_COLUMNS] = {};

//: Collider k's displacement d (3) at t (s) and its velocity u (3) over the key interval after t.
void displacement(const Physics& phys, Index k, double t, double* d, double* u) {
    d[0] = d[1] = d[2] = 0.0;
    u[0] = u[1] = u[2] = 0.0;
    const double* before = START_KEY;
    const double* rows = phys.collider_keys;
    const double slack = key_slack(t);
    for (Index r = 0; r < phys.collider_key_count; ++r) {
        const double* key = rows + r * COLLIDER_KEY_COLUMNS;
        if (static_cast<Index>(key[K_COLLIDER]) != k) continue;
        if (key[K_TIME] <= t + slack) {
            before = key;
            continue;
        }
        const double span = key[K_TIME] - before[K_TIME];
        const double fraction = (t - before[K_TIME]) / span;
        for (int c = 0; c < 3; ++c) {
            d[c] = before[K_X + c] + fraction * (key[K_X + c] - before[K_X + c]);
            u[c] = (key[K_X + c] - before[K_X + c]) / span;
        }
        return;
    }
    for (int c = 0; c < 3; ++c) d[c] = before[K_X + c];  // at or after the last key: held there
}

}  // namespace

bool collider_moves(const Physics& phys, Index k) {
    for (Index r = 0; r < phys.collider_key_count; ++r) {
        const double* key = phys.collider_keys + r * COLLIDER_KEY_COLUMNS;
        if (static_cast<Index>(key[K_COLLIDER]) == k && (key[K_X] != 0.0 || key[K_Y] != 0.0 || key[K_Z] != 0.0)) {
            return true;
        }
    }
    return false;
}

void start_collider_motion(const Physics& phys, double t) {
    if (phys.collider_motion == nullptr) return;
    for (Index k = 0; k < phys.collider_count; ++k) {
        double* row = phys.collider_motion + k * MOTION_COLUMNS;
        displacement(phys, k, t, row + MOTION_NOW, row + MOTION_VELOCITY);
        std::copy(row + MOTION_NOW, row + MOTION_NOW + 3, row + MOTION_START);
    }
}

void end_collider_motion(const Physics& phys, double t) {
    if (phys.collider_motion == nullptr) return;
    for (Index k = 0; k < phys.collider_count; ++k) {
        double* row = phys.collider_motion + k * MOTION_COLUMNS;
        double u[3];
        displacement(phys, k, t, row + MOTION_NOW, u);
    }
}

double next_collider_key(const Physics& phys, double t) {
    double next = std::numeric_limits<double>::infinity();
    const double slack = key_slack(t);
    const Index count = phys.collider_key_count;
    const double* rows = phys.collider_keys;
    for (Index r = 0; r < count; ++r) {  // rows by collider, then time (Fixtures::collider_keys)
        const double* key = rows + r * COLLIDER_KEY_COLUMNS;
        if (!(key[K_TIME] > t + slack) || !(key[K_TIME] < next)) continue;
        const bool first = r == 0 || rows[(r - 1) * COLLIDER_KEY_COLUMNS + K_COLLIDER] != key[K_COLLIDER];
        const bool last = r + 1 == count || rows[(r + 1) * COLLIDER_KEY_COLUMNS + K_COLLIDER] != key[K_COLLIDER];
        const double* before = first ? START_KEY : key - COLLIDER_KEY_COLUMNS;
        bool jumps = false;  // the velocity before the key differs from the one after it
        for (int c = 0; c < 3; ++c) {
            const double in = (key[K_X + c] - before[K_X + c]) / (key[K_TIME] - before[K_TIME]);
            const double* after = key + COLLIDER_KEY_COLUMNS;
            const double out = last ? 0.0 : (after[K_X + c] - key[K_X + c]) / (after[K_TIME] - key[K_TIME]);
            jumps = jumps || in != out;
        }
        if (jumps) next = key[K_TIME];
    }
    return next;
}

bool colliders_ahead(const Physics& phys, double t) {
    // (a collider moving at t moves until a key after which its velocity differs: 0 after its last)
    return next_collider_key(phys, t) < std::numeric_limits<double>::infinity();
}

double collider_step_limit(const Physics& phys) {
    double limit = std::numeric_limits<double>::infinity();
    if (phys.collider_motion == nullptr) return limit;
    for (Index k = 0; k < phys.collider_count; ++k) {
        const double* u = phys.collider_motion + k * MOTION_COLUMNS + MOTION_VELOCITY;
        const double speed = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        if (!(speed > 0.0)) continue;
        const double* row = phys.colliders + k * COLLIDER_COLUMNS;
        double half = std::numeric_limits<double>::infinity();
        switch (static_cast<Index>(row[C_SHAPE])) {
            case SPHERE: half = row[C_RADIUS]; break;
            case CYLINDER: half = std::min(row[C_RADIUS], 0.5 * row[C_HEIGHT]); break;
            case BOX: half = 0.5 * std::min({row[C_SIZE_X], row[C_SIZE_Y], row[C_SIZE_Z]}); break;
            case MESH: {
                const double* header = phys.meshes.headers + static_cast<Index>(row[C_RADIUS]) * MESH_COLUMNS;
                if (header[M_SOLID] == 0.0) break;
                for (Index c = 0; c < 3; ++c) half = std::min(half, 0.5 * (header[M_HI_X + c] - header[M_LO_X + c]));
                break;
            }
            default: break;  // a plane
        }
        limit = std::min(limit, MOTION_STEP_FRACTION * half / speed);
    }
    return limit;
}

void carry_held(Index n, const Physics& phys, const double* held, const double* pos, double h, double* trial_pos,
                double* trial_vel) {
    if (phys.collider_motion == nullptr) return;
    for (Index i = 0; i < n; ++i) {
        const double* u = held_rate(phys, held[i]);
        if (u == nullptr) continue;  // free, pinned, on the floor or a layer
        for (Index c = 0; c < 3; ++c) {
            trial_pos[c * n + i] = pos[c * n + i] + h * u[c];
            trial_vel[c * n + i] = u[c];
        }
    }
}

}  // namespace wc
