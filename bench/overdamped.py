"""Overdamped springs: the hanging sheet (1 m square, pinned along its y_max edge in air, released
horizontal) swung 1 s in frames of 1/30 s at the default tolerance, against the same scene at
REFERENCE_TOLERANCE (a hundredth of the default) run in the same process, for each spring damping.

    .venv/bin/python bench/overdamped.py [--sides 11 21] [--damping 0.2 100 1000 10000 100000]
                                         [--integrator bdf2]

Prints per side and damping: the damping ratio of the stiffest springs' mode (over 1, the adaptive
steps' linear solves are tightened: docs/model.md section 7), the largest distance over the frames of
the default's centroid from the reference's, the default's steps, Newton and CG iterations and CPU time,
and that time against the default damping's (0.2 N s/m; 1.0 when it is the default).
"""

from __future__ import annotations

import argparse
import math
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from hanging_sheet import FRAME, REFERENCE_TOLERANCE, sheet as hanging_sheet  # noqa: E402

DURATION = 1.0


def sheet(side: int, damping: float, tolerance: float, integrator: str) -> wetcloth.Scene:
    """The hanging sheet (self-collision on, the default) with these settings."""
    return hanging_sheet(side, "on", damping=damping, tolerance=tolerance, integrator=integrator)


def swing(scene: wetcloth.Scene) -> tuple[np.ndarray, float, wetcloth.Simulation]:
    """The centroid (frames, 3) m at each frame's end, the CPU time (s) and the simulation."""
    sim = wetcloth.Simulation(scene)
    centroids, spent = [], 0.0
    for _ in range(round(DURATION / FRAME)):
        start = time.process_time()
        sim.advance(FRAME)
        spent += time.process_time() - start
        centroids.append(sim.positions.mean(axis=0))
    return np.array(centroids), spent, sim


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sides", type=int, nargs="+", default=[11, 21])
    parser.add_argument("--damping", type=float, nargs="+", default=[0.2, 100.0, 1e3, 1e4, 1e5], help="N s/m")
    parser.add_argument("--integrator", default="bdf2", choices=["bdf2", "implicit_euler"])
    args = parser.parse_args()
    for side in args.sides:
        baseline = None
        for damping in args.damping:
            default = sheet(side, damping, wetcloth.Scene().tolerance, args.integrator)
            control = wetcloth.Simulation(default)._control
            ratio = control.damping_rate / (2.0 * math.sqrt(control.omega_squared))
            reference, _, _ = swing(sheet(side, damping, REFERENCE_TOLERANCE, args.integrator))
            centroids, spent, sim = swing(default)
            baseline = spent if baseline is None else baseline
            counts = sim.solver_counts
            error = np.linalg.norm(centroids - reference, axis=1).max()
            print(f"{side} x {side} damping {damping:8g} N s/m (damping ratio {ratio:8.3g}): centroid within "
                  f"{1e3 * error:6.3f} mm  steps {sim.steps:4d}  Newton {counts['newton_iterations']:5d}  "
                  f"CG {counts['cg_iterations']:6d}  CPU {spent:6.2f} s ({spent / baseline:5.1f}x the first damping's)",
                  flush=True)


if __name__ == "__main__":
    main()
