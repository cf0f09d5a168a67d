"""The FMI 3.0 variables and ``modelDescription.xml`` of WetCloth3.fmu, from the shared vocabulary (pythonfmu3).

The FMI 2.0 types map to FMI 3.0 ones: Real -> Float64, String -> String, Integer -> Int32, except
that an Integer parameter that sizes an array output (``nx``, ``ny``) is a UInt64 structural
parameter, as FMI 3.0 requires of a ``Dimension``'s variable; a mesh cloth's faces are a constant
UInt64 array output (pythonfmu3's binary aborts the host's process on any ``fmi3GetUInt32``: no UInt32
variable).  pythonfmu3 writes causality, variability, start, units and the model structure; here each
variable also gets ``min``/``max`` (a constant its whole ``start``) and the outputs their
direct-feedthrough dependencies.
"""

from __future__ import annotations

from typing import Callable, Sequence
from xml.etree.ElementTree import Element

from pythonfmu3 import Dimension, Float64, Int32, String, UInt64, Unit
from pythonfmu3.enums import Fmi3Causality, Fmi3Initial, Fmi3Variability
from pythonfmu3.variables import ModelVariable

from wetcloth.fmu.vocabulary import FEEDTHROUGH, VariableSpec, WithAttributes, units_of, xml_attributes


class Float64Variable(WithAttributes, Float64):
    """A pythonfmu3 ``Float64`` (scalar or array) with range."""


class Int32Variable(WithAttributes, Int32):
    """A pythonfmu3 ``Int32`` with range."""


class UInt64Variable(WithAttributes, UInt64):
    """A pythonfmu3 ``UInt64`` with range (a structural parameter), or a constant array (a mesh's faces)."""


class StringVariable(WithAttributes, String):
    """A pythonfmu3 ``String``."""


def dimension_sources(specs: Sequence[VariableSpec]) -> set[str]:
    """Names of the parameters that size array variables: FMI 3.0 structural parameters."""
    return {d for spec in specs for d in spec.dimensions if isinstance(d, str)}


def make_variable(spec: VariableSpec, getter: Callable, setter: Callable | None,
                  value_references: dict[str, int], structural: set[str]) -> ModelVariable:
    """The pythonfmu3 variable of a spec (``value_references`` of the variables its dimensions name)."""
    attributes = xml_attributes(spec)
    unit = attributes.pop("unit", None)
    causality = spec.causality
    kwargs = dict(variability=Fmi3Variability[spec.variability], description=spec.description,
                  initial={"exact": Fmi3Initial.exact, "calculated": Fmi3Initial.calculated}.get(spec.initial),
                  getter=getter, setter=setter)
    start = None if spec.variability == "constant" else spec.start  # a constant's: in ``attributes``
    if spec.type == "String":
        return StringVariable(spec.name, attributes, causality=Fmi3Causality[causality], start=spec.start, **kwargs)
    dimensions = [Dimension(start=str(d)) if isinstance(d, int) else Dimension(valueReference=str(value_references[d]))
                  for d in spec.dimensions]
    if spec.type == "UInt64":
        return UInt64Variable(spec.name, attributes, causality=Fmi3Causality[causality], dimensions=dimensions, **kwargs)
    if spec.type == "Integer":
        cls = UInt64Variable if spec.name in structural else Int32Variable
        causality = "structuralParameter" if spec.name in structural else causality
        return cls(spec.name, attributes, causality=Fmi3Causality[causality], start=spec.start, **kwargs)
    return Float64Variable(spec.name, attributes, causality=Fmi3Causality[causality], start=start, unit=unit,
                           dimensions=dimensions, **kwargs)


def units(specs: Sequence[VariableSpec]) -> list[Unit]:
    """pythonfmu3 unit definitions (SI base-unit exponents) of the units the variables use."""
    return [Unit(u.name, factor=u.factor, **dict(u.exponents)) for u in units_of(specs)]


def extend_model_description(root: Element, specs: Sequence[VariableSpec]) -> Element:
    """Add the outputs' direct-feedthrough dependencies to pythonfmu3's ModelStructure (in place)."""
    value_reference = {spec.name: str(i) for i, spec in enumerate(specs)}
    name_of = {vr: name for name, vr in value_reference.items()}
    for output in root.find("ModelStructure").findall("Output"):
        sources = FEEDTHROUGH.get(name_of[output.get("valueReference")], ())
        output.set("dependencies", " ".join(value_reference[s] for s in sources))
        output.set("dependenciesKind", " ".join("dependent" for _ in sources))
    return root
