"""Beyond the thesis (docs/model.md section 5): wicking, drying, wetness-dependent stiffness, currents."""

import math

import numpy as np
import pytest
from scipy.special import erfc

import wetcloth
from support.reference import NumpyReference

DRY_FLOOR = dict(water_level=-5.0, floor_level=-1.0, initial_tilt=0.0, initial_height=-0.998)


def test_with_every_effect_off_each_step_is_the_core_model():
    """With wicking, drying, wet stiffness, currents and the air's drag (on by default: air_density 0
    here) off, the simulator is the thesis core: along a fast-absorbing towel's landing (1.5 s, through
    air, water contact and absorption), every step agrees with the NumPy reference, which implements
    the core alone (and the air's drag when on, checked in tests/test_kernels.py), taken from the same state.

    Compared step by step in this process, not with arrays stored on another CPU: a trajectory
    amplifies round-off differences (vector width, fused multiply-add) far beyond any bound one
    can derive.  One step from equal inputs differs by round-off in the forces, which partly cancel
    (springs against gravity): each value may differ by 1e-10 (~5e5 ulps) of the larger of its
    array's scale and what the step can change it by (h times the largest acceleration, and h
    times that for positions).  Switching any effect on moves values by orders of magnitude more."""
    scene = wetcloth.load_scene("thesis_fast", nx=9, ny=11, absorption_rate=1.0, integrator="explicit_euler",
                                tolerance=0.0, max_step=2e-4, air_density=0.0)
    assert (scene.wicking_rate, scene.drying_rate, scene.wet_stiffness_factor, scene.current_x, scene.current_y) == (
        0.0, 0.0, 0.0, 0.0, 0.0)
    sim = wetcloth.Simulation(scene, skip_idle_work=False)
    reference = NumpyReference(sim.model)
    touched = absorbed = False
    while sim.time < 1.5:
        before = sim.state.copy()
        h = scene.max_step
        expected = reference.explicit_step(before, h)
        accel = np.abs(reference.forces(before.pos, before.vel, before.water)).max() / sim.model.mass(before.water).min()
        change = {"water": 0.0, "vel": h * accel, "pos": h * (np.abs(before.vel).max() + h * accel)}
        sim.advance(h)
        for name in ("pos", "vel", "water"):
            got, want = getattr(sim.state, name), getattr(expected, name)
            scale = max(np.abs(want).max(), np.abs(getattr(before, name)).max(), change[name])
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * scale, err_msg=f"{name} at t = {sim.time:.4f} s")
        touched = touched or bool((sim.model.submerged > 0).any())
        absorbed = absorbed or bool((sim.state.water > before.water).any())
    assert touched and absorbed, "the run must reach the water and absorb, or the effects' code paths go untested"


def wicking_strip(ny, duration, rate=1e-4, length=0.4):
    """A strip resting on a dry floor, its y < 0 half saturated, the rest dry; wicking only."""
    scene = wetcloth.load_scene(nx=2, ny=ny, width=0.02, length=length, wicking_rate=rate, absorption_rate=0.0,
                                absorption_capacity=2.0, **DRY_FLOOR)
    sim = wetcloth.Simulation(scene)
    y = sim.model.topology.rest_xy[1]
    sim._buffers.water[...] = np.where(y < 0, 1.0, np.where(y == 0, 0.5, 0.0)) * sim.model.capacity
    total = sim.state.water.sum()
    sim.advance(duration)
    return sim, y, total


def test_wicking_spreads_as_one_dimensional_diffusion():
    """From a step of saturation, sat(y, t) = erfc(y / (2 sqrt(D t))) / 2 on an infinite strip (the
    front, sqrt(D t) = 2.2 cm after 5 s, stays far from the ends at +-20 cm: the ends' effect is
    ~1e-10).  The finite-volume scheme is second order in the spacing: at 1 cm the error is under
    2% of the step, and halving the spacing cuts it about four times."""
    D, t = 1e-4, 5.0
    errors = []
    for ny in (41, 81):
        sim, y, _ = wicking_strip(ny, t, rate=D)
        exact = 0.5 * erfc(y / (2 * math.sqrt(D * t)))
        errors.append(np.abs(sim.wetness - exact).max())
    assert errors[0] < 2e-2, errors
    assert 3.0 < errors[0] / errors[1] < 5.0, errors


