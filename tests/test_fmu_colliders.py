"""A unit built with a scene's colliders (`build-fmu --scene`) has their number fields as parameters
(collider1_radius, ...; issue 26's one vocabulary): set through fmpy, they run as `Scene.replace` does in the
Python API, in the pythonfmu units and the native one; a value out of range fails the initialization naming
the parameter and its range; batch studies on the FMU engine vary them."""

from __future__ import annotations

import numpy as np
import pytest
from test_fmu_support import message_callbacks, run_child

import wetcloth
from wetcloth.fmu import native
from wetcloth.simulation import OUTPUT_NAMES

#: The ball of tablecloth_sphere, smaller than the scene's 0.3 m: the sheet falls 4 cm further onto it.
RADIUS = 0.26
#: Communication points of the runs (s): the sheet lands on the ball at about 0.09 s.
STOP, STEP = 0.6, 0.1

#: A child process: the unit at argv[1] run for STOP s at 1 / STEP Hz with the scene's values changed by the
#: JSON argv[2], through the batch FMU engine (argv[3] "study": its values checked in Python first) or
#: wetcloth.fmu.cosim.simulate ("unit": the unit checks them); prints the outputs at every communication
#: point, or the error raised.
RUN = r"""
import json, sys
import wetcloth
from wetcloth.batch.engines import fmu_series
from wetcloth.fmu.cosim import simulate
from wetcloth.simulation import OUTPUT_NAMES
changes = json.loads(sys.argv[2])
try:
    if sys.argv[3] == "study":
        params = wetcloth.load_scene("tablecloth_sphere").replace(**changes).to_dict()
        result = fmu_series(params, 0.6, 10.0, sys.argv[1])
    else:
        result = simulate(sys.argv[1], duration=0.6, fps=10, start_values=changes, output=OUTPUT_NAMES)
    print(json.dumps({"rows": [[float(result[n][k]) for n in OUTPUT_NAMES] for k in range(len(result["time"]))]}))
except Exception as exc:
    print(json.dumps({"error": f"{type(exc).__name__}: {exc}"}))
"""


#: A child process: the FMI 2.0 unit at argv[1] with collider1_radius argv[2] stepped 0.3 s, its state
#: serialized, stepped 0.3 s more; a second instance restores the state and steps the same 0.3 s.  Prints
#: both instances' outputs and the radius the second reads before and after the restore.
STATE = r"""
import json, sys
import fmpy
from fmpy.fmi2 import FMU2Slave
from wetcloth.simulation import OUTPUT_NAMES
directory = fmpy.extract(sys.argv[1])
md = fmpy.read_model_description(directory)
vr = {v.name: v.valueReference for v in md.modelVariables}
def instance(name):
    unit = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier=md.coSimulation.modelIdentifier,
                     instanceName=name)
    unit.instantiate(loggingOn=False)
    return unit
first = instance("first")
first.setReal([vr["collider1_radius"]], [float(sys.argv[2])])
first.setupExperiment(startTime=0.0)
first.enterInitializationMode()
first.exitInitializationMode()
first.doStep(0.0, 0.3)
state = first.serializeFMUstate(first.getFMUstate())
first.doStep(0.3, 0.3)
second = instance("second")
radius = second.getReal([vr["collider1_radius"]])
second.setFMUstate(second.deSerializeFMUstate(state))
radius += second.getReal([vr["collider1_radius"]])
second.doStep(0.3, 0.3)
outputs = [vr[n] for n in OUTPUT_NAMES]
print(json.dumps({"first": first.getReal(outputs), "second": second.getReal(outputs), "radius": radius}))
"""


def python_rows(scene) -> np.ndarray:
    """The Python API's outputs at the communication points k * STEP (k = 0 ... STOP / STEP), reached as fmpy's
    units reach them: from the previous point by the step."""
    sim, rows, previous = wetcloth.Simulation(scene), [], 0.0
    for k in range(round(STOP / STEP) + 1):
        t = k * STEP
        sim.advance(max(0.0, previous + (t - previous) - sim.time))
        previous = t
        rows.append([sim.outputs()[n] for n in OUTPUT_NAMES])
    return np.array(rows)


@pytest.fixture(scope="module")
def expected():
    scene = wetcloth.load_scene("tablecloth_sphere")
    return {"as built": python_rows(scene), "smaller": python_rows(scene.replace(collider1_radius=RADIUS))}


