"""Cloth folding onto itself at fixed frame steps (``implicit_euler``, ``tolerance = 0``, ``max_step`` one frame)
with self-collision on: the energy the steps make, and what they cost.

    .venv/bin/python bench/self_contact_energy.py [--starts 3] [--duration 3] [--fps 30] [corner] [disc]

Cases: `corner`, a 41 x 41 sheet, 1 m square, hung by one corner (its sides swing together and fold over each
other), and `disc`, the 2.5k-vertex disc of bench/mesh_cost.py hung by its cap.  Nothing drives them (no water,
wind, grip or keyed collider), so a rise of the mechanical energy (``wetcloth.energy``) from one frame to the
next is energy the steps made.  The folding is chaotic (a micrometre of starting height changes which frame
rises most), so each case runs from --starts starting heights a micrometre apart; per start: the largest rise
(J) and in how many frames the energy rose at all, the steps taken again, the self-collision stage's pushes and
the CPU time per frame.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from mesh_cost import CASES as MESH_CASES, shapes_of  # noqa: E402
from wetcloth.energy import mechanical_energy  # noqa: E402

#: Above the 1e-9 J of round-off in summing the energy over the particles: a frame that made energy.
RISE = 1e-9


def corner_sheet() -> dict:
    """A 41 x 41 sheet, 1 m square, in still air, held at the corner x <= -0.45, y >= 0.45 m."""
    return dict(nx=41, ny=41, width=1.0, length=1.0, pinned_vertices="box:-9,0.45,-9,-0.45,9,9", initial_tilt=0.0,
                initial_height=2.0, water_level=-10.0, floor_level=-20.0)


def capped_disc() -> dict:
    """bench/mesh_cost.py's irregular 2.5k-vertex disc hanging in air, held where y >= 0.6 m (its cap)."""
    return dict(**MESH_CASES["hanging in air"], **shapes_of(2500, shuffle=False, square_meshes=False)["mesh"],
                pinned_vertices="box:-9,0.6,-9,9,9,9")


CASES = {"corner": ("sheet hung by a corner", corner_sheet), "disc": ("disc hung by its cap", capped_disc)}


def run(fields: dict, lift: float, fps: float, duration: float) -> str:
    scene = wetcloth.load_scene(**fields, self_collision="on", integrator="implicit_euler", tolerance=0.0,
                                max_step=1.0 / fps)
    sim = wetcloth.Simulation(scene)
    sim._buffers.pos[:, 2] += lift
    energy, rises, cpu = mechanical_energy(sim), [], 0.0
    frames = round(duration * fps)
    for _ in range(frames):
        start = time.process_time()
        sim.advance(1.0 / fps)
        cpu += time.process_time() - start
        now = mechanical_energy(sim)
        rises.append(now - energy)
        energy = now
    rises = np.array(rises)
    rising = int((rises > RISE).sum())
    return (f"start +{1e6 * lift:.0f} um: largest rise {rises.max():+.2g} J, energy rose in {rising:2d} frames; "
            f"steps taken again {sim.rejected_steps:3d}; pushes {sim.contact_counts['responses']:6d}; "
            f"{1e3 * cpu / frames:6.1f} ms/frame")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", metavar="CASE", help="corner, disc (default both)")
    parser.add_argument("--starts", type=int, default=3, help="starting heights, a micrometre apart (default 3)")
    parser.add_argument("--duration", type=float, default=3.0, help="simulated seconds (default 3)")
    parser.add_argument("--fps", type=float, default=30.0, help="frames (steps) per second (default 30)")
    args = parser.parse_args()
    unknown = [key for key in args.cases if key not in CASES]
    if unknown:
        parser.error(f"unknown case {unknown[0]!r}; allowed: {', '.join(CASES)}")
    for key in args.cases or list(CASES):
        name, fields = CASES[key][0], CASES[key][1]()
        print(f"{name}, {args.duration:g} s at 1/{args.fps:g} s steps:", flush=True)
        for k in range(args.starts):
            print("  " + run(fields, 1e-6 * k, args.fps, args.duration), flush=True)


if __name__ == "__main__":
    main()
