"""The grip (docs/model.md section 6.4): the pinned particles follow a prescribed displacement, from
keys in the scene ([[grip_key]]) and from the inputs grip_x, grip_y, grip_z, with the displacement's
rate as their velocity, under every integrator."""

import re

import numpy as np
import pytest

import wetcloth
from wetcloth.errors import BlowUpError, ConfigError, ParameterError
from wetcloth.scene import load_scene

INTEGRATORS = ["bdf2", "implicit_euler", "symplectic_euler", "explicit_euler"]


def assert_each(vectors: np.ndarray, expected, atol: float) -> None:
    """Every column of vectors (3, m) is the vector expected (3) within atol (m or m/s)."""
    error = np.abs(vectors - np.asarray(expected, dtype=float)[:, None]).max()
    assert error <= atol, (error, expected)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_a_soaked_towel_lifted_out_of_the_water_keeps_its_water_and_hangs_from_the_grip(integrator):
    """The lift preset: a soaked towel on the water, held by its y_min edge, lifted 0.8 m from 1 s to
    5 s.  The pinned edge sits at its start + the keys' displacement (+0.4 m at 3 s, +0.8 m from 5 s)
    within 1 um, moving at the keys' rate (0.2 m/s) while they rise and still after; the towel follows
    it out of the water (every particle above the surface at 8 s) with its water mass unchanged to
    the bit: it was saturated, and there is no drip model (nor drying: drying_rate 0).  The explicit
    schemes on a 7 x 9 grid (their steps are set by stability), the implicit ones on the preset's."""
    grid = {} if integrator in ("bdf2", "implicit_euler") else dict(nx=7, ny=9)
    sim = wetcloth.Simulation(load_scene("lift", integrator=integrator, **grid))
    pinned = sim.model.topology.pinned
    start, water = sim.state.pos[:, pinned].copy(), sim.state.water.sum()
    for t, lift, rate in ((1.0, 0.0, 0.0), (3.0, 0.4, 0.2), (5.0, 0.8, 0.2), (8.0, 0.8, 0.0)):
        sim.advance(t - sim.time)
        state = sim.state
        assert_each(state.pos[:, pinned] - start, (0.0, 0.0, lift), 1e-6)
        assert_each(state.vel[:, pinned], (0.0, 0.0, rate), 1e-9)
    assert state.water.sum() == water
    assert state.pos[2].min() > sim.scene.water_level + sim.scene.thickness


def test_a_towel_lifted_half_soaked_keeps_the_water_it_took_up_while_in_the_water():
    """The lift preset with the towel at 0.3 of its capacity: it takes up water until the grip has
    lifted it out (every particle above the surface at 5 s), then not a gram more or less (no drip, no
    drying)."""
    sim = wetcloth.Simulation(load_scene("lift", initial_saturation=0.3))
    start = sim.state.water.sum()
    sim.advance(5.0)
    lifted = sim.state.water.sum()
    assert lifted > start and sim.state.pos[2].min() > sim.scene.water_level + sim.scene.thickness
    sim.advance(3.0)
    assert sim.state.water.sum() == lifted


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_a_towel_dragged_along_the_water_moves_its_edge_at_the_grips_rate_while_it_soaks(integrator):
    """The lift preset's towel at 0.3 of its capacity dragged along x (0.3 m in 1 s) instead of lifted: its
    pinned edge, half in the water (initial_height 0), takes up water as it moves, and still moves at the keys' 0.3 m/s (the
    uptake's rescaling of velocities, which keeps momentum as masses grow, spares the pinned particles)."""
    scene = load_scene("lift", nx=7, ny=9, initial_height=0.0, initial_saturation=0.3, grip_keys=[dict(time=1.0, x=0.3)],
                       integrator=integrator)
    sim = wetcloth.Simulation(scene)
    pinned = sim.model.topology.pinned
    water = sim.state.water[pinned].copy()
    sim.advance(0.5)
    assert (sim.state.water[pinned] > water).all()
    assert_each(sim.state.vel[:, pinned], (0.3, 0.0, 0.0), 1e-9)


