"""Air (docs/model.md section 4.4): the face drag of the air above the water, relative to the wind.

The analytic cases of section 10 (9 and 10): a horizontal sheet falling at its terminal velocity, a
flag at its steady angle in wind; the inputs; the switch; one vocabulary for the new names."""

import json
import math

import numpy as np
import pytest

import wetcloth
from conftest import G, INTEGRATORS
from wetcloth.cli import main

#: Nothing but air: water and floor far below, no absorption.
IN_AIR = dict(water_level=-100.0, floor_level=-50.0, absorption_capacity=0.0, absorption_rate=0.0)


def terminal_velocity(scene: wetcloth.Scene) -> float:
    """v_t = sqrt(2 m g / (rho_air C_n A)) (m/s) of a horizontal sheet: m / A is its areal density."""
    return math.sqrt(2.0 * scene.areal_density * G / (scene.air_density * scene.drag_normal))


def mean_velocity(sim: wetcloth.Simulation) -> np.ndarray:
    mass = sim.model.mass(sim.state.water)
    return (sim.state.vel * mass).sum(axis=1) / mass.sum()


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_a_horizontal_sheet_falls_at_the_terminal_velocity(integrator):
    """A flat sheet released horizontal in air: v(t) = v_t tanh(g t / v_t), v_t = sqrt(2 m g / (rho C_n A))
    (2.48 m/s for the towel's 0.45 kg/m2; free fall would be at 19.6 m/s after the 2 s).

    The air's drag is lumped to the particles with their area shares, like the mass, so every particle
    of the flat sheet has the same acceleration and the discrete model is the analytic one exactly
    (its drag is along the normal alone: the tangential coefficient does not enter).  Only the time
    integration errs; over the transient (time constant v_t / g = 0.25 s) it is 0.07 % of v_t at worst
    (implicit Euler), and after 2 s (8 time constants, tanh = 1 - 2e-7) the fall speed is v_t within
    1e-6.  The 1 % of the issue is asked at every 0.05 s and at the end."""
    scene = wetcloth.load_scene(nx=9, ny=9, initial_tilt=0.0, initial_height=0.0, integrator=integrator, **IN_AIR)
    v_t = terminal_velocity(scene)
    sim = wetcloth.Simulation(scene)
    worst = 0.0
    while sim.time < 2.0 - 1e-9:
        sim.advance(0.05)
        expected = -v_t * math.tanh(G * sim.time / v_t)
        worst = max(worst, abs(mean_velocity(sim)[2] - expected) / v_t)
    assert worst < 1e-2
    assert -mean_velocity(sim)[2] == pytest.approx(v_t, rel=1e-2)
    assert np.ptp(sim.positions[:, 2]) < 1e-3, "it falls flat"


def test_an_upward_wind_set_mid_fall_lifts_the_sheet_at_the_terminal_velocity():
    """``wind_z`` is an input: set to 2 v_t while the sheet falls at v_t, the air now passes it at
    3 v_t upward and it settles where the air passes it at v_t, that is rising at v_t (1 %, as above:
    2 s is 8 time constants).  Before the change it fell at v_t."""
    scene = wetcloth.load_scene(nx=7, ny=7, initial_tilt=0.0, initial_height=0.0, **IN_AIR)
    v_t = terminal_velocity(scene)
    sim = wetcloth.Simulation(scene)
    sim.advance(2.0)
    assert mean_velocity(sim)[2] == pytest.approx(-v_t, rel=1e-2)
    sim.set_inputs(wind_z=2.0 * v_t)
    sim.advance(2.0)
    assert mean_velocity(sim)[2] == pytest.approx(v_t, rel=1e-2)
    assert np.ptp(sim.positions[:, 2]) < 1e-3


def flag_angle(scene: wetcloth.Scene, wind: float) -> float:
    """The steady angle (rad) from the vertical of a flat sheet hanging from a horizontal edge in a
    horizontal wind normal to that edge: (1/2) rho C_n A U^2 cos^2(theta) = m g sin(theta), a quadratic
    in sin(theta)."""
    q = 0.5 * scene.air_density * scene.drag_normal * wind * wind
    w = scene.areal_density * G
    return math.asin((-w + math.sqrt(w * w + 4.0 * q * q)) / (2.0 * q))


