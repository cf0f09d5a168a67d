"""The native unit of a scene whose cloth comes from a mesh file (``build-fmu --native --scene``; native_mesh.py,
the core's ClothMesh): what depends on the file alone is built in as arrays, the rest computed from the unit's
parameters in C++, and the unit runs the cloth as ``wetcloth.Simulation`` does.

How close: identical.  The unit and Simulation run the same core with the same arrays (the built-in ones are
the Python front end's, written with repr's round trip; the C++ set-up keeps the Python's order of operations),
so their outputs and positions must be equal bit for bit, as for the grid's native unit (test_fmu_native.py).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from test_fmu_native import OVERLAP, advance_as_the_unit, assert_agree
from test_fmu_support import run_child

import wetcloth
from wetcloth.errors import ParameterError
from wetcloth.simulation import OUTPUT_NAMES

#: The outputs compared: the core's and the largest error estimate of the communication step's steps.
COLUMNS = (*OUTPUT_NAMES, "step_error")

native = pytest.importorskip("wetcloth.fmu.native")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs"))
import make_meshes  # noqa: E402

#: A small disc (95 vertices: band factors alone) and one above ALGEBRAIC_SIZE (755: the algebraic hierarchy).
SMALL_RINGS, LARGE_RINGS = 5, 15
#: The disc lands on water, wets and is held by a box of pins at its -y rim, which the grip moves.
SCENE = """\
cloth_mesh = "{mesh}"
place_mesh = "on"
initial_height = 0.05
initial_tilt = 20.0
absorption_rate = 0.5
wicking_rate = 1e-4
pinned_vertices = "box:-1,-1,-1,1,{pin_y},1"
"""


def write_scene(folder: Path, rings: int, name: str, pins: bool = True) -> Path:
    points, triangles = make_meshes.round_cloth(radius=0.3, rings=rings)
    make_meshes.write(folder / f"{name}.ply", points, triangles)
    text = SCENE.format(mesh=f"{name}.ply", pin_y=-0.27)
    if not pins:
        text = "\n".join(line for line in text.splitlines() if not line.startswith("pinned"))
    (folder / f"{name}.toml").write_text(text)
    return folder / f"{name}.toml"


@pytest.fixture(scope="module")
def units(tmp_path_factory, native_objects):
    """The small disc's scene and its native units (FMI 2 and 3), the large disc's and its FMI 2 unit."""
    folder = tmp_path_factory.mktemp("native_mesh")
    objects = native_objects
    small = write_scene(folder, SMALL_RINGS, "small")
    large = write_scene(folder, LARGE_RINGS, "large", pins=False)
    return {"small": small, "large": large, "objects": objects,
            2: native.build_native_fmu(folder / "small2.fmu", 2, build_dir=objects, scene=small),
            3: native.build_native_fmu(folder / "small3.fmu", 3, build_dir=objects, scene=small),
            "large2": native.build_native_fmu(folder / "large2.fmu", 2, build_dir=objects, scene=large)}


def python_rows(scene, times, signal=None):
    """Simulation's outputs at fmpy's communication points `times`, stepped as the unit steps, with the
    inputs of `signal` (time, then a column per input) set before each step as fmpy sets them; and the
    positions (n, 3) at each."""
    from fmpy.simulation import Input

    sim, rows, positions, previous = wetcloth.Simulation(scene), [], [], 0.0
    for t in times:
        if signal is not None:
            names = signal.dtype.names[1:]
            inputs, _ = Input.interpolate(time=previous, t=signal["time"], after_event=True,
                                          table=np.array([signal[n] for n in names]))
            sim.set_inputs(**dict(zip(names, map(float, inputs))))
        advance_as_the_unit(sim, t)
        rows.append([*(sim.outputs()[n] for n in OUTPUT_NAMES), sim.error_estimate])
        positions.append(sim.positions)
        previous = t
    return rows, positions


def test_the_native_units_of_a_mesh_cloth_run_it_as_the_python_api(units):
    """FMI 2 and FMI 3 units of the small disc (pinned by a box, wetting, wicking), driven through fmpy: the
    outputs of Simulation on the same scene, bit for bit; FMI 3's positions have the mesh's vertex count as
    first dimension and are Simulation.positions."""
    import fmpy

    from wetcloth.fmu.cosim import simulate

    scene = wetcloth.load_scene(units["small"])
    n = wetcloth.Simulation(scene).model.topology.n
    result = fmpy.simulate_fmu(str(units[2]), stop_time=0.3, output_interval=0.05)
    rows, _ = python_rows(scene, result["time"])
    assert_agree([[row[k] for k in COLUMNS] for row in result], rows, "FMI 2")
    three = simulate(units[3], duration=0.3, fps=20, output=[*COLUMNS, "positions", "wetness"])
    assert three["positions"].shape == (len(three["time"]), n, 3) and three["wetness"].shape == (len(three["time"]), n)
    rows, positions = python_rows(scene, three["time"])
    assert_agree([[three[k][i] for k in COLUMNS] for i in range(len(three["time"]))], rows, "FMI 3")
    np.testing.assert_array_equal(three["positions"], np.array(positions))
    assert three["water_mass"][-1] > 0 and np.ptp(three["positions"][-1][:, 2]) > 0.01  # it wets and moves


def test_tunable_parameters_change_the_run_as_in_python(units):
    """Stiffness, damping, areal_density, the placement and place_mesh set before initialisation: the
    Python run of the scene with those values, bit for bit, and another run than the built one."""
    import fmpy

    scene = wetcloth.load_scene(units["small"])
    values = {"stretch_stiffness": 3500.0, "bend_stiffness": 5.0, "damping": 0.4, "areal_density": 0.3,
              "initial_height": 0.15, "initial_tilt": 10.0}
    built = fmpy.simulate_fmu(str(units[2]), stop_time=0.2, output_interval=0.05)
    for changes in (values, {"place_mesh": "off", "initial_height": 0.3}):
        result = fmpy.simulate_fmu(str(units[2]), stop_time=0.2, output_interval=0.05, start_values=changes)
        rows, _ = python_rows(scene.replace(**changes), result["time"])
        assert_agree([[row[k] for k in COLUMNS] for row in result], rows, str(changes))
        assert np.abs(result["centroid_z"] - built["centroid_z"]).max() > 1e-4, changes


def test_the_large_mesh_with_its_algebraic_hierarchy_runs_as_the_python_api(units):
    """755 vertices: the preconditioner's algebraic multigrid (pyamg's prolongators, built in) gives the same
    run as Simulation's, bit for bit."""
    import fmpy

    scene = wetcloth.load_scene(units["large"])
    assert wetcloth.Simulation(scene).model.topology.n > wetcloth._core.ALGEBRAIC_SIZE
    result = fmpy.simulate_fmu(str(units["large2"]), stop_time=0.1, output_interval=0.05)
    rows, _ = python_rows(scene, result["time"])
    assert_agree([[row[k] for k in COLUMNS] for row in result], rows, "large mesh")


