"""Steps and redone steps of a study's runs (deterministic on one machine: no timing), the counts behind
``bench/study_tail.py``'s CPU seconds.

    .venv/bin/python bench/study_steps.py [--study models/studies/towel_sink_sensitivity.toml] [--top 8] [--every 1]

Runs each run as the batch runner's Python engine does (samples at the study's rate, in compiled code) and
prints the total of steps and of steps taken again (``Simulation.steps``, ``rejected_steps``), and the runs
with the most of both together.  ``--every k`` runs every k-th run only, as in ``study_tail.py``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from wetcloth.batch.spec import load_study  # noqa: E402
from wetcloth.runner import frame_times  # noqa: E402
from wetcloth.scene import from_dict, preset_dir  # noqa: E402
from wetcloth.simulation import Simulation  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--study", type=Path, default=preset_dir() / "studies" / "towel_sink_sensitivity.toml")
    parser.add_argument("--top", type=int, default=8, help="runs with the most steps to list (default 8)")
    parser.add_argument("--every", type=int, default=1, help="run every k-th run only (default 1: all)")
    args = parser.parse_args()
    if args.every < 1:
        parser.error("--every must be at least 1")
    study = load_study(args.study)
    runs = study.runs()[:: args.every]
    times = frame_times(study.duration, study.sample_rate)
    steps, redone = [], []
    for run in runs:
        sim = Simulation(from_dict(run.params))
        sim.sample(times)
        steps.append(sim.steps)
        redone.append(sim.rejected_steps)
    steps, redone = np.array(steps), np.array(redone)
    tries = steps + redone
    print(f"{args.study.name}: {len(runs)} runs, {steps.sum()} steps and {redone.sum()} taken again "
          f"({tries.sum()} in all)")
    for i in np.argsort(tries)[::-1][: args.top]:
        print(f"  run {i * args.every}: {steps[i]} steps, {redone[i]} taken again")


if __name__ == "__main__":
    main()
