"""A batch study: a base scene, axes over its parameters, run settings and the metrics to record.

A study file is TOML (see ``docs/batch.md`` and ``models/studies/``)::

    description = "time to sink over capacity x rate"
    scene = "thesis_fast"          # base scene: preset name or scene TOML (relative to this file)
    duration = 60.0                # s of simulated time per run
    sample_rate = 10.0             # Hz: outputs are sampled at this rate for the metrics
    sink_depth = 0.05              # m: 'sunk' once the centroid is more than this below the surface
    metrics = ["time_to_sink", "final_depth", "final_wet_mass", "time_to_90_wet_mass"]
    series = ["depth", "wet_mass"] # outputs whose curves are kept (NAME.series.zarr beside the table)

    [base]                         # parameter overrides shared by every run
    nx = 9
    ny = 9

    [axes]                         # one axis per parameter: a list, a range, bounds or a random draw
    absorption_capacity = [1.0, 2.0, 3.8]
    absorption_rate = { start = 0.05, stop = 0.5, num = 4 }

The runs are the points of the axes (``wetcloth.batch.axes``), or, for a study with a
``[sensitivity]`` table, the points of its design (``wetcloth.batch.sensitivity``).  Every run is
keyed by all its parameter values and run settings (``run_key``), so a rerun can skip what is
done.  A study is checked whole when it is made: every mistake is reported at once, each naming its key.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from wetcloth import run_settings
from wetcloth.batch.axes import (SAMPLINGS, Axis, check_count, check_name, from_unit, parse_axis, point_count,
                                 points, typed)
from wetcloth.batch.engines import ENGINES, is_fmu_variable
from wetcloth.batch.metrics import DEFAULT_METRICS, check_metric_names
from wetcloth.batch.plot_spec import PlotSpec, SeriesPlotSpec, plot_specs
from wetcloth.batch.sensitivity import SensitivitySpec, check_factors, design, parse_sensitivity
from wetcloth.batch.series import check_series_names
from wetcloth.errors import ConfigError, Mistakes, StudyError, check_choice, did_you_mean
from wetcloth.mesh_file import is_mesh
from wetcloth.scene import (
    PARAMETERS,
    RESERVED_KEYS,
    parameter_field,
    preset_dir,
    read_scene_file,
    read_toml,
    resolve_preset_path,
    resolve_scene_path,
)

DEFAULT_SAMPLE_RATE = 10.0  # Hz
DEFAULT_SINK_DEPTH = 0.05  # m

#: Keys allowed at the top level of a study file.
STUDY_KEYS = (
    "name", "description", "scene", "duration", "sample_rate", "sink_depth", "metrics", "series", "engine", "fmu",
    "seed", "samples", "sampling", "base", "axes", "plot", "sensitivity",
)
#: A study's name names its output files (``out/batch/<name>.parquet``): one file name, no folder.
_PLAIN_NAME = re.compile(r"^[^/\\\x00]+$")


def run_key(params: dict[str, Any], settings: dict[str, Any]) -> str:
    """A short, stable hash of a run's full parameter values and run settings."""
    text = json.dumps({"params": params, "settings": settings}, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


@dataclass(frozen=True)
class Run:
    """One run of a study: its key, its full parameter values and its coordinates on the axes."""

    key: str
    params: dict[str, Any]
    point: dict[str, Any]


def _positive(key: str, value, allow_zero: bool = False, most: float = math.inf) -> float:
    ok = (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
          and (value >= 0 if allow_zero else value > 0) and value <= most)
    if not ok:
        bound = f" and <= {most:g}" if math.isfinite(most) else ""
        raise StudyError(key, f"must be a finite number {'>= 0' if allow_zero else '> 0'}{bound}, got {value!r}")
    return float(value)


def _whole(key: str, value) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or value < 0:
        raise StudyError(key, f"must be a whole number >= 0, got {value!r}")
    return value


def _check_name(name) -> str:
    if not (isinstance(name, str) and _PLAIN_NAME.match(name) and name.strip(" .")):
        raise StudyError("name", f"{name!r} must be a plain file name (no folder, not '.' or '..'): it names "
                                 "the study's output files, which stay in their folder (give --out to choose it)")
    return name


#: The checks of a study's own settings: field -> check(value) returning the value to keep.
_SETTING_CHECKS = {
    "name": _check_name,
    "duration": lambda v: _positive("duration", v, most=run_settings.SETTINGS["duration"].hi),
    "sample_rate": lambda v: _positive("sample_rate", v, most=run_settings.SETTINGS["fps"].hi),
    "sink_depth": lambda v: _positive("sink_depth", v, allow_zero=True),
    "metrics": functools.partial(check_metric_names, "metrics", at_least_one=True),
    "series": functools.partial(check_series_names, "series"),
    "engine": functools.partial(check_choice, StudyError, "engine", allowed=ENGINES),
    "seed": lambda v: _whole("seed", v),
    "samples": lambda v: _whole("samples", v),
    "sampling": functools.partial(check_choice, StudyError, "sampling", allowed=SAMPLINGS),
}


def _check_settings(values: dict[str, Any], mistakes: Mistakes) -> dict[str, Any]:
    """Each of a study's own settings in ``values`` checked alone (mistakes collected); the checked values."""
    checked = {}
    for key, value in values.items():
        with mistakes.collect():
            checked[key] = _SETTING_CHECKS[key](value)
    return checked


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
    series: tuple[str, ...] = ()  # outputs whose curves are kept, at sample_rate (wetcloth.batch.series)
    engine: str = "python"
    fmu: str = ""  # FMU path for engine 'fmu'; "" = models/WetCloth.fmu
    seed: int = 0
    samples: int = 0
    sampling: str = "random"  # how the sampled axes' points are placed: random, lhs or sobol
    sensitivity: SensitivitySpec | None = None  # a sensitivity design instead of grid and samples
    plots: tuple[PlotSpec | SeriesPlotSpec, ...] = ()
    description: str = ""
    scene: str = ""  # where the base scene came from (for messages)

    def __post_init__(self):
        mistakes = Mistakes()
        checked = _check_settings({key: getattr(self, key) for key in _SETTING_CHECKS}, mistakes)
        mistakes.raise_if_any()
        for key, value in checked.items():
            object.__setattr__(self, key, value)
        self._check_together()

    # ---- construction
    @classmethod
    def from_dict(cls, data: dict[str, Any], base_dir: str | Path | None = None, name: str | None = None,
                  source: str | None = None, require_axes: bool = False) -> "Study":
        """A study from the contents of a study file (relative scene paths resolve from ``base_dir``);
        ``source`` (e.g. 'study file x.toml') heads the error listing every mistake.  ``require_axes``
        (a study file): a study without axes, one run of its scene, is a mistake."""
        if not isinstance(data, dict):
            raise StudyError("study", f"expected a table of settings, got {type(data).__name__}")
        mistakes = Mistakes(source)
        for key in data:
            if key not in STUDY_KEYS:
                mistakes.add(StudyError(key, did_you_mean(key, STUDY_KEYS, "key")))
        scene_path, scene_file = None, {}
        with mistakes.collect():
            scene_path, scene_file = _scene_file(data.get("scene"), base_dir)
        base = {}
        with mistakes.collect():
            base = _base(data.get("base", {}), mistakes, base_dir)
        axes = []
        with mistakes.collect():
            table = data.get("axes", {})
            if not isinstance(table, dict):
                raise StudyError("axes", "must be a table of parameter = values")
            for key, spec in table.items():
                with mistakes.collect():
                    axes.append(_located_axis(parse_axis(key, spec), base_dir))
            if require_axes and not table:
                raise StudyError("axes", "none given: a study varies at least one parameter, one [axes] entry "
                                         "each (e.g. absorption_rate = [0.2, 0.4]); one run of a scene is "
                                         "'wetcloth run'")
        plots = ()
        with mistakes.collect():
            plots = plot_specs(data.get("plot", []))
        sensitivity = None
        if "sensitivity" in data:
            with mistakes.collect():
                sensitivity = parse_sensitivity(data["sensitivity"])
        # run settings: the study's, else the scene file's [run] table, else the defaults (one rule)
        duration = data.get("duration", run_settings.resolve(scene_file.get("run")).duration)
        settings = dict(name=data.get("name", name or "study"), duration=duration,
                        sample_rate=data.get("sample_rate", DEFAULT_SAMPLE_RATE),
                        sink_depth=data.get("sink_depth", DEFAULT_SINK_DEPTH),
                        metrics=data.get("metrics", list(DEFAULT_METRICS)), series=data.get("series", []),
                        engine=data.get("engine", "python"),
                        seed=data.get("seed", 0), samples=data.get("samples", 0),
                        sampling=data.get("sampling", "random"))
        settings = _check_settings(settings, mistakes)
        for key in ("description", "fmu"):
            if not isinstance(data.get(key, ""), str):
                mistakes.add(StudyError(key, f"must be text, got {data[key]!r}"))
        mistakes.raise_if_any()
        try:
            return cls(
                **settings,
                description=data.get("description", ""),
                scene=str(scene_path),
                scene_values={k: v for k, v in scene_file.items() if k not in RESERVED_KEYS},
                base=base,
                axes=tuple(axes),
                fmu=str(_resolve_relative(data["fmu"], base_dir)) if "fmu" in data else "",
                plots=plots,
                sensitivity=sensitivity,
            )
        except ConfigError as exc:  # what the parts are wrong about together
            mistakes.add(exc)
            mistakes.raise_if_any()

    def replace(self, **changes) -> "Study":
        """A copy with some settings changed (validated)."""
        return dataclasses.replace(self, **changes)

    def _check_together(self) -> None:
        """What the axes, [base], samples and plots must agree on (every mistake at once)."""
        mistakes = Mistakes()
        names = self.axis_names
        if len(set(names)) != len(names):
            mistakes.add(StudyError("axes", f"repeated axis in {names}"))
        for both in (n for n in names if n in self.base):
            mistakes.add(StudyError(f"axes.{both}", "is also set in [base]: set it in one place"))
        if self.engine == "fmu":
            for fixed in (n for n in names if not is_fmu_variable(n)):
                mistakes.add(StudyError(f"axes.{fixed}", "is built into an FMU, not one of its variables (colliders' "
                                                         "shapes and files, grip keys and collider keys): engine "
                                                         "'fmu' cannot vary it; use engine 'python'"))
        if self.sensitivity is not None:
            self._check_sensitivity(mistakes)
        else:
            self._check_sampling(mistakes)
        try:
            run_settings.check_frames(self.duration, self.sample_rate, "sample_rate")
        except run_settings.RunSettingError as exc:
            mistakes.add(StudyError("sample_rate", exc.problems[0][2]))
        with mistakes.collect():
            self.check_plots(self.plots)
        mistakes.raise_if_any()

    def _check_sampling(self, mistakes: Mistakes) -> None:
        """Sampled axes need samples; lhs and sobol need sampled axes, sobol a power of 2 of samples."""
        has_random = any(a.is_random for a in self.axes)
        if has_random and self.samples < 1:
            mistakes.add(StudyError("samples", "sampled axes ({low, high} or {random = ...}) need samples >= 1 "
                                               "(the number of joint points)"))
        if self.samples and not has_random:
            mistakes.add(StudyError("samples", "is only for sampled axes ({low, high} or {random = ...}); there are none"))
        if self.sampling != "random" and not has_random:
            mistakes.add(StudyError("sampling", f"{self.sampling!r} places the points of sampled axes ({{low, high}} or "
                                                "{random = ...}); there are none"))
        if self.sampling == "sobol" and self.samples > 1 and self.samples & (self.samples - 1):
            lower = 1 << (self.samples.bit_length() - 1)
            mistakes.add(StudyError("samples", f"sampling = 'sobol' needs a power of 2 (the balance of Sobol' points), "
                                               f"got {self.samples}: take {lower} or {2 * lower}"))
        with mistakes.collect():
            check_count("samples" if has_random else "axes", "the axes span", point_count(self.axes, self.samples))

    def _check_sensitivity(self, mistakes: Mistakes) -> None:
        """A sensitivity design places every run: its factors are the (sampled) axes, and it needs
        neither samples nor sampling; it analyses recorded metrics."""
        spec = self.sensitivity
        if self.samples:
            mistakes.add(StudyError("samples", "the [sensitivity] design places the runs: give its size as "
                                               "[sensitivity] samples (sobol) or trajectories (morris)"))
        if self.sampling != "random":
            mistakes.add(StudyError("sampling", "the [sensitivity] design places the runs: leave sampling out"))
        with mistakes.collect():
            check_factors(spec, self.axes)
        for metric in spec.metrics:
            if metric not in self.metrics:
                mistakes.add(StudyError("sensitivity.metrics", f"{metric!r} is not recorded; recorded: "
                                                               f"{', '.join(self.metrics)}"))
        with mistakes.collect():
            check_count("sensitivity", f"the {spec.method} design of {len(self.axes)} factors has",
                        spec.run_count(len(self.axes)))

    def check_plots(self, specs) -> None:
        """Each plot names a recorded metric and one or two axes of this study; a series plot, saved
        outputs and an axis to colour by."""
        names = self.axis_names
        mistakes = Mistakes()  # every plot's mistakes at once
        for spec in specs:
            if isinstance(spec, SeriesPlotSpec):
                with mistakes.collect():
                    self._check_series_plot(spec)
                continue
            if spec.metric not in self.metrics:
                mistakes.add(StudyError("plot", f"metric {spec.metric!r} is not recorded; recorded: "
                                                f"{', '.join(self.metrics)}"))
            for axis in (spec.x, spec.y):
                if axis is not None and axis not in names:
                    mistakes.add(StudyError("plot", f"{axis!r} is not an axis of this study; axes: "
                                                    f"{', '.join(names) or 'none'}"))
            if spec.y is not None and spec.y == spec.x:
                mistakes.add(StudyError("plot", f"a heatmap needs two different axes, got {spec.x!r} twice"))
        mistakes.raise_if_any()

    def _check_series_plot(self, spec: SeriesPlotSpec) -> None:
        if not self.series:
            raise StudyError("plot", "a plot of kind 'series' draws the curves the study keeps: give the outputs to "
                                     "keep as series = [...] (e.g. series = [\"depth\", \"wet_mass\"])")
        for name in spec.series:
            if name not in self.series:
                raise StudyError("plot", f"series {name!r} is not kept; kept: {', '.join(self.series)} "
                                         "(add it to the study's series)")
        if spec.color is not None and spec.color not in self.axis_names:
            raise StudyError("plot", f"color {spec.color!r} is not an axis of this study; axes: "
                                     f"{', '.join(self.axis_names) or 'none'}")

    # ---- the runs
    @property
    def axis_names(self) -> list[str]:
        return [a.name for a in self.axes]

    @property
    def settings(self) -> dict[str, Any]:
        """Run settings that, with the parameters, determine a run's result."""
        return dict(duration=self.duration, sample_rate=self.sample_rate, sink_depth=self.sink_depth,
                    engine=self.engine, metrics=sorted(self.metrics))

    def design(self) -> np.ndarray:
        """A sensitivity study's design in the unit cube: one row per point, one column per axis."""
        if self.sensitivity is None:
            raise ValueError(f"study {self.name!r} has no [sensitivity] table, so no design")
        return design(self.sensitivity, self.axis_names, self.seed)

    def points(self) -> list[dict[str, Any]]:
        """Axis coordinates of every point: the design's rows mapped through each axis's
        distribution, or the grid crossed with the sampled points (``wetcloth.batch.axes.points``)."""
        if self.sensitivity is None:
            return points(self.axes, self.samples, self.seed, self.sampling)
        unit = self.design()
        columns = [from_unit(axis, unit[:, j]) for j, axis in enumerate(self.axes)]
        return [dict(zip(self.axis_names, row)) for row in zip(*columns)]

    def _point_runs(self) -> list[Run]:
        """One run per point, in point order (coinciding points give the same run twice)."""
        base = self.base_params()
        settings = self.settings
        return [Run(run_key(base | point, settings), base | point, point) for point in self.points()]

    def point_keys(self) -> list[str]:
        """The run key of every point, in point order (a key repeats where points coincide)."""
        return [r.key for r in self._point_runs()]

    def base_params(self) -> dict[str, Any]:
        """Every parameter's value before the axes: defaults, then the scene file, then [base]."""
        defaults = {name: f.default for name, f in PARAMETERS.items()}
        return defaults | self.scene_values | self.base

    def runs(self) -> list[Run]:
        """Every run of the study in order; identical runs (repeated draws, coinciding design
        points) appear once."""
        return list({r.key: r for r in self._point_runs()}.values())  # in order of first occurrence


def _base(table, mistakes: Mistakes, base_dir) -> dict[str, Any]:
    """The [base] table: parameter = value, each typed (ranges are checked per run), a mesh file's path
    found from the study file's folder ``base_dir``."""
    if not isinstance(table, dict):
        raise StudyError("base", "must be a table of parameter = value")
    base = {}
    for key, value in table.items():
        with mistakes.collect():
            check_name(key, f"base.{key}")
            base[key] = _located(key, typed(key, value, f"base.{key}"), base_dir)
    return base


def _located(name: str, value, base_dir):
    """A mesh file's path in a study (``cloth_mesh``, ``collider<k>_file``) from the study file's folder
    ``base_dir`` when it is there, made absolute (every worker then finds it), as the base scene's path
    is; else as given (from the working folder)."""
    if base_dir is None or not isinstance(value, str) or not is_mesh(value):
        return value
    if not parameter_field(name).metadata.get("mesh"):
        return value
    path = _resolve_relative(value, base_dir)
    return str(path.resolve()) if path.exists() else value


def _located_axis(axis: Axis, base_dir) -> Axis:
    """``axis`` with its mesh files' paths found as ``_located`` finds them."""
    distribution = axis.distribution
    if distribution is not None and "values" in distribution:
        distribution = distribution | {"values": [_located(axis.name, v, base_dir) for v in distribution["values"]]}
    return dataclasses.replace(axis, values=tuple(_located(axis.name, v, base_dir) for v in axis.values),
                               distribution=distribution)


def _resolve_relative(ref: str, base_dir) -> Path:
    path = Path(ref)
    if not path.is_absolute() and base_dir is not None and (Path(base_dir) / path).exists():
        return Path(base_dir) / path
    return path


def _scene_file(ref, base_dir) -> tuple[Path, dict[str, Any]]:
    """The base scene's path and its contents (checked)."""
    if ref is not None and not isinstance(ref, str):
        raise StudyError("scene", f"must be a preset name or a scene TOML path, got {ref!r}")
    path = resolve_scene_path(None if ref is None else _resolve_relative(ref, base_dir))
    try:
        return path, read_scene_file(path)
    except ConfigError as exc:
        raise StudyError("scene", str(exc).replace("\n", ";")) from None


def load_study(path: str | Path) -> "Study":
    """Read and validate a study TOML file, or a preset study such as 'sink_map' (models/studies/): every
    mistake at once, naming the file."""
    path = resolve_preset_path(path, preset_dir() / "studies", "study")
    data = read_toml(path, "study file")
    return Study.from_dict(data, base_dir=path.parent, name=path.stem, source=f"study file {path}", require_axes=True)