def test_a_cloth_does_not_fall_asleep_while_grip_keys_lie_ahead():
    """A hanging sheet is still after ~3 s (it falls asleep by 5 s without keys: the test below), but a
    key at 6 s lifts its edge 0.1 m from 5 s: it stays awake until then, and the edge is lifted."""
    scene = load_scene(nx=7, ny=9, width=0.2, length=0.3, initial_tilt=90.0, pinned_edge="y_max", initial_height=0.5,
                       water_level=-0.5, self_collision="off", grip_key1_time=5.0, grip_key2_time=6.0, grip_key2_z=0.1)
    sim = wetcloth.Simulation(scene)
    pinned = sim.model.topology.pinned
    start = sim.state.pos[:, pinned].copy()
    sim.advance(6.0)
    assert_each(sim.state.pos[:, pinned] - start, (0.0, 0.0, 0.1), 1e-6)
    sim.advance(3.0)
    assert sim.sleeping  # and after the last key it may


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_a_hanging_sheet_moved_by_the_grip_inputs_comes_to_rest_translated(integrator):
    """A sheet hanging in air from its y_max edge comes to rest (falls asleep); the inputs then move the
    grip by (0.2, 0, 0.3) m, reached linearly over the next advance (1 s), and the sheet swings and comes
    to rest again: its rest shape is the first one translated by the grip's displacement, as the springs
    and gravity have the same equilibrium about the moved edge.  Tolerance 5e-5 m, a tenth of the sleep
    rule's 0.5 mm (both rests are where the cloth fell asleep; measured 0.007-5 um)."""
    scene = load_scene(nx=7, ny=9, width=0.2, length=0.3, initial_tilt=90.0, pinned_edge="y_max", initial_height=0.5,
                       water_level=-0.5, self_collision="off", integrator=integrator)
    sim = wetcloth.Simulation(scene)
    sim.advance(5.0)
    assert sim.sleeping
    rest = sim.state.pos.copy()
    pinned = sim.model.topology.pinned
    sim.set_inputs(grip_x=0.2, grip_z=0.3)
    sim.advance(1.0)
    assert_each(sim.state.pos[:, pinned] - rest[:, pinned], (0.2, 0.0, 0.3), 1e-6)
    # the last step's velocity is the ramp's: the displacement over the advance
    assert_each(sim.state.vel[:, pinned], (0.2, 0.0, 0.3), 1e-9)
    sim.advance(7.0)
    assert sim.sleeping
    assert_each(sim.state.pos - rest, (0.2, 0.0, 0.3), 5e-5)


@pytest.mark.parametrize("moved_by", ["keys", "inputs"])
def test_a_state_taken_while_the_grip_moves_restores_and_runs_on_to_the_bit(moved_by):
    """A snapshot taken while the grip moves the pinned particles (at its rate, so their velocities are not
    zero) is restored, and the run from it repeats the run that went on, bit for bit.  (Before, restoring it
    was refused: "pinned particles do not move"; a native unit could then not go back from a failed step.)"""
    scene = load_scene("lift", nx=7, ny=9) if moved_by == "keys" else load_scene(
        nx=7, ny=9, initial_tilt=90.0, pinned_edge="y_max", initial_height=0.5)
    sim = wetcloth.Simulation(scene)
    sim.advance(1.5)
    if moved_by == "inputs":
        sim.set_inputs(grip_x=0.1, grip_z=0.2)
        sim.advance(0.3)
    pinned = sim.model.topology.pinned
    assert np.abs(sim.state.vel[:, pinned]).max() > 0.01  # the grip moves them
    snapshot = sim.snapshot()
    sim.advance(0.5)
    went_on = sim.snapshot()
    sim.restore(snapshot)
    sim.advance(0.5)
    np.testing.assert_array_equal(sim.state.pos, went_on["state"].pos)
    np.testing.assert_array_equal(sim.state.vel, went_on["state"].vel)


#: The sweep's towel after its ball has swept through it (the ball then at (0, 0.3, 0.35) m, radius 0.12 m), and
#: grip inputs that carry its pinned top edge (y = 0, z = 0.85 m) to y = 0.3, z = 0.35 m, into the ball, over the
#: next 0.1 s.
PRESSED_AFTER, PRESSING, RAMP = 2.5, dict(grip_y=0.3, grip_z=-0.5), 0.1


