"""Cost of the FMI 3.0 unit's mesh outputs per communication step, against the FMI 2.0 unit.

    .venv/bin/python bench/fmu3_arrays.py [--duration 10] [--rate 30] [--repeat 3] [--grid NX NY]

The same scene, in this process, through fmpy's ``FMU2Slave`` (WetCloth.fmu) and ``FMU3Slave``
(WetCloth3.fmu).  Per communication point a master sets every input, steps, and reads: FMI 2.0 the
six scalar outputs (``fmi2GetReal``); FMI 3.0 the same six (``fmi3GetFloat64``), then also the mesh
arrays ``positions`` (n x 3) and ``wetness`` (n) in the same call.  Also timed: the direct Python
run, and the direct run reading ``Simulation.positions`` and ``.wetness`` each step (what the mesh
costs without FMI).  Times are CPU seconds of this process (``time.process_time``; the machine may
be shared), runs interleaved, the best of ``--repeat``; instantiation is outside the loops.
"""

from __future__ import annotations

import argparse
import atexit
import shutil
import sys
import tempfile
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

import wetcloth
from wetcloth.fmu.builder import build_fmu
from wetcloth.simulation import OUTPUT_NAMES

from _fmu_units import CLOCK, direct_run, started_fmu2  # noqa: E402



def direct(scene: wetcloth.Scene, duration: float, rate: float, mesh: bool) -> tuple[float, float]:
    """CPU time (s) of the direct run, and of its output reads alone."""
    return direct_run(scene, duration, rate, (lambda sim: (sim.positions.ravel().tolist(), sim.wetness.tolist()))
                      if mesh else None)


def loop(fmi: int, directory: str, md, scene: wetcloth.Scene, duration: float, rate: float,
         mesh: bool) -> tuple[float, float]:
    """CPU time (s) of the communication loop through the unit, and of its output reads alone."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    inputs = [v.name for v in md.modelVariables if v.causality == "input"]
    input_vrs, input_values = [vr[n] for n in inputs], [getattr(scene, n) for n in inputs]
    n = scene.nx * scene.ny
    read = [vr[name] for name in OUTPUT_NAMES] + ([vr["positions"], vr["wetness"]] if mesh else [])
    count = len(OUTPUT_NAMES) + (4 * n if mesh else 0)
    if fmi == 2:
        fmu = started_fmu2(directory, md, scene)
        set_inputs, get_outputs = fmu.setReal, lambda: fmu.getReal(read)
    else:
        fmu = FMU3Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName="bench")
        fmu.instantiate()
        fmu.setUInt64([vr["nx"], vr["ny"]], [scene.nx, scene.ny])
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        set_inputs, get_outputs = fmu.setFloat64, lambda: fmu.getFloat64(read, nValues=count)
    reading = 0.0
    start = CLOCK()
    t = 0.0
    for k in range(round(duration * rate)):
        set_inputs(input_vrs, input_values)
        t_next = (k + 1) / rate
        fmu.doStep(t, t_next - t)
        t = t_next
        before = CLOCK()
        values = get_outputs()
        reading += CLOCK() - before
    elapsed = CLOCK() - start
    assert len(values) == count
    fmu.terminate()
    fmu.freeInstance()
    return elapsed, reading


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=10.0, help="simulated time per run, s (default 10)")
    parser.add_argument("--rate", type=float, default=30.0, help="communication rate, Hz (default 30)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per figure; the best counts (default 3)")
    parser.add_argument("--grid", type=int, nargs=2, metavar=("NX", "NY"), help="particles (default: the towel's)")
    args = parser.parse_args(argv)
    scene = wetcloth.load_scene()
    if args.grid:
        scene = scene.replace(nx=args.grid[0], ny=args.grid[1])
    work = Path(tempfile.mkdtemp(prefix="wetcloth_bench_fmu3_"))
    atexit.register(shutil.rmtree, work, ignore_errors=True)
    units = {}
    for fmi in (2, 3):
        path = str(build_fmu(work / f"WetCloth{fmi}.fmu", fmi_version=fmi))
        units[fmi] = (extract(path, unzipdir=str(work / f"unit{fmi}")), read_model_description(path))
    direct(scene, 0.5, args.rate, True)  # one untimed run first: lazy imports, memory first touched
    cases = {
        "direct run": lambda: direct(scene, args.duration, args.rate, False),
        "direct run + mesh read": lambda: direct(scene, args.duration, args.rate, True),
        "FMI 2.0, scalars": lambda: loop(2, *units[2], scene, args.duration, args.rate, False),
        "FMI 3.0, scalars": lambda: loop(3, *units[3], scene, args.duration, args.rate, False),
        "FMI 3.0, scalars + mesh arrays": lambda: loop(3, *units[3], scene, args.duration, args.rate, True),
    }
    times = {name: [] for name in cases}
    for _ in range(args.repeat):  # interleaved, so that all see the same machine load
        for name, run in cases.items():
            times[name].append(run())
    best = {name: (min(t for t, _ in values), min(r for _, r in values)) for name, values in times.items()}
    steps = round(args.duration * args.rate)
    base = best["FMI 2.0, scalars"]
    print(f"scene: default towel, {scene.nx} x {scene.ny} particles ({scene.nx * scene.ny} vertices), "
          f"{args.duration:g} s at {args.rate:g} Hz ({steps} steps), best of {args.repeat}; Python "
          f"{sys.version.split()[0]}")
    print()
    print("| loop | CPU s | per step (us) | against FMI 2.0 | reading the outputs, per step (us) |")
    print("|---|---|---|---|---|")
    for name, (total, reading) in best.items():
        print(f"| {name} | {total:.3f} | {1e6 * total / steps:.0f} | {100 * (total - base[0]) / base[0]:+.1f} % "
              f"| {1e6 * reading / steps:.0f} |")
    mesh = best["FMI 3.0, scalars + mesh arrays"][1] - best["FMI 2.0, scalars"][1]
    print()
    print(f"reading the mesh arrays too ({4 * scene.nx * scene.ny} values) costs {1e6 * mesh / steps:.0f} us per step "
          f"more than the FMI 2.0 outputs: {100 * mesh / base[0]:.1f} % of an FMI 2.0 step")
    return 0


if __name__ == "__main__":
    sys.exit(main())
