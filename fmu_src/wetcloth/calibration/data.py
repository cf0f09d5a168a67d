"""Measurements to fit: a CSV of output curves against time, or of measured sink times.

Curves: a ``time`` column (s, from the release of the cloth, increasing) and any of the outputs
(``depth``, ``wet_mass``, ``water_mass``, ``centroid_x``, ``centroid_y``, ``centroid_z``; SI units),
each with an optional ``sigma_NAME`` column: the standard deviation of that measurement's noise,
in its unit.  An empty cell is a value not measured at that time (a wet mass weighed at other
times than the depth was read); text that is not a finite number, ``nan`` included, is refused.

Sink times: a ``time_to_sink`` column (s), one row per timed drop, optionally ``sigma_time_to_sink``.

Lines starting with ``#`` are comments.  Every mistake of a file is reported at once, each naming
its row or column (``DataError``, a ValueError: the command line's exit status 2).  A sigma lies within
``SIGMA_RANGE``; before a fit, ``check_against_scene`` refuses values no cloth of the scene can show
(wet mass in g, depth in cm).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wetcloth.errors import ConfigError, Mistakes, did_you_mean
from wetcloth.mesh_file import is_mesh
from wetcloth.run_settings import MAX_FRAMES, SETTINGS
from wetcloth.scene import PARAMETERS, Scene
from wetcloth.simulation import OUTPUT_NAMES, OUTPUTS
from wetcloth.topology import build_topology

TIME = "time"
SINK = "time_to_sink"
SIGMA = "sigma_"
#: Units of every column a data file may have.
UNITS = {TIME: "s", **{name: unit for name, (unit, _) in OUTPUTS.items()}, SINK: "s"}
#: The values a sigma may take, in its column's unit (m, kg, s).  Below 1e-12 (a hundredth of an atom,
#: a nanogram) no instrument measures, and the weighted residuals (model - data) / sigma of outputs
#: within a scene's ranges (under 1e10 m or kg) stay below 1e22: their squares, summed over every
#: value, and the Jacobian's products stay far from a float's largest, 1.8e308 (at 1e-200 they
#: overflowed).  Above 1e12 a value says nothing, and the squares stay far above a float's smallest.
SIGMA_RANGE = (1e-12, 1e12)
#: How far a measured value may lie outside what the scene can produce (``check_against_scene``) before it
#: is refused: a reading's error, not a unit's (g for kg is 1000x, cm for m 100x): MARGIN times the scene's
#: size of that quantity (the water's depth, the cloth's dry mass) plus NOISE sigma where sigma is given.
MARGIN = 0.1
NOISE = 5.0


class DataError(ConfigError):
    """A measurements file is malformed; the message names the column or row and what is allowed.

    Its problems are ``("column", name, message)``, ``("row", "3 (line 5)", message)`` or
    ``("file", "", message)``; the text heads them with the file (``data file x.csv: ...``)."""

    label = "column"

    def __str__(self) -> str:
        lines = [f"column '{name}': {message}" if label == "column" else f"row {name}: {message}"
                 if label == "row" else message for label, name, message in self.problems]
        head = f"{self.source}: " if self.source else ""
        if len(lines) == 1:
            return head + lines[0]
        return f"{head}{len(lines)} mistakes\n" + "\n".join("  " + line for line in lines)


def _file_error(source: str, message: str) -> DataError:
    error = DataError("", message, label="file")
    error.source = source
    return error


def _row(r: int, line: int, message: str) -> DataError:
    """A mistake in data row ``r`` (1-based, below the header), on ``line`` of the file."""
    return DataError(f"{r} (line {line})", message, label="row")


@dataclass(frozen=True)
class Curves:
    """Output curves measured at ``times`` (s): ``values[name]`` (NaN where not measured) and
    ``sigma[name]`` (the noise's standard deviation per row, or None: to be estimated from the fit)."""

    times: np.ndarray
    values: dict[str, np.ndarray]
    sigma: dict[str, np.ndarray | None]
    source: str = ""
    kind: str = field(default="curves", init=False)

    @property
    def names(self) -> tuple[str, ...]:
        """The measured outputs, in the order of ``OUTPUT_NAMES``."""
        return tuple(n for n in OUTPUT_NAMES if n in self.values)

    def count(self, name: str) -> int:
        return int(np.isfinite(self.values[name]).sum())

    @property
    def observations(self) -> int:
        return sum(self.count(n) for n in self.names)


@dataclass(frozen=True)
class SinkTimes:
    """Timed drops: each ``times[i]`` (s) is when a drop went ``sink_depth`` under; ``sigma`` per
    timing (s) or None."""

    times: np.ndarray
    sigma: np.ndarray | None
    source: str = ""
    kind: str = field(default="sink", init=False)

    @property
    def observations(self) -> int:
        return int(self.times.size)

    def mean(self) -> tuple[float, float | None, int | None]:
        """The sink time to fit (s), its standard error (s; None when it cannot be known: one timing
        without a sigma) and the degrees of freedom of that error (None: a known sigma)."""
        t = self.times
        if self.sigma is not None:  # inverse-variance weighted mean of timings of known noise
            w = 1.0 / self.sigma ** 2
            return float(np.sum(w * t) / np.sum(w)), float(1.0 / math.sqrt(np.sum(w))), None
        if t.size < 2:
            return float(t[0]), None, None
        return float(t.mean()), float(t.std(ddof=1) / math.sqrt(t.size)), t.size - 1


def allowed_columns() -> list[str]:
    return [TIME, *OUTPUT_NAMES, *(SIGMA + n for n in OUTPUT_NAMES), SINK, SIGMA + SINK]


def read_measurements(path: str | Path) -> Curves | SinkTimes:
    """The measurements in the CSV file ``path``, checked whole (a DataError lists every mistake)."""
    path = Path(path)
    source = f"data file {path}"
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:  # -sig: a spreadsheet's byte-order mark is no text
            lines = [(i, line) for i, line in enumerate(fh, 1) if line.strip() and not line.lstrip().startswith("#")]
    except UnicodeDecodeError as exc:
        raise _file_error(source, f"not a text (CSV) file: byte {exc.object[exc.start]:#04x} at position "
                                  f"{exc.start} is not UTF-8") from None
    except OSError as exc:  # a missing file: FileNotFoundError, reported as it is
        if isinstance(exc, FileNotFoundError):
            raise FileNotFoundError(f"data file {str(path)!r} not found") from None
        raise _file_error(source, f"cannot be read: {exc.strerror or exc}") from None
    if not lines:
        raise _file_error(source, f"empty: the first line names the columns: '{TIME}' and any of "
                                  f"{', '.join(OUTPUT_NAMES)} (or '{SINK}' alone)")
    rows = list(csv.reader(line for _, line in lines))
    numbers = [n for n, _ in lines]
    header = [h.strip() for h in rows[0]]
    if len(header) == 1 and ";" in header[0]:
        raise _file_error(source, f"the header {header[0]!r} separates its columns with ';' (a spreadsheet's CSV in "
                                  "some languages): separate them with commas, and write decimal points")
    mistakes = Mistakes(source)
    columns = _check_header(header, mistakes)
    mistakes.raise_if_any()
    table = {name: np.full(len(rows) - 1, np.nan) for name in columns}
    for r, (row, line) in enumerate(zip(rows[1:], numbers[1:]), 1):
        if len(row) != len(header):
            mistakes.add(_row(r, line, f"{len(row)} cells, the header names {len(header)} columns"))
            continue
        for name, text in zip(header, row):
            text = text.strip()
            if not text:
                continue
            try:
                value = float(text)
            except ValueError:
                mistakes.add(_row(r, line, f"column '{name}': {text!r} is not a number"))
                continue
            if not math.isfinite(value):
                mistakes.add(_row(r, line, f"column '{name}': {text!r} is not a finite number (leave the cell "
                                             f"empty where nothing was measured)"))
                continue
            table[name][r - 1] = value
    if len(rows) < 2:
        mistakes.add(DataError("", "no data rows below the header", label="file"))
    mistakes.raise_if_any()
    data = _sink_times(table, numbers[1:], source, mistakes) if SINK in table else _curves(table, numbers[1:], source, mistakes)
    mistakes.raise_if_any()
    return data


def _check_header(header: list[str], mistakes: Mistakes) -> list[str]:
    known = allowed_columns()
    seen = set()
    for name in header:
        with mistakes.collect():
            if not name:
                raise DataError("", "the header has an empty column name", label="file")
            if name in seen:
                raise DataError(name, "named twice in the header")
            seen.add(name)
            if name not in known:
                raise DataError(name, did_you_mean(name, known, "column", listing=(
                    f"columns: '{TIME}' in s and any of {', '.join(OUTPUT_NAMES)}, each with an optional "
                    f"sigma_NAME; or '{SINK}' in s alone, with an optional sigma_{SINK}")))
    if SINK in seen:
        others = [n for n in header if n not in (SINK, SIGMA + SINK)]
        if others:
            mistakes.add(DataError(SINK, f"sink times are fitted alone: a file with '{SINK}' (one row per timed drop, "
                                         f"optional '{SIGMA}{SINK}') has no other columns; got {', '.join(others)}"))
    elif SIGMA + SINK in seen:
        mistakes.add(DataError(SIGMA + SINK, f"without a '{SINK}' column"))
    else:
        if TIME not in seen:
            mistakes.add(DataError(TIME, f"missing: measured curves need a '{TIME}' column (s, from the release of "
                                         f"the cloth); or give '{SINK}' (s) alone for a sink-time fit"))
        if not any(n in seen for n in OUTPUT_NAMES):
            mistakes.add(DataError("", f"no measured output: give at least one of {', '.join(OUTPUT_NAMES)}",
                                   label="file"))
        for name in seen:
            if name.startswith(SIGMA) and name[len(SIGMA):] not in seen:
                mistakes.add(DataError(name, f"without a '{name[len(SIGMA):]}' column to give the noise of"))
    return header


def _check_sigma(name: str, values: np.ndarray, present: np.ndarray, lines: list[int], mistakes: Mistakes) -> None:
    """A mistake for each row of sigma column ``name`` outside SIGMA_RANGE (in its column's unit), or
    empty where its value is ``present``."""
    lo, hi = SIGMA_RANGE
    unit = UNITS[name[len(SIGMA):]]
    for r in np.flatnonzero(present & ~((lo <= values) & (values <= hi))):
        mistakes.add(_row(r + 1, lines[r], f"column '{name}': {values[r]:g} {unit} is outside a sigma's range (the "
                                           f"standard deviation of the noise); allowed: {lo:g} <= {name} <= {hi:g} {unit}"
                          if np.isfinite(values[r]) else
                          f"column '{name}': empty, but the value it belongs to is measured"))


def _curves(table: dict, lines: list[int], source: str, mistakes: Mistakes) -> Curves:
    t = table[TIME]
    for r in np.flatnonzero(~np.isfinite(t)):
        mistakes.add(_row(r + 1, lines[r], f"column '{TIME}': empty; every row needs its time"))
    ok = np.isfinite(t)
    for r in np.flatnonzero(ok & (t < 0)):
        mistakes.add(_row(r + 1, lines[r], f"column '{TIME}': {t[r]:g} s is before the start; times count from "
                                           f"the release of the cloth (0 s)"))
    duration = SETTINGS["duration"]
    if ok.any() and t[ok].max() > duration.hi:
        mistakes.add(DataError(TIME, f"{t[ok].max():g} s is beyond the longest run, {duration.hi:g} s"))
    if t.size > MAX_FRAMES:
        mistakes.add(DataError(TIME, f"{t.size} rows; at most {MAX_FRAMES}"))
    valid = t[ok]
    bad = np.flatnonzero(np.diff(valid) <= 0)
    if bad.size:
        i = bad[0]
        rows = np.flatnonzero(ok)
        mistakes.add(DataError(TIME, f"not increasing: row {rows[i + 1] + 1} (line {lines[rows[i + 1]]}) has "
                                     f"{valid[i + 1]:g} s after {valid[i]:g} s" +
                                     (f" ({bad.size} places)" if bad.size > 1 else "") +
                                     "; one row per time, in increasing order (several measurements at one time: "
                                     "give their mean, and their spread as sigma_NAME)"))
    values, sigma = {}, {}
    for name in OUTPUT_NAMES:
        if name not in table:
            continue
        values[name] = table[name]
        present = np.isfinite(table[name])
        if not present.any():
            mistakes.add(DataError(name, "no values: every cell is empty"))
        s = table.get(SIGMA + name)
        if s is not None:
            _check_sigma(SIGMA + name, s, present, lines, mistakes)
            s = np.where(present, s, np.nan)
        sigma[name] = s
    return Curves(times=t, values=values, sigma=sigma, source=source)


def _sink_times(table: dict, lines: list[int], source: str, mistakes: Mistakes) -> SinkTimes:
    t = table[SINK]
    present = np.isfinite(t)
    if not present.any():
        mistakes.add(DataError(SINK, "no values: every cell is empty"))
    for r in np.flatnonzero(present & (t <= 0)):
        mistakes.add(_row(r + 1, lines[r], f"column '{SINK}': {t[r]:g} s; a sink time is > 0"))
    for r in np.flatnonzero(present & (t > SETTINGS["duration"].hi / 2)):
        mistakes.add(_row(r + 1, lines[r], f"column '{SINK}': {t[r]:g} s is beyond what a fit simulates "
                                           f"({SETTINGS['duration'].hi / 2:g} s)"))
    s = table.get(SIGMA + SINK)
    if s is not None:
        _check_sigma(SIGMA + SINK, s, present, lines, mistakes)
        s = s[present]
    return SinkTimes(times=t[present], sigma=s, source=source)


def check_against_scene(data: Curves, scene: Scene, fitted: dict[str, tuple[float, float]]) -> None:
    """Refuse values no cloth of ``scene`` can show, whatever the fitted parameters ``fitted`` (name ->
    (lo, hi) bounds) become: a DataError naming each such column, the range and what to check (the unit)."""
    mistakes = Mistakes(data.source or None)
    for name, (lo, hi, size, why, hint) in _scene_ranges(scene, fitted).items():
        if name not in data.values:
            continue
        v, s = data.values[name], data.sigma[name]
        slack = MARGIN * size + NOISE * (s if s is not None else 0.0)
        bad = np.flatnonzero((v < lo - slack) | (v > hi + slack))  # False where not measured (NaN)
        if bad.size:
            more = f"; {bad.size - 1} more row{'s' if bad.size > 2 else ''} likewise" if bad.size > 1 else ""
            mistakes.add(DataError(name, f"{v[bad[0]]:g} {UNITS[name]} (row {bad[0] + 1}{more}) is impossible for "
                                         f"this scene: {why}; {hint}"))
    mistakes.raise_if_any()


def _scene_ranges(scene: Scene, fitted: dict[str, tuple[float, float]]) -> dict[str, tuple]:
    """Per output, (lo, hi, size, why, hint): the values (m, kg) a cloth of ``scene`` can show with its
    ``fitted`` parameters anywhere within their bounds, the size of that quantity (m, kg: the water's
    depth, the dry mass), why, and what to check (the unit, the scene) when data lie beyond them."""
    def extreme(name: str, side: int) -> float:  # side 0: the lowest the parameter may be, 1: the highest
        return fitted[name][side] if name in fitted else float(getattr(scene, name))

    cap = PARAMETERS["absorption_capacity"].metadata["hi"]
    dry = [scene.areal_density * float(build_topology(scene).area.sum())] * 2  # kg: least, most
    sizes = () if is_mesh(scene.cloth_mesh) else ("width", "length")  # a mesh cloth's area is its file's
    for name in ("areal_density", *sizes):  # the dry mass is proportional to each
        if name in fitted:
            dry = [dry[side] * extreme(name, side) / getattr(scene, name) for side in (0, 1)]
    floor = extreme("floor_level", 0)
    deepest = extreme("water_level", 1) - floor
    in_m = "positions are in m (0.05, not 5 cm), and the scene's water_level and floor_level are the container's"
    in_kg = "masses are in kg (0.129, not 129 g), and the scene's areal_density and size are the cloth's"
    return {
        "depth": (-math.inf, deepest, max(deepest, 0.0), f"the cloth cannot go below the floor: a depth is at most "
                  f"water_level - floor_level = {deepest:.4g} m", in_m),
        "centroid_z": (floor, math.inf, max(deepest, 0.0), f"the cloth cannot go below the floor: centroid_z is at "
                       f"least floor_level = {floor:.4g} m", in_m),
        "wet_mass": (dry[0], dry[1] * (1 + cap), dry[0], f"a wet mass lies between the cloth's dry mass, "
                     f"{dry[0]:.4g} kg, and its dry mass times 1 + {cap:g} (the largest allowed absorption_capacity), "
                     f"{dry[1] * (1 + cap):.4g} kg", in_kg),
        "water_mass": (0.0, dry[1] * cap, dry[0], f"the water held lies between 0 and the cloth's dry mass times "
                       f"{cap:g} (the largest allowed absorption_capacity), {dry[1] * cap:.4g} kg", in_kg),
    }
