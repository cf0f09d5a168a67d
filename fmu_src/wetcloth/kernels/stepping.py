"""The step loop: one compiled call advances the cloth from one output time to the next.

Each accepted step: the integrator's step (with step-size control; particles at rest on the floor are
held there during it), the floor, self-collision, the
water's exchanges over the step (uptake, drying, wicking), the blow-up guard, the multistep history,
and the check for sleep.  Everything that evolves lives in arrays the caller owns (the state, the
BDF2 history, the sleep anchor, ``clock`` and the self-collision stage's ``contact``), so a snapshot
of those arrays is a snapshot of the run and restoring it repeats the run bit for bit.
"""

from __future__ import annotations

import math
from collections import namedtuple

from numba.extending import overload

from wetcloth.kernels import OPTIONS, counted_kernel, kernel
from wetcloth.kernels.absorption import dry, keep_momentum, uptake, uptake_timing_error, wick
from wetcloth.kernels.assembly import forces
from wetcloth.kernels.floor import agree_history, floor_contact, hold_resting, release_all, release_slipping
from wetcloth.kernels.implicit import bdf2_step, implicit_euler_step
from wetcloth.kernels.integration import copy, euler_update, largest_deviation, speed_and_finiteness, total
from wetcloth.kernels.self_contact import resolve as self_collision

#: Integrator codes (``Control.integrator``).
EXPLICIT_EULER, SYMPLECTIC_EULER, IMPLICIT_EULER, BDF2 = range(4)
#: ``Control.scheme``: an empty marker whose type (not value) selects the compiled step (``take_step``).
ExplicitSteps = namedtuple("ExplicitSteps", "")
ImplicitEulerSteps = namedtuple("ImplicitEulerSteps", "")
Bdf2Steps = namedtuple("Bdf2Steps", "")
SCHEMES = {EXPLICIT_EULER: ExplicitSteps(), SYMPLECTIC_EULER: ExplicitSteps(), IMPLICIT_EULER: ImplicitEulerSteps(),
           BDF2: Bdf2Steps()}

#: Slots of ``clock`` (float64): simulated time (s); the controller's next step (s); the last
#: accepted step (s; 0 when there is no history for BDF2 to use); the fastest particle's speed
#: (m/s); time spent still (s), time since stillness was last checked (s), whether water moved
#: since then, whether asleep; accepted and rejected steps; the step that blew up (s); BDF2's last
#: Newton convergence rate (-, 0 before one was observed) and the correction it followed (m/s), the
#: kind of its first guess (``implicit.LINE`` or ``PARABOLA``) and its last solve's CG iterations.
(TIME, NEXT_STEP, LAST_STEP, SPEED, CALM_TIME, UNCHECKED_TIME, EXCHANGING, SLEEPING, STEPS, REJECTED, FAILED_STEP,
 NEWTON_RATE, RATE_CORRECTION, FIRST_GUESS, LAST_SOLVE) = range(15)
CLOCK_SIZE = 15

#: What ``advance`` returns.
DONE, BLOWN_UP, PAUSED = 0, 1, 2

#: Integrator and controller settings: ``scheme`` (see SCHEMES), ``tolerance`` (-), ``allowed`` local position error per step
#: (m, 0 = fixed steps of ``max_step`` s); ``newton_tolerance`` (m); ``cg_tolerance`` (-, BDF2's linear
#: solves, relative to the correction); the explicit schemes' stability data:
#: ``omega_squared`` (1/s2, Gershgorin bound of the springs), ``buoyancy_omega_squared`` (1/s2),
#: ``damping_rate`` (1/s), ``spring_limit`` (s, explicit Euler), drag rate ``drag_rate_offset +
#: drag_rate_slope * speed`` (1/s); the sleep rule: ``sleep_distance`` (m) for ``sleep_after`` s.
Control = namedtuple("Control", "scheme integrator tolerance allowed max_step newton_tolerance cg_tolerance "
                                "omega_squared buoyancy_omega_squared damping_rate spring_limit drag_rate_offset "
                                "drag_rate_slope smallest_step growth shrink blow_up_speed sleep_distance sleep_after")
#: State buffers: current and trial (pos, vel (3, n), water (n)), BDF2 history (the state before the
#: last step, and the acceleration (3, n) m/s^2 the last step implied at its end), sleep anchor, and
#: ``held`` (n): 1 for the particles the floor holds during the current step (scratch, set from the
#: state at the start of each step).
Buffers = namedtuple("Buffers", "pos vel water trial_pos trial_vel trial_water prev_pos prev_vel prev_water acceleration "
                                "anchor held")

