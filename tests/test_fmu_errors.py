"""Bad values and blow-ups: an FMI error or discard status and a logged message naming the variable and
its allowed range; the master survives and reads finite, last good outputs.

Every case runs in one child process (each in its own FMU instance), so that a crash fails these
tests instead of taking the test suite down with it.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from test_fmu_support import SMALL, built_fmu

from wetcloth.scene import PARAMETERS, describe_range

#: Each case: parameters set in initialization mode, then actions: ["step", h], ["set", {name: value}],
#: ["step_at", t, h] (a doStep from a given time), ["deserialize", bytes as latin-1 text].
CASES = {
    "input_out_of_range": (SMALL, [["step", 0.1], ["set", {"water_density": -1.0}], ["step", 0.1],
                                   ["set", {"water_density": 1000.0}], ["step", 0.1]]),
    "input_not_a_number": (SMALL, [["step", 0.1], ["set", {"water_level": float("nan")}], ["step", 0.1]]),
    "input_above_range": (SMALL, [["step", 0.1], ["set", {"absorption_rate": 1e9}], ["step", 0.1]]),
    "integer_parameter": (SMALL | {"ny": 1}, [["step", 0.1], ["step", 0.1]]),
    "string_parameter": (SMALL | {"drag_model": "foam"}, [["step", 0.1]]),
    "mesh_format": (SMALL | {"mesh_format": "stl"}, [["step", 0.1]]),
    "cloth_below_floor": (SMALL | {"initial_height": -2.0}, [["step", 0.1], ["set", {"initial_height": -2.0}],
                                                           ["step", 0.1]]),
    "fixed_after_initialization": (SMALL, [["step", 0.1], ["set", {"nx": 5}], ["step", 0.1], ["set", {"nx": 9}],
                                           ["step", 0.1]]),
    "blow_up": (SMALL | {"integrator": "explicit_euler", "tolerance": 0.0, "max_step": 0.01,
                         "stretch_stiffness": 1e6, "damping": 0.0}, [["step", 0.05], ["step", 0.5]]),
    "mesh_dir_is_a_file": (SMALL | {"mesh_output_dir": "@FILE@"}, [["step", 0.1]]),
    "wrong_time": (SMALL, [["step", 0.1], ["step_at", 5.0, 0.1], ["step", 0.1]]),
    "corrupt_state": (SMALL, [["step", 0.1], ["deserialize", "not a state"]]),
}

CHILD = r"""
import json, math, sys
sys.path.insert(0, sys.argv[2])
from pathlib import Path
import test_fmu_support as support
from wetcloth.simulation import OUTPUT_NAMES
support._BUILT["fmu"] = Path(sys.argv[1])
cases = json.loads(sys.stdin.read())
for name, (values, actions) in cases.items():
    unit = support.Unit(name=name, initialize=False)
    record = {"case": name, "statuses": [], "outputs": []}
    unit.fmu.setupExperiment(startTime=0.0)
    unit.fmu.enterInitializationMode()
    record["statuses"].append(["init_set", unit.set(**values)])
    record["statuses"].append(["exit_init", unit._call(unit.fmu.exitInitializationMode)])
    record["outputs"].append(unit.outputs())
    for action in actions:
        if action[0] == "step":
            status = unit.step(action[1])
        elif action[0] == "step_at":
            status = unit._call(unit.fmu.doStep, action[1], action[2])
        elif action[0] == "set":
            status = unit.set(**action[1])
        elif action[0] == "deserialize":
            status = unit._call(unit.fmu.deSerializeFMUstate, action[1].encode("latin-1"))
        record["statuses"].append([action[0], status])
        if action[0] != "deserialize":
            record["outputs"].append(unit.outputs())
    record["messages"] = unit.messages
    if action[0] != "deserialize":
        unit.close()
    print(json.dumps(record), flush=True)
# The master survives a discard inside fmpy's own simulate_fmu, too.
import fmpy
values, _ = cases["blow_up"]
try:  # FMI logging off: the reason still reaches Python's logging (stderr)
    result = fmpy.simulate_fmu(sys.argv[1], stop_time=1.0, output_interval=0.05, start_values=values)
    print(json.dumps({"case": "simulate_fmu", "raised": None, "times": result["time"].tolist(),
                      "last": {n: float(result[n][-1]) for n in OUTPUT_NAMES}}))
except Exception as exc:
    print(json.dumps({"case": "simulate_fmu", "raised": str(exc)}))
