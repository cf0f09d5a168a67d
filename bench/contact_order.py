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
from scipy.integrate import solve_ivp  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import test_curved_sliding as bead  # noqa: E402  (the analytic bead and its scene)

import wetcloth  # noqa: E402
from wetcloth.scene import load_scene  # noqa: E402


def departure():
    """The analytic departure from the ball: time (s), angle and angular speed (rad/s)."""
    sol = solve_ivp(bead.swing, [0.0, 5.0], [bead.START, 0.0], events=bead.push, rtol=1e-12, atol=1e-14)
    (t,), ((theta, omega),) = sol.t_events[0], sol.y_events[0]
    return t, theta, omega


def bead_path(step: float, integrator: str, until: float, on_ball: float | None) -> tuple[np.ndarray, int]:
    """The bead's centroid (m, one row a sample) every 25 ms up to `until` s (after `on_ball` s, set on the ball
    then, if given); its steps."""
    if on_ball is not None:
        return bead.bead_path(step, start=on_ball, until=until, integrator=integrator)
    scene = load_scene(nx=2, ny=2, width=bead.WIDTH, length=bead.WIDTH, initial_tilt=np.degrees(bead.START),
                       initial_height=bead.HEIGHT, thickness=bead.THICKNESS, water_level=-5.0, floor_level=-6.0,
                       air_density=0.0, stretch_stiffness=1e4, self_collision="off", integrator=integrator,
                       tolerance=0.0, max_step=step,
                       colliders=({"shape": "sphere", "x": 0.0, "y": bead.BALL[1], "z": bead.BALL[2],
                                   "radius": bead.RADIUS, "friction": 0.0},))
    sim = wetcloth.Simulation(scene)
    path = []
    for t in sample_times(0.0, until):
        sim.advance(t - sim.time)
        path.append(sim.state.pos.mean(axis=1))
    return np.array(path), sim.steps


def sample_times(start: float, until: float) -> np.ndarray:
    return np.arange(start + 0.025, until + 1e-9, 0.025)


def largest(distances: np.ndarray) -> float:
    return float(np.linalg.norm(distances, axis=1).max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=float, nargs="+", default=[0.004, 0.002, 0.001, 0.0005])
    parser.add_argument("--until", type=float, default=0.35, help="simulated seconds (default 0.35)")
    parser.add_argument("--fine", type=float, default=0.125, help="the reference's step over the shortest (0.125)")
    parser.add_argument("--on-ball", type=float, default=None, help="start on the ball at this time (s)")
    args = parser.parse_args()
    leaves = departure()
    exact = np.array([bead.analytic(t, leaves) for t in sample_times(args.on_ball or 0.0, args.until)])
    fine_step = args.fine * min(args.steps)
    print(f"bead on a frictionless ball, until {args.until:g} s (it leaves the ball at {leaves[0]:.3f} s); "
          f"reference: the same scheme at {1e3 * fine_step:g} ms")
    print("| integrator | step | from the analytic bead | ratio | from the reference | ratio | steps |\n"
          "|---|---|---|---|---|---|---|")
    for integrator in ("bdf2", "implicit_euler"):
        reference, _ = bead_path(fine_step, integrator, args.until, args.on_ball)
        rows = []
        for h in args.steps:
            path, steps = bead_path(h, integrator, args.until, args.on_ball)
            rows.append((h, largest(path - exact), largest(path - reference), steps))
        for k, (h, analytic, fine, steps) in enumerate(rows):
            ratios = [f"{row / rows[k + 1][c]:.2f}" if k + 1 < len(rows) else "" for c, row in ((1, analytic), (2, fine))]
            print(f"| {integrator} | {1e3 * h:g} ms | {1e6 * analytic:.2f} um | {ratios[0]} | {1e6 * fine:.2f} um | "
                  f"{ratios[1]} | {steps} |", flush=True)


if __name__ == "__main__":
    main()
