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

//: The terms' penalty stiffness as a multiple of the cloth's stiffest spring (N/m per N/m): soft, so that the
//: penalty steers the solve and leaves the thickness to the stage after it.  On a 41 x 41 sheet hung by a corner
//: at 1/30 s steps (its sides fold together) and the 2.5k-vertex disc hung by its cap, three starting heights a
//: micrometre apart each: at 0.1 no frame gained energy on the sheet and up to 0.003 J in 1-3 frames on the disc
//: (without the terms 0.04-0.14 J in 20-26 frames, 0.045-0.05 J in 10-11), the sheet's frames 0.65x the time
//: and the disc's 1.05x; at 1 (the colliders' 10 is stiffer still) the sheet took 0.27x the time but gained up
//: to 0.086 J, the disc 0.037 J at 1.5x the time; at 0.4 the sheet 0.3x, up to 0.0013 J, the disc 1.08x, 0.006 J.
inline constexpr double SELF_SUPPORT_STIFFNESS = 0.1;

//: Append to supports the candidate pairs (the list in contact) whose gap at positions pos (3, n) is below
//: `thickness` (m) plus how far they close in `ahead` s at velocities vel (3, n), as SELF_SUPPORT terms whose
//: penalty starts at `thickness` (its onset `distance`, m: the supports' gap, Supports::distance); their
//: stiffness SELF_SUPPORT_STIFFNESS times the cloth's stiffest spring, their friction the cloth's
//: self-contact coefficient.  Returns how many terms supports has.
Index gather_self_supports(const Contact& contact, const Cloth& cloth, Index n, const double* pos, const double* vel,
                           double thickness, double distance, double ahead, Supports& supports);

}  // namespace wc::self_contact
