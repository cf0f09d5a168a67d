"""CPU time of the implicit solve's kernels on bench/mesh_cost.py's shapes (the irregular 10k-vertex disc,
the 100 x 100 grid and that grid read as a quad mesh) after --settle s of the landing on water: per call,
best of --repeat rounds, and each shape's per vertex against the grid's, for comparing builds of the core
(run each build in turn).

    .venv/bin/python bench/mesh_kernels.py [--repeat 5] [--settle 0.2] [--case landing|hanging]

forces_and_blocks: the forces and the Jacobian's pieces (a Newton iteration's); forces: the forces
alone; system_matvec: A p (a CG iteration's product); apply: the preconditioner (a CG iteration);
follow_cloth: the particles' frames (a Newton iteration's); refresh: the in-plane systems at the rest
stiffness and their multigrid levels (a factorisation).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth import _core  # noqa: E402
from mesh_cost import CASES, PIN, shapes_of  # noqa: E402
from sheet_kernels import best_time  # noqa: E402

STEP = 1e-3  # s, the step the blocks are built for


def kernels(sim: wetcloth.Simulation) -> dict:
    """The kernels of ``sim``'s solve as calls on its own arrays, with how many calls a round makes."""
    model, plane, buffers = sim.model, sim._plane, sim._buffers
    cloth, work, mass = model.cloth, model.work, sim._solver.mass
    p = np.random.default_rng(1).standard_normal((3, model.topology.n))
    out = np.zeros_like(p)
    scales = iter(np.tile([1e-6, 1e-4], 10**6))  # (beta h)^2 s^2, 100x apart: refresh factors at every call
    return {
        "forces_and_blocks": (lambda: _core.forces_and_blocks(cloth, model.physics, work, buffers.pos, buffers.vel,
                                                              buffers.water, STEP, 0.0), 40),
        "forces": (lambda: _core.forces(cloth, model.physics, work, buffers.pos, buffers.vel, buffers.water), 40),
        "system_matvec": (lambda: _core.system_matvec(cloth, work, mass, p, out), 200),
        "apply": (lambda: _core.apply(plane, cloth.free, p, out), 100),
        "follow_cloth": (lambda: _core.follow_cloth(plane, cloth, buffers.pos), 100),
        "refresh": (lambda: _core.refresh(plane, cloth, mass, next(scales)), 10),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--settle", type=float, default=0.2, help="simulated seconds before the kernels are timed")
    parser.add_argument("--case", choices=("landing", "hanging"), default="landing")
    args = parser.parse_args()
    shapes = shapes_of(10000, shuffle=False, square_meshes=False)
    case = CASES["landing on water" if args.case == "landing" else "hanging in air"]
    calls = {}
    for kind, shape in shapes.items():
        sim = wetcloth.Simulation(wetcloth.load_scene(**case, **shape, **extra_of(args.case)))
        sim.advance(args.settle)
        calls[kind] = (sim.model.topology.n, kernels(sim))
    print(f"{args.case} after {args.settle} s: CPU us per call, best of {args.repeat}; per vertex against the grid")
    for name in calls["grid"][1]:
        times = {kind: best_time(*calls[kind][1][name], args.repeat) for kind in calls}
        ratios = "  ".join(f"{kind} {times[kind]:8.1f} ({times[kind] / n / (times['grid'] / calls['grid'][0]):.2f}x)"
                           for kind, (n, _) in calls.items())
        print(f"{name:<18} {ratios}", flush=True)


def extra_of(case: str) -> dict:
    """The scene settings a case adds to every shape (bench/mesh_cost.py)."""
    return dict(self_collision="off", **(dict(pinned_vertices=PIN) if case == "hanging" else {}))


if __name__ == "__main__":
    main()
