"""Cold start: a new Python process that imports wetcloth and runs a small towel, as a fresh Dask
worker or a first ``wetcloth run`` does.

    .venv/bin/python bench/cold_start.py [--repeat 5]

Each start is a new process (``sys.executable -c CODE``) with an empty home directory: ``HOME``,
``XDG_CACHE_HOME`` and ``TMPDIR`` point to new empty folders, and it runs in another one.  It imports
wetcloth and runs 0.5 s of a 9 x 9 towel (``wetcloth.load_scene(nx=9, ny=9)``, the default
integrator).  Nothing is compiled and nothing is looked up in a cache: the compiled core is built
at install (docs/core.md).  Timed: the whole process, launch to exit (wall clock, in this process),
and ``import wetcloth`` alone (in the child); the CPU time of the child is printed too.  Target:
the whole process under 1 s, import included.  The operating system's file cache is not emptied:
after the first start the files are read from memory, as on any machine that ran Python recently.
Best (median) of ``--repeat``; the machine may be shared.

``WETCLOTH_PKGRUN=SCRIPT`` in the environment runs each child as ``python SCRIPT FILE`` (FILE holding
CODE) instead: a wrapper that runs FILE against another wetcloth than the installed one.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SCENE = dict(nx=9, ny=9)
DURATION = 0.5  # s simulated
TARGET = 1.0  # s wall, whole process

CODE = f"""
import json, time
start = time.perf_counter()
import wetcloth
imported = time.perf_counter()
sim = wetcloth.Simulation(wetcloth.load_scene(**{SCENE!r}))
sim.advance({DURATION!r})
print(json.dumps({{"import": imported - start, "run": time.perf_counter() - imported,
                  "depth": sim.outputs()["depth"], "wetcloth": wetcloth.__file__}}))
"""


def start_once(folder: Path) -> dict:
    """One start in a new process whose home, cache, temporary and working folders are new and
    empty under ``folder``: its timings (s)."""
    for name in ("home", "cache", "tmp", "cwd"):
        (folder / name).mkdir(parents=True)
    env = dict(os.environ, HOME=str(folder / "home"), XDG_CACHE_HOME=str(folder / "cache"), TMPDIR=str(folder / "tmp"))
    wrapper = os.environ.get("WETCLOTH_PKGRUN")
    if wrapper:
        script = folder / "start.py"
        script.write_text(CODE)
        argv = [sys.executable, wrapper, str(script)]
    else:
        argv = [sys.executable, "-c", CODE]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    launched = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, timeout=600, env=env, cwd=folder / "cwd")
    wall = time.perf_counter() - launched
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"start failed ({done.returncode}):\n{done.stderr[-3000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return json.loads(done.stdout.strip().splitlines()[-1]) | {"wall": wall, "cpu": cpu}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="starts; best and median (default 5)")
    args = parser.parse_args(argv)
    runs = []
    with tempfile.TemporaryDirectory(prefix="wetcloth_bench_start_") as folder:
        for k in range(args.repeat):
            result = start_once(Path(folder) / f"start{k}")
            runs.append(result)
            print(f"start {k + 1}: {result['wall']:.3f} s wall, {result['cpu']:.3f} s CPU (import "
                  f"{result['import']:.3f} s, run {result['run']:.3f} s; depth {result['depth']:.6f} m)", flush=True)
    print(f"\n{SCENE['nx']} x {SCENE['ny']} towel, {DURATION:g} s, new process with an empty home; wetcloth from "
          f"{Path(runs[0]['wetcloth']).parent}; Python {sys.version.split()[0]}; best (median) of {args.repeat}; "
          f"load average {os.getloadavg()[0]:.1f}\n")
    print("| whole process, wall (s) | CPU (s) | import wetcloth (s) | run (s) |")
    print("|---|---|---|---|")
    cells = [f"{min(r[key] for r in runs):.3f} ({statistics.median(r[key] for r in runs):.3f})"
             for key in ("wall", "cpu", "import", "run")]
    print(f"| {' | '.join(cells)} |")
    best = min(r["wall"] for r in runs)
    print(f"\ntarget: under {TARGET:g} s wall, import included: {'met' if best < TARGET else 'missed'} "
          f"(best {best:.3f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
