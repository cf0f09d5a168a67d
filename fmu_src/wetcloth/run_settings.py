"""Run settings (a scene file's ``[run]`` table): how long to simulate and how often to record.

One rule for every front end (``wetcloth run``, batch studies, the FMU's default experiment):
a value given explicitly (command line, study file, API argument) wins, else the scene file's
``[run]`` table, else ``DEFAULTS``.  Each setting has a range; ``frames`` bounds the work one run
may ask for (``duration * fps`` frames are recorded and kept in memory).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any, Mapping

from wetcloth.errors import ConfigError, Mistakes, did_you_mean, not_a_number


class RunSettingError(ConfigError):
    """A ``[run]`` setting is unknown, of the wrong type or out of range."""

    label = "[run]"


@dataclass(frozen=True)
class Setting:
    name: str
    default: float
    unit: str
    lo: float  # exclusive
    hi: float  # inclusive
    doc: str


#: The ``[run]`` settings: name -> (default, unit, range, meaning).
SETTINGS: dict[str, Setting] = {s.name: s for s in (
    Setting("duration", 10.0, "s", 0.0, 1e6, "simulated time of a run"),
    Setting("fps", 30.0, "1/s", 0.0, 1e4, "frames per second: outputs (CSV rows, batch samples) and exported meshes"),
)}
DEFAULTS = {name: s.default for name, s in SETTINGS.items()}
#: Most frames one run may record (duration * fps + 1): each is a row in memory (about 0.6 kB)
#: and, when exporting, a mesh file.  Almost two hours at 30 fps.
MAX_FRAMES = 200_000


def describe(setting: Setting) -> str:
    """'0 < duration <= 1e+06 s'."""
    return f"{setting.lo:g} < {setting.name} <= {setting.hi:g} {setting.unit}"


def check_setting(name: str, value) -> float:
    """The value of run setting ``name`` as a float, or RunSettingError naming it and its range."""
    if name not in SETTINGS:
        raise RunSettingError(name, did_you_mean(name, SETTINGS, "run setting"))
    s = SETTINGS[name]
    if isinstance(value, bool) or not isinstance(value, numbers.Real):  # Real: NumPy's scalars too
        raise RunSettingError(name, f"{not_a_number(value)}; allowed: {describe(s)}")
    if not (math.isfinite(value) and s.lo < value <= s.hi):
        raise RunSettingError(name, f"{value!r} is out of range; allowed: {describe(s)}")
    return float(value)


def check_run_table(table) -> dict[str, float]:
    """A scene file's ``[run]`` table checked whole (every mistake at once): name -> value."""
    if not isinstance(table, Mapping):
        raise ConfigError("run", f"must be the table [run] ({', '.join(SETTINGS)}): '[run]' on a line of its "
                                 f"own, then one setting per line; got {table!r}")
    mistakes, values = Mistakes(), {}
    for name, value in table.items():
        with mistakes.collect():
            values[name] = check_setting(name, value)
    mistakes.raise_if_any()
    return values


def whole_frames(duration: float, fps: float) -> int:
    """How many frames at 0, 1/fps, ... lie within ``duration`` (s): the frames an export writes."""
    return int(math.floor(duration * fps + 1e-9)) + 1


def check_frames(duration: float, fps: float, fps_name: str = "fps") -> None:
    """Refuse a run that would record more than ``MAX_FRAMES`` frames, naming the bound."""
    frames = whole_frames(duration, fps)
    if frames > MAX_FRAMES:
        raise RunSettingError(fps_name, f"{duration:g} s at {fps:g} frames/s is {frames:.3g} frames; at most "
                                        f"{MAX_FRAMES} per run: lower {fps_name} or duration")


@dataclass(frozen=True)
class RunSettings:
    """How long to simulate (s) and how many frames per second to record (1/s)."""

    duration: float = DEFAULTS["duration"]
    fps: float = DEFAULTS["fps"]


def resolve(run_table: Mapping[str, Any] | None = None, **given) -> RunSettings:
    """The run settings: each value in ``given`` that is not None, else ``run_table``'s, else the default.

    ``run_table``: a scene file's ``[run]`` table (checked here too); ``given``: duration=, fps=.
    Raises a ConfigError with every mistake, and refuses more than ``MAX_FRAMES`` frames."""
    mistakes = Mistakes()
    table: dict[str, float] = {}
    with mistakes.collect():
        table = check_run_table(run_table or {})
    values = dict(DEFAULTS) | table
    for name, value in given.items():
        if value is not None:
            with mistakes.collect():
                values[name] = check_setting(name, value)
    mistakes.raise_if_any()
    check_frames(values["duration"], values["fps"])
    return RunSettings(**values)
