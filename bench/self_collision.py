"""What self-collision costs: each scene run with ``self_collision`` "off" and "on", alternately, in one process.

    .venv/bin/python bench/self_collision.py [--repeat 5] [--skip-stability] [--landing-only] [--hanging-only]

* The default towel's landing (its first 0.5 s: the drop and the impact, and its first 3 s), frames
  of 1/30 s as the FMU reads them: the stage's share of the run (on - off) / on from the best of
  ``--repeat`` alternating runs of each, and the candidate lists built (exact counts).  Timed in CPU
  time of the process, as every figure here (the runs are single-threaded): on a shared machine
  wall time also counts other jobs' time slices, which swamped the difference.
* The hanging sheet of issue 25 (81 x 81, 1 m square, pinned along y_max, released horizontal in air:
  it swings down and its free edge whips, but it never comes near itself), its first 0.5 s in frames
  of 1/30 s, with the default adaptive steps and with fixed frame steps (``tolerance = 0``,
  ``max_step = 1/30``; such a step may be rejected and retried shorter): ms per frame and per step
  off and on from the best of ``--repeat`` alternating runs, the ratio on / off, the candidate lists
  built and the most candidate pairs held after any frame (exact counts).
* The default towel (``models/towel.toml``, 21 x 29, 20 s: it lands, floats and soaks, and never
  folds): the stage only checks that its candidate list (empty) still holds.  Figure: the median
  of the per-pair ratios on / off (the runs alternate, so a load change on a shared machine hits both).
* The folding scenes of ``tests/test_self_collision.py`` (the edge-on drop into a pool, a towel
  folded over its pinned edge by a current) and a crumpling one: wall time, steps and the most
  edge-triangle crossings in any 0.25 s frame (the test's checker), without and with the stage.
* A larger crumpled pile (the default towel's 21 x 29 grid, dropped upright as the crumpling one) at the
  fixed-step mode (``implicit_euler``, 1/30 s steps), 3 s: CPU time, steps and steps taken again (a step
  whose pushes gained energy is taken again in halves), without and with the stage, and whether it is asleep at
  the end (``--pile-only``; it lies on the floor from about 4 s: ``--pile-duration 8``, asleep by about 12 s:
  ``--pile-duration 16``).
* The adaptive stability sweep of ``bench/stability.py`` (quick grid: 324 stressed runs, every
  integrator) with the stage on, as it is by default; ``--skip-stability`` leaves it out.
"""

from __future__ import annotations

import argparse
import statistics
import time

import wetcloth
import _paths  # noqa: F401  (tests/ on sys.path)
from stability import adaptive_sweep
from test_self_collision import CURRENT_OVER_PIN, EDGE_ON_POOL, crossings

FRAME = 0.25  # s
#: The worst case met: a soft towel (bend_stiffness 2 N/m) dropped upright onto a floor in air crumples
#: into a pile of layers (a corner of the random drops of ``tests/test_self_collision.py``).
CRUMPLED = dict(nx=11, ny=15, bend_stiffness=2.0, initial_tilt=90.0, initial_height=0.4, floor_level=0.0,
                water_level=-5.0)


def timed_run(values: dict, duration: float, count_crossings: bool = False) -> tuple[float, wetcloth.Simulation, int]:
    """CPU time (s) of ``duration`` s in frames of FRAME s, the simulation, and the most crossings in
    a frame (counted outside the timed part; 0 unless ``count_crossings``)."""
    sim = wetcloth.Simulation(wetcloth.load_scene(**values))
    spent, worst = 0.0, 0
    for _ in range(round(duration / FRAME)):
        start = time.process_time()
        sim.advance(FRAME)
        spent += time.process_time() - start
        if count_crossings:
            worst = max(worst, crossings(sim.positions, sim.triangles))
    return spent, sim, worst


