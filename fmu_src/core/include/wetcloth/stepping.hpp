// The step loop: one call advances the cloth from one output time to the next (port of
// bf41571:fmu_src/wetcloth/kernels/stepping.py and sampling.py).
//
// Each accepted step: the integrator's step with step-size control (particles at rest on the floor
// held there during it), the floor, self-collision, the water's exchanges over the step (uptake,
// drying, wicking), the blow-up guard, the multistep history, and the check for sleep.  Everything
// that evolves lives in arrays the caller owns (the state, the BDF2 history, the sleep anchor, the
// clock and self-collision's reference and margin), so a snapshot of those arrays is a snapshot of
// the run and restoring it repeats the run bit for bit.
#pragma once
#include <string>

#include "wetcloth/core.hpp"

namespace wc {

//: Safety factor on the explicit schemes' linear-stability limit, and on the proposed next step.
inline constexpr double STABILITY_SAFETY = 0.9;
inline constexpr double STEP_SAFETY = 0.9;
//: A step rejected again for its error is cut by the order its error showed between the two tries, at least
//: this one.
inline constexpr double LEAST_OBSERVED_ORDER = 0.5;
//: Wicking's explicit sub-steps are at most this fraction of their stability limit
//: (Physics::wick_step_limit): forward Euler then errs in time by at most a tenth of what the finite
//: volumes err in space (ratio 6 D dt / dx^2 = 3 dt / limit), and both errors fall as dx^2.
inline constexpr double WICK_SUBSTEP_FRACTION = 1.0 / 30.0;
//: An output interval up to this fraction of a step longer than a whole number of planned steps is
//: divided into that number of (slightly longer) steps.
inline constexpr double STEP_COUNT_SLACK = 1e-6;
//: Number of outputs: centroid x, y, z (m), depth (m), wet mass, water mass (kg).
inline constexpr Index OUTPUT_COUNT = 6;
//: A step the controller rejects more often than this (smaller steps, or a solve that did not converge)
//: is a blow-up: from max_step to SMALLEST_STEP takes about 15 rejections; the floor's releases do not count.
inline constexpr int MAX_REJECTIONS = 100;

//: Fixed steps whose self-collision needs rigid impact zones are halved down to this fraction of max_step.
inline constexpr double SUBSTEP_LEAST = 0.25;
//: Fixed steps that gain energy are halved down to this fraction of max_step: self-collision's pushes on a sheet
//: folding onto itself still gained up to 0.088 J in quarter-frame steps (bench/self_contact_energy.py).
inline constexpr double GAIN_SUBSTEP_LEAST = 1.0 / 16.0;
//: A step gains energy where its end's lies above its start's by more than this fraction of the sums of their
//: terms' magnitudes (J): less is the noise of solves stopped within their tolerance and of the sums.  A towel
//: floating at rest on water rising under it "gained" 2e-19 to 6e-16 J in a step, up to 5e-13 of that scale,
//: and 254 of its steps were taken again; 1e-10 of a cloth's few joules is the benchmarks' 1e-9 J.
inline constexpr double ENERGY_NOISE = 1e-10;
//: Wall-clock seconds after which advance returns PAUSED (checked between steps), so that its caller
//: sees signals (Ctrl-C) in time.  Where a call returns never changes what is computed.
inline constexpr double PAUSE_AFTER = 0.1;

//: A cloth asleep while it absorbs (sunk: docs/model.md section 7) wakes once a particle has grown this
//: fraction heavier than at its last step, to find the rest of its new weight.
inline constexpr double SLEEP_WEIGHT_GROWTH = 0.02;

//: Bounds of a state the step loop goes on from (state_problem): simulated time (s), any coordinate (m),
//: and the water a particle holds per kg of its dry mass (kg/kg: absorption_capacity's largest value;
//: the capacity is an input, so a cloth may hold more than the current one allows).
inline constexpr double MAX_TIME = 1e9;
inline constexpr double MAX_COORDINATE = 1e6;
inline constexpr double MAX_WATER_RATIO = 100.0;

//: The arrays and numbers a snapshot restores into a Core, for state_problem (each (3, n) or (n) as in
//: Buffers; `clock` CLOCK_SIZE; `others` further values that need only be finite, such as the
//: preconditioner's).
struct StateView {
    const double* pos = nullptr;
    const double* vel = nullptr;
    const double* water = nullptr;
    const double* prev_pos = nullptr;
    const double* prev_vel = nullptr;
    const double* prev_water = nullptr;
    const double* acceleration = nullptr;
    const double* anchor = nullptr;
    const double* contact_reference = nullptr;
    double contact_margin = 0.0;
    const double* clock = nullptr;
    const double* others = nullptr;
    Index other_count = 0;
};

//: Empty if the state could be the cloth's (every value finite; time 0 to MAX_TIME s; positions within
//: MAX_COORDINATE m, none more than a thickness below the floor; speeds below blow_up_speed, pinned
//: particles still; water 0 to MAX_WATER_RATIO times the dry mass; a positive next step; the counters
//: whole numbers >= 0; asleep only at rest), else what is wrong, naming the value (as
//: Simulation.snapshot() names it).  The cloth's `free` flags must be the model's (between steps).
std::string state_problem(const Cloth& cloth, const Physics& phys, const Control& control, const StateView& state);

//: Largest step (s) for which the explicit scheme is linearly stable with particles up to speed (m/s).
double stable_step(const Control& control, double speed);

//: Step until clock[TIME] reaches target (s) or the cloth falls asleep (time then jumps to target).
//: Returns DONE; BLOWN_UP with the last good state kept (clock[FAILED_STEP] the step that failed: its
//: state not finite or faster than blow_up_speed, or rejected more than MAX_REJECTIONS times, or too
//: short to advance the time); or PAUSED short of the target after max_steps steps or about
//: pause_after s of wall-clock time (call again to go on: the results are the same bits).
Status advance(Core& core, double target, Index max_steps, double pause_after = PAUSE_AFTER);

//: The outputs into row (OUTPUT_COUNT): centroid weighted by wet mass, depth = water_level - centroid z,
//: wet mass, absorbed water.
void record_outputs(Index n, const double* dry_mass, double water_level, const double* pos, const double* water,
                    double* row);

struct SamplingResult {
    Status status;
    Index next;  // the next sample to record
};

//: Advance to times[k] (s, ascending) for k = first, first + 1, ... < count and record the outputs there
//: in outputs[k * OUTPUT_COUNT ...], and in errors[k] the largest local error (m) any step after times[k - 1]
//: (or the start) up to times[k] estimated for itself (errors zeroed by the caller before the first call).
//: PAUSED after about max_steps steps or pause_after s of wall-clock time (call again from `next`).
SamplingResult advance_sampling(Core& core, const double* times, Index count, double* outputs, double* errors,
                                Index first, Index max_steps, double pause_after = PAUSE_AFTER);

}  // namespace wc
