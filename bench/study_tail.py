"""How a study's time spreads over its runs: the share of the costliest 5 % (issue 25 asks for at most 15 %
on the sensitivity example).

    .venv/bin/python bench/study_tail.py [--study models/studies/towel_sink_sensitivity.toml] [--top 5] [--every 1]

Runs every run of the study serially through ``wetcloth.batch.engines.python_series`` (what the batch
runner's workers call), after one short untimed warm-up run, and prints the CPU time of the whole,
the median and largest run, the share of the costliest 5 %, and the factors of the costliest runs.
``--every k`` runs every k-th run only (a quicker look; the shares are then those of that subset).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

from wetcloth.batch.engines import python_series  # noqa: E402
from wetcloth.batch.spec import load_study  # noqa: E402
from wetcloth.scene import preset_dir  # noqa: E402


def study_runs(description: str, top: int | None, top_help: str = "", every: int = 1, more=None):
    """The command line of a study benchmark (--study, --every, and --top unless top is None; ``more(parser)``
    adds its own): its arguments, the study and the runs to take (every ``--every``-th)."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--study", type=Path, default=preset_dir() / "studies" / "towel_sink_sensitivity.toml")
    if top is not None:
        parser.add_argument("--top", type=int, default=top, help=f"{top_help} (default {top})")
    parser.add_argument("--every", type=int, default=every, help=f"run every k-th run only (default {every})")
    if more is not None:
        more(parser)
    args = parser.parse_args()
    if args.every < 1:
        parser.error("--every must be at least 1")
    study = load_study(args.study)
    return args, study, study.runs()[:: args.every]


def main() -> None:
    args, study, runs = study_runs(__doc__.splitlines()[0], 5, "costliest runs to list")
    python_series(runs[0].params, 0.1, study.sample_rate)
    seconds = []
    for run in runs:
        start = time.process_time()
        python_series(run.params, study.duration, study.sample_rate)
        seconds.append(time.process_time() - start)
    seconds = np.array(seconds)
    order = np.argsort(seconds)[::-1]
    tail = order[: max(1, round(0.05 * len(runs)))]
    print(f"{args.study.name}: {len(runs)} runs, {seconds.sum():.1f} s of CPU, median run {np.median(seconds):.3f} s, "
          f"costliest {seconds.max():.2f} s; the costliest 5 % ({len(tail)} runs) take "
          f"{seconds[tail].sum() / seconds.sum():.1%}")
    factors = [axis.name for axis in study.axes]
    for i in order[: args.top]:
        described = ", ".join(f"{k} {runs[i].params[k]:.4g}" for k in factors if k in runs[i].params)
        print(f"  {seconds[i]:.2f} s: {described}")


if __name__ == "__main__":
    main()
