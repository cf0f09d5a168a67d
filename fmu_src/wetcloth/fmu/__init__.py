"""WetCloth.fmu: the FMI 2.0 co-simulation unit around ``wetcloth.Simulation`` (built with pythonfmu)."""
