// The tank floor: a rigid plane with Coulomb friction (port of bf41571:fmu_src/wetcloth/kernels/floor.py).
#pragma once
#include <algorithm>
#include <cmath>

#include "wetcloth/core.hpp"

namespace wc {

//: When a step must be taken again because held particles slip, the particles held on the floor or a
//: collider whose force is beyond RELEASE_ROUND_CONE of their friction cone go free with them: the next
//: to slip, they would otherwise cost a round each (a tablecloth pulled over a table's edge: 1.7x faster
//: with 0.5, bench/tablecloth_drape.py; the sensitivity study unchanged, within its noise).
inline constexpr double RELEASE_ROUND_CONE = 0.5;

//: Coulomb's rule for a particle held still on a surface (the floor's, a collider's, a layer's): it slips
//: unless the force f (3, N) presses it onto the surface of unit outward normal (3) and the force's part
//: along the surface is at most `friction` times the part pressing.
inline bool slips(const double* f, const double* normal, double friction) {
    const double pressing = -(f[0] * normal[0] + f[1] * normal[1] + f[2] * normal[2]);
    double along2 = 0.0;
    for (int c = 0; c < 3; ++c) {
        const double t = f[c] + pressing * normal[c];
        along2 += t * t;
    }
    return pressing <= 0.0 || std::sqrt(along2) > friction * pressing;
}

//: The part of force f (3, N) that a surface of unit outward normal (3) and `friction` does not hold, into
//: excess (3): all of f if it lifts the particle off, else its part along the surface less friction times
//: the part pressing (zero if that is within the cone: slips is false).
inline void slip_force(const double* f, const double* normal, double friction, double* excess) {
    const double pressing = -(f[0] * normal[0] + f[1] * normal[1] + f[2] * normal[2]);
    for (int c = 0; c < 3; ++c) excess[c] = pressing > 0.0 ? f[c] + pressing * normal[c] : f[c];
    if (pressing <= 0.0) return;
    const double along = std::sqrt(excess[0] * excess[0] + excess[1] * excess[1] + excess[2] * excess[2]);
    const double kept = along > friction * pressing ? 1.0 - friction * pressing / along : 0.0;
    for (int c = 0; c < 3; ++c) excess[c] *= kept;
}

//: The inelastic Coulomb impulse of a surface of unit outward normal (3) on velocity v (3, m/s, in place):
//: the part into the surface dv_n is removed and the sliding speed drops by friction * dv_n, never
//: reversing (the floor's and the colliders' contact).
inline void coulomb_stop(double* v, const double* normal, double friction) {
    const double vn = v[0] * normal[0] + v[1] * normal[1] + v[2] * normal[2];
    const double dvn = vn < 0.0 ? -vn : 0.0;
    double vt[3];
    double vt2 = 0.0;
    for (int c = 0; c < 3; ++c) {
        vt[c] = v[c] - vn * normal[c];
        vt2 += vt[c] * vt[c];
    }
    const double slide = std::sqrt(vt2);
    double keep = 1.0;
    if (slide > 0.0) {
        const double k = 1.0 - friction * dvn / slide;
        keep = k > 0.0 ? k : 0.0;
    }
    const double vn_kept = vn > 0.0 ? vn : 0.0;
    for (int c = 0; c < 3; ++c) v[c] = vn_kept * normal[c] + keep * vt[c];
}

//: Particle i of pos, vel (3, n), in contact with a surface of unit outward normal (3), gets the history of
//: a straight motion at its velocity across the surface over a step of h s: the parts of prev_pos and
//: prev_vel along the normal become those of pos - h vel and vel; the parts along the surface are left as
//: they were, so that sliding keeps its history (on the floor and on colliders, after the step).
inline void normal_history(Index n, Index i, const double* normal, const double* pos, const double* vel,
                           double* prev_pos, double* prev_vel, double h) {
    double dp = 0.0;
    double dv = 0.0;
    for (Index c = 0; c < 3; ++c) {
        const Index k = c * n + i;
        dp += (pos[k] - h * vel[k] - prev_pos[k]) * normal[c];
        dv += (vel[k] - prev_vel[k]) * normal[c];
    }
    for (Index c = 0; c < 3; ++c) {
        prev_pos[c * n + i] += dp * normal[c];
        prev_vel[c * n + i] += dv * normal[c];
    }
}

//: m_i + e^T (D_i + B_i) e (kg): particle i's inertia along the unit vector e (3) in an implicit step's
//: matrix, D_i its springs' part of its diagonal block (diagonal_blocks (6, n)) and B_i its own (blocks
//: (6, n)); m_i (mass (n)) alone when diagonal_blocks is null (the explicit schemes).
inline double effective_mass(Index n, Index i, const double* mass, const double* diagonal_blocks,
                             const double* blocks, const double* e) {
    if (diagonal_blocks == nullptr) return mass[i];
    double s[6];
    for (Index slot = 0; slot < 6; ++slot) s[slot] = diagonal_blocks[slot * n + i] + blocks[slot * n + i];
    return mass[i] + block_quadratic(s, e[0], e[1], e[2]);
}

//: How particle i, held on a surface (unit outward normal, friction) that the force f (3, N) slips it off,
//: slides through a step of h s: by the force's excess over friction (slip_force, N) on its inertia along
//: that excess (effective_mass, kg), from rest, as the floor's and colliders' slips and those on a mesh's
//: edges go.
struct Slide {
    double excess[3];     // N
    double direction[3];  // the excess's unit vector (zero for a zero excess)
    double inertia;       // kg

