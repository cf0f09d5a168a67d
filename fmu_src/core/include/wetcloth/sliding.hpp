// Particles sliding on the floor or a collider, in contact with it through an implicit step (docs/model.md
// section 6.1): their velocity across the surface is prescribed (they stay on it) and kinetic friction acts
// on them as a force of the step, not as an impulse after it.  (The set itself, Sliding, is in core.hpp.)
#pragma once
#include <vector>

#include "wetcloth/core.hpp"

namespace wc {


//: A particle on a surface whose velocity across it is at most this fraction of its sliding speed is not
//: leaving it: what the step's rounding leaves of a velocity set along the surface.
inline constexpr double ACROSS_ROUNDING = 1e-9;

//: Gather the free, not held particles that lie on the floor (centre at floor_z or below) or touch a collider
//: (touched_collider's, with `slack` m) and slide along it: moving along the surface, not away from it.
//: Returns how many.
Index gather_sliding(Index n, const Physics& phys, const double* pos, const double* vel, const double* free,
                     Sliding& sliding, double slack = 0.0);

//: Add to the sliding set the free particles at rest (velocity (3, n) zero) on the floor or a collider that
//: a step's force (3, n, N) presses onto it and pushes along it: released from their hold, they would slide
//: along that push (their direction of sliding); touching as gather_sliding's.  Returns how many.
Index add_released(Index n, const Physics& phys, const double* pos, const double* vel, const double* free,
                   const double* force, Sliding& sliding, double slack = 0.0);

//: Remove the parts of a (3, n) along the sliding particles' normals.
void project_sliding(const Sliding& sliding, Index n, double* a);

//: The sliding particles' velocities (3, n) get their prescribed normal part, speed (m/s) that keeps each
//: where it is across the surface (moving with a moving surface over the step of h s; on a curved one, in the
//: tangent plane of its path's predicted end, n then that end's normal): n . (pos + h u - hat_pos) / bh +
//: h^2 kappa s^2 / (2 bh), pos the step's start, u the surface's velocity, hat_pos (3, n) the scheme's x^ with
//: x+ = x^ + bh v+, kappa s^2 the path's centripetal acceleration (0 on a flat surface).
void prescribe_normal_speed(Sliding& sliding, Index n, const double* pos, const double* hat_pos, double h, double bh,
                            double* vel);

//: Kinetic friction on the sliding particles into force (3, n, N): friction times the force pressing each
//: onto its surface (zero if none: the force into it less its mass (n, kg) times its path's centripetal
//: acceleration), against its direction of sliding at the step's start; or, where sliding.smoothed (fixed
//: steps), IPC's smoothed Coulomb law on its velocity (3, n) relative to the surface at the step's end
//: (smoothed_friction.hpp) with the normal force lag_normal_force held, its stiffness times bh (s) into the
//: diagonal blocks (6, n).
void add_sliding_friction(const Sliding& sliding, Index n, const double* mass, const double* vel, double bh,
                          double* force, double* blocks);

//: For the smoothed law: each sliding particle's normal force for the step, the force (3, n, N) at the step's
//: start pressing it onto its surface (pressing's, 0 if it lifts), held through the step's Newton iterations
//: (lagged, as IPC's: the friction is then the gradient of a dissipation potential, and Newton's matrix its
//: exact Jacobian).  Taken at each Newton iterate (before), it left the normal force's dependence on the
//: positions out of the matrix: a sheet swinging onto the floor at 1/30 s steps got 8 m/s corrections, and a
//: frame ended with springs stretched by 43 %.
void lag_normal_force(Sliding& sliding, Index n, const double* mass, const double* force);

//: A predicted normal force within this fraction of the start's is taken (lag_predicted_normal_force).  A
//: smooth slide changes it by a few percent a step (the bead of tests/test_curved_sliding.py on a ball of
//: friction 0.1: at most 1.1 % in a 4 ms step); a landing within a step, which the history cannot foresee, by
//: up to 7 times (a sheet onto a box at BDF2's 1/30 s steps: taken, it took 514 steps, 192 taken again, instead
//: of 284 and 90).
inline constexpr double PREDICTION_TRUST = 0.25;

//: For BDF2 with history: each sliding particle's normal force for the step becomes the one it will press with
//: at the step's end (h s) as the history predicts it, from the force (3, n) at the predicted positions and the
//: velocities vel (3, n, m/s) predicted there (a curved path's centripetal part along the end's normal), where
//: that is within PREDICTION_TRUST of lag_normal_force's.  The start's lags the step's end by h: the bead on a
//: ball of friction 0.1 slid at first order in the step.
void lag_predicted_normal_force(Sliding& sliding, Index n, const Physics& phys, const double* mass,
                                const double* force, const double* vel, double h);

//: After the step's solve: a sliding particle whose velocity (3, n, m/s) along its direction of sliding is
//: (relative to its surface's) no longer positive has stopped within the step: its velocity is set to its
//: surface's (zero but on a moving collider) and its position (3, n) to x^ + bh v+ with v+ that velocity
//: along the surface and its prescribed velocity across it.  With the smoothed law (sliding.smoothed), one whose
//: slip at the step's end is within its stick (below SLIP_SPEED) is at rest where the solve put it: its
//: velocity set to its surface's (held in the next step).  Returns how many stopped.
Index stop_reversed(const Sliding& sliding, Index n, const double* hat_pos, double bh, double* pos, double* vel);

//: After the step: the particles whose force (3, n) lifts them off their surface (their normal was held in the
//: solve; on a curved path, the force along the normal beyond mass times the path's centripetal acceleration)
//: move as they would have from rest along the start's normal under it, by F_n h^2 / (2 m_e) (m_e their
//: inertia along it in the step's matrix, as slip_on_supports) from the start's tangent plane, and their
//: velocity by F_n h / m_e; the others on the floor are put back exactly at floor_z (rounding), those on a
//: curved collider exactly onto it, their velocity along it.  Returns the largest such move (m), or -1 without
//: moving anything if a lift is beyond `limit` (m): the step is then taken again without them (drop_lifting).
double lift_off(const Sliding& sliding, Index n, const Physics& phys, const double* force, const double* mass,
                const double* diagonal_blocks, const double* blocks, double h, double limit, double* pos, double* vel);

//: Mark in on_path (n, resized and cleared) the particles of the set that slid along a curved collider through
//: the step (their normal turning), returns how many.  Their history, the step's start on the surface moving
//: along it, lies on their curved path, and they keep it (collider_history): a straight motion's history along
//: the normal drops the path's centripetal part, h kappa s^2 of the previous velocity, and BDF2's next step
//: then loses h^2 kappa^2 s^3 / 3 of its speed along the path (first order: docs/model.md 6.3).
Index mark_curved_paths(const Sliding& sliding, Index n, std::vector<char>& on_path);

//: Leave out of the sliding set the particles that the force (3, n) lifts off (as lift_off judges them, mass
//: (n) kg); returns how many.
Index drop_lifting(Sliding& sliding, Index n, const double* mass, const double* force);

}  // namespace wc