#: Safety factor on the explicit schemes' linear-stability limit, and on the proposed next step.
STABILITY_SAFETY = 0.9
STEP_SAFETY = 0.9
#: Wicking's explicit sub-steps are at most this fraction of their stability limit (``wick_step_limit``,
#: about dx^2 / (2 D) on a strip): forward Euler then errs in time by at most a tenth of what the
#: finite volumes err in space.  On a mode of wavenumber k, forward Euler's sub-steps of dt lose
#: D^2 k^4 dt / 2 of its decay rate, the three-point difference D dx^2 k^4 / 12; the ratio is
#: 6 D dt / dx^2 = 3 dt / limit.  Sub-steps as long as the mechanical step (up to ``max_step``)
#: would let the time error dominate wherever the cloth's steps are long (a cloth resting on the
#: floor); in proportion to the limit, both errors fall as dx^2.
WICK_SUBSTEP_FRACTION = 1.0 / 30.0
#: An output interval up to this fraction of a step longer than a whole number of planned steps is
#: divided into that number of (slightly longer) steps.
STEP_COUNT_SLACK = 1e-6


@kernel
def stable_step(control, speed):
    """Largest step (s) for which the scheme is linearly stable with particles up to ``speed`` (m/s)."""
    gamma = control.damping_rate + control.drag_rate_offset + control.drag_rate_slope * speed
    if control.integrator == EXPLICIT_EULER:
        limit = control.spring_limit
        if gamma > 0.0:
            limit = min(limit, 2.0 / gamma)
        return STABILITY_SAFETY * limit
    if control.integrator == SYMPLECTIC_EULER:
        # For x'' = -w^2 x - g x' the scheme is stable iff h < 4 / (g + sqrt(g^2 + 4 w^2)).
        omega2 = control.omega_squared + control.buoyancy_omega_squared
        return STABILITY_SAFETY * 4.0 / (gamma + math.sqrt(gamma * gamma + 4.0 * omega2))
    return math.inf


@kernel
def _surface(phys):
    """Height (m) below which a particle's centre touches water (its submerged fraction is positive)."""
    return phys.water_level + (0.5 * phys.thickness if phys.smooth else 0.0)


@kernel
def _absorbing(phys):
    return phys.absorption_capacity > 0.0 and phys.absorption_rate > 0.0


@kernel
def _euler_step(cloth, phys, control, work, solver, plane, buf, clock, h):
    """Explicit or symplectic Euler (``control.integrator``); see ``take_step``."""
    for i in range(buf.water.shape[0]):
        solver.mass[i] = cloth.dry_mass[i] + buf.water[i]
    forces(cloth, phys, work, buf.pos, buf.vel, buf.water)
    largest = euler_update(buf.pos, buf.vel, work.force, cloth.dry_mass, buf.water, cloth.free, h,
                           control.integrator == SYMPLECTIC_EULER, buf.trial_pos, buf.trial_vel)
    return 0.5 * h * largest, 1, True  # |h (v+ - v)| / 2: first- against second-order position update


@kernel
def _implicit_euler_step(cloth, phys, control, work, solver, plane, buf, clock, h):
    """Backward Euler; see ``take_step``."""
    largest = implicit_euler_step(cloth, phys, work, solver, buf.pos, buf.vel, buf.water, h, buf.trial_pos,
                                  buf.trial_vel)
    return 0.5 * h * largest, 1, True


@kernel
def _bdf2_step(cloth, phys, control, work, solver, plane, buf, clock, h):
    """BDF2; see ``take_step``."""
    h_prev = clock[LAST_STEP]
    # BDF2 takes the forces and inertia at the end of the step, so it needs the water the cloth will
    # hold then: the uptake along the extrapolated path (the exact uptake follows the step).
    step_water = buf.trial_water
    copy(buf.water, step_water)
    if _absorbing(phys):
        predicted, predicted_speed = solver.predicted[0], solver.predicted[1]  # scratch: z and v_z
        w = h / h_prev if h_prev > 0.0 else 0.0
        for i in range(step_water.shape[0]):
            predicted[i] = buf.pos[2, i] + h * buf.vel[2, i] + w * w * (
                buf.prev_pos[2, i] - buf.pos[2, i] + h_prev * buf.vel[2, i])
            predicted_speed[i] = buf.vel[2, i] + w * (buf.vel[2, i] - buf.prev_vel[2, i])
        uptake(buf.pos[2], predicted, buf.vel[2], predicted_speed, _surface(phys), cloth.dry_mass,
               phys.absorption_capacity, phys.absorption_rate, h, buf.water, step_water)
    error, converged = bdf2_step(cloth, phys, work, solver, plane, buf.pos, buf.vel, buf.water, step_water,
                                 buf.prev_pos, buf.prev_vel, buf.prev_water, buf.acceleration, h, h_prev,
                                 control.newton_tolerance, control.cg_tolerance, clock[NEWTON_RATE:LAST_SOLVE + 1],
                                 buf.trial_pos, buf.trial_vel)
    return error, 2 if h_prev > 0.0 else 1, converged


