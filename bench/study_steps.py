"""Steps and redone steps of a study's runs (deterministic on one machine: no timing), the counts behind
``bench/study_tail.py``'s CPU seconds.

    .venv/bin/python bench/study_steps.py [--study models/studies/towel_sink_sensitivity.toml] [--top 8] [--every 1]

Runs each run as the batch runner's Python engine does (samples at the study's rate, in compiled code) and
prints the total of steps and of steps taken again (``Simulation.steps``, ``rejected_steps``), and the runs
with the most of both together.  ``--every k`` runs every k-th run only, as in ``study_tail.py``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from study_tail import study_runs  # noqa: E402
from wetcloth.runner import frame_times  # noqa: E402
from wetcloth.scene import from_dict  # noqa: E402
from wetcloth.simulation import Simulation  # noqa: E402


def main() -> None:
    args, study, runs = study_runs(__doc__.splitlines()[0], 8, "runs with the most steps to list")
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
