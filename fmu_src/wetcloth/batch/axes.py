"""A study's axes: lists, ranges and sampled axes over scene parameters, and the points they span.

An axis is a list of values, a range (``{start, stop, num [, log]}`` or ``{start, stop, step}``,
stop included), or a sampled axis: bounds (``{low, high [, log]}``) or a distribution
(``{random = KIND, ...}``).  The points of a study are the Cartesian product of the grid axes
(lists and ranges, in order, the last varying fastest), crossed with ``samples`` joint points of
the sampled axes, placed by the study's ``sampling``: independent random draws, a Latin
hypercube or a scrambled Sobol' sequence (``scipy.stats.qmc``), all seeded, so a rerun makes the
same points.  No study may span more than ``MAX_RUNS`` points: the count is checked before any is made.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from wetcloth.errors import ConfigError, StudyError, did_you_mean
from wetcloth.scene import PARAMETER_LISTING, PARAMETERS, is_parameter, normalise, parameter_field

DISTRIBUTIONS = ("uniform", "loguniform", "normal", "integers", "choice")
#: Random kinds and the keys each takes.
DISTRIBUTION_KEYS = {"uniform": ("low", "high"), "loguniform": ("low", "high"), "normal": ("mean", "std"),
                     "integers": ("low", "high"), "choice": ("values",)}
RANGE_KEYS = ("start", "stop", "num", "step", "log")
BOUNDS_KEYS = ("low", "high", "log")
#: How the joint points of the sampled axes are placed: independent draws (numpy), a Latin
#: hypercube or a scrambled Sobol' sequence (scipy.stats.qmc).
SAMPLINGS = ("random", "lhs", "sobol")
SIGNIFICANT_DIGITS = 12  # range values are rounded to this many digits, so 0.1 from a range equals 0.1 from a list
#: Most runs one study may have (and so values one axis may have): 100 000 runs of 1 s each keep
#: two cores busy for 14 hours.
MAX_RUNS = 100_000


@dataclass(frozen=True)
class Axis:
    """One study axis: grid ``values``, or a sampled axis's ``distribution`` (a dict: ``random`` =
    its kind and that kind's keys), sampled ``samples`` times."""

    name: str
    values: tuple = ()
    distribution: dict | None = None

    @property
    def is_random(self) -> bool:
        return self.distribution is not None


def _round(value: float) -> float:
    return float(f"{value:.{SIGNIFICANT_DIGITS}g}")


def is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def check_count(key: str, what: str, count: float) -> None:
    """Refuse more than ``MAX_RUNS`` of something (values of an axis, draws, runs), naming the bound."""
    if count > MAX_RUNS:
        raise StudyError(key, f"{what} {count:.3g}; at most {MAX_RUNS} runs per study: split the study or "
                              "take coarser axes")


def check_name(name: str, where: str) -> None:
    """``name`` must be a scene parameter or a collider field (the FMU's own parameters are not)."""
    if is_parameter(name):
        return
    from wetcloth.fmu.vocabulary import variable_specs

    if any(v.name == name and v.causality == "parameter" for v in variable_specs()):  # mesh_output_dir, mesh_format
        raise StudyError(where, f"{name!r} is an FMU-only parameter, not a scene parameter: a study varies scene "
                                "parameters and records metrics; to keep the meshes of a run, run its scene with "
                                "'wetcloth run --export DIR'")
    raise StudyError(where, f"{name!r}: " + did_you_mean(name, PARAMETERS, listing=PARAMETER_LISTING))


def typed(name: str, value, where: str):
    """``value`` in parameter ``name``'s type, by the scene's one rule (``wetcloth.scene.normalise``);
    ranges are checked per run."""
    try:
        return normalise(name, value)
    except ConfigError as exc:
        raise StudyError(where, exc.problems[0][2]) from None


