"""The artists' fixed frame steps (``implicit_euler``, ``tolerance = 0``, ``max_step`` one frame) on the
shipped presets, against the default adaptive steps run in the same process.

    .venv/bin/python bench/frame_steps.py [PRESET ...] [--duration 3] [--fps 30]

For each preset and both steppings: CPU time per frame, steps taken and taken again; for the frame
steps also the ratio of their time to the adaptive run's, the largest error a step estimated for itself
(``error_estimate``), the largest rise of the cloth's mechanical energy from one frame to the next
(``wetcloth.energy``; only a passive cloth in still air, as in ``tablecloth`` and ``tablecloth_sphere``,
must not gain any: water, wind, grips and keyed colliders do work on the others, bench/driven_energy.py weighs
it) and the median and
largest distance of a particle from where the adaptive run has it at the end.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth.energy import mechanical_energy  # noqa: E402

PRESETS = ("tablecloth", "tablecloth_sphere", "bucket", "sweep", "lift", "flag", "towel")


def run(scene: wetcloth.Scene, frames: int, fps: float) -> dict:
    """Advance scene frame by frame: CPU s, positions at the end (n, 3), largest step error (m) and largest
    energy rise between frames (J)."""
    sim = wetcloth.Simulation(scene)
    energy, rise, error, cpu = mechanical_energy(sim), -np.inf, 0.0, 0.0
    for _ in range(frames):
        start = time.process_time()
        sim.advance(1.0 / fps)
        cpu += time.process_time() - start
        error = max(error, sim.error_estimate)
        now = mechanical_energy(sim)
        rise, energy = max(rise, now - energy), now
    return {"cpu": cpu, "positions": sim.positions, "steps": sim.steps, "again": sim.rejected_steps,
            "error": error, "rise": rise}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("presets", nargs="*", default=list(PRESETS))
    parser.add_argument("--duration", type=float, default=3.0, help="simulated seconds (default 3)")
    parser.add_argument("--fps", type=float, default=30.0)
    args = parser.parse_args()
    frames = round(args.duration * args.fps)
    print(f"{args.duration:g} s at {args.fps:g} fps; ms/frame CPU; 'again': steps taken again")
    print("| preset | adaptive | frame steps | ratio | largest step error | largest energy rise | "
          "distance at the end, median / largest |")
    print("|---|---|---|---|---|---|---|")
    for name in args.presets:
        scene = wetcloth.load_scene(name)
        adaptive = run(scene, frames, args.fps)
        fixed = run(scene.replace(integrator="implicit_euler", tolerance=0.0, max_step=1.0 / args.fps), frames, args.fps)
        distance = np.linalg.norm(fixed["positions"] - adaptive["positions"], axis=1)
        print(f"| {name} | {1e3 * adaptive['cpu'] / frames:.1f} ({adaptive['steps']} steps, {adaptive['again']} again) "
              f"| {1e3 * fixed['cpu'] / frames:.1f} ({fixed['again']} again) | {fixed['cpu'] / adaptive['cpu']:.2f} "
              f"| {1e3 * fixed['error']:.1f} mm | {fixed['rise']:.2g} J "
              f"| {1e3 * np.median(distance):.1f} / {1e3 * distance.max():.1f} mm |", flush=True)


if __name__ == "__main__":
    main()
