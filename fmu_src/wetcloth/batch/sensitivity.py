"""Global sensitivity of a study's metrics to its sampled axes: a Saltelli (Sobol' indices) or a
Morris design through SALib.

A study with a ``[sensitivity]`` table makes its runs from the method's design instead of a grid
or ``samples`` draws: each sampled axis (bounds ``{low, high [, log]}`` or a distribution) is one
factor; the design is made in the unit cube (seeded by the study's ``seed``) and mapped through
each axis's distribution (``wetcloth.batch.axes.from_unit``).  The runs are ordinary runs (Dask
tasks, rows of the results table, resumed by key).  Once they are done, :func:`sensitivity_indices`
gives per metric and factor:

- ``sobol``: first-order and total indices ``S1``, ``ST`` (shares of the metric's variance) with
  the half-widths ``S1_conf``, ``ST_conf`` of their bootstrap confidence intervals.  Runs:
  ``samples * (factors + 2)`` (SALib's ``sample.sobol`` without second-order indices).
- ``morris``: ``mu_star`` (mean absolute elementary effect: the metric's change in one step of the
  design, in its unit, scaled to the factor's whole range) with ``mu_star_conf``, ``mu`` (its
  signed mean) and ``sigma`` (spread of the effects: interactions or non-linearity).  Runs:
  ``trajectories * (factors + 1)``.

The estimators need every run of the design.  A metric whose design has a run that failed, is not
run yet, or has no value (NaN, e.g. a towel that never sank) gets no indices: the result says
which runs, and why, instead of an estimate from a partial design.
"""

from __future__ import annotations

import functools
import math
import textwrap
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from wetcloth.batch.metrics import METRICS, check_metric_names
from wetcloth.errors import Mistakes, StudyError, check_choice, did_you_mean

if TYPE_CHECKING:
    import pandas as pd

    from wetcloth.batch.axes import Axis
    from wetcloth.batch.spec import Study

METHODS = ("sobol", "morris")
SENSITIVITY_KEYS = ("method", "samples", "trajectories", "levels", "conf_level", "resamples", "metrics")
#: Keys that belong to one method only.
_METHOD_KEYS = {"samples": "sobol", "trajectories": "morris", "levels": "morris"}
#: Distributions a Morris design can step through: ordered and bounded (not normal, not choice).
_MORRIS_KINDS = ("uniform", "loguniform", "integers")
#: The indices each method gives per factor (``_conf``: half-width of the confidence interval).
INDICES = {"sobol": ("S1", "S1_conf", "ST", "ST_conf"), "morris": ("mu_star", "mu_star_conf", "mu", "sigma")}
#: Runs of a design not listed one by one in a message, past this many per kind of problem.
_EXAMPLES = 3


def _power_of_two(n: int) -> bool:
    return n >= 1 and n & (n - 1) == 0


def _whole_at_least(key: str, value, least: int) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or value < least:
        raise StudyError(f"sensitivity.{key}", f"must be a whole number >= {least}, got {value!r}")
    return value


def _check_samples(value) -> int:
    _whole_at_least("samples", value, 2)
    if not _power_of_two(value):
        lower = 1 << (value.bit_length() - 1)
        raise StudyError("sensitivity.samples", f"must be a power of 2 (the balance of the Sobol' points of the "
                                                f"Saltelli design), got {value}: take {lower} or {2 * lower}")
    return value


def _check_levels(value) -> int:
    _whole_at_least("levels", value, 2)
    if value % 2:
        raise StudyError("sensitivity.levels", f"must be even (Morris' steps then cover the levels evenly), got {value}")
    return value


def _check_conf_level(value) -> float:
    if not (isinstance(value, (int, float)) and not isinstance(value, bool) and 0.0 < value < 1.0):
        raise StudyError("sensitivity.conf_level", f"must be a number between 0 and 1 (exclusive), got {value!r}")
    return float(value)


_CHECKS = {
    "method": functools.partial(check_choice, StudyError, "sensitivity.method", allowed=METHODS),
    "samples": _check_samples,
    "trajectories": lambda v: _whole_at_least("trajectories", v, 2),
    "levels": _check_levels,
    "conf_level": _check_conf_level,
    "resamples": lambda v: _whole_at_least("resamples", v, 10),
    "metrics": functools.partial(check_metric_names, "sensitivity.metrics", at_least_one=False),
}


