// The tank floor: a rigid plane with Coulomb friction (docs/model.md section 6.1; port of
// bf41571:fmu_src/wetcloth/kernels/floor.py).
//
// Two parts of one rule.  A particle that reaches the floor during a step is put back on it and loses
// its downward velocity, and its sliding speed drops by `friction` times that loss (floor_contact,
// after the step).  A particle that lies still on the floor (static friction) is held there during the
// step, as a constraint of the step's own solve (hold_resting), as long as the force on it presses it
// onto the floor within the friction cone (release_slipping).  Holding it, rather than letting the step
// push it into the floor and projecting it back, keeps the multistep history and the error estimate
// of an implicit step free of the floor.  Where the floor did change a particle's motion, its history
// is made to agree with its new velocity (agree_history).
#include "wetcloth/floor.hpp"


namespace wc {

//: The normal velocity change dv_n removed by the floor reduces the sliding speed by friction * dv_n (an
//: inelastic Coulomb impulse), never reversing it.
Index floor_contact(Index n, double z_min, double friction, double* pos, double* vel) {
    Index touching = 0;
    const double up[3] = {0.0, 0.0, 1.0};
    double* z = pos + 2 * n;
    for (Index i = 0; i < n; ++i) {
        if (z[i] >= z_min) continue;
        touching += 1;
        z[i] = z_min;
        double v[3] = {vel[i], vel[n + i], vel[2 * n + i]};
        coulomb_stop(v, up, friction);
        for (Index c = 0; c < 3; ++c) vel[c * n + i] = v[c];
    }
    return touching;
}

//: Those on the floor (centre at z_min, m, where floor_contact left it) with zero velocity (friction
//: stopped them) get free 0 and held 1 (all others held 0).  Pinned particles are left alone.
Index hold_resting(Index n, double z_min, const double* pos, const double* vel, double* free, double* held) {
    Index count = 0;
    const double* z = pos + 2 * n;
    const double* vx = vel;
    const double* vy = vel + n;
    const double* vz = vel + 2 * n;
    for (Index i = 0; i < n; ++i) {
        const bool resting = free[i] != 0.0 && z[i] <= z_min && vx[i] == 0.0 && vy[i] == 0.0 && vz[i] == 0.0;
        held[i] = resting ? 1.0 : 0.0;
        if (resting) {
            free[i] = 0.0;
            count += 1;
        }
    }
    return count;
}

//: Release the held particles that the step's force (N, (3, n)) lifts (upward normal force) or pushes
//: along the floor above friction times the force into it: the floor's impulse would not have kept them
//: still either.  Returns how many (the step is then to be redone).
Index release_slipping(Index n, double friction, const double* force, double* free, double* held) {
    Index released = 0;
    const double up[3] = {0.0, 0.0, 1.0};
    for (Index i = 0; i < n; ++i) {
        if (held[i] != 1.0) continue;  // (held on a layer or a collider: their own releases)
        const double f[3] = {force[i], force[n + i], force[2 * n + i]};
        if (slips(f, up, friction)) {
            held[i] = 0.0;
            free[i] = 1.0;
            released += 1;
        }
    }
    return released;
}

void release_all(Index n, double* free, double* held) {
    for (Index i = 0; i < n; ++i) {
        if (held[i] != 0.0) {
            free[i] = 1.0;
            held[i] = 0.0;
        }
    }
}

//: After a step of h s: the particles on the floor (centre at z_min, m) get the vertical history of a
//: straight motion at their present velocity (prev z = z - h v_z, prev v_z = v_z), so that a multistep
//: scheme does not carry on the fall the floor stopped, and its error estimate does not see the stop as a
//: large error at the next step.  Their horizontal history is kept: a sliding particle's friction
//: deceleration is then the Coulomb value mu g (with a straight history there too, BDF2's velocity
//: update would take only 2/3 of each step's acceleration, the floor's impulse with it).
Index agree_history(Index n, double z_min, const double* pos, const double* vel, double* prev_pos, double* prev_vel,
                    double h) {
    Index count = 0;
    const double up[3] = {0.0, 0.0, 1.0};
    for (Index i = 0; i < n; ++i) {
        if (pos[2 * n + i] > z_min) continue;
        count += 1;
        normal_history(n, i, up, pos, vel, prev_pos, prev_vel, h);
    }
    return count;
}

}  // namespace wc
