"""Run a study's runs on Dask and keep the results table: submission, results, safe points.

Each run is one ``Client.submit`` task (``wetcloth.batch.engines.execute``) on the client of
``wetcloth.batch.cluster.dask_client``.  A worker that dies mid-run is replaced (its Nanny restarts
it) and the scheduler reruns its tasks elsewhere, up to Dask's
``distributed.scheduler.allowed-failures`` times; past that, the run is recorded as an error
(``KilledWorker``) and the study goes on.  Results are written to the Parquet table at safe points
(every ``flush_interval`` s and at the end, also when interrupted), whole or not at all, and a
rerun skips the runs whose ``run_key`` is already in the table.  A study that keeps curves
(``series``) appends them to ``NAME.series.zarr`` beside the table at the same safe points, after the
table (``wetcloth.batch.series``); a run whose row is in the table but whose curves are not in the store
(the study had no ``series`` then, or was killed between the two) is run again, and its row replaced.
"""

from __future__ import annotations

import math
import sys
import time
import uuid
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import pandas as pd
from tqdm.auto import tqdm

from wetcloth.batch import cluster
from wetcloth.batch.engines import ERROR, OK, execute, fmu_path_or_default
from wetcloth.batch.results import KEY, full_row, make_table, normalise, read_table, write_table
from wetcloth.batch.series import SeriesStore, curves_dataset, select_runs, series_path
from wetcloth.batch.spec import Run, Study, load_study
from wetcloth.scene import from_dict

FLUSH_INTERVAL = 2.0  # s between writes of the results table while a study runs


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
    series: Any = None  # the kept curves of the study's runs (xarray Dataset), if it keeps any
    series_path: Path | None = None  # where they are kept (NAME.series.zarr beside the table)
    for_curves: int = 0  # of the runs run now: those run again only because their curves were missing

    def summary(self) -> str:
        text = f"{self.study.name}: {self.total} runs"
        if self.skipped:
            text += f", {self.skipped} already in {self.out}"
        text += f"; ran {self.ran}: {self.ok} ok, {self.failed} failed"
        if self.for_curves:
            text += f" ({self.for_curves} of them again, for curves missing from {self.series_path})"
        if self.ran:
            text += f", in {self.elapsed:.1f} s ({60.0 * self.ran / max(self.elapsed, 1e-9):.0f} runs/min)"
        return text


def _task(run: Run, study: Study) -> dict[str, Any]:
    return dict(key=run.key, params=run.params, duration=study.duration, sample_rate=study.sample_rate,
                sink_depth=study.sink_depth, metrics=list(study.metrics), engine=study.engine,
                fmu=fmu_path_or_default(study.fmu) if study.engine == "fmu" else "", series=list(study.series))


def as_study(spec, name: str | None = None) -> Study:
    """A Study from a Study, a study file path, or a dict in the study-file layout."""
    if isinstance(spec, Study):
        return spec
    if isinstance(spec, (str, Path)):
        return load_study(spec)
    if isinstance(spec, dict):
        return Study.from_dict(spec, base_dir=Path.cwd(), name=name or spec.get("name", "study"))
    raise TypeError(f"a study is a Study, a study TOML path or a dict, got {type(spec).__name__}")


def without_retried(existing: pd.DataFrame, runs: list[Run], retry_errors: bool) -> pd.DataFrame:
    """The rows of ``existing`` that count as done for ``runs``: all, or with ``retry_errors`` all but
    the runs' error rows (those are run again)."""
    if not (retry_errors and len(existing)):
        return existing
    return existing[~(existing[KEY].isin({r.key for r in runs}) & (existing["status"] == ERROR))]


def runs_to_do(runs: list[Run], existing: pd.DataFrame, retry_errors: bool = False,
               curves: set[str] | None = None) -> list[Run]:
    """The ``runs`` a study still has to run: not in the ``existing`` table (or recorded as errors,
    with ``retry_errors``), and, for a study that keeps curves, the ok runs whose curves are not among
    ``curves`` (the run keys the series store holds whole; None: the study keeps none)."""
    done = without_retried(existing, runs, retry_errors)
    if curves is not None and len(done):  # an ok row counts as done only with its curves
        done = done[(done["status"] != OK) | done[KEY].isin(curves)]
    done = set(done[KEY])
    return [r for r in runs if r.key not in done]


