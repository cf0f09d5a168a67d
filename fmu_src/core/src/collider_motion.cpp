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

//: R (3 x 3, by rows) = exp([r]): the rotation by |r| rad about r (3) (Rodrigues).
void rotation_of(const double* r, double* R) {
    const double angle = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    const double a[3] = {angle > 0.0 ? r[0] / angle : 0.0, angle > 0.0 ? r[1] / angle : 0.0,
                         angle > 0.0 ? r[2] / angle : 0.0};
    const double s = std::sin(angle), c = std::cos(angle), t = 1.0 - c;
    R[0] = c + t * a[0] * a[0], R[1] = t * a[0] * a[1] - s * a[2], R[2] = t * a[0] * a[2] + s * a[1];
    R[3] = t * a[1] * a[0] + s * a[2], R[4] = c + t * a[1] * a[1], R[5] = t * a[1] * a[2] - s * a[0];
    R[6] = t * a[2] * a[0] - s * a[1], R[7] = t * a[2] * a[1] + s * a[0], R[8] = c + t * a[2] * a[2];
}

//: C = A B (3 x 3 by rows); transpose_b: C = A B^T.
void multiply(const double* A, const double* B, bool transpose_b, double* C) {
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            double sum = 0.0;
            for (int m = 0; m < 3; ++m) sum += A[3 * i + m] * (transpose_b ? B[3 * j + m] : B[3 * m + j]);
            C[3 * i + j] = sum;
        }
    }
}

//: The rotation vector r (3, rad, angle in [0, pi]) of the rotation R (3 x 3 by rows): log(R).
void rotation_vector(const double* R, double* r) {
    const double cosine = std::clamp(0.5 * (R[0] + R[4] + R[8] - 1.0), -1.0, 1.0);
    const double w[3] = {R[7] - R[5], R[2] - R[6], R[3] - R[1]};  // 2 sin(angle) times the axis
    const double angle = std::atan2(0.5 * std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]), cosine);  // (not acos:
    // it loses half the digits near 0 and pi)
    const double sine = std::sin(angle);
    if (angle < 1e-6) {  // exp([r]) = I + [r] + O(angle^2)
        for (int c = 0; c < 3; ++c) r[c] = 0.5 * w[c];
        return;
    }
    if (sine > 1e-3) {
        for (int c = 0; c < 3; ++c) r[c] = 0.5 * angle / sine * w[c];
        return;
    }
    // near a half turn: the axis a from the symmetric part, R + R^T = 2 cos I + 2 (1 - cos) a a^T
    Index big = 0;
    for (Index c = 1; c < 3; ++c) big = R[4 * c] > R[4 * big] ? c : big;
    double a[3];
    a[big] = std::sqrt(std::max(0.0, (R[4 * big] - cosine) / (1.0 - cosine)));
    for (Index c = 0; c < 3; ++c) {
        if (c != big) a[c] = 0.5 * (R[3 * c + big] + R[3 * big + c]) / ((1.0 - cosine) * a[big]);
    }
    const double sign = w[0] * a[0] + w[1] * a[1] + w[2] * a[2] < 0.0 ? -1.0 : 1.0;  // (w = 2 sin a)
    for (int c = 0; c < 3; ++c) r[c] = sign * angle * a[c];
}

//: The angular velocity (3, rad/s) of collider k over its key interval that ends at key `key` (from
//: before, START_KEY for its first).
void key_spin(const double* before, const double* key, double* omega) {
    double Ra[9], Rb[9], relative[9];
    rotation_of(before + K_RX, Ra);
    rotation_of(key + K_RX, Rb);
    multiply(Rb, Ra, true, relative);
    rotation_vector(relative, omega);
    for (int c = 0; c < 3; ++c) omega[c] /= key[K_TIME] - before[K_TIME];
}

//: Collider k's keys around t (s): the last at or before t (START_KEY if none) and the first after it (null
//: at or after the last key).
struct KeyInterval {
    const double* before;
    const double* after;
};

KeyInterval key_interval(const Physics& phys, Index k, double t) {
    const double* before = START_KEY;
    const double slack = key_slack(t);
    for (Index r = 0; r < phys.collider_key_count; ++r) {
        const double* key = phys.collider_keys + r * COLLIDER_KEY_COLUMNS;
        if (static_cast<Index>(key[K_COLLIDER]) != k) continue;
        if (key[K_TIME] > t + slack) return {before, key};
        before = key;
    }
    return {before, nullptr};
}

