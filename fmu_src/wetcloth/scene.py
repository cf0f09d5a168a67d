"""The scene: every parameter of a simulation, its unit, range and meaning, validated in one place.

One vocabulary: the field names below are the names used in scene files (TOML),
in ``wetcloth run --set name=value``, in ``load_scene(path, name=value)``, as FMU
variables and as batch-study axes.  Units are SI.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from wetcloth.errors import ConfigError, Mistakes, ParameterError, did_you_mean
from wetcloth.run_settings import SETTINGS as RUN_SETTINGS
from wetcloth.run_settings import check_run_table

#: FMU causality of a scene parameter: changeable at every communication point,
#: or fixed at instantiation.
INPUT = "input"
PARAMETER = "parameter"


def _param(default, unit: str, doc: str, lo=None, hi=None, lo_open=False, choices=(), fmu=PARAMETER):
    """A scene field with its unit, documentation and allowed range in the field metadata."""
    return field(
        default=default,
        metadata=dict(unit=unit, doc=doc, lo=lo, hi=hi, lo_open=lo_open, choices=tuple(choices), fmu=fmu),
    )


INTEGRATORS = ("explicit_euler", "symplectic_euler", "implicit_euler", "bdf2")
EDGES = ("none", "x_min", "x_max", "y_min", "y_max")
SWITCH = ("on", "off")


@dataclass(frozen=True)
class Scene:
    """A cloth dropped onto water.  The defaults are the cotton towel of ``models/towel.toml``."""

    # --- cloth geometry and grid
    nx: int = _param(21, "-", "particles along the width (x)", 2, 1024)
    ny: int = _param(29, "-", "particles along the length (y)", 2, 1024)
    width: float = _param(0.5, "m", "cloth size along x", 0.0, 100.0, lo_open=True)
    length: float = _param(0.7, "m", "cloth size along y", 0.0, 100.0, lo_open=True)
    # --- fabric
    areal_density: float = _param(0.45, "kg/m2", "dry fabric mass per area", 0.0, 100.0, lo_open=True)
    thickness: float = _param(
        0.002, "m", "envelope thickness: buoyant volume = area * thickness", 0.0, 1.0, lo_open=True
    )
    stretch_stiffness: float = _param(
        2000.0, "N/m", "spring stiffness per unit strain per unit width", 0.0, 1e8, lo_open=True
    )
    bend_stiffness: float = _param(20.0, "N/m", "bending-spring stiffness per unit strain per unit width; 0 = off", 0.0, 1e8)
    damping: float = _param(0.2, "N s/m", "spring damping per unit strain rate per unit width", 0.0, 1e6)
    damping_model: str = _param(
        "projected", "-", "spring damping: 'projected' (along the spring) or 'thesis' (eq. 3.2)",
        choices=("projected", "thesis"),
    )
    # --- water
    water_level: float = _param(0.0, "m", "height of the water surface (z is up)", -1e4, 1e4, fmu=INPUT)
    water_density: float = _param(1000.0, "kg/m3", "density of the water", 0.0, 1e5, lo_open=True, fmu=INPUT)
    water_viscosity: float = _param(1.0e-3, "Pa s", "dynamic viscosity of the water (Stokes drag)", 0.0, 1e3)
    drag_model: str = _param("face", "-", "'face' (per-triangle, default) or 'stokes' (thesis eq. 3.5)", choices=("face", "stokes"))
    drag_normal: float = _param(1.2, "-", "face-drag coefficient across the cloth, C_n", 0.0, 100.0)
    drag_tangential: float = _param(0.03, "-", "face-drag coefficient along the cloth, C_t", 0.0, 100.0)
    drag_linear: float = _param(2.0, "N s/m3", "face-drag linear term c_lin per area", 0.0, 1e6)
    buoyancy_model: str = _param(
        "smooth", "-", "'smooth' (slab fraction, default) or 'thesis' (all or nothing)", choices=("smooth", "thesis")
    )
    # --- absorption (Buras law)
    absorption_capacity: float = _param(
        3.8, "kg/kg", "equilibrium water uptake per kg of dry fabric (Buras Q)", 0.0, 100.0, fmu=INPUT
    )
    absorption_rate: float = _param(
        0.15, "1/s", "initial uptake rate, kg water per kg dry fabric per s (Buras I)", 0.0, 1e4, fmu=INPUT
    )
    # --- beyond the thesis (docs/model.md section 5): each off at 0 and then skipped
    wicking_rate: float = _param(
        0.0, "m2/s", "diffusion constant of water through the fabric, driven by saturation; 0 = off", 0.0, 1.0
    )
    drying_rate: float = _param(0.0, "1/s", "fraction of its water a particle in air loses per second; 0 = off", 0.0, 100.0)
    wet_stiffness_factor: float = _param(
        0.0, "-", "stiffness scales by 1 + factor * saturation (negative softens); 0 = off", -0.9, 10.0
    )
    current_x: float = _param(0.0, "m/s", "water velocity along x, which the drag acts relative to", -10.0, 10.0, fmu=INPUT)
    current_y: float = _param(0.0, "m/s", "water velocity along y, which the drag acts relative to", -10.0, 10.0, fmu=INPUT)
    # --- air (docs/model.md section 4.4): face drag on the part of the cloth out of the water; on by default
    air_density: float = _param(
        1.2, "kg/m3", "density of the air above the water (face drag in air); 0 = off", 0.0, 1000.0
    )
    wind_x: float = _param(0.0, "m/s", "air velocity along x, which the drag in air acts relative to", -100.0, 100.0, fmu=INPUT)
    wind_y: float = _param(0.0, "m/s", "air velocity along y, which the drag in air acts relative to", -100.0, 100.0, fmu=INPUT)
    wind_z: float = _param(0.0, "m/s", "air velocity along z (up), which the drag in air acts relative to", -100.0, 100.0,
                           fmu=INPUT)
    initial_saturation: float = _param(0.0, "-", "absorbed water at t = 0, as a fraction of the capacity", 0.0, 1.0)
    # --- initial state and surroundings
    initial_height: float = _param(0.1, "m", "z of the cloth's centre at t = 0 (cloth at rest)", -1e4, 1e4)
    initial_tilt: float = _param(10.0, "deg", "rotation about the x axis at t = 0; 90 is vertical", -90.0, 90.0)
    floor_level: float = _param(-1.0, "m", "z of the tank floor", -1e4, 1e4)
    floor_friction: float = _param(0.5, "-", "Coulomb friction coefficient of the floor", 0.0, 10.0)
    # --- self-collision (docs/model.md section 6.2)
    self_collision: str = _param(
        "on", "-", "'on': the cloth never passes through itself and keeps its layers a thickness apart; "
        "'off' skips it (a cloth that cannot fold saves its small cost)", choices=SWITCH)
    self_friction: float = _param(0.4, "-", "Coulomb friction coefficient between layers of the cloth", 0.0, 10.0)
    pinned_edge: str = _param("none", "-", "edge held fixed in space: none, x_min, x_max, y_min, y_max", choices=EDGES)
    # --- time integration
    integrator: str = _param(
        "bdf2", "-", "time integrator: 'bdf2' (second order, implicit, steps set by the tolerance), "
        "'implicit_euler' (first order; with tolerance 0 and max_step one frame, frame-long steps that never "
        "fail), 'symplectic_euler', or 'explicit_euler' (the thesis scheme)", choices=INTEGRATORS)
    tolerance: float = _param(
        5e-6, "-", "local position error per step relative to the cloth size; 0 = fixed steps", 0.0, 1.0
    )
    max_step: float = _param(0.1, "s", "largest internal time step", 0.0, 1.0, lo_open=True)

    def __post_init__(self):
        validate(self)

    def replace(self, **overrides) -> "Scene":
        """A copy with some parameters changed (validated)."""
        return from_dict(dataclasses.asdict(self) | overrides)

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


PARAMETERS: dict[str, dataclasses.Field] = {f.name: f for f in dataclasses.fields(Scene)}
PARAMETER_LISTING = f"there are {len(PARAMETERS)}; 'wetcloth params' lists them"


def describe_range(f: dataclasses.Field) -> str:
    """The allowed values of a field, as a user reads them: '0 < thickness <= 1 m'."""
    md = f.metadata
    if md["choices"]:
        return "one of " + ", ".join(repr(c) for c in md["choices"])
    unit = "" if md["unit"] == "-" else f" {md['unit']}"
    lo_sign = "<" if md["lo_open"] else "<="
    return f"{md['lo']:g} {lo_sign} {f.name} <= {md['hi']:g}{unit}"


def _field(name: str) -> dataclasses.Field:
    if name not in PARAMETERS:
        raise ParameterError(name, did_you_mean(name, PARAMETERS, listing=PARAMETER_LISTING))
    return PARAMETERS[name]


def normalise(name: str, value):
    """``value`` in the type of parameter ``name``, by the one rule of every source (scene files,
    ``--set``, Python, studies, the FMU): a string parameter takes a string; a number parameter a
    number (never text or a boolean), a whole-number one also a float that is whole (3.0 -> 3)."""
    f = _field(name)
    if f.type == "str":
        if not isinstance(value, str):
            raise ParameterError(name, f"expected a string, got {value!r}; allowed: {describe_range(f)}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        hint = " (text: write the number without quotes)" if isinstance(value, str) else ""
        raise ParameterError(name, f"expected a number, got {value!r}{hint}; allowed: {describe_range(f)}")
    if f.type == "int":
        if isinstance(value, float) and not value.is_integer():
            raise ParameterError(name, f"expected a whole number, got {value!r}; allowed: {describe_range(f)}")
        return int(value)
    return float(value)


def check_value(name: str, value):
    """One parameter's value, normalised and checked against its range alone (no cross-parameter checks)."""
    value = normalise(name, value)
    f = PARAMETERS[name]
    md = f.metadata
    if f.type == "str":
        if value not in md["choices"]:
            close = difflib.get_close_matches(value, md["choices"], n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ParameterError(name, f"{value!r} is not allowed{hint}; allowed: {describe_range(f)}")
        return value
    if not math.isfinite(value):
        raise ParameterError(name, f"{value!r} is not a finite number; allowed: {describe_range(f)}")
    below = value <= md["lo"] if md["lo_open"] else value < md["lo"]
    if below or value > md["hi"]:
        raise ParameterError(name, f"{value!r} is out of range; allowed: {describe_range(f)}")
    return value


def parse_text(name: str, text: str):
    """A parameter's value from text (``--set name=text``): the number it spells for a number
    parameter (then the same rule as a TOML value: ``nx=3.0`` is 3), the text for a string one."""
    f = _field(name)
    if f.type == "str":
        return text
    for kind in (int, float):
        try:
            return normalise(name, kind(text.strip()))
        except ValueError:
            continue
    raise ParameterError(name, f"expected a number, got {text!r}; allowed: {describe_range(f)}")


def validate(scene: Scene) -> None:
    """Check every parameter against its range and the scene as a whole, normalising the values
    (3.0 -> 3 for nx, 1 -> 1.0 for width); raise ParameterError with every mistake found."""
    mistakes = Mistakes()
    for name in PARAMETERS:
        with mistakes.collect():
            object.__setattr__(scene, name, check_value(name, getattr(scene, name)))
    mistakes.raise_if_any()
    half_drop = 0.5 * scene.length * abs(math.sin(math.radians(scene.initial_tilt)))
    lowest = scene.initial_height - half_drop - 0.5 * scene.thickness
    if lowest <= scene.floor_level:
        raise ParameterError(
            "initial_height",
            f"the cloth starts at or below the floor (lowest point {lowest:g} m, floor_level "
            f"{scene.floor_level:g} m); allowed: initial_height > floor_level + {half_drop + 0.5 * scene.thickness:g} m",
        )


def from_dict(values: dict[str, Any]) -> Scene:
    """A validated Scene from a mapping of parameter names to values (every mistake at once)."""
    mistakes = Mistakes()
    for name in values:
        with mistakes.collect():
            _field(name)
    mistakes.raise_if_any()
    return Scene(**values)


#: Keys of a scene file that are not scene parameters: a description and the ``[run]`` table.
RESERVED_KEYS = ("description", "run")


def preset_dir() -> Path:
    """Folder of the scene presets shipped with wetcloth (the repository's ``models/``)."""
    return Path(str(resources.files("wetcloth.presets")))


def resolve_scene_path(path: str | Path | None) -> Path:
    """A scene file from a path, or a preset name such as 'thesis_fast'; None is the default towel."""
    if path is None:
        return preset_dir() / "towel.toml"
    candidate = Path(path)
    if candidate.exists():
        return candidate
    preset = preset_dir() / (candidate.name if candidate.suffix == ".toml" else candidate.name + ".toml")
    if preset.exists():
        return preset
    names = ", ".join(sorted(p.stem for p in preset_dir().glob("*.toml")))
    raise FileNotFoundError(f"scene file {str(path)!r} not found (presets: {names})")


def read_toml(path: Path, what: str = "scene file") -> dict[str, Any]:
    """A TOML file's contents; a ConfigError naming the file (``what``: 'scene file', 'study file')
    if it cannot be read or parsed."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        message = f"not valid TOML: {exc}"
    except UnicodeDecodeError as exc:
        message = f"not a text (TOML) file: byte {exc.object[exc.start]:#04x} at position {exc.start} is not UTF-8"
    except OSError as exc:
        message = f"cannot be read: {exc.strerror or exc}"
    raise ConfigError(str(path), message, label=what)


def read_scene_file(path: str | Path | None) -> dict[str, Any]:
    """A scene file's contents, checked whole: parameters (normalised), ``description`` and the
    ``[run]`` table (see ``wetcloth.run_settings``).  A ConfigError names the file and every mistake."""
    resolved = resolve_scene_path(path)
    data = read_toml(resolved)
    mistakes = Mistakes(f"scene file {resolved}")
    for key, value in list(data.items()):
        with mistakes.collect():
            if key == "run":
                data[key] = check_run_table(value)
            elif key == "description":
                if not isinstance(value, str):
                    raise ParameterError(key, f"must be text, got {value!r}")
            elif key in RUN_SETTINGS:
                raise ParameterError(key, f"is a run setting: put it in the [run] table ({key} = {value!r} under [run])")
            else:
                data[key] = check_value(key, value)
    mistakes.raise_if_any()
    return data


def load_scene(path: str | Path | None = None, **overrides) -> Scene:
    """Load a scene from TOML (default: the towel preset), with parameter overrides."""
    data = read_scene_file(path)
    values = {k: v for k, v in data.items() if k not in RESERVED_KEYS}
    return from_dict(values | overrides)
