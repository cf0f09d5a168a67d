"""The compiled core (C++) against the numba kernels it replaced, in one process, alternately.

    .venv/bin/pip install 'numba>=0.63' scipy       # what the numba kernels need
    .venv/bin/python bench/core_against_numba.py [--rev bf41571] [--repeat 2] [--jobs towel,sink_map,...]

(or, to leave ``.venv`` as the project installs it, ``.venv/bin/pip install --target DIR 'numba>=0.63'`` and
the run prefixed with ``PYTHONPATH=DIR``).

The numba kernels live on in git: ``--rev`` (default bf41571, the last commit with numba) is
exported to a temporary folder and imported as a second ``wetcloth`` beside the installed one, each
package's modules swapped into ``sys.modules`` before its runs (each keeps its own module tree, so
both run in this process and share its load).  Jobs, each run through the same Python calls in both:

* ``towel``: the default towel, 90 s, outputs read at 30 Hz (as the FMU and the frame export read them);
* ``sink_map``: ``models/studies/sink_map.toml``'s 16 runs through the batch runner's function
  (``wetcloth.batch.engines.python_series``);
* ``landing64``, ``landing81``: a 64 x 64 towel and an 81 x 81 sheet, the first 3 s (the landing),
  outputs at 30 Hz;
* ``hanging81``, ``hanging81_self``: issue 25's test case, the 81 x 81 sheet (1 m square) hanging from
  its y_max edge in air, released horizontal, the first 1 s at 30 Hz, self-collision off and on.

Prints each job's best wall time for both and the ratio (numba over core: above 1, the core is
faster), and the largest difference of the outputs.  At the port the two were the same algorithms,
differing by rounding; the model has changed since (docs/model.md), so the difference is now the
model's.  For the jobs whose figures issue 25 quoted from the machine it set its aims on
(ISSUE_25_MS_PER_FRAME, measured on the numba code of its day: ``--rev 3b99e00``), also the numba run's
time per frame here against the issue's: how fast this machine is against that one.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np

import _paths  # noqa: F401  (tests/ on sys.path)
from support.hanging import HANGING

ROOT = Path(__file__).resolve().parent.parent
FPS = 30.0
JOBS = ("towel", "sink_map", "landing64", "landing81", "hanging81", "hanging81_self")
#: Simulated seconds of the jobs run frame by frame.
SECONDS = {"towel": 90.0, "landing64": 3.0, "landing81": 3.0, "hanging81": 1.0, "hanging81_self": 1.0}
#: ms per 1/30 s frame that issue 25 quoted from its machine (a 2-core AMD EPYC): (least, most).
ISSUE_25_MS_PER_FRAME = {"landing81": (108.0, 108.0), "hanging81": (359.0, 359.0), "hanging81_self": (2533.0, 3185.0)}


def export_numba_package(rev: str, folder: Path) -> Path:
    """A ``wetcloth`` package of revision ``rev`` (with its presets and exporter) under ``folder``."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "fmu_src/wetcloth", "models", "exporter"],
                             check=True, capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(folder, filter="data")
    package = folder / "fmu_src" / "wetcloth"
    (folder / "models").rename(package / "presets")
    (folder / "exporter").rename(package / "exporter")
    return folder / "fmu_src"


def _wetcloth_modules() -> dict:
    return {name: module for name, module in sys.modules.items() if name == "wetcloth" or name.startswith("wetcloth.")}


