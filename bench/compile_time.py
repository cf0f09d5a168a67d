"""Cold and warm start of a first run: numba compiling every kernel, then loading them from its cache.

    .venv/bin/python bench/compile_time.py [--repeat 2] [--against main]

Each start is a new Python process that imports wetcloth and runs a 9 x 9 towel (the default scene
at ``nx = ny = 9``, default integrator) for 2 s of simulated time, so that every kernel of a run
(springs, water forces, absorption, the implicit solver, the step loop) is needed:

* cold: an empty numba cache (``NUMBA_CACHE_DIR`` set to a new folder): every kernel compiles;
* warm: the same folder as the cold start left it: the kernels load from the cache.

``--against REF`` also times the sources of git revision ``REF`` (``git archive`` into a temporary
folder, laid out as an installed package), interleaved with the working tree's, so that both see
the same machine load.  Prints wall and CPU seconds of the whole process (CPU: user + system of the
child, which is where numba compiles); best (median) of ``--repeat``.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time
start = time.perf_counter()
if sys.argv[1]:  # another revision's sources: hide the editable install of the working tree
    sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in getattr(f, "__module__", "").lower()]
    sys.path.insert(0, sys.argv[1])
import wetcloth
imported = time.perf_counter()
sim = wetcloth.Simulation(wetcloth.load_scene(nx=9, ny=9))
sim.advance(2.0)
out = sim.outputs()
print(json.dumps({"import": imported - start, "run": time.perf_counter() - imported, "depth": out["depth"],
                  "wetcloth": wetcloth.__file__}))
"""


def extract(ref: str, folder: Path) -> Path:
    """The sources of git revision ``ref`` laid out as installed (``wetcloth``, ``wetcloth.exporter``,
    ``wetcloth.presets``) under ``folder``; returns the folder to put on ``sys.path``."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", ref, "fmu_src/wetcloth", "exporter",
                              "models"], check=True, capture_output=True).stdout
    tree = folder / "tree"
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(tree, filter="data")
    site = folder / "site"
    site.mkdir()
    package = shutil.move(tree / "fmu_src" / "wetcloth", site / "wetcloth")
    shutil.move(tree / "exporter", Path(package) / "exporter")
    shutil.move(tree / "models", Path(package) / "presets")
    return site


def start_once(site: str, cache: Path) -> dict:
    """One start in a new process whose numba cache is ``cache``: its timings (s)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    launched = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", CHILD, site], capture_output=True, text=True, timeout=1800,
                          env=dict(os.environ, NUMBA_CACHE_DIR=str(cache)), cwd=tempfile.gettempdir())
    wall = time.perf_counter() - launched
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"start failed ({done.returncode}):\n{done.stderr[-3000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return json.loads(done.stdout.strip().splitlines()[-1]) | {"wall": wall, "cpu": cpu}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2, help="starts per figure; the best counts (default 2)")
    parser.add_argument("--against", metavar="REF", help="also time the sources of this git revision")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="wetcloth_bench_compile_") as folder:
        work = Path(folder)
        sources = {"working tree": ""}
        if args.against:
            sources[args.against] = str(extract(args.against, work / "ref"))
        figures = {(name, kind): [] for name in sources for kind in ("cold", "warm")}
        for k in range(args.repeat):
            for n, (name, site) in enumerate(sources.items()):
                cache = work / f"cache{n}-{k}"
                for kind in ("cold", "warm"):
                    result = start_once(site, cache)
                    figures[name, kind].append(result)
                    print(f"{name:14s} {kind}: {result['wall']:6.1f} s wall, {result['cpu']:6.1f} s CPU "
                          f"(import {result['import']:.1f} s; depth {result['depth']:.6f} m)", flush=True)
    print(f"\n9 x 9 towel, 2 s, new process; best (median) of {args.repeat}; load average "
          f"{os.getloadavg()[0]:.1f}\n")
    print("| sources | start | wall (s) | CPU (s) |")
    print("|---|---|---|---|")
    for (name, kind), runs in figures.items():
        cells = [f"{min(r[key] for r in runs):.1f} ({statistics.median(r[key] for r in runs):.1f})"
                 for key in ("wall", "cpu")]
        print(f"| {name} | {kind} | {cells[0]} | {cells[1]} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