def towel_overhead(repeat: int) -> None:
    duration = 20.0
    times = {"off": [], "on": []}
    for _ in range(repeat):
        for mode in ("off", "on"):
            spent, sim, _ = timed_run({"self_collision": mode}, duration)
            times[mode].append(spent)
    ratios = [on / off for on, off in zip(times["on"], times["off"])]
    counts = sim.contact_counts
    print(f"default towel, {duration:g} s, {repeat} alternating pairs: off best {min(times['off']):.2f} s, "
          f"on best {min(times['on']):.2f} s; on / off median {statistics.median(ratios):.3f} "
          f"(pairs {', '.join(f'{r:.3f}' for r in ratios)}); {sim.steps} steps, {counts['rebuilds']} candidate lists "
          f"built, {counts['busy_steps']} steps with candidates", flush=True)


def landing_share(repeat: int) -> None:
    for duration in (0.5, 3.0):
        best, rebuilds, steps = {}, 0, 0
        for _ in range(repeat):
            for mode in ("off", "on"):
                sim = wetcloth.Simulation(wetcloth.load_scene(self_collision=mode))
                start = time.process_time()
                for _ in range(round(duration * 30)):
                    sim.advance(1.0 / 30.0)
                spent = time.process_time() - start
                best[mode] = min(best.get(mode, spent), spent)
                if mode == "on":
                    rebuilds, steps = sim.contact_counts["rebuilds"], sim.steps
        print(f"default towel's first {duration:g} s (frames of 1/30 s), best of {repeat} alternating, CPU time: off "
              f"{best['off']:.3f} s, on {best['on']:.3f} s; the stage's share {(best['on'] - best['off']) / best['on']:.1%} "
              f"({best['on'] - best['off']:.3f} s); {steps} steps, {rebuilds} candidate lists built", flush=True)


#: The hanging sheet of issue 25.
HANGING = dict(nx=81, ny=81, width=1.0, length=1.0, pinned_edge="y_max", initial_tilt=0.0, initial_height=2.0,
               water_level=-10.0, floor_level=-20.0)
#: Fixed frame steps.
FRAME_STEPS = dict(tolerance=0.0, max_step=1.0 / 30.0)


def hanging_sheet_cost(repeat: int, duration: float = 0.5) -> None:
    frames = round(duration * 30)
    for label, extra in (("adaptive steps", {}), ("fixed frame steps", FRAME_STEPS)):
        best, rows = {}, {}
        for _ in range(repeat):
            for mode in ("off", "on"):
                sim = wetcloth.Simulation(wetcloth.load_scene(**HANGING, **extra, self_collision=mode))
                spent, most = 0.0, 0
                for _ in range(frames):
                    start = time.process_time()
                    sim.advance(1.0 / 30.0)
                    spent += time.process_time() - start
                    counts = sim.contact_counts
                    most = max(most, counts["point_triangle_candidates"] + counts["edge_edge_candidates"])
                best[mode] = min(best.get(mode, spent), spent)
                rows[mode] = (sim.steps, sim.rejected_steps, counts, most)
        (steps, rejected, _, _), (_, _, counts, most) = rows["off"], rows["on"]
        per_frame = {m: 1000.0 * best[m] / frames for m in best}
        per_step = {m: 1000.0 * best[m] / rows[m][0] for m in best}
        print(f"hanging sheet 81 x 81, first {duration:g} s, {label} (best of {repeat} alternating, CPU time): off "
              f"{per_frame['off']:.1f} ms/frame ({per_step['off']:.2f} ms/step), on {per_frame['on']:.1f} ms/frame "
              f"({per_step['on']:.2f} ms/step); on / off {best['on'] / best['off']:.2f}x; {steps} steps, {rejected} "
              f"rejected; {counts['rebuilds']} candidate lists built, {counts['busy_steps']} steps with candidates, "
              f"at most {most} candidate pairs after a frame", flush=True)


def off_and_on(values: dict, duration: float, repeat: int) -> tuple[dict, dict]:
    """The least CPU time (s) of each mode ("off", "on") over ``repeat`` alternating runs of ``duration`` s,
    and each mode's first run: its simulation and the most crossings in a frame."""
    best, first = {}, {}
    for k in range(repeat):
        for mode in ("off", "on"):
            spent, sim, worst = timed_run(values | {"self_collision": mode}, duration, count_crossings=k == 0)
            best[mode] = min(best.get(mode, spent), spent)
            if k == 0:
                first[mode] = (sim, worst)
    return best, first


