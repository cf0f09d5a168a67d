"""Physical sanity: free fall, a hanging cloth at rest, frame-long steps that lose energy, monotone wet
mass, no NaN, the blow-up guard."""

import math

import numpy as np
import pytest

import wetcloth
from conftest import G, INTEGRATORS, explicit_near_the_smallest_step
from support.hanging import HANGING
from wetcloth.energy import mechanical_energy
from wetcloth.integrators import SMALLEST_STEP

DRY_AIR = dict(water_level=-50.0, floor_level=-100.0, initial_tilt=0.0, initial_height=0.0)
#: Free fall's closed form holds in vacuum: without the air's drag (air_density 0), which at 1 m/s
#: would already slow the default sheet by 16 % of g (it falls at 2.5 m/s terminal: tests/test_air.py).
VACUUM = DRY_AIR | dict(air_density=0.0)


@pytest.mark.parametrize("integrator", INTEGRATORS[:3])
def test_free_fall_matches_g_t_squared_over_two(integrator):
    """Without water and air (air_density 0: g t^2 / 2 is the fall in vacuum), an unstretched cloth
    falls as one body: z(t) = z0 - g t^2 / 2.

    With fixed steps h, Euler's position after n steps is z0 - g h^2 n (n +- 1) / 2: the error
    is exactly g h t / 2 (explicit: too little fall, symplectic and implicit: too much).
    """
    h, duration = 1e-3, 1.0
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=5, ny=5, integrator=integrator, tolerance=0.0, max_step=h,
                                                  **VACUUM))
    sim.advance(duration)
    fall = -sim.outputs()["centroid_z"]
    bound = G * h * duration / 2
    assert fall == pytest.approx(G * duration**2 / 2, abs=bound * (1 + 1e-6))
    assert abs(fall - G * duration**2 / 2) == pytest.approx(bound, rel=1e-6)
    assert np.ptp(sim.positions[:, 2]) < 1e-12, "falls as one flat body"


def test_free_fall_is_exact_to_second_order_with_bdf2():
    """In vacuum (air_density 0, as above), BDF2 is exact for a constant acceleration once it has history; its first step (backward
    Euler, v1 exact, x1 too low by g h^2 / 2) leaves an offset that the recursion
    e+ = (4 e - e_prev) / 3 carries to 3/2 of it: 0.75 g h^2 (7 um at 1 ms), against Euler's
    g h t / 2 (5 mm).  We allow g h^2 (plus the Newton tolerance, 1e-6 of the cloth's size a step)."""
    h, duration = 1e-3, 1.0
    scene = wetcloth.load_scene(nx=5, ny=5, integrator="bdf2", tolerance=0.0, max_step=h, **VACUUM)
    sim = wetcloth.Simulation(scene)
    sim.advance(duration)
    fall = -sim.outputs()["centroid_z"]
    assert fall == pytest.approx(G * duration**2 / 2, abs=G * h * h + 1e-6 * scene.length)
    assert np.ptp(sim.positions[:, 2]) < 1e-9, "falls as one flat body"


@pytest.mark.parametrize("integrator", ["symplectic_euler", "implicit_euler", "bdf2"])
def test_hanging_cloth_pinned_at_one_edge_comes_to_rest(integrator):
    """A vertical cloth held by its top edge stretches under its weight, bounces, and the spring
    damping brings it to rest: after 3 s the fastest particle moves slower than 10 um/s (the
    conjugate-gradient tolerance leaves ~1e-7 m/s), and the pinned edge has not moved."""
    scene = wetcloth.load_scene(nx=7, ny=9, initial_tilt=90.0, pinned_edge="y_max",
                                water_level=-50.0, floor_level=-100.0, integrator=integrator)
    sim = wetcloth.Simulation(scene, skip_idle_work=False)  # no sleeping: the physics must come to rest
    pinned = sim.model.topology.pinned
    start = sim.positions[pinned]
    sim.advance(3.0)
    assert np.abs(sim.velocities).max() < 1e-5
    np.testing.assert_array_equal(sim.positions[pinned], start)
    assert sim.positions[:, 2].min() < start[:, 2].min() - scene.length, "hangs, stretched by its weight"


