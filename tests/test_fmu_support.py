"""Shared helpers of the WetCloth FMU tests: one build of each unit per test process, an fmpy instance
driver, a child-process runner.

Importable from the other ``test_fmu_*`` files (pytest puts ``tests/`` on ``sys.path``); it also
checks that the helpers themselves drive the unit.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import wetcloth
from wetcloth.simulation import OUTPUT_NAMES

#: Small, fast scene used throughout: a 9 x 9 cloth (docs/model.md's coarsest refinement level).
SMALL = {"nx": 9, "ny": 9}
#: A cloth that explodes within a fraction of a second (fixed explicit steps far above the stable step
#: of 1e6 N/m).  When exactly depends on the physics: ``last_good_time`` computes it.
BLOW_UP = SMALL | {"integrator": "explicit_euler", "tolerance": 0.0, "max_step": 0.01, "stretch_stiffness": 1e6,
                   "damping": 0.0}


def last_good_time(params: dict, interval: float, duration: float = 1.0) -> float:
    """The last communication point (s, multiple of ``interval``) that the Python simulator reaches
    with ``params`` before it blows up, computed in this process: where a unit that refuses the
    failing step stays."""
    sim = wetcloth.Simulation(wetcloth.scene.from_dict(params))
    for k in range(round(duration / interval)):
        try:
            sim.advance(interval)
        except wetcloth.BlowUpError:
            return k * interval
    raise AssertionError(f"{params} did not blow up within {duration} s")


#: A unit run by libcosim may differ from a direct run by this many times what last-bit differences of the
#: communication times alone make (measured by assert_like_direct_runs): libcosim's time arithmetic is a third
#: such path.
TIME_ROUNDING_MARGIN = 10.0


def direct_outputs(rows: list[dict], raise_at: int, level: float, interval) -> list[dict]:
    """The outputs of a Simulation of SMALL advanced by interval(sim, k) s at each of the master's ``rows``,
    with the water raised to ``level`` m before row ``raise_at``, as the master raised it."""
    sim = wetcloth.Simulation(wetcloth.Scene(**SMALL))
    outputs = []
    for k in range(len(rows)):
        if k == raise_at:
            sim.set_inputs(water_level=level)
        sim.advance(max(0.0, interval(sim, k)))
        outputs.append(sim.outputs())
    return outputs


def assert_like_direct_runs(rows: list[dict], raise_at: int, level: float, step: float) -> None:
    """Check a master's rows (time and outputs after each communication step of ``step`` s) against a
    Simulation of SMALL run directly to the rows' times.  Communication times that differ from the master's
    in the last bits (libcosim counts integer nanoseconds: ~1e-17 s) move the steps' ends, and the step
    control amplifies that into the outputs (the water's rise within a step is taken again at smaller
    steps).  How far, this process measures: the direct run again, by whole steps from the last row's time
    as the unit advances; the rows may differ from the first run by TIME_ROUNDING_MARGIN times the two
    direct runs' largest difference in each output, by 1e-12, or by 1e-9 of the value."""
    direct = direct_outputs(rows, raise_at, level, lambda sim, k: rows[k]["time"] - sim.time)
    by_steps = direct_outputs(rows, raise_at, level,
                              lambda sim, k: (rows[k - 1]["time"] if k else 0.0) + step - sim.time)
    spread = {name: max(abs(a[name] - b[name]) for a, b in zip(direct, by_steps)) for name in OUTPUT_NAMES}
    for k, (row, want) in enumerate(zip(rows, direct)):
        assert math.isclose(row["time"], (k + 1) * step, rel_tol=0.0, abs_tol=1e-12), (k, row["time"])
        for name in OUTPUT_NAMES:
            allowed = max(1e-12, TIME_ROUNDING_MARGIN * spread[name])
            assert math.isclose(row[name], want[name], rel_tol=1e-9, abs_tol=allowed), (k, name, spread[name])


_BUILT: dict[str, Path] = {}


def built_fmu(fmi_version: int = 2) -> Path:
    """WetCloth.fmu (FMI 2.0) or WetCloth3.fmu (FMI 3.0) built from the current sources, once per test process."""
    key = f"fmu{fmi_version}"
    if key not in _BUILT:
        from wetcloth.fmu.builder import build_fmu

        folder = Path(tempfile.mkdtemp(prefix="wetcloth_fmu_test_"))
        _BUILT[key] = build_fmu(folder / ("WetCloth.fmu" if fmi_version == 2 else "WetCloth3.fmu"), fmi_version)
    return _BUILT[key]


def extracted_fmu(fmi_version: int = 2) -> tuple[Path, object]:
    """The unit extracted once per process, and its model description (fmpy)."""
    key = f"dir{fmi_version}"
    if key not in _BUILT:
        from fmpy import extract, read_model_description

        _BUILT[key] = Path(extract(str(built_fmu(fmi_version))))
        _BUILT[f"md{fmi_version}"] = read_model_description(str(built_fmu(fmi_version)))
    return _BUILT[key], _BUILT[f"md{fmi_version}"]


