"""Energy at fixed frame steps (``implicit_euler``, ``tolerance = 0``, ``max_step`` one frame) in contact:
passive sheets in still air and still water meeting the floor, the analytic colliders and the water, which must
not gain energy.

    .venv/bin/python bench/frame_step_energy.py [--fps 30 24] [--duration 2] [--starts 1] [CASE ...]

For each case and frame rate: the largest rise of the cloth's energy, mechanical and buoyancy's
(``wetcloth.energy.total_energy``), from one frame to the next against the energy it starts with, in how many
frames it rose at all, the largest strain of any spring at a frame's end, the steps taken again and the CPU time.
Nothing drives these sheets (no current, wind, grip or keyed collider; no uptake), so a rise is energy the step
made.  Where a sheet lands and folds, its path is chaotic in the steps' rounding: with --starts N each case runs
from N starting heights a micrometre apart, and the figures are over all of them (frames and steps taken again
summed).
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth.energy import total_energy  # noqa: E402

#: A 0.6 m square 21 x 21 sheet in air over the floor (z = 0), dry: what each case shares.
SHEET = dict(nx=21, ny=21, width=0.6, length=0.6, initial_tilt=0.0, water_level=-10.0, floor_level=0.0,
             absorption_rate=0.0, absorption_capacity=0.0)
#: Above the 1e-9 J of round-off in summing the energy over the particles: a frame that made energy.
RISE = 1e-9
#: Still water at z = 0 over a floor 1 m down.
POOL = dict(water_level=0.0, floor_level=-1.0)
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
    "tilted onto still water": dict(initial_height=0.3, initial_tilt=40.0, **POOL),
    "swinging into still water": dict(initial_height=0.4, pinned_edge="y_max", **POOL),
}


def largest_strain(sim: wetcloth.Simulation) -> float:
    """The largest relative stretch of a grid spring now (-)."""
    cloth, pos, worst = sim.model.cloth, sim.state.pos, 0.0
    for offset, rest, stiffness in zip(cloth.offsets, cloth.rest, cloth.stiffness):
        i = np.flatnonzero(stiffness)
        worst = max(worst, (np.linalg.norm(pos[:, i] - pos[:, i + offset], axis=0).max() - rest) / rest)
    return worst


def run(case: dict, fps: float, duration: float, starts: int) -> str:
    frames = round(duration * fps)
    rise, rising, strain, again, cpu = -np.inf, 0, 0.0, 0, 0.0
    for k in range(starts):
        lifted = {**case, "initial_height": case["initial_height"] + 1e-6 * k}
        scene = wetcloth.load_scene(**{**SHEET, **lifted}).replace(integrator="implicit_euler", tolerance=0.0,
                                                                   max_step=1.0 / fps)
        sim = wetcloth.Simulation(scene)
        start = last = total_energy(sim)
        for _ in range(frames):
            clock = time.process_time()
            sim.advance(1.0 / fps)
            cpu += time.process_time() - clock
            now = total_energy(sim)
            rise, rising, last = max(rise, now - last), rising + (now - last > RISE), now
            strain = max(strain, largest_strain(sim))
        again += sim.rejected_steps
    return (f"{rise:.2g} J of {start:.2f} J | {rising} of {starts * frames} | {100 * strain:.1f} % | {again} | "
            f"{1000 * cpu / (starts * frames):.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cases", nargs="*", help="cases whose name contains any of these words (default: all)")
    parser.add_argument("--fps", type=float, nargs="+", default=[30.0, 24.0], help="frame rates (1/s)")
    parser.add_argument("--duration", type=float, default=2.0, help="simulated time (s)")
    parser.add_argument("--starts", type=int, default=1, help="starting heights, a micrometre apart (default 1)")
    args = parser.parse_args()
    print(f"{args.duration:g} s, {args.starts} start(s); largest energy rise in a frame | frames it rose in | "
          "largest strain | steps taken again | ms/frame CPU")
    print("| case | fps | rise | frames | strain | again | ms/frame |\n|---|---|---|---|---|---|---|")
    for name, case in CASES.items():
        if args.cases and not any(word in name for word in args.cases):
            continue
        for fps in args.fps:
            print(f"| {name} | {fps:g} | {run(case, fps, args.duration, args.starts)} |", flush=True)


if __name__ == "__main__":
    main()
