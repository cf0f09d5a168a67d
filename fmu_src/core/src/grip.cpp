// The grip (docs/model.md section 6.4): the pinned particles follow a prescribed displacement.
#include "wetcloth/grip.hpp"

#include <cmath>

namespace wc {

namespace {

//: The first pinned particle (free 0, held 0), or -1.
Index first_pinned(Index n, const double* free, const double* held) {
    for (Index i = 0; i < n; ++i) {
        if (free[i] == 0.0 && held[i] == 0.0) return i;
    }
    return -1;
}

}  // namespace

void key_displacement(const Physics& phys, double t, double* d) {
    d[0] = d[1] = d[2] = 0.0;
    const Index count = phys.grip_key_count;
    if (count == 0) return;
    const double* keys = phys.grip_keys;
    const double* last = keys + 4 * (count - 1);
    if (t >= last[0]) {
        for (int c = 0; c < 3; ++c) d[c] = last[1 + c];
        return;
    }
    Index j = 0;
    while (keys[4 * j] <= t) ++j;  // the first key after t (times increase, the last is after t)
    const double* after = keys + 4 * j;
    const double zero[4] = {0.0, 0.0, 0.0, 0.0};
    const double* before = j > 0 ? keys + 4 * (j - 1) : zero;
    const double fraction = (t - before[0]) / (after[0] - before[0]);
    for (int c = 0; c < 3; ++c) d[c] = before[1 + c] + fraction * (after[1 + c] - before[1 + c]);
}

GripMove grip_move(Index n, const Physics& phys, const double* free, const double* held, const double* pos,
                   double t, double h, double remaining) {
    GripMove move;
    if (phys.grip_origin == nullptr) return move;
    const Index p = first_pinned(n, free, held);
    if (p < 0) return move;
    double keys_now[3], keys_end[3];
    key_displacement(phys, t, keys_now);
    key_displacement(phys, t + h, keys_end);
    const double target[3] = {phys.grip_x, phys.grip_y, phys.grip_z};
    double now[3], part[3];
    double left = 0.0;
    bool displaced = false;
    for (int c = 0; c < 3; ++c) {
        now[c] = pos[c * n + p] - phys.grip_origin[c * n + p];
        part[c] = now[c] - keys_now[c];
        left = std::fmax(left, std::fabs(target[c] - part[c]));
        displaced = displaced || now[c] != 0.0 || target[c] != 0.0;
    }
    const bool keys_ahead = phys.grip_key_count > 0 && t < phys.grip_keys[4 * (phys.grip_key_count - 1)];
    move.moving = keys_ahead || left > GRIP_RESOLUTION;
    move.acts = move.moving || displaced;
    if (!move.acts) return move;
    const double fraction = h < remaining ? h / remaining : 1.0;
    for (int c = 0; c < 3; ++c) {
        const double input = move.moving ? part[c] + fraction * (target[c] - part[c]) : target[c];
        move.end[c] = keys_end[c] + input;
        move.rate[c] = move.moving ? (move.end[c] - now[c]) / h : 0.0;
    }
    return move;
}

void place_grip(Index n, const Physics& phys, const GripMove& move, const double* free, const double* held,
                double* pos, double* vel) {
    if (!move.acts) return;
    for (Index i = 0; i < n; ++i) {
        if (free[i] != 0.0 || held[i] != 0.0) continue;
        for (Index c = 0; c < 3; ++c) {
            if (pos != nullptr) pos[c * n + i] = phys.grip_origin[c * n + i] + move.end[c];
            vel[c * n + i] = move.rate[c];
        }
    }
}

}  // namespace wc