@dataclass(frozen=True)
class SensitivitySpec:
    """The ``[sensitivity]`` table of a study: the method and its design size, the confidence level
    and bootstrap resamples of the intervals, and the metrics to analyse (empty: all recorded)."""

    method: str = "sobol"
    samples: int = 64  # sobol: base samples N (a power of 2); runs N * (factors + 2)
    trajectories: int = 10  # morris: trajectories r; runs r * (factors + 1)
    levels: int = 4  # morris: grid levels of the unit range (even)
    conf_level: float = 0.95
    resamples: int = 1000  # bootstrap resamples of the confidence intervals
    metrics: tuple[str, ...] = ()

    def __post_init__(self):
        mistakes = Mistakes()
        for key, check in _CHECKS.items():
            with mistakes.collect():
                object.__setattr__(self, key, check(getattr(self, key)))
        mistakes.raise_if_any()

    def run_count(self, factors: int) -> int:
        """Points of the design for ``factors`` factors (identical points run once)."""
        return self.samples * (factors + 2) if self.method == "sobol" else self.trajectories * (factors + 1)

    def describe(self, factors: int) -> str:
        """'sobol design: 64 base samples x (6 factors + 2) = 512 runs'."""
        if self.method == "sobol":
            return (f"sobol design: {self.samples} base samples x ({factors} factors + 2) = "
                    f"{self.run_count(factors)} runs")
        return (f"morris design: {self.trajectories} trajectories x ({factors} factors + 1) = "
                f"{self.run_count(factors)} runs, {self.levels} levels")


def parse_sensitivity(table) -> SensitivitySpec:
    """The ``[sensitivity]`` table of a study file, checked whole (every mistake at once)."""
    if not isinstance(table, dict):
        raise StudyError("sensitivity", "must be a table: method, samples or trajectories, ...")
    mistakes = Mistakes()
    for key in table:
        if key not in SENSITIVITY_KEYS:
            mistakes.add(StudyError(f"sensitivity.{key}", did_you_mean(key, SENSITIVITY_KEYS, "key")))
    method = table.get("method", "sobol")
    for key, owner in _METHOD_KEYS.items():
        if key in table and method in METHODS and method != owner:
            other = "samples" if owner == "morris" else "trajectories"
            mistakes.add(StudyError(f"sensitivity.{key}", f"is for method = '{owner}'; method '{method}' takes "
                                                          f"{other} (see docs/batch.md)"))
    mistakes.raise_if_any()
    return SensitivitySpec(**table)


def check_factors(spec: SensitivitySpec, axes: tuple[Axis, ...]) -> None:
    """The factors of a sensitivity study are its axes, every one sampled (bounds or a distribution);
    Morris steps through ordered, bounded ranges only."""
    mistakes = Mistakes()
    if not axes:
        mistakes.add(StudyError("axes", "a sensitivity study needs at least one factor: an axis with bounds "
                                        "{low, high} (or a distribution)"))
    for axis in axes:
        where = f"axes.{axis.name}"
        if not axis.is_random:
            mistakes.add(StudyError(where, "a sensitivity study's axes are its factors: give bounds {low, high [, "
                                           "log]} or a distribution; set a fixed value in [base]"))
        elif spec.method == "morris" and axis.distribution["random"] not in _MORRIS_KINDS:
            mistakes.add(StudyError(where, f"random = {axis.distribution['random']!r} has no ordered, bounded range "
                                           "for Morris' steps: give bounds {low, high [, log]}, or use method = 'sobol'"))
    mistakes.raise_if_any()


def _problem(names: list[str]) -> dict[str, Any]:
    """SALib's problem: the factors in the unit cube (each axis maps [0, 1] to its values)."""
    return {"num_vars": len(names), "names": list(names), "bounds": [[0.0, 1.0]] * len(names)}


def design(spec: SensitivitySpec, names: list[str], seed: int) -> np.ndarray:
    """The design in the unit cube: one row per run, one column per factor (seeded by ``seed``).

    Sobol: Saltelli's scheme on a scrambled Sobol' sequence (``SALib.sample.sobol``), whose first
    ``N`` base samples do not depend on the total, so raising ``samples`` keeps the runs done.
    Morris: ``trajectories`` one-at-a-time paths over ``levels`` levels (``SALib.sample.morris``)."""
    if spec.method == "sobol":
        from SALib.sample import sobol

        return sobol.sample(_problem(names), spec.samples, calc_second_order=False, scramble=True, seed=seed)
    from SALib.sample import morris

    return morris.sample(_problem(names), spec.trajectories, num_levels=spec.levels, seed=seed)