STATES = r"""
import json, sys
import fmpy
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
directory = fmpy.extract(sys.argv[1])
md = fmpy.read_model_description(directory)
var = {v.name: v.valueReference for v in md.modelVariables}
outputs = [var[n] for n in ("centroid_x", "centroid_y", "centroid_z", "water_mass")]

def unit(name):
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName=name)
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return fmu

def run(fmu, start, stop, h=0.05):
    rows, t = [], start
    while t < stop - 1e-12:
        fmu.doStep(t, h)
        t += h
        rows.append(fmu.getReal(outputs))
    return rows

a = unit("a")
run(a, 0.0, 0.1)
state = a.getFMUstate()
data = a.serializeFMUstate(state)
first = run(a, 0.1, 0.3)
a.setFMUstate(state)
again = run(a, 0.1, 0.3)
b = unit("b")
b.setFMUstate(b.deSerializeFMUstate(data))
elsewhere = run(b, 0.1, 0.3)
refused = []
for name, value in (("stretch_stiffness", 2500.0), ("bend_stiffness", 0.0), ("bend_rigidity", 0.0),
                    ("bend_rigidity", 1e-4)):
    c = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName=name)
    messages = []
    c.instantiate(callbacks=None)
    try:
        c.setReal([var[name]], [value])
        refused.append([name, 0])
    except FMICallException as exc:
        refused.append([name, int(exc.status)])
print(json.dumps({"first": first, "again": again, "elsewhere": elsewhere, "refused": refused}))
"""


