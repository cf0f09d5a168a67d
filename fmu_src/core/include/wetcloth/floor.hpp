// The tank floor: a rigid plane with Coulomb friction (port of bf41571:fmu_src/wetcloth/kernels/floor.py).
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Keep particle centres at or above z_min (m); stop their fall and apply friction.  Returns how many touch.
Index floor_contact(Index n, double z_min, double friction, double* pos, double* vel);

//: Hold the particles at rest on the floor for the coming step (free 0, held 1); returns how many.
Index hold_resting(Index n, double z_min, const double* pos, const double* vel, double* free, double* held);

//: Release the held particles that force (3, n) does not keep on the floor; returns how many.
Index release_slipping(Index n, double friction, const double* force, double* free, double* held);

//: Give the held particles back their free flag after the step.
void release_all(Index n, double* free, double* held);

//: Particles on the floor get the history of a straight motion at their velocity; returns how many.
Index agree_history(Index n, double z_min, const double* pos, const double* vel, double* prev_pos, double* prev_vel,
                    double h);

}  // namespace wc
