"""The Blender extension's fabric presets (exporter/blender_extension/fabrics.py): valid scenes, the towel's
own values, their conversions, and the table of docs/blender.md section 8.3 that gives their sources."""

import math
import re
from pathlib import Path

import pytest

import wetcloth
from wetcloth.exporter.blender_extension.fabrics import (DENIM_BENDING_RIGIDITY, FABRIC_PARAMETERS, FABRICS,
                                                         NEWTON_PER_METRE_PER_GF_PER_CM,
                                                         energy_equivalent_stiffness, fabric_parameters,
                                                         pore_water_capacity)
from wetcloth.exporter.blender_extension.parameters import FABRIC
from wetcloth.scene import PARAMETERS

DOCS = Path(__file__).resolve().parents[1] / "docs" / "blender.md"
#: The table's units, in SI.
UNITS = {"kg/m2": 1.0, "mm": 1e-3, "N/m": 1.0, "N m": 1.0, "N s/m": 1.0, "kg/kg": 1.0, "1/s": 1.0}
ROW = re.compile(r"^\| `(?P<preset>[A-Z_]+)` \| `(?P<name>[a-z_]+)` \| (?P<value>[0-9.]+) (?P<unit>[^|]+?) \|")


def documented_presets() -> dict[str, dict[str, float]]:
    """Section 8.3's table: preset -> parameter -> value (SI)."""
    text = DOCS.read_text()
    section = text[text.index("### 8.3 Fabric presets"):text.index("### 8.4 Bake")]
    table: dict[str, dict[str, float]] = {}
    for match in map(ROW.match, section.splitlines()):
        if match:
            value = float(match["value"]) * UNITS[match["unit"]]
            table.setdefault(match["preset"], {})[match["name"]] = value
    return table


def test_every_preset_is_a_valid_scene_and_the_towel_is_the_default():
    assert list(FABRICS) == ["COTTON_TERRY_TOWEL", "COTTON_JERSEY", "DENIM", "POLYESTER", "SILK"]
    assert set(FABRIC_PARAMETERS) == set(FABRIC) - {"initial_saturation"}
    defaults = wetcloth.Scene()
    assert fabric_parameters("COTTON_TERRY_TOWEL") == {name: getattr(defaults, name) for name in FABRIC_PARAMETERS}
    for key in FABRICS:
        parameters = fabric_parameters(key)
        assert tuple(parameters) == FABRIC_PARAMETERS
        # raises if any value is outside its field's range (on a mesh cloth: denim's bend_rigidity needs one)
        wetcloth.load_scene("tablecloth").replace(**parameters)
    with pytest.raises(ValueError, match="unknown fabric preset 'WOOL'"):
        fabric_parameters("WOOL")


def test_the_documented_table_is_the_code():
    """Every preset parameter appears once in docs/blender.md section 8.3 with the code's value (equal
    up to the unit conversion's rounding)."""
    table = documented_presets()
    assert list(table) == list(FABRICS)
    for key, documented in table.items():
        code = fabric_parameters(key)
        assert list(documented) == list(code), key
        for name, value in documented.items():
            assert math.isclose(value, code[name], rel_tol=1e-12), (key, name, value, code[name])


def test_denims_bending_rigidity_is_its_kes_b_in_n_m():
    """Conversion (e): the six denims' mean KES bending rigidity B (gf cm2/cm) in N m, to the three figures the
    table prints; the presets without a measured B bend by their springs (bend_rigidity 0)."""
    b = sum(DENIM_BENDING_RIGIDITY) / len(DENIM_BENDING_RIGIDITY) * 9.80665e-3 * 1e-4 / 1e-2
    assert math.isclose(fabric_parameters("DENIM")["bend_rigidity"], b, rel_tol=5e-3)
    assert [fabric_parameters(key)["bend_rigidity"] for key in FABRICS if key != "DENIM"] == [0.0] * 4


def test_the_pore_volume_gives_the_default_towels_capacity():
    """Conversion (d) on the default towel's thickness and areal density gives models/towel.toml's
    absorption_capacity, 3.8 kg/kg, by the same derivation ("pores of a 2 mm, 450 g/m2 towel"): within
    half its last printed digit, 0.05 kg/kg."""
    field = {name: PARAMETERS[name].default for name in ("thickness", "areal_density", "absorption_capacity")}
    capacity = pore_water_capacity(field["thickness"], field["areal_density"], "cotton")
    assert abs(capacity - field["absorption_capacity"]) <= 0.05


def test_the_energy_equivalent_stiffness_of_a_linear_fabric_is_its_stiffness():
    """A fabric whose load rises linearly, k per unit strain (N/m), to the strain EMT stores k EMT^2 / 2:
    conversion (c) gives k back."""
    k, strain_percent = 6000.0, 5.0
    tensile_energy = k / NEWTON_PER_METRE_PER_GF_PER_CM * (strain_percent / 100) ** 2 / 2  # gf cm/cm2
    assert math.isclose(energy_equivalent_stiffness(tensile_energy, strain_percent), k, rel_tol=1e-12)
