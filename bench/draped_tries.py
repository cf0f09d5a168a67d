"""How often a cloth draping over a collider takes its steps again: a 25 x 25 towel and a round mesh
cloth (817 vertices: 16 rings of 48 quads around a fan of triangles) dropped on a ball in a pool.

    .venv/bin/python bench/draped_tries.py [--duration 0.5]

Prints CPU time, accepted and rejected steps (a step is taken again when Newton fails, its error is
too large, or particles held on the ball slip farther than the step's allowed error: docs/model.md
section 6.1), the tries per accepted step, Newton iterations and CG iterations per Newton iteration;
with ``--accuracy``, also the largest distance (mm) of a particle at the end from where a run at 1/1000
of the tolerance leaves it, for the run advanced in one call and in calls of 0.1 s, 0.05 s and 1/30 s
(where the calls end moves the steps: a drape's distance varies several fold with it, so one figure
alone says little), and their root mean square over the particles.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth.mesh_file import make_mesh  # noqa: E402

BALL = ({"shape": "sphere", "radius": 0.3},)
HEIGHT, WATER = 0.311, 0.1  # m: the cloth 11 mm above the ball's top, the pool's surface


def round_cloth(segments: int = 48, rings: int = 16, inner: float = 0.04, outer: float = 0.4):
    """A disc at HEIGHT: rings of quads from radius inner to outer (m), a centre vertex fanned to the first."""
    angles = 2 * np.pi * np.arange(segments) / segments
    radii = np.linspace(inner, outer, rings + 1)
    points = [np.column_stack([r * np.cos(angles), r * np.sin(angles), np.full(segments, HEIGHT)]) for r in radii]
    points = np.vstack(points + [[[0.0, 0.0, HEIGHT]]])
    centre = len(points) - 1
    j = np.arange(segments)
    fan = np.column_stack([np.full(segments, centre), j, (j + 1) % segments])
    k, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    k, j = k.ravel(), j.ravel()
    quads = np.column_stack([k * segments + j, (k + 1) * segments + j, (k + 1) * segments + (j + 1) % segments,
                             k * segments + (j + 1) % segments])
    return make_mesh(points, [fan, quads], shown="round cloth")


def report(label: str, scene: wetcloth.Scene, duration: float, accuracy: bool) -> None:
    sim = wetcloth.Simulation(scene)
    start = time.process_time()
    sim.advance(duration)
    spent = time.process_time() - start
    solves = sim.solver_counts
    newton = solves["newton_iterations"]
    line = (f"{label:<28} {spent:6.2f} s CPU  steps {sim.steps:5d}  rejected {sim.rejected_steps:5d}  "
            f"tries per step {(sim.steps + sim.rejected_steps) / sim.steps:4.2f}  "
            f"Newton {newton}  CG a Newton iteration {solves['cg_iterations'] / newton:.2f}")
    if accuracy:
        reference = wetcloth.Simulation(scene.replace(tolerance=scene.tolerance / 1000))
        reference.advance(duration)
        largest, rms = [], []
        for piece in (duration, 0.1, 0.05, 1 / 30):
            run = wetcloth.Simulation(scene)
            while run.time < duration - 1e-9:
                run.advance(min(piece, duration - run.time))
            distance = 1e3 * np.linalg.norm(run.positions - reference.positions, axis=1)
            largest.append(distance.max())
            rms.append(np.sqrt(np.mean(distance**2)))
        line += (f"  from the reference, advanced in one call and in 0.1, 0.05, 1/30 s: largest "
                 f"{' '.join(f'{d:.2f}' for d in largest)} mm, rms {' '.join(f'{d:.2f}' for d in rms)} mm")
    print(line, flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=0.5, help="simulated seconds (default 0.5)")
    parser.add_argument("--accuracy", action="store_true", help="also the distance from a run at 1/100 of the tolerance")
    args = parser.parse_args()
    common = dict(water_level=WATER, colliders=BALL)
    report("towel 25 x 25 on a ball", wetcloth.load_scene(nx=25, ny=25, width=0.8, length=0.8, initial_tilt=0.0,
                                                           initial_height=HEIGHT, **common), args.duration,
           args.accuracy)
    report("round mesh (817) on a ball", wetcloth.load_scene(cloth_mesh=round_cloth(), place_mesh="off", **common),
           args.duration, args.accuracy)


if __name__ == "__main__":
    main()
