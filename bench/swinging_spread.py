"""How much the swinging sheet's error depends on the path: the 21 x 21 sheet of tests/test_accuracy.py
(1 m, pinned along y_max, swinging down in air for 0.5 s) at tolerances a few per mille to 30 % apart.

    .venv/bin/python bench/swinging_spread.py [--scales 1 0.1 0.01]

For each scale of the default tolerance, the runs at scale x (1, 1.001, 1.01, 1.03, 1.1, 1.2, 1.3):
their steps, and the largest particle and centroid distance (mm) at 0.5 s from a run at 1e-4 of the
default tolerance, in this process.  Where the spread is wide, one run's error says little about the
tolerance, and a test comparing two runs there compares paths, not settings.
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402

NUDGES = (1.0, 1.001, 1.01, 1.03, 1.1, 1.2, 1.3)
DEFAULT_TOLERANCE = wetcloth.Scene().tolerance


def swung(tolerance: float) -> wetcloth.Simulation:
    """The swinging sheet after 0.5 s at ``tolerance``."""
    scene = wetcloth.load_scene(nx=21, ny=21, width=1.0, length=1.0, pinned_edge="y_max", initial_tilt=0.0,
                                initial_height=2.0, water_level=-10.0, floor_level=-20.0, tolerance=tolerance)
    sim = wetcloth.Simulation(scene)
    sim.advance(0.5)
    return sim


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scales", type=float, nargs="+", default=[1.0, 0.1, 0.01],
                        help="scales of the default tolerance (default 1 0.1 0.01)")
    args = parser.parse_args()
    reference = swung(DEFAULT_TOLERANCE * 1e-4).positions
    print("| tolerance | steps | largest particle error, mm | centroid error, mm |")
    print("|---|---|---|---|")
    for scale in args.scales:
        runs = [swung(DEFAULT_TOLERANCE * scale * nudge) for nudge in NUDGES]
        steps = [sim.steps for sim in runs]
        largest = [1e3 * np.abs(sim.positions - reference).max() for sim in runs]
        centroid = [1e3 * np.abs(sim.positions.mean(axis=0) - reference.mean(axis=0)).max() for sim in runs]
        print(f"| {DEFAULT_TOLERANCE * scale:.0e} x {NUDGES[0]:g}..{NUDGES[-1]:g} | {min(steps)}-{max(steps)} | "
              f"{' '.join(f'{e:.3f}' for e in largest)} | {' '.join(f'{e:.3f}' for e in centroid)} |", flush=True)


if __name__ == "__main__":
    main()