def _bootstrap_seed(seed: int) -> int:
    """A non-zero seed for the bootstrap, from the study's: SALib's ``sobol.analyze`` takes a seed of
    0 for none (then its intervals change from one call to the next)."""
    return int(np.random.SeedSequence(seed).generate_state(1)[0]) | 1


def analyze(spec: SensitivitySpec, names: list[str], unit_design: np.ndarray, outputs: np.ndarray,
            seed: int) -> dict[str, np.ndarray]:
    """The indices of one output (``outputs[i]`` of design row ``i``; finite, not constant), one value
    per factor: S1, S1_conf, ST, ST_conf (sobol) or mu_star, mu_star_conf, mu, sigma (morris); the
    ``_conf`` entries are half-widths of the ``spec.conf_level`` bootstrap intervals."""
    y = np.asarray(outputs, float)
    if y.shape != (len(unit_design),) or not np.isfinite(y).all():
        raise ValueError(f"need one finite output per design row ({len(unit_design)}), got shape {y.shape}")
    if spec.method == "sobol":
        from SALib.analyze import sobol

        result = sobol.analyze(_problem(names), y, calc_second_order=False, num_resamples=spec.resamples,
                               conf_level=spec.conf_level, seed=_bootstrap_seed(seed))
    else:
        from SALib.analyze import morris

        result = morris.analyze(_problem(names), np.asarray(unit_design, float), y, num_resamples=spec.resamples,
                                conf_level=spec.conf_level, num_levels=spec.levels, seed=_bootstrap_seed(seed))
    return {k: np.asarray(result[k], float) for k in INDICES[spec.method]}


@dataclass
class SensitivityResult:
    """The indices of a sensitivity study: ``indices`` (one row per metric and factor; columns
    ``metric``, ``unit``, ``parameter``, ``rank`` (1 = most influential, by ST or mu_star), the
    method's indices, ``method``, ``runs``, ``conf_level``) and ``problems``: metric -> why it has
    no indices (failed, missing or undefined runs, or a constant metric).  ``metrics``: every
    analysed metric, with indices or not."""

    spec: SensitivitySpec
    factors: list[str]
    metrics: list[str]
    runs: int
    indices: pd.DataFrame
    problems: dict[str, str] = field(default_factory=dict)


def _describe_run(key: str, point: dict[str, Any]) -> str:
    values = ", ".join(f"{n}={v:.4g}" if isinstance(v, float) else f"{n}={v}" for n, v in point.items())
    return f"run {key} ({values})"


def _examples(keys: list[str], points: dict[str, dict], extra: dict[str, str] | None = None) -> str:
    shown = [_describe_run(k, points[k]) + (f": {extra[k]}" if extra else "") for k in keys[:_EXAMPLES]]
    more = f"; and {len(keys) - _EXAMPLES} more" if len(keys) > _EXAMPLES else ""
    return "; ".join(shown) + more


def _undefined_hint(metric: str, study: Study) -> str:
    if metric == "time_to_sink":
        return (f"it did not sink within duration = {study.duration:g} s: a longer duration, or bounds within which "
                "every run sinks")
    return "the metric is undefined there (docs/batch.md, Metrics)"