#: The step of each family of schemes, by the type of ``Control.scheme``.
_STEPS = {ExplicitSteps: _euler_step, ImplicitEulerSteps: _implicit_euler_step, Bdf2Steps: _bdf2_step}


def take_step(scheme, cloth, phys, control, work, solver, plane, buf, clock, h):
    """The integrator's step of ``h`` s from the current state into the trial buffers; the particle
    masses it used are left in ``solver.mass``.  Returns (local position error estimate m, order of
    that estimate, converged).  Compiled callers only: the step is chosen by the type of ``scheme``
    when the loop is compiled, so only the schemes a run uses are ever compiled."""
    raise NotImplementedError("take_step is called from compiled code only")


@overload(take_step, jit_options=OPTIONS)
def _take_step_of(scheme, cloth, phys, control, work, solver, plane, buf, clock, h):
    step = _STEPS[scheme.instance_class]
    return lambda scheme, cloth, phys, control, work, solver, plane, buf, clock, h: step(
        cloth, phys, control, work, solver, plane, buf, clock, h)


@kernel
def _exchange_water(cloth, phys, work, buf, mass_used, h):
    """Uptake where the cloth touches water, drying in air, wicking between neighbours; each skipped
    when its rate is zero.  ``mass_used`` (kg) is what the step took as each particle's mass: the
    momentum it gave is kept as the uptake changes that mass.  Returns whether any particle's water
    changed."""
    copy(buf.water, buf.trial_water)
    absorbing = _absorbing(phys)
    if not (absorbing or phys.drying_rate > 0.0 or phys.wicking_rate > 0.0):
        return False
    surface = _surface(phys)
    exchanged = 0
    z_start, z_end, vz_start, vz_end = buf.pos[2], buf.trial_pos[2], buf.vel[2], buf.trial_vel[2]
    if absorbing:
        exchanged += uptake(z_start, z_end, vz_start, vz_end, surface, cloth.dry_mass, phys.absorption_capacity, phys.absorption_rate,
                            h, buf.water, buf.trial_water)
        keep_momentum(mass_used, cloth.dry_mass, buf.trial_water, buf.trial_vel)
    if phys.drying_rate > 0.0:
        exchanged += dry(z_start, z_end, vz_start, vz_end, surface, phys.drying_rate, h, buf.trial_water)
    if phys.wicking_rate > 0.0 and phys.absorption_capacity > 0.0:
        substeps = max(1, math.ceil(h / (WICK_SUBSTEP_FRACTION * phys.wick_step_limit)))
        moved = wick(cloth.wick_offsets, cloth.wick_conductance, cloth.capacity, cloth.dry_mass, substeps, h,
                     buf.trial_water, buf.trial_vel, work.wick_buffer)
        for c in range(3):
            for i in range(cloth.free.shape[0]):
                buf.trial_vel[c, i] *= cloth.free[i]
        exchanged += moved > 0.0
    return exchanged > 0


@kernel
def _maybe_sleep(control, phys, buf, clock, h, exchanging):
    """Fall asleep after ``sleep_after`` s still, with no water exchange (velocities then zero).
    Stillness is checked every ``sleep_after / 20`` s of simulated time, not at every step."""
    if not phys.skip_idle:
        return
    if exchanging:
        clock[EXCHANGING] = 1.0
    clock[UNCHECKED_TIME] += h
    if clock[UNCHECKED_TIME] < control.sleep_after / 20:
        return
    if clock[EXCHANGING] != 0.0 or largest_deviation(buf.pos, buf.anchor) > control.sleep_distance:
        copy(buf.pos, buf.anchor)
        clock[CALM_TIME] = 0.0
    else:
        clock[CALM_TIME] += clock[UNCHECKED_TIME]
    clock[UNCHECKED_TIME] = 0.0
    clock[EXCHANGING] = 0.0
    if clock[CALM_TIME] >= control.sleep_after:
        clock[SLEEPING] = 1.0
        buf.vel[...] = 0.0
        clock[SPEED] = 0.0
        clock[LAST_STEP] = 0.0  # the velocities changed: BDF2 starts afresh


