"""The round tablecloth of issue 26 draped over its table, at two resolutions of the same disc.

    .venv/bin/python bench/tablecloth_drape.py [--rings 25 50] [--duration 3] [--seeds 26] [--bend-rigidity D]

models/tablecloth.toml with docs/make_meshes.py's disc of each ``--rings`` (25: the preset's ~2k
vertices; 50: ~8k) and each ``--seeds`` (the jitter's random seed; 26: the preset's).  Per run: CPU
time, steps, the deepest any particle came into the table (sampled every 1/30 s; contact keeps
thickness/2), the centre's height above the table top less thickness/2, the hem's height (mean z of
the rim vertices) at the end, and how it hangs: the rim's mean distance from the table's axis (its
flare; the table's radius is 0.4 m) and the spread of its heights (the folds' crests stand higher);
then, per seed, the hem heights' difference between the resolutions (the issue asks for 5 mm).
``--bend-rigidity D``: the hinges' rigidity (N m) instead of the preset's; 0: the triangles' bending springs.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs"))
import make_meshes  # noqa: E402

import wetcloth  # noqa: E402

TABLE_TOP = 0.75  # m


def drape(rings: int, seed: int, duration: float, settings: dict) -> float:
    points, triangles = make_meshes.round_cloth(rings=rings, seed=seed)
    path = Path(tempfile.mkdtemp()) / "disc.ply"
    make_meshes.write(path, points, triangles)
    scene = wetcloth.load_scene("tablecloth", cloth_mesh=str(path), **settings)
    table, gap = scene.colliders[0], 0.5 * scene.thickness
    sim = wetcloth.Simulation(scene)
    r = np.hypot(points[:, 0], points[:, 1])
    centre, rim = int(np.argmin(r)), np.isclose(r, make_meshes.RADIUS)
    deepest, spent = 0.0, 0.0
    for _ in range(round(duration * 30)):
        start = time.process_time()
        sim.advance(1 / 30)
        spent += time.process_time() - start
        deepest = max(deepest, gap - table.distance(sim.state.pos).min())
    pos = sim.state.pos
    hem = float(pos[2, rim].mean())
    solves = sim.solver_counts
    print(f"{len(points):6d} vertices, seed {seed}: {spent:7.1f} s CPU  steps {sim.steps:6d}  "
          f"rejected {sim.rejected_steps:6d}  Newton {solves['newton_iterations']}  CG a Newton iteration "
          f"{solves['cg_iterations'] / solves['newton_iterations']:.2f}  "
          f"deepest into the table {1e3 * deepest:+.4f} mm  centre {1e3 * (pos[2, centre] - TABLE_TOP - gap):+.4f} mm "
          f"above top + thickness/2  hem at z = {hem:.4f} m (sd {1e3 * pos[2, rim].std():.1f} mm), "
          f"rim {np.hypot(pos[0, rim], pos[1, rim]).mean():.4f} m from the axis", flush=True)
    return hem


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rings", type=int, nargs="+", default=[25, 50])
    parser.add_argument("--duration", type=float, default=3.0, help="simulated seconds (default 3)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[make_meshes.SEED])
    parser.add_argument("--bend-rigidity", type=float, help="the hinges' rigidity (N m; 0: bending springs)")
    args = parser.parse_args()
    settings = {} if args.bend_rigidity is None else {"bend_rigidity": args.bend_rigidity}
    for seed in args.seeds:
        hems = [drape(rings, seed, args.duration, settings) for rings in args.rings]
        for a, b, ra, rb in zip(hems, hems[1:], args.rings, args.rings[1:]):
            print(f"hem height, seed {seed}, {ra} rings against {rb}: {1e3 * (b - a):+.2f} mm")


if __name__ == "__main__":
    main()
