// A mesh's springs, listed (docs/model.md section 3.3): spring k joins particles pairs[k] and
// pairs[S + k], with its own rest length, stiffness and damping; the first T are tension-only, the next
// B buckling (a triangle's edges), the rest both ways; of those the last H are hinges' terms (rest length 0,
// linear), damped by c (v_i - v_j) whatever the damping model, so that a hinge's damping, like its
// stiffness, is a positive semidefinite form although some of its terms' coefficients are negative.  The
// same laws as the grid's families (spring_law.hpp), gathered and scattered through the index lists.
#pragma once
#include "wetcloth/core.hpp"
#include "wetcloth/mesh_records.hpp"

namespace wc {

//: Add the listed springs' tension and damping (N) to the force sums of the records (their state filled).
void listed_spring_forces(const Cloth& cloth, const Physics& phys, const MeshRecords& records);

//: As listed_spring_forces, plus their pieces of a Newton step (as spring_forces_and_blocks): adds to the
//: sums' force and diagonal blocks; writes work.pair_direction, pair_along, pair_across.
void listed_spring_forces_and_blocks(const Cloth& cloth, const Physics& phys, const MeshRecords& records, double h,
                                     double slack_slope, Work& work);

//: Add the listed springs' part of the system matrix times p (3, n) to out.
void listed_spring_matvec(const Cloth& cloth, const Work& work, const double* p, double* out);

}  // namespace wc