def test_a_saved_state_repeats_the_run_here_and_in_another_instance(units):
    """getFMUstate / setFMUstate, and serialized into another instance: the run from 0.1 s repeats bit for bit."""
    records, _ = run_child(STATES, units[2])
    result = records[-1]
    assert result["again"] == result["first"] and result["elsewhere"] == result["first"]
    assert len(result["first"]) == 4 and result["first"][0] != result["first"][-1]


def test_what_the_built_in_mesh_fixes_is_refused_with_its_name(units):
    """bend_stiffness 0 on a mesh built with bending springs, and another stretch_stiffness on a mesh whose
    algebraic hierarchy was built for the scene's: an FMI error from the set call (the Python API would
    build another structure)."""
    small, _ = run_child(STATES, units[2])
    no_hinges = [["bend_rigidity", 0], ["bend_rigidity", 3]]  # built without hinges: 0 only
    assert small[-1]["refused"] == [["stretch_stiffness", 0], ["bend_stiffness", 3], *no_hinges]  # band factors alone
    large, _ = run_child(STATES, units["large2"])
    assert large[-1]["refused"] == [["stretch_stiffness", 3], ["bend_stiffness", 3], *no_hinges]
    import fmpy  # and each unit's model description declares the range it takes

    for unit, stiffness_fixed in ((units[2], False), (units["large2"], True)):
        declared = {v.name: v for v in fmpy.read_model_description(str(unit)).modelVariables}
        stretch, bend = declared["stretch_stiffness"], declared["bend_stiffness"]
        assert (float(stretch.min) == float(stretch.max) == float(stretch.start)) is stiffness_fixed
        assert 0.0 < float(bend.min) < 1e-300 and float(bend.max) == 1e8  # above 0: the bending springs stay


