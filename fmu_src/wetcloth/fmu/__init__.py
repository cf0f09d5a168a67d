"""WetCloth FMUs: co-simulation units around ``wetcloth.Simulation`` (FMI 2.0 with pythonfmu, FMI 3.0
with pythonfmu3), and co-simulating them through fmpy.

    from wetcloth.fmu import build_fmu, demo
    build_fmu()                           # models/WetCloth.fmu, FMI 2.0
    build_fmu(fmi_version=3)              # models/WetCloth3.fmu, FMI 3.0 with the mesh as array outputs
    demo("out/demo")                      # co-simulate the towel through fmpy: frames, CSV, plot

Inside a unit, ``wetcloth_fmu_slave.py`` (or ``wetcloth_fmu3_slave.py``) runs the bootstrap
(``bootstrap.py``: which wetcloth, a quick start), then the unit class of ``fmi2.py`` (``fmi3.py``),
both thin adapters of ``unit.py``.  This package imports nothing heavy up front.  docs/fmi.md is
the user's guide.
"""

from pathlib import Path

__all__ = ["MODEL_NAME", "build_fmu", "default_fmu_path", "demo", "simulate"]

#: Model name and FMI model identifier (binary name) of both units.
MODEL_NAME = "WetCloth"
#: The GUID (FMI 3.0: instantiationToken) of the unit ``build_fmu`` is building, derived from its
#: contents (the slave classes' ``to_xml`` writes it); None otherwise.
BUILD_TOKEN: str | None = None


def default_fmu_path(fmi_version: int = 2) -> Path:
    """Where ``wetcloth build-fmu`` writes a unit and where the demo and batch studies look for it:
    ``models/WetCloth.fmu`` (FMI 2.0) or ``models/WetCloth3.fmu`` (FMI 3.0), relative to the current folder."""
    if fmi_version not in (2, 3):
        raise ValueError(f"FMI version must be 2 or 3, got {fmi_version!r}")
    return Path("models") / f"{MODEL_NAME}{'' if fmi_version == 2 else fmi_version}.fmu"


def __getattr__(name):
    if name == "build_fmu":
        from wetcloth.fmu.builder import build_fmu

        return build_fmu
    if name in ("demo", "simulate"):
        from wetcloth.fmu import cosim

        return getattr(cosim, name)
    raise AttributeError(f"module 'wetcloth.fmu' has no attribute {name!r}")
