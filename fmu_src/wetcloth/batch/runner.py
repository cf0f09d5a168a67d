"""Run a study on Dask: a local cluster of processes by default, or any running scheduler.

Each run is one ``Client.submit`` task (``wetcloth.batch.engines.execute``).  A worker that dies
mid-run is replaced (its Nanny restarts it) and the scheduler reruns its tasks elsewhere, up to
Dask's ``distributed.scheduler.allowed-failures`` times; past that, the run is recorded as an
error (``KilledWorker``) and the study goes on.  Results are written to the Parquet table at
safe points (every ``flush_interval`` s and at the end, also when interrupted), and a rerun skips
the runs whose ``run_key`` is already in the table.
"""

from __future__ import annotations

import logging
import math
import signal
import time
import uuid
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import pandas as pd
from tqdm.auto import tqdm

from wetcloth.batch.engines import ERROR, OK, execute, fmu_path_or_default
from wetcloth.batch.results import KEY, make_table, normalise, read_table, full_row, write_table
from wetcloth.batch.study import Run, Study, load_study
from wetcloth.scene import from_dict

FLUSH_INTERVAL = 2.0  # s between writes of the results table while a study runs
LOCAL_HTTP = "127.0.0.1:0"  # the local cluster's dashboard / HTTP address: any free port, loopback only
SCHEDULER_TIMEOUT = 60.0  # s to connect to a scheduler, and then for the workers asked for to connect


@dataclass
class StudyReport:
    """What one invocation did: the study's table (every run, in order) and the counts."""

    study: Study
    table: pd.DataFrame
    total: int  # runs in the study
    skipped: int  # already in the results table
    ran: int  # run now (including runs rejected before reaching a worker)
    ok: int  # of those, status 'ok'
    failed: int  # of those, status 'error'
    elapsed: float  # s of wall-clock time
    out: Path | None

    def summary(self) -> str:
        text = f"{self.study.name}: {self.total} runs"
        if self.skipped:
            text += f", {self.skipped} already in {self.out}"
        text += f"; ran {self.ran}: {self.ok} ok, {self.failed} failed"
        if self.ran:
            text += f", in {self.elapsed:.1f} s ({60.0 * self.ran / max(self.elapsed, 1e-9):.0f} runs/min)"
        return text


def _check_workers(workers) -> int | None:
    if workers is None:
        return None
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be a whole number >= 1, got {workers!r}")
    return workers


@contextmanager
def dask_client(client=None, scheduler: str | None = None, workers: int | None = None, timeout: float | None = None):
    """A Dask client: ``client`` as given; one connected to ``scheduler`` (waiting for ``workers``;
    ``timeout`` s each, default ``SCHEDULER_TIMEOUT``); or a local cluster of ``workers``
    single-threaded processes (default one per core) that starts here and stops on exit."""
    workers = _check_workers(workers)
    timeout = SCHEDULER_TIMEOUT if timeout is None else timeout
    if client is not None:
        yield client
        return
    from dask.system import CPU_COUNT  # the cores this process may use (affinity and cgroup limits)
    from distributed import Client, LocalCluster

    if scheduler:
        with Client(scheduler, set_as_default=False, timeout=timeout) as c:
            if workers:
                c.wait_for_workers(workers, timeout=timeout)
            yield c
        return
    # the scheduler always serves HTTP: on a free port of this machine only, not on 8787 of every interface
    with LocalCluster(n_workers=workers or CPU_COUNT, threads_per_worker=1, processes=True,
                      dashboard_address=LOCAL_HTTP, silence_logs=logging.ERROR, preload=[__name__]) as cluster, \
            Client(cluster, set_as_default=False) as c:
        yield c


