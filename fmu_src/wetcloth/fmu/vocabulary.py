"""The FMU's variables, generated from the ``Scene`` fields: one vocabulary for scene files, FMI 2.0 and 3.0.

Every ``Scene`` field becomes an FMU variable of the same name: ints are FMI Integer, strings
String, floats Real; fields whose metadata says ``fmu="input"`` are continuous Real inputs, the
others fixed parameters.  Unit, description, start value and range come from the field metadata,
so parameters added to the Scene later appear in the FMU without touching this package.
Two FMU-only parameters (``mesh_output_dir``, ``mesh_format``) and the six outputs of
``wetcloth.simulation.OUTPUTS`` with ``step_error`` (``STEP_OUTPUTS``) complete the interface; the FMI 3.0 unit adds the mesh of every
step as array outputs (``MESH_OUTPUTS``), dimensioned by the grid parameters ``ny`` and ``nx``, and a cloth from a
mesh file's faces and UVs as constant array outputs (``MESH_CONSTANTS``).  A unit built
with a scene's colliders (``build-fmu --scene``) has, last, each collider's number fields as fixed Real
parameters under their flattened names (``collider1_radius``: ``COLLIDER_VARIABLES``).
"""

from __future__ import annotations

import dataclasses
import math
import re
import sys
from dataclasses import dataclass
from typing import Any, Iterable

from wetcloth.errors import ParameterError
from wetcloth.fmu import MODEL_NAME
from wetcloth.scene import COLLIDER_FIELDS, INPUT, PARAMETERS, check_value, describe_range
from wetcloth.simulation import OUTPUTS

#: Mesh formats the unit can write at every communication point, and how messages name them.
MESH_FORMATS = ("ply", "obj")
MESH_FORMAT_RANGE = "one of " + ", ".join(repr(f) for f in MESH_FORMATS)

#: The FMI 3.0 unit's array outputs: the cloth mesh of the current step, in the vertex order of the
#: exported frames (vertex ``row * nx + col``; a cloth from a mesh file: the file's order, and its vertex
#: count for ny, nx): name -> (unit, meaning, dimensions; a name is the grid parameter holding that size).  ``Simulation`` has a property of each name.
MESH_OUTPUTS = {
    "positions": ("m", "vertex positions x, y, z; vertex row * nx + col (z is up)", ("ny", "nx", 3)),
    "wetness": ("-", "saturation of each vertex, absorbed water over capacity (0 to 1)", ("ny", "nx")),
}

#: The FMI 3.0 unit's constant array outputs of a cloth from a mesh file (built with --scene), as its exported
#: frames have them (``packed_scene.PackedScene``): name -> (FMI type, unit, meaning); sized by the mesh.
MESH_CONSTANTS = {
    "faces": ("UInt64", "-", "the mesh file's faces: each face's vertex indices (from 0, the file's vertex order), "
                             "as in the file (one that mixes triangles and quads: the triangles of their split)"),
    "uv": ("Real", "-", "texture coordinates (u, v) of each vertex: the mesh file's, else those of the flat rest "
                        "sheet (0 to 1)"),
}

#: Outputs beyond ``Simulation.outputs()``: name -> (unit, meaning).  ``step_error`` is
#: ``Simulation.error_estimate`` after the communication step.
STEP_OUTPUTS = {
    "step_error": ("m", "the largest local position error a step of the last communication step estimated for "
                        "itself: what the step size costs (0 before the first step)"),
}


