"""Cost of one step: ms per step and ns per spring per step, per integrator and grid size, against a
plain NumPy version of the same explicit step (``wetcloth.reference``) timed in the same process.

    .venv/bin/python bench/step_speed.py [--sizes 32 64 128 256] [--repeat 5]

The scene needs every force family: a tilted towel across the water surface (springs of all three
families, buoyancy, face drag, absorption).  Each figure is the best of ``--repeat`` timed batches.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import wetcloth
from wetcloth.reference import NumpyReference

EXPLICIT_STEP = 1e-5  # s, or half the explicit schemes' stability limit where that is smaller
IMPLICIT_STEP = 2e-3  # s: a typical accepted step of the adaptive implicit scheme on the towel


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


def measure(size: int, repeat: int) -> list[dict]:
    rows = []
    count = max(2, int(2e6 / size**2))
    probe = wetcloth.Simulation(scene(size).replace(integrator="explicit_euler"))
    explicit_step = min(EXPLICIT_STEP, 0.5 * probe.integrator.stable_step(1.0))
    baseline_sim = wetcloth.Simulation(scene(size).replace(integrator="explicit_euler", tolerance=0.0,
                                                           max_step=explicit_step))
    baseline_sim.advance(20 * explicit_step)  # let it touch the water
    reference = NumpyReference(baseline_sim.model)
    state = baseline_sim.state
    numpy_time = time_steps(lambda: reference.explicit_step(state, explicit_step), max(2, count // 20), repeat)
    springs = baseline_sim.model.topology.spring_count
    rows.append(dict(size=size, integrator="numpy explicit (baseline)", ms=numpy_time * 1e3,
                     ns_per_spring=numpy_time * 1e9 / springs, speedup=1.0, cg=""))
    for integrator, h in (("explicit_euler", explicit_step), ("symplectic_euler", explicit_step),
                          ("implicit_euler", IMPLICIT_STEP)):
        sim = wetcloth.Simulation(scene(size).replace(integrator=integrator, tolerance=0.0, max_step=h))
        sim.state = state.copy()
        sim._trial = state.copy()
        per_step = time_steps(lambda: sim._step(h), count if integrator != "implicit_euler" else max(2, count // 10),
                              repeat)
        rows.append(dict(size=size, integrator=integrator, ms=per_step * 1e3, ns_per_spring=per_step * 1e9 / springs,
                         speedup=numpy_time / per_step,
                         cg=str(getattr(sim.integrator, "last_iterations", ""))))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 64, 128, 256])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    print("| grid | springs | integrator | ms/step | ns/spring/step | speed-up vs NumPy | CG iterations |")
    print("|---|---|---|---|---|---|---|")
    for size in args.sizes:
        springs = wetcloth.Simulation(scene(size)).model.topology.spring_count
        for row in measure(size, args.repeat):
            print(f"| {size}x{size} | {springs} | {row['integrator']} | {row['ms']:.3f} | {row['ns_per_spring']:.2f} "
                  f"| {row['speedup']:.1f}x | {row['cg']} |", flush=True)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
