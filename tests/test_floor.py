"""The tank floor (docs/model.md section 6.1): no penetration, Coulomb friction, and a cloth at rest on
it held there during each step, so that its steps are set by the rest of its motion."""

import numpy as np
import pytest

import wetcloth
from support.rollback import assert_restored_run_repeats
from support.sliding import STEP, assert_slides_coulomb_distance
from wetcloth._core import GRAVITY
from wetcloth.energy import mechanical_energy
from wetcloth.simulation import State

#: A heavy (saturated) 7 x 7 cloth lying flat 1 mm above the floor, under water: it settles at once.
ON_FLOOR = dict(nx=7, ny=7, width=0.3, length=0.3, initial_tilt=0.0, initial_height=-0.498, floor_level=-0.5,
                initial_saturation=1.0, absorption_rate=0.0)


def test_a_cloth_resting_on_the_floor_takes_steps_of_max_step_and_stays_on_it():
    """A sunk towel that keeps absorbing lands on the floor and lies there (sleep off, so that every step
    is taken: a sunk towel may sleep while it absorbs, the next test).

    At rest every particle's centre is exactly on the floor (``floor_z``: the floor puts it there and
    holds it), none below it, and nothing moves along the floor.  Before particles at rest were held,
    each step pushed them into the floor by ``h^2 g'`` and the floor pushed them back, which BDF2's
    error estimate took for an error of that size: ~450 steps per simulated second.  Now the steps
    are those of ``max_step``: at most ``1 / max_step`` per second, plus one per output interval
    (here 0.5 s) that does not divide into whole steps."""
    scene = wetcloth.load_scene(nx=9, ny=9, initial_tilt=5.0, initial_height=-0.9, floor_level=-1.0,
                                initial_saturation=0.95, absorption_capacity=4.0, absorption_rate=0.2)
    sim = wetcloth.Simulation(scene, skip_idle_work=False)
    floor = sim.model.floor_z
    sim.advance(3.5)  # lands at ~1.5 s and settles by ~2.5 s
    assert (sim.state.pos[2] == floor).all()
    resting = sim.state.pos.copy()
    water, steps, duration = sim.state.water.sum(), sim.steps, 5.0
    for _ in range(int(duration / 0.5)):
        sim.advance(0.5)
        assert (sim.state.pos[2] >= floor).all()
    assert sim.state.water.sum() > water  # held by the floor, still absorbing
    np.testing.assert_array_equal(sim.state.pos, resting)
    assert sim.steps - steps <= duration / scene.max_step + duration / 0.5


#: The towel of the test above (sunk, absorbing, landing on the floor at ~1.5 s).
SUNK_ABSORBING = dict(nx=9, ny=9, initial_tilt=5.0, initial_height=-0.9, floor_level=-1.0, initial_saturation=0.95,
                      absorption_capacity=4.0, absorption_rate=0.2)


def buras(water, dry_mass, capacity, rate, t):
    """The Buras law's water (kg) after t s under water from ``water``: Q - (Q - q) exp(-R t / C)."""
    full = capacity * dry_mass
    return full - (full - water) * np.exp(-rate * t / capacity)


