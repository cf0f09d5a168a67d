"""Overhead of a sensitivity study over the same number of plain runs, on one warm local Dask cluster.

    .venv/bin/python bench/batch_sensitivity.py                          # 64 runs of a 5 x 5 towel, 2 s each
    .venv/bin/python bench/batch_sensitivity.py --samples 16 --nx 5 --ny 7 --duration 60 --markdown

The sensitivity study is the towel example's (models/studies/towel_sink_sensitivity.toml: six
factors, a Sobol' design of ``samples`` base samples, so ``samples x 8`` runs; three metrics that
every run has, whatever its duration: final_depth, final_wet_mass, final_water_mass); the plain study has
the same six axes as bounds and as many runs, placed by independent random draws.  Both run on the
same warm cluster (workers started and warmed once, not timed), in memory (no table file), one
after the other in each of ``--repeat`` rounds.  Timed apart, each the best of its rounds:

- making the runs (``Study.runs()``: the design or the draws, and the run keys),
- running them (``run_study``),
- for the sensitivity study, its indices (``sensitivity_indices``: SALib's bootstrap), the CSV and
  the bar plot.

The overhead is the sensitivity study's total over the plain study's.  The machine's load average
is printed: on a shared machine the run phase varies more than the overhead does.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import tempfile
import time
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "models" / "studies" / "towel_sink_sensitivity.toml"
#: Three metrics, as the example has, that every run has whatever its duration (a short run does not sink).
METRICS = ("final_depth", "final_wet_mass", "final_water_mass")


def studies(samples: int, nx: int, ny: int, duration: float):
    """(sensitivity study, plain study with as many runs): the example's factors and settings."""
    from wetcloth.batch import load_study

    example = load_study(EXAMPLE)
    sensitivity = example.replace(base={"nx": nx, "ny": ny}, duration=duration, metrics=METRICS,
                                  sensitivity=dataclasses.replace(example.sensitivity, samples=samples))
    runs = len(sensitivity.runs())
    plain = sensitivity.replace(name="plain", sensitivity=None, samples=runs, sampling="random")
    return sensitivity, plain


def timed(work):
    """(wall-clock s of ``work()``, its result)."""
    start = time.perf_counter()
    result = work()
    return time.perf_counter() - start, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=8, help="Sobol' base samples, a power of 2 (default 8: 64 runs)")
    parser.add_argument("--nx", type=int, default=5, help="grid nx (default 5)")
    parser.add_argument("--ny", type=int, default=5, help="grid ny (default 5)")
    parser.add_argument("--duration", type=float, default=2.0, help="simulated s per run (default 2)")
    parser.add_argument("--workers", type=int, default=2, help="local workers (default 2)")
    parser.add_argument("--repeat", type=int, default=3, help="time each phase this many times, keep the best (default 3)")
    parser.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = parser.parse_args()

    from wetcloth.batch import dask_client, plot_sensitivity, run_study, sensitivity_indices, write_csv

    sensitivity, plain = studies(args.samples, args.nx, args.ny, args.duration)
    runs = len(plain.runs())
    print(f"# {runs} runs of the towel, {args.nx} x {args.ny} grid, {args.duration:g} s each, {args.workers} local "
          f"workers; {os.cpu_count()} cores, {platform.processor() or platform.machine()}; load average before: "
          f"{os.getloadavg()[0]:.2f}")
    best = {}  # (study name, phase) -> best s over the repeats
    inside = {}  # study name -> mean s of one run inside its worker, in its best repeat

    def keep(name: str, phase: str, seconds: float) -> bool:
        better = seconds < best.get((name, phase), float("inf"))
        if better:
            best[(name, phase)] = seconds
        return better

    with dask_client(workers=args.workers) as client, tempfile.TemporaryDirectory() as tmp:
        run_study(plain.replace(samples=args.workers, duration=min(1.0, args.duration)), client=client)  # warm-up
        for _ in range(args.repeat):  # interleaved, so that a busy spell of the machine hits both alike
            for study in (plain, sensitivity):
                keep(study.name, "make", timed(study.runs)[0])
                ran, report = timed(lambda: run_study(study, client=client))
                assert report.ok == report.total, report.table.loc[report.table.status != "ok", "error"].tolist()
                if keep(study.name, "run", ran):
                    inside[study.name] = float(report.table["run_time"].mean())
                if study.sensitivity is not None:
                    def analyse():
                        result = sensitivity_indices(study, report.table)
                        write_csv(result.indices, Path(tmp) / "indices.csv")
                        plot_sensitivity(result, Path(tmp) / "indices.png", study=study)
                        return result

                    analysis, result = timed(analyse)
                    assert not result.problems, result.problems
                    keep(study.name, "indices", analysis)
    rows = [(False, best[(plain.name, "make")], best[(plain.name, "run")], 0.0),
            (True, best[(sensitivity.name, "make")], best[(sensitivity.name, "run")], best[(sensitivity.name, "indices")])]
    (_, make0, ran0, _), (_, make1, ran1, analysis1) = rows
    total0, total1 = make0 + ran0, make1 + ran1 + analysis1
    table = [("plain (random draws)", make0, ran0, inside[plain.name], "-", total0, "1.00x"),
             (f"sensitivity (sobol, {args.samples} x 8)", make1, ran1, inside[sensitivity.name], f"{analysis1:.2f}",
              total1, f"{total1 / total0:.2f}x")]
    if args.markdown:
        print("| study | make the runs (s) | run them (s) | mean run in its worker (s) | indices + CSV + plot (s) "
              "| total (s) | vs plain |")
        print("|---|---|---|---|---|---|---|")
        for label, make, ran, run, analysis, total, ratio in table:
            print(f"| {label} | {make:.3f} | {ran:.2f} | {run:.3f} | {analysis} | {total:.2f} | {ratio} |")
    else:
        for label, make, ran, run, analysis, total, ratio in table:
            print(f"{label:32s} make {make:6.3f} s  run {ran:7.2f} s (mean run {run:.3f} s)  indices {analysis:>5s} s  "
                  f"total {total:7.2f} s  {ratio}")
    print(f"# overhead: {total1 - total0:+.2f} s over {runs} runs ({1e3 * (total1 - total0) / runs:+.1f} ms per run); "
          f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":  # required: Dask's worker processes re-import this file when they start
    main()