"""


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    blocker = tmp_path_factory.mktemp("errors") / "a_file"
    blocker.write_text("not a directory")
    cases = json.loads(json.dumps(CASES).replace("@FILE@", str(blocker)))
    done = subprocess.run([sys.executable, "-c", CHILD, str(built_fmu()), str(Path(__file__).parent)],
                          input=json.dumps(cases), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, f"the child master crashed ({done.returncode}):\n{done.stderr[-4000:]}"
    records = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    return {r["case"]: r for r in records} | {"stderr": done.stderr}


def error_messages(record) -> str:
    return "\n".join(text for status, text in record["messages"] if status >= 3)


def statuses(record, kind):
    return [s for k, s in record["statuses"] if k == kind]


def assert_finite_outputs(record):
    for outputs in record["outputs"]:
        assert all(math.isfinite(v) for v in outputs.values()), outputs


def assert_names_range(record, name):
    text = error_messages(record)
    assert f"'{name}'" in text and describe_range(PARAMETERS[name]) in text, text


@pytest.mark.parametrize("case, name", [("input_out_of_range", "water_density"),
                                        ("input_not_a_number", "water_level"),
                                        ("input_above_range", "absorption_rate")])
def test_bad_input_is_refused_with_its_range_and_the_step_discarded(results, case, name):
    record = results[case]
    assert statuses(record, "step")[:2] == [0, 2]  # 2 = fmi2Discard: the unit does not step
    assert_names_range(record, name)
    assert record["outputs"][3] == record["outputs"][1]  # after the refused step: the last good outputs
    assert_finite_outputs(record)


def test_a_corrected_input_lets_the_unit_step_again(results):
    record = results["input_out_of_range"]
    assert statuses(record, "step") == [0, 2, 0]
    assert record["outputs"][-1] != record["outputs"][1]


@pytest.mark.parametrize("case, name", [("integer_parameter", "ny"), ("string_parameter", "drag_model")])
def test_bad_parameter_is_refused_with_its_range(results, case, name):
    record = results[case]
    assert set(statuses(record, "step")) == {2}
    assert_names_range(record, name)
    assert_finite_outputs(record)


def test_bad_mesh_format_names_the_formats(results):
    record = results["mesh_format"]
    assert statuses(record, "step") == [2]
    assert "'mesh_format'" in error_messages(record) and "'ply', 'obj'" in error_messages(record)


def test_cloth_below_the_floor_names_initial_height_and_its_bound(results):
    record = results["cloth_below_floor"]
    assert statuses(record, "step") == [2, 2]  # setting a parameter to its own value does not make it valid
    text = error_messages(record)
    assert "'initial_height'" in text and "allowed: initial_height >" in text, text
    assert_finite_outputs(record)


def test_a_parameter_cannot_change_after_initialization(results):
    record = results["fixed_after_initialization"]
    assert statuses(record, "step") == [0, 2, 0]  # set back to the value it has, the unit steps again
    assert "'nx' is fixed once the unit is initialized" in error_messages(record)
    assert record["outputs"][3] == record["outputs"][1] != record["outputs"][-1]


def test_blow_up_discards_the_step_and_keeps_the_last_good_outputs(results):
    record = results["blow_up"]
    assert statuses(record, "step") == [0, 2]
    text = error_messages(record)
    assert "exploded" in text or "non-finite" in text
    assert "stretch_stiffness" in text and "stays at t = 0.05 s" in text, text
    assert record["outputs"][-1] == record["outputs"][1]  # rolled back to the communication point
    assert_finite_outputs(record)


def test_an_unusable_mesh_folder_names_mesh_output_dir(results):
    record = results["mesh_dir_is_a_file"]
    assert statuses(record, "step") == [2]
    assert "'mesh_output_dir'" in error_messages(record)


def test_a_step_from_the_wrong_time_is_discarded(results):
    record = results["wrong_time"]
    assert statuses(record, "step") == [0, 0] and statuses(record, "step_at") == [2]
    assert "but the unit is at t = 0.1 s" in error_messages(record)


def test_a_corrupt_serialized_state_is_refused_without_a_crash(results):
    record = results["corrupt_state"]
    assert statuses(record, "deserialize")[0] >= 3  # pythonfmu reports Python exceptions as fatal
    assert "not a serialized WetCloth FMU state" in error_messages(record)


def test_fmpy_simulate_fmu_survives_a_blow_up_and_keeps_the_last_good_outputs(results):
    """fmpy stops at the unit's last successful time (0.05 s; the cloth explodes at 0.06 s)."""
    record = results["simulate_fmu"]
    assert record["raised"] is None
    assert record["times"][-1] == pytest.approx(0.05) and record["times"][-2] == pytest.approx(0.05)
    assert all(math.isfinite(v) for v in record["last"].values())
    assert "exploded" in results["stderr"]  # logged through Python's logging although FMI logging was off
