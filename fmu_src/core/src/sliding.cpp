// Particles sliding on the floor or a collider through an implicit step (sliding.hpp; docs/model.md
// section 6.1).
//
// A particle that slides on a surface and is left free in the step's solve falls into the surface under the
// force pressing it there, by h'^2 F_n / m, and is put back after the step, where its friction acts as an
// impulse: the step's error estimate sees both (the fall across the surface and the friction missing from
// the motion along it) and holds the steps of a cloth settling on the floor to about 1 ms.  So in the solve
// its velocity across the surface is prescribed (it stays where it is across it: the corrections of Newton's
// iterations have no part along the normal) and kinetic friction is a force of the step: friction times the
// force pressing it onto the surface, against its direction of sliding at the step's start.  One that
// friction stops within the step ends it at rest on the surface (held in the next step, static friction);
// one that the force lifts off moves at the step's end as a held particle that slips does.
#include "wetcloth/sliding.hpp"

#include <algorithm>
#include <cmath>

#include "wetcloth/collider_motion.hpp"
#include "wetcloth/colliders.hpp"
#include "wetcloth/floor.hpp"
#include "wetcloth/smoothed_friction.hpp"

namespace wc {

namespace {

//: The surface particle i lies on: the floor (centre at floor_z or below) or the collider it touches (k, -1:
//: the floor; touched_collider's, with `slack` m), its outward normal into nrm, its friction and its velocity u
//: (m/s: a moving collider's, else 0); false if none.
bool surface_under(const Physics& phys, Index n, Index i, const double* pos, double slack, double nrm[3],
                   double& friction, bool& on_floor, double u[3], Index& k) {
    nrm[0] = 0.0;
    nrm[1] = 0.0;
    nrm[2] = 1.0;
    u[0] = u[1] = u[2] = 0.0;
    friction = phys.floor_friction;
    on_floor = pos[2 * n + i] <= phys.floor_z;
    k = -1;
    if (on_floor) return true;
    k = phys.collider_count > 0 ? touched_collider(phys, n, i, pos, nrm, slack) : -1;
    if (k < 0) return false;
    friction = phys.colliders[k * COLLIDER_COLUMNS + C_FRICTION];
    const double p[3] = {pos[i], pos[n + i], pos[2 * n + i]};
    surface_velocity(phys, k, p, u);
    return true;
}

//: The part t of a (3) along the surface of normal nrm; returns its length.
double along_surface(const double a[3], const double nrm[3], double t[3]) {
    const double across = a[0] * nrm[0] + a[1] * nrm[1] + a[2] * nrm[2];
    double length2 = 0.0;
    for (int c = 0; c < 3; ++c) {
        t[c] = a[c] - across * nrm[c];
        length2 += t[c] * t[c];
    }
    return std::sqrt(length2);
}

//: Add particle i, on collider k (-1: the floor), sliding along t (3, of `length`), its normal turning at
//: turning (3, 1/s).
void add_particle(Sliding& sliding, Index i, const double nrm[3], const double t[3], double length, double friction,
                  bool on_floor, const double u[3], Index k, const double turning[3]) {
    sliding.index.push_back(i);
    double centripetal = 0.0;
    for (int c = 0; c < 3; ++c) {
        sliding.normal.push_back(nrm[c]);
        sliding.start_normal.push_back(nrm[c]);
        sliding.direction.push_back(t[c] / length);
        sliding.start_direction.push_back(t[c] / length);
        sliding.surface_velocity.push_back(u[c]);
        sliding.turning.push_back(turning[c]);
        centripetal += t[c] * turning[c];
    }
    sliding.friction.push_back(friction);
    sliding.on_floor.push_back(on_floor ? 1 : 0);
    sliding.collider.push_back(k);
    sliding.centripetal.push_back(centripetal);
    sliding.normal_speed.push_back(0.0);
    sliding.curving.push_back(0.0);
}

//: Sliding particle s's slip u (3, m/s: its velocity (3, n) relative to its surface, along it); returns |u|.
double slip_speed(const Sliding& sliding, Index s, Index n, const double* vel, double* u = nullptr) {
    const Index i = sliding.index[s];
    const double* nrm = &sliding.normal[3 * s];
    const double* w = &sliding.surface_velocity[3 * s];
    double slip[3] = {vel[i] - w[0], vel[n + i] - w[1], vel[2 * n + i] - w[2]};
    const double across = slip[0] * nrm[0] + slip[1] * nrm[1] + slip[2] * nrm[2];
    for (int c = 0; c < 3; ++c) slip[c] -= across * nrm[c];
    if (u != nullptr) std::copy(slip, slip + 3, u);
    return std::sqrt(slip[0] * slip[0] + slip[1] * slip[1] + slip[2] * slip[2]);
}

//: The force (N) particle s of the set presses onto its surface with: the force (3, n) into it less what
//: keeps it on a curved path (mass (n) kg times its centripetal acceleration); negative if it lifts off.
double pressing(const Sliding& sliding, Index s, Index n, const double* mass, const double* force) {
    const Index i = sliding.index[s];
    const double* nrm = &sliding.normal[3 * s];
    const double into = -(force[i] * nrm[0] + force[n + i] * nrm[1] + force[2 * n + i] * nrm[2]);
    return sliding.centripetal[s] != 0.0 ? into - mass[i] * sliding.centripetal[s] : into;
}

//: Turn sliding particle s's normal and direction to the surface's where its path over a curved collider
//: will end a step of h s (predicted from its start's velocity): the step's force across the surface acts
//: along the end's normal, as the implicit step takes it, and its end lies in the end's tangent plane, which
//: stands h^2 kappa s^2 / 2 (`curving`, m) farther out along that normal than the start.
void to_end(Sliding& sliding, Index s, double h) {
    const double* n0 = &sliding.start_normal[3 * s];
    const double* t0 = &sliding.start_direction[3 * s];
    double* nrm = &sliding.normal[3 * s];
    double* t = &sliding.direction[3 * s];
    double length2 = 0.0;
    for (int c = 0; c < 3; ++c) {
        nrm[c] = n0[c] + h * sliding.turning[3 * s + c];
        length2 += nrm[c] * nrm[c];
    }
    const double scale = 1.0 / std::sqrt(length2);
    double across = 0.0;
    for (int c = 0; c < 3; ++c) {
        nrm[c] *= scale;
        across += t0[c] * nrm[c];
    }
    double along2 = 0.0;
    for (int c = 0; c < 3; ++c) {
        t[c] = t0[c] - across * nrm[c];
        along2 += t[c] * t[c];
    }
    const double unit = 1.0 / std::sqrt(along2);
    for (int c = 0; c < 3; ++c) t[c] *= unit;
    sliding.curving[s] = 0.5 * h * h * sliding.centripetal[s];
}

//: The force (N) sliding particle s will press onto its surface with at the end of a step of h s, from the
//: force (3, n) and velocity (3, n, m/s) predicted there: along the end's normal (to_end's), less its mass (n,
//: kg) times the centripetal acceleration of its predicted slip along a curved collider.
double pressing_ahead(Sliding& sliding, Index s, Index n, const Physics& phys, const double* mass,
                      const double* force, const double* vel, double h) {
    const Index i = sliding.index[s];
    if (sliding.centripetal[s] == 0.0) return pressing(sliding, s, n, mass, force);
    to_end(sliding, s, h);
    const double* nrm = &sliding.normal[3 * s];
    const double* u = &sliding.surface_velocity[3 * s];
    const double v[3] = {vel[i] - u[0], vel[n + i] - u[1], vel[2 * n + i] - u[2]};
    double slip[3], turning[3];
    along_surface(v, nrm, slip);
    normal_turning(phys, sliding.collider[s], nrm, slip, turning);
    const double into = -(force[i] * nrm[0] + force[n + i] * nrm[1] + force[2 * n + i] * nrm[2]);
    return into - mass[i] * (slip[0] * turning[0] + slip[1] * turning[1] + slip[2] * turning[2]);
}

}  // namespace

void Sliding::resize(Index count) {
    const auto each = static_cast<std::size_t>(count), three = 3 * each;
    index.resize(each);
    normal.resize(three);
    friction.resize(each);
    direction.resize(three);
    on_floor.resize(each);
    surface_velocity.resize(three);
    collider.resize(each);
    start_normal.resize(three);
    start_direction.resize(three);
    turning.resize(three);
    centripetal.resize(each);
    normal_speed.assign(each, 0.0);
    curving.assign(each, 0.0);
}

void Sliding::move_entry(Index to, Index from) {
    index[to] = index[from];
    for (Index c = 0; c < 3; ++c) {
        normal[3 * to + c] = normal[3 * from + c];
        direction[3 * to + c] = direction[3 * from + c];
        surface_velocity[3 * to + c] = surface_velocity[3 * from + c];
        start_normal[3 * to + c] = start_normal[3 * from + c];
        start_direction[3 * to + c] = start_direction[3 * from + c];
        turning[3 * to + c] = turning[3 * from + c];
    }
    friction[to] = friction[from];
    on_floor[to] = on_floor[from];
    collider[to] = collider[from];
    centripetal[to] = centripetal[from];
}

Index gather_sliding(Index n, const Physics& phys, const double* pos, const double* vel, const double* free,
                     Sliding& sliding, double slack) {
    sliding.resize(0);
    for (Index i = 0; i < n; ++i) {
        if (free[i] == 0.0) continue;  // pinned, or held at rest
        double nrm[3], friction, u[3];
        bool on_floor;
        Index k;
        if (!surface_under(phys, n, i, pos, slack, nrm, friction, on_floor, u, k)) continue;
        const double v[3] = {vel[i] - u[0], vel[n + i] - u[1], vel[2 * n + i] - u[2]};  // relative to the surface
        double t[3];
        const double slide = along_surface(v, nrm, t);
        if (!(slide > 0.0)) continue;
        const double vn = v[0] * nrm[0] + v[1] * nrm[1] + v[2] * nrm[2];
        if (vn > ACROSS_ROUNDING * slide) continue;  // leaving the surface
        double turning[3] = {0.0, 0.0, 0.0};
        if (k >= 0) normal_turning(phys, k, nrm, t, turning);
        add_particle(sliding, i, nrm, t, slide, friction, on_floor, u, k, turning);
    }
    return sliding.count();
}

Index add_released(Index n, const Physics& phys, const double* pos, const double* vel, const double* free,
                   const double* force, Sliding& sliding, double slack) {
    std::vector<char> listed(n, 0);
    for (const Index i : sliding.index) listed[i] = 1;
    Index added = 0;
    for (Index i = 0; i < n; ++i) {
        if (free[i] == 0.0 || listed[i]) continue;
        double nrm[3], friction, u[3];
        bool on_floor;
        Index k;
        if (!surface_under(phys, n, i, pos, slack, nrm, friction, on_floor, u, k)) continue;
        if (vel[i] != u[0] || vel[n + i] != u[1] || vel[2 * n + i] != u[2]) continue;  // not at rest on it
        const double f[3] = {force[i], force[n + i], force[2 * n + i]};
        const double fn = f[0] * nrm[0] + f[1] * nrm[1] + f[2] * nrm[2];
        if (fn >= 0.0) continue;  // lifted off: free
        double t[3];
        const double along = along_surface(f, nrm, t);
        if (!(along > 0.0)) continue;
        const double still[3] = {0.0, 0.0, 0.0};  // at rest: its normal does not turn yet
        add_particle(sliding, i, nrm, t, along, friction, on_floor, u, k, still);
        added += 1;
    }
    return added;
}

void project_sliding(const Sliding& sliding, Index n, double* a) {
    for (Index s = 0; s < sliding.count(); ++s) {
        const Index i = sliding.index[s];
        const double* nrm = &sliding.normal[3 * s];
        const double along = a[i] * nrm[0] + a[n + i] * nrm[1] + a[2 * n + i] * nrm[2];
        for (int c = 0; c < 3; ++c) a[c * n + i] -= along * nrm[c];
    }
}

void prescribe_normal_speed(Sliding& sliding, Index n, const double* pos, const double* hat_pos, double h, double bh,
                            double* vel) {
    for (Index s = 0; s < sliding.count(); ++s) {
        const Index i = sliding.index[s];
        if (sliding.centripetal[s] != 0.0) to_end(sliding, s, h);
        const double* nrm = &sliding.normal[3 * s];
        const double* u = &sliding.surface_velocity[3 * s];
        double gap = 0.0;
        double vn = 0.0;
        for (int c = 0; c < 3; ++c) {
            gap += (pos[c * n + i] - hat_pos[c * n + i]) * nrm[c];
            vn += vel[c * n + i] * nrm[c];
        }
        const double un = u[0] * nrm[0] + u[1] * nrm[1] + u[2] * nrm[2];
        if (un != 0.0) gap += h * un;  // (a still surface: as before, to the bit)
        if (sliding.curving[s] != 0.0) gap += sliding.curving[s];
        const double speed = gap / bh;
        sliding.normal_speed[s] = speed;
        for (int c = 0; c < 3; ++c) vel[c * n + i] += (speed - vn) * nrm[c];
    }
}

void add_sliding_friction(const Sliding& sliding, Index n, const double* mass, const double* vel, double bh,
                          double* force, double* blocks) {
    for (Index s = 0; s < sliding.count(); ++s) {
        const Index i = sliding.index[s];
        const double onto = sliding.smoothed ? sliding.lagged_onto[static_cast<std::size_t>(s)]
                                             : pressing(sliding, s, n, mass, force);
        if (!(onto > 0.0)) continue;
        const double kinetic = sliding.friction[s] * onto;
        if (!sliding.smoothed) {
            for (int c = 0; c < 3; ++c) force[c * n + i] -= kinetic * sliding.direction[3 * s + c];
            continue;
        }
        double u[3];
        const double y = slip_speed(sliding, s, n, vel, u);
        const double a = slip_factor(y);
        double stiffness[6];
        slip_stiffness(kinetic, y, u, &sliding.normal[3 * s], stiffness);
        for (int c = 0; c < 3; ++c) force[c * n + i] -= kinetic * a * u[c];
        for (int e = 0; e < 6; ++e) blocks[e * n + i] += bh * stiffness[e];
    }
}

void lag_normal_force(Sliding& sliding, Index n, const double* mass, const double* force) {
    sliding.lagged_onto.resize(static_cast<std::size_t>(sliding.count()));
    for (Index s = 0; s < sliding.count(); ++s) {
        sliding.lagged_onto[static_cast<std::size_t>(s)] = std::max(pressing(sliding, s, n, mass, force), 0.0);
    }
}

void lag_predicted_normal_force(Sliding& sliding, Index n, const Physics& phys, const double* mass,
                                const double* force, const double* vel, double h) {
    for (Index s = 0; s < sliding.count(); ++s) {
        double& onto = sliding.lagged_onto[static_cast<std::size_t>(s)];
        const double predicted = std::max(pressing_ahead(sliding, s, n, phys, mass, force, vel, h), 0.0);
        if (std::abs(predicted - onto) <= PREDICTION_TRUST * onto) onto = predicted;
    }
}

Index stop_reversed(const Sliding& sliding, Index n, const double* hat_pos, double bh, double* pos, double* vel) {
    Index stopped = 0;
    for (Index s = 0; s < sliding.count(); ++s) {
        const Index i = sliding.index[s];
        const double* nrm = &sliding.normal[3 * s];
        const double* t = &sliding.direction[3 * s];
        const double* u = &sliding.surface_velocity[3 * s];
        if (sliding.smoothed) {  // held by the smoothed law's stick: at rest where the solve put it
            // (not one without friction: it has no stick, and slides on however slowly)
            if (!(sliding.friction[s] > 0.0) || !(slip_speed(sliding, s, n, vel) < SLIP_SPEED)) continue;
            stopped += 1;
            for (int c = 0; c < 3; ++c) vel[c * n + i] = u[c];
            continue;
        }
        const double onward = (vel[i] - u[0]) * t[0] + (vel[n + i] - u[1]) * t[1] + (vel[2 * n + i] - u[2]) * t[2];
        if (onward > 0.0) continue;
        stopped += 1;
        const double un = u[0] * nrm[0] + u[1] * nrm[1] + u[2] * nrm[2];
        for (int c = 0; c < 3; ++c) {  // at rest on the surface (exactly: held in the next step), where it is across it
            const Index k = c * n + i;
            vel[k] = u[c];
            pos[k] = hat_pos[k] + bh * sliding.normal_speed[s] * nrm[c];
            if (u[c] != 0.0 || un != 0.0) pos[k] += bh * (u[c] - un * nrm[c]);  // carried along a moving surface
        }
    }
    return stopped;
}

double lift_off(const Sliding& sliding, Index n, const Physics& phys, const double* force, const double* mass,
                const double* diagonal_blocks, const double* blocks, double h, double limit, double* pos, double* vel) {
    double farthest = 0.0;
    const double reach = 0.5 * phys.thickness;
    for (int pass = 0; pass < 2; ++pass) {  // first: how far each would move; second: move them
        for (Index s = 0; s < sliding.count(); ++s) {
            const Index i = sliding.index[s];
            const double* nrm = &sliding.normal[3 * s];
            const bool lifts = pressing(sliding, s, n, mass, force) < 0.0;
            const double lifting = force[i] * nrm[0] + force[n + i] * nrm[1] + force[2 * n + i] * nrm[2];
            const double inertia = lifts ? effective_mass(n, i, mass, diagonal_blocks, blocks, nrm) : 1.0;
            // From the end's tangent plane to where it would have gone (along the start's velocity).
            const double move = lifts ? 0.5 * lifting / inertia * h * h + sliding.curving[s] : 0.0;
            if (pass == 0) {
                if (move > limit) return -1.0;
                farthest = std::max(farthest, move);
                continue;
            }
            const double* u = &sliding.surface_velocity[3 * s];
            const double vn = (vel[i] - u[0]) * nrm[0] + (vel[n + i] - u[1]) * nrm[1] + (vel[2 * n + i] - u[2]) * nrm[2];
            for (int c = 0; c < 3; ++c) {
                pos[c * n + i] += move * nrm[c];
                vel[c * n + i] += (lifts ? lifting / inertia * h + 2.0 * sliding.curving[s] / h : 0.0) * nrm[c] - vn * nrm[c];
            }
            if (sliding.on_floor[s] && !lifts) pos[2 * n + i] = phys.floor_z;
            if (sliding.curving[s] != 0.0 && !lifts) {
                farthest = std::max(farthest, onto_surface(phys, sliding.collider[s], n, i, reach, h, pos, vel));
            }
        }
    }
    return farthest;
}

Index mark_curved_paths(const Sliding& sliding, Index n, std::vector<char>& on_path) {
    on_path.assign(static_cast<std::size_t>(n), 0);
    Index marked = 0;
    for (Index s = 0; s < sliding.count(); ++s) {
        if (sliding.centripetal[s] == 0.0) continue;
        on_path[static_cast<std::size_t>(sliding.index[s])] = 1;
        marked += 1;
    }
    return marked;
}

Index drop_lifting(Sliding& sliding, Index n, const double* mass, const double* force) {
    Index kept = 0;
    const Index count = sliding.count();
    for (Index s = 0; s < count; ++s) {
        if (pressing(sliding, s, n, mass, force) < 0.0) continue;
        sliding.move_entry(kept, s);
        kept += 1;
    }
    sliding.resize(kept);
    return count - kept;
}

}  // namespace wc