def test_wicking_conserves_water_and_keeps_saturation_in_bounds():
    """Total water to round-off; saturation never above 1 or below 0, even with steps far longer
    than the explicit diffusion limit (sub-steps take care of it)."""
    sim, _, total = wicking_strip(21, 30.0, rate=5e-3)
    assert sim.state.water.sum() == pytest.approx(total, rel=1e-13)
    sat = sim.state.water / sim.model.capacity
    assert sat.min() >= 0.0 and sat.max() <= 1.0
    assert np.ptp(sat) < 1e-3, "at D = 5e-3 m2/s the 0.2 m strip has evened out in 30 s"


def test_towel_draped_into_water_wicks_above_the_waterline():
    """A towel hanging into a basin (its lower half floats on the surface) gets wet 5 cm and more
    above the surface only through wicking: never touched by water, those particles stay dry
    without it."""
    def wet_above(rate):
        scene = wetcloth.load_scene("wicking", nx=5, ny=9, wicking_rate=rate)
        sim = wetcloth.Simulation(scene)
        sim.advance(10.0)
        above = sim.positions[:, 2] > scene.water_level + 0.05
        assert above.any()
        return sim.wetness[above].max()

    assert wet_above(0.0) == 0.0
    assert wet_above(2e-4) > 1e-3


def test_drying_follows_its_exponential_law_in_air_and_stops_under_water():
    rate = 0.05
    scene = wetcloth.load_scene(nx=5, ny=5, drying_rate=rate, initial_saturation=1.0, absorption_rate=0.0,
                                **DRY_FLOOR)
    sim = wetcloth.Simulation(scene)
    start = sim.outputs()["water_mass"]
    sim.advance(10.0)
    assert sim.outputs()["water_mass"] == pytest.approx(start * math.exp(-rate * 10.0), rel=1e-12)
    under = wetcloth.Simulation(scene.replace(water_level=0.0, absorption_rate=0.0))
    under.advance(2.0)
    assert under.outputs()["water_mass"] == pytest.approx(start, rel=1e-15)


def test_drying_preset_loses_water_and_never_goes_negative():
    sim = wetcloth.Simulation(wetcloth.load_scene("drying", nx=5, ny=7))
    start = sim.outputs()["water_mass"]
    sim.advance(20.0)
    assert 0.0 <= sim.outputs()["water_mass"] < start
    assert (sim.state.water >= 0).all()


def test_wet_cloth_softened_by_half_stretches_twice_as_far():
    """Hanging saturated from its top edge, with stiffness scaled by 1 + f * saturation: f = -0.5
    halves every spring, so the stretch under the same weight doubles (small strains: 2 +- 5%)."""
    def stretch(factor):
        scene = wetcloth.load_scene(nx=5, ny=7, initial_tilt=90.0, pinned_edge="y_max", water_level=-50.0,
                                    floor_level=-100.0, initial_saturation=1.0, absorption_rate=0.0,
                                    wet_stiffness_factor=factor, integrator="implicit_euler")
        sim = wetcloth.Simulation(scene)
        sim.advance(3.0)
        return np.ptp(sim.positions[:, 2]) - scene.length

    plain, softened = stretch(0.0), stretch(-0.5)
    assert plain > 0
    assert softened / plain == pytest.approx(2.0, rel=0.05)


def test_floating_towel_drifts_at_the_current_velocity():
    """Drag acts on the velocity relative to the water: a floating towel is carried along until it
    moves with the current (relative speed decays at least at c_lin s / areal density ~ 1/s)."""
    scene = wetcloth.load_scene("current", nx=7, ny=7)
    sim = wetcloth.Simulation(scene)
    sim.advance(12.0)
    mean = sim.velocities.mean(axis=0)
    assert mean[0] == pytest.approx(scene.current_x, rel=1e-2)
    assert mean[1] == pytest.approx(scene.current_y, abs=1e-2 * abs(scene.current_x))


def test_current_is_an_input_that_can_change_mid_run():
    sim = wetcloth.Simulation(wetcloth.load_scene("thesis_float", nx=5, ny=5))
    sim.advance(1.0)
    sim.set_inputs(current_y=-0.05)
    sim.advance(10.0)
    assert sim.velocities[:, 1].mean() == pytest.approx(-0.05, rel=2e-2)
