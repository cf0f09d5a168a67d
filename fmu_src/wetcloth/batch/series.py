"""A study's curves: each run's outputs at the study's ``sample_rate``, kept as an xarray Dataset in Zarr.

A study with ``series = ["depth", "wet_mass"]`` saves those outputs of every run that finished ok
in ``NAME.series.zarr`` beside its results table ``NAME.parquet``: one Dataset with dims ``run``
and ``time``, readable with ``xarray.open_zarr``::

    depth     (run, time) float64  m    wet_mass  (run, time) float64  kg
    run       (run)   the run_key, as in the results table
    time      (time)  s, 0, 1/sample_rate, ... duration (the runner's frame times)
    <axis>    (run)   each study axis's value of the run, its unit as the attribute ``units``

Each variable carries ``units`` and ``long_name`` attributes.  The store is Zarr format 2 with
consolidated metadata (written by zarr-python 3): consolidated metadata is part of format 2 (that of
format 3 is not in its specification, and zarr-python warns on each write), and readers that know
only format 2 open it too.

**Whole or not at all.**  The runner appends the curves that arrived at each safe point of the
results table.  An append writes each file whole (zarr >= 3.1.3 writes a file beside its target and
renames it) and the consolidated metadata last, which readers use: a study killed in the middle of
an append leaves the store as it was before it, readable; the next writer first trims what the
killed append had begun (:meth:`SeriesStore.repair`).  A new store, and a store rewritten because
its layout changes (another time grid, new outputs or axes: :meth:`SeriesStore.write`), is written
in a folder beside it and renamed into place.  Curves already in the store are never written twice.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import threading
import uuid
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterable, Sequence

import numpy as np

from wetcloth.simulation import OUTPUT_NAMES, OUTPUTS

if TYPE_CHECKING:  # xarray is imported when curves are made or read, not with the study spec
    import xarray as xr

#: The suffix of a study's curves beside its table: ``out/batch/NAME.parquet`` -> ``NAME.series.zarr``.
SUFFIX = ".series.zarr"
#: Values of a curve chunk at most (about 2 MB of float64): rows of runs times samples of time.
CHUNK_VALUES = 262_144
#: Runs per chunk of the coordinates along ``run`` (run keys, axis values).
COORD_CHUNK = 4096


def series_path(table: str | Path) -> Path:
    """Where the curves of the results table ``table`` go: ``NAME.series.zarr`` beside ``NAME.parquet``."""
    table = Path(table)
    return table.with_name(table.stem + SUFFIX)


def check_series_names(key: str, value) -> tuple[str, ...]:
    """``value`` (a list of output names, each known and none repeated; empty: no curves) as a tuple;
    else a ``StudyError`` naming ``key``, every unknown name and the outputs that can be saved."""
    from wetcloth.errors import Mistakes, StudyError, did_you_mean

    allowed = ", ".join(OUTPUT_NAMES)
    if not isinstance(value, (list, tuple)):
        raise StudyError(key, f"give a list of the outputs to save, any of: {allowed}; got {value!r}")
    mistakes = Mistakes()
    for name in value:
        if name not in OUTPUT_NAMES:
            if name == "time":
                hint = "saved with every curve (their dimension): leave it out"
            else:
                hint = did_you_mean(str(name), OUTPUT_NAMES, "output").replace(f"; known: {allowed}", "")
            mistakes.add(StudyError(key, f"{name!r}: {hint} (outputs: {allowed})"))
    mistakes.raise_if_any()
    if len(set(value)) != len(value):
        raise StudyError(key, f"repeated output in {list(value)}")
    return tuple(value)


# ---------------------------------------------------------------- the curves of some runs as a Dataset


def time_grid(duration: float, sample_rate: float) -> np.ndarray:
    """The sample times (s) of a study's runs: the runner's frame times (``wetcloth.runner.frame_times``)."""
    from wetcloth.runner import frame_times

    return frame_times(duration, sample_rate)


def on_grid(curves: dict[str, np.ndarray], name: str, grid: np.ndarray) -> np.ndarray:
    """Output ``name`` of one run on the study's time ``grid``: as recorded when its samples are the
    grid's (the Python engine's are; the FMU's communication times are sums of steps, equal to
    round-off), else interpolated linearly by the run's own ``time`` (NaN outside it)."""
    values = np.asarray(curves[name], float)
    own = np.asarray(curves["time"], float)
    if own.shape == grid.shape and np.allclose(own, grid, rtol=0.0, atol=1e-6 * max(1.0, float(grid[-1]))):
        return values
    return np.interp(grid, own, values, left=np.nan, right=np.nan)