def test_the_pythonfmu_units_take_the_colliders_fields_as_parameters(tmp_path, expected):
    """FMI 2.0 and 3.0: collider1_radius is a fixed Real parameter starting at the scene's 0.3 m; set to 0.26 m
    (FMI 2.0: by a study's run on the FMU engine) it gives the Python run of the scene with that radius
    (1e-12 m, as the other unit-against-Python tests: the same core), which lands 4 cm lower than the scene as
    built; -0.1 m is refused at initialization naming the parameter and its range.  An FMU state of the run
    holds the radius: restored in a fresh instance, whose radius is the scene's, the run goes on as the
    uninterrupted one, bit for bit.  (bb80f15: no such variable; the study's run fails as the unit carries
    "other fields"; and a state of a unit with colliders could not be serialized: scene_id's KeyError.)"""
    import fmpy

    from wetcloth.fmu.builder import build_fmu

    for version in (2, 3):
        fmu = build_fmu(tmp_path / f"Sphere{version}.fmu", fmi_version=version, scene="tablecloth_sphere")
        variable = {v.name: v for v in fmpy.read_model_description(str(fmu)).modelVariables}["collider1_radius"]
        assert (variable.causality, variable.variability, float(variable.start)) == ("parameter", "fixed", 0.3)
        (run,), _ = run_child(RUN, fmu, f'{{"collider1_radius": {RADIUS}}}', "study" if version == 2 else "unit",
                              cwd=tmp_path)
        assert "error" not in run, run
        np.testing.assert_allclose(run["rows"], expected["smaller"], rtol=0, atol=1e-12, err_msg=f"FMI {version}")
        assert expected["as built"][-1, 2] - expected["smaller"][-1, 2] > 0.03
        (refused,), _ = run_child(RUN, fmu, '{"collider1_radius": -0.1}', "unit", cwd=tmp_path)
        assert "collider1_radius" in refused["error"] and "0 < collider1_radius <= 10000 m" in refused["error"]
    (resumed,), _ = run_child(STATE, tmp_path / "Sphere2.fmu", RADIUS, cwd=tmp_path)
    assert resumed["radius"] == [0.3, RADIUS] and resumed["second"] == resumed["first"]


def test_the_native_unit_takes_the_colliders_fields_as_parameters(tmp_path, native_objects, expected):
    """The native unit's collider1_radius, set to 0.26 m through fmpy, gives the Python run of the scene with that
    radius bit for bit; -0.1 m is refused by the set call (an FMI error naming the parameter and its range); an
    FMU state of the run holds the radius: restored in a fresh instance, whose radius is the scene's, the run
    goes on as the uninterrupted one, bit for bit.  (bb80f15: no such variable.)"""
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    fmu = native.build_native_fmu(tmp_path / "sphere.fmu", 2, build_dir=native_objects, scene="tablecloth_sphere")
    result = fmpy.simulate_fmu(str(fmu), stop_time=STOP, output_interval=STEP,
                               start_values={"collider1_radius": RADIUS})
    np.testing.assert_array_equal(np.array([[row[n] for n in OUTPUT_NAMES] for row in result]), expected["smaller"])

    md = fmpy.read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    directory = fmpy.extract(str(fmu), unzipdir=str(tmp_path / "unzipped"))
    messages = []
    callbacks = message_callbacks(messages)
    first = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="first")
    first.instantiate(callbacks=callbacks, loggingOn=False)  # errors are logged with logging off too
    with pytest.raises(fmpy.fmi1.FMICallException):
        first.setReal([vr["collider1_radius"]], [-0.1])
    assert messages == [(3, "parameter 'collider1_radius': -0.1 is out of range; allowed: 0 < collider1_radius "
                            "<= 10000 m (value refused: collider1_radius stays 0.3)")]
    first.freeInstance()
    (resumed,), _ = run_child(STATE, fmu, RADIUS, cwd=tmp_path)
    assert resumed["radius"] == [0.3, RADIUS] and resumed["second"] == resumed["first"]


def test_a_study_on_the_fmu_engine_varies_a_colliders_field(tmp_path):
    """`engine = "fmu"` accepts an axis over a collider's number field (bb80f15 refused it as built into the unit)
    and still refuses one over its shape or over a key."""
    from wetcloth.batch import Study
    from wetcloth.errors import ConfigError

    study = Study.from_dict(dict(scene="tablecloth_sphere", duration=0.2, engine="fmu",
                                 axes={"collider1_radius": [0.26, 0.28]}))
    assert [run.params["collider1_radius"] for run in study.runs()] == [0.26, 0.28]
    with pytest.raises(ConfigError, match=r"axes.collider1_shape' is built into an FMU"):
        Study.from_dict(dict(scene="tablecloth_sphere", duration=0.2, engine="fmu",
                             axes={"collider1_shape": ["sphere", "box"]}))
