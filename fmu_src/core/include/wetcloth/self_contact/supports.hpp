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
//: steps, eight starting heights a micrometre apart, 720 frames each): the energy rose in no frame, at 33-50 and
//: 48-55 ms a frame (the same at 0.025, and at 1, with the stage's pushes of response.hpp's kept_distance).  The
//: crumpled 21 x 29 pile of bench/self_collision.py (--pile-only), on the floor from about 4 s: at 0.025 its layers
//: sank into each other in every step and the stage's pushes added the energy back (8e-5 J a step, mostly the
//: springs'), so every step gained energy and was taken again in halves down to GAIN_SUBSTEP_LEAST: 740 steps
//: and 10 s of CPU a simulated second, against 60-95 steps and 1.3-2.1 s at 0.1; one step a frame and 0.2 s since
//: the stage leaves the pairs the solve balanced (Contact::layers_solved).  (Before kept_distance, at 0.1
//: the sheet's energy rose in 0-2 frames of three starts, up to 0.054 J, the disc's in 1-8; at 0.4 in 2-4 and 3-7.)
inline constexpr double SELF_SUPPORT_STIFFNESS = 0.1;

//: A pair becomes a term only where its contact normal stands across its elements, within this lean (the sine
//: of its angle with their normal, supports.cpp's tilt; 0.05, 3 degrees).  A point beside a triangle, or an
//: edge beside a parallel one, gathered because it closes on it within the step, has its normal along the
//: layer, and its fixed-normal penalty held a layer that slid over another back: a sheet on a pinned sheet on
//: a 15 deg slope, frictionless, at 1/30 s steps slid 0.28x as far as it should (bench/layer_friction.py).
//: A point over a layer stands over some triangle of it; the stage after the solve still takes every pair.
inline constexpr double SUPPORT_TILT = 0.05;

//: Append to supports the candidate pairs (the list in contact) whose gap at positions pos (3, n) is below
//: `thickness` (m) plus how far they close in `ahead` s at velocities vel (3, n), as SELF_SUPPORT terms whose
//: penalty starts at `thickness` (its onset `distance`, m: the supports' gap, Supports::distance), their
//: friction the cloth's self-contact coefficient (their stiffness, Supports::self_stiffness, is
//: SELF_SUPPORT_STIFFNESS times the cloth's stiffest spring: the stepper sets it with the colliders').
//: Returns how many terms supports has.
Index gather_self_supports(const Contact& contact, Index n, const double* pos, const double* vel, double thickness,
                           double distance, double ahead, Supports& supports);

}  // namespace wc::self_contact