#: Flags: the edge held, the tilt it is released at (90: hanging; 0: horizontal, it swings down), the
#: wind component blowing normal to the hanging sheet and its axis, the wind speed (m/s).
FLAGS = {
    "y_max in wind_y 1.5 m/s": ("y_max", 90.0, "wind_y", 1, 1.5),
    "x_min in wind_x 3 m/s": ("x_min", 0.0, "wind_x", 0, 3.0),
}


@pytest.mark.parametrize("flag", FLAGS.values(), ids=FLAGS.keys())
def test_a_flag_in_wind_settles_at_the_analytic_angle(flag):
    """A sheet held along a horizontal edge hangs in still air for 1 s; then a horizontal wind normal to
    it (set as an input) lifts it to the angle theta from the vertical where the normal drag's torque
    about the edge balances gravity's, (1/2) rho C_n A U^2 cos^2(theta) = m g sin(theta) (19.1 degrees
    at 1.5 m/s, 45.7 at 3 m/s; the tangential drag acts along the lever arm: no torque).

    Why the grid adds no error: gravity and the air's drag are both uniform per area and lumped with
    the area shares, and at theta the load across the sheet, rho_a g sin(theta) - (1/2) rho C_n U^2
    cos^2(theta) per area, vanishes everywhere: the flat sheet at theta is an exact equilibrium of the
    discrete model too, whatever its bending stiffness (the default's here).  The stretch under its
    weight (strain ~ rho_a g L / stiffness = 1.5e-3) lies along the sheet and turns nothing.  What is
    left is that it is not quite still: at 1.5 m/s its swing decays (0.05 % from 4 s on, at rest by
    8 s); at 3 m/s its free edge flutters (+-5 mm, up to 0.1 m/s), moving the centroid's angle by up to
    0.14 % and the fitted plane's by 0.36 % (measured from 4 s to 7 s, 3 s after the wind rose).  The
    issue's 2 % is asked of both, every 0.25 s."""
    edge, tilt, component, axis, wind = flag
    scene = wetcloth.load_scene(nx=15, ny=21, initial_tilt=tilt, pinned_edge=edge, initial_height=1.0, **IN_AIR)
    theta = flag_angle(scene, wind)
    sim = wetcloth.Simulation(scene)
    sim.advance(1.0)
    held = sim.model.topology.pinned
    still = sim.positions.copy()
    sim.set_inputs(**{component: wind})
    sim.advance(3.0)
    assert np.abs(sim.positions - still).max() > 0.1, "the wind moved it"
    while sim.time < 7.0 - 1e-9:
        sim.advance(0.25)
        p = sim.positions
        offset = p.mean(axis=0) - p[held].mean(axis=0)  # uniform dry sheet: centroid = mean
        by_centroid = math.atan2(offset[axis], -offset[2])
        normal = np.linalg.svd(p - p.mean(axis=0), full_matrices=False)[2][2]
        by_plane = math.atan2(abs(normal[2]), abs(normal[axis]))
        assert by_centroid == pytest.approx(theta, rel=2e-2), sim.time
        assert by_plane == pytest.approx(theta, rel=2e-2), sim.time
        np.testing.assert_array_equal(p[held], still[held])


def test_without_air_the_wind_does_nothing_and_under_water_the_air_does_nothing():
    """air_density 0 switches the drag in air off: the wind changes nothing, to the bit.  And the air
    acts only on the part of the cloth out of the water: a heavy sheet sinking wholly under water
    (every particle's s = 1) moves to the bit as without wind."""
    def run(**values):
        sim = wetcloth.Simulation(wetcloth.load_scene(nx=7, ny=9, **values))
        sim.advance(1.0)
        return sim.state.pos.copy()

    windy = dict(wind_x=3.0, wind_y=-2.0, wind_z=1.0)
    np.testing.assert_array_equal(run(air_density=0.0, **windy), run(air_density=0.0))
    assert np.abs(run(**windy) - run()).max() > 1e-3, "with air the wind acts"
    under = dict(areal_density=2.0, initial_tilt=0.0, initial_height=-0.2, absorption_capacity=0.0)
    np.testing.assert_array_equal(run(**under, **windy), run(**under))