def folding_cost(repeat: int) -> None:
    print("\n| scene | simulated | off: CPU, steps, most crossings | on: CPU, steps, most crossings | on / off |")
    print("|---|---|---|---|---|")
    for name, values, duration in (("edge-on drop into a 0.6 m pool (15 x 21)", EDGE_ON_POOL, 6.0),
                                   ("folded over its pinned edge by a current (15 x 21)", CURRENT_OVER_PIN, 2.0),
                                   ("crumpled: soft towel dropped upright from 0.4 m in air (11 x 15)", CRUMPLED, 1.5)):
        best, first = off_and_on(values, duration, repeat)
        cells = [f"{best[m]:.2f} s, {first[m][0].steps} steps, {first[m][1]}" for m in ("off", "on")]
        print(f"| {name} | {duration:g} s | {cells[0]} | {cells[1]} | {best['on'] / best['off']:.2f}x |", flush=True)


#: A larger, softer pile at the artists' fixed-step mode: the default towel's 21 x 29 grid, dropped upright as CRUMPLED.
PILE = CRUMPLED | dict(nx=21, ny=29, integrator="implicit_euler") | FRAME_STEPS


def pile_at_frame_steps(repeat: int, duration: float = 3.0) -> None:
    """The 21 x 29 pile at fixed 1/30 s steps: CPU time off and on, steps, steps taken again (a step whose
    pushes gained energy is taken again in halves), the most crossings in a 0.25 s frame, and whether it is
    asleep at the end."""
    best, first = off_and_on(PILE, duration, repeat)
    cells = [f"{best[m]:.2f} s, {first[m][0].steps} steps, {first[m][0].rejected_steps} taken again, "
             f"{first[m][1]} crossings, {'asleep' if first[m][0].sleeping else 'awake'} at the end"
             for m in ("off", "on")]
    print(f"\ncrumpled 21 x 29 pile at fixed 1/30 s steps (implicit_euler), {duration:g} s: off {cells[0]}; "
          f"on {cells[1]}; on / off {best['on'] / best['off']:.2f}x", flush=True)


def stability() -> None:
    start = time.perf_counter()
    rows = adaptive_sweep(quick=True)
    failures = [r for r in rows if not r["stable"] or r["wet_mass_decreased"]]
    print(f"\nstability sweep (bench/stability.py's adaptive mode, quick grid), self_collision on: "
          f"{len(rows) - len(failures)} of {len(rows)} stressed runs stable with non-decreasing wet mass "
          f"({time.perf_counter() - start:.0f} s)")
    for r in failures:
        print("  FAILED:", r)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="alternating off/on pairs (default 5)")
    parser.add_argument("--skip-stability", action="store_true")
    parser.add_argument("--landing-only", action="store_true", help="only the default towel's landing")
    parser.add_argument("--hanging-only", action="store_true", help="only the hanging sheet")
    parser.add_argument("--hanging-duration", type=float, default=0.5, help="simulated s of the hanging sheet")
    parser.add_argument("--pile-only", action="store_true", help="only the crumpled pile at fixed frame steps")
    parser.add_argument("--pile-duration", type=float, default=3.0, help="simulated s of the pile (default 3)")
    args = parser.parse_args()
    wetcloth.Simulation(wetcloth.load_scene(nx=3, ny=3)).advance(0.01)  # one untimed run first
    if args.pile_only:
        pile_at_frame_steps(args.repeat, args.pile_duration)
        return
    if not args.landing_only:
        hanging_sheet_cost(args.repeat, args.hanging_duration)
    if args.hanging_only:
        return
    landing_share(args.repeat)
    if args.landing_only:
        return
    towel_overhead(args.repeat)
    folding_cost(max(1, args.repeat // 2))
    pile_at_frame_steps(max(1, args.repeat // 2), args.pile_duration)
    if not args.skip_stability:
        stability()


if __name__ == "__main__":
    main()
