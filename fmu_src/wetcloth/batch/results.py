"""The results table: one row per run, keyed by ``run_key``; Parquet on disk, written whole or not at all.

Columns, in order: ``run_key``; the study's axes; the metrics (``sank`` after ``time_to_sink``);
``status`` ('ok' or 'error'), ``error`` (the message, or empty), ``run_time`` (s of wall-clock time
in the worker), ``cpu_time`` (s of CPU time of the run), ``worker``; the run settings ``engine``,
``duration`` (s), ``sample_rate`` (Hz),
``sink_depth`` (m); then every other scene parameter, so each row says how to reproduce it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable

import pandas as pd

from wetcloth.batch.metrics import METRICS
from wetcloth.files import whole_file
from wetcloth.scene import PARAMETERS

KEY = "run_key"
STATUS_COLUMNS = ("status", "error", "run_time", "cpu_time", "worker")
SETTING_COLUMNS = ("engine", "duration", "sample_rate", "sink_depth")


def metric_columns(metrics: Iterable[str]) -> list[str]:
    """Metric column names in order, with ``sank`` right after ``time_to_sink``."""
    out = []
    for name in metrics:
        out.append(name)
        if name == "time_to_sink":
            out.append("sank")
    return out


def full_row(run, study, result: dict[str, Any]) -> dict[str, Any]:
    """A table row from a run (its parameters) and its result (status, error, metrics, run_time, worker)."""
    row = {KEY: run.key}
    row.update(run.point)
    for column in metric_columns(study.metrics):
        row[column] = result.get(column)
    for column in STATUS_COLUMNS:
        row[column] = result.get(column)
    row.update(engine=study.engine, duration=study.duration, sample_rate=study.sample_rate, sink_depth=study.sink_depth)
    for name, value in run.params.items():
        row.setdefault(name, value)
    return row


def column_order(columns: Iterable[str], axes: Iterable[str] = ()) -> list[str]:
    columns = list(columns)
    metric_cols = metric_columns(METRICS)
    first = [KEY, *axes, *metric_cols, *STATUS_COLUMNS, *SETTING_COLUMNS, *PARAMETERS]
    ordered = [c for c in dict.fromkeys(first) if c in columns]
    return ordered + [c for c in columns if c not in ordered]


def normalise(table: pd.DataFrame, axes: Iterable[str] = ()) -> pd.DataFrame:
    """Columns in the documented order and types: metrics float (NaN = none), ``sank`` nullable bool."""
    table = table[column_order(table.columns, axes)].reset_index(drop=True)
    for name in METRICS:
        if name in table:
            table[name] = pd.to_numeric(table[name], errors="coerce").astype("float64")
    if "sank" in table:
        table["sank"] = table["sank"].astype("boolean")
    for column in ("run_time", "cpu_time"):
        if column in table:
            table[column] = table[column].astype("float64")
    return table


def make_table(rows: list[dict[str, Any]], axes: Iterable[str] = ()) -> pd.DataFrame:
    return normalise(pd.DataFrame(rows, columns=None if rows else [KEY]), axes)


def read_table(path: str | Path) -> pd.DataFrame:
    """The results table at ``path`` (Parquet), or an empty table if there is none yet."""
    path = Path(path)
    if not path.exists():
        return make_table([])
    table = pd.read_parquet(path)
    if KEY not in table:
        raise ValueError(f"{path} is not a wetcloth results table (no '{KEY}' column)")
    return table


def write_table(table: pd.DataFrame, path: str | Path) -> Path:
    """Write ``table`` as Parquet, whole or not at all: a reader, a crash or a full disk never sees
    half a file, and a failed write leaves the previous table as it was."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with whole_file(path) as tmp, open(tmp, "wb") as fh:
        table.to_parquet(fh, index=False)
    return path


def write_csv(table: pd.DataFrame, path: str | Path) -> Path:
    """Write ``table`` as CSV (NaN as empty cells), whole or not at all."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with whole_file(path) as tmp, open(tmp, "w", newline="") as fh:
        table.to_csv(fh, index=False)
    return path
