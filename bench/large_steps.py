"""The default integrator against the previous default, on the jobs users run, timed in one process.

    .venv/bin/python bench/large_steps.py towel [--repeat 2]     # 21 x 29 towel, 90 s at 30 Hz
    .venv/bin/python bench/large_steps.py grids [--seconds 3]    # 64 x 64 towel, 81 x 81 sheet, at 30 Hz

``towel``: the default towel (``models/towel.toml``) for its 90 s, outputs read at 30 Hz as the FMU
and the frame export read them, with the current defaults and with the previous default
(symplectic Euler, tolerance 1e-4, steps up to 0.01 s), alternately; best wall time of
``--repeat``.  Prints each run's time, steps, the time it sank (centroid 5 cm under the surface),
its final wet mass, and the ratios.

``grids``: a 64 x 64 towel (real-time factor: simulated over wall-clock seconds) and an 81 x 81
sheet of the same size (milliseconds per 1/30 s frame), each with the defaults, over ``--seconds``
simulated from the drop, and with the previous default over a tenth of that.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import wetcloth

PREVIOUS = dict(integrator="symplectic_euler", tolerance=1e-4, max_step=0.01)
FPS = 30.0
SINK_DEPTH = 0.05  # m


def run(scene: wetcloth.Scene, seconds: float) -> dict:
    """Advance ``scene`` frame by frame at FPS for ``seconds``, reading the outputs at every frame."""
    sim = wetcloth.Simulation(scene)
    frames = int(round(seconds * FPS))
    sink = float("nan")
    start = time.perf_counter()
    for _ in range(frames):
        sim.advance(1.0 / FPS)
        out = sim.outputs()
        if np.isnan(sink) and out["depth"] > SINK_DEPTH:
            sink = sim.time
    wall = time.perf_counter() - start
    return dict(wall=wall, steps=sim.steps, sink=sink, wet_mass=out["wet_mass"], frames=frames,
                **sim.solver_counts)


def towel(repeat: int) -> None:
    scene = wetcloth.load_scene()
    duration = wetcloth.scene.read_scene_file(None)["run"]["duration"]
    settings = {"default": {}, "previous": PREVIOUS}
    wetcloth.Simulation(scene).advance(0.1)  # compile / load the kernels outside the timings
    best = {}
    for _ in range(repeat):
        for name, overrides in settings.items():
            result = run(scene.replace(**overrides), duration)
            print(f"{name:8s} {result['wall']:7.2f} s  {result['steps']:7d} steps  sank at {result['sink']:.3f} s  "
                  f"wet mass {result['wet_mass']:.6f} kg  (Newton {result['newton_iterations']}, "
                  f"CG {result['cg_iterations']})", flush=True)
            if name not in best or result["wall"] < best[name]["wall"]:
                best[name] = result
    new, old = best["default"], best["previous"]
    print(f"\nspeed-up {old['wall'] / new['wall']:.1f}x (best of {repeat}); sink time {new['sink']:.3f} s against "
          f"{old['sink']:.3f} s ({new['sink'] - old['sink']:+.3f} s); final wet mass {new['wet_mass'] / old['wet_mass'] - 1:+.2e} "
          f"relative; {new['wall'] / new['frames'] * 1e3:.2f} ms per frame against {old['wall'] / old['frames'] * 1e3:.2f}")


def grids(seconds: float) -> None:
    for size, name in ((64, "64 x 64 towel"), (81, "81 x 81 sheet")):
        scene = wetcloth.load_scene(nx=size, ny=size)
        wetcloth.Simulation(scene).advance(0.05)
        new = run(scene, seconds)
        old = run(scene.replace(**PREVIOUS), seconds / 10)
        per_frame_new = new["wall"] / new["frames"] * 1e3
        per_frame_old = old["wall"] / old["frames"] * 1e3
        print(f"{name}: default {per_frame_new:.1f} ms per 1/30 s frame ({seconds / new['wall']:.2f}x real time, "
              f"{new['steps']} steps, Newton {new['newton_iterations']}, CG {new['cg_iterations']}); previous default "
              f"{per_frame_old:.1f} ms per frame ({seconds / 10 / old['wall']:.2f}x real time); "
              f"ratio {per_frame_old / per_frame_new:.1f}x", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("job", choices=("towel", "grids"))
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--seconds", type=float, default=3.0)
    args = parser.parse_args()
    towel(args.repeat) if args.job == "towel" else grids(args.seconds)


if __name__ == "__main__":
    main()
