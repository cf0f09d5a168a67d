"""FMU state: get/set and serialize cover the whole unit, so rolled-back and resumed runs repeat exactly."""

from __future__ import annotations

import numpy as np
from test_fmu_support import SMALL, Unit

from wetcloth.simulation import OUTPUT_NAMES

#: A scene whose state has everything moving: falling, tilted, absorbing, with an input change.
VALUES = SMALL | {"initial_tilt": 30.0, "absorption_rate": 0.5}


def run(unit: Unit, steps: int, h: float = 0.05, level_at: int | None = 3) -> list[tuple]:
    """Step ``steps`` times, raising the water level at step ``level_at``; outputs after every step."""
    rows = []
    for k in range(steps):
        if k == level_at:
            unit.set(water_level=0.02)
        assert unit.step(h) == 0
        rows.append(tuple(unit.outputs()[n] for n in OUTPUT_NAMES))
    return rows


def test_restored_state_repeats_the_run_exactly():
    unit = Unit(VALUES)
    try:
        run(unit, 6, level_at=None)
        t_saved = unit.time
        state = unit.fmu.getFMUstate()
        first = run(unit, 10)
        unit.fmu.setFMUstate(state)
        unit.time = t_saved
        second = run(unit, 10)
        unit.fmu.setFMUstate(state)  # a state can be restored again
        unit.time = t_saved
        third = run(unit, 10)
        unit.fmu.freeFMUstate(state)
    finally:
        unit.close()
    assert first == second == third  # bit for bit: the whole state, step controller included, came back
    assert len(set(first)) == len(first)  # and the run was not standing still


def test_restore_brings_back_inputs_set_after_the_snapshot():
    unit = Unit(VALUES)
    try:
        state = unit.fmu.getFMUstate()
        unit.set(water_level=0.3)
        unit.step(0.1)
        unit.fmu.setFMUstate(state)
        unit.time = 0.0
        assert unit.get("water_level") == 0.0
        unit.fmu.freeFMUstate(state)
    finally:
        unit.close()


def test_serialized_state_resumes_in_a_fresh_instance():
    uninterrupted = Unit(VALUES, name="whole")
    try:
        run(uninterrupted, 6, level_at=None)
        saved_time = uninterrupted.time
        saved = uninterrupted.fmu.serializeFMUstate(uninterrupted.fmu.getFMUstate())
        expected = run(uninterrupted, 10)
    finally:
        uninterrupted.close()
    assert isinstance(saved, bytes) and len(saved) > 0

    # A new instance with other parameters: the deserialized state replaces all of it.
    fresh = Unit({"nx": 4, "ny": 6, "water_level": 0.1}, name="resumed")
    try:
        state = fresh.fmu.deSerializeFMUstate(saved)
        fresh.fmu.setFMUstate(state)
        fresh.fmu.freeFMUstate(state)
        fresh.time = saved_time  # the master resumes from the saved communication point
        assert fresh.get("nx") == VALUES["nx"] and fresh.get("water_level") == 0.0
        resumed = run(fresh, 10)
    finally:
        fresh.close()
    assert resumed == expected


def test_state_of_one_instance_does_not_leak_into_another():
    a, b = Unit(VALUES, name="a"), Unit(VALUES, name="b")
    try:
        run(a, 4, level_at=None)
        state = a.fmu.getFMUstate()
        before = b.outputs()
        run(a, 4)
        assert b.outputs() == before
        a.fmu.freeFMUstate(state)
        assert np.isfinite(list(a.outputs().values())).all()
    finally:
        a.close()
        b.close()
