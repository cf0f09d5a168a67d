"""Energy at fixed frame steps (``implicit_euler``, ``tolerance = 0``, ``max_step`` one frame) of driven cloth:
the presets a grip (``lift``), a current (``current``), the wind (``flag``) or a keyed collider (``sweep``) drive.

    .venv/bin/python bench/driven_energy.py [PRESET ...] [--fps 24 30]

For each preset and frame rate: of the frames taken as one step, how many the cloth's energy (mechanical and
buoyancy's, ``wetcloth.energy``) ended above its start's by more than the drivers' work bound
(``tests/support/driven.py``, recomputed from the forces: docs/model.md section 7), and the largest such excess (J;
negative: every frame within its bound); then the steps taken again and the CPU time per frame.  Over a frame in
which a keyed collider that may reach the cloth moves (the sweep's ball, without turning), energy and bound are
those seen from a frame moving with it, where it stands still and contact only takes energy, as the core weighs
them (``ball_velocity``).  Frames taken in parts are checked by the core in those parts, against their own
bounds.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

import _paths  # noqa: E402,F401  (tests/ on sys.path)
import wetcloth  # noqa: E402
from support.driven import DriveBound, ball_velocity, energy_in_frame  # noqa: E402

#: Each preset's run (s): the lift's grip stops at 5 s, the sweep's ball at 2 s.
PRESETS = {"lift": 8.0, "current": 20.0, "flag": 5.0, "sweep": 4.0}
#: Above the 1e-9 J of round-off in summing the energy over the particles.
ROUND_OFF = 1e-9


def run(preset: str, seconds: float, fps: float) -> str:
    h = 1.0 / fps
    scene = wetcloth.load_scene(preset, integrator="implicit_euler", tolerance=0.0, max_step=h)
    sim = wetcloth.Simulation(scene)
    bound = DriveBound(scene)
    frames = round(seconds * fps)
    checked, over, excess, cpu = 0, 0, -np.inf, 0.0
    for _ in range(frames):
        start, start_vel, again = sim.time, sim.state.vel.copy(), sim.rejected_steps
        ball = ball_velocity(scene, sim, start, h)
        energy = energy_in_frame(sim, ball)
        clock = time.process_time()
        sim.advance(h)
        cpu += time.process_time() - clock
        if sim.rejected_steps == again:
            beyond = energy_in_frame(sim, ball) - energy - bound(sim, start_vel, h, frame=ball)
            checked, over, excess = checked + 1, over + (beyond > ROUND_OFF), max(excess, beyond)
    return f"{checked} of {frames} | {over} | {excess:+.2g} J | {sim.rejected_steps} | {1000 * cpu / frames:.1f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("presets", nargs="*", default=list(PRESETS), help="presets (default: all four)")
    parser.add_argument("--fps", type=float, nargs="+", default=[24.0, 30.0], help="frame rates (1/s)")
    args = parser.parse_args()
    print("frames checked | over the drivers' bound | largest excess | steps taken again | ms/frame CPU")
    print("| preset | s | fps | checked | over | excess | again | ms/frame |\n|---|---|---|---|---|---|---|---|")
    for preset in args.presets:
        for fps in args.fps:
            print(f"| {preset} | {PRESETS[preset]:g} | {fps:g} | {run(preset, PRESETS[preset], fps)} |", flush=True)


if __name__ == "__main__":
    main()
