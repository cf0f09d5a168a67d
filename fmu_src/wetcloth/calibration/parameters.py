"""The parameters a fit varies: scene number parameters, each with bounds within its allowed range.

Besides the scene's own parameters, the number fields of its ``[[collider]]``, ``[[grip_key]]`` and
``[[collider_key]]`` tables, by their flattened names (``collider1_z``, ``grip_key2_z``), as ``--set``
takes them."""

from __future__ import annotations

import math
from dataclasses import dataclass

from wetcloth.errors import ConfigError, Mistakes, ParameterError
from wetcloth.scene import (Scene, collider_key_name, collider_name, describe_range, grip_key_name, is_parameter,
                            parameter_field)

#: Number parameters that set how the equations are solved, not the cloth or the water: a fit does
#: not vary them (the fit's own choice of ``tolerance`` is in ``problem.fit_tolerance``).
NUMERICAL = ("tolerance", "max_step")


class BoundsError(ConfigError):
    """A ``--bounds`` entry is malformed, outside its parameter's range or for a parameter not fitted."""

    label = "--bounds"


@dataclass(frozen=True)
class FitParameter:
    """One fitted parameter: its ``start`` value, the bounds ``lo`` .. ``hi`` the fit keeps it in
    (``given``: from ``--bounds``, else the allowed range), and ``scale``, the size the fit measures
    it in (its start value's magnitude; if it starts at 0, the width of its --bounds, else one unit:
    1 m, 1 deg ..., or its allowed range's width if narrower)."""

    name: str
    start: float
    lo: float
    hi: float
    given: bool

    @property
    def unit(self) -> str:
        return parameter_field(self.name).metadata["unit"]

    @property
    def scale(self) -> float:
        """The size (its unit) the fit measures the parameter in; its Jacobian's step is 1e-4 of it at 0.
        An allowed range is no size to go by: +-1e4 m for a collider's x made steps of 2 m."""
        if self.start != 0.0:
            return abs(self.start)
        width = self.hi - self.lo if self.given else min(self.hi - self.lo, 1.0)
        return width if math.isfinite(width) and width > 0 else 1.0

    @property
    def finite(self) -> bool:
        """Whether both bounds are finite numbers a search can sample between."""
        return math.isfinite(self.lo) and math.isfinite(self.hi)


def check_name(name: str, scene: Scene) -> str:
    """``name`` if it is a number parameter of ``scene`` a fit may vary; else a ParameterError naming it
    and what it takes."""
    f = parameter_field(name)  # unknown: 'did you mean ...?'
    if f.type == "str":
        kind = "a choice" if f.metadata["choices"] else "text"
        raise ParameterError(name, f"takes {kind} ({describe_range(f, name)}), not a number a fit can vary; "
                                   f"choose it in the scene or with --set {name}=...")
    if f.type == "int":
        raise ParameterError(name, f"is a whole number ({describe_range(f, name)}); a fit varies continuous number "
                                   f"parameters: set it in the scene or with --set {name}=...")
    if name in NUMERICAL:
        raise ParameterError(name, f"sets how the equations are solved ({describe_range(f, name)}), not the cloth or "
                                   f"the water: a fit does not vary it (set it with --set {name}=...)")
    if name not in scene.to_dict():
        raise ParameterError(name, _missing_table(name, scene))
    return name


#: The scene's arrays of tables whose fields a fit may vary: (table, how a flattened name is parsed, the
#: scene's attribute holding them).
TABLES = (("collider", collider_name, "colliders"), ("grip_key", grip_key_name, "grip_keys"),
          ("collider_key", collider_key_name, "collider_keys"))


def _missing_table(name: str, scene: Scene) -> str:
    """Why the flattened table field ``name`` (collider3_z) is not in ``scene``: how many such tables it has."""
    table, (k, field), attribute = next((t, parse(name), a) for t, parse, a in TABLES if parse(name) is not None)
    count = len(getattr(scene, attribute))
    if count == 0:
        return (f"the scene has no [[{table}]] tables, so no {table}{k}; a fit varies the scene's number "
                f"parameters ('wetcloth params') and the number fields of its [[collider]], [[grip_key]] and "
                f"[[collider_key]] tables")
    return (f"the scene has {count} [[{table}]] table{'s' if count > 1 else ''}, so no {table}{k}; allowed: "
            f"{table}1_{field}" + (f" .. {table}{count}_{field}" if count > 1 else ""))


def parse_bounds(text: str) -> tuple[str, float, float]:
    """'NAME=LO:HI' -> (name, lo, hi); a BoundsError saying what is wrong."""
    name, sep, rest = text.partition("=")
    name = name.strip()
    lo_text, colon, hi_text = rest.partition(":")
    if not sep or not name or not colon:
        raise BoundsError(name or text, f"expected NAME=LO:HI (e.g. absorption_rate=0.05:2), got {text!r}")
    try:
        lo, hi = float(lo_text), float(hi_text)
    except ValueError:
        raise BoundsError(name, f"LO and HI must be numbers, got {text!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise BoundsError(name, f"LO and HI must be finite numbers, got {text!r}")
    if not lo < hi:
        raise BoundsError(name, f"LO must be below HI, got {lo:g}:{hi:g}")
    return name, lo, hi


def fit_parameters(scene: Scene, names: list[str], bounds: dict[str, tuple[float, float]] | None = None,
                   need_start_inside: bool = True) -> list[FitParameter]:
    """The fitted parameters ``names`` of ``scene`` with ``bounds`` (name -> (lo, hi)), checked whole:
    every mistake at once (ParameterError, BoundsError or a ConfigError holding both).

    Bounds must lie within the parameter's allowed range (an open end excluded).  The start, the
    scene's value, must lie within the bounds unless ``need_start_inside`` is False (a global
    search, which starts from its own samples)."""
    bounds = dict(bounds or {})
    mistakes = Mistakes()
    if not names:
        raise ParameterError("--params", "give at least one parameter to fit, e.g. --params absorption_rate")
    seen = set()
    for name in names:
        with mistakes.collect():
            if name in seen:
                raise ParameterError(name, "named twice in --params")
            seen.add(name)
            check_name(name, scene)
    mistakes.raise_if_any()
    for name in bounds:
        if name not in names:
            with mistakes.collect():
                message = "not a fitted parameter" if is_parameter(name) else "unknown parameter"
                raise BoundsError(name, f"{message}; the fitted ones are {', '.join(names)} (--params)")
    out = []
    values = scene.to_dict()
    for name in names:
        f = parameter_field(name)
        md = f.metadata
        start = float(values[name])
        if name in bounds:
            lo, hi = bounds[name]
            with mistakes.collect():
                below = lo <= md["lo"] if md["lo_open"] else lo < md["lo"]
                if below or hi > md["hi"]:
                    raise BoundsError(name, f"{lo:g}:{hi:g} is outside the allowed range: {describe_range(f, name)}")
                if need_start_inside and not lo <= start <= hi:
                    raise BoundsError(name, f"{lo:g}:{hi:g} does not hold the start value {start:g} (the scene's): "
                                            f"widen the bounds, or start inside them with --set {name}=VALUE "
                                            f"(or search them with --global)")
            out.append(FitParameter(name, start, lo, hi, True))
        else:
            lo = md["lo"]
            if md["lo_open"]:  # the fit may come close to an open end, never onto it
                lo = math.nextafter(lo, math.inf) if lo == 0.0 else lo + 1e-12 * max(abs(lo), 1.0)
            out.append(FitParameter(name, start, lo, float(md["hi"]), False))
    mistakes.raise_if_any()
    return out
