"""Which build of the compiled core this process runs.

On x86-64 the core is built twice (CMakeLists.txt): for any x86-64 CPU (``wetcloth._core``) and for
x86-64-v3 (AVX2, FMA, BMI2: Intel from Haswell, AMD from Zen; ``wetcloth._core_x86_64_v3``), which
steps the hanging sheet 4-5 % faster.  Both give the same results bit for bit (no fast-math, no
fused multiply-adds: tests/test_core_builds.py).  :func:`load` imports the fastest build the CPU runs
and installs it as ``wetcloth._core``, so that every ``from wetcloth import _core`` gets it.  The
environment variable ``WETCLOTH_CORE`` (``baseline`` or ``x86-64-v3``) picks one instead.
"""

from __future__ import annotations

import importlib
import importlib.machinery
import importlib.util
import os
import sys
from pathlib import Path
from types import ModuleType

#: The variable that picks a build by name.
ENVIRONMENT = "WETCLOTH_CORE"
#: Each build's module, slowest first.
MODULES = {"baseline": "wetcloth._core", "x86-64-v3": "wetcloth._core_x86_64_v3"}
#: The CPU features (as numpy names them) x86-64-v3 needs, where numpy has no X86_V3 entry.
V3_FEATURES = ("AVX", "AVX2", "FMA3", "F16C")


def cpu_features() -> dict[str, bool]:
    """The CPU's features as numpy's run-time dispatch found them (empty off x86 or if numpy hides them)."""
    for name in ("numpy._core._multiarray_umath", "numpy.core._multiarray_umath"):
        try:
            return dict(importlib.import_module(name).__cpu_features__)
        except (ImportError, AttributeError):
            continue
    return {}


def runs(build: str, features: dict[str, bool]) -> bool:
    """Whether a CPU with these features runs `build`."""
    if build == "baseline":
        return True
    if "X86_V3" in features:
        return bool(features["X86_V3"])
    return all(features.get(name, False) for name in V3_FEATURES)


def installed(build: str) -> bool:
    """Whether `build`'s module was built and installed (x86-64-v3 only on x86-64)."""
    return importlib.util.find_spec(MODULES[build]) is not None


def runnable(build: str) -> bool:
    """Whether `build` is installed and this CPU runs it."""
    return installed(build) and runs(build, cpu_features())


def choose(requested: str | None, features: dict[str, bool], available) -> str:
    """The build to load: `requested` (the environment's value) if given, else the fastest that is
    `available` (a predicate on names) and that the CPU runs.  Raises ImportError, naming the variable and
    its values, for a name that is unknown, not installed or beyond the CPU."""
    if requested:
        if requested not in MODULES:
            raise ImportError(f"{ENVIRONMENT} must be one of {', '.join(map(repr, MODULES))} (or unset: the "
                              f"fastest this CPU runs), got {requested!r}")
        if not available(requested):
            raise ImportError(f"{ENVIRONMENT}={requested!r}: this install has no such build of the core "
                              f"(it is built on x86-64 only); unset {ENVIRONMENT} or set it to 'baseline'")
        if not runs(requested, features):
            raise ImportError(f"{ENVIRONMENT}={requested!r}: this CPU lacks x86-64-v3 (AVX, AVX2, FMA, F16C); "
                              f"unset {ENVIRONMENT} or set it to 'baseline'")
        return requested
    return [build for build in MODULES if available(build) and runs(build, features)][-1]


def load() -> ModuleType:
    """Import the chosen build and make it ``wetcloth._core``."""
    core = importlib.import_module(MODULES[chosen()])
    sys.modules["wetcloth._core"] = core
    sys.modules["wetcloth"]._core = core  # (as importing wetcloth._core itself would set it)
    return core


def chosen() -> str:
    """The name of the build :func:`load` picks: ``baseline`` or ``x86-64-v3``."""
    return choose(os.environ.get(ENVIRONMENT), cpu_features(), installed)


def running() -> str:
    """The name of the build this process runs (``import wetcloth`` loaded it)."""
    name = sys.modules["wetcloth._core"].__spec__.name
    return next(build for build, module in MODULES.items() if module == name)


def module_files() -> list[Path]:
    """Every installed build's module file, for packing the core into a unit that may run on any CPU."""
    folder = Path(sys.modules["wetcloth._core"].__file__).resolve().parent  # (import wetcloth loaded it)
    files = []
    for module in MODULES.values():
        spec = importlib.machinery.PathFinder.find_spec(module.rpartition(".")[2], [str(folder)])
        if spec is not None:
            files.append(Path(spec.origin).resolve())
    return files
