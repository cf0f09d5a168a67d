// A moving mesh collider's vertices and edges (a still one's at fixed steps) as supports inside the implicit step
// (docs/model.md section 6.3, "Supports in the solve").  A coarse cloth cannot wrap a mesh finer than its particles:
// the mesh's vertices poke into its triangles, and the edges' pass (collider_edges.hpp) pushes the poked triangle back
// after each step, a support the step's solve does not see.  Each pair of a collider feature and a cloth
// element near at the step's start (Supports, gathered by gather_supports) becomes a one-sided penalty on
// the pair's gap along its contact normal there, g = n . sum_k w_k x_k (the weights and normal fixed for
// the step, the collider's points where it is at the step's end):
//     E = stiffness / 2 (distance - g)^2 where g < distance, else 0 (J),
// its force F_k = stiffness (distance - g) w_k n on the pair's cloth particle k, and its stiffness
// stiffness w_k w_l n n^T (rank one over the pair's particles) in Newton's system: the diagonal blocks with
// the per-particle blocks (so the preconditioner sees them), the rest in the matrix product.
// Friction (the collider's coefficient mu, off when 0): on the pair's relative velocity at the step's end,
// u = sum_k w_k v_k (the collider's points at its surface's velocity there), its part across n, u_t, meets
// the smoothed Coulomb force of IPC (Li et al. 2020), F_k = -w_k mu N f1(|u_t|) u_t / |u_t|, N = stiffness
// (distance - g_0) the pair's normal force at the step's start (lagged, as IPC's: fixed for the step; at fixed
// steps a pair met within the step takes it from an iterate: lag_arriving_normal_force), f1(y)
// = 2 y / eps - y^2 / eps^2 below eps = SUPPORT_SLIP_SPEED, else 1: minus the gradient in v_k of the
// dissipation potential D = mu N f0(|u_t|), f0' = f1 (W).  Its stiffness in velocity, w_k w_l mu N H (H the
// Hessian of f0(|u_t|), rank two in the plane across n, positive semidefinite), joins Newton's system times bh
// as the normal term's does: with N fixed Newton's matrix is the step's exact Jacobian.
#pragma once
#include "wetcloth/core.hpp"
#include "wetcloth/smoothed_friction.hpp"