def _coordinate(name: str, values: Sequence[Any]) -> np.ndarray:
    """An axis's values along ``run``, typed by its parameter: float64, int64, or text (object)."""
    from wetcloth.scene import parameter_field

    default = parameter_field(name).default
    if isinstance(default, str):
        return np.array([str(v) for v in values], dtype=object)
    if isinstance(default, int) and all(isinstance(v, int) for v in values):
        return np.array(values, dtype=np.int64)
    return np.array(values, dtype=np.float64)


def _axis_attrs(name: str) -> dict[str, str]:
    from wetcloth.scene import parameter_field

    meta = parameter_field(name).metadata
    attrs = {"long_name": meta.get("doc", name)}
    if meta.get("unit", "-") != "-":
        attrs["units"] = meta["unit"]
    return attrs


def curves_dataset(results: Iterable[tuple[Any, dict[str, np.ndarray]]], study) -> "xr.Dataset":
    """The curves of ``results`` ((run, curves) pairs: a ``Run`` of ``study`` and its outputs with their
    ``time``) as a Dataset: the study's ``series`` on its time grid, dims ``run`` and ``time``, the
    run keys and the study's axes as coordinates along ``run``, units as attributes."""
    import xarray as xr

    results = list(results)
    grid = time_grid(study.duration, study.sample_rate)
    data = {}
    for name in study.series:
        rows = [on_grid(curves, name, grid) for _, curves in results]
        values = np.vstack(rows) if rows else np.empty((0, grid.size))
        unit, meaning = OUTPUTS[name]
        data[name] = (("run", "time"), values, {"units": unit, "long_name": meaning})
    coords = {
        "run": ("run", np.array([run.key for run, _ in results], dtype=object),
                {"long_name": "run_key of the run's row in the results table"}),
        "time": ("time", grid, {"units": "s", "long_name": "simulated time"}),
    }
    for axis in study.axis_names:
        coords[axis] = ("run", _coordinate(axis, [run.point[axis] for run, _ in results]), _axis_attrs(axis))
    from wetcloth import __version__

    attrs = {"source": f"wetcloth {__version__} batch study", "study": study.name,
             "sample_rate": study.sample_rate}
    return xr.Dataset(data, coords=coords, attrs=attrs)


# ---------------------------------------------------------------- the store