def test_bad_values_are_refused_naming_the_parameter_and_its_range():
    for name, value, allowed in [("air_density", -0.1, "0 <= air_density <= 1000 kg/m3"),
                                 ("air_density", 1001.0, "0 <= air_density <= 1000 kg/m3"),
                                 ("wind_x", 100.5, "-100 <= wind_x <= 100 m/s"),
                                 ("wind_y", math.nan, "-100 <= wind_y <= 100 m/s"),
                                 ("wind_z", -math.inf, "-100 <= wind_z <= 100 m/s")]:
        with pytest.raises(wetcloth.ParameterError, match=f"parameter '{name}'.*allowed: {allowed}"):
            wetcloth.load_scene(**{name: value})
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=3, ny=3))
    with pytest.raises(wetcloth.ParameterError, match="parameter 'air_density' is fixed once the simulation starts"):
        sim.set_inputs(air_density=0.0)
    with pytest.raises(wetcloth.ParameterError, match="'wind_x'.*allowed: -100 <= wind_x <= 100 m/s"):
        sim.set_inputs(wind_x=200.0)


def test_one_vocabulary_for_the_new_names(tmp_path, capsys):
    """Scene files, --set, Python, studies and ``wetcloth params``; the FMU variables are checked by the
    FMU tests (tests/test_fmu_build.py, tests/test_fmu_native.py)."""
    from wetcloth.batch import Study
    from wetcloth.scene import parse_text

    path = tmp_path / "windy.toml"
    path.write_text("air_density = 1.0\nwind_x = 2.0\nwind_y = -1\nwind_z = 0.5\n")
    scene = wetcloth.load_scene(path)
    assert (scene.air_density, scene.wind_x, scene.wind_y, scene.wind_z) == (1.0, 2.0, -1.0, 0.5)
    assert parse_text("air_density", "0") == 0.0 and parse_text("wind_z", "-3.5") == -3.5
    study = Study.from_dict({"duration": 1.0, "base": {"air_density": 1.0}, "axes": {"wind_x": [0.0, 4.0]}})
    assert [(r.params["air_density"], r.params["wind_x"]) for r in study.runs()] == [(1.0, 0.0), (1.0, 4.0)]
    assert main(["params", str(path), "--json"]) == 0
    rows = {r["name"]: r for r in json.loads(capsys.readouterr().out)}
    assert (rows["air_density"]["unit"], rows["air_density"]["default"], rows["air_density"]["fmu"]) == (
        "kg/m3", 1.2, "parameter")
    for name in ("wind_x", "wind_y", "wind_z"):
        assert (rows[name]["unit"], rows[name]["range"], rows[name]["fmu"]) == (
            "m/s", f"-100 <= {name} <= 100 m/s", "input")
    assert main(["run", str(path), "--duration", "0.1", "--set", "wind_z=500", "--csv",
                 str(tmp_path / "out.csv")]) == 2
    assert "parameter 'wind_z': 500.0 is out of range; allowed: -100 <= wind_z <= 100 m/s" in capsys.readouterr().err


def drag_jacobian(model, state, eps=1e-4) -> np.ndarray:
    """D = -dF/dv (3n x 3n, N s/m) of the cloth's total force at ``state`` by central differences in the
    velocities: with no spring damping, the drag's alone (gravity, buoyancy and the springs do not
    depend on them)."""
    n = model.topology.n
    columns = []
    for j in range(3 * n):
        step = np.zeros(3 * n)
        step[j] = eps
        plus = model.forces(state.pos, state.vel + step.reshape(3, n), state.water).copy()
        minus = model.forces(state.pos, state.vel - step.reshape(3, n), state.water).copy()
        columns.append(-(plus - minus).ravel() / (2.0 * eps))
    return np.array(columns).T


#: Fluids the drag's power is asked of: still water with the linear term alone (the drag linear in the
#: velocity), and a wind of 5 m/s along z with the quadratic terms (linearised about that relative motion).
FLUIDS = {
    "water": dict(initial_height=-0.2, air_density=0.0, drag_normal=0.0, drag_tangential=0.0, drag_linear=7.0),
    "wind": dict(IN_AIR, initial_height=0.0, wind_z=5.0, drag_tangential=0.5),
}


