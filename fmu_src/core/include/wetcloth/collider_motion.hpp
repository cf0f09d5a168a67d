// Colliders moved by keys (docs/model.md section 6.3, "Moving colliders"): each collider may be displaced
// from where its row puts it by d_k(t), linear between its keys ((time, x, y, z, rx, ry, rz) rows of
// Physics::collider_keys), 0 at t = 0 and the last key's after it, and turned about its centre c_k (its
// row's C_X..C_Z) by R_k(t): the key's rotation vector (rx, ry, rz) rad, by slerp between keys (a constant
// angular velocity omega over each key interval).  The step loop ends steps on key times, so a collider
// moves at one velocity and one angular velocity through a step; the geometry (colliders.cpp,
// collider_mesh.cpp) is looked up at its table point c_k + R_k^T (p - c_k - d_k) (p - d_k if it does not
// turn), normals turned back by R_k, and friction acts on the velocity relative to its surface's there,
// v_k + omega x (p - c_k - d_k).
#pragma once
#include <vector>

#include "wetcloth/colliders.hpp"
#include "wetcloth/core.hpp"
#include "wetcloth/vec3.hpp"

namespace wc {

//: Columns of a row of Physics::collider_motion: the displacement now (m), the velocity over the current
//: step (m/s), the displacement at the step's start (m); the angular velocity over the step (rad/s), the
//: rotation now and at the step's start (3 x 3, by rows), and 1 if the collider turns at all (a key of
//: nonzero rotation), else 0 (then the rotation columns are not looked at).
enum MotionColumn : Index {
    MOTION_NOW = 0, MOTION_VELOCITY = 3, MOTION_START = 6, MOTION_SPIN = 9, MOTION_TURN = 12, MOTION_TURN_START = 21,
    MOTION_TURNS = 30, MOTION_COLUMNS = 31
};

//: Columns of a row of Physics::collider_keys: collider (from 0), time s, displacement m, rotation vector rad.
enum ColliderKeyColumn : Index { K_COLLIDER = 0, K_TIME, K_X, K_Y, K_Z, K_RX, K_RY, K_RZ, COLLIDER_KEY_COLUMNS };

//: A key time within this many seconds (relative, at least 1 s) of t counts as reached at t: the step that
//: ends on it by rounding leaves no sliver.
inline double key_slack(double t) { return 1e-12 * (t > 1.0 ? t : 1.0); }

//: Whether collider k has a key of nonzero displacement or rotation (a moving mesh's edges' pass runs in its
//: table frame, collider_edges.hpp).
bool collider_moves(const Physics& phys, Index k);

//: Set every collider's motion for a step from t (s): its displacement at t, now and at the step's start,
//: and its velocity over the key interval after t.  Nothing without keys.
void start_collider_motion(const Physics& phys, double t);

//: Move every collider to its displacement at t (s), the step's end (velocity and start kept).
void end_collider_motion(const Physics& phys, double t);

//: Collider k's displacement now (3) and velocity over the step (3), or null when nothing moves (or k < 0:
//: the floor).
inline const double* collider_shift(const Physics& phys, Index k) {
    return phys.collider_motion != nullptr && k >= 0 ? phys.collider_motion + k * MOTION_COLUMNS : nullptr;
}

//: The first key time after t (s) (beyond key_slack) at which a collider's velocity changes, or infinity
//: (keys that do not change the velocity, such as keys of zero displacement, do not end steps).
double next_collider_key(const Physics& phys, double t);

//: Whether a collider moves at t (s) or will (then the cloth does not fall asleep).
bool colliders_ahead(const Physics& phys, double t);

//: Whether a collider moves over the step its motion rows are set for (start_collider_motion): a velocity or,
//: for one that turns, an angular velocity other than zero.
bool colliders_move(const Physics& phys);

//: Whether collider k moves over that step (none of another index does: the floor's, a pair of the cloth's own).
bool collider_moving(const Physics& phys, Index k);

//: The greatest speed (m/s) of collider k's surface over that step: |v| + |omega| r_far (r_far as
//: collider_step_limit's).
double surface_speed(const Physics& phys, Index k);

//: Which colliders (1 in (collider_count) where so) move over that step and may touch the cloth at pos (3, n)
//: within it: within thickness + h (surface_speed + cloth_speed) + g h^2 of a particle (m; cloth_speed (m/s) the
//: fastest particle's, h (s) the longest step).
std::vector<char> colliders_near(const Physics& phys, Index n, const double* pos, double cloth_speed, double h);

//: Whether the colliders marked in `near` (colliders_near) all move at one velocity without turning: then that
//: velocity (3, m/s) into u, the frame in which they stand still (zero where none is near).
bool common_frame(const Physics& phys, const std::vector<char>& near, double* u);

//: The longest step (s) over which no point of a moving collider's surface moves farther than
//: MOTION_STEP_FRACTION of its half size (a sphere's radius, a box's or cylinder's smallest half edge, a
//: solid mesh's smallest half box edge; planes and open meshes are not limited), or infinity.  A point's
//: speed is at most |v| + |omega| r_far, r_far the farthest point's distance from the centre (0 for a sphere:
//: its turning does not move its surface).
double collider_step_limit(const Physics& phys);

//: The fraction of its half size a collider may move in one step: a particle it sweeps over in a step
//: still lies on the side it entered from, and is pushed back out there.
inline constexpr double MOTION_STEP_FRACTION = 0.5;

//: Whether a collider's motion row (shift, or null) turns it.
inline bool turns(const double* shift) { return shift != nullptr && shift[MOTION_TURNS] != 0.0; }

//: The point q (3) of the collider's table frame (where its row puts it) that lies at `at` (3) now (or at
//: the step's start when `start`): c + R^T (at - c - d), or at - d when it does not turn; at when it does
//: not move (shift null).  centre: the row's C_X..C_Z.
void table_point(const double* shift, const double* centre, const double* at, bool start, double* q);

//: The world point p (3) where the table point q (3) is now: c + d + R (q - c), or q + d.
void world_point(const double* shift, const double* centre, const double* q, double* p);

//: The world direction (3) of a table-frame direction v (3) now: R v in place (unchanged if it does not turn).
void world_direction(const double* shift, double* v);

//: The table-frame direction (3) of a world direction v (3) now: R^T v in place (world_direction's inverse).
void table_direction(const double* shift, double* v);

//: Collider k's place h s after the step's start (its motion row set by start_collider_motion): the world
//: point p (3) of its table point q (3) and the world direction v (3, in place) of a table-frame direction.
void world_point_after(const Physics& phys, Index k, double h, const double* q, double* p);
void world_direction_after(const Physics& phys, Index k, double h, double* v);

//: The velocity (3, m/s) over the step of collider k's surface at world point p (3):
//: v_k + omega x (p - c - d) (d now); 0 when it does not move.
void surface_velocity(const Physics& phys, Index k, const double* p, double* u);

//: The velocity (3, m/s) at which the moving collider that holds particle i (its Buffers::held value) carries
//: it over a step of h s from pos (3, n): v_k, or the chord (carried - p) / h of its turn; false (rate unset)
//: when it is not held on a collider or nothing moves.
bool held_rate(const Physics& phys, double held, Index n, Index i, const double* pos, double h, double* rate);

//: The particles held on a moving collider (held (n) collider_held(k)) move with it over a step of h s:
//: trial_pos (3, n) = pos + h rate (held_rate), trial_vel its surface's velocity there at the step's end.
void carry_held(Index n, const Physics& phys, const double* held, const double* pos, double h, double* trial_pos,
                double* trial_vel);

}  // namespace wc