@pytest.mark.parametrize("integrator", ["symplectic_euler", "implicit_euler", "bdf2"])
def test_swinging_cloth_is_damped_by_thesis_damping(integrator):
    """Released 10 degrees off vertical it swings as a pendulum.  Projected damping leaves rigid
    rotation alone (and the model has no air drag), but the thesis form -k_d (v_i - v_j) damps
    it: the largest speed falls a hundredfold in 5 s."""
    scene = wetcloth.load_scene(nx=7, ny=9, initial_tilt=80.0, pinned_edge="y_max", damping_model="thesis",
                                water_level=-50.0, floor_level=-100.0, integrator=integrator)
    sim = wetcloth.Simulation(scene)
    sim.advance(0.5)
    early = np.abs(sim.velocities).max()
    sim.advance(5.0)
    assert np.abs(sim.velocities).max() < 0.01 * early


def test_frame_long_implicit_euler_steps_never_fail_and_lose_energy_in_every_frame():
    """The fixed-step mode for artists (implicit_euler, tolerance 0, max_step one frame) on a 41 x 41
    sheet, 1 m square, released horizontal from one edge: it falls, swings and hangs.  Each of the 90
    frames is one step (none rejected: BDF2's fixed steps quarter a frame where Newton fails), and the
    mechanical energy (kinetic, gravity, elastic) falls in every frame, as backward Euler's exact
    solution of a dissipative system must.  Measured: it falls by at least 2.2e-4 J a frame out of
    9 J; the allowance 1e-9 J is round-off in summing the energy over 1681 particles (1e-16 relative
    each), so any rise the solver let in would show.  Newton stops once the residual it leaves can do
    no more work over the step than a tenth of the scheme's own damping (DESCENT_ENERGY_FRACTION):
    188 iterations over the 90 steps, where the cap allows 360.  The error estimate reports what the
    frame-long steps cost: millimetres to centimetres here (the largest frame's: 2.1 cm in air, 2.7 cm in vacuum),
    where the default's steps err by micrometres.  The largest over the frames, not the last frame's:
    the air damps the swing, and by the last frame the sheet barely moves (0.7 mm in air, 3 mm in vacuum)."""
    scene = wetcloth.load_scene(nx=41, ny=41, integrator="implicit_euler", tolerance=0.0, max_step=1 / 30, **HANGING)
    sim = wetcloth.Simulation(scene)
    energies, estimates = [mechanical_energy(sim)], []
    for _ in range(90):
        sim.advance(1 / 30)
        energies.append(mechanical_energy(sim))
        estimates.append(sim.error_estimate)
    assert sim.steps == 90 and sim.rejected_steps == 0
    assert sim.solver_counts["newton_iterations"] < 3 * 90, "the energy stop ends most steps early"
    assert np.diff(energies).max() < 1e-9, np.diff(energies).max()
    assert energies[-1] < energies[0] - 1.0, "it fell and swung: potential energy went"
    assert 1e-3 < max(estimates) < 0.1


def test_a_frame_long_steps_error_estimate_is_the_size_of_its_true_error():
    """What the fixed-step mode reports per frame (``error_estimate``) is the size of what the frame's
    step really got wrong: the largest distance of any particle from a converged step (BDF2 at tolerance
    5e-9) over the same frame from the same state.  The estimate is backward Euler's leading error term,
    h |v+ - v| / 2, plus what Newton left unsolved where it stopped short.  On the 41 x 41 hanging sheet
    at 1/30 s, every 4th of its first 60 frames: true errors 0.75-8.4 mm, estimates 0.71-3.0 times them.
    Bound: at least half the true error (a user must not be told a frame is better than it is) and at
    most 4 times it.  A zero or a fixed figure fails: the true errors span a factor of 11, more than the
    bound's 8.  (bb80f15 counted the last Newton correction as unsolved: 12 times the true error where
    the energy test stopped Newton.)"""
    scene = wetcloth.load_scene(nx=41, ny=41, integrator="implicit_euler", tolerance=0.0, max_step=1 / 30, **HANGING)
    sim = wetcloth.Simulation(scene)
    checked = range(1, 61, 4)
    for frame in range(1, 61):
        if frame in checked:
            converged = wetcloth.Simulation(scene.replace(integrator="bdf2", tolerance=5e-9, max_step=0.1))
            converged._buffers.pos[...] = sim.state.pos
            converged._buffers.vel[...] = sim.state.vel
            converged.advance(1 / 30)
        sim.advance(1 / 30)
        if frame in checked:
            true_error = np.linalg.norm(sim.positions - converged.positions, axis=1).max()
            assert 0.5 * true_error <= sim.error_estimate <= 4.0 * true_error, (frame, sim.error_estimate, true_error)