def test_a_sunk_towel_at_rest_sleeps_while_it_absorbs_and_wakes_as_its_weight_grows():
    """A towel at rest on the floor, wholly under water and heavier than the water it displaces, falls
    asleep although it still absorbs (docs/model.md section 7): its growing weight only presses it
    harder onto the floor.  Asleep nothing moves and no step is taken, but each particle's water still
    follows the Buras law from where it was (exact over any time, so to rounding: rtol 1e-12).  It wakes
    when a particle has grown 2 % (SLEEP_WEIGHT_GROWTH) heavier than at its last step: at
    ``C/R ln((Q - q) / (Q - q_w))``, ``q_w = 1.02 (m0 + q_last) - m0``, taken at 0.05 s either side.  A
    snapshot taken asleep, restored, repeats the run across the wake to the bit."""
    scene = wetcloth.load_scene(**SUNK_ABSORBING)
    sim = wetcloth.Simulation(scene)
    while not sim.sleeping:
        assert sim.time < 6.0, "asleep within a few seconds of landing (at ~1.5 s)"
        sim.advance(0.1)
    snap = sim.snapshot()
    m0, water, last = sim.model.dry_mass, sim.state.water.copy(), snap["prev_water"]
    rate, capacity = scene.absorption_rate, scene.absorption_capacity
    full, wake_at = capacity * m0, 1.02 * (m0 + last) - m0
    wake = (capacity / rate * np.log((full - water) / (full - wake_at))).min()  # s from now
    asleep_at, positions, steps = sim.time, sim.positions, sim.steps
    sim.advance(wake - 0.05)
    assert sim.sleeping and sim.steps == steps
    np.testing.assert_array_equal(sim.positions, positions)
    np.testing.assert_allclose(sim.state.water, buras(water, m0, capacity, rate, sim.time - asleep_at), rtol=1e-12)
    sim.advance(0.1)
    assert sim.steps > steps, "awake again, to find the rest of its new weight"
    sim.restore(snap)  # asleep, across the wake: a restored run repeats to the bit
    assert sim.sleeping
    assert_restored_run_repeats(sim, snap, wake + 0.5)


def test_a_floating_towel_does_not_sleep_while_it_absorbs():
    """Afloat, a towel that absorbs grows heavier and sinks deeper: it must not fall asleep however
    still it lies (this towel, the sensitivity example's, floats nearly still from ~4 s and sinks from
    ~7 s; it fell asleep afloat, by 10 s, when the rule ignored the uptake)."""
    sim = wetcloth.Simulation(wetcloth.load_scene(**FLOATS_THEN_SINKS))
    for _ in range(100):
        sim.advance(0.1)
        assert not sim.sleeping
    assert sim.outputs()["centroid_z"] < -0.1, "sinking"


#: A 5 x 7 towel of the sensitivity example (models/studies/towel_sink_sensitivity.toml).
FLOATS_THEN_SINKS = dict(nx=5, ny=7, absorption_rate=0.7383830841998982, absorption_capacity=7.015019977465272,
                         areal_density=0.4833177274093032, thickness=0.00201255202293396,
                         initial_tilt=17.183734118007123, drag_normal=1.293426938354969)


@pytest.mark.parametrize("integrator", ["bdf2", "symplectic_euler"])
def test_static_friction_holds_a_cloth_the_current_pulls_less_than_friction(integrator):
    """Coulomb's static friction: a current drags the cloth along the floor with a force ``F_t``
    pressing it down with ``F_n`` (weight less buoyancy); with ``floor_friction`` above ``F_t / F_n``
    (computed from the model's own forces at rest) nothing moves, to the bit.  Drag and weight are
    lumped by the same area shares, so the ratio is the same for every particle (checked)."""
    mu_needed = _friction_ratio(0.3)
    sim = wetcloth.Simulation(wetcloth.load_scene(**ON_FLOOR, floor_friction=1.02 * mu_needed, integrator=integrator))
    sim.advance(0.5)
    before = sim.state.pos.copy()
    sim.set_inputs(current_x=0.3)
    sim.advance(1.0)
    np.testing.assert_array_equal(sim.state.pos, before)


