"""A sheet of quads bent by hinges (``bend_rigidity``) against the same sheet on its bending springs, in one
process: a 0.2 m square of 31 x 31 vertices hanging from its x = 0 edge in air, released flat, for 2 s, at the
default adaptive steps and at fixed frame steps (``implicit_euler``, ``tolerance = 0``, ``max_step`` 1/24 s).

    .venv/bin/python bench/quad_hinges.py [--side 31] [--rigidity 1e-4] [--jitter 0.2] [--repeat 2]

The regular file forms the built-in grid, so on springs it runs the grid's families and preconditioner, and
on hinges the mesh path; ``--jitter`` moves its inner vertices at random by up to that fraction of the spacing
(seeded), and both run the mesh path.  Prints CPU time (best of ``--repeat``), steps, Newton and CG iterations,
and each hinged run's time against the springs' (docs/model.md section 2.4; docs/core.md, the mesh
preconditioner).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import meshio  # noqa: E402
import numpy as np  # noqa: E402

import wetcloth  # noqa: E402

SIZE = 0.2  # m, the square's side
HEIGHT = 1.0  # m, where it hangs
FRAME = 1.0 / 24.0


def sheet_file(directory: Path, side: int, jitter: float) -> Path:
    """The square as side x side vertices (x fastest) and its quads, inner vertices moved by up to ``jitter``."""
    spacing = SIZE / (side - 1)
    col, row = np.tile(np.arange(side), side), np.repeat(np.arange(side), side)
    points = np.stack([col * spacing, row * spacing - 0.5 * SIZE, np.full(side * side, HEIGHT)], axis=1)
    inner = (col > 0) & (col < side - 1) & (row > 0) & (row < side - 1)
    points[inner, :2] += np.random.default_rng(7).uniform(-jitter, jitter, (int(inner.sum()), 2)) * spacing
    quads = np.array([[r * side + c, r * side + c + 1, (r + 1) * side + c + 1, (r + 1) * side + c]
                      for r in range(side - 1) for c in range(side - 1)], dtype=np.int32)
    path = directory / f"sheet{side}_{jitter}.ply"
    meshio.write(path, meshio.Mesh(points, [("quad", quads)]))
    return path


def run(scene: wetcloth.Scene, repeat: int) -> tuple[float, wetcloth.Simulation]:
    """The best CPU time (s) of ``repeat`` 2 s runs, and the last run's simulation."""
    best = np.inf
    for _ in range(repeat):
        sim = wetcloth.Simulation(scene)
        start = time.process_time()
        sim.advance(2.0)
        best = min(best, time.process_time() - start)
    return best, sim


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=31)
    parser.add_argument("--rigidity", type=float, default=1e-4, help="bend_rigidity of the hinged runs, N m")
    parser.add_argument("--jitter", type=float, default=0.2)
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    steppings = {"adaptive (bdf2)": {}, "frame steps (implicit_euler)": dict(integrator="implicit_euler",
                                                                               tolerance=0.0, max_step=FRAME)}
    with tempfile.TemporaryDirectory() as directory:
        for jitter in (0.0, args.jitter):
            path = sheet_file(Path(directory), args.side, jitter)
            for label, stepping in steppings.items():
                times = {}
                for bending, rigidity in (("springs", 0.0), ("hinges", args.rigidity)):
                    scene = wetcloth.Scene(cloth_mesh=str(path), bend_rigidity=rigidity, place_mesh="off",
                                           pinned_vertices="box:-1,-1,-5,1e-9,1,5", **stepping)
                    times[bending], sim = run(scene, args.repeat)
                    counts = sim.solver_counts
                    print(f"jitter {jitter:4.2f}  {label:28s} {bending:8s} {times[bending]:6.2f} s CPU  "
                          f"steps {sim.steps:5d}  Newton {counts['newton_iterations']:5d}  "
                          f"CG {counts['cg_iterations']:6d}  path {'mesh' if sim.model.topology.listed else 'grid'}")
                print(f"{'':12s}{label:28s} hinges / springs {times['hinges'] / times['springs']:.2f}x")


if __name__ == "__main__":
    main()
