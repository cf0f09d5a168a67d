// Self-collision (docs/model.md section 6.2; port of bf41571:fmu_src/wetcloth/kernels/self_contact/).
#pragma once
#include <cmath>

#include "wetcloth/core.hpp"

namespace wc {

//: The self-collision stage of one step of h s from x0 to x1 (both (3, n), m; x1 and the end velocities
//: v1 (m/s) changed in place); mass (n) kg, free (n).  Returns whether it changed x1 or v1.
bool resolve(Contact& contact, double thickness, double floor_z, double blow_up_speed, Index n, const double* mass,
             const double* free, const double* x0, double* x1, double* v1, double h);

//: Build the candidate list from contact.reference with `margin` (m) (what a restored snapshot does).
void build(Contact& contact, Index n, double thickness, double margin);

//: Forget the candidate list: margin 0, no pairs.
void invalidate(Contact& contact);

//: Layers at rest (self_contact/resting.cpp): a particle is held on a layer for a step when a candidate
//: pair puts it within (1 + RESTING_SLACK) times the thickness of a still element (a triangle, or an
//: edge when the particle ends an edge; still: its particles held on the floor or a layer, or pinned),
//: and it is at rest or coming onto that element slower than RESTING_SPEED and slowly enough that the
//: self-collision response's inelastic impulse would stop it (sliding at most friction times the
//: approach).  RESTING_PASSES passes let stacked layers rest.  Held particles are marked LAYER_HELD in
//: `held` (the floor's are 1).  Measured on 5 x 7 towels lying on the floor with a crease over
//: themselves (the sensitivity example's costliest runs): the crease's particles lay 1.0-1.7
//: thicknesses from the elements under them (edges on edges holding some of them up) and came onto them
//: at up to 13 mm/s in every 1 ms step, to be pushed back at every step.
inline constexpr double RESTING_SLACK = 1.0;
inline constexpr double RESTING_SPEED = 0.02;  // m/s
inline constexpr Index RESTING_PASSES = 4;
inline constexpr double LAYER_HELD = 2.0;

//: Whether a particle of velocity v (3, m/s) is at rest on a support of unit outward normal (3) or coming
//: onto it slowly enough (below RESTING_SPEED) that an inelastic impulse with `friction` stops it.
inline bool comes_to_rest(const double* v, const double* normal, double friction) {
    const double approach = -(v[0] * normal[0] + v[1] * normal[1] + v[2] * normal[2]);  // m/s onto the support
    const double sx = v[0] + approach * normal[0], sy = v[1] + approach * normal[1], sz = v[2] + approach * normal[2];
    const double sliding = std::sqrt(sx * sx + sy * sy + sz * sz);
    return !(approach < 0.0 || sliding > friction * approach ||
             approach * approach + sliding * sliding > RESTING_SPEED * RESTING_SPEED);
}

//: Hold the free particles at rest on a still layer for the coming step (free 0, held LAYER_HELD); returns
//: how many.  pos, vel (3, n).
Index hold_on_layers(Contact& contact, double thickness, Index n, const double* pos, const double* vel, double* free,
                     double* held);

//: Release the layer-held particles whose support is no longer still (the floor released one of its
//: particles), and those resting on them; returns how many (the step is then to be redone).
Index release_unsupported(Contact& contact, Index n, double* free, double* held);

//: Before a step: release the layer-held particles that the force now on them (3, n; computed at the
//: step's start) lifts off their support or pushes along it beyond friction times the force into it,
//: and those resting on them; returns how many.  (At the end of the step its force is checked again only
//: for supports the floor let go: a particle held one step too many starts sliding a step late, where
//: taking such steps again, as the floor's releases are, cost the edge-on drop into a pool 1.8 times the
//: steps.)
Index release_sliding(Contact& contact, Index n, const double* force, double* free, double* held);

//: After release_sliding: hold the free particles that another still element holds as hold_on_layers
//: would and that the force on them (3, n; at the step's start) presses onto it within friction (a particle
//: in the corner of a fold, on a flat layer and against a sloping one, whose first support let it slide);
//: returns how many.  hold_on_layers must have run in this step (its supports are kept).
Index hold_within_friction(Contact& contact, double thickness, Index n, const double* pos, const double* vel,
                           const double* force, double* free, double* held);

}  // namespace wc
