"""FMI rules every unit applies alike (native and pythonfmu, FMI 2.0 and 3.0): a max_step too small to advance
time, a step ending past 1e9 s or past the experiment's stop time, a stop time before the start time, illegal
call orders and a string that is not UTF-8.  Each unit runs in a child process (a crash fails a test, not the
suite)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from test_fmu_support import SMALL, built_fmu, run_child

from wetcloth.fmu import native

#: A child master: the unit at argv[1] (a folder), FMI version argv[2], the scenario argv[3]; prints one JSON
#: record {"statuses": [...], "errors": [messages of status Error or Fatal, in order]}.
MASTER = r"""
import ctypes, json, sys
import fmpy
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE)
from fmpy.fmi3 import FMU3Slave
directory, version, scenario = sys.argv[1], int(sys.argv[2]), sys.argv[3]
small = json.loads(sys.argv[4])
md = fmpy.read_model_description(directory)
var = {v.name: v for v in md.modelVariables}
errors = []

def log(*args):  # FMI 2.0: (env, instance, status, category, message); FMI 3.0: (env, status, category, message)
    if int(args[2] if version == 2 else args[1]) >= 3:
        errors.append(args[-1].decode("utf-8"))  # a message that is not UTF-8 fails here

callbacks = fmi2CallbackFunctions()
callbacks.logger = fmi2CallbackLoggerTYPE(log)
callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)

def status(call, *args, **kwargs):
    try:
        call(*args, **kwargs)
        return 0
    except FMICallException as exc:
        return int(exc.status)

def new(values):
    cls = FMU2Slave if version == 2 else FMU3Slave
    fmu = cls(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName="u")
    if version == 2:
        fmu.instantiate(callbacks=callbacks, loggingOn=True)
    else:
        fmu.instantiate(loggingOn=True, logMessage=log)
    for name, value in values.items():
        v = var[name]
        setter = {"Real": "setReal", "Float64": "setFloat64", "Integer": "setInteger", "UInt64": "setUInt64",
                  "Int64": "setInt64", "Int32": "setInt32"}[v.type]
        status(getattr(fmu, setter), [v.valueReference], [value])  # a refused value: logged, pending
    return fmu

def enter(fmu, start=0.0, stop=None):
    if version == 2:
        return [status(fmu.setupExperiment, startTime=start, stopTime=stop), status(fmu.enterInitializationMode)]
    return [status(fmu.enterInitializationMode, startTime=start, stopTime=stop)]

statuses = []
if scenario == "tiny max_step":
    fmu = new(dict(small, max_step=1e-300))
    statuses = enter(fmu) + [status(fmu.exitInitializationMode)]
elif scenario == "past 1e9":
    fmu = new(small)
    statuses = enter(fmu) + [status(fmu.exitInitializationMode), status(fmu.doStep, 0.0, 1e9),
                             status(fmu.doStep, 1e9, 0.5)]
    state = fmu.getFMUstate() if version == 2 else fmu.getFMUState()
    data = fmu.serializeFMUstate(state) if version == 2 else fmu.serializeFMUState(state)
    statuses.append(status(fmu.deSerializeFMUstate if version == 2 else fmu.deserializeFMUState, data))
elif scenario == "stop time":
    fmu = new(small)
    statuses = enter(fmu, stop=0.1) + [status(fmu.exitInitializationMode), status(fmu.doStep, 0.0, 0.05),
                                       status(fmu.doStep, 0.05, 1.0), status(fmu.doStep, 0.05, 0.05)]
elif scenario == "stop before start":
    statuses = enter(new(small), start=1.0, stop=0.5)
elif scenario == "call order":
    fmu = new(small)
    statuses = [status(fmu.terminate), status(fmu.exitInitializationMode)] + enter(fmu)
    statuses += [status(fmu.exitInitializationMode), status(fmu.exitInitializationMode)]
    statuses += enter(fmu)[-1:] + [status(fmu.terminate)] + enter(fmu)[-1:]
elif scenario == "not utf-8":
    fmu = new(small)
    values = (ctypes.c_char_p * 1)(b"\xff\xfe")
    vr = var["integrator"].valueReference
    if version == 2:
        statuses = [status(fmu.fmi2SetString, fmu.component, (ctypes.c_uint * 1)(vr), 1, values)]
    else:
        statuses = [status(fmu.fmi3SetString, fmu.component, (ctypes.c_uint32 * 1)(vr), 1, values, 1)]