namespace wc {

//: The gap (m) the solve keeps a collider feature from a cloth element, as a fraction of thickness / 2: below
//: the particles' own distance from a collider's surface, so that a cloth lying on a flat part of a mesh
//: (its edges and vertices in the face's plane, the cloth thickness / 2 above) is not pressed by them; above
//: the edges' pass's (EDGE_GAP of it).
inline constexpr double SUPPORT_DISTANCE = 0.5;

//: The penalty's stiffness as a multiple of the cloth's stiffest spring (N/m per N/m).
inline constexpr double SUPPORT_STIFFNESS = 10.0;

//: The slip speed (m/s) below which a support's friction acts as a stiff viscous stick: the smoothed law's
//: (smoothed_friction.hpp).
inline constexpr double SUPPORT_SLIP_SPEED = SLIP_SPEED;
//: The same for the cloth's pairs with itself (self_contact/supports.hpp): ten times slower, so that layers at
//: rest on layers creep at most 0.1 mm/s and the cloth can fall asleep.  At SLIP_SPEED the crumpled 21 x 29 pile
//: of bench/self_collision.py (--pile-only) crept at 1-7 mm/s for as long as it ran (20 s, three starts a
//: micrometre apart; 0.25 s frames of the 11 x 15 one: two of six asleep by 20 s); at this speed all three fell
//: asleep at 7-11 s (the smaller one's six at 6-15 s), in 2.9-4.0 s of CPU for 20 s against 4.7-7.0.
inline constexpr double SELF_SLIP_SPEED = 1e-4;

//: The cloth particles a term holds at most (a pair of the cloth with itself: four; with a collider: up to three,
//: the others -1).
inline constexpr int SUPPORT_POINTS = 4;

//: A term's collider index for a pair of the cloth's own elements (self_contact/supports.hpp): its normal fixed
//: in the world for the step, its offset table_part's first entry, its friction Supports::self_friction.
inline constexpr Index SELF_SUPPORT = -2;

//: A term's collider index for the floor (a horizontal plane at the floor's level that never moves, with the
//: floor's friction): the analytic supports' (collider_analytic_supports.hpp) at fixed steps.
inline constexpr Index FLOOR_SUPPORT = -1;

//: Keep the first `kept` gathered terms of supports (0: none), dropping the rest.
void keep_terms(Supports& supports, Index kept);

//: The cloth's stiffest spring (N/m): the penalties' stiffness is a multiple of it (Supports::stiffness,
//: SUPPORT_STIFFNESS times; Supports::self_stiffness, self_contact::SELF_SUPPORT_STIFFNESS times).
double stiffest_spring(const Cloth& cloth);

//: Term t's penalty stiffness (N/m): Supports::self_stiffness for a pair of the cloth with itself, else stiffness.
inline double term_stiffness(const Supports& supports, Index t) {
    const bool self = supports.collider[static_cast<std::size_t>(t)] == SELF_SUPPORT;
    return self ? supports.self_stiffness : supports.stiffness;
}

//: Set each term's world normal and offset for a step of h s from the step's start (the colliders' motion
//: rows set for it: collider_motion.hpp), the collider's points where it is at the step's end, and its
//: collider's friction, its points' weighted velocity there and its normal force at the start, the cloth at
//: pos (3, n); bh (s) the step matrix's velocity factor (its position factor bh^2).
void place_supports(Supports& supports, const Physics& phys, Index n, const double* pos, double h, double bh);

//: The terms with friction but no normal force at the step's start (met within it; not the cloth's own pairs,
//: whose friction the self-collision stage applies after the step) that press at positions
//: pos (3, n) and slip faster than SUPPORT_SLIP_SPEED at velocities vel (3, n), a Newton iterate: their normal
//: force there, stiffness (distance - g) (N), held for the rest of the step (IPC's friction lagged from an
//: iterate), so that a particle arriving within a step of h s has friction in it.  At most what lands the
//: pair (mass (n) kg; along its gap 1 / sum_k w_k^2 / m_k) within the step: its approach at start_vel (3, n,
//: m/s) stopped and its weight held (an iterate far from the solution can lie deep in the penalty).  Their
//: friction at vel joins force (3, n) and blocks (6, n) as add_support_forces adds it.  Returns how many.
Index lag_arriving_normal_force(Supports& supports, Index n, const double* mass, const double* start_vel,
                                const double* pos, const double* vel, double h, double* force, double* blocks);

//: The terms whose normal force lag_arriving_normal_force took from an iterate (Supports::arrived) that do not press
//: at positions pos (3, n), a converged solve's end: their normal force back to 0 (lagged again should a later
//: iterate press them), so that friction acts only where the step ends in contact.  A Newton iterate far from the
//: solution may press a support the solution never reaches: a frame step's first iterate let a sheet lying on
//: another fall through it onto the plane under both, and that plane's friction held the top sheet from sliding on
//: the bottom one for the frame (bench/layer_friction.py).  Returns how many.
Index drop_departed(Supports& supports, Index n, const double* pos);

//: The change of the cloth's pairs' summed normal force (a fraction of the lagged sum) at which
//: relag_self_normal_force takes their normal forces again.
inline constexpr double SELF_RELAG_CHANGE = 0.1;

//: The cloth's pairs with itself (SELF_SUPPORT terms with friction): where their normal forces at positions pos (3,
//: n), an iterate the solve would stop at, sum to more than SELF_RELAG_CHANGE of the lagged sum apart from it, each
//: takes its own there (IPC's lag, taken again within the step) and true is returned.  The step's start lags a pair
//: gathered as layers slide over each other at the depth the layers had under fewer pairs: a sheet sliding on
//: another at 0.9 tan a, at 1/30 s steps, met 338 pairs where 231 had held its weight, their lagged normal forces
//: summed to 1.25 times that weight, and their friction stopped it (bench/layer_friction.py: 0.35 of Coulomb's
//: slide in 0.2 s, 0.83 with this).
bool relag_self_normal_force(Supports& supports, Index n, const double* pos);

//: Each term's gap at positions pos (3, n, m): offset + sum_k w_k normal . x_k (m).
double support_gap(const Supports& supports, Index term, Index n, const double* pos);

//: The penalty's energy (J) at positions pos (3, n).
double support_energy(const Supports& supports, Index n, const double* pos);

//: The friction's dissipation potential (W) at velocities vel (3, n): sum mu N f0(|u_t|).
double support_dissipation(const Supports& supports, Index n, const double* vel);

//: The pressing terms' forces (N) at positions pos into force (3, n) and the stiffness's diagonal blocks of
//: those and the anticipated ones times scale into blocks (6, n; xx, yy, zz, xy, xz, yz), marking which press
//: and which are stiff; the friction's forces at
//: velocities vel (3, n) of the terms with a normal force at the step's start and their velocity stiffness's
//: diagonal blocks times velocity_scale, keeping that stiffness for the product.
void add_support_forces(Supports& supports, Index n, const double* pos, const double* vel, double* force,
                        double* blocks);

//: out (3, n) += the terms' stiffness off the diagonal blocks (the stiff ones' times scale, the friction's
//: times velocity_scale) times p (3, n), in the rows of free particles (free (n) 1).
void add_support_product(const Supports& supports, Index n, const double* free, const double* p, double* out);

//: Remove from a (3, n) the parts along each pressing term's normal at its particles: the support sets their
//: motion there (the step's error estimate leaves it out, as the floor's and colliders' contact).
void project_supported(const Supports& supports, Index n, double* a);

//: After the step is taken (pos, vel its end, prev_pos, prev_vel its start, (3, n)): the particles of the
//: terms that pressed at its end get the history of a straight motion along the term's normal (as the
//: floor's normal_history), so that BDF2's next step and its error estimate do not carry the support's kick.
void support_history(const Supports& supports, Index n, const double* pos, const double* vel, double* prev_pos,
                     double* prev_vel, double h);

}  // namespace wc
