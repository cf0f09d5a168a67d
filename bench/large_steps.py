"""The default integrator against the previous default, on the jobs users run, timed in one process.

    .venv/bin/python bench/large_steps.py towel [--repeat 2]     # 21 x 29 towel, 90 s at 30 Hz
    .venv/bin/python bench/large_steps.py grids [--seconds 3]    # 64 x 64 towel, 81 x 81 sheet, at 30 Hz
    .venv/bin/python bench/large_steps.py grids --whole          # also the 64 x 64 towel's whole 90 s
    .venv/bin/python bench/large_steps.py preconditioner         # one application, banded and multigrid

``towel``: the default towel (``models/towel.toml``) for its 90 s, outputs read at 30 Hz as the FMU
and the frame export read them, with the current defaults and with the previous default
(symplectic Euler, tolerance 1e-4, steps up to 0.01 s), alternately; best wall time of
``--repeat``.  Prints each run's time, steps, the time it sank (centroid 5 cm under the surface),
its final wet mass, and the ratios.

``grids``: a 64 x 64 towel (real-time factor: simulated over wall-clock seconds) and an 81 x 81
sheet of the same size (milliseconds per 1/30 s frame), each with the defaults, over ``--seconds``
simulated from the drop (the landing), alternately with the preconditioner's banded factors on the
whole grid instead of its multigrid cycle (the core's ``plane.cpp``), best of ``--repeat``; then the
previous default over a tenth of that.  ``--whole``: also the 64 x 64 towel's whole run (90 s, as
the default towel), with the real-time factors of its landing and of the whole run.

``preconditioner``: one application of the plane preconditioner (``_core.apply``; ``plane.cpp``,
``multigrid.cpp``) with the banded factors and with the multigrid cycle, alternately, best of 7
batches, from the default towel's 21 x 29 to 128 x 128 (the crossover that sets ``MULTIGRID_SIDE``,
``plane.hpp``), and one refactorisation of each (``_core.refresh``).
"""

from __future__ import annotations

import argparse
import contextlib
import time

import numpy as np

import wetcloth
from wetcloth import _core, preconditioner as plane

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
    wetcloth.Simulation(scene).advance(0.1)  # one untimed run first: memory and caches warm
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


@contextlib.contextmanager
def banded_preconditioner():
    """Simulations made inside use the banded factors on any grid (no multigrid): ``make_plane``
    reads ``wetcloth.preconditioner.MULTIGRID_SIDE`` when ``Simulation`` allocates its plane."""
    side = plane.MULTIGRID_SIDE
    plane.MULTIGRID_SIDE = 1 << 30
    try:
        yield
    finally:
        plane.MULTIGRID_SIDE = side


def grids(seconds: float, repeat: int, whole: bool) -> None:
    for size, name in ((64, "64 x 64 towel"), (81, "81 x 81 sheet")):
        scene = wetcloth.load_scene(nx=size, ny=size)
        wetcloth.Simulation(scene).advance(0.05)
        best = {}
        for _ in range(repeat):
            for setting in ("multigrid", "banded"):
                with banded_preconditioner() if setting == "banded" else contextlib.nullcontext():
                    result = run(scene, seconds)
                if setting not in best or result["wall"] < best[setting]["wall"]:
                    best[setting] = result
        old = run(scene.replace(**PREVIOUS), seconds / 10)
        per_frame = {setting: result["wall"] / result["frames"] * 1e3 for setting, result in best.items()}
        per_frame_old = old["wall"] / old["frames"] * 1e3
        for setting, result in best.items():
            print(f"{name}, {seconds:g} s: default, {setting:9s} {per_frame[setting]:7.1f} ms per 1/30 s frame "
                  f"({seconds / result['wall']:.2f}x real time, {result['steps']} steps, Newton "
                  f"{result['newton_iterations']}, CG {result['cg_iterations']}, factorisations "
                  f"{result['factorisations']})", flush=True)
        print(f"{name}: multigrid {per_frame['banded'] / per_frame['multigrid']:.2f}x faster than banded "
              f"(best of {repeat}); previous default {per_frame_old:.1f} ms per frame "
              f"({seconds / 10 / old['wall']:.2f}x real time), {per_frame_old / per_frame['multigrid']:.1f}x the default's",
              flush=True)
    if whole:
        whole_run(seconds)


def whole_run(landing: float) -> None:
    """The 64 x 64 towel's whole run (the default towel's duration), its landing timed apart."""
    scene = wetcloth.load_scene(nx=64, ny=64)
    duration = wetcloth.scene.read_scene_file(None)["run"]["duration"]
    sim = wetcloth.Simulation(scene)
    walls = []
    start = time.perf_counter()
    for part in (landing, duration - landing):
        for _ in range(int(round(part * FPS))):
            sim.advance(1.0 / FPS)
            sim.outputs()
        walls.append(time.perf_counter() - start)
    counts = sim.solver_counts
    print(f"64 x 64 towel, whole {duration:g} s run: {walls[1]:.1f} s wall, {duration / walls[1]:.2f}x real time "
          f"(landing, first {landing:g} s: {landing / walls[0]:.2f}x; after it: "
          f"{(duration - landing) / (walls[1] - walls[0]):.2f}x); {sim.steps} steps, Newton "
          f"{counts['newton_iterations']}, CG {counts['cg_iterations']}", flush=True)


def preconditioner() -> None:
    from wetcloth.model import Model
    for nx, ny in ((21, 29), (24, 24), (32, 32), (48, 48), (64, 64), (81, 81), (128, 128)):
        topology = Model(wetcloth.load_scene(nx=nx, ny=ny)).topology
        n = topology.n
        mass, scale, free = np.full(n, 5e-4 * 441 / n), (2.0 / 3.0 / FPS) ** 2, np.ones(n)
        r, z = np.random.default_rng(0).standard_normal((3, n)), np.zeros((3, n))
        planes = {setting: plane.make_plane(nx, ny, topology.spring_family_names, topology.spring_stiffness,
                                            multigrid_side=side)
                  for setting, side in (("banded", 1 << 30), ("multigrid", 0))}
        best = dict.fromkeys(planes, float("inf"))
        factor = dict.fromkeys(planes, float("inf"))
        count = max(3, int(2e5 / n))
        for _ in range(7):
            for setting, p in planes.items():
                start = time.perf_counter()
                p.reference[1] = 0.0
                _core.refresh(p, topology.spring_offset, mass, scale)
                factor[setting] = min(factor[setting], time.perf_counter() - start)
                start = time.perf_counter()
                for _ in range(count):
                    _core.apply(p, free, r, z)
                best[setting] = min(best[setting], (time.perf_counter() - start) / count)
        print(f"{nx} x {ny}: one application banded {best['banded'] * 1e6:.0f} us, multigrid "
              f"{best['multigrid'] * 1e6:.0f} us ({len(planes['multigrid'].grid.levels)} levels), "
              f"{best['banded'] / best['multigrid']:.2f}x; refactorisation {factor['banded'] * 1e3:.2f} against "
              f"{factor['multigrid'] * 1e3:.2f} ms", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("job", choices=("towel", "grids", "preconditioner"))
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--whole", action="store_true", help="grids: also the 64 x 64 towel's whole run")
    args = parser.parse_args()
    if args.job == "towel":
        towel(args.repeat)
    elif args.job == "grids":
        grids(args.seconds, args.repeat, args.whole)
    else:
        preconditioner()


if __name__ == "__main__":
    main()