@contextlib.contextmanager
def interrupts_held():
    """Ctrl-C held back while the block writes (zarr writes from its own thread: an interrupt that left
    the block would leave that thread writing while the runner writes again), then raised."""
    if threading.current_thread() is not threading.main_thread() or (
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield
        return
    held = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: held.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if held:
        raise KeyboardInterrupt


def _texts(values) -> np.ndarray:
    """Text values (numpy str, StringDType or object) as an object array of str."""
    values = np.asarray(values)
    return np.array([str(v) for v in values.ravel().tolist()], dtype=object).reshape(values.shape)


def run_keys(ds: "xr.Dataset") -> list[str]:
    """The run keys of ``ds``, in its order."""
    return _texts(ds["run"].values).tolist()


def _text_as_object(ds: "xr.Dataset") -> "xr.Dataset":
    """Text coordinates as object arrays (Zarr's variable-length UTF-8), whatever numpy or pandas read
    them as (numpy's StringDType, pandas 3's str: not every xarray version encodes those)."""
    import pandas as pd

    for name, var in list(ds.variables.items()):
        if var.dtype.kind in "OUST" or str(var.dtype) == "str" or name == "run":
            texts = _texts(var.values)
            if name in ds.dims:  # an index: pandas would infer its own string type from an object array
                ds = ds.assign_coords({name: (name, pd.Index(texts, dtype=object), var.attrs)})
            else:
                ds[name] = var.copy(data=texts)
    return ds


def _encoding(ds: "xr.Dataset") -> dict[str, dict]:
    """Chunks of every variable: curves by rows of runs over (up to CHUNK_VALUES of) time, coordinates
    along ``run`` by COORD_CHUNK runs."""
    times = max(1, ds.sizes.get("time", 1))
    time_chunk = min(times, CHUNK_VALUES)
    run_chunk = max(1, min(COORD_CHUNK, CHUNK_VALUES // time_chunk))
    encoding = {}
    for name, var in ds.variables.items():
        if var.dims == ("run", "time"):
            encoding[name] = {"chunks": (run_chunk, time_chunk)}
        elif var.dims == ("run",):
            encoding[name] = {"chunks": (COORD_CHUNK,)}
    return encoding


def _pad(ds: "xr.Dataset", like: "xr.Dataset") -> "xr.Dataset":
    """``ds`` with the curves and run coordinates of ``like`` that it lacks: NaN curves, NaN numbers,
    empty text."""
    for name, var in like.data_vars.items():
        if name not in ds and var.dims == ("run", "time"):
            ds[name] = (("run", "time"), np.full((ds.sizes["run"], ds.sizes["time"]), np.nan), var.attrs)
    for name, var in like.coords.items():
        if name not in ds.coords and var.dims == ("run",):
            fill = np.full(ds.sizes["run"], "", dtype=object) if var.dtype.kind in "OUST" else \
                np.full(ds.sizes["run"], np.nan)
            ds = ds.assign_coords({name: ("run", fill, var.attrs)})
    return ds


def _same_kind(a: np.dtype, b: np.dtype) -> bool:
    text = "OUST"
    return (a.kind in text and b.kind in text) or a == b


class SeriesStore:
    """The curves of a results table, ``NAME.series.zarr`` (see the module's doc).  One writer at a
    time, as for the table."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._backup = self.path.with_name(f".{self.path.name}.old")

    # ---- reading
    def exists(self) -> bool:
        self.recover()
        return self.path.exists()

    def open(self) -> "xr.Dataset | None":
        """The Dataset, or None if there is none yet: the curves read lazily (dask), as ``xarray.open_zarr``
        gives them; the coordinates along ``run`` (run keys, axes: one value per run) read, so that
        selecting and grouping runs by them works at once."""
        import xarray as xr

        if not self.exists():
            return None
        try:
            ds = xr.open_zarr(self.path, consolidated=True)
            return ds.assign_coords({n: ds[n].compute() for n in ds.coords if ds[n].dims == ("run",) and n != "run"})
        except Exception as exc:
            raise OSError(f"cannot read the study's curves {self.path} ({type(exc).__name__}: {exc}); move it "
                          "away to save them anew (a rerun then runs again the runs whose curves it lacks)") from None

    def complete_keys(self, names: Iterable[str]) -> set[str]:
        """The run keys whose curves of every output in ``names`` the store holds (none NaN throughout)."""
        ds = self.open()
        names = list(names)
        if ds is None or not names or any(name not in ds.data_vars for name in names):
            return set()
        keys = np.array(run_keys(ds), dtype=object)
        if not keys.size:
            return set()
        whole = np.ones(keys.size, bool)
        for name in names:
            whole &= ~np.asarray(ds[name].isnull().all("time").values)
        return set(keys[whole].tolist())

    # ---- writing
    def recover(self) -> None:
        """Undo what a writer killed in the middle left behind: a rewrite's swap half done, its
        temporary folders."""
        if self._backup.exists():
            if self.path.exists():  # the swap was done: the backup is the old store
                shutil.rmtree(self._backup)
            else:  # killed between the two renames: the old store comes back
                os.rename(self._backup, self.path)
        for tmp in self.path.parent.glob(f".{self.path.name}.tmp-*"):
            shutil.rmtree(tmp, ignore_errors=True)

    def repair(self) -> None:
        """Trim the arrays an append killed in the middle had begun to lengthen back to the lengths of the
        consolidated metadata (what readers see), so that the next append continues from there."""
        import zarr

        consolidated = self.open()
        if consolidated is None:
            return
        sizes = dict(consolidated.sizes)
        group = zarr.open_group(self.path, mode="r+", use_consolidated=False)
        trimmed = False
        for _, array in group.arrays():
            dims = array.attrs.get("_ARRAY_DIMENSIONS", [])
            expected = tuple(sizes.get(d, n) for d, n in zip(dims, array.shape))
            if tuple(array.shape) != expected:
                array.resize(expected)
                trimmed = True
        if trimmed:
            zarr.consolidate_metadata(self.path)

    def write(self, batch: "xr.Dataset", complete: set[str] | None = None) -> int:
        """Add the curves of ``batch``; returns how many runs were added.  Runs in ``complete`` (keys the
        store holds whole for ``batch``'s outputs) are left out; a run the store holds without some of
        those outputs is replaced.  Appended where the layout is the store's (its time grid, outputs
        and axes); else the store is rewritten with the union of both (NaN where a run has no value)."""
        import xarray as xr

        with interrupts_held():
            self.recover()
            keys = run_keys(batch)
            if complete:
                batch = batch.isel(run=np.flatnonzero(~np.isin(keys, list(complete))))
            if not batch.sizes["run"]:
                return 0
            batch = _text_as_object(batch.copy())
            if not self.path.exists():
                self._replace_with(batch)
                return batch.sizes["run"]
            self.repair()
            stored = xr.open_zarr(self.path, consolidated=True)
            stored_keys = set(run_keys(stored))
            replaced = [k for k in run_keys(batch) if k in stored_keys]
            batch = _pad(batch, stored)
            for name, var in stored.variables.items():  # whole numbers join a column of floats as floats
                if name in batch.variables and var.dtype.kind == "f" and batch[name].dtype.kind in "iu":
                    batch[name] = batch[name].astype(var.dtype)
            if not replaced and self._appendable(stored, batch):
                batch.to_zarr(self.path, mode="a", append_dim="run", consolidated=True)
                return batch.sizes["run"]
            # another layout, or curves to complete: the union, written anew
            old = stored.drop_sel(run=replaced).load() if replaced else stored.load()
            old = _pad(_text_as_object(old), batch)
            merged = xr.concat([old, batch], dim="run", join="outer", data_vars="all", coords="different",
                               compat="equals", combine_attrs="override")
            merged.attrs = dict(stored.attrs)
            self._replace_with(merged)
            return batch.sizes["run"]

    @staticmethod
    def _appendable(stored: "xr.Dataset", batch: "xr.Dataset") -> bool:
        """Whether ``batch`` continues ``stored`` as it is: the same time grid, outputs and axes, of the same types."""
        if set(batch.variables) != set(stored.variables) or batch.sizes["time"] != stored.sizes["time"]:
            return False
        if not np.array_equal(batch["time"].values, stored["time"].values):
            return False
        return all(_same_kind(batch[n].dtype, stored[n].dtype) and batch[n].dims == stored[n].dims
                   for n in batch.variables)

    def _replace_with(self, ds: "xr.Dataset") -> None:
        """Write ``ds`` as the whole store: in a folder beside it, then renamed into place (the old store
        is moved aside first and removed last; ``recover`` finishes a swap that was cut short)."""
        tmp = self.path.with_name(f".{self.path.name}.tmp-{uuid.uuid4().hex[:8]}")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        ds = _text_as_object(ds)
        for var in ds.variables.values():
            var.encoding = {}
        try:
            ds.to_zarr(tmp, mode="w-", zarr_format=2, consolidated=True, encoding=_encoding(ds))
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        if self.path.exists():
            os.rename(self.path, self._backup)
        os.rename(tmp, self.path)
        shutil.rmtree(self._backup, ignore_errors=True)


def read_series(path: str | Path) -> "xr.Dataset":
    """The curves of a study: ``path`` is the store (``NAME.series.zarr``) or its results table
    (``NAME.parquet``).  The same as ``xarray.open_zarr(store)``."""
    path = Path(path)
    store = SeriesStore(path if path.name.endswith(SUFFIX) else series_path(path))
    ds = store.open()
    if ds is None:
        raise FileNotFoundError(f"no curves at {store.path}: a study saves them with series = [...]")
    return ds


def select_runs(ds: "xr.Dataset | None", keys: Sequence[str]) -> "xr.Dataset | None":
    """The runs ``keys`` of ``ds`` that it holds, in that order."""
    if ds is None:
        return None
    held = set(run_keys(ds))
    return ds.sel(run=[k for k in keys if k in held])


__all__ = ["SUFFIX", "SeriesStore", "check_series_names", "curves_dataset", "read_series", "select_runs",
           "series_path", "time_grid"]
