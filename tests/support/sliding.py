"""Coulomb sliding checks shared by the floor and collider tests: a sheet at rest on a surface is given
a speed along it and slides to a stop after the analytic distance, up to the step's known first-order
error."""

from __future__ import annotations

import numpy as np
import pytest

from wetcloth._core import GRAVITY
from wetcloth.simulation import State

#: The fixed step of the sliding runs (s): tolerance 0, max_step STEP.
STEP = 1e-3


def assert_slides_coulomb_distance(sim, direction, normal, friction: float, speed: float = 0.5) -> None:
    """Give every particle of ``sim`` (a sheet lying still on a surface of unit outward ``normal``, run
    in fixed steps of STEP s without air or water) the velocity ``speed`` (m/s) along ``direction`` (a
    unit vector along the surface, downhill if it slopes); it must stop after Coulomb's distance
    ``v0^2 / (2 a)``, ``a = g (friction n_z - d_z)`` the deceleration (n_z, d_z the vertical parts of
    the normal and the direction), and stay stopped (held, velocity exactly 0).

    Kinetic friction is a force of each implicit step (docs/model.md section 6.1), so the sheet decelerates
    at the constant ``a`` within the step's solve.  BDF2 is exact for such a motion (a quadratic in time)
    but for its first step, backward Euler's, which moves ``a h^2 / 2`` short: the distance is Coulomb's.
    Implicit Euler moves each step with the velocity at its end: ``h sum_k (v0 - k a h)`` over the
    ``v0 / (a h)`` steps falls short of Coulomb's distance by ``v0 h / 2``, a relative ``-h a / v0``.
    That prediction is asserted to within ``2 h^2 (g + a)``: the first and the last step (the first
    step's shortfall, the stop within the last), each moving at most ``h`` times one step's velocity
    change.  (Before friction went into the solve it acted as an impulse after each step, and the
    distance exceeded Coulomb's by ``h (mu g_n + g_t) / v0`` under implicit Euler, ``(4/3) h mu g_n /
    v0`` under BDF2.)"""
    direction, normal = np.asarray(direction, float), np.asarray(normal, float)
    state = sim.state
    assert np.abs(state.vel).max() == 0.0  # lying still
    vel = np.zeros_like(state.vel) + speed * direction[:, None]
    sim.state = State(state.time, state.pos.copy(), vel, state.water.copy())
    start = sim.state.pos.copy()
    pressing, along = GRAVITY * normal[2], -GRAVITY * direction[2]
    deceleration = friction * pressing - along
    stop_time = speed / deceleration
    sim.advance(stop_time + 0.2)
    distance = direction @ (sim.state.pos - start).mean(axis=1)
    coulomb = speed**2 / (2.0 * deceleration)
    excess = 0.0 if sim.scene.integrator == "bdf2" else -STEP * deceleration / speed
    assert distance == pytest.approx(coulomb * (1.0 + excess), abs=2 * STEP**2 * (GRAVITY + deceleration))
    assert np.abs(sim.state.vel).max() == 0.0