def test_a_mesh_file_that_forms_the_grid_runs_as_the_python_api(units, tmp_path):
    """A quad mesh file whose vertices form the built-in grid, off the origin, its top row pinned by a point
    attribute: Python runs it with the grid's springs from the file's start, and so do the FMI 2 and 3 units,
    bit for bit, with the built values and with another tilt and stiffness; the grid's nx and ny set on the
    unit change nothing (the file's grid is built in, as Python ignores them for a mesh)."""
    import fmpy
    import meshio

    from wetcloth.fmu.cosim import simulate

    nx, ny = 6, 5
    col, row = np.tile(np.arange(nx), ny), np.repeat(np.arange(ny), nx)
    points = np.stack([0.3 + 0.08 * col, -0.1 + 0.07 * row, np.full(nx * ny, 0.4)], axis=1)
    quads = np.array([[r * nx + c, r * nx + c + 1, (r + 1) * nx + c + 1, (r + 1) * nx + c]
                      for r in range(ny - 1) for c in range(nx - 1)], dtype=np.int32)
    meshio.write(tmp_path / "grid.ply", meshio.Mesh(points, [("quad", quads)],
                                                   point_data={"held": (row == ny - 1).astype(np.float64)}))
    (tmp_path / "grid.toml").write_text('cloth_mesh = "grid.ply"\nplace_mesh = "on"\ninitial_height = 0.2\n'
                                        'initial_tilt = 15.0\npinned_vertices = "held"\nabsorption_rate = 0.5\n')
    scene = wetcloth.load_scene(tmp_path / "grid.toml")
    topology = wetcloth.Simulation(scene).model.topology
    assert not topology.listed and (topology.nx, topology.ny) == (nx, ny) and topology.pinned.sum() == nx
    fmu2 = native.build_native_fmu(tmp_path / "grid2.fmu", 2, build_dir=units["objects"], scene=tmp_path / "grid.toml")
    fmu3 = native.build_native_fmu(tmp_path / "grid3.fmu", 3, build_dir=units["objects"], scene=tmp_path / "grid.toml")
    for changes in ({}, {"initial_tilt": 40.0, "stretch_stiffness": 2500.0, "bend_stiffness": 0.0}):
        result = fmpy.simulate_fmu(str(fmu2), stop_time=0.3, output_interval=0.05, start_values=changes)
        rows, _ = python_rows(scene.replace(**changes), result["time"])
        assert_agree([[row[k] for k in COLUMNS] for row in result], rows, str(changes))
    other_grid = fmpy.simulate_fmu(str(fmu2), stop_time=0.3, output_interval=0.05, start_values={"nx": 9, "ny": 7})
    assert_agree([[row[k] for k in COLUMNS] for row in other_grid], python_rows(scene, other_grid["time"])[0],
                 "nx and ny set")
    three = simulate(fmu3, duration=0.3, fps=20, output=[*COLUMNS, "positions"])
    rows, positions = python_rows(scene, three["time"])
    assert_agree([[three[k][i] for k in COLUMNS] for i in range(len(three["time"]))], rows, "FMI 3")
    np.testing.assert_array_equal(three["positions"], np.array(positions))
    assert np.ptp(three["positions"][-1][:, 2]) > 0.01  # it hangs from its pinned row and moves


def test_pins_by_a_point_attribute_of_the_mesh_file_run_as_the_python_api(units, tmp_path):
    """pinned_vertices naming a point attribute of the mesh file (the vertices of its -x half): the unit
    holds them as Simulation does, bit for bit, and the run differs from the box's."""
    import fmpy
    import meshio

    points, triangles = make_meshes.round_cloth(radius=0.3, rings=SMALL_RINGS)
    half = (points[:, 0] < -0.2).astype(np.float64)
    meshio.write(tmp_path / "pinned.ply", meshio.Mesh(points, [("triangle", triangles.astype(np.int32))],
                                                      point_data={"held": half}))
    text = SCENE.format(mesh="pinned.ply", pin_y=0.0).replace('"box:-1,-1,-1,1,0.0,1"', '"held"')
    (tmp_path / "pinned.toml").write_text(text)
    fmu = native.build_native_fmu(tmp_path / "pinned.fmu", 2, build_dir=units["objects"], scene=tmp_path / "pinned.toml")
    scene = wetcloth.load_scene(tmp_path / "pinned.toml")
    assert 0 < np.count_nonzero(wetcloth.Simulation(scene).model.topology.pinned) < len(points)
    result = fmpy.simulate_fmu(str(fmu), stop_time=0.2, output_interval=0.05)
    rows, _ = python_rows(scene, result["time"])
    assert_agree([[row[k] for k in COLUMNS] for row in result], rows, "attribute pins")
    box = fmpy.simulate_fmu(str(units[2]), stop_time=0.2, output_interval=0.05)
    assert np.abs(result["centroid_x"] - box["centroid_x"]).max() > 1e-3


