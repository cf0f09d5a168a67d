"""Rollback checks shared by the tests: a restored run must repeat the original bit for bit."""

from __future__ import annotations

import numpy as np


def assert_restored_run_repeats(sim, snapshot: dict, seconds: float) -> None:
    """Advance ``sim`` (taken at ``snapshot``) by ``seconds``, restore ``snapshot``, advance again:
    positions, velocities and water must be the same to the last bit."""
    sim.advance(seconds)
    first = sim.state.copy()
    sim.restore(snapshot)
    sim.advance(seconds)
    for name in ("pos", "vel", "water"):
        np.testing.assert_array_equal(getattr(sim.state, name), getattr(first, name))
