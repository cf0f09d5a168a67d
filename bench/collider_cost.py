"""What colliders the cloth never touches cost (issue 26: under 5 %).

    .venv/bin/python bench/collider_cost.py [--repeat 5] [--duration 5]

The default towel at 41 x 57 lands on the water for ``--duration`` s: without colliders, with a far
analytic sphere, with the bucket mesh collider (models/meshes/bucket.ply, 1200 triangles) far away,
and with the bucket right under the floating towel, its rim 2 cm under the water (the box test
skips it too while the cloth floats above).  Each run's CPU seconds, best and median of ``--repeat`` rounds taken in turn, and the ratio
to the run without colliders; the step counts show the runs are the same.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import wetcloth  # noqa: E402
from wetcloth.scene import preset_dir  # noqa: E402

BUCKET = str(preset_dir() / "meshes" / "bucket.ply")
CASES = {
    "none": (),
    "far sphere": ({"shape": "sphere", "x": 5.0, "radius": 0.3},),
    "far bucket mesh": ({"shape": "mesh", "file": BUCKET, "x": 5.0},),
    "bucket mesh under": ({"shape": "mesh", "file": BUCKET, "z": -0.32},),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--duration", type=float, default=5.0)
    args = parser.parse_args()
    times = {name: [] for name in CASES}
    steps = {}
    for _ in range(args.repeat):
        for name, colliders in CASES.items():
            sim = wetcloth.Simulation(wetcloth.load_scene(nx=41, ny=57, colliders=colliders))
            start = time.process_time()
            sim.advance(args.duration)
            times[name].append(time.process_time() - start)
            steps[name] = sim.steps
    base = min(times["none"])
    for name, t in times.items():
        print(f"{name:<18} best {min(t):6.2f} s  median {statistics.median(t):6.2f} s  steps {steps[name]:5d}  "
              f"{min(t) / base:.3f}x of none", flush=True)


if __name__ == "__main__":
    main()
