// Colliders moved by keys (docs/model.md section 6.3, "Moving colliders"): each collider may be displaced
// from where its row puts it by d_k(t), linear between its keys ((time, x, y, z) rows of
// Physics::collider_keys), 0 at t = 0 and the last key's after it.  The step loop ends steps on key times,
// so a collider moves at one velocity through a step; the geometry (colliders.cpp, collider_mesh.cpp) is
// looked up at p - d_k, and friction acts on the velocity relative to the collider's.
#pragma once
#include "wetcloth/colliders.hpp"
#include "wetcloth/core.hpp"

namespace wc {

//: Columns of a row of Physics::collider_motion: the displacement now (m), the velocity over the current
//: step (m/s), the displacement at the step's start (m).
enum MotionColumn : Index { MOTION_NOW = 0, MOTION_VELOCITY = 3, MOTION_START = 6, MOTION_COLUMNS = 9 };

//: Columns of a row of Physics::collider_keys.
enum ColliderKeyColumn : Index { K_COLLIDER = 0, K_TIME, K_X, K_Y, K_Z, COLLIDER_KEY_COLUMNS };

//: A key time within this many seconds (relative, at least 1 s) of t counts as reached at t: the step that
//: ends on it by rounding leaves no sliver.
inline double key_slack(double t) { return 1e-12 * (t > 1.0 ? t : 1.0); }

//: Whether collider k has a key of nonzero displacement (a moving mesh's edges are left out of the edges'
//: pass, collider_edges.hpp: only the particles' contact keeps the cloth off it).
bool collider_moves(const Physics& phys, Index k);

//: Set every collider's motion for a step from t (s): its displacement at t, now and at the step's start,
//: and its velocity over the key interval after t.  Nothing without keys.
void start_collider_motion(const Physics& phys, double t);

//: Move every collider to its displacement at t (s), the step's end (velocity and start kept).
void end_collider_motion(const Physics& phys, double t);

//: Collider k's displacement now (3) and velocity over the step (3), or null when nothing moves.
inline const double* collider_shift(const Physics& phys, Index k) {
    return phys.collider_motion != nullptr ? phys.collider_motion + k * MOTION_COLUMNS : nullptr;
}

//: The first key time after t (s) (beyond key_slack) at which a collider's velocity changes, or infinity
//: (keys that do not change the velocity, such as keys of zero displacement, do not end steps).
double next_collider_key(const Physics& phys, double t);

//: Whether a collider moves at t (s) or will (then the cloth does not fall asleep).
bool colliders_ahead(const Physics& phys, double t);

//: The longest step (s) over which no moving collider moves farther than MOTION_STEP_FRACTION of its
//: half size (a sphere's radius, a box's or cylinder's smallest half edge, a solid mesh's smallest half
//: box edge; planes and open meshes are not limited), or infinity.
double collider_step_limit(const Physics& phys);

//: The fraction of its half size a collider may move in one step: a particle it sweeps over in a step
//: still lies on the side it entered from, and is pushed back out there.
inline constexpr double MOTION_STEP_FRACTION = 0.5;

//: The velocity (3, m/s) of the moving collider that holds a particle (its Buffers::held value), or null
//: (not held on a collider, or nothing moves).
inline const double* held_rate(const Physics& phys, double held) {
    if (phys.collider_motion == nullptr || held < collider_held(0)) return nullptr;
    return phys.collider_motion + static_cast<Index>(held - collider_held(0)) * MOTION_COLUMNS + MOTION_VELOCITY;
}

//: The particles held on a moving collider (held (n) collider_held(k)) move with it over a step of h s:
//: trial_pos (3, n) = pos + h u, trial_vel = u (u its velocity).
void carry_held(Index n, const Physics& phys, const double* held, const double* pos, double h, double* trial_pos,
                double* trial_vel);

}  // namespace wc
