// The step loop: one call advances the cloth from one output time to the next (port of
// wetcloth/kernels/stepping.py and sampling.py).
//
// Each accepted step: the integrator's step with step-size control (particles at rest on the floor
// held there during it), the floor, self-collision, the water's exchanges over the step (uptake,
// drying, wicking), the blow-up guard, the multistep history, and the check for sleep.  Everything
// that evolves lives in arrays the caller owns (the state, the BDF2 history, the sleep anchor, the
// clock and self-collision's reference and margin), so a snapshot of those arrays is a snapshot of
// the run and restoring it repeats the run bit for bit.
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Safety factor on the explicit schemes' linear-stability limit, and on the proposed next step.
inline constexpr double STABILITY_SAFETY = 0.9;
inline constexpr double STEP_SAFETY = 0.9;
//: Wicking's explicit sub-steps are at most this fraction of their stability limit
//: (Physics::wick_step_limit): forward Euler then errs in time by at most a tenth of what the finite
//: volumes err in space (ratio 6 D dt / dx^2 = 3 dt / limit), and both errors fall as dx^2.
inline constexpr double WICK_SUBSTEP_FRACTION = 1.0 / 30.0;
//: An output interval up to this fraction of a step longer than a whole number of planned steps is
//: divided into that number of (slightly longer) steps.
inline constexpr double STEP_COUNT_SLACK = 1e-6;
//: Number of outputs: centroid x, y, z (m), depth (m), wet mass, water mass (kg).
inline constexpr Index OUTPUT_COUNT = 6;

//: Largest step (s) for which the explicit scheme is linearly stable with particles up to speed (m/s).
double stable_step(const Control& control, double speed);

//: Step until clock[TIME] reaches target (s) or the cloth falls asleep (time then jumps to target).
//: Returns DONE; BLOWN_UP with the last good state kept (clock[FAILED_STEP] the step); or PAUSED after
//: max_steps steps short of the target (call again to go on).
Status advance(Core& core, double target, Index max_steps);

//: The outputs into row (OUTPUT_COUNT): centroid weighted by wet mass, depth = water_level - centroid z,
//: wet mass, absorbed water.
void record_outputs(Index n, const double* dry_mass, double water_level, const double* pos, const double* water,
                    double* row);

struct SamplingResult {
    Status status;
    Index next;  // the next sample to record
};

//: Advance to times[k] (s, ascending) for k = first, first + 1, ... < count and record the outputs there
//: in outputs[k * OUTPUT_COUNT ...].  PAUSED after about max_steps steps (call again from `next`).
SamplingResult advance_sampling(Core& core, const double* times, Index count, double* outputs, Index first,
                                Index max_steps);

}  // namespace wc
