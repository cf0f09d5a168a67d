"""Cost of one step: ms per step and ns per spring per step, per integrator and grid size, against a
plain NumPy version of the same explicit step (``tests/support/reference.py``) timed in the same
process; for the implicit schemes also their iterations per step and the cost of one
conjugate-gradient iteration (a product with the system matrix and one preconditioner solve).

    .venv/bin/python bench/step_speed.py [--sizes 32 64 128 256] [--repeat 5]

The scene needs every force family: a tilted towel across the water surface (springs of all three
families, buoyancy, face drag, absorption).  Steps are fixed: 1e-5 s for the explicit schemes (or
half their stability limit), 2e-3 s for implicit Euler, 1/30 s for BDF2.  Steps run in one
``advance`` call, as the simulation runs them.  Each figure is the best of ``--repeat`` batches.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import wetcloth
from wetcloth._core import _system_matvec, apply
import _paths  # noqa: E402,F401  (tests/ on sys.path for the oracles)
from support.reference import NumpyReference

EXPLICIT_STEP = 1e-5  # s, or half the explicit schemes' stability limit where that is smaller
IMPLICIT_STEP = 2e-3  # s: a typical accepted step of adaptive implicit Euler on the towel
BDF2_STEP = 1 / 30  # s: BDF2's step on the floating towel at the default tolerance


def scene(size: int) -> wetcloth.Scene:
    return wetcloth.load_scene(nx=size, ny=size, initial_height=0.0, initial_tilt=0.5)


def time_steps(step, count: int, repeat: int) -> float:
    """Best time (s) per call of ``step`` over ``repeat`` batches of ``count`` calls."""
    step()
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(count):
            step()
        best = min(best, (time.perf_counter() - start) / count)
    return best


def cg_iteration_cost(sim: wetcloth.Simulation, repeat: int) -> float:
    """Seconds for one conjugate-gradient iteration of BDF2: a product with the system matrix and
    one application of the plane preconditioner."""
    model, state = sim.model, sim.state
    work, plane = model.work, sim._plane
    mass = model.mass(state.water)
    p = np.random.default_rng(0).normal(size=state.pos.shape)
    out = np.zeros_like(p)

    def iteration():
        _system_matvec(model.cloth.offsets, work.direction, work.along, work.across, mass, work.blocks,
                       model.free, p, out, work.buf)
        apply(plane, model.free, out, p)

    return time_steps(iteration, 200, repeat)


def measure(size: int, repeat: int) -> list[dict]:
    rows = []
    count = max(2, int(2e6 / size**2))
    probe = wetcloth.Simulation(scene(size).replace(integrator="explicit_euler"))
    explicit_step = min(EXPLICIT_STEP, 0.5 * probe.integrator.stable_step(1.0))
    baseline_sim = wetcloth.Simulation(scene(size).replace(integrator="explicit_euler", tolerance=0.0,
                                                           max_step=explicit_step))
    baseline_sim.advance(20 * explicit_step)  # let it touch the water
    reference = NumpyReference(baseline_sim.model)
    state = baseline_sim.state.copy()
    numpy_time = time_steps(lambda: reference.explicit_step(state, explicit_step), max(2, count // 20), repeat)
    springs = baseline_sim.model.topology.spring_count
    rows.append(dict(size=size, integrator="numpy explicit (baseline)", ms=numpy_time * 1e3,
                     ns_per_spring=numpy_time * 1e9 / springs, speedup=1.0, iterations="", cg_us=""))
    for integrator, h in (("explicit_euler", explicit_step), ("symplectic_euler", explicit_step),
                          ("implicit_euler", IMPLICIT_STEP), ("bdf2", BDF2_STEP)):
        sim = wetcloth.Simulation(scene(size).replace(integrator=integrator, tolerance=0.0, max_step=h))
        sim.state = state
        steps = count if not sim.integrator.implicit else max(2, count // 20)
        sim.advance(h)
        before = sim.solver_counts
        per_step = time_steps(lambda: sim.advance(steps * h), 1, repeat) / steps
        after = sim.solver_counts
        done = steps * (repeat + 1)  # time_steps makes one call before its timed ones
        iterations = ""
        cg_us = ""
        if integrator == "bdf2":
            iterations = (f"{(after['newton_iterations'] - before['newton_iterations']) / done:.1f} Newton, "
                          f"{(after['cg_iterations'] - before['cg_iterations']) / done:.1f} CG")
            cg_us = f"{cg_iteration_cost(sim, repeat) * 1e6:.0f}"
        elif integrator == "implicit_euler":
            iterations = f"{(after['cg_iterations'] - before['cg_iterations']) / done:.1f} CG"
        rows.append(dict(size=size, integrator=integrator, ms=per_step * 1e3, ns_per_spring=per_step * 1e9 / springs,
                         speedup=numpy_time / per_step, iterations=iterations, cg_us=cg_us))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 64, 128, 256])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    print("| grid | springs | integrator | ms/step | ns/spring/step | speed-up vs NumPy | iterations per step "
          "| us per CG iteration |")
    print("|---|---|---|---|---|---|---|---|")
    for size in args.sizes:
        springs = wetcloth.Simulation(scene(size)).model.topology.spring_count
        for row in measure(size, args.repeat):
            print(f"| {size}x{size} | {springs} | {row['integrator']} | {row['ms']:.3f} | {row['ns_per_spring']:.2f} "
                  f"| {row['speedup']:.1f}x | {row['iterations']} | {row['cg_us']} |", flush=True)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