//: Collider k's rotation R (3 x 3 by rows) at t (s) and its angular velocity omega (3, rad/s) over the key
//: interval after t: slerp between the keys' rotations (R(t) = exp((t - t_a) [omega]) R_a, omega =
//: log(R_b R_a^T) / (t_b - t_a)), identity at t = 0, the last key's after it.
void orientation(const Physics& phys, Index k, double t, double* R, double* omega) {
    const KeyInterval at = key_interval(phys, k, t);
    omega[0] = omega[1] = omega[2] = 0.0;
    if (at.after == nullptr) {  // at or after the last key: held there
        rotation_of(at.before + K_RX, R);
        return;
    }
    key_spin(at.before, at.after, omega);
    double Ra[9], turn[9], step[3];
    rotation_of(at.before + K_RX, Ra);
    for (int c = 0; c < 3; ++c) step[c] = (t - at.before[K_TIME]) * omega[c];
    rotation_of(step, turn);
    multiply(turn, Ra, false, R);
}

//: Whether collider k has a key of nonzero rotation.
bool collider_turns(const Physics& phys, Index k) {
    for (Index r = 0; r < phys.collider_key_count; ++r) {
        const double* key = phys.collider_keys + r * COLLIDER_KEY_COLUMNS;
        if (static_cast<Index>(key[K_COLLIDER]) == k && (key[K_RX] != 0.0 || key[K_RY] != 0.0 || key[K_RZ] != 0.0)) {
            return true;
        }
    }
    return false;
}

//: The distance (m) from collider row `row`'s centre to the farthest point of its surface that turning moves
//: (0 for a sphere and a plane; a solid mesh's farthest corner of its box; an open mesh's 0: not limited).
double turning_reach(const Physics& phys, const double* row) {
    switch (static_cast<Index>(row[C_SHAPE])) {
        case CYLINDER: return std::hypot(row[C_RADIUS], 0.5 * row[C_HEIGHT]);
        case BOX: return 0.5 * std::sqrt(row[C_SIZE_X] * row[C_SIZE_X] + row[C_SIZE_Y] * row[C_SIZE_Y] +
                                         row[C_SIZE_Z] * row[C_SIZE_Z]);
        case MESH: {
            const double* header = phys.meshes.headers + static_cast<Index>(row[C_RADIUS]) * MESH_COLUMNS;
            double far2 = 0.0;
            for (Index c = 0; c < 3; ++c) {
                const double lo = header[M_LO_X + c] - row[C_X + c], hi = header[M_HI_X + c] - row[C_X + c];
                far2 += std::max(lo * lo, hi * hi);
            }
            return std::sqrt(far2);
        }
        default: return 0.0;
    }
}

//: Collider k's displacement d (3) at t (s) and its velocity u (3) over the key interval after t.
void displacement(const Physics& phys, Index k, double t, double* d, double* u) {
    const KeyInterval at = key_interval(phys, k, t);
    u[0] = u[1] = u[2] = 0.0;
    if (at.after == nullptr) {  // at or after the last key: held there
        for (int c = 0; c < 3; ++c) d[c] = at.before[K_X + c];
        return;
    }
    const double span = at.after[K_TIME] - at.before[K_TIME];
    const double fraction = (t - at.before[K_TIME]) / span;
    for (int c = 0; c < 3; ++c) {
        d[c] = at.before[K_X + c] + fraction * (at.after[K_X + c] - at.before[K_X + c]);
        u[c] = (at.after[K_X + c] - at.before[K_X + c]) / span;
    }
}

}  // namespace

bool collider_moves(const Physics& phys, Index k) {
    for (Index r = 0; r < phys.collider_key_count; ++r) {
        const double* key = phys.collider_keys + r * COLLIDER_KEY_COLUMNS;
        if (static_cast<Index>(key[K_COLLIDER]) == k && (key[K_X] != 0.0 || key[K_Y] != 0.0 || key[K_Z] != 0.0)) {
            return true;
        }
    }
    return collider_turns(phys, k);
}

