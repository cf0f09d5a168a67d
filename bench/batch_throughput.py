"""Batch-study throughput (runs per minute) on a local Dask cluster of 1 and 2 worker processes.

    .venv/bin/python bench/batch_throughput.py                 # 16 runs, 17 x 17 towel, 30 s each
    .venv/bin/python bench/batch_throughput.py --runs 8 --nx 9 --workers 1 2 --markdown --engine fmu

For each worker count: start a local cluster (timed apart), warm every worker with one run
(its imports: wetcloth and its compiled core; nothing is compiled), then time ``run_study`` over
the whole study.  The
serial baseline runs the same scenes one after another in this process, without Dask, so the
table shows both the scaling and Dask's own overhead.  The machine's load average is printed
because other processes on a shared machine take cores away from the workers.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np


def make_study(runs: int, nx: int, duration: float, engine: str = "python"):
    from wetcloth.batch import Study

    rates = np.round(np.linspace(0.2, 2.0, runs), 6).tolist()  # one axis, every run a different scene
    return Study.from_dict(dict(scene="thesis_fast", duration=duration, sample_rate=10.0, engine=engine,
                                base=dict(nx=nx, ny=nx), axes=dict(absorption_rate=rates)), name="throughput")


def serial(study, repeat: int) -> tuple[float, float]:
    """(wall-clock s to run every scene in this process, no Dask, after one warm-up run, best of
    ``repeat``; CPU share: CPU time / wall-clock time of the runs)."""
    from wetcloth.batch.engines import execute
    from wetcloth.batch.execution import _task

    runs = study.runs()
    execute(_task(runs[0], study))  # warm-up, untimed: lazy imports, memory first touched
    best = None
    for _ in range(repeat):
        start = time.perf_counter()
        rows = [execute(_task(r, study)) for r in runs]
        elapsed = time.perf_counter() - start
        assert all(r["status"] == "ok" for r in rows), [r["error"] for r in rows if r["status"] != "ok"]
        if best is None or elapsed < best[0]:
            best = (elapsed, sum(r["cpu_time"] for r in rows) / sum(r["run_time"] for r in rows))
    return best


def on_cluster(study, workers: int, repeat: int) -> tuple[float, float, float, float, float]:
    """(cluster start-up s, first run on every worker s, wall-clock s of the study on the warm
    cluster of ``workers`` processes (best of ``repeat``), mean wall-clock s of one run inside its
    worker in that repeat, and the runs' CPU share: CPU time / wall-clock time)."""
    from wetcloth.batch import dask_client, run_study
    from wetcloth.batch.engines import execute
    from wetcloth.batch.execution import _task

    start = time.perf_counter()
    with dask_client(workers=workers) as client:  # the local cluster 'wetcloth batch' starts
        client.wait_for_workers(workers)
        startup = time.perf_counter() - start
        start = time.perf_counter()
        short = study.replace(duration=1.0)
        warmups = [client.submit(execute, _task(short.runs()[0], short), workers=[address], pure=False)
                   for address in client.scheduler_info()["workers"]]
        client.gather(warmups)
        warmup = time.perf_counter() - start
        best = None
        for _ in range(repeat):
            start = time.perf_counter()
            report = run_study(study, client=client)
            elapsed = time.perf_counter() - start
            assert report.ok == report.total, report.table[report.table.status != "ok"]["error"].tolist()
            if best is None or elapsed < best[0]:
                t = report.table
                best = (elapsed, float(t["run_time"].mean()), float(t["cpu_time"].sum() / t["run_time"].sum()))
    return startup, warmup, *best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=16, help="runs in the study (default 16)")
    parser.add_argument("--nx", type=int, default=17, help="grid nx = ny (default 17)")
    parser.add_argument("--duration", type=float, default=30.0, help="simulated s per run (default 30)")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="worker counts (default 1 2)")
    parser.add_argument("--engine", choices=["python", "fmu"], default="python",
                        help="python simulator (default) or models/WetCloth.fmu through fmpy (built if stale)")
    parser.add_argument("--repeat", type=int, default=1, help="time each setting this many times, keep the best")
    parser.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = parser.parse_args()

    study = make_study(args.runs, args.nx, args.duration, args.engine)
    if args.engine == "fmu":
        from wetcloth.batch import default_fmu_path
        from wetcloth.fmu.builder import build_fmu, is_stale

        if is_stale(default_fmu_path()):
            build_fmu(default_fmu_path())
    print(f"# engine {args.engine}: {args.runs} runs of thesis_fast, {args.nx} x {args.nx} grid, {args.duration:g} s each; "
          f"{os.cpu_count()} cores, {platform.processor() or platform.machine()}; "
          f"load average before: {os.getloadavg()[0]:.2f}")
    base, base_cpu = serial(study, args.repeat)
    rows = [("serial, no Dask", 1, "-", "-", base, base / args.runs, base_cpu)]
    for n in args.workers:
        startup, warmup, elapsed, per_run, cpu = on_cluster(study, n, args.repeat)
        rows.append((f"Dask, {n} worker{'s' if n > 1 else ''}", n, f"{startup:.1f}", f"{warmup:.1f}", elapsed, per_run, cpu))
    one = next((r[4] for r in rows if r[0] == "Dask, 1 worker"), None)
    # busy: share of the workers' wall-clock time spent inside runs (the rest is Dask and idling);
    # CPU share: CPU time / wall-clock time of the runs, below 100% when other processes take the cores
    header = ("| setting | cluster start-up (s) | worker warm-up (s) | study wall time (s) | runs/min "
              "| speed-up vs 1 worker | mean run (s) | workers busy | CPU share of runs |")
    if args.markdown:
        print(header)
        print("|---|---|---|---|---|---|---|---|---|")
    for label, n, startup, warmup, elapsed, per_run, cpu in rows:
        rate = 60.0 * args.runs / elapsed
        speedup = f"{one / elapsed:.2f}x" if one and label.startswith("Dask") else "-"
        busy = f"{100 * per_run * args.runs / (n * elapsed):.0f}%"
        if args.markdown:
            print(f"| {label} | {startup} | {warmup} | {elapsed:.1f} | {rate:.1f} | {speedup} | {per_run:.2f} "
                  f"| {busy} | {100 * cpu:.0f}% |")
        else:
            print(f"{label:18s} start-up {startup:>5s} s  warm-up {warmup:>5s} s  study {elapsed:6.1f} s  "
                  f"{rate:6.1f} runs/min  speed-up {speedup}  mean run {per_run:.2f} s  busy {busy}  "
                  f"CPU share {100 * cpu:.0f}%")
    print(f"# load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":  # required: Dask's worker processes re-import this file when they start
    main()
