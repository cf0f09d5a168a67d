"""``models/studies/sink_map.toml`` end to end with whichever wetcloth is imported, at its own defaults.

    .venv/bin/python bench/study_end_to_end.py [--repeat 2]

Runs the study's 16 runs serially through ``wetcloth.batch.engines.python_series`` (what the batch
runner's workers call) and prints the wall time of the 16 (best of ``--repeat``), after one short
untimed warm-up run (in code older than the compiled core, where numba compiles or loads the kernels).
To compare with another version of the code, check it out beside this one and put it first on the
path, alternating the two on the same machine, e.g. against the code as it was when issue 11 (large
steps) was filed:

    git worktree add --detach /tmp/wt-filed 63363dd^
    PYTHONPATH=/tmp/wt-filed/fmu_src .venv/bin/python bench/study_end_to_end.py
    .venv/bin/python bench/study_end_to_end.py

Unlike ``bench/sink_map_speed.py``, which runs today's code with two integrators, this measures what
a user of each version waits for; the older code's symplectic Euler lacks every speed-up the two
integrators share today.
"""

from __future__ import annotations

import argparse
import time

import wetcloth
from wetcloth.batch.engines import python_series

from _sink_map import sink_map_runs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    study, runs = sink_map_runs()
    best = float("inf")
    for _ in range(args.repeat):
        start = time.perf_counter()
        for run in runs:
            python_series(run.params, study.duration, study.sample_rate)
        best = min(best, time.perf_counter() - start)
    print(f"sink_map ({len(runs)} runs of {study.duration:g} s) with {wetcloth.__file__}: {best:.2f} s "
          f"(best of {args.repeat})")


if __name__ == "__main__":
    main()