def test_wet_mass_never_decreases_and_nothing_is_nan():
    """Over a landing, floating and sinking run: wet mass is non-decreasing (no drying in the
    core), every output and every array finite."""
    sim = wetcloth.Simulation(wetcloth.load_scene("thesis_fast", nx=9, ny=11, absorption_rate=1.0))
    previous = 0.0
    while sim.time < 20.0:
        sim.advance(0.1)
        out = sim.outputs()
        assert all(math.isfinite(v) for v in out.values()), out
        assert out["wet_mass"] >= previous
        previous = out["wet_mass"]
        assert sim.state.is_finite()
    assert out["depth"] > 0.02, "absorbing fast, it has sunk"
    assert 0.0 <= sim.wetness.min() and sim.wetness.max() <= 1.0


def test_blow_up_guard_stops_with_cause_and_last_good_time():
    """Fixed steps far beyond explicit Euler's limit (h > c/k = 1e-4 s) blow up; the guard stops
    the run with a message naming the step, the stiffness and the last good time, and the
    simulation keeps its last good (finite) state."""
    scene = wetcloth.load_scene(nx=9, ny=9, integrator="explicit_euler", tolerance=0.0, max_step=2e-3,
                                initial_tilt=30.0, **{k: v for k, v in DRY_AIR.items() if k != "initial_tilt"})
    sim = wetcloth.Simulation(scene)
    with pytest.raises(wetcloth.BlowUpError) as err:
        sim.advance(10.0)
    message = str(err.value)
    assert "stretch_stiffness" in message and "step" in message and "Last good time" in message
    assert err.value.last_good_time == sim.time < 10.0
    assert sim.state.is_finite()
    assert all(math.isfinite(v) for v in sim.outputs().values())
    # The message names the scheme's stability bound at rest, and fixed steps of that bound hold the same scene
    # through the time it blew up in and as long again.
    bound = sim.integrator.stable_step(0.0)
    assert f"explicit_euler is stable on this cloth at rest at steps up to {bound:.2g} s" in message, message
    held = wetcloth.Simulation(scene.replace(max_step=bound))
    held.advance(2.0 * sim.time)
    assert held.state.is_finite() and np.abs(held.velocities).max() < 10.0


@pytest.mark.parametrize("integrator", ["explicit_euler", "symplectic_euler"])
def test_an_explicit_scheme_that_needs_steps_below_the_smallest_is_refused_naming_what_sets_its_bound(integrator):
    """Found by a random trial: symplectic Euler with damping = 2.7e5 N s/m is stable on the towel only at steps
    of 1.3e-10 s, and crept on (a second of it, hours; an FMU's 0.05 s doStep, minutes).  Now refused at the start,
    as the native units refuse it; the implicit schemes take the same scene."""
    stiff = wetcloth.load_scene(integrator=integrator, damping=2.7e5)
    with pytest.raises(wetcloth.ParameterError) as exc:
        wetcloth.Simulation(stiff)
    assert exc.value.name == "integrator"
    assert str(exc.value).startswith(f"parameter 'integrator': '{integrator}' is stable on this cloth only at steps "
                                     "up to 1.3e-10 s, below the smallest step (1e-09 s), set by the springs' "
                                     "damping (parameter damping: a rate of 1.3e+10 1/s); allowed: 'bdf2' or "
                                     "'implicit_euler'"), str(exc.value)
    tiny = wetcloth.load_scene(integrator=integrator, damping=0.0, stretch_stiffness=1e8, width=1e-3, length=1e-3,
                               nx=81, ny=81)
    with pytest.raises(wetcloth.ParameterError, match="set by the springs' stiffness over the particles' masses"):
        wetcloth.Simulation(tiny)
    dragged = wetcloth.load_scene(integrator=integrator, water_density=1e5, drag_normal=100.0, current_x=10.0,
                                  areal_density=0.005)
    with pytest.raises(wetcloth.ParameterError, match=r"set by the drag at rest \(water_density, .* less drag$"):
        wetcloth.Simulation(dragged)
    for implicit in ("bdf2", "implicit_euler"):
        wetcloth.Simulation(stiff.replace(integrator=implicit)).advance(0.01)