def design_outputs(study: Study, by_key: pd.DataFrame, metric: str, keys: list[str],
                   points: dict[str, dict]) -> tuple[np.ndarray | None, str | None]:
    """The metric of every design row of ``study`` (whose run keys are ``keys``, in design order) from
    the results table ``by_key`` (indexed by run key), or None and why not: the runs of the design
    that are not in the table, failed, or have no value, each named with its ``points`` values."""
    unique = list(dict.fromkeys(keys))
    missing = [k for k in unique if k not in by_key.index]
    present = by_key.loc[[k for k in unique if k in by_key.index]]
    failed = present[present["status"] != "ok"]
    values = present.reindex(columns=[metric])[metric].astype(float)  # all NaN if no run recorded it
    undefined = [k for k in present.index[present["status"] == "ok"] if not math.isfinite(values[k])]
    parts = []
    if missing:
        parts.append(f"{len(missing)} not run yet (run the same command to run them): " + _examples(missing, points))
    if len(failed):
        errors = {k: str(e).splitlines()[0] for k, e in failed["error"].items()}
        parts.append(f"{len(failed)} failed (after fixing the cause, --retry-errors runs them again): "
                     + _examples(list(failed.index), points, errors))
    if undefined:
        parts.append(f"{len(undefined)} {'has' if len(undefined) == 1 else 'have'} no value "
                     f"(NaN: {_undefined_hint(metric, study)}): "
                     + _examples(undefined, points))
    if parts:
        return None, (f"no indices: the {study.sensitivity.method} design needs a value from each of its "
                      f"{len(unique)} runs, and " + "; ".join(parts))
    y = values.loc[keys].to_numpy(float)
    if np.ptp(y) == 0.0:
        return None, f"no indices: {metric} is {y[0]:g} in every run, there is no variation to apportion"
    return y, None


def sensitivity_indices(study: Study, table: pd.DataFrame) -> SensitivityResult:
    """The indices of sensitivity study ``study`` from its results ``table`` (every metric of its
    ``[sensitivity] metrics``, default all recorded): see :class:`SensitivityResult`."""
    import pandas as pd

    from wetcloth.batch.results import KEY

    spec = study.sensitivity
    if spec is None:
        raise ValueError(f"study {study.name!r} has no [sensitivity] table")
    names = study.axis_names
    unit = study.design()
    keys = study.point_keys()
    points = {r.key: r.point for r in study.runs()}
    by_key = table.drop_duplicates(KEY, keep="last").set_index(KEY)
    runs = len(points)
    metrics = list(spec.metrics or study.metrics)
    rows, problems = [], {}
    for metric in metrics:
        y, problem = design_outputs(study, by_key, metric, keys, points)
        if problem is not None:
            problems[metric] = problem
            continue
        found = analyze(spec, names, unit, y, study.seed)
        order = found["ST" if spec.method == "sobol" else "mu_star"]
        ranks = np.empty(len(names), int)
        ranks[np.argsort(-order, kind="stable")] = np.arange(1, len(names) + 1)
        for j, name in enumerate(names):
            rows.append({"metric": metric, "unit": METRICS[metric].unit, "parameter": name, "rank": int(ranks[j])}
                        | {k: float(v[j]) for k, v in found.items()}
                        | {"method": spec.method, "runs": runs, "conf_level": spec.conf_level})
    columns = ["metric", "unit", "parameter", "rank", *INDICES[spec.method], "method", "runs", "conf_level"]
    return SensitivityResult(spec=spec, factors=names, metrics=metrics, runs=runs,
                             indices=pd.DataFrame(rows, columns=columns), problems=problems)


def format_indices(result: SensitivityResult) -> str:
    """The indices as text for a terminal: per metric, the factors from most to least influential."""
    spec = result.spec
    level = f"{100 * spec.conf_level:g}%"
    lines = [f"sensitivity ({spec.describe(len(result.factors))}; +- {level} confidence):"]
    for metric in result.metrics:
        unit = METRICS[metric].unit
        lines.append(f"  {metric} ({unit})")
        if metric in result.problems:
            lines.extend(textwrap.wrap(result.problems[metric], 110, initial_indent="    ", subsequent_indent="      "))
            continue
        frame = result.indices[result.indices["metric"] == metric].sort_values("rank")
        width = max(len(n) for n in frame["parameter"])
        if spec.method == "sobol":
            lines.append(f"    {'parameter':<{width}}  {'S1':>15}  {'ST':>15}")
            for r in frame.itertuples():
                lines.append(f"    {r.parameter:<{width}}  {r.S1:7.3f} +- {r.S1_conf:5.3f}  {r.ST:7.3f} +- {r.ST_conf:5.3f}")
        else:
            lines.append(f"    {'parameter':<{width}}  {'mu* (' + unit + ')':>21}  {'mu':>10}  {'sigma':>10}")
            for r in frame.itertuples():
                lines.append(f"    {r.parameter:<{width}}  {r.mu_star:10.4g} +- {r.mu_star_conf:<8.3g}  "
                             f"{r.mu:10.4g}  {r.sigma:10.4g}")
    return "\n".join(lines)
