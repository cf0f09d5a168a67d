"""Start time of WetCloth.fmu in a fresh extract: cold (first start for this user) and warm (any later one).

    .venv/bin/python bench/fmu_start.py [--repeat 3] [--fmi 2]   # --fmi 3: WetCloth3.fmu

Each start is a new Python process that has numpy, numba and fmpy but not wetcloth (the editable
install is hidden from it, as on a co-simulation engineer's machine) and runs
``fmpy.simulate_fmu(WetCloth.fmu, stop_time=0.1)`` on a 5 x 5 cloth: fmpy extracts the FMU into a
new temporary folder, the unit's bootstrap finds its wetcloth and numba compiles or loads the
kernels, three communication points are computed.  Timed (wall clock): the whole ``simulate_fmu``
call, and the child process from launch to exit.

* before: the per-user copy cannot be made (``WETCLOTH_FMU_CACHE`` points below a file), so the unit
  imports the wetcloth of each extract and numba compiles every kernel at every start, as all
  starts did before the per-user copy;
* cold: an empty per-user folder: the first start copies wetcloth there and compiles;
* warm: that folder as the cold start left it, and a new extract: the kernels load from numba's cache.

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
import json, sys, time
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in getattr(f, "__module__", "").lower()]
sys.path[:] = [p for p in sys.path if "fmu_src" not in p]
import fmpy
start = time.perf_counter()
fmpy.simulate_fmu(sys.argv[1], stop_time=0.1, output_interval=0.05, start_values={"nx": 5, "ny": 5},
                  output=["depth"])
print(json.dumps({"simulate_fmu": time.perf_counter() - start, "wetcloth": sys.modules["wetcloth"].__file__}))
"""


def start_once(fmu: Path, cache: Path) -> dict:
    """One start in a new process with ``WETCLOTH_FMU_CACHE=cache``: its timings (s)."""
    launched = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", CHILD, str(fmu)], capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, WETCLOTH_FMU_CACHE=str(cache)), cwd=tempfile.gettempdir())
    if done.returncode != 0:
        raise RuntimeError(f"start failed ({done.returncode}):\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1]) | {"process": time.perf_counter() - launched}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="starts per figure; the best counts (default 3)")
    parser.add_argument("--fmi", type=int, choices=(2, 3), default=2, help="FMI version of the unit (default 2)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="wetcloth_bench_start_") as folder:
        return report(Path(folder), args)


def report(work: Path, args) -> int:
    """Build the unit in ``work``, time its starts, print the table."""
    fmu = build_fmu(work / ("WetCloth.fmu" if args.fmi == 2 else "WetCloth3.fmu"), fmi_version=args.fmi)
    blocked = work / "a_file"
    blocked.write_text("not a folder")
    figures: dict[str, list[dict]] = {"before": [], "cold": [], "warm": []}
    for k in range(args.repeat):  # interleaved, so that all see the same machine load
        figures["before"].append(start_once(fmu, blocked / "cache"))
        cache = work / f"cache{k}"
        figures["cold"].append(start_once(fmu, cache))
        figures["warm"].append(start_once(fmu, cache))
    print(f"{fmu.name} (FMI {args.fmi}.0), fresh extract per start, 5 x 5 cloth, 0.1 s; Python "
          f"{sys.version.split()[0]}; best (median) of {args.repeat}, wall clock")
    print()
    print("| start | simulate_fmu (s) | whole process (s) |")
    print("|---|---|---|")
    for name, runs in figures.items():
        cells = [f"{min(r[key] for r in runs):.1f} ({statistics.median(r[key] for r in runs):.1f})"
                 for key in ("simulate_fmu", "process")]
        print(f"| {name} | {cells[0]} | {cells[1]} |")
    best = {name: min(r["simulate_fmu"] for r in runs) for name, runs in figures.items()}
    print()
    print(f"warm start {best['before'] / best['warm']:.0f}x quicker than before; wetcloth ran from "
          f"{Path(figures['warm'][0]['wetcloth']).parent}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