void table_point(const double* shift, const double* centre, const double* at, bool start, double* q) {
    if (shift == nullptr) {
        for (int c = 0; c < 3; ++c) q[c] = at[c];
        return;
    }
    const double* d = shift + (start ? MOTION_START : MOTION_NOW);
    if (!turns(shift)) {
        for (int c = 0; c < 3; ++c) q[c] = at[c] - d[c];
        return;
    }
    const double* R = shift + (start ? MOTION_TURN_START : MOTION_TURN);
    const double r[3] = {at[0] - centre[0] - d[0], at[1] - centre[1] - d[1], at[2] - centre[2] - d[2]};
    for (int c = 0; c < 3; ++c) q[c] = centre[c] + (R[c] * r[0] + R[3 + c] * r[1] + R[6 + c] * r[2]);
}

void world_point(const double* shift, const double* centre, const double* q, double* p) {
    if (shift == nullptr) {
        for (int c = 0; c < 3; ++c) p[c] = q[c];
        return;
    }
    const double* d = shift + MOTION_NOW;
    if (!turns(shift)) {
        for (int c = 0; c < 3; ++c) p[c] = q[c] + d[c];
        return;
    }
    const double* R = shift + MOTION_TURN;
    const double r[3] = {q[0] - centre[0], q[1] - centre[1], q[2] - centre[2]};
    for (int c = 0; c < 3; ++c) p[c] = centre[c] + d[c] + (R[3 * c] * r[0] + R[3 * c + 1] * r[1] + R[3 * c + 2] * r[2]);
}

void world_direction(const double* shift, double* v) {
    if (!turns(shift)) return;
    const double* R = shift + MOTION_TURN;
    const double w[3] = {v[0], v[1], v[2]};
    for (int c = 0; c < 3; ++c) v[c] = R[3 * c] * w[0] + R[3 * c + 1] * w[1] + R[3 * c + 2] * w[2];
}

void table_direction(const double* shift, double* v) {
    if (!turns(shift)) return;
    const double* R = shift + MOTION_TURN;
    const double w[3] = {v[0], v[1], v[2]};
    for (int c = 0; c < 3; ++c) v[c] = R[c] * w[0] + R[3 + c] * w[1] + R[6 + c] * w[2];
}

void surface_velocity(const Physics& phys, Index k, const double* p, double* u) {
    const double* shift = collider_shift(phys, k);
    if (shift == nullptr) {
        u[0] = u[1] = u[2] = 0.0;
        return;
    }
    for (int c = 0; c < 3; ++c) u[c] = shift[MOTION_VELOCITY + c];
    if (!turns(shift)) return;
    const double* centre = phys.colliders + k * COLLIDER_COLUMNS + C_X;
    const double* w = shift + MOTION_SPIN;
    const double r[3] = {p[0] - centre[0] - shift[MOTION_NOW], p[1] - centre[1] - shift[MOTION_NOW + 1],
                         p[2] - centre[2] - shift[MOTION_NOW + 2]};
    double spin[3];
    cross(w, r, spin);
    for (int c = 0; c < 3; ++c) u[c] += spin[c];
}

bool held_rate(const Physics& phys, double held, Index n, Index i, const double* pos, double h, double* rate) {
    if (phys.collider_motion == nullptr || held < collider_held(0)) return false;
    const Index k = static_cast<Index>(held - collider_held(0));
    const double* shift = phys.collider_motion + k * MOTION_COLUMNS;
    for (int c = 0; c < 3; ++c) rate[c] = shift[MOTION_VELOCITY + c];
    if (!turns(shift)) return true;
    // carried: c + d + h v + exp(h [omega]) (p - c - d), so the chord velocity v + (exp(h [omega]) - I) r / h
    const double* centre = phys.colliders + k * COLLIDER_COLUMNS + C_X;
    double step[3], turn[9];
    for (int c = 0; c < 3; ++c) step[c] = h * shift[MOTION_SPIN + c];
    rotation_of(step, turn);
    const double r[3] = {pos[i] - centre[0] - shift[MOTION_NOW], pos[n + i] - centre[1] - shift[MOTION_NOW + 1],
                         pos[2 * n + i] - centre[2] - shift[MOTION_NOW + 2]};
    for (int c = 0; c < 3; ++c) {
        const double moved = turn[3 * c] * r[0] + turn[3 * c + 1] * r[1] + turn[3 * c + 2] * r[2] - r[c];
        rate[c] += moved / h;
    }
    return true;
}

