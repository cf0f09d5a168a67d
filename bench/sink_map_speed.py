"""``models/studies/sink_map.toml`` end to end, serially, with the default integrator and the previous one.

    .venv/bin/python bench/sink_map_speed.py [--repeat 2]

Each of the study's 16 runs goes through the same function the batch runner's workers call
(``wetcloth.batch.engines.python_series``: ``wetcloth.runner.run`` at the study's sample rate), once
with the study's parameters (the current default integrator) and once with the previous default
(symplectic Euler, tolerance 1e-4, steps up to 0.01 s), alternately in this process; the
study's time is the sum of its runs (best of ``--repeat``).  The time to sink of each run is
compared between the two.  Wall time is what a user waits for; the CPU time of the thread that ran
the runs (also printed) is less disturbed by other work on a shared machine.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from wetcloth.batch.engines import python_series

from _sink_map import sink_map_runs

PREVIOUS = dict(integrator="symplectic_euler", tolerance=1e-4, max_step=0.01)


def sink_time(series: dict, depth: float) -> float:
    hits = np.flatnonzero(series["depth"] > depth)
    return float(series["time"][hits[0]]) if hits.size else float("nan")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    study, runs = sink_map_runs()
    totals = {"default": float("inf"), "previous": float("inf")}
    cpu_totals = dict(totals)
    sinks = {}
    for _ in range(args.repeat):
        spent = {"default": 0.0, "previous": 0.0}
        cpu = {"default": 0.0, "previous": 0.0}
        for run in runs:
            for name, overrides in (("default", {}), ("previous", PREVIOUS)):
                start, cpu_start = time.perf_counter(), time.thread_time()
                series = python_series(run.params | overrides, study.duration, study.sample_rate)
                spent[name] += time.perf_counter() - start
                cpu[name] += time.thread_time() - cpu_start
                sinks.setdefault(run.key, {})[name] = sink_time(series, study.sink_depth)
        for name in totals:
            totals[name] = min(totals[name], spent[name])
            cpu_totals[name] = min(cpu_totals[name], cpu[name])
        print(f"default {spent['default']:.2f} s, previous {spent['previous']:.2f} s for {len(runs)} runs "
              f"(CPU {cpu['default']:.2f} s, {cpu['previous']:.2f} s: {cpu['previous'] / cpu['default']:.1f}x)", flush=True)
    differences = [abs(s["default"] - s["previous"]) for s in sinks.values()
                   if np.isfinite(s["default"]) and np.isfinite(s["previous"])]
    sunk = sum(np.isfinite(s["previous"]) for s in sinks.values())
    print(f"\nsink_map ({len(runs)} runs of {study.duration:g} s): {totals['default']:.2f} s against "
          f"{totals['previous']:.2f} s, {totals['previous'] / totals['default']:.1f}x faster (best of {args.repeat}; "
          f"CPU time of this thread {cpu_totals['previous'] / cpu_totals['default']:.1f}x); "
          f"time to sink differs by at most {max(differences, default=0.0):.3f} s over the {sunk} runs that sank")


if __name__ == "__main__":
    main()
