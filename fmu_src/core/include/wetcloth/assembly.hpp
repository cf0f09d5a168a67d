// The total force on every particle and, for the implicit schemes, the pieces of its Jacobian
// (port of bf41571:fmu_src/wetcloth/kernels/assembly.py).  Each force family is one call, skipped when the scene
// does not need it.
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Fill out (n) with each particle's submerged fraction (0..1) from heights z (n, m); return the largest.
double submerged(const Physics& phys, Index n, const double* z, double* out);

//: Total force (N) on every particle into work.force (3, n); the submerged fractions into work.submerged.
void forces(const Cloth& cloth, const Physics& phys, Work& work, const double* pos, const double* vel,
            const double* water);

//: Forces as `forces`, plus the pieces of the system matrix M - h dF/dv - h^2 dF/dx: work.blocks the
//: per-particle blocks (drag, buoyancy), work.diagonal_blocks the springs' part
//: of the diagonal blocks, and each spring's block in work.direction, along, across.  With slack_slope > 0
//: the blocks count every tension-only spring as at least that fraction of taut along itself
//: (spring_forces_and_blocks): a majorant of the true Jacobian, for steps that start far from their solution.
void forces_and_blocks(const Cloth& cloth, const Physics& phys, Work& work, const double* pos, const double* vel,
                       const double* water, double h, double slack_slope = 0.0);

//: The flowing fluids' drive (W) on the cloth at pos, vel (3, n), seen from a frame moving at `frame` (3, m/s):
//: the sum over the particles of the water's drag dotted with the current less `frame` and the air's drag dotted
//: with the wind less `frame` (drag as `forces` adds it; 0 where neither fluid flows in that frame).  Each drag
//: opposes the cloth's motion relative to its fluid, F . (v - u) <= 0, so this bounds the drag's power there,
//: F . (v - frame), from above: the most work per second the fluids' flow can do on the cloth.  work.force,
//: work.submerged and work.cells are its scratch.
double fluid_drive(const Cloth& cloth, const Physics& phys, Work& work, const double* pos, const double* vel,
                   const double* frame);

}  // namespace wc
