"""Order of accuracy in contact: the bead of tests/test_curved_sliding.py (a 2 mm sheet released near the top
of a frictionless ball) sliding down the ball, at fixed steps halved in turn, against the analytic bead.

    .venv/bin/python bench/contact_order.py [--steps 0.004 0.002 0.001 0.0005] [--until 0.35]

For BDF2 and backward Euler at each fixed step h (``tolerance = 0``, ``max_step = h``): the bead's largest
distance from the analytic one every 25 ms until ``--until`` s (before it leaves the ball at 0.40 s), the
steps, and the ratio of each error to the next (4 per halving: second order; 2: first).
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


def largest_error(step: float, integrator: str, until: float, leaves) -> tuple[float, int]:
    """The bead's largest distance (m) from the analytic one every 25 ms up to `until` s; its steps."""
    scene = load_scene(nx=2, ny=2, width=bead.WIDTH, length=bead.WIDTH, initial_tilt=np.degrees(bead.START),
                       initial_height=bead.HEIGHT, thickness=bead.THICKNESS, water_level=-5.0, floor_level=-6.0,
                       air_density=0.0, stretch_stiffness=1e4, self_collision="off", integrator=integrator,
                       tolerance=0.0, max_step=step,
                       colliders=({"shape": "sphere", "x": 0.0, "y": bead.BALL[1], "z": bead.BALL[2],
                                   "radius": bead.RADIUS, "friction": 0.0},))
    sim = wetcloth.Simulation(scene)
    worst = 0.0
    for t in np.arange(0.025, until + 1e-9, 0.025):
        sim.advance(t - sim.time)
        worst = max(worst, float(np.linalg.norm(sim.state.pos.mean(axis=1) - bead.analytic(t, leaves))))
    return worst, sim.steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=float, nargs="+", default=[0.004, 0.002, 0.001, 0.0005])
    parser.add_argument("--until", type=float, default=0.35, help="simulated seconds (default 0.35)")
    args = parser.parse_args()
    leaves = departure()
    print(f"bead on a frictionless ball, until {args.until:g} s (it leaves the ball at {leaves[0]:.3f} s)")
    print("| integrator | step | largest error | steps | ratio to the next |\n|---|---|---|---|---|")
    for integrator in ("bdf2", "implicit_euler"):
        rows = [(h, *largest_error(h, integrator, args.until, leaves)) for h in args.steps]
        for k, (h, error, steps) in enumerate(rows):
            ratio = f"{error / rows[k + 1][1]:.2f}" if k + 1 < len(rows) else ""
            print(f"| {integrator} | {1e3 * h:g} ms | {1e6 * error:.2f} um | {steps} | {ratio} |", flush=True)


if __name__ == "__main__":
    main()