@counted_kernel  # passes self-collision's typed lists on
def _step(cloth, phys, control, work, solver, plane, contact, buf, clock, remaining):
    """Take one accepted step of at most ``remaining`` s.  Returns DONE or BLOWN_UP."""
    adaptive = control.allowed > 0.0
    # Particles at rest on the floor take no part in the step (a constraint of its solve) unless its
    # forces would move them; the model's ``free`` flags are theirs again before the step ends.
    held = hold_resting(phys.floor_z, buf.pos, buf.vel, cloth.free, buf.held)
    while True:
        if adaptive:
            planned = min(clock[NEXT_STEP], control.max_step, stable_step(control, clock[SPEED]))
        else:  # fixed steps of max_step, as the user asked (only shorter where BDF2's Newton fails)
            planned = min(clock[NEXT_STEP], control.max_step)
        if control.integrator == BDF2 and clock[LAST_STEP] > 0.0:
            planned = min(planned, control.growth * clock[LAST_STEP])  # BDF2 is zero-stable for ratios < 2.4
        # Equal steps to the end of the interval rather than a last sliver (and no extra step for an
        # interval a rounding error longer than a whole number of planned steps).
        h = remaining / max(1.0, math.ceil(remaining / planned - STEP_COUNT_SLACK))
        error, order, converged = take_step(control.scheme, cloth, phys, control, work, solver, plane, buf, clock, h)
        if held > 0 and converged:
            released = release_slipping(phys.floor_friction, work.force, cloth.free, buf.held)
            if released > 0:  # redo the step with them free
                held -= released
                clock[REJECTED] += 1
                continue
        if not converged and h > control.smallest_step:
            clock[NEXT_STEP] = max(control.smallest_step, 0.25 * h)
            clock[REJECTED] += 1
            continue
        if not adaptive:  # the blow-up guard watches
            clock[NEXT_STEP] = control.max_step
            break
        # Error relative to what is allowed: the position error, and the uptake's (a fraction of the
        # wet mass, held to the tolerance), whichever is larger, with its order.
        ratio = error / control.allowed
        if _absorbing(phys):
            water_error = uptake_timing_error(buf.pos[2], buf.trial_pos[2], buf.vel[2], buf.trial_vel[2],
                                              _surface(phys), cloth.dry_mass, phys.absorption_capacity,
                                              phys.absorption_rate, h, buf.water)
            water_ratio = water_error / (control.tolerance * (total(cloth.dry_mass) + total(buf.water)))
            if water_ratio > ratio:
                ratio, order = water_ratio, 1
        finite = math.isfinite(ratio)
        factor = STEP_SAFETY * ratio ** (-1.0 / (order + 1)) if ratio > 0.0 else control.growth
        if ratio <= 1.0 or h <= control.smallest_step or not finite:
            proposed = h * min(control.growth, max(control.shrink, factor)) if finite else h
            # A step cut short by the end of the interval says nothing against the planned one.
            clock[NEXT_STEP] = max(proposed, planned) if h < planned and ratio <= 1.0 else proposed
            break
        clock[NEXT_STEP] = max(control.smallest_step, h * max(control.shrink, factor))
        clock[REJECTED] += 1
    if held > 0:
        release_all(cloth.free, buf.held)
    on_floor = floor_contact(phys.floor_z, phys.floor_friction, buf.trial_pos, buf.trial_vel) > 0 or held > 0
    kinked = self_collision(contact, phys.thickness, phys.floor_z, control.blow_up_speed, solver.mass, cloth.free,
                            buf.pos, buf.trial_pos, buf.trial_vel, h)
    exchanging = _exchange_water(cloth, phys, work, buf, solver.mass, h)
    speed, finite = speed_and_finiteness(buf.trial_pos, buf.trial_vel, buf.trial_water)
    if not (finite and speed < control.blow_up_speed):
        clock[FAILED_STEP] = h
        return BLOWN_UP
    clock[SPEED] = speed
    copy(buf.pos, buf.prev_pos)
    copy(buf.vel, buf.prev_vel)
    copy(buf.water, buf.prev_water)
    copy(buf.trial_pos, buf.pos)
    copy(buf.trial_vel, buf.vel)
    copy(buf.trial_water, buf.water)
    if control.integrator == BDF2:
        copy(solver.step_acceleration, buf.acceleration)
    if on_floor:
        agree_history(phys.floor_z, buf.pos, buf.vel, buf.prev_pos, buf.prev_vel, h)
    clock[LAST_STEP] = 0.0 if kinked else h  # self-collision's push: BDF2 starts afresh
    clock[TIME] += h
    clock[STEPS] += 1
    _maybe_sleep(control, phys, buf, clock, h, exchanging)
    return DONE


@counted_kernel  # takes self-collision's typed lists
def advance(cloth, phys, control, work, solver, plane, contact, buf, clock, target, max_steps):
    """Step until ``clock[TIME]`` reaches ``target`` (s) or the cloth falls asleep (time then jumps to
    ``target``).  Returns DONE; BLOWN_UP with the last good state kept; or PAUSED after
    ``max_steps`` steps short of the target (call again to go on)."""
    taken = 0
    while target - clock[TIME] > 1e-12 * max(1.0, abs(target)) and clock[SLEEPING] == 0.0:
        if taken >= max_steps:
            return PAUSED
        if _step(cloth, phys, control, work, solver, plane, contact, buf, clock, target - clock[TIME]) != DONE:
            return BLOWN_UP
        taken += 1
    clock[TIME] = max(clock[TIME], target)
    return DONE