def test_a_cloth_the_current_pulls_harder_than_friction_slides_at_the_terminal_speed():
    """With ``floor_friction`` at 0.6 of ``F_t / F_n`` the held particles are released and the cloth
    slides until the drag of the water passing it balances sliding friction: ``F_t(u - v) = mu F_n``,
    solved for ``v`` by bisection on the model's forces (drag relative to the cloth's velocity).

    Tolerance: the floor's friction impulse comes after each step, so the centroid moves with the
    velocity before it, which exceeds the velocity after it by ``mu (F_n / m) h`` (h the step); that
    twice, plus 0.1 % of the speed for what is left of the approach (time constant ~0.4 s, after 4 s)."""
    u, share = 0.3, 0.6
    mu = share * _friction_ratio(u)
    sim = wetcloth.Simulation(wetcloth.load_scene(**ON_FLOOR, floor_friction=mu))
    sim.advance(0.5)
    sim.set_inputs(current_x=u)
    model, state = sim.model, sim.state

    def pull_and_press(v):
        vel = np.zeros_like(state.vel)
        vel[0] = v
        force = model.forces(state.pos.copy(), vel, state.water.copy())
        return force[0].sum(), -force[2].sum()

    low, high = 0.0, u
    for _ in range(60):
        middle = 0.5 * (low + high)
        pull, press = pull_and_press(middle)
        low, high = (middle, high) if pull > mu * press else (low, middle)
    terminal = 0.5 * (low + high)
    sim.advance(4.0)
    x, steps = sim.outputs()["centroid_x"], sim.steps
    sim.advance(1.0)
    speed = sim.outputs()["centroid_x"] - x
    step = 1.0 / (sim.steps - steps)
    press = pull_and_press(terminal)[1] / model.mass(sim.state.water).sum()
    assert speed == pytest.approx(terminal, abs=2 * mu * press * step + 1e-3 * terminal)
    assert (sim.state.pos[2] >= model.floor_z).all()