namespace {

//: Collider k's rotation (3 x 3 by rows) h s after the step's start: exp(h [omega]) R_start.
void rotation_after(const double* shift, double h, double* R) {
    double step[3], turn[9];
    for (int c = 0; c < 3; ++c) step[c] = h * shift[MOTION_SPIN + c];
    rotation_of(step, turn);
    multiply(turn, shift + MOTION_TURN_START, false, R);
}

}  // namespace

void world_point_after(const Physics& phys, Index k, double h, const double* q, double* p) {
    const double* shift = collider_shift(phys, k);
    if (shift == nullptr) {
        for (int c = 0; c < 3; ++c) p[c] = q[c];
        return;
    }
    double d[3];
    for (int c = 0; c < 3; ++c) d[c] = shift[MOTION_START + c] + h * shift[MOTION_VELOCITY + c];
    if (!turns(shift)) {
        for (int c = 0; c < 3; ++c) p[c] = q[c] + d[c];
        return;
    }
    double R[9];
    rotation_after(shift, h, R);
    const double* centre = phys.colliders + k * COLLIDER_COLUMNS + C_X;
    const double r[3] = {q[0] - centre[0], q[1] - centre[1], q[2] - centre[2]};
    for (int c = 0; c < 3; ++c) p[c] = centre[c] + d[c] + (R[3 * c] * r[0] + R[3 * c + 1] * r[1] + R[3 * c + 2] * r[2]);
}

void world_direction_after(const Physics& phys, Index k, double h, double* v) {
    const double* shift = collider_shift(phys, k);
    if (!turns(shift)) return;
    double R[9];
    rotation_after(shift, h, R);
    const double w[3] = {v[0], v[1], v[2]};
    for (int c = 0; c < 3; ++c) v[c] = R[3 * c] * w[0] + R[3 * c + 1] * w[1] + R[3 * c + 2] * w[2];
}

void start_collider_motion(const Physics& phys, double t) {
    if (phys.collider_motion == nullptr) return;
    for (Index k = 0; k < phys.collider_count; ++k) {
        double* row = phys.collider_motion + k * MOTION_COLUMNS;
        displacement(phys, k, t, row + MOTION_NOW, row + MOTION_VELOCITY);
        std::copy(row + MOTION_NOW, row + MOTION_NOW + 3, row + MOTION_START);
        row[MOTION_TURNS] = collider_turns(phys, k) ? 1.0 : 0.0;
        if (row[MOTION_TURNS] == 0.0) continue;
        orientation(phys, k, t, row + MOTION_TURN, row + MOTION_SPIN);
        std::copy(row + MOTION_TURN, row + MOTION_TURN + 9, row + MOTION_TURN_START);
    }
}

void end_collider_motion(const Physics& phys, double t) {
    if (phys.collider_motion == nullptr) return;
    for (Index k = 0; k < phys.collider_count; ++k) {
        double* row = phys.collider_motion + k * MOTION_COLUMNS;
        double u[3];
        displacement(phys, k, t, row + MOTION_NOW, u);
        if (row[MOTION_TURNS] != 0.0) orientation(phys, k, t, row + MOTION_TURN, u);
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
        const double* after = key + COLLIDER_KEY_COLUMNS;
        for (int c = 0; c < 3; ++c) {
            const double in = (key[K_X + c] - before[K_X + c]) / (key[K_TIME] - before[K_TIME]);
            const double out = last ? 0.0 : (after[K_X + c] - key[K_X + c]) / (after[K_TIME] - key[K_TIME]);
            jumps = jumps || in != out;
        }
        if (!jumps && collider_turns(phys, static_cast<Index>(key[K_COLLIDER]))) {  // or the angular velocity
            double in[3], out[3] = {0.0, 0.0, 0.0};
            key_spin(before, key, in);
            if (!last) key_spin(key, after, out);
            jumps = in[0] != out[0] || in[1] != out[1] || in[2] != out[2];
        }
        if (jumps) next = key[K_TIME];
    }
    return next;
}

bool colliders_ahead(const Physics& phys, double t) {
    // (a collider moving at t moves until a key after which its velocity differs: 0 after its last)
    return next_collider_key(phys, t) < std::numeric_limits<double>::infinity();
}

