"""CPU time of the implicit solve's kernels on the hanging sheet of issue 25 (bench/hanging_sheet.py,
81 x 81, self-collision on) after 1 s of fixed frame steps (``implicit_euler``, the sheet folded):
per call, best of --repeat rounds, for comparing builds of the core (run each build in turn).

    .venv/bin/python bench/sheet_kernels.py [--repeat 5]

forces_and_blocks: the forces and the Jacobian's pieces (a Newton iteration's residual); system_matvec:
A p with the springs' blocks in double precision; its single form: a CG iteration's product, the families'
blocks read in single precision (builds without it: not shown); set_systems_from_jacobian: the fixed steps' three frame systems and
their multigrid levels (once a Newton iteration); apply: the preconditioner with those systems (a CG
iteration); coarse build: the coarse space's Galerkin matrix and its band factor (once a Newton
iteration); coarse correction: its P (P^T A P)^-1 P^T r added to the preconditioner's z (a CG iteration);
dot: one of CG's dot products.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth import _core  # noqa: E402
from hanging_sheet import FRAME, sheet  # noqa: E402


def best_time(call, calls: int, repeat: int) -> float:
    """Best over ``repeat`` rounds of the CPU time (us) of one of ``calls`` calls."""
    best = np.inf
    for _ in range(repeat):
        start = time.process_time()
        for _ in range(calls):
            call()
        best = min(best, (time.process_time() - start) / calls)
    return 1e6 * best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    sim = wetcloth.Simulation(sheet(81, "on", tolerance=0.0, max_step=FRAME, integrator="implicit_euler"))
    for _ in range(30):
        sim.advance(FRAME)
    model, plane, buffers = sim.model, sim._plane, sim._buffers
    cloth, work, mass = model.cloth, model.work, sim._solver.mass
    p = np.random.default_rng(1).standard_normal((3, model.topology.n))
    out = np.zeros_like(p)
    coarse = _core.CoarseSpace(cloth, _core.COARSE_SIDE)
    assert coarse.build(cloth, work, mass, buffers.pos)
    kernels = {
        "forces_and_blocks": (lambda: _core.forces_and_blocks(cloth, model.physics, work, buffers.pos, buffers.vel,
                                                              buffers.water, FRAME, 0.0), 50),
        "system_matvec": (lambda: _core.system_matvec(cloth, work, mass, p, out), 300),
        "system_matvec, single springs": (lambda: _core._system_matvec_single(cloth, work, mass, p, out), 300),
        "set_systems_from_jacobian": (lambda: _core.set_systems_from_jacobian(plane, cloth, mass, work), 20),
        "apply": (lambda: _core.apply(plane, cloth.free, p, out), 200),
        "coarse build": (lambda: coarse.build(cloth, work, mass, buffers.pos), 100),
        "coarse correction": (lambda: coarse.add_correction(cloth, p, out), 1000),
        "dot": (lambda: _core.dot(p, out), 1000),
    }
    if not hasattr(_core, "_system_matvec_single"):
        del kernels["system_matvec, single springs"]
    print(f"hanging sheet 81 x 81 after 1 s of implicit_euler frame steps: CPU us per call, best of {args.repeat}")
    for name, (call, calls) in kernels.items():
        print(f"{name:<28} {best_time(call, calls, args.repeat):9.1f} us", flush=True)


if __name__ == "__main__":
    main()