@pytest.mark.parametrize("integrator", ["bdf2", "implicit_euler"])
def test_a_sheet_pushed_along_the_floor_stops_after_coulombs_distance(integrator):
    """A 5 x 5 sheet lying still on the floor, pushed to 0.5 m/s along x with floor_friction 0.3, stops
    after ``v0^2 / (2 mu g)`` (4.2 cm), up to each scheme's known first-order excess (0.6 % and 0.8 %
    at these 1 ms steps; see support.sliding).  In air without drag (air_density 0) and above the water,
    so that friction is the only force along the floor and the distance has that closed form.  Before
    the floor kept the particles' horizontal history, BDF2 slid 1.5 times as far (its velocity update
    took 2/3 of the fall the floor stops, so friction took 2/3 of the speed it should)."""
    scene = wetcloth.load_scene(nx=5, ny=5, width=0.1, length=0.1, initial_tilt=0.0, thickness=0.002,
                                initial_height=-0.5 + 0.001 + 1e-6, floor_level=-0.5, water_level=-0.9,
                                air_density=0.0, floor_friction=0.3, integrator=integrator, tolerance=0.0,
                                max_step=STEP)
    sim = wetcloth.Simulation(scene)
    sim.advance(0.1)  # lands (1 um) and is held
    assert_slides_coulomb_distance(sim, (1.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.3)


def test_a_sheet_sliding_on_the_floor_decelerates_at_mu_g_in_adaptive_steps():
    """Kinetic friction is a force of the implicit step (docs/model.md section 6.1): a sheet pushed to
    0.5 m/s along the floor (friction 0.3, no air or water) slows at ``mu g``, and with the default
    adaptive BDF2 steps stops after ``v0^2 / (2 mu g)``.

    Its velocity is linear in time and its position quadratic, which BDF2 reproduces exactly (and its
    first guess, the parabola through the last steps, is exact too): the velocity at each output is
    ``v0 - mu g t`` to the rounding of the few dozen steps taken (1e-12 m/s).  The distance errs only
    in the first step (backward Euler's, ``a h^2 / 2``, which is its error estimate ``h |v+ - v| / 2``,
    held to the allowed local error ``tolerance`` times the sheet's size; BDF2 carries it on times 3/2,
    its parasitic root being 1/3) and in the step within which the sheet stops (at most its distance
    from the predictor, 5/2 times its estimate at equal steps): within 4 allowed errors (2 um).  With
    friction as an impulse after each step (before), the sheet slid 0.36 % (0.15 mm) too far, in 384
    steps instead of 27."""
    scene = wetcloth.load_scene(nx=5, ny=5, width=0.1, length=0.1, initial_tilt=0.0, thickness=0.002,
                                initial_height=-0.5 + 0.001 + 1e-6, floor_level=-0.5, water_level=-0.9,
                                air_density=0.0, floor_friction=0.3)
    sim = wetcloth.Simulation(scene)
    sim.advance(0.1)  # lands (1 um) and is held
    state, speed, deceleration = sim.state, 0.5, 0.3 * GRAVITY
    assert np.abs(state.vel).max() == 0.0
    vel = np.zeros_like(state.vel)
    vel[0] = speed
    sim.state = State(state.time, state.pos.copy(), vel, state.water.copy())
    start = sim.state.pos.copy()
    for k in range(1, 9):
        sim.advance(0.02)
        np.testing.assert_allclose(sim.state.vel[0], speed - deceleration * 0.02 * k, rtol=0, atol=1e-12)
        assert (sim.state.pos[2] == sim.model.floor_z).all()
    sim.advance(0.2)
    assert np.abs(sim.state.vel).max() == 0.0  # stopped, held
    distance = (sim.state.pos[0] - start[0]).mean()
    allowed = scene.tolerance * max(scene.width, scene.length)
    assert distance == pytest.approx(speed**2 / (2.0 * deceleration), abs=4 * allowed)


def test_rollback_on_the_floor_repeats_the_run_bit_for_bit():
    """The held set is derived from the state at the start of each step, so a snapshot taken while the
    cloth lies on the floor (and a current starts to pull it) restores a run that repeats exactly."""
    sim = wetcloth.Simulation(wetcloth.load_scene(**ON_FLOOR, floor_friction=0.6 * _friction_ratio(0.3)))
    sim.advance(0.5)
    sim.set_inputs(current_x=0.3)
    sim.advance(0.05)
    assert_restored_run_repeats(sim, sim.snapshot(), 0.3)


def _friction_ratio(current: float) -> float:
    """``F_t / F_n`` of the ON_FLOOR cloth at rest on the floor in a current (m/s) along x."""
    sim = wetcloth.Simulation(wetcloth.load_scene(**ON_FLOOR))
    sim.advance(0.5)
    assert (sim.state.pos[2] == sim.model.floor_z).all()
    sim.set_inputs(current_x=current)
    state = sim.state
    force = sim.model.forces(state.pos.copy(), np.zeros_like(state.vel), state.water.copy())
    ratio = np.hypot(force[0], force[1]) / -force[2]
    assert ratio.max() == pytest.approx(ratio.min(), rel=1e-8)
    return float(ratio.max())


@pytest.mark.parametrize("step", [1.0 / 30.0, 1.0 / 24.0])
def test_a_sheet_swinging_onto_the_floor_at_frame_steps_creates_no_energy(step):
    """A 21 x 21 sheet, 0.6 m square, pinned along y_max 0.4 m above the floor (friction 0.5), released
    horizontal in air, swings down and slides over the floor, at fixed frame steps (implicit Euler,
    tolerance 0) for 1.5 s. Nothing drives it, so its mechanical energy never exceeds its start's, and
    no spring stretches by a tenth of its length (hanging, they stretch by 0.2 %; the swing 1.6-6 %).
    Before, friction on the particles sliding on the floor took its normal force from Newton's iterates:
    as the sheet struck the floor, Newton's direction went astray (8 m/s corrections), and one frame ended
    with springs stretched by 43 % (1/30 s) and 70 % (1/24 s), at 5.2 J and 12.0 J against 0.64 J."""
    scene = wetcloth.load_scene(nx=21, ny=21, width=0.6, length=0.6, initial_height=0.4, initial_tilt=0.0,
                                pinned_edge="y_max", floor_level=0.0, water_level=-10.0, absorption_rate=0.0,
                                absorption_capacity=0.0, floor_friction=0.5, integrator="implicit_euler",
                                tolerance=0.0, max_step=step)
    sim = wetcloth.Simulation(scene)
    cloth = sim.model.cloth
    start = mechanical_energy(sim)
    for _ in range(round(1.5 / step)):
        sim.advance(step)
        assert mechanical_energy(sim) <= start
        for offset, rest, stiffness in zip(cloth.offsets, cloth.rest, cloth.stiffness):
            i = np.flatnonzero(stiffness)
            length = np.linalg.norm(sim.state.pos[:, i] - sim.state.pos[:, i + offset], axis=0)
            assert length.max() <= 1.1 * rest
        assert (sim.state.pos[2] >= sim.model.floor_z).all()
