"""A batch study: a base scene, axes over scene parameters, a duration and the metrics to record.

A study file is TOML (see ``docs/batch.md`` and ``models/studies/``)::

    description = "time to sink over capacity x rate"
    scene = "thesis_fast"          # base scene: preset name or scene TOML (relative to this file)
    duration = 60.0                # s of simulated time per run
    sample_rate = 10.0             # Hz: outputs are sampled at this rate for the metrics
    sink_depth = 0.05              # m: 'sunk' once the centroid is more than this below the surface
    metrics = ["time_to_sink", "final_depth", "final_wet_mass", "time_to_90_wet_mass"]

    [base]                         # parameter overrides shared by every run
    nx = 9
    ny = 9

    [axes]                         # one axis per parameter: a list, a range or a random draw
    absorption_capacity = [1.0, 2.0, 3.8]
    absorption_rate = { start = 0.05, stop = 0.5, num = 4 }

The runs are the Cartesian product of the grid axes (lists and ranges), crossed with
``samples`` joint draws of the random axes (seeded by ``seed``).  Every run is keyed by all
its parameter values and run settings (``run_key``), so a rerun can skip what is done.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from wetcloth.batch.metrics import DEFAULT_METRICS, METRICS
from wetcloth.scene import PARAMETERS, RESERVED_KEYS, coerce, describe_range, read_scene_file, resolve_scene_path

ENGINES = ("python", "fmu")
DISTRIBUTIONS = ("uniform", "loguniform", "normal", "integers", "choice")
DEFAULT_SAMPLE_RATE = 10.0  # Hz
DEFAULT_SINK_DEPTH = 0.05  # m
SIGNIFICANT_DIGITS = 12  # range values are rounded to this many digits, so 0.1 from a range equals 0.1 from a list

#: Keys allowed at the top level of a study file.
STUDY_KEYS = (
    "name", "description", "scene", "duration", "sample_rate", "sink_depth", "metrics", "engine", "fmu",
    "seed", "samples", "base", "axes", "plot",
)


class StudyError(ValueError):
    """A study file or study dict is malformed; the message names the key and what is allowed."""

    def __init__(self, key: str, message: str):
        super().__init__(f"study '{key}': {message}")
        self.key = key


def default_fmu_path() -> str:
    """``models/WetCloth.fmu``, where ``wetcloth build-fmu`` writes it (``wetcloth.fmu.default_fmu_path``)."""
    from wetcloth.fmu import default_fmu_path as fmu_path

    return str(fmu_path())


@dataclass(frozen=True)
class PlotSpec:
    """A plot of ``metric`` against axis ``x`` (a line), or over ``x`` and ``y`` (a heatmap)."""

    metric: str
    x: str
    y: str | None = None

    def filename(self, study_name: str) -> str:
        if self.y is None:
            return f"{study_name}_{self.metric}_vs_{self.x}.png"
        return f"{study_name}_{self.metric}_{self.x}_x_{self.y}.png"


def parse_plot_spec(text: str) -> PlotSpec:
    """'METRIC:AXIS' (line) or 'METRIC:X,Y' (heatmap), as given to ``wetcloth batch --plot``."""
    metric, sep, rest = text.partition(":")
    axes = [a.strip() for a in rest.split(",") if a.strip()]
    if not sep or not metric.strip() or len(axes) not in (1, 2):
        raise StudyError("plot", f"expected METRIC:AXIS or METRIC:X,Y, got {text!r}")
    return PlotSpec(metric.strip(), axes[0], axes[1] if len(axes) == 2 else None)


@dataclass(frozen=True)
class Axis:
    """One study axis: grid ``values``, or a random ``distribution`` (a dict) drawn ``samples`` times."""

    name: str
    values: tuple = ()
    distribution: dict | None = None

    @property
    def is_random(self) -> bool:
        return self.distribution is not None


@dataclass(frozen=True)
class Run:
    """One run of a study: its key, its full parameter values and its coordinates on the axes."""

    key: str
    params: dict[str, Any]
    point: dict[str, Any]


def _round(value: float) -> float:
    return float(f"{value:.{SIGNIFICANT_DIGITS}g}")


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _check_type(name: str, value, where: str) -> None:
    """The value's kind (number or string) must match the parameter's; ranges are checked per run."""
    f = PARAMETERS[name]
    if f.type == "str" and not isinstance(value, str):
        raise StudyError(where, f"{name} takes a string ({describe_range(f)}), got {value!r}")
    if f.type != "str" and not _is_number(value):
        raise StudyError(where, f"{name} takes a number ({describe_range(f)}), got {value!r}")


def _check_name(name: str, where: str) -> None:
    if name in PARAMETERS:
        return
    from wetcloth.fmu.vocabulary import variable_specs

    if any(v.name == name and v.causality == "parameter" for v in variable_specs()):  # mesh_output_dir, mesh_format
        raise StudyError(where, f"{name!r} is an FMU-only parameter, not a scene parameter: a study varies scene "
                                "parameters and records metrics; to keep the meshes of a run, run its scene with "
                                "'wetcloth run --export DIR'")
    raise StudyError(where, f"unknown parameter {name!r}; known: {', '.join(PARAMETERS)}")


def _range_values(name: str, spec: dict) -> tuple:
    """Values of a range table ``{start, stop, num [, log]}`` or ``{start, stop, step}`` (stop included)."""
    where = f"axes.{name}"
    allowed = {"start", "stop", "num", "step", "log"}
    if unknown := set(spec) - allowed:
        raise StudyError(where, f"unknown key(s) {sorted(unknown)}; a range has start, stop and num (or step), optional log")
    if not {"start", "stop"} <= set(spec) or ("num" in spec) == ("step" in spec):
        raise StudyError(where, "a range needs start, stop and exactly one of num or step")
    start, stop = spec["start"], spec["stop"]
    if not (_is_number(start) and _is_number(stop) and math.isfinite(start) and math.isfinite(stop)):
        raise StudyError(where, f"start and stop must be finite numbers, got {start!r}, {stop!r}")
    if "num" in spec:
        num = spec["num"]
        if not isinstance(num, int) or isinstance(num, bool) or num < 1:
            raise StudyError(where, f"num must be a whole number >= 1, got {num!r}")
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
        if not _is_number(step) or not math.isfinite(step) or step == 0 or (stop - start) * step < 0:
            raise StudyError(where, f"step must be a finite number, non-zero, from start toward stop; got {step!r}")
        count = int(math.floor((stop - start) / step + 1e-9)) + 1
        values = start + step * np.arange(count)
    if PARAMETERS[name].type == "int":
        if not all(float(v).is_integer() for v in np.round(values, 9)):
            raise StudyError(where, f"{name} takes whole numbers; this range gives {values.tolist()}")
        return tuple(int(round(v)) for v in values)
    return tuple(_round(float(v)) for v in values)


def _parse_distribution(name: str, spec: dict) -> dict:
    """A random axis ``{random = KIND, ...}``: uniform/loguniform (low, high), normal (mean, std),
    integers (low, high; both included), choice (values)."""
    where = f"axes.{name}"
    kind = spec.get("random")
    needs = {"uniform": ("low", "high"), "loguniform": ("low", "high"), "normal": ("mean", "std"),
             "integers": ("low", "high"), "choice": ("values",)}
    if kind not in needs:
        raise StudyError(where, f"random must be one of {', '.join(DISTRIBUTIONS)}, got {kind!r}")
    keys = set(spec) - {"random"}
    if keys != set(needs[kind]):
        raise StudyError(where, f"random = {kind!r} takes exactly {', '.join(needs[kind])}; got {sorted(keys)}")
    is_str = PARAMETERS[name].type == "str"
    if kind == "choice":
        values = spec["values"]
        if not isinstance(values, list) or not values:
            raise StudyError(where, "choice needs a non-empty list of values")
        for v in values:
            _check_type(name, v, where)
        return {"random": kind, "values": list(values)}
    if is_str:
        raise StudyError(where, f"{name} is a string parameter: use random = 'choice'")
    a, b = (spec[k] for k in needs[kind])
    if not (_is_number(a) and _is_number(b) and math.isfinite(a) and math.isfinite(b)):
        raise StudyError(where, f"{', '.join(needs[kind])} must be finite numbers, got {a!r}, {b!r}")
    if kind in ("uniform", "loguniform", "integers") and not a < b:
        raise StudyError(where, f"needs low < high, got {a!r}, {b!r}")
    if kind == "loguniform" and a <= 0:
        raise StudyError(where, f"loguniform needs low > 0, got {a!r}")
    if kind == "normal" and not b > 0:
        raise StudyError(where, f"normal needs std > 0, got {b!r}")
    if kind == "integers" and not (isinstance(a, int) and isinstance(b, int)):
        raise StudyError(where, f"integers needs whole-number low and high, got {a!r}, {b!r}")
    if PARAMETERS[name].type == "int" and kind != "integers":
        raise StudyError(where, f"{name} takes whole numbers: use random = 'integers' or 'choice'")
    return dict(spec)


def _parse_axis(name, spec) -> Axis:
    where = f"axes.{name}"
    _check_name(name, where)
    if isinstance(spec, list):
        if not spec:
            raise StudyError(where, "an axis needs at least one value")
        for v in spec:
            _check_type(name, v, where)
        values = tuple(coerce(name, v) for v in spec)
    elif isinstance(spec, dict) and "random" in spec:
        return Axis(name, distribution=_parse_distribution(name, spec))
    elif isinstance(spec, dict):
        if PARAMETERS[name].type == "str":
            raise StudyError(where, f"{name} is a string parameter: give a list of values")
        values = _range_values(name, spec)
    else:
        _check_type(name, spec, where)
        values = (coerce(name, spec),)
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


def _positive(key: str, value, allow_zero=False) -> float:
    ok = _is_number(value) and math.isfinite(value) and (value >= 0 if allow_zero else value > 0)
    if not ok:
        raise StudyError(key, f"must be a finite number {'>= 0' if allow_zero else '> 0'}, got {value!r}")
    return float(value)


def run_key(params: dict[str, Any], settings: dict[str, Any]) -> str:
    """A short, stable hash of a run's full parameter values and run settings."""
    text = json.dumps({"params": params, "settings": settings}, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


@dataclass(frozen=True)
class Study:
    """A parsed, validated study.  Build it with :func:`load_study` or :meth:`Study.from_dict`."""

    name: str
    duration: float  # s
    scene_values: dict[str, Any] = field(default_factory=dict)  # the base scene file's parameters
    base: dict[str, Any] = field(default_factory=dict)  # overrides shared by every run
    axes: tuple[Axis, ...] = ()
    sample_rate: float = DEFAULT_SAMPLE_RATE  # Hz
    sink_depth: float = DEFAULT_SINK_DEPTH  # m
    metrics: tuple[str, ...] = DEFAULT_METRICS
    engine: str = "python"
    fmu: str = ""  # FMU path for engine 'fmu'; "" = models/WetCloth.fmu
    seed: int = 0
    samples: int = 0
    plots: tuple[PlotSpec, ...] = ()
    description: str = ""
    scene: str = ""  # where the base scene came from (for messages)

    def __post_init__(self):
        self._validate()

    # ---- construction
    @classmethod
    def from_dict(cls, data: dict[str, Any], base_dir: str | Path | None = None, name: str | None = None) -> "Study":
        """A study from the contents of a study file (relative scene paths resolve from ``base_dir``)."""
        if not isinstance(data, dict):
            raise StudyError("study", f"expected a table of settings, got {type(data).__name__}")
        if unknown := [k for k in data if k not in STUDY_KEYS]:
            raise StudyError(unknown[0], f"unknown key; allowed: {', '.join(STUDY_KEYS)}")
        scene_ref = data.get("scene")
        scene_path = _resolve_scene(scene_ref, base_dir)
        scene_file = read_scene_file(scene_path)
        run_table = scene_file.get("run", {})
        scene_values = {k: v for k, v in scene_file.items() if k not in RESERVED_KEYS}
        for key, value in scene_values.items():
            _check_name(key, f"scene ({scene_path})")
        base = data.get("base", {})
        if not isinstance(base, dict):
            raise StudyError("base", "must be a table of parameter = value")
        for key, value in base.items():
            _check_name(key, f"base.{key}")
            _check_type(key, value, f"base.{key}")
        axes_table = data.get("axes", {})
        if not isinstance(axes_table, dict):
            raise StudyError("axes", "must be a table of parameter = values")
        axes = tuple(_parse_axis(k, v) for k, v in axes_table.items())
        if "duration" in data:
            duration = data["duration"]
        elif "duration" in run_table:
            duration = run_table["duration"]
        else:
            raise StudyError("duration", f"missing: give the simulated time per run in s (the scene {scene_path.name} has no [run] duration)")
        plots = data.get("plot", [])
        if not isinstance(plots, list) or not all(isinstance(p, dict) for p in plots):
            raise StudyError("plot", "must be an array of tables [[plot]] with metric, x and optional y")
        plot_specs = []
        for p in plots:
            if set(p) - {"metric", "x", "y"} or not {"metric", "x"} <= set(p):
                raise StudyError("plot", f"each [[plot]] has metric, x and optional y; got {sorted(p)}")
            plot_specs.append(PlotSpec(p["metric"], p["x"], p.get("y")))
        metrics = data.get("metrics", list(DEFAULT_METRICS))
        if not isinstance(metrics, list):
            raise StudyError("metrics", f"must be a list of metric names, got {metrics!r}")
        return cls(
            name=str(data.get("name", name or "study")),
            description=str(data.get("description", "")),
            scene=str(scene_path),
            scene_values=scene_values,
            base={k: coerce(k, v) for k, v in base.items()},
            axes=axes,
            duration=duration,
            sample_rate=data.get("sample_rate", DEFAULT_SAMPLE_RATE),
            sink_depth=data.get("sink_depth", DEFAULT_SINK_DEPTH),
            metrics=tuple(metrics),
            engine=data.get("engine", "python"),
            fmu=str(_resolve_relative(data["fmu"], base_dir)) if "fmu" in data else "",
            seed=data.get("seed", 0),
            samples=data.get("samples", 0),
            plots=tuple(plot_specs),
        )

    def replace(self, **changes) -> "Study":
        """A copy with some settings changed (validated)."""
        return dataclasses.replace(self, **changes)

    def _validate(self) -> None:
        object.__setattr__(self, "duration", _positive("duration", self.duration))
        object.__setattr__(self, "sample_rate", _positive("sample_rate", self.sample_rate))
        object.__setattr__(self, "sink_depth", _positive("sink_depth", self.sink_depth, allow_zero=True))
        if unknown := [m for m in self.metrics if m not in METRICS]:
            raise StudyError("metrics", f"unknown metric {unknown[0]!r}; known: {', '.join(METRICS)}")
        if not self.metrics:
            raise StudyError("metrics", f"give at least one of: {', '.join(METRICS)}")
        if len(set(self.metrics)) != len(self.metrics):
            raise StudyError("metrics", f"repeated metric in {list(self.metrics)}")
        if self.engine not in ENGINES:
            raise StudyError("engine", f"{self.engine!r} is not allowed; allowed: {', '.join(ENGINES)}")
        if not isinstance(self.seed, int) or isinstance(self.seed, bool) or self.seed < 0:
            raise StudyError("seed", f"must be a whole number >= 0, got {self.seed!r}")
        names = [a.name for a in self.axes]
        if len(set(names)) != len(names):
            raise StudyError("axes", f"repeated axis in {names}")
        if both := [n for n in names if n in self.base]:
            raise StudyError(f"axes.{both[0]}", "is also set in [base]: set it in one place")
        has_random = any(a.is_random for a in self.axes)
        if not isinstance(self.samples, int) or isinstance(self.samples, bool) or self.samples < 0:
            raise StudyError("samples", f"must be a whole number >= 0, got {self.samples!r}")
        if has_random and self.samples < 1:
            raise StudyError("samples", "random axes need samples >= 1 (the number of joint draws)")
        if self.samples and not has_random:
            raise StudyError("samples", "is only for random axes ({random = ...}); there are none")
        self.check_plots(self.plots)

    def check_plots(self, specs) -> None:
        """Each plot names a recorded metric and one or two axes of this study."""
        names = [a.name for a in self.axes]
        for spec in specs:
            if spec.metric not in self.metrics:
                raise StudyError("plot", f"metric {spec.metric!r} is not recorded; recorded: {', '.join(self.metrics)}")
            for axis in (spec.x, spec.y):
                if axis is not None and axis not in names:
                    raise StudyError("plot", f"{axis!r} is not an axis of this study; axes: {', '.join(names) or 'none'}")
            if spec.y is not None and spec.y == spec.x:
                raise StudyError("plot", f"a heatmap needs two different axes, got {spec.x!r} twice")

    # ---- the runs
    @property
    def axis_names(self) -> list[str]:
        return [a.name for a in self.axes]

    @property
    def settings(self) -> dict[str, Any]:
        """Run settings that, with the parameters, determine a run's result."""
        return dict(duration=self.duration, sample_rate=self.sample_rate, sink_depth=self.sink_depth,
                    engine=self.engine, metrics=sorted(self.metrics))

    def points(self) -> list[dict[str, Any]]:
        """Axis coordinates of every run: grid axes crossed, then crossed with the random draws."""
        grid = [a for a in self.axes if not a.is_random]
        random_axes = [a for a in self.axes if a.is_random]
        grid_points = [dict(zip([a.name for a in grid], combo)) for combo in itertools.product(*(a.values for a in grid))]
        if random_axes:
            rng = np.random.default_rng(self.seed)
            draws = {a.name: _draw(a, rng, self.samples) for a in random_axes}
            samples = [{name: draws[name][i] for name in draws} for i in range(self.samples)]
        else:
            samples = [{}]
        order = self.axis_names
        return [{n: (g | s)[n] for n in order} for g in grid_points for s in samples]

    def base_params(self) -> dict[str, Any]:
        """Every parameter's value before the axes: defaults, then the scene file, then [base]."""
        defaults = {name: f.default for name, f in PARAMETERS.items()}
        values = defaults | self.scene_values | self.base
        return {k: coerce(k, v) for k, v in values.items()}

    def runs(self) -> list[Run]:
        """Every run of the study in order; identical runs (repeated random draws) appear once."""
        base = self.base_params()
        settings = self.settings
        out, seen = [], set()
        for point in self.points():
            params = base | point
            key = run_key(params, settings)
            if key not in seen:
                seen.add(key)
                out.append(Run(key, params, point))
        return out


def _resolve_relative(ref: str, base_dir) -> Path:
    path = Path(ref)
    if not path.is_absolute() and base_dir is not None and (Path(base_dir) / path).exists():
        return Path(base_dir) / path
    return path


def _resolve_scene(ref, base_dir) -> Path:
    if ref is None:
        return resolve_scene_path(None)
    if not isinstance(ref, str):
        raise StudyError("scene", f"must be a preset name or a scene TOML path, got {ref!r}")
    return resolve_scene_path(_resolve_relative(ref, base_dir))


def load_study(path: str | Path) -> Study:
    """Read and validate a study TOML file."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"study file {str(path)!r} not found")
    with open(path, "rb") as fh:
        try:
            data = tomllib.load(fh)
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"study file {path}: {exc}") from None
    return Study.from_dict(data, base_dir=path.parent, name=path.stem)
