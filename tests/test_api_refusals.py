"""The Python API refuses what it cannot run, naming the argument or parameter and what is allowed (the
hostile trial of the Python API): times past a state's latest, states of other dtypes, durations that are no
number of seconds, topologies of other cloths, files on analytic colliders; and a blow-up caused by a grip or
collider moved impossibly fast names that move."""

from __future__ import annotations

import numpy as np
import pytest

import wetcloth
from wetcloth import _core
from wetcloth.errors import BlowUpError, ParameterError
from wetcloth.scene import PARAMETERS, Collider, GripKey, Scene
from wetcloth.state import State


def small(**values) -> wetcloth.Simulation:
    return wetcloth.Simulation(wetcloth.load_scene(**(dict(nx=5, ny=5) | values)))


# ============================================================== 1. the latest time
def test_advance_and_sample_refuse_to_pass_the_latest_time_a_state_holds():
    sim = small()
    with pytest.raises(ValueError, match=r"duration: 2000000000.0 s is out of range; allowed: 0 <= duration <= "
                                         r"1e\+09 s"):
        sim.advance(2e9)
    with pytest.raises(ValueError, match=r"times: the last, 1e\+12 s, is out of range; allowed: .* to 1e\+09 s"):
        sim.sample([0.1, 1e12])
    assert sim.time == 0.0 and sim.steps == 0
    state = sim.state.copy()
    state.time = _core.MAX_TIME - 0.25
    sim.state = state
    with pytest.raises(ValueError, match=r"allowed: 0 <= duration <= 0.25 s"):
        sim.advance(0.5)
    sim.advance(0.25)  # up to the limit, and the state it ends in is one a snapshot holds
    assert sim.time == _core.MAX_TIME
    sim.restore(sim.snapshot())


# ============================================================== 2. the state's arrays
@pytest.mark.parametrize("dtype", [int, complex, np.float32])
def test_an_assigned_state_of_another_dtype_is_refused_naming_the_field(dtype):
    sim = small()
    sim.advance(0.1)
    before = sim.state.copy()
    forged = State(before.time, before.pos.astype(dtype), before.vel.copy(), before.water.copy())
    with pytest.raises(ValueError, match=rf"state.pos: expected a float64 array of shape \(3, 25\), got "
                                         rf"{np.dtype(dtype).name}"):
        sim.state = forged
    assert np.array_equal(sim.state.pos, before.pos)


def test_the_states_arrays_are_read_only_views():
    sim = small()
    state = sim.state
    with pytest.raises(ValueError, match="read-only"):
        state.water[:] = -5.0
    assert (sim.state.water >= 0.0).all()
    sim.advance(0.1)
    assert np.array_equal(state.pos, sim.state.pos)  # still the simulation's
    sim.state = state.copy()  # the way to change it


# ============================================================== 3. durations
@pytest.mark.parametrize("duration", ["1", None, np.array([0.1]), True])
def test_advance_refuses_what_is_no_number_of_seconds(duration):
    sim = small()
    with pytest.raises(TypeError, match=r"duration: expected a number, got .*; allowed: 0 <= duration <= 1e\+09 s"):
        sim.advance(duration)
    assert sim.time == 0.0


def test_whole_numbers_beyond_any_float_are_refused_naming_what_they_are():
    sim = small()
    with pytest.raises(ValueError, match=r"duration: a whole number s is out of range; allowed"):
        sim.advance(10**400)
    state = sim.state
    with pytest.raises(ValueError, match=r"state.time: a whole number above 1e\+09 s; a state's time is 0"):
        sim.state = State(10**400, state.pos.copy(), state.vel.copy(), state.water.copy())
    sim.advance(np.float64(0.05))  # NumPy's numbers are numbers
    sim.advance(1)


# ============================================================== 4. blow-ups of a move too fast
@pytest.mark.parametrize("values, inputs, says", [
    (dict(nx=5, ny=5, pinned_edge="x_min"), dict(grip_z=10000.0),
     r"the grip's inputs \(grip_z\) move the pinned particles 1e\+04 m over the 0.5 s to t = 0.5 s: 2e\+04 m/s"),
    (dict(nx=5, ny=5, pinned_edge="x_min", grip_keys=[GripKey(time=1e-6, z=1e4)]), {},
     r"grip_key1 moves the pinned particles 1e\+04 m in 1e-06 s from t = 0 s: 1e\+10 m/s"),
    (dict(path="sweep", collider_key1_time=1e-6, collider_key1_y=100.0), {},
     r"collider_key1 moves collider 1 100 m in 1e-06 s from t = 0 s: 1e\+08 m/s"),
])
def test_a_blow_up_of_a_grip_or_collider_moved_too_fast_names_the_move(values, inputs, says):
    sim = wetcloth.Simulation(wetcloth.load_scene(values.pop("path", None), **values))
    sim.set_inputs(**inputs)
    with pytest.raises(BlowUpError, match="Likely cause: " + says + r", too fast for the cloth \(it blows up at "
                                          r"1000 m/s\); make that move smaller or slower") as caught:
        sim.advance(0.5)
    assert "stretch_stiffness" not in str(caught.value)


def test_sample_names_the_grips_move_to_the_next_time():
    sim = small(pinned_edge="x_min")
    sim.set_inputs(grip_z=10000.0)
    with pytest.raises(BlowUpError, match=r"Likely cause: the grip's inputs \(grip_z\) move the pinned particles "
                                          r"1e\+04 m over the 0.25 s to t = 0.25 s: 4e\+04 m/s"):
        sim.sample([0.25, 0.5])