#: A child process: fmpy runs the unit at argv[1] for argv[2] s at 0.1 s communication steps and prints the
#: last value of output argv[3].
RUN_UNIT = r"""
import json, sys
import fmpy
res = fmpy.simulate_fmu(sys.argv[1], stop_time=float(sys.argv[2]), output_interval=0.1, output=[sys.argv[3]])
print(json.dumps({sys.argv[3]: float(res[sys.argv[3]][-1])}))
"""


def run_child(code: str, *args, cwd=None, env=None, timeout: float = 300, stdin: str | None = None) -> tuple:
    """Run Python ``code`` in a child process (so that a crash of the FMU's host fails a test, not the
    suite); its JSON lines (``print(json.dumps(...))``) and the completed process."""
    done = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd, env=env, input=stdin)
    assert done.returncode == 0, f"the child master failed ({done.returncode}):\n{done.stderr[-4000:]}"
    records = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    return records, done


def call_status(call, *args, **kwargs) -> int:
    """The FMI status of an fmpy call: 0 (OK) unless it raises FMICallException (a child master's helper)."""
    from fmpy.fmi1 import FMICallException

    try:
        call(*args, **kwargs)
        return 0
    except FMICallException as exc:
        return int(exc.status)


def message_callbacks(messages: list):
    """fmpy's FMI 2.0 callbacks (fmi2CallbackFunctions) whose logger appends (status, text) to ``messages``; keep
    them alive as long as the instance given them."""
    from fmpy import calloc, free
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                           fmi2CallbackLoggerTYPE)

    def logger(env, instance, status, category, message):
        messages.append((int(status), message.decode("utf-8")))

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    return callbacks


class Unit:
    """One WetCloth instance driven through fmpy's FMU2Slave, with its log messages collected.

    ``Unit(parameters)`` instantiates with logging on, sets the parameters and initializes;
    ``step(h)`` returns the FMI status (0 ok, 2 discard, ...), never raising on a bad status.
    """

    def __init__(self, values: dict | None = None, name: str = "unit", initialize: bool = True):
        from fmpy.fmi2 import FMU2Slave

        directory, md = extracted_fmu()
        self.md = md
        self.vars = {v.name: v for v in md.modelVariables}
        self.messages: list[tuple[int, str]] = []
        self._callbacks = message_callbacks(self.messages)
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=str(directory),
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate(callbacks=self._callbacks, loggingOn=True)
        self.time = 0.0
        self.initialized = False
        if initialize:
            self.fmu.setupExperiment(startTime=0.0)
            self.fmu.enterInitializationMode()
            self.set(**(values or {}))
            self.fmu.exitInitializationMode()
            self.initialized = True

    def _call(self, function, *args) -> int:
        """Call a raw fmi2 function; its status (fmpy's wrappers raise on statuses above warning)."""
        from fmpy.fmi1 import FMICallException

        try:
            function(*args)
            return 0
        except FMICallException as exc:
            return int(exc.status)

    def set(self, **values) -> int:
        status = 0
        for name, value in values.items():
            v = self.vars[name]
            setter = {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger, "String": self.fmu.setString}[v.type]
            status = max(status, self._call(setter, [v.valueReference], [value]))
        return status

    def get(self, *names):
        values = []
        for name in names:
            v = self.vars[name]
            getter = {"Real": self.fmu.getReal, "Integer": self.fmu.getInteger, "String": self.fmu.getString}[v.type]
            value = getter([v.valueReference])[0]
            values.append(value.decode() if isinstance(value, bytes) else value)
        return values[0] if len(values) == 1 else values

    def outputs(self) -> dict[str, float]:
        return dict(zip(OUTPUT_NAMES, self.fmu.getReal([self.vars[n].valueReference for n in OUTPUT_NAMES])))

    def step(self, h: float) -> int:
        status = self._call(self.fmu.doStep, self.time, h)
        if status == 0:
            self.time += h
        return status

    def errors(self) -> list[str]:
        return [m for s, m in self.messages if s >= 3]

    def close(self) -> None:
        self._call(self.fmu.terminate)
        self.fmu.freeInstance()


def assert_same_outputs(a: dict, b: dict, rtol: float = 1e-12, atol: float = 1e-15) -> None:
    """Equal to round-off: the unit runs the same arithmetic as the direct simulation."""
    for name in OUTPUT_NAMES:
        assert math.isclose(a[name], b[name], rel_tol=rtol, abs_tol=atol), (name, a[name], b[name])


def test_unit_helper_reports_time_and_outputs():
    unit = Unit(SMALL)
    try:
        before = unit.outputs()
        sim = wetcloth.Simulation(wetcloth.Scene(**SMALL))
        assert_same_outputs(before, sim.outputs())  # initial outputs are the scene's initial state
        assert unit.step(0.1) == 0 and unit.time == 0.1
        sim.advance(0.1)
        assert_same_outputs(unit.outputs(), sim.outputs())
        assert all(np.isfinite(list(unit.outputs().values())))
    finally:
        unit.close()