@dataclass(frozen=True)
class VariableSpec:
    """One FMU variable: FMI type ('Real', 'Integer', 'String'; FMI 3.0 also 'UInt64'), causality, variability
    ('constant': an array output whose values, ``start``, are in the model description), start and range."""

    name: str
    type: str
    causality: str  # "input", "parameter", "output" or (FMI 3.0's time) "independent"
    variability: str  # "continuous" or "fixed"
    description: str
    unit: str = "-"  # the Scene's unit text; "-" is dimensionless (no FMI unit)
    start: Any = None  # None for outputs (initial="calculated")
    min: float | int | None = None
    max: float | int | None = None
    scene: bool = True  # a Scene field (else an FMU-only parameter or an output)
    dimensions: tuple[str | int, ...] = ()  # array outputs: sizes, or names of the parameters holding them
    min_open: bool = False  # the value must be above ``min`` (FMI's min is inclusive: see ``declared_min``)
    nominal: float | None = None  # Reals: the magnitude of a typical value (FMI ``nominal``, > 0)
    collider: int = 0  # a collider's field (``collider<k>_<field>``): its collider k (1, 2, ...); else 0

    @property
    def declared_min(self) -> float | int | None:
        """``min`` as the model description declares it: for a value that must be above ``min``, the
        least double above it (the least normal one above 0), since FMI's ``min`` is inclusive."""
        if self.min is None or not self.min_open:
            return self.min
        return sys.float_info.min if self.min == 0 else math.nextafter(float(self.min), math.inf)

    @property
    def values(self) -> list:
        """A constant array output's values in order (``start`` holds its rows)."""
        return [value for row in self.start for value in row]

    @property
    def initial(self) -> str | None:
        if self.variability == "constant":
            return "exact"
        return {"parameter": "exact", "output": "calculated"}.get(self.causality)


def _fmi_type(f: dataclasses.Field) -> str:
    kind = f.type if isinstance(f.type, str) else f.type.__name__
    try:
        return {"float": "Real", "int": "Integer", "str": "String"}[kind]
    except KeyError:
        raise TypeError(f"Scene field {f.name!r} has type {kind!r}; the FMU maps only float, int and str") from None


def scene_spec(f: dataclasses.Field) -> VariableSpec:
    """The FMU variable of one Scene field, from its metadata."""
    md = f.metadata
    fmi_type = _fmi_type(f)
    is_input = md["fmu"] == INPUT
    if is_input and fmi_type != "Real":
        raise TypeError(f"Scene field {f.name!r} is an FMU input but not a float; FMU inputs are continuous Reals")
    numeric = fmi_type != "String"
    return VariableSpec(
        name=f.name,
        type=fmi_type,
        causality="input" if is_input else "parameter",
        variability="continuous" if is_input else "fixed",
        description=f"{md['doc']} (allowed: {describe_range(f)})",
        unit=md["unit"],
        start=f.default,
        min=md["lo"] if numeric else None,
        max=md["hi"] if numeric else None,
        min_open=bool(md["lo_open"]) and numeric,
        nominal=(abs(float(f.default)) or 1.0) if fmi_type == "Real" else None,
    )


#: The collider fields that are FMU parameters (Reals): every number field; the shape and a mesh collider's
#: file stay as the unit was built.
COLLIDER_VARIABLES = tuple(name for name, f in COLLIDER_FIELDS.items() if f.type == "float")


def collider_specs(colliders: Iterable[dict]) -> list[VariableSpec]:
    """The parameters of the colliders built into a unit (``PackedScene.colliders``: their fields), collider
    after collider: each of ``COLLIDER_VARIABLES`` as ``collider<k>_<field>``, its start value the collider's."""
    specs = []
    for k, fields in enumerate(colliders, 1):
        for name in COLLIDER_VARIABLES:
            f, flat = COLLIDER_FIELDS[name], f"collider{k}_{name}"
            md, start = f.metadata, float(fields[name])
            specs.append(VariableSpec(
                name=flat, type="Real", causality="parameter", variability="fixed",
                description=f"collider {k} ({fields['shape']}): {md['doc']} (allowed: {describe_range(f, flat)})",
                unit=md["unit"], start=start, min=md["lo"], max=md["hi"], min_open=bool(md["lo_open"]),
                nominal=abs(start) or 1.0, collider=k))
    return specs


#: Inputs whose change shows in an output at once, without a step (direct feedthrough).
FEEDTHROUGH = {"depth": ("water_level",)}

#: The FMU-only parameters: name -> (start, meaning).
FMU_PARAMETERS = {
    "mesh_output_dir": ("", "folder for one mesh frame per communication point, written only by this unit "
                            "(a folder holding other files is refused); empty = no meshes"),
    "mesh_format": ("ply", f"mesh format of the frames (allowed: {MESH_FORMAT_RANGE})"),
}