def test_a_blow_up_of_a_slow_grip_still_blames_the_step():
    sim = small(pinned_edge="x_min", grip_keys=[GripKey(time=1.0, z=0.1)], stretch_stiffness=1e8,
                integrator="explicit_euler", tolerance=0.0, max_step=0.01)
    with pytest.raises(BlowUpError, match="Likely cause: the step is too large for stretch_stiffness = 1e\\+08 N/m"):
        sim.advance(0.5)


# ============================================================== 5. drag_linear
def test_drag_linear_stops_where_the_model_still_runs():
    assert PARAMETERS["drag_linear"].metadata["hi"] == 1e4
    wetcloth.load_scene(drag_linear=1e4)
    with pytest.raises(ParameterError, match=r"'drag_linear': 200000.0 is out of range; allowed: 0 <= drag_linear "
                                             r"<= 10000 N s/m3"):
        wetcloth.load_scene(drag_linear=2e5)


def test_areal_density_stops_where_fabrics_start():
    """The random trial's very light cloth: at 1e-4 kg/m2 a towel in a 10 m/s wind blew up, at 1e-3 it took minutes
    a second.  The lightest allowed (5 g/m2, half the lightest fabrics') runs that wind for a second."""
    with pytest.raises(ParameterError, match=r"'areal_density': 0.001 is out of range; allowed: 0.005 <= "
                                             r"areal_density <= 100 kg/m2"):
        wetcloth.load_scene(areal_density=1e-3)
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=7, ny=7, areal_density=0.005, wind_z=-10.0))
    sim.advance(1.0)
    assert np.isfinite(sim.positions).all()


def test_cells_far_longer_than_wide_are_refused_naming_the_counts_that_square_them():
    """The random trial's 0.5 m wide, 1.1 mm long cloth of 7 x 7 (cells 455 times as long as wide) took 60 s of CPU
    for 1 s afloat.  Refused, naming both ways to squarer cells; each suggested count is accepted, and runs."""
    with pytest.raises(ParameterError, match=r"'ny': the grid's cells are 455 times longer one way than the other "
                                             r"\(width/\(nx-1\) = 0.0833 m, length/\(ny-1\) = 0.000183 m\).*allowed: "
                                             r"at most 100 times \(ny <= 2, nx >= 29, or change width or length\)"):
        wetcloth.load_scene(nx=7, ny=7, length=0.0011)
    with pytest.raises(ParameterError, match=r"'nx': .* \(nx >= 29, or change width or length\)"):
        wetcloth.load_scene(nx=2, ny=7, length=0.0011)  # ny cannot go below 2
    with pytest.raises(ParameterError, match=r"'nx': .*\(nx <= 3, ny >= 121, or change width or length\)"):
        wetcloth.load_scene(nx=7, ny=50, width=0.001, length=2.0)  # the other way round
    for squarer in (dict(ny=2), dict(nx=29)):
        sim = wetcloth.Simulation(wetcloth.load_scene(**(dict(nx=7, ny=7, length=0.0011) | squarer)))
        sim.advance(1.0)
        assert np.isfinite(sim.positions).all() and sim.steps < 5000, sim.steps
    wetcloth.load_scene(nx=2, ny=2, width=0.1, length=0.001)  # 100 times: allowed


# ============================================================== 6. what Simulation takes
def test_a_topology_of_another_cloth_is_refused_naming_topology():
    scene = wetcloth.load_scene(nx=5, ny=5)
    with pytest.raises(ParameterError, match=r"'topology': has 36 particles, the scene's cloth 25; allowed: a "
                                             r"topology of the scene's cloth"):
        wetcloth.Simulation(scene, topology=small(nx=6, ny=6).model.topology)
    with pytest.raises(ParameterError, match=r"'topology': has the scene's 25 particles at other rest positions"):
        wetcloth.Simulation(scene, topology=small(width=0.6).model.topology)
    with pytest.raises(ParameterError, match=r"'topology': expected a wetcloth.topology.Topology, got str"):
        wetcloth.Simulation(scene, topology="grid")
    wetcloth.Simulation(scene, topology=small(initial_tilt=3.0).model.topology)  # the same cloth, placed otherwise


def test_a_scene_given_by_name_is_refused_saying_how_to_load_it():
    with pytest.raises(TypeError, match=r"scene: expected a wetcloth.Scene, got str 'towel'; load one with "
                                        r"wetcloth.load_scene\('towel'\)"):
        wetcloth.Simulation("towel")


# ============================================================== 7. scenes
def test_a_file_on_an_analytic_collider_is_refused_naming_it(tmp_path):
    with pytest.raises(ParameterError, match=r"'collider1_file': a sphere collider takes no file .*; allowed: a file "
                                             r"with shape = 'mesh' only"):
        wetcloth.load_scene(colliders=[Collider(shape="sphere", file=str(tmp_path / "ball.obj"), z=-0.5)])
    with pytest.raises(ParameterError, match=r"'collider1_file': a mesh collider needs its mesh file"):
        wetcloth.load_scene(colliders=[Collider(shape="mesh", z=-0.5)])


def test_a_misspelled_scene_field_gets_the_nearest_name():
    with pytest.raises(ParameterError, match=r"'widht': unknown parameter; did you mean 'width'\?"):
        Scene(widht=0.5)
    with pytest.raises(ParameterError, match=r"'collider1_radius' is a field of a listed table"):
        Scene(collider1_radius=0.5)
    assert Scene(width=0.6).width == 0.6
