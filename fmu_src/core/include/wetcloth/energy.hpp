// The cloth's mechanical energy (kinetic, gravitational, the springs' elastic), as wetcloth.energy weighs it: the
// fixed-step mode takes a step again in halves where it ends above its start's by more than what drives the cloth
// may have done (stepping.cpp; docs/model.md section 7).
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Kinetic + gravitational (zero at z = 0) + elastic energy (J) of the cloth at pos, vel (both (3, n)) with the
//: particles' masses `mass` and water `water` (n, kg): every spring with its law (docs/model.md sections 2.4
//: and 3; hinges' terms both ways) and its stiffness, grown by wet_factor (Physics::wet_factor) times its ends'
//: mean saturation (water / capacity).  With `magnitude`, also the sum of its terms' magnitudes there (J), the
//: scale of its rounding.
double mechanical_energy(const Cloth& cloth, double wet_factor, const double* mass, const double* water,
                         const double* pos, const double* vel, double* magnitude = nullptr);

//: Buoyancy's potential energy (J) at pos (3, n): rho g times each particle's volume times the depth integral of
//: its submerged fraction (docs/model.md sections 4.1 and 4.2), so that minus its gradient is the buoyancy force.
double buoyancy_energy(const Cloth& cloth, const Physics& phys, const double* pos);

}  // namespace wc