def test_a_grid_pinned_by_a_box_runs_as_the_python_api(units, tmp_path):
    """pinned_vertices' box on the built-in grid, the grip lifting what it pins: the unit's outputs are
    Simulation's, bit for bit, with the built values and with another tilt (another start); a tilt that
    leaves the box empty fails the initialization with the Python API's message."""
    import fmpy

    scene_file = tmp_path / "pins.toml"
    scene_file.write_text('nx = 7\nny = 9\ninitial_height = 0.3\npinned_vertices = "box:-1,-1,-1,1,-0.3,1"\n')
    fmu = native.build_native_fmu(tmp_path / "pins.fmu", 2, build_dir=units["objects"], scene=scene_file)
    signal = np.array([(0.0, 0.0), (0.4, 0.2)], dtype=[("time", float), ("grip_z", float)])
    scene = wetcloth.load_scene(scene_file)
    for changes in ({}, {"initial_tilt": 30.0}):
        result = fmpy.simulate_fmu(str(fmu), stop_time=0.4, output_interval=0.05, start_values=changes, input=signal)
        rows, _ = python_rows(scene.replace(**changes), result["time"], signal)
        assert_agree([[row[k] for k in COLUMNS] for row in result], rows, str(changes))
    free = fmpy.simulate_fmu(str(fmu), stop_time=0.4, output_interval=0.05)
    assert result["centroid_z"][-1] - free["centroid_z"][-1] > 0.02  # the grip lifted the pinned row
    records, _ = run_child(OVERLAP, fmu, "initial_tilt", "80.0")
    with pytest.raises(ParameterError) as exc:
        wetcloth.load_scene(scene_file, initial_tilt=80.0)
    assert records[-1] == {"status": 3, "errors": [f"initialization refused: {exc.value}"]}


def test_a_start_below_the_floor_or_a_box_without_vertices_fails_the_initialization_as_in_python(units):
    """Values valid one by one that place the mesh below the floor, or leave the box of pins empty: the
    initialization fails with the Python API's message."""
    for name, value in (("initial_height", -1.2), ("initial_tilt", -60.0)):
        records, _ = run_child(OVERLAP, units[2], name, str(value))
        with pytest.raises(ParameterError) as exc:
            wetcloth.load_scene(units["small"], **{name: value})
        assert records[-1] == {"status": 3, "errors": [f"initialization refused: {exc.value}"]}, name


def test_a_unit_of_a_mesh_bent_by_hinges_runs_as_the_python_api_and_keeps_them(units, tmp_path):
    """The small disc bent by hinges (bend_rigidity, their terms built in with the listed springs): the FMI 2
    unit runs it as Simulation does, bit for bit, with the built rigidity and another one with bend_stiffness 0
    (unused where hinges bend); it declares bend_rigidity above 0 and refuses 0 (the hinges stay: an FMI error
    from the set call), as the unit without hinges declares and takes only 0
    (test_what_the_built_in_mesh_fixes_is_refused_with_its_name), and takes any bend_stiffness."""
    import fmpy

    path = write_scene(tmp_path, SMALL_RINGS, "hinged")
    path.write_text(path.read_text() + "bend_rigidity = 1e-4\n")
    scene = wetcloth.load_scene(path)
    assert wetcloth.Simulation(scene).model.topology.hinge_count > 0
    fmu = native.build_native_fmu(tmp_path / "hinged2.fmu", 2, build_dir=units["objects"], scene=path)
    runs = {}
    for changes in ({"bend_rigidity": 1e-4}, {"bend_rigidity": 3e-3, "bend_stiffness": 0.0}):
        result = fmpy.simulate_fmu(str(fmu), stop_time=0.2, output_interval=0.05, start_values=changes)
        rows, _ = python_rows(scene.replace(**changes), result["time"])
        assert_agree([[row[k] for k in COLUMNS] for row in result], rows, str(changes))
        runs[changes["bend_rigidity"]] = result["centroid_z"]
    assert np.abs(runs[1e-4] - runs[3e-3]).max() > 1e-6
    for unit, hinged in ((fmu, True), (units[2], False)):
        declared = {v.name: v for v in fmpy.read_model_description(str(unit)).modelVariables}
        rigidity, bend = declared["bend_rigidity"], declared["bend_stiffness"]
        assert (float(rigidity.min) > 0.0) is hinged and float(rigidity.max) == (100.0 if hinged else 0.0)
        assert (float(bend.min) == 0.0) is hinged  # hinges bend every face: any bend_stiffness, unused
    records, _ = run_child(STATES, fmu)  # (a set call the unit refuses, in a process of its own)
    assert records[-1]["refused"][1:] == [["bend_stiffness", 0], ["bend_rigidity", 3], ["bend_rigidity", 0]]