def test_an_explicit_scheme_just_above_the_smallest_step_runs_and_an_input_that_would_take_it_below_is_refused():
    """The rule's edge: a bound 1e-6 above the smallest step runs; a current (an input, adding drag) that takes
    the bound below it is refused naming the rule, and the run goes on unchanged."""
    scene = explicit_near_the_smallest_step(1e-6)
    sim = wetcloth.Simulation(scene)
    assert SMALLEST_STEP < sim.integrator.stable_step(0.0) < 1.00001 * SMALLEST_STEP
    sim.advance(2e-8)
    assert sim.state.is_finite()
    with pytest.raises(wetcloth.ParameterError, match="'explicit_euler' is stable on this cloth only at steps up to"):
        sim.set_inputs(current_x=10.0)
    assert sim.scene == scene and sim.integrator.control() == sim._control
    sim.advance(2e-8)
    assert sim.time == pytest.approx(4e-8) and sim.state.is_finite()
    with pytest.raises(wetcloth.ParameterError, match="below the smallest step"):
        wetcloth.Simulation(explicit_near_the_smallest_step(-1e-6))


def test_same_scene_with_adaptive_steps_does_not_blow_up():
    scene = wetcloth.load_scene(nx=9, ny=9, integrator="explicit_euler", initial_tilt=30.0,
                                **{k: v for k, v in DRY_AIR.items() if k != "initial_tilt"})
    sim = wetcloth.Simulation(scene)
    sim.advance(1.0)
    assert sim.state.is_finite()


def test_rising_water_carries_a_floating_cloth_up():
    """Inputs change from the next step on: raise the water by 5 cm and the floating cloth
    follows, ending at the same depth below the new surface."""
    scene = wetcloth.load_scene("thesis_float", nx=7, ny=7, initial_tilt=0.0, initial_height=0.002)
    sim = wetcloth.Simulation(scene)
    sim.advance(2.0)
    before = sim.outputs()
    for k in range(50):
        sim.set_inputs(water_level=0.001 * (k + 1))
        sim.advance(0.02)
    sim.advance(3.0)
    after = sim.outputs()
    assert after["centroid_z"] == pytest.approx(before["centroid_z"] + 0.05, abs=1e-4)
    assert after["depth"] == pytest.approx(before["depth"], abs=1e-4)


def test_only_inputs_change_during_a_run():
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=3, ny=3))
    with pytest.raises(wetcloth.ParameterError, match="'nx'.*fixed"):
        sim.set_inputs(nx=5)
    with pytest.raises(wetcloth.ParameterError, match="'water_density'.*out of range"):
        sim.set_inputs(water_density=-1.0)
    with pytest.raises(ValueError, match="duration"):
        sim.advance(-1.0)


def test_sampling_in_compiled_code_repeats_advance_and_outputs_bit_for_bit():
    """``sample`` steps to each time and records the outputs there without returning to Python:
    the same steps and values as ``advance`` to each time followed by ``outputs``.  (Times in
    eighths of a second, so that ``advance``'s target ``time + (t - time)`` is ``t`` exactly.)"""
    scene = wetcloth.load_scene("thesis_fast", nx=7, ny=7)
    times = np.arange(0, 17) / 8.0
    one_by_one = wetcloth.Simulation(scene)
    expected = []
    for t in times:
        one_by_one.advance(t - one_by_one.time)
        expected.append(list(one_by_one.outputs().values()))
    sampled = wetcloth.Simulation(scene)
    outputs = sampled.sample(times)
    np.testing.assert_array_equal(outputs, np.array(expected))
    assert sampled.steps == one_by_one.steps > len(times)
    np.testing.assert_array_equal(sampled.state.pos, one_by_one.state.pos)


