"""The native unit (``wetcloth build-fmu --native``): its start, and what a doStep costs beyond the physics.

    .venv/bin/python bench/fmu_native.py [--repeat 5] [--steps 3000] [--native FMU] [--python FMU]
    .venv/bin/python bench/fmu_native.py --scene tablecloth --step 0.01 --steps 100 --clock cpu

Both units are driven by a minimal master: ctypes calls straight into their binaries (no fmpy wrapper
in the loop), the default towel, 1 ms communication steps from t = 0 (its landing: one internal BDF2 step
per communication step), ``fmi2DoStep`` then ``fmi2GetReal`` of the six outputs at every point.

* start: a new process (Python with ctypes only, for the native unit) loads the binary, instantiates,
  initializes and takes the first 1 ms doStep; timed from before the load to after initialization
  (target: under 50 ms to the first doStep) and to the end of that doStep.  pythonfmu's WetCloth.fmu
  is timed the same way in a process that has wetcloth's dependencies (its start imports them);
* per step: the native unit, ``wetcloth.Simulation.advance`` to the same points with ``outputs()`` in
  the same process, and pythonfmu's WetCloth.fmu;
* overhead: what a native doStep costs beyond the physics, measured directly: ``fmi2DoStep`` with a
  zero step (everything but the internal steps: the checks, the copy of the state kept to fall back to
  after a failed step) plus ``fmi2GetReal`` of the six outputs (target: at most 0.05 ms).  The native
  unit and ``wetcloth.Simulation`` run the same compiled core (the same C++ sources and optimisation flags), so
  "native minus Simulation" is what separates the two drivers: doStep and getReal through ctypes
  against ``advance`` and ``outputs()`` in Python.

Wall-clock times (``time.perf_counter``; ``--clock cpu``: the process's CPU time, ``time.process_time``, but for
the start, a child's), each the best of ``--repeat`` (median in brackets): the machine may be shared.  Builds the
units into a temporary folder unless given; ``--scene`` (a scene file or preset, e.g. a cloth from a mesh file)
builds them with that scene built in, runs it instead of the towel with communication steps of ``--step`` s, and
times the native build: from nothing, and after another scene's unit (the core and the unit's fixed sources
compiled before: only the generated source compiles).
"""

from __future__ import annotations

import argparse
import ctypes
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import fmpy

import wetcloth
from wetcloth.fmu.builder import build_fmu
from wetcloth.fmu.native import VARIABLES_SOURCE, build_native_fmu
from wetcloth.simulation import OUTPUT_NAMES

CO_SIMULATION = 1  # fmi2CoSimulation

#: A master in a new process with nothing but ctypes: load, instantiate, initialize, one doStep.
START = r"""
import ctypes, json, sys, time
so, guid, resources, h = sys.argv[1], sys.argv[2].encode(), sys.argv[3].encode(), float(sys.argv[4])
LOGGER = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p)
ALLOCATE = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t)
FREE = ctypes.CFUNCTYPE(None, ctypes.c_void_p)
class Callbacks(ctypes.Structure):
    _fields_ = [("logger", LOGGER), ("allocateMemory", ALLOCATE), ("freeMemory", FREE),
                ("stepFinished", ctypes.c_void_p), ("componentEnvironment", ctypes.c_void_p)]
libc = ctypes.CDLL(None)
libc.calloc.restype = ctypes.c_void_p
callbacks = Callbacks(LOGGER(lambda *a: None), ALLOCATE(lambda n, s: libc.calloc(n, s)),
                      FREE(lambda p: libc.free(ctypes.c_void_p(p))), None, None)
start = time.perf_counter()
lib = ctypes.CDLL(so)
lib.fmi2Instantiate.restype = ctypes.c_void_p
lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_void_p,
                                ctypes.c_int, ctypes.c_int]
for name in ("fmi2SetupExperiment", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2DoStep"):
    getattr(lib, name).restype = ctypes.c_int
lib.fmi2SetupExperiment.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_double, ctypes.c_int,
                                    ctypes.c_double]
lib.fmi2EnterInitializationMode.argtypes = lib.fmi2ExitInitializationMode.argtypes = [ctypes.c_void_p]
lib.fmi2DoStep.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
c = lib.fmi2Instantiate(b"start", 1, guid, resources, ctypes.byref(callbacks), 0, 0)
assert c and lib.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == 0
assert lib.fmi2EnterInitializationMode(c) == 0 and lib.fmi2ExitInitializationMode(c) == 0
ready = time.perf_counter()
assert lib.fmi2DoStep(c, 0.0, h, 1) == 0
stepped = time.perf_counter()
print(json.dumps({"ready": ready - start, "first_step": stepped - start}))
"""


