"""Where a study's steps go: each run's steps, steps taken again and CPU seconds before its towel first touches
the floor and after (the floor landing), and its metrics.

    .venv/bin/python bench/study_phases.py [--study models/studies/towel_sink_sensitivity.toml] [--every 8]
        [--top 5]

Runs each run frame by frame at the study's sample rate (``Simulation.advance``), a frame counted on the floor
once a particle's centre has reached the floor (``floor_z``) at its start, and prints per phase the total steps,
steps taken again and CPU seconds, then the runs with the most tries on the floor.  The metrics (those of the
study, from the frames' outputs as ``compute_metrics`` takes them) are printed summed, to compare branches: the
steps and metrics are deterministic on one machine, the CPU seconds are not.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

from study_tail import study_runs  # noqa: E402
from wetcloth.batch.metrics import SERIES, compute_metrics  # noqa: E402
from wetcloth.runner import frame_times  # noqa: E402
from wetcloth.scene import from_dict  # noqa: E402
from wetcloth.simulation import Simulation  # noqa: E402

PHASES = ("above the floor", "on the floor")


def run_phases(params: dict, duration: float, sample_rate: float, names: list[str]):
    """(steps, taken again, CPU s) per phase (2, 3) of one run, and its sampled outputs {name: series}."""
    sim = Simulation(from_dict(params))
    tally = np.zeros((2, 3))
    series = {name: [] for name in names}
    landed = False
    for t in frame_times(duration, sample_rate):
        landed = landed or bool((sim.state.pos[2] <= sim.model.floor_z).any())
        steps, redone, start = sim.steps, sim.rejected_steps, time.process_time()
        sim.advance(t - sim.time)
        tally[int(landed)] += (sim.steps - steps, sim.rejected_steps - redone, time.process_time() - start)
        outputs = sim.outputs()
        for name in names:
            series[name].append(outputs[name] if name != "time" else sim.time)
    return tally, {name: np.array(values) for name, values in series.items()}


def main() -> None:
    args, study, runs = study_runs(__doc__.splitlines()[0], 5, "runs with the most tries on the floor to list", every=8)
    names = list(SERIES)
    tallies, metrics = [], []
    for run in runs:
        tally, series = run_phases(run.params, study.duration, study.sample_rate, names)
        tallies.append(tally)
        metrics.append(compute_metrics(series, study.metrics, study.sink_depth))
    tallies = np.array(tallies)
    print(f"{study.name}: {len(runs)} runs")
    for p, phase in enumerate(PHASES):
        steps, redone, cpu = tallies[:, p].sum(axis=0)
        print(f"  {phase}: {int(steps)} steps, {int(redone)} taken again, {cpu:.2f} s of CPU")
    for name in metrics[0]:
        if name != "sank":
            print(f"  sum of {name}: {np.nansum([m[name] for m in metrics]):.6f}")
    tries = tallies[:, 1, 0] + tallies[:, 1, 1]
    for i in np.argsort(tries)[::-1][: args.top]:
        print(f"  run {i * args.every}: on the floor {int(tallies[i, 1, 0])} steps, {int(tallies[i, 1, 1])} taken again")


if __name__ == "__main__":
    main()