def _range_values(name: str, spec: dict) -> tuple:
    """Values of a range table ``{start, stop, num [, log]}`` or ``{start, stop, step}`` (stop included)."""
    where = f"axes.{name}"
    if unknown := sorted(set(spec) - set(RANGE_KEYS)):
        raise StudyError(where, f"unknown key(s) {unknown}; a range has start, stop and num (or step), optional log")
    if not {"start", "stop"} <= set(spec) or ("num" in spec) == ("step" in spec):
        raise StudyError(where, "a range needs start, stop and exactly one of num or step")
    start, stop = spec["start"], spec["stop"]
    if not (is_number(start) and is_number(stop) and math.isfinite(start) and math.isfinite(stop)):
        raise StudyError(where, f"start and stop must be finite numbers, got {start!r}, {stop!r}")
    if "num" in spec:
        num = spec["num"]
        if not (is_number(num) and float(num).is_integer() and num >= 1):
            raise StudyError(where, f"num must be a whole number >= 1, got {num!r}")
        check_count(where, "num is", num)
        num = int(num)
        log = spec.get("log", False)
        if not isinstance(log, bool):
            raise StudyError(where, f"log must be true or false, got {log!r}")
        if log:
            if start <= 0 or stop <= 0:
                raise StudyError(where, f"a log range needs start > 0 and stop > 0, got {start!r}, {stop!r}")
            values = np.geomspace(start, stop, num) if num > 1 else np.array([start], float)
        else:
            values = np.linspace(start, stop, num)
    else:
        if "log" in spec:
            raise StudyError(where, "log goes with num, not with step")
        step = spec["step"]
        if not is_number(step) or not math.isfinite(step) or step == 0 or (stop - start) * step < 0:
            raise StudyError(where, f"step must be a finite number, non-zero, from start toward stop; got {step!r}")
        count = math.floor((stop - start) / step + 1e-9) + 1
        check_count(where, f"step {step:g} from {start:g} to {stop:g} gives", count)
        values = start + step * np.arange(count)
    if parameter_field(name).type == "int":
        if not all(float(v).is_integer() for v in np.round(values, 9)):
            raise StudyError(where, f"{name} takes whole numbers; this range gives {values.tolist()}")
        return tuple(int(round(v)) for v in values)
    return tuple(_round(float(v)) for v in values)


def _parse_distribution(name: str, spec: dict) -> dict:
    """A random axis ``{random = KIND, ...}``: uniform/loguniform (low, high), normal (mean, std),
    integers (low, high; both included), choice (values)."""
    where = f"axes.{name}"
    kind = spec.get("random")
    if kind not in DISTRIBUTION_KEYS:
        raise StudyError(where, f"random must be one of {', '.join(DISTRIBUTIONS)}, got {kind!r}")
    needs = DISTRIBUTION_KEYS[kind]
    keys = set(spec) - {"random"}
    if keys != set(needs):
        raise StudyError(where, f"random = {kind!r} takes exactly {', '.join(needs)}; got {sorted(keys)}")
    if kind == "choice":
        values = spec["values"]
        if not isinstance(values, list) or not values:
            raise StudyError(where, "choice needs a non-empty list of values")
        return {"random": kind, "values": [typed(name, v, where) for v in values]}
    if parameter_field(name).type == "str":
        raise StudyError(where, f"{name} is a string parameter: use random = 'choice'")
    a, b = (spec[k] for k in needs)
    if not (is_number(a) and is_number(b) and math.isfinite(a) and math.isfinite(b)):
        raise StudyError(where, f"{', '.join(needs)} must be finite numbers, got {a!r}, {b!r}")
    if kind in ("uniform", "loguniform", "integers") and not a < b:
        raise StudyError(where, f"needs low < high, got {a!r}, {b!r}")
    if kind == "loguniform" and a <= 0:
        raise StudyError(where, f"loguniform needs low > 0, got {a!r}")
    if kind == "normal" and not b > 0:
        raise StudyError(where, f"normal needs std > 0, got {b!r}")
    if kind == "integers" and not (isinstance(a, int) and isinstance(b, int)):
        raise StudyError(where, f"integers needs whole-number low and high, got {a!r}, {b!r}")
    if parameter_field(name).type == "int" and kind != "integers":
        raise StudyError(where, f"{name} takes whole numbers: use random = 'integers' or 'choice'")
    return dict(spec)


def _bounds_distribution(name: str, spec: dict) -> dict:
    """A bounds table ``{low, high [, log]}`` as the distribution it means: uniform between the bounds
    (``log = true``: uniform in the logarithm); ``integers`` (both bounds included) for a whole-number
    parameter."""
    where = f"axes.{name}"
    if unknown := sorted(set(spec) - set(BOUNDS_KEYS)):
        raise StudyError(where, f"unknown key(s) {unknown}; bounds are low and high, optional log")
    if not {"low", "high"} <= set(spec):
        raise StudyError(where, "bounds need both low and high")
    log = spec.get("log", False)
    if not isinstance(log, bool):
        raise StudyError(where, f"log must be true or false, got {log!r}")
    if parameter_field(name).type == "str":
        raise StudyError(where, f"{name} is a string parameter: give a list of values or random = 'choice'")
    if parameter_field(name).type == "int":
        if log:
            raise StudyError(where, f"{name} takes whole numbers: bounds of a whole-number parameter take no log")
        kind = "integers"
    else:
        kind = "loguniform" if log else "uniform"
    return _parse_distribution(name, {"random": kind, "low": spec["low"], "high": spec["high"]})


def parse_axis(name: str, spec) -> Axis:
    """An axis from its study-file entry: a list, a range table, a bounds or random table, or one value."""
    where = f"axes.{name}"
    check_name(name, where)
    if isinstance(spec, list):
        if not spec:
            raise StudyError(where, "an axis needs at least one value")
        check_count(where, "the list has", len(spec))
        values = tuple(typed(name, v, where) for v in spec)
    elif isinstance(spec, dict) and "random" in spec:
        return Axis(name, distribution=_parse_distribution(name, spec))
    elif isinstance(spec, dict) and {"low", "high"} & set(spec):
        return Axis(name, distribution=_bounds_distribution(name, spec))
    elif isinstance(spec, dict):
        if parameter_field(name).type == "str":
            raise StudyError(where, f"{name} is a string parameter: give a list of values")
        values = _range_values(name, spec)
    else:
        values = (typed(name, spec, where),)
    if len(set(values)) != len(values):
        raise StudyError(where, f"repeated values in {list(values)}: each run is keyed by its parameters")
    return Axis(name, values=values)


