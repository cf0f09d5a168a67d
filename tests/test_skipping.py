"""Work a scene does not need is skipped, and skipping changes nothing that matters."""

import numpy as np
import pytest

import wetcloth
from wetcloth.state import State

IN_AIR = dict(water_level=-5.0, floor_level=-1.0, initial_tilt=0.0, initial_height=-0.95)


def run_both(scene, duration, every=0.1):
    """Outputs of the same scene with and without skipping, sampled every ``every`` s."""
    runs = []
    for skip in (True, False):
        sim = wetcloth.Simulation(scene, skip_idle_work=skip)
        rows = []
        while sim.time < duration - 1e-9:
            sim.advance(every)
            rows.append(list(sim.outputs().values()))
        runs.append((sim, np.array(rows)))
    return runs


def test_cloth_resting_on_the_floor_falls_asleep_and_nothing_changes():
    """Dropped 5 cm onto a dry floor, the cloth settles and sleeps: steps stop, time goes on.  The
    outputs differ from the fully computed run by less than the sleep distance (0.5 mm), and in
    fact, on a floor that holds the cloth still, by under 1e-5 m."""
    scene = wetcloth.load_scene(nx=7, ny=9, **IN_AIR)
    (sleepy, rows), (awake, reference) = run_both(scene, 5.0)
    assert sleepy.sleeping and not awake.sleeping
    assert sleepy.steps < awake.steps / 2
    np.testing.assert_allclose(rows, reference, rtol=0, atol=1e-5)


def test_absorbing_cloth_does_not_sleep():
    """A cloth resting on the tank floor under water keeps soaking up water: it never sleeps, and its
    wet mass is the fully computed run's."""
    scene = wetcloth.load_scene(nx=5, ny=5, **(IN_AIR | dict(water_level=0.0)), absorption_rate=0.05)
    (sleepy, rows), (_, reference) = run_both(scene, 3.0)
    assert not sleepy.sleeping
    np.testing.assert_array_equal(rows, reference)


def test_floating_cloth_falls_asleep():
    """A cloth floating still (its heave jitter below the sleep distance) sleeps within seconds."""
    scene = wetcloth.load_scene("thesis_float", nx=5, ny=5, initial_tilt=0.0, initial_height=0.002)
    sim = wetcloth.Simulation(scene)
    sim.advance(5.0)
    assert sim.sleeping


def test_new_input_wakes_a_sleeping_cloth():
    """A cloth asleep on a dry tank floor wakes when water flows in, and floats up to the surface."""
    scene = wetcloth.load_scene(nx=5, ny=5, **IN_AIR, absorption_capacity=0.0, absorption_rate=0.0)
    sim = wetcloth.Simulation(scene)
    sim.advance(2.0)
    assert sim.sleeping
    sim.set_inputs(water_level=-5.0)
    assert sim.sleeping, "setting an input to its current value changes nothing"
    sim.set_inputs(water_level=-0.5)
    assert not sim.sleeping
    sim.advance(6.0)  # it rises at ~0.17 m/s
    assert sim.outputs()["depth"] == pytest.approx(0.0, abs=scene.thickness)


def test_falling_through_air_skips_the_water_kernels_with_identical_results():
    """High above the water, no particle touches it: results are bit for bit those of the run that
    evaluates the water forces anyway (they are exactly zero)."""
    scene = wetcloth.load_scene(nx=6, ny=6, initial_height=5.0, initial_tilt=20.0)
    (_, rows), (_, reference) = run_both(scene, 0.5)
    np.testing.assert_array_equal(rows, reference)


def test_half_submerged_cloth_skips_dry_rows_with_identical_results():
    """A vertical cloth half under water: rows of cells above the surface are skipped, and the
    drag is exactly what computing every row gives."""
    scene = wetcloth.load_scene(nx=6, ny=9, initial_height=0.0, initial_tilt=90.0, absorption_rate=0.0,
                                absorption_capacity=0.0, areal_density=1.0)
    (_, rows), (_, reference) = run_both(scene, 0.3)
    np.testing.assert_array_equal(rows, reference)


def test_snapshot_and_restore_repeat_a_run_exactly():
    """restore(snapshot()) puts back everything that evolves, including the step control and sleep."""
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=5, ny=7))
    sim.advance(0.3)
    saved = sim.snapshot()
    sim.advance(0.2)
    sim.set_inputs(water_level=0.01)
    sim.advance(0.2)
    first = sim.outputs(), sim.steps
    sim.restore(saved)
    sim.advance(0.2)
    sim.set_inputs(water_level=0.01)
    sim.advance(0.2)
    assert (sim.outputs(), sim.steps) == first


def test_snapshot_holds_numbers_and_arrays_only_and_repeats_bdf2_exactly():
    """The snapshot contract: a flat dict of arrays, Python numbers, the state (a dataclass of arrays)
    and the scene.  BDF2's history
    (the previous state) and its preconditioner's factorisation come back, so the run repeats bit
    for bit after a restore, with an input changed in between."""
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=6, ny=7, integrator="bdf2", absorption_rate=1.0))
    sim.advance(0.4)
    saved = sim.snapshot()
    assert all(isinstance(v, (np.ndarray, float, int, bool, wetcloth.Scene, State)) for v in saved.values())
    assert "prev_pos" in saved and "preconditioner_mass" in saved
    runs = []
    for _ in range(2):
        sim.advance(0.2)
        sim.set_inputs(water_level=0.01)
        sim.advance(0.3)
        runs.append((sim.positions.copy(), sim.outputs(), sim.steps))
        sim.restore(saved)
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    assert runs[0][1:] == runs[1][1:]


def test_restore_refuses_a_wrong_snapshot_and_changes_nothing():
    """A snapshot of another cloth (other grid), with a key missing, or of another scene is refused
    with a message naming what does not fit, before anything changes."""
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=5, ny=6))
    sim.advance(0.1)
    before = (sim.time, sim.positions.copy(), sim.scene)
    other = wetcloth.Simulation(wetcloth.load_scene(nx=6, ny=6))
    with pytest.raises(ValueError, match="nx"):
        sim.restore(other.snapshot())
    missing = sim.snapshot()
    del missing["prev_vel"]
    with pytest.raises(ValueError, match="prev_vel"):
        sim.restore(missing)
    heavier = sim.snapshot() | {"scene": sim.scene.replace(areal_density=1.0)}
    with pytest.raises(ValueError, match="areal_density"):
        sim.restore(heavier)
    assert sim.time == before[0] and sim.scene == before[2]
    np.testing.assert_array_equal(sim.positions, before[1])