def dask_setup(worker) -> None:
    """Preload of the local cluster's workers (Dask calls it in each worker process as it starts):
    ignore SIGINT.  Ctrl-C in a terminal reaches every process of the group; this process then
    cancels the runs and stops the workers, which would otherwise each print a traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _task(run: Run, study: Study) -> dict[str, Any]:
    return dict(key=run.key, params=run.params, duration=study.duration, sample_rate=study.sample_rate,
                sink_depth=study.sink_depth, metrics=list(study.metrics), engine=study.engine,
                fmu=fmu_path_or_default(study.fmu) if study.engine == "fmu" else "")


def as_study(spec, name: str | None = None) -> Study:
    """A Study from a Study, a study file path, or a dict in the study-file layout."""
    if isinstance(spec, Study):
        return spec
    if isinstance(spec, (str, Path)):
        return load_study(spec)
    if isinstance(spec, dict):
        return Study.from_dict(spec, base_dir=Path.cwd(), name=name or spec.get("name", "study"))
    raise TypeError(f"a study is a Study, a study TOML path or a dict, got {type(spec).__name__}")


def run_study(
    study: Study,
    out: str | Path | None = None,
    *,
    client=None,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool = False,
    retry_errors: bool = False,
    flush_interval: float = FLUSH_INTERVAL,
    on_result: Callable[[dict[str, Any]], None] | None = None,
) -> StudyReport:
    """Run every run of ``study`` not yet in the table at ``out`` (Parquet; None = keep in memory).

    Runs go to ``client``, else to the cluster at ``scheduler``, else to a local cluster of
    ``workers`` processes started for this call (only if there is something to run).
    ``retry_errors`` runs again the runs recorded as errors.  ``on_result(row)`` is called in
    this process after each run is recorded.  Returns a :class:`StudyReport`.
    """
    _check_workers(workers)
    start = time.perf_counter()
    runs = study.runs()
    out = Path(out) if out is not None else None
    existing = read_table(out) if out is not None else make_table([])
    study_keys = {r.key for r in runs}
    if retry_errors and len(existing):
        existing = existing[~(existing[KEY].isin(study_keys) & (existing["status"] == ERROR))]
    done = set(existing[KEY])
    todo = [r for r in runs if r.key not in done]
    new_rows: list[dict[str, Any]] = []
    counts = {OK: 0, ERROR: 0}
    last_flush = time.monotonic()

    def combined() -> pd.DataFrame:
        frames = [f for f in (existing, make_table(new_rows, study.axis_names)) if len(f)]
        if not frames:
            return make_table([], study.axis_names)
        return normalise(pd.concat(frames, ignore_index=True), study.axis_names)

    def flush(force: bool = False) -> None:
        nonlocal last_flush
        if out is not None and new_rows and (force or time.monotonic() - last_flush >= flush_interval):
            write_table(combined(), out)
            last_flush = time.monotonic()

    bar = tqdm(total=len(todo), desc=study.name, unit="run", disable=not (progress and todo), dynamic_ncols=True)

    def record(run: Run, result: dict[str, Any]) -> None:
        row = full_row(run, study, result)
        new_rows.append(row)
        counts[row["status"]] += 1
        bar.set_postfix_str(f"ok {counts[OK]}, failed {counts[ERROR]}", refresh=False)  # runs done: the bar's count
        bar.update(1)
        if on_result is not None:
            on_result(row)
        flush()

    try:
        tasks = []
        for run in todo:  # scene errors (a value out of range) need no worker
            try:
                from_dict(run.params)
            except ValueError as exc:
                record(run, dict(status=ERROR, error=f"{type(exc).__name__}: {exc}", run_time=0.0, cpu_time=0.0,
                                 worker=None))
            else:
                tasks.append(run)
        if tasks:
            _run_on_dask(tasks, study, record, client=client, scheduler=scheduler, workers=workers)
    finally:
        bar.close()
        flush(force=True)
    table = combined()
    mine = normalise(table.set_index(KEY, drop=False).loc[[r.key for r in runs]], study.axis_names)  # in run order
    if out is not None and new_rows:  # other studies' rows first, then this study's in run order
        write_table(normalise(pd.concat([table[~table[KEY].isin(study_keys)], mine]), study.axis_names), out)
    return StudyReport(
        study=study, table=mine, total=len(runs), skipped=len(runs) - len(todo),
        ran=len(new_rows), ok=counts[OK], failed=counts[ERROR], elapsed=time.perf_counter() - start, out=out,
    )


def _run_on_dask(tasks: list[Run], study: Study, record, *, client, scheduler, workers) -> None:
    from distributed import as_completed

    with dask_client(client, scheduler, workers) as c:
        tag = uuid.uuid4().hex[:8]  # one submission's keys never collide with an earlier one's
        futures = {c.submit(execute, _task(run, study), key=f"wetcloth-{run.key}-{tag}", pure=False): run
                   for run in tasks}
        try:
            for future in as_completed(list(futures), loop=c.loop):
                run = futures.pop(future)
                if future.status == "finished":
                    result = future.result()
                else:  # the task itself failed in Dask (e.g. KilledWorker: its workers kept dying)
                    exc = future.exception()
                    result = dict(status=ERROR, error=f"{type(exc).__name__}: {exc}", run_time=math.nan,
                                  cpu_time=math.nan, worker=None)
                future.release()
                record(run, result)
        finally:
            if futures:  # interrupted: do not leave work on a shared cluster
                c.cancel(list(futures))


def study(
    spec,
    *,
    out: str | Path | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    client=None,
    engine: str | None = None,
    fmu: str | Path | None = None,
    progress: bool = False,
    retry_errors: bool = False,
) -> pd.DataFrame:
    """Run a batch study and return its table (pandas DataFrame, one row per run, in run order).

    ``spec``: a study TOML path, a dict in the same layout, or a :class:`Study`.  With ``out``
    (a Parquet path) results are saved as they come and a rerun skips the runs already there.
    Runs go to ``client``, or the Dask scheduler at ``scheduler``, or a local cluster of
    ``workers`` processes (default one per core).  ``engine``: 'python' (default) or 'fmu'.
    """
    s = as_study(spec)
    changes = {k: v for k, v in dict(engine=engine, fmu=None if fmu is None else str(fmu)).items() if v is not None}
    if changes:
        s = s.replace(**changes)
    return run_study(s, out, client=client, scheduler=scheduler, workers=workers, progress=progress,
                     retry_errors=retry_errors).table