def series_store(study: Study, out: str | Path | None) -> SeriesStore | None:
    """The store of ``study``'s curves beside the table ``out`` (None: it keeps none, or nothing is saved)."""
    return SeriesStore(series_path(out)) if out is not None and study.series else None


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
    announce: Callable[[str], None] | None = None,
) -> StudyReport:
    """Run every run of ``study`` not yet in the table at ``out`` (Parquet; None = keep in memory).

    Runs go to ``client``, else to the cluster at ``scheduler``, else to a local cluster of
    ``workers`` processes started for this call (only if there is something to run).
    ``retry_errors`` runs again the runs recorded as errors.  ``on_result(row)`` is called in
    this process after each run is recorded; ``announce(line)`` is given the Dask dashboard's
    address when this call connects to a scheduler or starts a local cluster.  Returns a
    :class:`StudyReport`.
    """
    cluster.check_workers(workers)
    start = time.perf_counter()
    runs = study.runs()
    out = Path(out) if out is not None else None
    existing = read_table(out) if out is not None else make_table([])
    study_keys = {r.key for r in runs}
    existing = without_retried(existing, runs, retry_errors)
    store = series_store(study, out)
    complete = store.complete_keys(study.series) if store is not None else None
    todo = runs_to_do(runs, existing, curves=complete)
    for_curves = len(set(existing[KEY]) & {r.key for r in todo}) if store is not None else 0
    new_rows: list[dict[str, Any]] = []
    new_curves: list[tuple[Run, dict]] = []  # not yet in the store (all of them without out)
    counts = {OK: 0, ERROR: 0}
    last_flush = time.monotonic()

    def combined() -> pd.DataFrame:
        new = make_table(new_rows, study.axis_names)
        old = existing[~existing[KEY].isin(set(new[KEY]))] if len(new) else existing  # a row run again replaces its old one
        frames = [f for f in (old, new) if len(f)]
        if not frames:
            return make_table([], study.axis_names)
        return normalise(pd.concat(frames, ignore_index=True), study.axis_names)

    def flush(force: bool = False) -> None:
        nonlocal last_flush
        if out is not None and new_rows and (force or time.monotonic() - last_flush >= flush_interval):
            save(combined())
            if store is not None and new_curves:  # after the table: a run in the store is always in the table
                save_curves()
            last_flush = time.monotonic()

    def save_curves() -> None:
        try:
            store.write(curves_dataset(new_curves, study), complete)
        except OSError as exc:
            raise OSError(f"cannot save the study's curves in {store.path} ({exc.strerror or exc}); the "
                          f"{len(new_curves)} runs finished now are in the table without them: a rerun runs "
                          "them again") from None
        complete.update(run.key for run, _ in new_curves)
        new_curves.clear()

    def save(table: pd.DataFrame) -> None:
        try:
            write_table(table, out)
        except OSError as exc:  # a full disk: the table on disk stays whole, as it was
            raise OSError(f"cannot save the results table {out} ({exc.strerror or exc}): it is left as it was; "
                          f"the {len(new_rows)} runs finished now are not in it") from None

    bar = tqdm(total=len(todo), desc=study.name, unit="run", disable=not (progress and todo), dynamic_ncols=True)

    def record(run: Run, result: dict[str, Any]) -> None:
        curves = result.pop("series", None)
        if curves is not None and study.series:
            new_curves.append((run, curves))
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
            _run_on_dask(tasks, study, record, client=client, scheduler=scheduler, workers=workers,
                         announce=None if announce is None else lambda line: _beside(announce, line))
    finally:
        bar.close()
        flush(force=True)
    table = combined()
    mine = normalise(table.set_index(KEY, drop=False).loc[[r.key for r in runs]], study.axis_names)  # in run order
    if out is not None and new_rows:  # other studies' rows first, then this study's in run order
        save(normalise(pd.concat([table[~table[KEY].isin(study_keys)], mine]), study.axis_names))
    curves = None
    if store is not None:
        curves = select_runs(store.open(), [r.key for r in runs])
    elif study.series and new_curves:  # nothing saved: the curves of this call, in memory
        by_key = {run.key: (run, c) for run, c in new_curves}
        curves = curves_dataset([by_key[r.key] for r in runs if r.key in by_key], study)
    if curves is None and study.series:  # kept, but no run has any (none finished ok)
        curves = curves_dataset([], study)
    return StudyReport(
        study=study, table=mine, total=len(runs), skipped=len(runs) - len(todo),
        ran=len(new_rows), ok=counts[OK], failed=counts[ERROR], elapsed=time.perf_counter() - start, out=out,
        series=curves, series_path=store.path if store is not None else None, for_curves=for_curves,
    )