def _draw(axis: Axis, rng: np.random.Generator, samples: int) -> list:
    d = axis.distribution
    kind = d["random"]
    if kind == "uniform":
        values = rng.uniform(d["low"], d["high"], samples)
    elif kind == "loguniform":
        values = np.exp(rng.uniform(math.log(d["low"]), math.log(d["high"]), samples))
    elif kind == "normal":
        values = rng.normal(d["mean"], d["std"], samples)
    elif kind == "integers":
        return [int(v) for v in rng.integers(d["low"], d["high"], samples, endpoint=True)]
    else:  # choice
        return [d["values"][i] for i in rng.integers(0, len(d["values"]), samples)]
    return [float(v) for v in values]


def from_unit(axis: Axis, u) -> list:
    """The values of sampled ``axis`` at unit coordinates ``u`` (each in [0, 1]): its inverse
    cumulative distribution, so points spread evenly in the unit cube (a Latin hypercube, a Sobol'
    sequence, a sensitivity design) spread by the axis's distribution.  ``integers`` and ``choice``
    split [0, 1] into equal parts, one per value (u = 1 is the last value)."""
    d = axis.distribution
    kind = d["random"]
    u = np.asarray(u, float)
    if kind in ("integers", "choice"):
        options = list(range(d["low"], d["high"] + 1)) if kind == "integers" else d["values"]
        index = np.minimum((u * len(options)).astype(int), len(options) - 1)
        return [options[i] for i in index]
    if kind == "uniform":
        values = d["low"] + u * (d["high"] - d["low"])
    elif kind == "loguniform":
        values = d["low"] * (d["high"] / d["low"]) ** u
    else:  # normal: u = 0 or 1 would be -inf or +inf; the open interval keeps every value finite
        from scipy.stats import norm

        values = d["mean"] + d["std"] * norm.ppf(np.clip(u, np.nextafter(0.0, 1.0), np.nextafter(1.0, 0.0)))
    return [float(v) for v in values]


def unit_points(sampling: str, dimensions: int, samples: int, seed: int) -> np.ndarray:
    """``samples`` points of the unit cube of ``dimensions`` dimensions (rows), seeded: a Latin
    hypercube (``lhs``) or a scrambled Sobol' sequence (``sobol``; ``samples`` a power of 2 keeps
    its balance, and the first n points of a longer sequence are the n-point sequence)."""
    from scipy.stats import qmc

    if sampling == "lhs":
        return qmc.LatinHypercube(dimensions, rng=seed).random(samples)
    if sampling == "sobol":
        return qmc.Sobol(dimensions, scramble=True, rng=seed).random(samples)
    raise ValueError(f"sampling {sampling!r} has no unit points; known: lhs, sobol")


def point_count(axes: tuple[Axis, ...], samples: int) -> int:
    """How many points ``points`` gives (before identical runs are merged)."""
    grid = math.prod(len(a.values) for a in axes if not a.is_random)
    return grid * (samples if any(a.is_random for a in axes) else 1)


def sampled_points(axes: list[Axis], samples: int, seed: int, sampling: str = "random") -> list[dict[str, Any]]:
    """``samples`` joint points of the sampled ``axes``: independent draws from
    ``numpy.random.default_rng(seed)`` (``random``, axis by axis), or a seeded Latin hypercube or
    Sobol' sequence mapped through each axis's distribution (``from_unit``)."""
    if sampling == "random":
        rng = np.random.default_rng(seed)
        columns = {a.name: _draw(a, rng, samples) for a in axes}
    else:
        unit = unit_points(sampling, len(axes), samples, seed)
        columns = {a.name: from_unit(a, unit[:, j]) for j, a in enumerate(axes)}
    return [{name: columns[name][i] for name in columns} for i in range(samples)]


def points(axes: tuple[Axis, ...], samples: int, seed: int, sampling: str = "random") -> list[dict[str, Any]]:
    """Axis coordinates of every run: grid axes crossed, then crossed with the sampled points."""
    grid = [a for a in axes if not a.is_random]
    random_axes = [a for a in axes if a.is_random]
    grid_points = [dict(zip([a.name for a in grid], combo)) for combo in itertools.product(*(a.values for a in grid))]
    drawn = sampled_points(random_axes, samples, seed, sampling) if random_axes else [{}]
    order = [a.name for a in axes]
    return [{n: (g | s)[n] for n in order} for g in grid_points for s in drawn]
