"""Cost of the FMU over a direct Python run of the same scene, at 30 Hz and 100 Hz communication.

    .venv/bin/python bench/fmu_overhead.py [--duration 10] [--repeat 3] [--rates 30 100] [--grid NX NY]

Direct: ``Simulation.advance`` to each communication point, then ``outputs()``.  FMU: the same
scene through WetCloth.fmu in fmpy's ``FMU2Slave`` (ctypes, pythonfmu's C++ and back into
Python), per communication point ``fmi2SetReal`` of every input, ``fmi2DoStep`` and
``fmi2GetReal`` of the six outputs, as a master with connected inputs does.  Also timed:
``fmpy.simulate_fmu`` end to end (extraction, instantiation, recorder).

Times are CPU seconds of this process (``time.process_time``: the machine is shared, and the
unit runs in this process), direct and FMU runs interleaved, each figure the best of
``--repeat``; instantiation and initialization are outside the loop times.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import fmpy
from fmpy import extract, read_model_description

import wetcloth
from wetcloth.fmu.builder import build_fmu
from wetcloth.simulation import OUTPUT_NAMES

from _fmu_units import CLOCK, direct_run, started_fmu2  # noqa: E402



def direct(scene: wetcloth.Scene, duration: float, rate: float) -> float:
    return direct_run(scene, duration, rate)[0]


def through_fmu(directory: str, md, scene: wetcloth.Scene, duration: float, rate: float) -> tuple[float, float]:
    """Loop time (s) and one-off instantiate-to-initialized time (s)."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    inputs = [v.name for v in md.modelVariables if v.causality == "input"]
    input_vrs = [vr[n] for n in inputs]
    input_values = [getattr(scene, n) for n in inputs]
    output_vrs = [vr[n] for n in OUTPUT_NAMES]
    setup = CLOCK()
    fmu = started_fmu2(directory, md, scene)
    setup = CLOCK() - setup
    steps = round(duration * rate)
    start = CLOCK()
    t = 0.0
    for k in range(steps):
        fmu.setReal(input_vrs, input_values)
        t_next = (k + 1) / rate
        fmu.doStep(t, t_next - t)
        t = t_next
        fmu.getReal(output_vrs)
    loop = CLOCK() - start
    fmu.terminate()
    fmu.freeInstance()
    return loop, setup


def end_to_end(fmu_path: str, scene: wetcloth.Scene, duration: float, rate: float) -> float:
    start = CLOCK()
    fmpy.simulate_fmu(fmu_path, stop_time=duration, output_interval=1.0 / rate,
                      start_values={"nx": scene.nx, "ny": scene.ny})
    return CLOCK() - start


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=10.0, help="simulated time per run, s (default 10)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per figure; the best counts (default 3)")
    parser.add_argument("--rates", type=float, nargs="+", default=[30.0, 100.0], help="communication rates, Hz")
    parser.add_argument("--grid", type=int, nargs=2, metavar=("NX", "NY"), help="particles (default: the towel's)")
    args = parser.parse_args(argv)

    scene = wetcloth.load_scene()  # the default towel
    if args.grid:
        scene = scene.replace(nx=args.grid[0], ny=args.grid[1])
    fmu_path = str(build_fmu(Path(tempfile.mkdtemp(prefix="wetcloth_bench_")) / "WetCloth.fmu"))
    directory, md = extract(fmu_path), read_model_description(fmu_path)
    direct(scene, 0.5, 30.0)  # one untimed run first: lazy imports, memory first touched
    print(f"scene: default towel, {scene.nx} x {scene.ny} particles, integrator {scene.integrator}, "
          f"{args.duration:g} s simulated per run, best of {args.repeat}; Python {sys.version.split()[0]}")
    print()
    print("| communication | direct run (CPU s) | FMU loop (CPU s) | overhead | per step (us) | fmpy.simulate_fmu (CPU s) |")
    print("|---|---|---|---|---|---|")
    setups = []
    for rate in args.rates:
        directs, loops = [], []
        for _ in range(args.repeat):  # interleaved, so both see the same machine load
            directs.append(direct(scene, args.duration, rate))
            loop, setup = through_fmu(directory, md, scene, args.duration, rate)
            loops.append(loop)
            setups.append(setup)
        d, f = min(directs), min(loops)
        e = min(end_to_end(fmu_path, scene, args.duration, rate) for _ in range(args.repeat))
        steps = round(args.duration * rate)
        print(f"| {rate:g} Hz | {d:.3f} | {f:.3f} | {100 * (f - d) / d:+.1f} % | {1e6 * (f - d) / steps:.0f} "
              f"| {e:.3f} |")
    print()
    print(f"instantiate + initialize (once per run): best {1e3 * min(setups):.1f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