def _beside(announce: Callable[[str], None], line: str) -> None:
    """``announce(line)`` with the progress bar cleared first and drawn again after, not overwritten."""
    with tqdm.external_write_mode(file=sys.stderr):  # the bar writes to stderr
        announce(line)


class WorkerWatch:
    """Says when the cluster has lost workers for good: fewer than the most it had, for longer than
    ``lost_after`` s (a Nanny restarts a worker that died within a few seconds), once per new count.
    ``count()`` gives the workers connected now, ``say(line)`` is told."""

    def __init__(self, count: Callable[[], int], say: Callable[[str], None], lost_after: float | None = None,
                 clock: Callable[[], float] = time.monotonic):
        self.count, self.say, self.clock = count, say, clock
        self.lost_after = LOST_AFTER if lost_after is None else lost_after
        self.peak, self.short_since, self.said = 0, None, None

    def look(self) -> None:
        now, workers = self.clock(), self.count()
        if workers >= self.peak:
            self.peak, self.short_since, self.said = workers, None, None
            return
        if self.short_since is None:
            self.short_since = now
        if now - self.short_since < self.lost_after or workers == self.said:
            return
        self.said = workers
        lost = f"wetcloth batch: {self.peak - workers} of {self.peak} Dask workers lost (gone for {self.lost_after:g} s)"
        if workers:
            self.say(f"{lost}; the study goes on with {workers}, slower")
        else:
            self.say(f"{lost}; none is left: the runs wait for a worker to connect (Ctrl-C stops the study, "
                     "the finished runs are saved)")


#: s between looks at the cluster's workers while a study runs, and how long one must be missing to be
#: said lost (longer than a Nanny takes to restart a worker that died).
WATCH_INTERVAL, LOST_AFTER = 1.0, 15.0


def _warn(line: str) -> None:
    warnings.warn(line, RuntimeWarning, stacklevel=3)


def _run_on_dask(tasks: list[Run], study: Study, record, *, client, scheduler, workers, announce) -> None:
    from distributed import as_completed

    with cluster.dask_client(client, scheduler, workers, announce=announce) as c:
        tag = uuid.uuid4().hex[:8]  # one submission's keys never collide with an earlier one's
        futures = {c.submit(execute, _task(run, study), key=f"wetcloth-{run.key}-{tag}", pure=False): run
                   for run in tasks}
        watch = WorkerWatch(lambda: len(c.scheduler_info()["workers"]), announce or _warn)
        next_look = time.monotonic()
        try:
            done = as_completed(list(futures), loop=c.loop)
            while done.count():
                if time.monotonic() >= next_look:  # between the results: whether workers were lost for good
                    watch.look()
                    next_look = time.monotonic() + WATCH_INTERVAL
                if not done.has_ready():
                    time.sleep(0.02)
                    continue
                for future in done.next_batch(block=False):
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
    ``progress``: a progress bar, and the Dask dashboard's address on stderr when a cluster is used.
    """
    s = as_study(spec)
    changes = {k: v for k, v in dict(engine=engine, fmu=None if fmu is None else str(fmu)).items() if v is not None}
    if changes:
        s = s.replace(**changes)
    return run_study(s, out, client=client, scheduler=scheduler, workers=workers, progress=progress,
                     retry_errors=retry_errors, announce=_to_stderr if progress else None).table


def _to_stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)
