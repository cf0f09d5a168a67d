"""Fabric presets of the Wet Cloth panel (``obj.wetcloth.preset``): the fabric parameters of each.

docs/blender.md section 8.3 gives every value with its source and conversion (a test checks that the
table and this module agree). The published figures are kept here as printed, in their own units, and
converted by the functions below; a parameter with no source found is the default towel's
(models/towel.toml, the scene's defaults), as the table says.
"""

from __future__ import annotations

from dataclasses import dataclass
from statistics import fmean

from wetcloth.scene import PARAMETERS

#: The scene parameters a preset sets, in the panel's order (``initial_saturation`` is the cloth's state
#: at t = 0, not a property of the fabric: presets leave it).
FABRIC_PARAMETERS = ("areal_density", "thickness", "stretch_stiffness", "bend_stiffness", "bend_rigidity", "damping",
                     "absorption_capacity", "absorption_rate")

#: kg/m3, the water that fills the pores.
FRESH_WATER_DENSITY = 1000.0
#: kg/m3, dry fibre: cotton 1.55 and silk 1.34 g/cm3 (flexuma.de), polyester 1.38 (textilesbar.com).
FIBRE_DENSITY = {"cotton": 1550.0, "polyester": 1380.0, "silk": 1340.0}
#: kg/m3, the default towel's bulk density (areal_density / thickness): the thickness of a fabric with no
#: measured one.
TOWEL_BULK_DENSITY = PARAMETERS["areal_density"].default / PARAMETERS["thickness"].default
#: N/m in one gf/cm (Kawabata's unit of force per width).
NEWTON_PER_METRE_PER_GF_PER_CM = 9.80665e-3 / 1e-2
#: N m in one gf cm2/cm (Kawabata's unit of bending rigidity, moment per curvature per width).
NEWTON_METRE_PER_GF_CM2_PER_CM = NEWTON_PER_METRE_PER_GF_PER_CM * 1e-4
#: kg/m2 in one oz/yd2.
KG_PER_M2_PER_OZ_PER_YD2 = 0.028349523125 / 0.83612736
#: kg/m2 in one momme, the weight of silk (4.340 g/m2).
KG_PER_M2_PER_MOMME = 4.340e-3


def energy_equivalent_stiffness(tensile_energy: float, strain_percent: float) -> float:
    """N/m per unit strain: the linear (tension-only) spring per unit width that stores a fabric's KES
    tensile energy WT (gf cm/cm2, that is gf/cm times strain) at its strain EMT (%): 2 WT / EMT^2."""
    strain = strain_percent / 100.0
    return 2.0 * tensile_energy / strain ** 2 * NEWTON_PER_METRE_PER_GF_PER_CM


def pore_water_capacity(thickness: float, areal_density: float, fibre: str) -> float:
    """kg of water per kg of dry fabric when water fills the envelope's pores: the envelope's volume per
    kg, thickness (m) / areal_density (kg/m2), less the fibre's own, times the water's density."""
    return FRESH_WATER_DENSITY * (thickness / areal_density - 1.0 / FIBRE_DENSITY[fibre])


#: Denims A-F of Kumari and Khurana, "Regenerated Cellulose-Based Denim Fabric for Tropical Regions",
#: Journal of Textiles 2016, Table 5 (KES-F): thickness (mm) of all six; tensile energy WT (gf cm/cm2) and
#: strain EMT (%) of B, C, D and F (A's and E's WT, printed 0.825 and 0.475, a twentieth of the others' at
#: like strains, are left out).
DENIM_THICKNESS_MM = (1.066, 1.188, 0.801, 1.040, 0.887, 0.973)
DENIM_TENSILE_ENERGY = (9.400, 8.975, 8.675, 8.950)
DENIM_STRAIN_PERCENT = (5.735, 4.695, 5.135, 5.455)
#: Their bending rigidity B (gf cm2/cm), all six.
DENIM_BENDING_RIGIDITY = (0.172, 0.144, 0.227, 0.147, 0.207, 0.148)


@dataclass(frozen=True)
class Fabric:
    """One preset: its label and tooltip, its fibre (a key of FIBRE_DENSITY), areal density (kg/m2) and,
    where measured, thickness (m), stretch stiffness (N/m) and bending rigidity (N m); ``None``: the thickness
    at the towel's bulk density, the towel's stiffness; a rigidity of 0: the bending springs."""

    label: str
    description: str
    fibre: str
    areal_density: float
    thickness: float | None = None
    stretch_stiffness: float | None = None
    bend_rigidity: float = 0.0


FABRICS = {
    "COTTON_TERRY_TOWEL": Fabric("Cotton terry towel", "The default towel: 450 g/m2, 2 mm (models/towel.toml)",
                                 "cotton", PARAMETERS["areal_density"].default, PARAMETERS["thickness"].default),
    "COTTON_JERSEY": Fabric("Cotton jersey", "Single jersey (t-shirts), 170 g/m2", "cotton", 0.17),
    "DENIM": Fabric("Denim", "12 oz/yd2 jeans denim, 0.99 mm, stiffness and bending from KES-F tests", "cotton",
                    round(12 * KG_PER_M2_PER_OZ_PER_YD2, 3), round(fmean(DENIM_THICKNESS_MM), 2) / 1000,
                    round(fmean(map(energy_equivalent_stiffness, DENIM_TENSILE_ENERGY, DENIM_STRAIN_PERCENT)), -1),
                    float(f"{fmean(DENIM_BENDING_RIGIDITY) * NEWTON_METRE_PER_GF_CM2_PER_CM:.3g}")),
    "POLYESTER": Fabric("Polyester", "Woven polyester shirting, 135 g/m2", "polyester", 0.135),
    "SILK": Fabric("Silk", "16 momme habotai or crepe de chine, 69 g/m2", "silk", round(16 * KG_PER_M2_PER_MOMME, 3)),
}


def fabric_parameters(identifier: str) -> dict[str, float]:
    """The scene parameters of fabric ``identifier`` (a key of FABRICS), FABRIC_PARAMETERS in order;
    ValueError naming the choices."""
    if identifier not in FABRICS:
        raise ValueError(f"unknown fabric preset {identifier!r}; choose one of {', '.join(FABRICS)}")
    fabric = FABRICS[identifier]
    thickness = fabric.thickness or round(fabric.areal_density / TOWEL_BULK_DENSITY, 6)
    towel = {name: PARAMETERS[name].default for name in FABRIC_PARAMETERS}
    return towel | {
        "areal_density": fabric.areal_density,
        "thickness": thickness,
        "stretch_stiffness": fabric.stretch_stiffness or towel["stretch_stiffness"],
        "bend_rigidity": fabric.bend_rigidity,
        "absorption_capacity": round(pore_water_capacity(thickness, fabric.areal_density, fabric.fibre), 2),
    }