def variable_specs(fields: Iterable[dataclasses.Field] | None = None, fmi_version: int = 2,
                   packed=None) -> list[VariableSpec]:
    """All FMU variables in value-reference order: Scene fields, mesh parameters, outputs (and, for
    FMI 3.0, the mesh array outputs, the time and a mesh cloth's faces and UVs), then the colliders'
    parameters.  ``packed``: the scene
    built into the unit (``packed_scene.PackedScene``), whose values are the start values; a mesh cloth's
    arrays have its vertex count as their first dimension instead of the grid's ny, nx; its colliders'
    number fields are parameters (``collider_specs``), last, so that the other variables keep their value
    references."""
    fields = PARAMETERS.values() if fields is None else fields
    specs = [scene_spec(f) for f in fields]
    if packed is not None:
        specs = [dataclasses.replace(s, start=packed.starts[s.name]) if s.name in packed.starts else s for s in specs]
    specs += [VariableSpec(name, "String", "parameter", "fixed", doc, start=start, scene=False)
              for name, (start, doc) in FMU_PARAMETERS.items()]
    nominal = output_nominals()
    specs += [VariableSpec(n, "Real", "output", "continuous", doc, unit=u, scene=False, nominal=nominal[n])
              for n, (u, doc) in {**OUTPUTS, **STEP_OUTPUTS}.items()]
    if fmi_version == 3:
        vertices = None if packed is None else packed.vertices
        specs += [VariableSpec(n, "Real", "output", "continuous", doc, unit=u, scene=False, nominal=nominal[n],
                               dimensions=dims if vertices is None else (vertices, *dims[2:]))
                  for n, (u, doc, dims) in MESH_OUTPUTS.items()]
        specs.append(VariableSpec("time", "Real", "independent", "continuous", "simulation time (the FMI 3.0 "
                                  "independent variable)", unit="s", scene=False, nominal=1.0))
        if packed is not None and packed.faces:
            for name, (kind, unit, doc) in MESH_CONSTANTS.items():
                values = [list(row) for row in getattr(packed, name)]
                specs.append(VariableSpec(name, kind, "output", "constant", doc, unit=unit, start=values, scene=False,
                                          dimensions=(len(values), len(values[0])),
                                          nominal=1.0 if kind == "Real" else None))
    if packed is not None:
        specs += collider_specs(packed.colliders)
    return specs


def output_nominals() -> dict[str, float]:
    """The outputs' typical magnitudes, from the default scene: lengths its cloth's size (m), masses
    its dry mass (kg), wetness 1, the step error its tolerance times its size (m)."""
    defaults = {name: f.default for name, f in PARAMETERS.items()}
    size = max(defaults["width"], defaults["length"])
    mass = defaults["areal_density"] * defaults["width"] * defaults["length"]
    lengths = ("centroid_x", "centroid_y", "centroid_z", "depth", "positions")
    return {**{name: size for name in lengths}, "wet_mass": mass, "water_mass": mass, "wetness": 1.0,
            "step_error": defaults["tolerance"] * size}


def check_variable(name: str, value) -> None:
    """Check one parameter or input value on its own (type and range); ParameterError naming the range."""
    if name == "mesh_format":
        if value not in MESH_FORMATS:
            raise ParameterError(name, f"{value!r} is not allowed; allowed: {MESH_FORMAT_RANGE}")
    elif name == "mesh_output_dir":
        if not isinstance(value, str):
            raise ParameterError(name, f"expected a folder path, got {value!r}")
    else:
        check_value(name, value)


# ----------------------------------------------------------------------------------- units
#: SI base-unit exponents (and factor to SI) of the unit symbols scene metadata may use.
_SYMBOLS: dict[str, tuple[dict[str, int], float]] = {
    "m": ({"m": 1}, 1.0),
    "kg": ({"kg": 1}, 1.0),
    "g": ({"kg": 1}, 1e-3),
    "s": ({"s": 1}, 1.0),
    "K": ({"K": 1}, 1.0),
    "mol": ({"mol": 1}, 1.0),
    "A": ({"A": 1}, 1.0),
    "N": ({"kg": 1, "m": 1, "s": -2}, 1.0),
    "Pa": ({"kg": 1, "m": -1, "s": -2}, 1.0),
    "J": ({"kg": 1, "m": 2, "s": -2}, 1.0),
    "W": ({"kg": 1, "m": 2, "s": -3}, 1.0),
    "rad": ({"rad": 1}, 1.0),
    "deg": ({"rad": 1}, math.pi / 180.0),
}
_FACTOR = re.compile(r"^([A-Za-z]+)(-?\d+)?$")


