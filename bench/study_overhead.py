"""What a study's runs cost outside their steps (issue 25): per run, the CPU of ``python_series`` (what the
batch runner's workers call) beyond that of its steps, against ``runner.run`` with its columns (how
``python_series`` took a run's series before), and the CPU of building the run's scene and ``Simulation``.

    .venv/bin/python bench/study_overhead.py [--study models/studies/towel_sink_sensitivity.toml] [--every 8]

Runs each run three ways in one process, in turns that rotate from run to run: its ``Simulation`` built and
sampled at the study's rate (the build, then the steps: ``Simulation.sample``), ``python_series``, and
``runner.run`` (no shapes, no progress bar) with its columns; the same steps each time (the series agree bit
for bit).  A way's cost outside the steps is its CPU less the steps'; averaged over the runs, the steps'
own spread (about 1 % of a run) mostly cancels.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

from study_tail import study_runs  # noqa: E402
from wetcloth.batch.engines import RUN_SERIES, python_series  # noqa: E402
from wetcloth.runner import frame_times, run  # noqa: E402
from wetcloth.scene import from_dict  # noqa: E402
from wetcloth.simulation import Simulation  # noqa: E402


def sampled(params: dict, times: np.ndarray) -> tuple[float, float]:
    """CPU seconds of building the run's Simulation, and of sampling it at ``times`` (its steps)."""
    start = time.process_time()
    sim = Simulation(from_dict(params))
    built = time.process_time()
    sim.sample(times)
    return built - start, time.process_time() - built


def through_run(params: dict, duration: float, sample_rate: float) -> dict[str, np.ndarray]:
    """The run's series as python_series took them before: runner.run's rows, then their columns."""
    result = run(from_dict(params), duration, sample_rate, shapes=0, progress=False, warn=None)
    return {name: result.column(name) for name in RUN_SERIES}


def main() -> None:
    args, study, runs = study_runs(__doc__.splitlines()[0], None, every=8)
    times = frame_times(study.duration, study.sample_rate)
    python_series(runs[0].params, 0.1, study.sample_rate)  # warm-up
    cpu = np.zeros((len(runs), 4))  # build, steps, python_series, runner.run
    for i, item in enumerate(runs):
        ways = [lambda: sampled(item.params, times),
                lambda: python_series(item.params, study.duration, study.sample_rate),
                lambda: through_run(item.params, study.duration, study.sample_rate)]
        for w in np.roll(np.arange(3), i):
            start = time.process_time()
            got = ways[w]()
            if w == 0:
                cpu[i, :2] = got
            else:
                cpu[i, w + 1] = time.process_time() - start
    per_run = 1e3 * cpu.mean(axis=0)
    build, steps, series, rows = per_run
    print(f"{args.study.name}: {len(runs)} runs, CPU per run (ms): the steps {steps:.2f}; outside them "
          f"python_series {series - steps:.2f}, runner.run with its columns {rows - steps:.2f}; "
          f"building the scene and Simulation {build:.2f}")


if __name__ == "__main__":
    main()