class Unit:
    """An FMI 2.0 unit driven through ctypes (the extracted folder, its model description)."""

    def __init__(self, directory: Path, md):
        from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2CallbackAllocateMemoryTYPE, \
            fmi2CallbackFreeMemoryTYPE
        from fmpy import calloc, free

        self.lib = lib = ctypes.CDLL(str(directory / "binaries" / "linux64" / "WetCloth.so"))
        lib.fmi2Instantiate.restype = ctypes.c_void_p
        lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p,
                                        ctypes.c_void_p, ctypes.c_int, ctypes.c_int]
        lib.fmi2SetupExperiment.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_double,
                                            ctypes.c_int, ctypes.c_double]
        lib.fmi2EnterInitializationMode.argtypes = lib.fmi2ExitInitializationMode.argtypes = [ctypes.c_void_p]
        lib.fmi2DoStep.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
        lib.fmi2GetReal.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p]
        lib.fmi2FreeInstance.argtypes = [ctypes.c_void_p]
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(lambda *args: None)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        resources = (directory / "resources").as_uri().encode()
        self.c = lib.fmi2Instantiate(b"bench", CO_SIMULATION, md.guid.encode(), resources,
                                     ctypes.byref(self.callbacks), 0, 0)
        assert self.c, "fmi2Instantiate failed"
        assert lib.fmi2SetupExperiment(self.c, 0, 0.0, 0.0, 0, 0.0) == 0
        assert lib.fmi2EnterInitializationMode(self.c) == 0 and lib.fmi2ExitInitializationMode(self.c) == 0
        vr = {v.name: v.valueReference for v in md.modelVariables}
        self.vrs = (ctypes.c_uint * 6)(*[vr[n] for n in OUTPUT_NAMES])
        self.values = (ctypes.c_double * 6)()
        self.t = 0.0

    def run(self, steps: int, h: float) -> float:
        """Wall time (s) of `steps` doSteps of h s, each followed by a read of the outputs."""
        lib, c, vrs, values = self.lib, self.c, self.vrs, self.values
        t = self.t
        start = clock()
        for k in range(steps):
            assert lib.fmi2DoStep(c, t, h, 1) == 0
            t += h
            lib.fmi2GetReal(c, vrs, 6, values)
        elapsed = clock() - start
        self.t = t
        return elapsed

    def free(self):
        self.lib.fmi2FreeInstance(self.c)


#: The clock of the per-step figures (--clock).
clock = time.perf_counter


def direct(steps: int, h: float, scene=None) -> float:
    sim = wetcloth.Simulation(scene)
    t = 0.0
    start = clock()
    for k in range(steps):
        sim.advance(t + h - sim.time)
        t += h
        sim.outputs()
    return clock() - start


def best(values: list[float]) -> str:
    return f"{min(values) * 1e3:.3f} ms ({statistics.median(values) * 1e3:.3f})"