@pytest.mark.parametrize("listed", [False, True], ids=["grid", "mesh path"])
@pytest.mark.parametrize("fluid", FLUIDS.values(), ids=FLUIDS.keys())
def test_the_drag_only_takes_energy_relative_to_its_fluid(fluid, listed):
    """A drag opposes the motion relative to its fluid: the power sum_i F_i . (v_i - u) <= 0 for any
    velocities, so near any motion the symmetric part of its velocity Jacobian D = -dF/dv is positive
    semi-definite (docs/model.md 4.3).  Each triangle's drag goes to its corners with their area shares
    (1/2 at the right angle, 1/4 at the others), each share at that corner's own velocity: D is then
    block-diagonal, each block a share of the triangles' positive semi-definite dF/du.  When the drag
    acted on the triangle at its corners' plain mean velocity, D's symmetric part had eigenvalues down to
    -1.7 % of its largest on this 7 x 7 sheet (D = sum_t W_t^T J_t A_t, shares against thirds): the drag
    fed motions such as a triangle's corners moving as (0, -1, 1.5), at a rate growing with C_n |u|, and
    a sheet blown by wind_z = -40 m/s with drag_normal = 100 onto the water blew up (below).  Now the
    least eigenvalue is zero within the finite differences' error (steps of 1e-4 m/s: 1e-11 of the
    largest from rounding the forces, about (1e-4 / |u_t|)^2 from the tangential term's |u_t| u_t,
    |u_t| 1.7 m/s here); 1e-7 of the largest is allowed.  On a sheet disturbed out of its plane;
    through the grid's rows and through the mesh path's triangle list alike."""
    from support.listed import listed_from_grid
    from test_kernels import disturbed_state
    from wetcloth.model import Model

    scene = wetcloth.load_scene(nx=7, ny=7, initial_tilt=20.0, damping=0.0, **fluid)
    model, state = disturbed_state(scene, seed=3, spread=1e-2)
    if listed:
        model = Model(scene, topology=listed_from_grid(model.topology))
    state.vel[:] = 0.0
    jacobian = drag_jacobian(model, state)
    eigenvalues = np.linalg.eigvalsh(0.5 * (jacobian + jacobian.T))
    assert eigenvalues[-1] > 0.0, "the drag acts"
    assert eigenvalues[0] >= -1e-7 * eigenvalues[-1], eigenvalues[:3] / eigenvalues[-1]


def test_a_strong_wind_presses_a_strongly_dragged_sheet_under_the_surface():
    """The random trial's scene: drag_normal = 100 (its range's top) in a downward wind of 40 m/s blows
    the tilted 7 x 7 towel onto the water at nearly the wind's speed, where the water's drag (830 times
    the air's) stops it within millimetres.  Sampled at `wetcloth run`'s frames it blew up at 0.0417 s
    (1000 m/s, the message blaming stretch_stiffness), and at any tolerance its particles reached 200 m/s:
    the drag fed energy into the sheet (above).

    Now it settles as it must: the wind pushes down whatever rises into the air's share of the surface
    slab, so at 0.1 s every particle lies under the surface, the highest where that share vanishes,
    thickness/2 = 1 mm under it (up to the 0.3 um at which the air's pressure, 96 kPa at 1 - s = 1,
    balances the net buoyancy, 15 Pa), and moves far slower than the wind (0.34 m/s at most).  The run
    at the default tolerance ends within 1 mm, particle by particle, of one at a thousandth of it
    (measured 0.14 mm; the folds reach 1.3 cm under the surface)."""
    def run(tolerance):
        scene = wetcloth.load_scene(nx=7, ny=7, drag_normal=100.0, wind_z=-40.0, tolerance=tolerance)
        sim = wetcloth.Simulation(scene)
        sim.sample(np.arange(1, 4) / 30.0)  # the frames of `wetcloth run --duration 0.1`
        return sim

    default = run(wetcloth.load_scene().tolerance)
    top = default.scene.water_level - 0.5 * default.scene.thickness
    assert default.positions[:, 2].max() == pytest.approx(top, abs=1e-5)
    assert np.abs(default.state.vel).max() < 0.1 * 40.0
    finest = run(default.scene.tolerance / 1000.0)
    assert np.abs(default.positions - finest.positions).max() < 1e-3