def test_a_blow_up_from_a_grip_pressing_pinned_particles_into_a_collider_says_so():
    """Contact pushes those pinned particles back out to thickness / 2 at every step while the grip puts them
    back in, until the cloth blows up; the message names that, not the springs' stiffness."""
    sim = wetcloth.Simulation(load_scene("sweep"))
    sim.advance(PRESSED_AFTER)
    sim.set_inputs(**PRESSING)
    with pytest.raises(BlowUpError) as caught:
        sim.advance(RAMP)
        sim.advance(1.0)
    message = str(caught.value)
    pressed = re.search(r"Likely cause: the grip presses pinned particle (\d+) into collider 1 \(a sphere\)", message)
    assert pressed, message
    assert "stretch_stiffness" not in message
    i = int(pressed.group(1))
    assert sim.model.cloth.free[i] == 0.0
    centre = np.array([0.0, 0.3, 0.35])  # the ball, where its keys left it
    assert np.linalg.norm(sim.state.pos[:, i] - centre) < 0.12 + 0.5 * sim.scene.thickness * (1 + 1e-6)


def test_without_a_grip_a_pinned_cloth_runs_as_before():
    """Keys and inputs at zero leave the pinned particles where they are, to the bit (the grip only acts
    once it is displaced), and a grip key that holds still changes nothing either."""
    base = dict(nx=7, ny=9, initial_tilt=90.0, pinned_edge="y_max", initial_height=0.5)
    plain = wetcloth.Simulation(load_scene(**base))
    still = wetcloth.Simulation(load_scene(**base, grip_key1_time=0.5, grip_key1_z=0.0))
    for sim in (plain, still):
        sim.advance(1.0)
    np.testing.assert_array_equal(still.state.pos, plain.state.pos)
    assert still.steps == plain.steps


def test_the_inputs_add_to_the_keys():
    """Keys and inputs together: the displacement is their sum (keys lift 0.1 m by 1 s, the input moves
    x by 0.05 m over the same advance)."""
    scene = load_scene(nx=7, ny=9, initial_tilt=90.0, pinned_edge="y_max", initial_height=0.5,
                       grip_key1_time=1.0, grip_key1_z=0.1)
    sim = wetcloth.Simulation(scene)
    pinned = sim.model.topology.pinned
    start = sim.state.pos[:, pinned].copy()
    sim.set_inputs(grip_x=0.05)
    sim.advance(1.0)
    assert_each(sim.state.pos[:, pinned] - start, (0.05, 0.0, 0.1), 1e-6)


def test_the_grip_moves_vertices_pinned_by_pinned_vertices_too():
    """A corner pinned by ``pinned_vertices`` (a box around it at t = 0) instead of an edge: the keys lift
    it 0.3 m in 1 s, moving at their 0.3 m/s."""
    scene = load_scene(nx=7, ny=9, initial_tilt=0.0, pinned_vertices="box:0.2,0.3,0.0,0.3,0.4,0.2",
                       grip_key1_time=1.0, grip_key1_z=0.3)
    sim = wetcloth.Simulation(scene)
    pinned = sim.model.topology.pinned
    assert np.flatnonzero(pinned).tolist() == [7 * 9 - 1]  # the (x_max, y_max) corner
    start = sim.state.pos[:, pinned].copy()
    sim.advance(1.0)
    assert_each(sim.state.pos[:, pinned] - start, (0.0, 0.0, 0.3), 1e-6)
    assert_each(sim.state.vel[:, pinned], (0.0, 0.0, 0.3), 1e-9)


