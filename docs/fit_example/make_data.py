"""Make the synthetic measurements of docs/fit.md: what the kitchen experiments would record for
a dishcloth whose true absorption is known, so that a fit can be checked against it.

    .venv/bin/python docs/fit_example/make_data.py

Writes measured.csv (depth read off a phone video every 2 s, wet mass weighed after timed soaks:
noise of 1 mm and 1 g) and sink_times.csv (five drops timed to 0.5 s), from dishcloth.toml with
the TRUTH below, with seeded noise.  tests/test_fit.py fits them and compares with TRUTH.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import wetcloth
from wetcloth.batch.metrics import first_crossing

HERE = Path(__file__).resolve().parent
SCENE = HERE / "dishcloth.toml"
#: The dishcloth's absorption, which the synthetic data are made with (1/s, kg/kg).
TRUTH = {"absorption_rate": 0.4, "absorption_capacity": 4.2}
VIDEO_TIMES = np.arange(0.0, 60.01, 2.0)                # s: a frame of the video read every 2 s
SOAK_TIMES = np.array([5.0, 10.0, 15.0, 20.0, 30.0, 45.0, 60.0])  # s in the water before weighing
SIGMA_DEPTH = 0.001      # m: a ruler on the box, read off the video
SIGMA_WET_MASS = 0.001   # kg: a kitchen scale
SIGMA_SINK = 0.5         # s: a drop timed with a stopwatch
SINK_DEPTH = 0.05        # m: 'sunk' once the middle of the cloth is 5 cm under
DROPS = 5
SEED = 2812


def main() -> None:
    scene = wetcloth.load_scene(SCENE, **TRUTH)
    rng = np.random.default_rng(SEED)
    times = np.union1d(VIDEO_TIMES, SOAK_TIMES)
    outputs = wetcloth.Simulation(scene).sample(times)
    depth = outputs[:, wetcloth.OUTPUT_NAMES.index("depth")] + rng.normal(0.0, SIGMA_DEPTH, times.size)
    wet = outputs[:, wetcloth.OUTPUT_NAMES.index("wet_mass")] + rng.normal(0.0, SIGMA_WET_MASS, times.size)
    lines = ["# SYNTHETIC data, made by the simulator (docs/fit_example/make_data.py), not measured: a dishcloth",
             f"# (dishcloth.toml) with absorption_rate = {TRUTH['absorption_rate']} 1/s and absorption_capacity = "
             f"{TRUTH['absorption_capacity']} kg/kg, plus noise of 1 mm and 1 g (seed {SEED}).",
             "# depth: read off a phone video every 2 s; wet_mass: weighed after timed soaks (a fresh dry cloth each).",
             "time,depth,sigma_depth,wet_mass,sigma_wet_mass"]
    for t, d, w in zip(times, depth, wet):
        video = np.isin(t, VIDEO_TIMES)
        soak = np.isin(t, SOAK_TIMES)
        lines.append(f"{t:g},{f'{d:.4f}' if video else ''},{SIGMA_DEPTH if video else ''},"
                     f"{f'{w:.4f}' if soak else ''},{SIGMA_WET_MASS if soak else ''}")
    (HERE / "measured.csv").write_text("\n".join(lines) + "\n")

    fine = np.arange(0.0, 60.0, 0.01)
    sink = first_crossing(fine, wetcloth.Simulation(scene).sample(fine)[:, wetcloth.OUTPUT_NAMES.index("depth")],
                          SINK_DEPTH, strict=True)
    timings = sink + rng.normal(0.0, SIGMA_SINK, DROPS)
    lines = ["# SYNTHETIC data, made by the simulator (docs/fit_example/make_data.py), not measured: the same",
             f"# dishcloth sinks (its middle 5 cm under) at {sink:.2f} s; five drops timed with a stopwatch (noise 0.5 s).",
             "time_to_sink"] + [f"{t:.1f}" for t in timings]
    (HERE / "sink_times.csv").write_text("\n".join(lines) + "\n")
    print(f"wrote {HERE / 'measured.csv'} and {HERE / 'sink_times.csv'} (sink time {sink:.3f} s)")


if __name__ == "__main__":
    main()