print(json.dumps({"statuses": statuses, "errors": errors}))
"""


@pytest.fixture(scope="module")
def units(tmp_path_factory, native_objects) -> dict:
    """The four units' extracted folders: 'native2', 'native3' (built here) and 'python2', 'python3'."""
    import fmpy

    folder = tmp_path_factory.mktemp("rules")
    fmus = {f"python{v}": built_fmu(v) for v in (2, 3)}
    for v in (2, 3):
        fmus[f"native{v}"] = native.build_native_fmu(folder / f"WetClothNative{'' if v == 2 else 3}.fmu", v,
                                                     build_dir=native_objects)
    return {kind: Path(fmpy.extract(str(fmu), unzipdir=str(folder / kind))) for kind, fmu in fmus.items()}


def run(units, kind: str, scenario: str) -> dict:
    records, _ = run_child(MASTER, units[kind], kind[-1], scenario, json.dumps(SMALL), timeout=120)
    return records[-1]


def error_status(kind: str) -> int:
    """An FMI Error, or Fatal from pythonfmu's FMI 2.0 binary (the only error status it lets a slave give)."""
    return 4 if kind == "python2" else 3


ALL = ["native2", "native3", "python2", "python3"]


@pytest.mark.parametrize("kind", ALL)
def test_a_max_step_that_stops_time_is_refused_at_initialization(units, kind):
    """max_step = 1e-300 s was accepted; doStep(0, 0.01) then never returned (t + max_step == t)."""
    record = run(units, kind, "tiny max_step")
    if kind.startswith("native"):
        assert record["statuses"][-1] == 3, record
    else:  # the pythonfmu binaries report a refused initialization as Fatal (see test_fmu_errors.py)
        assert record["statuses"][-1] >= 3, record
    assert any("parameter 'max_step': 1e-300 is out of range; allowed: 1e-06 <= max_step <= 1 s" in m
               for m in record["errors"]), record


@pytest.mark.parametrize("kind", ALL)
def test_a_step_ending_past_1e9_s_is_refused_and_the_state_stays_usable(units, kind):
    """doStep(1e9, 0.5) returned OK; the unit then refused every step and (pythonfmu) its own FMU state."""
    record = run(units, kind, "past 1e9")
    assert record["statuses"][-3:] == [0, error_status(kind), 0], record
    assert any("t + step <= 1e+09 s" in m and "got t = 1000000000.0 s, step 0.5 s" in m
               for m in record["errors"]), record


@pytest.mark.parametrize("kind", ["native2", "native3", "python2"])
def test_a_step_past_the_stop_time_is_refused(units, kind):
    """With stopTime 0.1 s, doStep(0.05, 1.0) returned OK; a step ending at the stop time is still taken."""
    record = run(units, kind, "stop time")
    assert record["statuses"][-3:] == [0, error_status(kind), 0], record
    assert ("doStep from t = 0.05 s by 1.0 s ends past the experiment's stopTime 0.1 s; "
            "allowed: t + step <= stopTime") in " ".join(record["errors"]), record


@pytest.mark.parametrize("kind", ["native2", "native3", "python2"])
def test_a_stop_time_before_the_start_time_is_refused(units, kind):
    record = run(units, kind, "stop before start")
    assert record["statuses"][0] == error_status(kind), record
    call = "fmi3EnterInitializationMode" if kind == "native3" else "fmi2SetupExperiment"
    assert (f"{call}: stopTime 0.5 s lies before startTime 1.0 s; allowed: stopTime >= startTime"
            in " ".join(record["errors"])), record


@pytest.mark.parametrize("version", [2, 3])
def test_the_native_unit_refuses_calls_out_of_order_naming_the_call_and_state(units, version):
    """Terminate before initialization and ExitInitializationMode without Enter returned OK (the unit then
    refused every step); so did a second Enter or Exit."""
    record = run(units, f"native{version}", "call order")
    fmi = f"fmi{version}"
    ok_enter = [0, 0] if version == 2 else [0]
    assert record["statuses"] == [3, 3, *ok_enter, 0, 3, 3, 0, 3], record
    setup = "SetupExperiment" if version == 2 else "EnterInitializationMode"
    for call, state, allowed in [("Terminate", "instantiated", "initialized (stepping)"),
                                 ("ExitInitializationMode", "instantiated", "initialization mode"),
                                 ("ExitInitializationMode", "initialized (stepping)", "initialization mode"),
                                 (setup, "initialized (stepping)", "instantiated"),
                                 (setup, "terminated", "instantiated")]:
        assert (f"{fmi}{call} is not allowed in the {state} state; allowed only in the {allowed} state"
                in record["errors"]), record


@pytest.mark.parametrize("version", [2, 3])
def test_the_native_unit_logs_bytes_that_are_not_utf8_escaped(units, version):
    """The refusal of integrator = b'\\xff\\xfe' copied the raw bytes into the log (not valid text)."""
    record = run(units, f"native{version}", "not utf-8")
    assert record["statuses"] == [3], record
    message = record["errors"][0]
    assert message.startswith("parameter 'integrator': '\\xff\\xfe' is not allowed; allowed: one of"), record
