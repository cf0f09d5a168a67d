"""The hanging sheet of issue 25: an 81 x 81 sheet, 1 m square, pinned along its y_max edge in air,
released horizontal (water and floor far below), in frames of 1/30 s.

    .venv/bin/python bench/hanging_sheet.py [--side 81] [--duration 0.5] [--self-collision off|on|both] [--reference]
                                            [--repeat 1]

For the default (BDF2, adaptive steps), BDF2 with fixed frame steps (``tolerance = 0``,
``max_step = 1/30``) and the fixed-step mode for artists (``implicit_euler``, the same steps): CPU
time per frame, steps and rejected steps, Newton and CG iterations (CG per Newton iteration is what
the preconditioner buys), the largest error a step estimated for itself (``error_estimate``), the
largest rise of the mechanical energy from one frame to the next (``wetcloth.energy``: kinetic,
gravity, elastic; negative: it fell in every frame) and the centroid at the end.  With ``--reference``,
also the default's largest distance (over the frames) of its centroid and of any particle from a
converged reference: the same scene at tolerance REFERENCE_TOLERANCE, run in the same process.  With
``--self-collision both``, each setting runs with self-collision on, then off, and the ratio of their
times is printed (the issue's cost of self-collision, in one process); with ``--repeat N``, on and off
take turns N times and the ratio is of each one's least time (a noisy machine slows runs, never speeds
them up).  Liu et al. 2013
ran this sheet at 50 ms a frame; the issue asks for 25 ms in fixed steps and 100 ms by default.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth.energy import mechanical_energy  # noqa: E402
import _paths  # noqa: E402,F401  (tests/ on sys.path)
from support.hanging import HANGING  # noqa: E402

FRAME = 1.0 / 30.0
#: The converged reference's tolerance: a hundredth of the default's (5e-6).
REFERENCE_TOLERANCE = 5e-8


def sheet(side: int, self_collision: str, **overrides) -> wetcloth.Scene:
    return wetcloth.load_scene(nx=side, ny=side, self_collision=self_collision, **HANGING, **overrides)


def run(label: str, scene: wetcloth.Scene, duration: float) -> tuple[np.ndarray, float]:
    """Print the run's figures; return its positions (frames, n, 3) m at the end of each frame and its
    CPU time per frame (s)."""
    sim = wetcloth.Simulation(scene)
    frames = round(duration / FRAME)
    spent, worst = 0.0, 0.0
    energy, rise = mechanical_energy(sim), -np.inf
    positions = []
    for _ in range(frames):
        start = time.process_time()
        sim.advance(FRAME)
        spent += time.process_time() - start
        worst = max(worst, sim.error_estimate)
        now = mechanical_energy(sim)
        energy, rise = now, max(rise, now - energy)
        positions.append(sim.positions.copy())
    counts = sim.solver_counts
    per_newton = counts["cg_iterations"] / max(1, counts["newton_iterations"])
    x, y, z = sim.positions.mean(axis=0)
    print(f"{label:<34} {1e3 * spent / frames:8.1f} ms/frame  steps {sim.steps:5d}  rejected {sim.rejected_steps:4d}  "
          f"Newton {counts['newton_iterations']:5d}  CG/Newton {per_newton:5.1f}  "
          f"largest step error {1e3 * worst:7.3f} mm  energy rise {rise:+.1e} J  centroid ({x:+.4f}, {y:+.4f}, {z:+.4f}) m", flush=True)
    return np.array(positions), spent / frames


def compare(positions: np.ndarray, reference: np.ndarray) -> None:
    """Print the largest distance (m) over the frames of the centroid and of any particle from the reference's."""
    centroid = np.linalg.norm(positions.mean(axis=1) - reference.mean(axis=1), axis=1).max()
    particle = np.linalg.norm(positions - reference, axis=2).max()
    print(f"default against tolerance {REFERENCE_TOLERANCE:g}: centroid within {1e3 * centroid:.3f} mm, "
          f"every particle within {1e3 * particle:.2f} mm", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--side", type=int, default=81)
    parser.add_argument("--duration", type=float, default=0.5, help="simulated seconds (default 0.5)")
    parser.add_argument("--self-collision", default="off", choices=("off", "on", "both"),
                        help="off (default), on, or both in turn with the ratio of their times")
    parser.add_argument("--repeat", type=int, default=1,
                        help="with --self-collision both: runs of each, in turn; the ratio of the least times")
    parser.add_argument("--reference", action="store_true",
                        help=f"compare the default with a converged run (tolerance {REFERENCE_TOLERANCE:g})")
    args = parser.parse_args()
    print(f"{args.side} x {args.side} sheet hanging from y_max, first {args.duration:g} s, "
          f"self_collision {args.self_collision}, CPU time")
    fixed = dict(tolerance=0.0, max_step=FRAME)
    settings = [("bdf2, adaptive (default)", {}), ("bdf2, fixed frame steps", fixed),
                ("implicit_euler, fixed frame steps", dict(integrator="implicit_euler", **fixed))]
    for label, overrides in settings:
        if args.self_collision == "both":
            times = {"on": [], "off": []}
            for _ in range(args.repeat):
                for setting, spent in times.items():
                    spent.append(run(f"{label}, {setting}", sheet(args.side, setting, **overrides), args.duration)[1])
            on, off = min(times["on"]), min(times["off"])
            print(f"{label}: self-collision on takes {on / off:.2f}x the time of off"
                  + (f" (least of {args.repeat} runs each)" if args.repeat > 1 else ""), flush=True)
            continue
        positions, _ = run(label, sheet(args.side, args.self_collision, **overrides), args.duration)
        if args.reference and not overrides:
            reference, _ = run(f"bdf2, tolerance {REFERENCE_TOLERANCE:g}",
                               sheet(args.side, args.self_collision, tolerance=REFERENCE_TOLERANCE), args.duration)
            compare(positions, reference)


if __name__ == "__main__":
    main()
