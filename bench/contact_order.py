"""Order of accuracy in contact: the bead of tests/test_curved_sliding.py (a 2 mm sheet released near the top
of a frictionless ball) sliding down the ball, at fixed steps halved in turn, against the analytic bead.

    .venv/bin/python bench/contact_order.py [--steps 0.004 0.002 0.001 0.0005] [--until 0.35] [--on-ball 0.05]

For BDF2 and backward Euler at each fixed step h (``tolerance = 0``, ``max_step = h``): the bead's largest
distance every 25 ms until ``--until`` s (before it leaves the ball at 0.40 s) from the analytic one and from a
run of the same model and scheme at a step ``--fine`` times the shortest (the reference for the order: the
analytic distance has a floor of 3.3 um, the sag of the bead's centroid below its corners on the ball), the
steps, and the ratio of each error to the next (4 per halving: second order; 2: first).  With ``--on-ball S``
the bead starts on the ball at S s where and as fast as the analytic bead is then (no landing: released 3 um
above it, the bead lands within the first step, whose error at 4 ms offsets the slide's).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import test_curved_sliding as bead  # noqa: E402  (the analytic bead and its scene)


def largest(distances: np.ndarray) -> float:
    return float(np.linalg.norm(distances, axis=1).max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=float, nargs="+", default=[0.004, 0.002, 0.001, 0.0005])
    parser.add_argument("--until", type=float, default=0.35, help="simulated seconds (default 0.35)")
    parser.add_argument("--fine", type=float, default=0.125, help="the reference's step over the shortest (0.125)")
    parser.add_argument("--on-ball", type=float, default=None, help="start on the ball at this time (s)")
    args = parser.parse_args()
    leaves = bead.analytic_departure()
    exact = np.array([bead.analytic(t, leaves) for t in bead.sample_times(args.on_ball or 0.0, args.until)])
    fine_step = args.fine * min(args.steps)
    print(f"bead on a frictionless ball, until {args.until:g} s (it leaves the ball at {leaves[0]:.3f} s); "
          f"reference: the same scheme at {1e3 * fine_step:g} ms")
    print("| integrator | step | from the analytic bead | ratio | from the reference | ratio | steps |\n"
          "|---|---|---|---|---|---|---|")
    for integrator in ("bdf2", "implicit_euler"):
        reference, _ = bead.bead_path(fine_step, start=args.on_ball, until=args.until, integrator=integrator)
        rows = []
        for h in args.steps:
            path, steps = bead.bead_path(h, start=args.on_ball, until=args.until, integrator=integrator)
            rows.append((h, largest(path - exact), largest(path - reference), steps))
        for k, (h, analytic, fine, steps) in enumerate(rows):
            ratios = [f"{row / rows[k + 1][c]:.2f}" if k + 1 < len(rows) else "" for c, row in ((1, analytic), (2, fine))]
            print(f"| {integrator} | {1e3 * h:g} ms | {1e6 * analytic:.2f} um | {ratios[0]} | {1e6 * fine:.2f} um | "
                  f"{ratios[1]} | {steps} |", flush=True)


if __name__ == "__main__":
    main()
