"""WetCloth.fmu: the FMI 2.0 co-simulation unit around ``wetcloth.Simulation`` (built with pythonfmu).

    from wetcloth.fmu import build_fmu, demo
    build_fmu("models/WetCloth.fmu")      # write the unit
    demo("out/demo")                      # co-simulate the towel through fmpy: frames, CSV, plot

The slave script ``wetcloth_fmu_slave.py`` imports ``wetcloth.fmu.vocabulary`` and
``wetcloth.fmu.description`` inside the FMU, so this package imports nothing heavy up front.
"""

__all__ = ["build_fmu", "demo", "simulate"]


def __getattr__(name):
    if name == "build_fmu":
        from wetcloth.fmu.builder import build_fmu

        return build_fmu
    if name in ("demo", "simulate"):
        from wetcloth.fmu import cosim

        return getattr(cosim, name)
    raise AttributeError(f"module 'wetcloth.fmu' has no attribute {name!r}")
