"""Energy at fixed frame steps (``implicit_euler``, ``tolerance = 0``, ``max_step`` one frame) in contact:
passive sheets in still air meeting the floor and the analytic colliders, which must not gain energy.

    .venv/bin/python bench/frame_step_energy.py [--fps 30 24] [--duration 2] [CASE ...]

For each case and frame rate: the largest rise of the cloth's mechanical energy from one frame to the next
(``wetcloth.energy``) against the energy it starts with, the largest strain of any spring at a frame's end,
the steps taken again and the CPU time.  Nothing drives these sheets (no water, wind, grip or keyed
collider), so a rise is energy the step made.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth.energy import mechanical_energy  # noqa: E402

#: A 0.6 m square 21 x 21 sheet in air over the floor (z = 0), dry: what each case shares.
SHEET = dict(nx=21, ny=21, width=0.6, length=0.6, initial_tilt=0.0, water_level=-10.0, floor_level=0.0,
             absorption_rate=0.0, absorption_capacity=0.0)
#: A 0.3 m block under the sheet's middle.
BLOCK = dict(x=0.0, y=0.0, z=0.15)
CASES = {
    "swinging onto the floor": dict(initial_height=0.4, pinned_edge="y_max"),
    "swinging onto the floor, friction 1": dict(initial_height=0.4, pinned_edge="y_max", floor_friction=1.0),
    "tilted onto the floor": dict(initial_height=0.3, initial_tilt=40.0),
    "onto a box": dict(initial_height=0.32, colliders=(dict(shape="box", size_x=0.3, size_y=0.3, size_z=0.3,
                                                            **BLOCK),)),
    "onto a cylinder": dict(initial_height=0.32, colliders=(dict(shape="cylinder", radius=0.15, height=0.3,
                                                                 **BLOCK),)),
    "off a frictionless ball": dict(initial_height=0.42, colliders=(dict(shape="sphere", x=0.0, y=0.0, z=0.2,
                                                                         radius=0.2, friction=0.0),)),
    "down a slope": dict(initial_height=0.5, colliders=(dict(shape="plane", z=0.2, normal_x=0.3, normal_z=1.0,
                                                             friction=0.2),)),
}


def largest_strain(sim: wetcloth.Simulation) -> float:
    """The largest relative stretch of a grid spring now (-)."""
    cloth, pos, worst = sim.model.cloth, sim.state.pos, 0.0
    for offset, rest, stiffness in zip(cloth.offsets, cloth.rest, cloth.stiffness):
        i = np.flatnonzero(stiffness)
        worst = max(worst, (np.linalg.norm(pos[:, i] - pos[:, i + offset], axis=0).max() - rest) / rest)
    return worst


def run(case: dict, fps: float, duration: float) -> str:
    scene = wetcloth.load_scene(**{**SHEET, **case}).replace(integrator="implicit_euler", tolerance=0.0,
                                                             max_step=1.0 / fps)
    sim = wetcloth.Simulation(scene)
    start = energy = mechanical_energy(sim)
    rise, strain, cpu = -np.inf, 0.0, 0.0
    for _ in range(round(duration * fps)):
        clock = time.process_time()
        sim.advance(1.0 / fps)
        cpu += time.process_time() - clock
        now = mechanical_energy(sim)
        rise, energy = max(rise, now - energy), now
        strain = max(strain, largest_strain(sim))
    return (f"{rise:.2g} J of {start:.2f} J | {100 * strain:.1f} % | {sim.rejected_steps} | "
            f"{1000 * cpu / round(duration * fps):.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cases", nargs="*", help="cases whose name contains any of these words (default: all)")
    parser.add_argument("--fps", type=float, nargs="+", default=[30.0, 24.0], help="frame rates (1/s)")
    parser.add_argument("--duration", type=float, default=2.0, help="simulated time (s)")
    args = parser.parse_args()
    print(f"{args.duration:g} s; largest energy rise in a frame | largest strain | steps taken again | ms/frame CPU")
    print("| case | fps | rise | strain | again | ms/frame |\n|---|---|---|---|---|---|")
    for name, case in CASES.items():
        if args.cases and not any(word in name for word in args.cases):
            continue
        for fps in args.fps:
            print(f"| {name} | {fps:g} | {run(case, fps, args.duration)} |", flush=True)


if __name__ == "__main__":
    main()
