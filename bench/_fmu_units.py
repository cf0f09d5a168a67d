"""What the FMU benchmarks share: a direct run of a scene read at a rate, and an FMI 2.0 unit started
for a scene (instantiated and initialized with its grid, as a master does)."""

from __future__ import annotations

import time

from fmpy.fmi2 import FMU2Slave

import wetcloth

CLOCK = time.process_time


def direct_run(scene: wetcloth.Scene, duration: float, rate: float, read=None) -> tuple[float, float]:
    """CPU time (s) of a direct run, ``Simulation.advance`` to each of ``duration * rate``
    communication points and ``outputs()`` there, and of the reads alone (``read(sim)`` after
    the outputs, if given)."""
    sim = wetcloth.Simulation(scene)
    reading = 0.0
    start = CLOCK()
    for k in range(round(duration * rate)):
        sim.advance((k + 1) / rate - sim.time)
        before = CLOCK()
        sim.outputs()
        if read is not None:
            read(sim)
        reading += CLOCK() - before
    return CLOCK() - start, reading


def started_fmu2(directory: str, md, scene: wetcloth.Scene) -> FMU2Slave:
    """An FMI 2.0 instance of the extracted unit in ``directory`` (model description ``md``),
    instantiated and initialized at t = 0 with the scene's grid size."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName="bench")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["nx"], vr["ny"]], [scene.nx, scene.ny])
    fmu.exitInitializationMode()
    return fmu
