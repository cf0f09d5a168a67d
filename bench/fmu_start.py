"""Start time of WetCloth.fmu in a fresh extract: to the end of its first doStep, in a new process.

    .venv/bin/python bench/fmu_start.py [--repeat 3] [--fmi 2]   # --fmi 3: WetCloth3.fmu

Each start is a new Python process that has numpy and fmpy but not wetcloth (the editable install
is hidden from it, as on a co-simulation engineer's machine), with an empty home directory
(``HOME``, ``XDG_CACHE_HOME`` and ``TMPDIR`` new empty folders).  It extracts the unit into a new
folder (``fmpy.extract``), loads its binary, instantiates and initializes it with a 5 x 5 cloth
(fmpy's ``FMU2Slave`` or ``FMU3Slave``; the unit's bootstrap imports the wetcloth inside the FMU,
with its compiled core: nothing is compiled at start), then takes one 0.05 s doStep.  Timed (wall
clock): from before the extraction to the end of the extraction, of the initialization and of the
first doStep, in the child; and the child process from launch to exit, in this process.

The machine may be shared: each figure is the best of ``--repeat`` (the median is printed too).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from wetcloth.fmu.builder import build_fmu

CHILD = r"""
import json, sys, tempfile, time
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in getattr(f, "__module__", "").lower()]
sys.path[:] = [p for p in sys.path if "fmu_src" not in p]
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
fmu_path, fmi = sys.argv[1], int(sys.argv[2])
start = time.perf_counter()
directory = extract(fmu_path, unzipdir=tempfile.mkdtemp())
md = read_model_description(directory)
extracted = time.perf_counter()
vr = {v.name: v.valueReference for v in md.modelVariables}
Slave = FMU2Slave if fmi == 2 else FMU3Slave
fmu = Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName="start")
fmu.instantiate()
if fmi == 2:
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["nx"], vr["ny"]], [5, 5])
else:
    fmu.setUInt64([vr["nx"], vr["ny"]], [5, 5])
    fmu.enterInitializationMode(startTime=0.0)
fmu.exitInitializationMode()
ready = time.perf_counter()
fmu.doStep(0.0, 0.05)
stepped = time.perf_counter()
fmu.terminate()
fmu.freeInstance()
print(json.dumps({"extract": extracted - start, "ready": ready - start, "first_step": stepped - start,
                  "wetcloth": sys.modules["wetcloth"].__file__}))
"""


def start_once(fmu: Path, fmi: int, folder: Path) -> dict:
    """One start in a new process whose home, cache and temporary folders are new under ``folder``."""
    for name in ("home", "cache", "tmp"):
        (folder / name).mkdir(parents=True)
    env = dict(os.environ, HOME=str(folder / "home"), XDG_CACHE_HOME=str(folder / "cache"), TMPDIR=str(folder / "tmp"))
    launched = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", CHILD, str(fmu), str(fmi)], capture_output=True, text=True,
                          timeout=600, env=env, cwd=folder / "tmp")
    if done.returncode != 0:
        raise RuntimeError(f"start failed ({done.returncode}):\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1]) | {"process": time.perf_counter() - launched}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="starts; the best counts (default 3)")
    parser.add_argument("--fmi", type=int, choices=(2, 3), default=2, help="FMI version of the unit (default 2)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="wetcloth_bench_start_") as folder:
        return report(Path(folder), args)


def report(work: Path, args) -> int:
    """Build the unit in ``work``, time its starts, print the table."""
    fmu = build_fmu(work / ("WetCloth.fmu" if args.fmi == 2 else "WetCloth3.fmu"), fmi_version=args.fmi)
    runs = [start_once(fmu, args.fmi, work / f"start{k}") for k in range(args.repeat)]
    print(f"{fmu.name} (FMI {args.fmi}.0), fresh extract per start, new process with an empty home, 5 x 5 cloth, "
          f"one 0.05 s doStep; Python {sys.version.split()[0]}; wetcloth ran from "
          f"{Path(runs[0]['wetcloth']).parent}; best (median) of {args.repeat}, wall clock")
    print()
    print("| extract (s) | to initialized (s) | to end of first doStep (s) | whole process (s) |")
    print("|---|---|---|---|")
    cells = [f"{min(r[key] for r in runs):.3f} ({statistics.median(r[key] for r in runs):.3f})"
             for key in ("extract", "ready", "first_step", "process")]
    print(f"| {' | '.join(cells)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