@dataclass(frozen=True)
class Unit:
    """An FMI unit: its name (Modelica syntax) and SI base-unit exponents and factor."""

    name: str
    exponents: tuple[tuple[str, int], ...]
    factor: float = 1.0


def _number_text(value) -> str:
    """A number as model-description text (a range bound, a start value): an int as is, a float exactly (repr)."""
    return str(int(value)) if isinstance(value, int) else repr(float(value))


def xml_attributes(spec: VariableSpec) -> dict[str, str]:
    """A variable's ``unit`` and ``nominal`` (Reals), ``min`` and ``max`` as model-description attributes
    (FMI 2.0 and 3.0)."""
    attributes = {}
    unit = fmi_unit_name(spec.unit)
    if spec.type == "Real" and unit is not None:
        attributes["unit"] = unit
    if spec.min is not None:
        attributes["min"] = _number_text(spec.declared_min)
    if spec.max is not None:
        attributes["max"] = _number_text(spec.max)
    if spec.type == "Real" and spec.nominal is not None:
        attributes["nominal"] = _number_text(float(spec.nominal))
    if spec.variability == "constant":  # whole (pythonfmu3 cuts a start of over 1000 characters to one)
        attributes["start"] = " ".join(_number_text(v) for v in spec.values)
    return attributes


class WithAttributes:
    """Mixin for pythonfmu and pythonfmu3 variables: extra XML attributes (unit, min, max) that the
    libraries do not write.  ``attribute_element`` picks the element that carries them."""

    def __init__(self, name: str, attributes: dict[str, str], **kwargs):
        super().__init__(name, **kwargs)
        self.attributes = attributes

    @staticmethod
    def attribute_element(node):
        """FMI 3.0: the variable's own element."""
        return node

    def to_xml(self):
        node = super().to_xml()
        element = self.attribute_element(node)
        for key, value in self.attributes.items():
            element.set(key, value)
        return node


def fmi_unit_name(unit: str) -> str | None:
    """The FMI/Modelica name of a scene unit ('N s/m' -> 'N.s/m'); None for dimensionless '-'."""
    if unit in ("-", ""):
        return None
    return ".".join(unit.split())


def parse_unit(unit: str) -> Unit:
    """Base-unit exponents of a scene unit such as 'kg/m3', 'N s/m', '1/s' or 'deg'."""
    numerator, _, denominator = unit.partition("/")
    exponents: dict[str, int] = {}
    factor = 1.0
    for sign, part in ((1, numerator), (-1, denominator)):
        for token in part.replace(".", " ").split():
            if token == "1":
                continue
            match = _FACTOR.match(token)
            if not match or match.group(1) not in _SYMBOLS:
                raise ValueError(f"unit {unit!r}: unknown symbol {token!r}; known: {', '.join(_SYMBOLS)}")
            power = sign * int(match.group(2) or 1)
            base, scale = _SYMBOLS[match.group(1)]
            for key, exp in base.items():
                exponents[key] = exponents.get(key, 0) + exp * power
            factor *= scale**power
    return Unit(fmi_unit_name(unit), tuple((k, v) for k, v in exponents.items() if v), factor)


def units_of(specs: Iterable[VariableSpec]) -> list[Unit]:
    """The distinct FMI units the variables use, in order of first use."""
    seen: dict[str, Unit] = {}
    for spec in specs:
        name = fmi_unit_name(spec.unit)
        if spec.type == "Real" and name is not None and name not in seen:
            try:
                seen[name] = parse_unit(spec.unit)
            except ValueError as exc:
                raise ValueError(f"variable {spec.name!r}: {exc}") from None
    return list(seen.values())