bool collider_moving(const Physics& phys, Index k) {
    if (phys.collider_motion == nullptr || k < 0 || k >= phys.collider_count) return false;
    const double* motion = phys.collider_motion + k * MOTION_COLUMNS;
    for (int c = 0; c < 3; ++c) {
        if (motion[MOTION_VELOCITY + c] != 0.0 || (turns(motion) && motion[MOTION_SPIN + c] != 0.0)) return true;
    }
    return false;
}

std::vector<char> colliders_near(const Physics& phys, Index n, const double* pos, double cloth_speed, double h) {
    std::vector<char> near(static_cast<std::size_t>(phys.collider_count), 0);
    for (Index k = 0; k < phys.collider_count; ++k) {
        if (!collider_moving(phys, k)) continue;
        const double reach = phys.thickness + h * (surface_speed(phys, k) + cloth_speed) + GRAVITY * h * h;
        double normal[3];
        for (Index i = 0; i < n && !near[static_cast<std::size_t>(k)]; ++i) {
            const double p[3] = {pos[i], pos[n + i], pos[2 * n + i]};
            near[static_cast<std::size_t>(k)] = collider_distance(phys, k, p, reach, normal) <= reach;
        }
    }
    return near;
}

bool common_frame(const Physics& phys, const std::vector<char>& near, double* u) {
    bool found = false;
    for (int c = 0; c < 3; ++c) u[c] = 0.0;
    for (Index k = 0; k < phys.collider_count; ++k) {
        if (!near[static_cast<std::size_t>(k)]) continue;
        const double* motion = phys.collider_motion + k * MOTION_COLUMNS;
        for (int c = 0; c < 3; ++c) {
            if (turns(motion) && motion[MOTION_SPIN + c] != 0.0) return false;
            if (found && motion[MOTION_VELOCITY + c] != u[c]) return false;
        }
        for (int c = 0; c < 3; ++c) u[c] = motion[MOTION_VELOCITY + c];
        found = true;
    }
    return true;
}

bool colliders_move(const Physics& phys) {
    for (Index k = 0; k < phys.collider_count; ++k) {
        if (collider_moving(phys, k)) return true;
    }
    return false;
}

double surface_speed(const Physics& phys, Index k) {
    const double* motion = phys.collider_motion + k * MOTION_COLUMNS;
    const double* u = motion + MOTION_VELOCITY;
    double speed = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (turns(motion)) {
        const double* w = motion + MOTION_SPIN;
        speed += std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) *
                 turning_reach(phys, phys.colliders + k * COLLIDER_COLUMNS);
    }
    return speed;
}

double collider_step_limit(const Physics& phys) {
    double limit = std::numeric_limits<double>::infinity();
    if (phys.collider_motion == nullptr) return limit;
    for (Index k = 0; k < phys.collider_count; ++k) {
        const double* row = phys.colliders + k * COLLIDER_COLUMNS;
        const double speed = surface_speed(phys, k);
        if (!(speed > 0.0)) continue;
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
        double u[3];
        if (!held_rate(phys, held[i], n, i, pos, h, u)) continue;  // free, pinned, on the floor or a layer
        for (Index c = 0; c < 3; ++c) trial_pos[c * n + i] = pos[c * n + i] + h * u[c];
        const Index k = static_cast<Index>(held[i] - collider_held(0));
        const double* shift = phys.collider_motion + k * MOTION_COLUMNS;
        if (turns(shift)) {  // its surface's velocity where the step leaves it (the collider moved by h v)
            const double* centre = phys.colliders + k * COLLIDER_COLUMNS + C_X;
            const double* w = shift + MOTION_SPIN;
            double r[3];
            for (Index c = 0; c < 3; ++c) {
                r[c] = trial_pos[c * n + i] - centre[c] - shift[MOTION_NOW + c] - h * shift[MOTION_VELOCITY + c];
            }
            double spin[3];
            cross(w, r, spin);
            for (Index c = 0; c < 3; ++c) u[c] = shift[MOTION_VELOCITY + c] + spin[c];
        }
        for (Index c = 0; c < 3; ++c) trial_vel[c * n + i] = u[c];
    }
}

}  // namespace wc