class Package:
    """One imported ``wetcloth`` module tree, swapped into ``sys.modules`` while it runs."""

    def __init__(self, path: Path | None):
        for name in _wetcloth_modules():
            del sys.modules[name]
        finders = list(sys.meta_path)
        if path is not None:  # import from ``path``, not through the editable install's finder
            sys.meta_path[:] = [f for f in finders if "ScikitBuild" not in type(f).__name__]
            sys.path.insert(0, str(path))
        try:
            self.wetcloth = importlib.import_module("wetcloth")
            self.engines = importlib.import_module("wetcloth.batch.engines")
            self.spec = importlib.import_module("wetcloth.batch.spec")
            importlib.import_module("wetcloth.runner")
            importlib.import_module("wetcloth.presets")  # its own presets: scenes load them by name, later
        finally:
            sys.meta_path[:] = finders
            if path is not None:
                sys.path.remove(str(path))
        self.modules = _wetcloth_modules()

    @contextlib.contextmanager
    def active(self):
        saved = _wetcloth_modules()
        for name in saved:
            del sys.modules[name]
        sys.modules.update(self.modules)
        try:
            yield self
        finally:
            for name in _wetcloth_modules():
                del sys.modules[name]
            sys.modules.update(saved)


def frames(package: Package, seconds: float, **overrides) -> np.ndarray:
    """Outputs at every 1/FPS s frame of a run of the scene ``overrides``, read as the FMU reads them."""
    wetcloth = package.wetcloth
    sim = wetcloth.Simulation(wetcloth.load_scene(**overrides))
    rows = []
    for _ in range(int(round(seconds * FPS))):
        sim.advance(1.0 / FPS)
        rows.append(list(sim.outputs().values()))
    return np.array(rows)


def sink_map(package: Package) -> np.ndarray:
    study = package.spec.load_study(package.wetcloth.scene.preset_dir() / "studies" / "sink_map.toml")
    series = [package.engines.python_series(run.params, study.duration, study.sample_rate) for run in study.runs()]
    return np.array([[s["depth"][-1], s["wet_mass"][-1]] for s in series])


def span(low: float, high: float, spec: str) -> str:
    """``low`` (if ``high`` equals it) or ``low-high``, each formatted by ``spec``."""
    return format(low, spec) if low == high else f"{low:{spec}}-{high:{spec}}"


def job(name: str, package: Package) -> np.ndarray:
    if name == "sink_map":
        return sink_map(package)
    if name == "towel":
        return frames(package, SECONDS[name])
    if name.startswith("hanging81"):
        return frames(package, SECONDS[name], nx=81, ny=81, self_collision="on" if name.endswith("_self") else "off",
                      **HANGING)
    size = {"landing64": 64, "landing81": 81}[name]
    return frames(package, SECONDS[name], nx=size, ny=size)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rev", default="bf41571", help="the numba revision (default: the last with numba)")
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--jobs", default=",".join(JOBS))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        numba = Package(export_numba_package(args.rev, Path(folder)))
        core = Package(None)
        packages = {"numba": numba, "core": core}
        for package in packages.values():  # compile numba's kernels, untimed
            with package.active():
                frames(package, 0.2, nx=9, ny=9)
        for name in args.jobs.split(","):
            best, results = {}, {}
            for _ in range(args.repeat):
                for label, package in packages.items():
                    with package.active():
                        start = time.perf_counter()
                        results[label] = job(name, package)
                        wall = time.perf_counter() - start
                    best[label] = min(best.get(label, np.inf), wall)
                    print(f"  {name:10s} {label:6s} {wall:7.3f} s", flush=True)
            difference = np.max(np.abs(results["core"] - results["numba"]) / np.maximum(1.0, np.abs(results["numba"])))
            print(f"{name:10s} numba {best['numba']:7.3f} s, core {best['core']:7.3f} s: core {best['numba'] / best['core']:.2f}x "
                  f"(best of {args.repeat}); outputs differ by {difference:.1e} at most (relative to max(1, |value|))",
                  flush=True)
            if name in ISSUE_25_MS_PER_FRAME:
                here = 1e3 * best["numba"] / (SECONDS[name] * FPS)
                least, most = ISSUE_25_MS_PER_FRAME[name]
                print(f"{name:10s} numba here {here:.1f} ms/frame, on issue 25's machine {span(least, most, 'g')}: "
                      f"this machine {span(least / here, most / here, '.2f')}x its speed", flush=True)


if __name__ == "__main__":
    main()
