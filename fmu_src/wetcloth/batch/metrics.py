"""Metrics of one run, computed from its output time series sampled at the study's rate.

Every metric is a float in SI units.  Crossing times are linearly interpolated between the two
samples around the crossing, so they resolve finer than the sample interval; a crossing that
never happens is NaN (``time_to_sink``: the run's ``sank`` column is then False).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

#: Output series a run must provide (s, m, kg, kg).
SERIES = ("time", "depth", "wet_mass", "water_mass")


@dataclass(frozen=True)
class Metric:
    name: str
    unit: str
    doc: str


METRICS: dict[str, Metric] = {m.name: m for m in (
    Metric("time_to_sink", "s",
           "first time depth (water_level - centroid_z) exceeds sink_depth; NaN if it never does (sank = False)"),
    Metric("final_depth", "m", "depth at the end of the run (positive below the surface)"),
    Metric("max_depth", "m", "largest depth over the run"),
    Metric("final_wet_mass", "kg", "wet mass (dry plus absorbed water) at the end of the run"),
    Metric("final_water_mass", "kg", "absorbed water at the end of the run"),
    Metric("time_to_90_wet_mass", "s", "first time wet_mass reaches 90% of its final value (0 if it starts there)"),
    Metric("time_to_90_water_mass", "s",
           "first time the absorbed water reaches 90% of its final amount; NaN if no water is absorbed"),
)}

def check_metric_names(key: str, value, at_least_one: bool) -> tuple[str, ...]:
    """``value`` (a list of metric names, each known and none repeated) as a tuple; else a
    ``StudyError`` naming ``key`` and every unknown name, with the nearest known ones."""
    from wetcloth.errors import Mistakes, StudyError, did_you_mean

    if not isinstance(value, (list, tuple)) or (at_least_one and not value):
        least = "at least one of" if at_least_one else "any of"
        raise StudyError(key, f"give a list of {least}: {', '.join(METRICS)}; got {value!r}")
    mistakes = Mistakes()
    for m in value:
        if m not in METRICS:
            mistakes.add(StudyError(key, f"{m!r}: " + did_you_mean(str(m), METRICS, "metric")))
    mistakes.raise_if_any()
    if len(set(value)) != len(value):
        raise StudyError(key, f"repeated metric in {list(value)}")
    return tuple(value)


#: Recorded when a study does not say which metrics it wants.
DEFAULT_METRICS = ("time_to_sink", "final_depth", "final_wet_mass", "time_to_90_wet_mass")


def first_crossing(time: np.ndarray, values: np.ndarray, level: float, strict: bool = False) -> float:
    """First time (s) ``values`` exceeds ``level`` (``>`` if ``strict``, else ``>=``), NaN if never.

    Linear interpolation between the last sample below the level and the first one past it;
    if the first sample is already past, the first sample's time.
    """
    time = np.asarray(time, float)
    values = np.asarray(values, float)
    past = values > level if strict else values >= level
    if not past.any():
        return float("nan")
    i = int(np.argmax(past))
    if i == 0:
        return float(time[0])
    t0, t1, y0, y1 = time[i - 1], time[i], values[i - 1], values[i]
    return float(t0 + (level - y0) / (y1 - y0) * (t1 - t0))


def compute_metrics(series: Mapping[str, np.ndarray], names, sink_depth: float) -> dict[str, float]:
    """The metrics ``names`` of one run from its ``series`` (time s, depth m, wet_mass kg,
    water_mass kg); with ``time_to_sink`` also ``sank`` (bool)."""
    if unknown := [n for n in names if n not in METRICS]:
        raise ValueError(f"unknown metric {unknown[0]!r}; known: {', '.join(METRICS)}")
    t = np.asarray(series["time"], float)
    if t.size == 0:
        raise ValueError("no samples: the run produced an empty time series")
    depth = np.asarray(series["depth"], float)
    wet = np.asarray(series["wet_mass"], float)
    water = np.asarray(series["water_mass"], float)
    out: dict[str, float] = {}
    for name in names:
        if name == "time_to_sink":
            out[name] = first_crossing(t, depth, sink_depth, strict=True)
            out["sank"] = bool(np.isfinite(out[name]))
        elif name == "final_depth":
            out[name] = float(depth[-1])
        elif name == "max_depth":
            out[name] = float(depth.max())
        elif name == "final_wet_mass":
            out[name] = float(wet[-1])
        elif name == "final_water_mass":
            out[name] = float(water[-1])
        elif name == "time_to_90_wet_mass":
            out[name] = first_crossing(t, wet, 0.9 * wet[-1])
        elif name == "time_to_90_water_mass":
            out[name] = first_crossing(t, water, 0.9 * water[-1]) if water[-1] > 0 else float("nan")
    return out
