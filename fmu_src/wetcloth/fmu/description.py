"""What pythonfmu 0.7 leaves out of the FMI 2.0 ``modelDescription.xml``, added at its seams (FMI 3.0: ``description3.py``).

pythonfmu writes each variable's causality, variability, start and description, and the
``ModelStructure/Outputs`` list, but no units, no ranges and no ``InitialUnknowns``.  Here:

* ``make_variable`` builds pythonfmu ``Real``/``Integer``/``String`` variables whose ``to_xml``
  also writes ``unit``, ``min`` and ``max``;
* ``extend_model_description`` adds ``UnitDefinitions`` (SI base-unit exponents), the outputs'
  direct-feedthrough dependencies and ``ModelStructure/InitialUnknowns``, so that
  ``fmpy.validation.validate_fmu`` reports no problems.
"""

from __future__ import annotations

from typing import Callable, Sequence
from xml.etree.ElementTree import Element, SubElement

from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Variability
from pythonfmu.variables import Integer, Real, ScalarVariable, String

from wetcloth.fmu.vocabulary import FEEDTHROUGH, VariableSpec, WithAttributes, units_of, xml_attributes


class _WithAttributes(WithAttributes):
    """FMI 2.0 keeps unit, min and max on the variable's type element (``<Real unit=...>``)."""

    @staticmethod
    def attribute_element(node):
        return node[0]


class RealVariable(_WithAttributes, Real):
    """A pythonfmu ``Real`` with unit and range."""


class IntegerVariable(_WithAttributes, Integer):
    """A pythonfmu ``Integer`` with range."""


class StringVariable(_WithAttributes, String):
    """A pythonfmu ``String``."""


_CLASSES = {"Real": RealVariable, "Integer": IntegerVariable, "String": StringVariable}


def make_variable(spec: VariableSpec, getter: Callable, setter: Callable | None) -> ScalarVariable:
    """The pythonfmu variable of a spec, reading and writing through ``getter``/``setter``."""
    attributes = xml_attributes(spec)
    initial = {"exact": Fmi2Initial.exact, "calculated": Fmi2Initial.calculated}.get(spec.initial)
    return _CLASSES[spec.type](
        spec.name,
        attributes,
        causality=Fmi2Causality[spec.causality],
        variability=Fmi2Variability[spec.variability],
        description=spec.description,
        initial=initial,
        getter=getter,
        setter=setter,
    )


def extend_model_description(root: Element, specs: Sequence[VariableSpec]) -> Element:
    """Add UnitDefinitions, output dependencies and InitialUnknowns to pythonfmu's XML (in place)."""
    index = {spec.name: i + 1 for i, spec in enumerate(specs)}  # ScalarVariable indices are 1-based

    units = units_of(specs)
    if units:
        definitions = Element("UnitDefinitions")
        for unit in units:
            node = SubElement(definitions, "Unit", name=unit.name)
            base = {key: str(exp) for key, exp in unit.exponents}
            if unit.factor != 1.0:
                base["factor"] = repr(unit.factor)
            SubElement(node, "BaseUnit", base)
        # The schema's order: CoSimulation, UnitDefinitions, TypeDefinitions, LogCategories, ...
        position = list(root).index(root.find("CoSimulation")) + 1
        root.insert(position, definitions)

    structure = root.find("ModelStructure")
    outputs = structure.find("Outputs")
    if outputs is not None:
        for unknown in outputs.findall("Unknown"):
            spec = specs[int(unknown.get("index")) - 1]
            sources = FEEDTHROUGH.get(spec.name, ())
            unknown.set("dependencies", " ".join(str(index[s]) for s in sources))
            unknown.set("dependenciesKind", " ".join("dependent" for _ in sources))
    initial = [s for s in specs if s.causality == "output" and s.initial in ("approx", "calculated")]
    if initial:
        node = SubElement(structure, "InitialUnknowns")
        for spec in initial:
            SubElement(node, "Unknown", index=str(index[spec.name]))
    return root
