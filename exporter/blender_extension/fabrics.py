"""Fabric presets of the Wet Cloth panel (``obj.wetcloth.preset``): scene parameters per fabric.

Only the areal density has a source per fabric (docs/blender.md section 8.3 lists them).  The
thickness follows from it at the towel's bulk density (0.45 kg/m2 over 2 mm = 225 kg/m3), an
assumption, not a measurement; every other fabric parameter (stiffness, damping, absorption) is
the towel's, for want of sources.
"""

from __future__ import annotations

#: Bulk density of the default towel (models/towel.toml): areal_density / thickness, kg/m3.
TOWEL_BULK_DENSITY = 0.45 / 0.002

#: identifier -> (label, areal density kg/m2, where the density comes from)
FABRICS = {
    "COTTON_TERRY_TOWEL": ("Cotton terry towel", 0.45,
                           "terry towel 300-600 g/m2 (aaenterprises.in fabric GSM chart); 450 is "
                           "models/towel.toml's hand towel"),
    "COTTON_JERSEY": ("Cotton jersey", 0.17, "single jersey (t-shirts) 140-200 g/m2, the middle "
                                             "(aaenterprises.in fabric GSM chart)"),
    "DENIM": ("Denim", 0.30, "denim / bottom-weight 200-400 g/m2, the middle (aaenterprises.in fabric GSM chart)"),
    "POLYESTER": ("Polyester", 0.135, "a woven polyester shirting: poplin / shirting 110-160 g/m2, the middle "
                                      "(aaenterprises.in fabric GSM chart)"),
    "SILK": ("Silk", 0.069, "16 momme habotai or crepe de chine, 1 momme = 4.34 g/m2 (silkmood.be, "
                            "'What is Momme?')"),
}

#: The scene parameters a preset sets.
FABRIC_PARAMETERS = ("areal_density", "thickness")


def fabric_parameters(identifier: str) -> dict[str, float]:
    """The scene parameters of fabric ``identifier`` (a key of FABRICS); ValueError naming the choices."""
    if identifier not in FABRICS:
        raise ValueError(f"unknown fabric preset {identifier!r}; choose one of {', '.join(FABRICS)}")
    density = FABRICS[identifier][1]
    return {"areal_density": density, "thickness": round(density / TOWEL_BULK_DENSITY, 6)}
