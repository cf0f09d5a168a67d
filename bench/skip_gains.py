"""What skipping unneeded work gains: each scene run with skipping on and off in the same process.

    .venv/bin/python bench/skip_gains.py [--repeat 2]

Skips measured: water kernels while no particle touches water (falling through air); dry rows of
the face drag (a cloth hanging half into water); sleeping (a cloth resting on a dry floor, a cloth
floating still); and the bending kernel, which is not built when bend_stiffness = 0.  The towel
landing on water needs everything: skipping must cost nothing there.
"""

from __future__ import annotations

import argparse
import time

import wetcloth

GRID = dict(nx=21, ny=29)


def scenes():
    towel = wetcloth.load_scene(**GRID)
    dry_tank = dict(water_level=-5.0, floor_level=-1.0, initial_tilt=0.0, initial_height=-0.95)
    return [
        ("falling through air", towel.replace(initial_height=20.0), 1.0),
        ("hanging half into water", towel.replace(initial_tilt=90.0, pinned_edge="y_max", initial_height=0.3,
                                                  absorption_rate=0.0), 2.0),
        ("resting on a dry floor", towel.replace(**dry_tank), 10.0),
        ("floating still", wetcloth.load_scene("thesis_float", **GRID), 20.0),
        ("towel landing (needs everything)", towel, 3.0),
    ]


def wall_time(scene, duration, skip, repeat) -> tuple[float, int]:
    """Best wall time (s) of ``repeat`` runs, and the steps taken."""
    best = float("inf")
    for _ in range(repeat):
        sim = wetcloth.Simulation(scene, skip_idle_work=skip)
        start = time.perf_counter()
        sim.advance(duration)
        best = min(best, time.perf_counter() - start)
    return best, sim.steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    wetcloth.Simulation(wetcloth.load_scene(nx=3, ny=3)).advance(0.01)  # one untimed run first
    print("| scene | simulated | skipping off | skipping on | gain | steps off / on |")
    print("|---|---|---|---|---|---|")
    for name, scene, duration in scenes():
        off, steps_off = wall_time(scene, duration, False, args.repeat)
        on, steps_on = wall_time(scene, duration, True, args.repeat)
        print(f"| {name} | {duration:g} s | {off:.2f} s | {on:.2f} s | {off / on:.2f}x | {steps_off} / {steps_on} |",
              flush=True)
    towel = wetcloth.load_scene(**GRID)
    with_bending, _ = wall_time(towel, 3.0, True, args.repeat)
    without_bending, _ = wall_time(towel.replace(bend_stiffness=0.0), 3.0, True, args.repeat)
    print(f"\nbending kernel: towel landing 3 s with bend_stiffness 20 N/m {with_bending:.2f} s, "
          f"with 0 (kernel not built) {without_bending:.2f} s: {with_bending / without_bending:.2f}x")


if __name__ == "__main__":
    main()