@pytest.mark.parametrize("pause_after", [None, 0.0])
def test_sampling_records_each_intervals_own_step_error_as_advance_does(pause_after):
    """``sample_errors[k]`` is the ``error_estimate`` an ``advance`` from times[k - 1] to times[k] leaves:
    the same steps' largest estimate, interval by interval, also when the compiled calls pause inside an
    interval (``pause_after = 0``: a call after every step); ``error_estimate`` after ``sample`` is their
    largest.  Fixed frame steps, where the estimate is what the user trades for speed."""
    scene = wetcloth.load_scene(nx=9, ny=9, integrator="implicit_euler", tolerance=0.0, max_step=1.0 / 32.0,
                                pinned_edge="y_max", **DRY_AIR)
    times = np.arange(1, 17) / 16.0  # two steps a sample
    one_by_one = wetcloth.Simulation(scene)
    expected = []
    for t in times:
        one_by_one.advance(t - one_by_one.time)
        expected.append(one_by_one.error_estimate)
    sampled = wetcloth.Simulation(scene)
    if pause_after is not None:
        sampled.pause_after = pause_after
    sampled.sample(times)
    np.testing.assert_array_equal(sampled.sample_errors, expected)
    assert sampled.error_estimate == max(expected) and len(set(expected)) > 4 and min(expected) > 0.0


def test_outputs_are_the_mass_weighted_centroid_and_masses():
    """``outputs`` (computed in compiled code) against NumPy's sums of the same state."""
    sim = wetcloth.Simulation(wetcloth.load_scene("thesis_fast", nx=7, ny=7))
    sim.advance(1.0)
    mass = sim.model.dry_mass + sim.state.water
    centroid = sim.state.pos @ mass / mass.sum()
    out = sim.outputs()
    assert list(out) == list(wetcloth.simulation.OUTPUT_NAMES)
    # Sums of 49 terms in another order (and a division) differ by under 64 eps times the sum of the
    # terms' magnitudes: for a centroid near zero, that of |m x| over the mass, not the centroid itself.
    rounding = 64 * np.finfo(float).eps
    scale = np.abs(sim.state.pos) @ mass / mass.sum()
    got = np.array([out["centroid_x"], out["centroid_y"], out["centroid_z"]])
    np.testing.assert_array_less(np.abs(got - centroid), rounding * scale)
    assert abs(out["depth"] - (sim.scene.water_level - centroid[2])) < rounding * (scale[2] + abs(sim.scene.water_level))
    assert out["wet_mass"] == pytest.approx(mass.sum(), rel=rounding)
    assert out["water_mass"] == pytest.approx(sim.state.water.sum(), rel=rounding)


def test_a_blow_up_while_sampling_keeps_the_outputs_of_the_times_reached():
    scene = wetcloth.load_scene(nx=9, ny=9, integrator="explicit_euler", tolerance=0.0, max_step=2e-3,
                                initial_tilt=30.0, **{k: v for k, v in DRY_AIR.items() if k != "initial_tilt"})
    sim = wetcloth.Simulation(scene)
    times = np.linspace(0.0, 10.0, 101)
    with pytest.raises(wetcloth.BlowUpError) as err:
        sim.sample(times)
    reached = err.value.partial_outputs
    assert 0 < len(reached) < len(times) and times[len(reached) - 1] <= sim.time < times[len(reached)]
    assert np.isfinite(reached).all()


@pytest.mark.parametrize("times", [[0.5, 0.25], [float("nan")], [[0.1, 0.2]]])
def test_sampling_times_must_be_ascending_and_finite(times):
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=5, ny=5))
    with pytest.raises(ValueError, match="times must be a 1-D sequence of finite times"):
        sim.sample(times)
