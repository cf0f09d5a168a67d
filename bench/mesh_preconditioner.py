"""A mesh's preconditioner: the band factors of the whole mesh against the algebraic multigrid
hierarchy, by mesh size (where ALGEBRAIC_SIZE, the size above which meshes take the hierarchy, comes from).

    .venv/bin/python bench/mesh_preconditioner.py [--rings 10 14 18] [--duration 1]

docs/make_meshes.py's irregular disc of each ``--rings`` (about pi rings^2 vertices), the default towel's
fabric, landing flat on water from 5 cm and hanging in air from the part of it at y >= 0.6 m; per run
CPU seconds, steps and CG iterations with either preconditioner (``make_mesh_plane``'s
``algebraic_size`` past the vertex count, or 0).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs"))
import make_meshes  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth import preconditioner  # noqa: E402

CASES = {
    "landing": dict(initial_tilt=0.0, initial_height=0.05),
    "hanging": dict(initial_tilt=0.0, initial_height=2.0, water_level=-10.0, floor_level=-20.0,
                    pinned_vertices="box:-9,0.6,-9,9,9,9"),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rings", type=int, nargs="+", default=[10, 14, 18])
    parser.add_argument("--duration", type=float, default=1.0, help="simulated seconds (default 1)")
    args = parser.parse_args()
    for rings in args.rings:
        points, triangles = make_meshes.round_cloth(rings=rings)
        path = Path(tempfile.mkdtemp()) / "disc.ply"
        make_meshes.write(path, points, triangles)
        for label, case in CASES.items():
            for kind, size in (("band", len(points)), ("algebraic", 0)):
                preconditioner.make_mesh_plane.__defaults__ = (size,)
                sim = wetcloth.Simulation(wetcloth.load_scene(cloth_mesh=str(path), place_mesh="on", **case))
                start = time.process_time()
                sim.advance(args.duration)
                seconds = time.process_time() - start
                print(f"{len(points):6d} vertices  {label}  {kind:<9} {seconds:6.2f} s CPU  steps {sim.steps:5d}  "
                      f"CG {sim.solver_counts['cg_iterations']:6d}  levels {len(sim._plane.algebraic.levels)}", flush=True)


if __name__ == "__main__":
    main()