def test_grip_keys_by_their_flattened_names_in_params_set_and_study_axes(tmp_path):
    """[[grip_key]] tables read in order as grip_key1, grip_key2; each field has one name everywhere."""
    from wetcloth.batch.axes import check_name, typed
    from wetcloth.commands.params import rows
    from wetcloth.scene import parse_text

    scene = load_scene("lift")
    assert [(k.time, k.z) for k in scene.grip_keys] == [(1.0, 0.0), (5.0, 0.8)]
    assert scene.to_dict()["grip_key2_z"] == 0.8
    assert scene.replace(grip_key2_z=0.5).grip_keys[1].z == 0.5
    assert scene.replace(grip_key3_time=6.0, grip_key3_x=0.2).grip_keys[2].x == 0.2
    assert parse_text("grip_key1_time", "2") == 2.0
    listed = {r["name"]: r for r in rows("lift")}
    assert listed["grip_key2_z"]["value"] == 0.8 and listed["grip_key2_time"]["range"] == "0 < grip_key2_time <= 1e+06 s"
    assert listed["grip_z"]["fmu"] == "input" and listed["grip_z"]["unit"] == "m"
    check_name("grip_key1_z", "axes")
    check_name("grip_x", "axes")
    assert typed("grip_key1_z", 1, "axes") == 1.0


@pytest.mark.parametrize("keys, name, words", [
    ([dict(time=2.0, z=0.1), dict(time=1.0, z=0.2)], "grip_key2_time", "is not after grip_key1_time = 2.0 s"),
    ([dict(time=1.0), dict(time=1.0, z=0.2)], "grip_key2_time", "allowed: key times that increase"),
    ([dict(time=0.0, z=0.1)], "grip_key1_time", "0 < grip_key1_time <= 1e+06 s"),
    ([dict(z=0.1)], "grip_key1_time", "a grip key needs its time"),
    ([dict(time=1.0, w=0.1)], "grip_key1_w", "unknown grip key field"),
    ([dict(time=1.0, z=2e4)], "grip_key1_z", "-10000 <= grip_key1_z <= 10000 m"),
])
def test_bad_grip_keys_are_named_with_their_allowed_range(keys, name, words):
    with pytest.raises(ParameterError) as info:
        load_scene(pinned_edge="y_min", grip_keys=keys)
    assert name in str(info.value) and words in str(info.value)


def test_grip_keys_without_pinned_particles_and_bad_tables_are_refused(tmp_path):
    with pytest.raises(ParameterError, match="grip_key1.*none are pinned.*pinned_edge"):
        load_scene(grip_key1_time=1.0, grip_key1_z=0.1)
    with pytest.raises(ParameterError, match="grip_key3_z.*there is no grip key 2"):
        load_scene(pinned_edge="y_min", grip_key1_time=1.0, grip_key3_z=0.1)
    path = tmp_path / "scene.toml"
    path.write_text('pinned_edge = "y_min"\ngrip_key = 3\n')
    with pytest.raises(ConfigError, match=r"grip keys are \[\[grip_key\]\] tables"):
        load_scene(path)
    path.write_text('pinned_edge = "y_min"\n[[grip_key]]\ntime = 2.0\n[[grip_key]]\ntime = 1.5\n')
    with pytest.raises(ConfigError, match="grip_key2_time"):
        load_scene(path)


def test_a_unit_built_with_a_scene_moves_the_grip_by_its_keys(tmp_path):
    """`wetcloth build-fmu --scene lift`: the unit carries the scene's [[grip_key]] tables (they are not
    variables) and, run for 1.5 s, gives the Python run's outputs, the run advanced to fmpy's
    communication points k * 0.1 s (equal to round-off, 1e-12 m).  Without the keys the edge stays on
    the water: by 1.5 s the keys have lifted it 0.1 m and the centroid is centimetres higher."""
    from test_fmu_support import RUN_UNIT, run_child

    from wetcloth.fmu.builder import build_fmu

    fmu = build_fmu(tmp_path / "Lift.fmu", scene="lift")
    run, _ = run_child(RUN_UNIT, fmu, "1.5", "centroid_z", cwd=tmp_path)
    heights = []
    for scene in (load_scene("lift"), load_scene("lift").replace(grip_keys=())):
        sim = wetcloth.Simulation(scene)
        for k in range(1, 16):
            sim.advance(k * 0.1 - sim.time)
        heights.append(sim.outputs()["centroid_z"])
    assert run[-1]["centroid_z"] == pytest.approx(heights[0], rel=0, abs=1e-12)
    assert heights[0] - heights[1] > 0.01
