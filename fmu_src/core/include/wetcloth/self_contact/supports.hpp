// The cloth's pairs with itself as supports inside fixed implicit steps (docs/model.md section 6.2, "Layers in
// the solve"): the self-collision stage treats pairs after the solve, which a frame-long step may leave far
// into each other, and its pushes add energy the solve never saw.  A candidate pair near at the step's start
// becomes a term of collider_supports.hpp: a one-sided penalty on the pair's gap along its contact normal there,
// g = n . sum_k w_k x_k (w its four closest-point weights, self_contact/geometry.hpp; weights and normal fixed
// for the step), pressing below the thickness, with the cloth's self-contact friction.  The step's energy test
// and its restarts (implicit.cpp: a solve that ends above the energy its step started with starts again from the
// lowest point toward rest) then see the layers' contact, and the stage after the solve is left what the step's
// start did not show.
#pragma once

#include "wetcloth/core.hpp"

namespace wc::self_contact {

//: The terms' penalty stiffness as a multiple of the cloth's stiffest spring (N/m per N/m).  Soft: a fixed normal
//: keeps each layer on its side through a frame-long step, and the thickness is left to the stage after the solve.
//: bench/self_contact_energy.py (a 41 x 41 sheet hung by a corner, the 2.5k-vertex disc hung by its cap, 1/30 s
//: steps, three starting heights a micrometre apart), frames in which the energy rose, and the time against
//: the stage alone (which let it rise in 18-27 and 9-12 frames, by up to 0.12 J): at 0.025 0-1 on either (one
//: frame in seven starts of the sheet, 0.0002 J; one in three of the disc, 0.001 J), 0.6x and 0.97x the time; at 0.005 none, 0.55x and 1.03x; at 0 (the
//: terms there but without force) as without them; at 0.1 0-2 frames on the sheet (up to 0.054 J), 1-8 on the
//: disc, 0.7x and 1.1x; at 0.4 2-4 and 3-7, 0.4x and 1.0x; at 10, the colliders' stiffness, up to 0.086 J,
//: 0.3x and 1.5x.
inline constexpr double SELF_SUPPORT_STIFFNESS = 0.025;

//: Append to supports the candidate pairs (the list in contact) whose gap at positions pos (3, n) is below
//: `thickness` (m) plus how far they close in `ahead` s at velocities vel (3, n), as SELF_SUPPORT terms whose
//: penalty starts at `thickness` (its onset `distance`, m: the supports' gap, Supports::distance), their
//: friction the cloth's self-contact coefficient (their stiffness, Supports::self_stiffness, is
//: SELF_SUPPORT_STIFFNESS times the cloth's stiffest spring: the stepper sets it with the colliders').
//: Returns how many terms supports has.
Index gather_self_supports(const Contact& contact, Index n, const double* pos, const double* vel, double thickness,
                           double distance, double ahead, Supports& supports);

}  // namespace wc::self_contact
