"""WetCloth.fmu in a second FMI master: libcosimpy, the Open Simulation Platform's co-simulation library.

libcosim loads the unit through FMI Library and steps it from its own worker threads; it runs in
a child process so that a crash there fails this test, not the suite.
"""

from __future__ import annotations

import json
import subprocess
import sys

from test_fmu_support import SMALL, assert_like_direct_runs, built_fmu

STEP_NS = 50_000_000  # libcosim counts time in integer nanoseconds: 0.05 s
STEPS = 12
RAISE_AT = 5  # step before which a manipulator raises the water level
LEVEL = 0.02  # m

CHILD = r"""
import json, sys
from fmpy import read_model_description
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimManipulator import CosimManipulator
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave
fmu, step_ns, steps, raise_at, level, values = sys.argv[1], *map(int, sys.argv[2:5]), float(sys.argv[5]), json.loads(sys.argv[6])
md = read_model_description(fmu)
vr = {v.name: v.valueReference for v in md.modelVariables}
outputs = [n for n in vr if md.modelVariables[vr[n]].causality == "output"]
execution = CosimExecution.from_step_size(step_ns)
index = execution.add_local_slave(CosimLocalSlave(fmu_path=fmu, instance_name="cloth"))
observer = CosimObserver.create_last_value()
execution.add_observer(observer)
override = CosimManipulator.create_override()
execution.add_manipulator(override)
for name, value in values.items():
    execution.integer_initial_value(index, vr[name], value)
rows = []
for k in range(steps):
    if k == raise_at:
        assert override.slave_real_values(index, [vr["water_level"]], [level])
    assert execution.step()
    rows.append({"time": execution.status().current_time * 1e-9,
                 **dict(zip(outputs, observer.last_real_values(index, [vr[n] for n in outputs])))})
print("ROWS " + json.dumps(rows), flush=True)
"""


def test_libcosim_runs_the_unit_like_a_direct_simulation(tmp_path):
    done = subprocess.run(
        [sys.executable, "-c", CHILD, str(built_fmu()), str(STEP_NS), str(STEPS), str(RAISE_AT), str(LEVEL),
         json.dumps(SMALL)],
        capture_output=True, text=True, timeout=300, cwd=tmp_path,
    )
    assert done.returncode == 0, f"libcosim master failed ({done.returncode}):\n{done.stderr[-4000:]}"
    rows = json.loads(next(line[5:] for line in done.stdout.splitlines() if line.startswith("ROWS ")))
    assert len(rows) == STEPS

    assert_like_direct_runs(rows, RAISE_AT, LEVEL, STEP_NS * 1e-9)
    # The manipulator's new level reached the cloth: it floats 2 cm higher at the end.
    assert rows[-1]["centroid_z"] > rows[RAISE_AT - 1]["centroid_z"] + 0.5 * LEVEL
