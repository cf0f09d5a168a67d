"""The fixed-step mode (``implicit_euler``, ``tolerance = 0``, ``max_step`` one frame) where the cloth moves
violently or folds onto itself, against the default adaptive steps run in the same process.

    .venv/bin/python bench/violent_frames.py [CASE ...]

The cases came from random trials (docs/open_problems.md): the ``flag`` preset blown back over its pole, the
same flag falling onto itself without air, the soaked ``lift`` towel dragged 2.2 m sideways through a
26 m/s wind, and the ``bucket`` towel bunched against the bucket's wall by an 8.25 m/s current.  For each: CPU seconds, steps and steps taken again (halved for self-collision's impact zones or
for energy gained), and the ratio of the frame steps' time to the adaptive run's.  A step taken again in
smaller pieces passes its size on to the next step (stepping.cpp), so a frame that folds is not tried whole
again at every step.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import wetcloth  # noqa: E402

#: The stepping's settings (scene values) for frames of the given length (s).
Steps = Callable[[float], dict]


def flag_blown_back(steps: Steps) -> wetcloth.Simulation:
    """The flag in a 14.8 m/s wind from behind its pole, 1.5 s at 1/24 s frames."""
    sim = wetcloth.Simulation(wetcloth.load_scene("flag", wind_x=-14.79, wind_z=1.46, **steps(1 / 24)))
    sim.advance(1.5)
    return sim


def flag_falling(steps: Steps) -> wetcloth.Simulation:
    """The flag without air, falling from its pole onto itself, 3 s at 1/30 s frames."""
    sim = wetcloth.Simulation(wetcloth.load_scene("flag", air_density=0.0, **steps(1 / 30)))
    sim.advance(3.0)
    return sim


def towel_dragged(steps: Steps) -> wetcloth.Simulation:
    """The soaked lift towel, its water lowered 1.45 m for 0.25 s, then its grip dragged 2.21 m along -x in
    0.25 s through a 25.9 m/s wind (1/24 s frames); the time is the whole 0.5 s."""
    sim = wetcloth.Simulation(wetcloth.load_scene("lift", **steps(1 / 24)))
    sim.set_inputs(water_level=-1.451)
    sim.advance(0.25)
    sim.set_inputs(grip_x=-2.21, wind_x=25.9)
    sim.advance(0.25)
    return sim


def bucket_torrent(steps: Steps) -> wetcloth.Simulation:
    """The bucket preset's towel, dropped into it for 0.5 s, then 0.5 s in an 8.25 m/s current that bunches
    it against the mesh bucket's wall (1/24 s frames)."""
    sim = wetcloth.Simulation(wetcloth.load_scene("bucket", **steps(1 / 24)))
    sim.advance(0.5)
    sim.set_inputs(current_x=8.25)
    sim.advance(0.5)
    return sim


CASES: dict[str, Callable[[Steps], wetcloth.Simulation]] = {
    "flag_blown_back": flag_blown_back, "flag_falling": flag_falling, "towel_dragged": towel_dragged,
    "bucket_torrent": bucket_torrent}


def frame_steps(frame: float) -> dict:
    """The fixed-step mode's settings for frames of `frame` s."""
    return {"integrator": "implicit_euler", "tolerance": 0.0, "max_step": frame}


def timed(case: Callable[[Steps], wetcloth.Simulation], steps: Steps) -> tuple[float, wetcloth.Simulation]:
    """CPU time (s) of running case with steps, and its simulation."""
    start = time.process_time()
    sim = case(steps)
    return time.process_time() - start, sim


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cases", nargs="*", metavar="CASE",
                        help=f"any of {', '.join(CASES)} (default all)")
    args = parser.parse_args()
    unknown = sorted(set(args.cases) - set(CASES))
    if unknown:
        parser.error(f"unknown case {', '.join(unknown)}; choose from {', '.join(CASES)}")
    print("CPU s; 'again': steps taken again")
    print("| case | adaptive | frame steps | ratio |")
    print("|---|---|---|---|")
    for name in args.cases or CASES:
        adaptive, a = timed(CASES[name], lambda frame: {})
        fixed, f = timed(CASES[name], frame_steps)
        print(f"| {name} | {adaptive:.1f} ({a.steps} steps, {a.rejected_steps} again) "
              f"| {fixed:.1f} ({f.steps} steps, {f.rejected_steps} again) | {fixed / adaptive:.2f} |", flush=True)


if __name__ == "__main__":
    main()
