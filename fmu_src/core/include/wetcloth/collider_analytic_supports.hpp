// The analytic colliders (plane, box, sphere, cylinder) and the floor as supports inside fixed implicit steps
// (docs/model.md section 6.3, "Supports in the solve").  A frame-long step carries a free particle into a collider it did not
// touch at the step's start; the particles' contact (colliders.hpp) then pushes it out after the step, a push
// the step's solve never saw, which stretches its springs (the tablecloth_sphere gained up to 0.08 J in a
// frame).  Each free particle that may reach a collider within the step becomes a term of the mesh supports
// (collider_supports.hpp, the same penalty and stiffness): the particle alone (weight 1) against the
// collider's tangent plane at its nearest point at the step's start, which a convex shape lies wholly behind,
// so that the plane keeps it out of the shape too.  It starts off the plane, never pressed (a term that did
// would give its stored energy to the step), so its friction's lagged normal force is zero: one that
// arrives slides on the collider in the next step (sliding.hpp).
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Keep the first `kept` terms of supports (a mesh's, gather_supports's) and add a term for each free particle
//: (free (n) not 0) sliding on no surface (sliding, or null) and each still analytic collider, and the floor
//: (collider FLOOR_SUPPORT), whose surface it is nearer than thickness + ahead |v| + ahead^2 GRAVITY at the
//: step's start (pos, vel (3, n); ahead s, the longest step): as far as the step may carry it.  (A moving one's, tried, had no friction for a particle it
//: meets within the step, whose lagged normal force is zero: the sweep's ball no longer dragged its towel,
//: which ended 67 mm from its adaptive run's place, against 12 mm with the pushes after the step.)  The term's
//: plane stands thickness / 2 - distance (m, the supports' gap) out from the collider's tangent plane, so
//: that its penalty starts where the particles' contact keeps them, thickness / 2 off the surface.  Returns
//: how many terms supports has.
Index gather_analytic_supports(const Physics& phys, Index n, const double* pos, const double* vel, const double* free,
                               const Sliding* sliding, double distance, double ahead, Index kept, Supports& supports);

}  // namespace wc