def per_step(values: list[float], steps: int) -> str:
    return f"{min(values) / steps * 1e6:.1f} us ({statistics.median(values) / steps * 1e6:.1f})"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs per figure; the best counts (default 5)")
    parser.add_argument("--steps", type=int, default=3000, help="1 ms communication steps per run (default 3000)")
    parser.add_argument("--native", type=Path, help="the native unit (default: build it)")
    parser.add_argument("--python", type=Path, help="pythonfmu's WetCloth.fmu (default: build it)")
    parser.add_argument("--scene", help="a scene file or preset built into both units and run (default: the towel)")
    parser.add_argument("--step", type=float, default=1e-3, help="communication step, s (default 0.001)")
    parser.add_argument("--clock", choices=("wall", "cpu"), default="wall", help="the per-step figures' clock")
    args = parser.parse_args(argv)
    h = args.step
    global clock
    clock = time.process_time if args.clock == "cpu" else time.perf_counter
    scene = None if args.scene is None else wetcloth.load_scene(args.scene)

    with tempfile.TemporaryDirectory(prefix="wetcloth_bench_native_") as tmp:
        tmp = Path(tmp)
        if args.scene is not None and args.native is None:
            print(f"native build with --scene {args.scene} (wall clock): ", end="", flush=True)
            for label in ("from nothing", "after another scene's unit"):
                for unit_object in (tmp / "objects").glob(f"{Path(VARIABLES_SOURCE).stem}-*.o"):
                    unit_object.unlink()  # the generated source compiles again, as for another scene
                start = time.perf_counter()
                build_native_fmu(tmp / "built.fmu", 2, build_dir=tmp / "objects", scene=args.scene)
                print(f"{label} {time.perf_counter() - start:.1f} s; ", end="", flush=True)
            print()
        native_fmu = args.native or build_native_fmu(tmp / "WetClothNative.fmu", 2, build_dir=tmp / "objects",
                                                     scene=args.scene)
        python_fmu = args.python or build_fmu(tmp / "WetCloth.fmu", 2, scene=args.scene)
        units = {}
        for label, fmu in (("native", native_fmu), ("pythonfmu", python_fmu)):
            directory = Path(fmpy.extract(str(fmu), unzipdir=str(tmp / label)))
            units[label] = (directory, fmpy.read_model_description(str(directory)))

        what = (f"default towel ({wetcloth.load_scene().nx} x {wetcloth.load_scene().ny})" if scene is None else
                f"scene {args.scene} ({wetcloth.Simulation(scene).model.topology.n} particles)")
        print(f"wetcloth {wetcloth.__version__}, {what}, {h * 1e3:g} ms communication steps, {args.clock} clock; "
              f"best of {args.repeat} (median)")
        print("\nstart, a new process: load + instantiate + initialize | to the end of the first doStep")
        for label, (directory, md) in units.items():
            ready, first = [], []
            for _ in range(args.repeat):
                done = subprocess.run([sys.executable, "-c", START, str(directory / "binaries" / "linux64" / "WetCloth.so"),
                                       md.guid, (directory / "resources").as_uri(), str(h)],
                                      capture_output=True, text=True, timeout=600)
                if done.returncode != 0:
                    raise RuntimeError(f"{label} start failed:\n{done.stderr[-3000:]}")
                record = json.loads(done.stdout.strip().splitlines()[-1])
                ready.append(record["ready"])
                first.append(record["first_step"])
            print(f"  {label:10s} {best(ready)} | {best(first)}")

        steps = args.steps
        native, python, pythonfmu, overhead, reads = [], [], [], [], []
        for _ in range(args.repeat):
            unit = Unit(*units["native"])
            native.append(unit.run(steps, h))
            # Beyond the physics: doStep of a zero step (checks, the fallback copy of the state), read.
            lib, c = unit.lib, unit.c
            start = clock()
            for _ in range(steps):
                lib.fmi2DoStep(c, unit.t, 0.0, 1)
            overhead.append(clock() - start)
            start = clock()
            for _ in range(steps):
                lib.fmi2GetReal(c, unit.vrs, 6, unit.values)
            reads.append(clock() - start)
            unit.free()
            python.append(direct(steps, h, scene))
        calls = []  # what a ctypes call costs by itself (a function that does nothing measurable)
        lib = ctypes.CDLL(str(units["native"][0] / "binaries" / "linux64" / "WetCloth.so"))
        lib.fmi2GetVersion.restype = ctypes.c_char_p
        for _ in range(args.repeat):
            start = clock()
            for _ in range(steps):
                lib.fmi2GetVersion()
            calls.append(clock() - start)
        for _ in range(max(1, args.repeat // 2)):
            unit = Unit(*units["pythonfmu"])
            pythonfmu.append(unit.run(steps, h))
            unit.free()

        print(f"\nper communication step ({steps} steps from t = 0: the landing)")
        print(f"  native / Simulation                    {min(native) / min(python):.3f}")
        print(f"  native unit: doStep + getReal          {per_step(native, steps)}")
        print(f"  wetcloth.Simulation: advance + outputs {per_step(python, steps)}")
        print(f"  pythonfmu WetCloth.fmu                 {per_step(pythonfmu, steps)}")
        print(f"  native minus Simulation                {(min(native) - min(python)) / steps * 1e6:.1f} us "
              "(the same core: the drivers' difference)")
        print("\nnative overhead beyond the physics, per doStep")
        print(f"  doStep of a zero step                  {per_step(overhead, steps)}")
        print(f"  getReal of the six outputs             {per_step(reads, steps)}")
        print(f"  (a ctypes call by itself               {per_step(calls, steps)})")
        print(f"  together, less two ctypes calls        "
              f"{(min(overhead) + min(reads) - 2 * min(calls)) / steps * 1e6:.1f} us")
    return 0


if __name__ == "__main__":
    sys.exit(main())
