"""Implicit steps: backward Euler (one linearised Newton step) and BDF2 (Newton iterations).

Both solve systems with the matrix ``A = M - h' dF/dv - h'^2 dF/dx`` (``h'`` the step times the
scheme's coefficient), which ``assembly.forces_and_blocks`` leaves as per-particle and per-spring
blocks; compressed springs contribute no negative stiffness, so A is symmetric positive definite.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from wetcloth.kernels import kernel
from wetcloth.kernels import plane as plane_preconditioner
from wetcloth.kernels.assembly import forces_and_blocks
from wetcloth.kernels.integration import (_dot, _system_matvec, conjugate_gradient_step, copy, invert_blocks,
                                          next_search_direction, solve_pcg)

#: Scratch of the implicit steps, each (3, n) unless noted: ``mass`` (n) kg; ``rhs``, ``dv``,
#: ``r``, ``z``, ``p``, ``ap`` of the linear solves; ``hat_pos``, ``hat_vel`` the BDF2 history
#: terms; ``predicted`` the extrapolated positions; ``diagonal`` (6, n) the system's 3x3 diagonal
#: blocks and ``inverse`` (6, n) their inverses;
#: ``step_acceleration`` (3, n) m/s^2 the acceleration the last BDF2 step implies at its end;
#: ``counters`` (int64: Newton iterations, CG iterations, factorisations, unconverged solves).
Solver = namedtuple("Solver", "mass rhs dv r z p ap hat_pos hat_vel predicted step_acceleration diagonal inverse counters")
NEWTON_ITERATIONS, CG_ITERATIONS, FACTORISATIONS, UNCONVERGED = range(4)

#: Backward Euler's conjugate gradients stop at this residual relative to the right-hand side
#: (on the towel this moves the centroid by 0.02 mm against a 1e-8 solve).
EULER_CG_TOLERANCE = 1e-4
EULER_CG_ITERATIONS = 500
#: BDF2: at most this many Newton iterations, each a conjugate-gradient solve until the error left
#: in the correction is estimated below CG_TOLERANCE of the correction, or below CG_FLOOR of the
#: Newton tolerance (at most NEWTON_CG_ITERATIONS iterations).  The floor keeps tiny corrections from
#: being solved to round-off; it must stay small, since an error left in every step's velocity is
#: not random and adds up over the run.
NEWTON_ITERATIONS_MAX = 8
#: Newton stops when the velocity correction is below NEWTON_RELATIVE of the fastest particle's speed
#: and velocity change (or below the position tolerance over NEWTON_VELOCITY_TIME s) and moves
#: positions by less than the position tolerance.
NEWTON_RELATIVE = 1e-3
NEWTON_VELOCITY_TIME = 1.0
#: After its first iteration Newton has no convergence rate of its own yet.  It borrows the rate
#: last observed (in an earlier step), scaled up by how much larger its correction is than the one
#: that rate followed (Newton's rate grows in proportion to the correction: Deuflhard's
#: affine-invariant model; an impact's first corrections are tens of times a floating step's), and
#: stops if the corrections still to come at that rate are within FIRST_ITERATION_TRUST of the
#: tolerance (a borrowed rate is a guess, hence the margin).  Measured (docs/benchmarks.md): on a
#: floating 9 x 9 cloth's 2 ms steps, 40 % fewer Newton and CG iterations; at 1.0, or without the
#: scaling, the sinking reference scene's wet mass erred by 1.2e-3 or 9.5e-4 (6.3e-4 before).
#: Only with the banded preconditioner: with the multigrid cycle's inexact solves the floating
#: 64 x 64 towel's accepted first iterates made its later steps fail their error test (3-6 s: 450
#: steps, 237 refused, against 90 and none without borrowing).
FIRST_ITERATION_TRUST = 0.3
#: Newton converges only linearly (its Jacobian is approximate: drag lumped, tension-only springs
#: clamped; each iteration cut the correction 2.5-3x on a sinking 9 x 9 cloth at 0.05 s steps), so
#: solving each correction much more closely than that rate is wasted.  Counts over sink_map's 16 runs and
#: the towel's 90 s at 30 Hz (Newton / CG iterations / factorisations), at the default tolerance:
#: 1e-2: 45 025 / 138 442 / 15 039 and 4572 / 14 405 / 515; 1e-1: 48 022 / 94 324 / 11 625 and
#: 5245 / 11 521 / 119 (10-13 % less time on sink_map, same accuracy); at 2e-1 the landing scene's
#: centroid erred 0.72 mm instead of 0.19-0.24 (bench/work_precision.py).  With fixed steps
#: (the converged references, or a user's choice) no error estimate watches the steps: their
#: solves go to FIXED_STEP_CG_TOLERANCE (at 1e-1 the 4 s sinking reference at 0.25 ms steps and
#: the same at half the step differed by 0.17 mm in centroid, at 1e-2 by 0.03 mm).
CG_TOLERANCE = 1e-1
FIXED_STEP_CG_TOLERANCE = 1e-2
CG_FLOOR = 1e-2
NEWTON_CG_ITERATIONS = 300


def make_solver(n: int) -> Solver:
    vectors = {name: np.zeros((3, n)) for name in ("rhs", "dv", "r", "z", "p", "ap", "hat_pos", "hat_vel",
                                                   "predicted", "step_acceleration")}
    return Solver(mass=np.zeros(n), diagonal=np.zeros((6, n)), inverse=np.zeros((6, n)), counters=np.zeros(4, dtype=np.int64), **vectors)


@kernel
def implicit_euler_step(cloth, phys, work, solver, pos, vel, water, h, out_pos, out_vel):
    """Backward Euler, one Newton step, solved by block-Jacobi conjugate gradients (Baraff and
    Witkin 1998): ``(M - h C - h^2 K) dv = h F + h^2 K v``, then ``x+ = x + h (v + dv)``.
    Returns ``max |dv|`` (m/s)."""
    n = pos.shape[1]
    mass = solver.mass
    for i in range(n):
        mass[i] = cloth.dry_mass[i] + water[i]
    forces_and_blocks(cloth, phys, work, pos, vel, water, h)
    rhs, dv, inverse, full = solver.rhs, solver.dv, solver.inverse, solver.diagonal
    for i in range(n):
        for c in range(3):
            rhs[c, i] = h * work.force[c, i] + work.rhs[c, i]
            dv[c, i] = rhs[c, i] / mass[i] * cloth.free[i]  # first guess: the explicit step
        for slot in range(6):
            full[slot, i] = work.diagonal_blocks[slot, i] + work.blocks[slot, i]
        for c in range(3):
            full[c, i] += mass[i]
    invert_blocks(full, inverse)
    iterations, _ = solve_pcg(cloth.offsets, work.direction, work.along, work.across, mass, work.blocks, inverse,
                              cloth.free, rhs, dv, solver.r, solver.z, solver.p, solver.ap, work.buf,
                              EULER_CG_TOLERANCE, EULER_CG_ITERATIONS)
    solver.counters[CG_ITERATIONS] += iterations
    largest = 0.0
    for c in range(3):
        for i in range(n):
            out_vel[c, i] = vel[c, i] + dv[c, i]
            out_pos[c, i] = pos[c, i] + h * out_vel[c, i]
            largest = max(largest, abs(dv[c, i]))
    return largest


@kernel
def _plane_pcg(cloth, work, solver, plane, b, x, rtol, floor, max_iterations):
    """Solve A x = b (x = 0 first) by conjugate gradients preconditioned by the plane preconditioner,
    until the preconditioned residual ``P^-1 r``, which estimates the error left in x, is at most
    ``rtol`` times its first value or ``floor`` in every component.  Returns (iterations, whether
    it got there)."""
    mass, r, z, p, ap = solver.mass, solver.r, solver.z, solver.p, solver.ap
    x[...] = 0.0
    copy(b, r)
    plane_preconditioner.apply(plane, cloth.free, r, z)
    copy(z, p)
    rz = _dot(r, z)
    accuracy = max(rtol * _largest(z), floor)
    iterations = 0
    while _largest(z) > accuracy and iterations < max_iterations:
        _system_matvec(cloth.offsets, work.direction, work.along, work.across, mass, work.blocks, cloth.free, p, ap,
                       work.buf)
        p_ap = _dot(p, ap)
        if not p_ap > 0.0:
            break
        conjugate_gradient_step(rz / p_ap, p, ap, x, r)
        iterations += 1
        plane_preconditioner.apply(plane, cloth.free, r, z)
        rz_new = _dot(r, z)
        next_search_direction(rz_new / rz, z, p)
        rz = rz_new
    return iterations, _largest(z) <= accuracy


@kernel
def _largest(a):
    largest = 0.0
    for c in range(3):
        for i in range(a.shape[1]):
            largest = max(largest, abs(a[c, i]))
    return largest


#: ``_first_guess`` kinds: the line through v_prev and v; the parabola through them with the slope
#: the last step implied at v.
LINE, PARABOLA = 0.0, 1.0


@kernel(inline="always")
def _first_guess(kind, v, v_prev, slope, h, h_prev):
    """Newton's first guess (m/s) of a velocity component h s ahead, extrapolated from v (now, with
    ``slope`` m/s^2) and v_prev (h_prev s ago).  The PARABOLA errs by third order in h where the
    solution is smooth on the step's scale (a floating cloth's bobbing at 2 ms steps: first
    corrections a third of the LINE's), the LINE by second order; on stiff modes at long steps
    (a floating cloth at 1/30 s) the implied slope is noise and the LINE does better."""
    w = h / h_prev
    if kind == PARABOLA:
        return v + h * slope + w * w * (v_prev - v + h_prev * slope)
    return v + w * (v - v_prev)


@kernel
def _better_guess(vel, prev_vel, acceleration, free, h, h_prev, solution):
    """Which ``_first_guess`` kind came closer to this step's ``solution`` (3, n): the next step's."""
    line = 0.0
    parabola = 0.0
    for c in range(3):
        for i in range(vel.shape[1]):
            if free[i] != 0.0:
                v, v_prev, slope, end = vel[c, i], prev_vel[c, i], acceleration[c, i], solution[c, i]
                line = max(line, abs(_first_guess(LINE, v, v_prev, slope, h, h_prev) - end))
                parabola = max(parabola, abs(_first_guess(PARABOLA, v, v_prev, slope, h, h_prev) - end))
    return PARABOLA if parabola < line else LINE


@kernel
def bdf2_step(cloth, phys, work, solver, plane, pos, vel, water, step_water, prev_pos, prev_vel, prev_water,
              acceleration, h, h_prev, newton_tolerance, cg_tolerance, memory, out_pos, out_vel):
    """One step of the variable-step BDF2 (backward Euler when ``h_prev == 0``: no history).

    With ``w = h / h_prev``, ``y+ = y^ + b h f(y+)`` for y = (x, p), where
    ``y^ = ((1 + w)^2 y - w^2 y_prev) / (1 + 2w)`` and ``b = (1 + w) / (1 + 2w)``.  The momentum
    ``p = m v`` is the history's variable, not the velocity: absorbed water arrives at rest, so
    uptake between steps leaves p unchanged (and slows v); a history of velocities would carry
    that slowing forward and count it twice.  Forces and inertia are those of ``step_water``, the
    water (kg) the particles will hold at the end of the step; ``water`` is what they hold now.  Newton
    iterations in the velocity, ``x+ = x^ + b h v+``, each solving
    ``A dv = b h F(x+, v+) - M (v+ - v^)`` (see CG_TOLERANCE), until the correction, or what the
    observed convergence rate leaves to come, is within tolerance: ``newton_tolerance`` (m) in
    position, and see NEWTON_RELATIVE for the velocity.

    ``memory`` (4,) carries over from step to step: the last convergence rate observed and the
    correction (m/s) it was observed after (FIRST_ITERATION_TRUST), which kind of first guess
    to start from (``_first_guess``, with the ``acceleration`` (3, n) m/s^2 the last step implied),
    and the CG iterations of the last linear solve (whether to refactor the preconditioner from
    the Jacobian: ``plane.jacobian_refresh_pays``).
    This step leaves in ``solver.step_acceleration`` the acceleration it implies at its end,
    ``(v+ - v^) / (b h)``, and in ``memory`` the kind of guess that would have come closer to its
    solution.

    Returns (local position error estimate m, converged).  The estimate is the corrector's
    distance from the quadratic extrapolation through x_prev, x, v (Milne's device): BDF2 errs by
    ``-(1+w)^2/(6w(1+2w)) h^3 x'''``, the extrapolation by ``(1+w)/(6w) h^3 x'''``, so the BDF2 error
    is ``(1+w)/(2+3w)`` times their difference.  Without history: ``h |v+ - v| / 2``.
    Pinned particles' positions are not estimated (they do not move).
    """
    n = pos.shape[1]
    mass, hat_pos, hat_vel, predicted, dv, rhs = (solver.mass, solver.hat_pos, solver.hat_vel, solver.predicted,
                                                  solver.dv, solver.rhs)
    free = cloth.free
    for i in range(n):
        mass[i] = cloth.dry_mass[i] + step_water[i]
    history = h_prev > 0.0
    w = h / h_prev if history else 0.0
    beta = (1.0 + w) / (1.0 + 2.0 * w)
    a = (1.0 + w) * (1.0 + w) / (1.0 + 2.0 * w)
    b = w * w / (1.0 + 2.0 * w)
    for c in range(3):
        for i in range(n):
            if history and free[i] != 0.0:  # (a pinned particle stays exactly where it is)
                hat_pos[c, i] = a * pos[c, i] - b * prev_pos[c, i]
                momentum = (cloth.dry_mass[i] + water[i]) * vel[c, i]
                previous_momentum = (cloth.dry_mass[i] + prev_water[i]) * prev_vel[c, i]
                hat_vel[c, i] = (a * momentum - b * previous_momentum) / mass[i]
                predicted[c, i] = pos[c, i] + h * vel[c, i] + w * w * (prev_pos[c, i] - pos[c, i] + h_prev * vel[c, i])
                guess = _first_guess(memory[2], vel[c, i], prev_vel[c, i], acceleration[c, i], h, h_prev)
            else:
                hat_pos[c, i] = pos[c, i]
                hat_vel[c, i] = (cloth.dry_mass[i] + water[i]) * vel[c, i] / mass[i]
                predicted[c, i] = pos[c, i]
                guess = hat_vel[c, i]
            out_vel[c, i] = guess * free[i]
    bh = beta * h
    for c in range(3):
        for i in range(n):
            out_pos[c, i] = hat_pos[c, i] + bh * out_vel[c, i]
    factored = plane_preconditioner.refresh(plane, cloth.offsets, mass, bh * bh)
    solver.counters[FACTORISATIONS] += factored > 0
    plane_preconditioner.follow_cloth(plane, cloth.grid_x, pos)
    converged = False
    previous = 0.0
    for _ in range(NEWTON_ITERATIONS_MAX):
        forces_and_blocks(cloth, phys, work, out_pos, out_vel, step_water, bh)
        plane_preconditioner.set_normal_diagonal(plane, mass, work.diagonal_blocks, work.blocks)
        if plane_preconditioner.jacobian_refresh_pays(plane, memory[3]):
            factored = plane_preconditioner.refresh_from_jacobian(plane, cloth.offsets, mass, work.along)
            if factored < 0:  # back to the rest stiffness
                factored = plane_preconditioner.refresh(plane, cloth.offsets, mass, bh * bh)
            solver.counters[FACTORISATIONS] += factored > 0
        for c in range(3):
            for i in range(n):
                rhs[c, i] = free[i] * (bh * work.force[c, i] - mass[i] * (out_vel[c, i] - hat_vel[c, i]))
        floor = CG_FLOOR * min(newton_tolerance / bh, newton_tolerance / NEWTON_VELOCITY_TIME)
        iterations, solved = _plane_pcg(cloth, work, solver, plane, rhs, dv, cg_tolerance, floor,
                                        NEWTON_CG_ITERATIONS)
        memory[3] = iterations
        solver.counters[NEWTON_ITERATIONS] += 1
        solver.counters[CG_ITERATIONS] += iterations
        solver.counters[UNCONVERGED] += not solved
        largest = 0.0
        increment = 0.0
        for c in range(3):
            for i in range(n):
                out_vel[c, i] += dv[c, i]
                out_pos[c, i] = hat_pos[c, i] + bh * out_vel[c, i]
                largest = max(largest, abs(dv[c, i]))
                increment = max(increment, abs(out_vel[c, i] - vel[c, i]), abs(out_vel[c, i]))
        if not math.isfinite(largest):
            break
        # The velocity's tolerance: an error left in every step's velocity is not random and adds up,
        # so it is held to a fraction of the velocity and of its change over the step, or to what
        # moves a particle by the position tolerance in NEWTON_VELOCITY_TIME.
        velocity_tolerance = max(NEWTON_RELATIVE * increment, newton_tolerance / NEWTON_VELOCITY_TIME)
        tolerance = min(newton_tolerance / bh, velocity_tolerance)
        # Converged when the correction, or the corrections still to come at the observed rate
        # (a geometric series), are within the tolerance.
        if previous > 0.0:
            rate, trust = largest / previous, 1.0
            memory[0], memory[1] = rate, previous
        else:  # first iteration: the rate last observed, scaled to this correction, with a margin
            rate = memory[0] * max(1.0, largest / memory[1]) if memory[1] > 0.0 else 0.0
            trust = FIRST_ITERATION_TRUST if plane_preconditioner.banded(plane) else 0.0
        if largest <= tolerance or (0.0 < rate < 1.0 and rate / (1.0 - rate) * largest <= trust * tolerance):
            converged = True
            break
        previous = largest
    for c in range(3):
        for i in range(n):
            solver.step_acceleration[c, i] = (out_vel[c, i] - hat_vel[c, i]) / bh
    if history:
        memory[2] = _better_guess(vel, prev_vel, acceleration, free, h, h_prev, out_vel)
    else:
        error = 0.0
        for c in range(3):
            for i in range(n):
                error = max(error, abs(out_vel[c, i] - vel[c, i]))
        return 0.5 * h * error, converged
    # The difference, filtered through (approximately) A^-1 M, as Shampine filters the error estimates
    # of stiff solvers: stiff modes (in-plane vibration, a floating cloth's heave), which the scheme
    # damps anyway, would otherwise dominate the estimate and hold the step far below what the
    # smooth motion needs.
    difference = solver.r
    for c in range(3):
        for i in range(n):
            difference[c, i] = free[i] * mass[i] * (out_pos[c, i] - predicted[c, i])
    plane_preconditioner.apply(plane, free, difference, solver.z)
    return (1.0 + w) / (2.0 + 3.0 * w) * _largest(solver.z), converged
