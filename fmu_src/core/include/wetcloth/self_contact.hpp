// Self-collision (docs/model.md section 6.2; port of bf41571:fmu_src/wetcloth/kernels/self_contact/).
#pragma once
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

}  // namespace wc