#: A child master: each (name, value) set in an instance of its own; the set call's status and the messages logged.
SETS = """
import json, sys
import fmpy
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from test_fmu_support import message_callbacks
directory = fmpy.extract(sys.argv[1])
md = fmpy.read_model_description(directory)
variables = {v.name: v for v in md.modelVariables}
for name, value in json.loads(sys.argv[2]):
    messages = []
    callbacks = message_callbacks(messages)
    unit = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName=name)
    unit.instantiate(callbacks=callbacks)
    setter = unit.setInteger if variables[name].type == "Integer" else unit.setReal
    try:
        setter([variables[name].valueReference], [value])
        status = 0
    except FMICallException as exc:
        status = int(exc.status)
    print(json.dumps({"name": name, "status": status, "messages": [m for _, m in messages]}))
"""


def test_a_unit_of_the_built_in_grid_bent_by_hinges_runs_as_the_python_api(units, tmp_path):
    """The built-in rectangle with bend_rigidity (topology._hinged_grid: the listed springs and hinges of its
    quads, started and pinned as the grid) built into a native unit: it runs as Simulation does, bit for bit,
    tilted and hanging from its pinned edge, with the built rigidity and another; it declares nx, ny, width and
    length fixed to those its hinges were built for, and refuses another value, and bend_rigidity 0, with an
    FMI error naming it.  (708bb22: a native unit of the grid refused bend_rigidity above 0.)"""
    import fmpy

    path = tmp_path / "hinged_grid.toml"
    path.write_text('nx = 9\nny = 7\nwidth = 0.4\nlength = 0.3\nbend_rigidity = 2e-5\npinned_edge = "y_max"\n'
                    "initial_tilt = 20.0\ninitial_height = 0.5\n")
    scene = wetcloth.load_scene(path)
    fmu = native.build_native_fmu(tmp_path / "hinged_grid.fmu", 2, build_dir=units["objects"], scene=path)
    ends = []
    for changes in ({}, {"bend_rigidity": 2e-4}):
        result = fmpy.simulate_fmu(str(fmu), stop_time=0.3, output_interval=0.05, start_values=changes)
        rows, _ = python_rows(scene.replace(**changes), result["time"])
        assert_agree([[row[k] for k in COLUMNS] for row in result], rows, str(changes))
        ends.append(rows[-1])
    assert abs(ends[0][2] - ends[1][2]) > 1e-5  # the rigidity acts (5e-5 m apart at 0.3 s: far above round-off)
    declared = {v.name: v for v in fmpy.read_model_description(str(fmu)).modelVariables}
    for name, value in (("nx", 9), ("ny", 7), ("width", 0.4), ("length", 0.3)):
        assert float(declared[name].min) == float(declared[name].max) == value, name
    assert float(declared["bend_rigidity"].min) > 0.0 and float(declared["bend_rigidity"].max) == 100.0  # (0, 100]
    records, _ = run_child(SETS, fmu, json.dumps([["nx", 10], ["width", 0.5], ["bend_rigidity", 0.0],
                                                  ["bend_stiffness", 0.0]]), cwd=Path(__file__).resolve().parent)
    assert [r["status"] for r in records] == [3, 3, 3, 0]
    assert records[0]["messages"][0].startswith("parameter 'nx': 10 is out of range; allowed: 9 (the hinges of this "
                                                "unit's grid were built for 9 x 7 particles; rebuild the unit")
    assert records[1]["messages"][0].startswith("parameter 'width': 0.5 is out of range; allowed: 0.4 m (the hinges")
    assert "this unit's mesh has hinges" in records[2]["messages"][0]
