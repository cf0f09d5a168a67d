"""Speed of a two-parameter fit: the towel on a 9 x 13 grid over 60 s, ``wetcloth fit`` end to end.

    .venv/bin/python bench/fit_speed.py [--repeat 3]

Synthetic data from the towel preset (``nx = 9, ny = 13``) with absorption_rate 0.3 1/s and
absorption_capacity 3.8 kg/kg: depth and wet mass at 1 Hz from 0 to 60 s with kitchen noise
(1 mm, 1 g, seeded), given as sigma columns.  The fit starts from 0.25 1/s and 3.5 kg/kg.  Timed:
``wetcloth.calibration.fit`` in this process (the runs; best of ``--repeat``), and the command
``wetcloth fit`` in a new process (Python's start, imports, the fit and the report: fit.json,
fitted_scene.toml, fit.png).  The target (issue 28): under 30 s on 2 cores.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import wetcloth
from wetcloth.calibration import fit, read_measurements

TRUTH = {"absorption_rate": 0.3, "absorption_capacity": 3.8}
START = {"absorption_rate": 0.25, "absorption_capacity": 3.5}
GRID = {"nx": 9, "ny": 13}


def write_data(path: Path) -> None:
    scene = wetcloth.load_scene("towel", **GRID, **TRUTH)
    times = np.arange(0.0, 60.01, 1.0)
    out = wetcloth.Simulation(scene).sample(times)
    rng = np.random.default_rng(28)
    depth = out[:, wetcloth.OUTPUT_NAMES.index("depth")] + rng.normal(0.0, 1e-3, times.size)
    wet = out[:, wetcloth.OUTPUT_NAMES.index("wet_mass")] + rng.normal(0.0, 1e-3, times.size)
    rows = ["time,depth,sigma_depth,wet_mass,sigma_wet_mass"]
    rows += [f"{t:g},{d:.6f},0.001,{w:.6f},0.001" for t, d, w in zip(times, depth, wet)]
    path.write_text("\n".join(rows) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        data_path = Path(tmp) / "towel_9x13.csv"
        write_data(data_path)
        data = read_measurements(data_path)
        scene = wetcloth.load_scene("towel", **GRID, **START)
        best = np.inf
        for _ in range(args.repeat):
            start, cpu = time.perf_counter(), time.process_time()
            result = fit(scene, data, list(TRUTH))
            spent, cpu = time.perf_counter() - start, time.process_time() - cpu
            best = min(best, spent)
            print(f"fit: {spent:.2f} s wall, {cpu:.2f} s CPU, {result.runs} runs; estimates "
                  + ", ".join(f"{n} = {v:.5g} +- {s:.2g}" for n, v, s in
                              zip(result.names, result.estimates, result.standard_errors)), flush=True)
        command = [str(Path(sys.executable).with_name("wetcloth")), "fit", "towel", "--data", str(data_path),
                   "--params", ",".join(TRUTH), "--out", str(Path(tmp) / "report"), "--no-progress",
                   *(f"--set={k}={v}" for k, v in {**GRID, **START}.items())]
        start = time.perf_counter()
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL, env=os.environ)
        whole = time.perf_counter() - start
    print(f"\ntwo-parameter fit, towel 9 x 13 over 60 s ({result.runs} runs, {os.cpu_count()} cores): "
          f"{best:.2f} s (best of {args.repeat}); 'wetcloth fit' end to end with its report {whole:.2f} s "
          f"(target: under 30 s)")


if __name__ == "__main__":
    main()