    //: The first of the slips' two passes (measure all, then slide all): whether it slides no farther than
    //: limit (m) in h s; if so, farthest (m) raised to how far it does.
    bool fits(double h, double limit, double& farthest) const {
        const double length = 0.5 * std::sqrt(excess[0] * excess[0] + excess[1] * excess[1] + excess[2] * excess[2]) /
                              inertia * h * h;
        if (length > limit) return false;
        farthest = std::max(farthest, length);
        return true;
    }
    //: Slide particle i of pos, vel (3, n) through the step.
    void apply(Index n, Index i, double h, double* pos, double* vel) const {
        for (int c = 0; c < 3; ++c) {
            pos[c * n + i] += 0.5 * excess[c] / inertia * h * h;
            vel[c * n + i] += excess[c] / inertia * h;
        }
    }
};

inline Slide slide_of(Index n, Index i, const double* f, const double* normal, double friction, const double* mass,
                      const double* diagonal_blocks, const double* blocks) {
    Slide s;
    slip_force(f, normal, friction, s.excess);
    const double size = std::sqrt(s.excess[0] * s.excess[0] + s.excess[1] * s.excess[1] + s.excess[2] * s.excess[2]);
    const double scale = size > 0.0 ? 1.0 / size : 0.0;  // (a force of exactly zero lifting off: no move)
    for (int c = 0; c < 3; ++c) s.direction[c] = s.excess[c] * scale;
    s.inertia = effective_mass(n, i, mass, diagonal_blocks, blocks, s.direction);
    return s;
}

//: Keep particle centres at or above z_min (m); stop their fall and apply friction.  Returns how many touch.
Index floor_contact(Index n, double z_min, double friction, double* pos, double* vel);

//: Hold the particles at rest on the floor for the coming step (free 0, held 1); returns how many.
Index hold_resting(Index n, double z_min, const double* pos, const double* vel, double* free, double* held);

//: Release the held particles that force (3, n) does not keep on the floor; returns how many.
Index release_slipping(Index n, double friction, const double* force, double* free, double* held);

//: Give the held particles back their free flag after the step.
void release_all(Index n, double* free, double* held);

//: Particles on the floor get the vertical history of a straight motion at their velocity; returns how many.
Index agree_history(Index n, double z_min, const double* pos, const double* vel, double* prev_pos, double* prev_vel,
                    double h);

}  // namespace wc
