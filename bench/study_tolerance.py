"""What a study's step tolerance costs and changes: each run of a study at several tolerances, its CPU time and
its metrics against those at the first tolerance given.

    .venv/bin/python bench/study_tolerance.py [--study models/studies/towel_sink_sensitivity.toml] [--every 8]
        [--tolerances 5e-6 1e-6 2e-5 5e-5]

Runs every ``--every``-th run of the study as its workers do (``python_series``), at each tolerance in turn,
and prints per tolerance the CPU seconds of all those runs and the largest and mean differences of the
study's time metrics (s) and the largest of its mass metrics (kg) from the first tolerance's.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

import numpy as np  # noqa: E402

from study_tail import study_runs  # noqa: E402
from wetcloth.batch.engines import python_series  # noqa: E402
from wetcloth.batch.metrics import compute_metrics  # noqa: E402


def main() -> None:
    def more(parser):
        parser.add_argument("--tolerances", type=float, nargs="+", default=[5e-6, 1e-6, 2e-5, 5e-5],
                            help="step tolerances, the first the reference (default 5e-6 1e-6 2e-5 5e-5)")

    args, study, runs = study_runs(__doc__.splitlines()[0], None, every=8, more=more)
    tolerances = args.tolerances
    cpu = dict.fromkeys(tolerances, 0.0)
    metrics = {t: [] for t in tolerances}
    for run in runs:
        for tolerance in tolerances:
            start = time.process_time()
            series = python_series(dict(run.params, tolerance=tolerance), study.duration, study.sample_rate)
            cpu[tolerance] += time.process_time() - start
            metrics[tolerance].append(compute_metrics(series, study.metrics, study.sink_depth))
    names = [name for name in metrics[tolerances[0]][0] if name != "sank"]
    reference = {name: np.array([m[name] for m in metrics[tolerances[0]]], float) for name in names}
    print(f"{len(runs)} runs of {study.name}, CPU and differences from tolerance {tolerances[0]:g}:")
    for tolerance in tolerances:
        parts = [f"tolerance {tolerance:8.1e}: {cpu[tolerance]:6.2f} s ({cpu[tolerances[0]] / cpu[tolerance]:.2f}x)"]
        for name in names:
            d = np.abs(np.array([m[name] for m in metrics[tolerance]], float) - reference[name])
            parts.append(f"{name} max {np.nanmax(d):.3g} mean {np.nanmean(d):.3g}")
        print("  " + "; ".join(parts), flush=True)


if __name__ == "__main__":
    main()
