"""Which wetcloth a WetCloth FMU runs, found quickly and explained (the FMU's ``wetcloth_fmu_bootstrap.py``).

The builder copies this file to the FMU's ``resources/`` under that name; the slave script calls
``load_wetcloth`` before it imports anything of wetcloth.  Standard library only: it runs before
the host is known to have wetcloth's dependencies.

pythonfmu's binary runs the slave in the Python of the process that loads the FMU (fmpy,
libcosimpy, any Python master).  One wetcloth per process:

1. a wetcloth already imported there is used, with a warning if its sources differ from the FMU's;
2. else the host's installed wetcloth, if its sources are the FMU's (same SHA-256 digests);
3. else the copy inside the FMU (``resources/wetcloth``), with its compiled core: it needs no more
   than numpy from the host, and nothing is compiled at start.

A dependency the host's Python lacks is named in an ImportError and in Python's logging (stderr
unless the host configured logging), also while the master's FMI logging is off.
"""

from __future__ import annotations

import atexit
import ctypes
import hashlib
import importlib
import importlib.util
import json
import logging
import os
import sys
from pathlib import Path

LOG = logging.getLogger("wetcloth.fmu")
#: Written by the builder into the FMU's resources: digests of the bundled wetcloth, variable names...
MANIFEST_NAME = "wetcloth_fmu_manifest.json"
#: This file's module name inside the FMU (beside the slave script, importable before wetcloth).
MODULE_NAME = "wetcloth_fmu_bootstrap"

_LOADED: dict[str, object] = {}  # resources folder -> the wetcloth module it runs
_RELEASED: dict[str, ctypes.CDLL] = {}  # binaries whose finalizePythonInterpreter runs at Python's exit


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def bundle_digest(files: dict[str, str]) -> str:
    """One digest of a bundle from its files' relative paths and digests."""
    return hashlib.sha256(json.dumps(sorted(files.items())).encode()).hexdigest()


def _same_files(folder: Path, files: dict[str, str]) -> bool:
    try:
        return all(digest(folder / rel) == value for rel, value in files.items())
    except OSError:
        return False


def _path_without(resources: Path) -> list[str]:
    return [p for p in sys.path if Path(p or ".").resolve() != resources]


def _host_wetcloth(resources: Path, package_files: dict[str, str]) -> bool:
    """Whether an installed wetcloth (outside the FMU) has the FMU's package sources."""
    saved = list(sys.path)
    try:
        sys.path[:] = _path_without(resources)
        spec = importlib.util.find_spec("wetcloth")
    finally:
        sys.path[:] = saved
    return bool(spec and spec.submodule_search_locations) and _same_files(
        Path(next(iter(spec.submodule_search_locations))), package_files)


def _import(path: list[str]):
    """``import wetcloth`` with ``path`` as ``sys.path`` (restored afterwards)."""
    saved = list(sys.path)
    try:
        sys.path[:] = path
        return importlib.import_module("wetcloth")
    finally:
        sys.path[:] = saved


def missing_dependency(exc: ModuleNotFoundError, requires: list[str]) -> ImportError:
    """An ImportError (also logged) naming the module the host's Python lacks and how to install it."""
    wanted = next((r for r in requires if r.split(";")[0].replace("-", "_").lower().startswith(
        (exc.name or "").split(".")[0].lower())), exc.name)
    message = (f"WetCloth FMU cannot start: the Python that loads it ({sys.executable}, Python "
               f"{sys.version_info.major}.{sys.version_info.minor}) has no module {exc.name!r}. Install it there: "
               f"{sys.executable} -m pip install '{wanted}'  (docs/fmi.md lists what the unit needs)")
    LOG.error("%s", message)
    return ImportError(message, name=exc.name)


class _LibraryInfo(ctypes.Structure):
    """The first two fields of the C library's ``struct dl_phdr_info``: load address, file name."""
    _fields_ = [("address", ctypes.c_void_p), ("name", ctypes.c_char_p)]


_VISIT = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(_LibraryInfo), ctypes.c_size_t, ctypes.c_void_p)


def loaded_libraries() -> list[str]:
    """The file names of the shared libraries this process has loaded, as they were loaded
    (``dl_iterate_phdr``); empty where the C library has no such function."""
    names = []

    def visit(info, size, data):
        if info.contents.name:
            names.append(os.fsdecode(info.contents.name))
        return 0

    iterate = getattr(ctypes.CDLL(None), "dl_iterate_phdr", None)
    if iterate is not None:
        iterate(_VISIT(visit), None)
    return names


def _unit_binary(name: str) -> bool:
    """Whether the library file ``name`` is a WetCloth unit's binary: ``binaries/<platform>/`` of an
    unpacked FMU whose resources hold this project's manifest."""
    path = Path(name)
    return path.parent.parent.name == "binaries" and (path.parents[2] / "resources" / MANIFEST_NAME).is_file()


def release_at_exit() -> None:
    """Have Python's exit call ``finalizePythonInterpreter`` of every WetCloth unit binary this
    process has loaded, before the binary's own exit handlers run (they release its interpreter
    helper twice and corrupt the heap: ``wetcloth.fmu.guard``, item 3).

    The library is opened once more here, so it stays loaded when its host frees the unit (its
    exit handlers would run then, as harmful).  All loaded binaries are looked at, not only those
    of the unit whose script calls this: for a second unit (another unpacked FMU) pythonfmu runs its
    script in the namespace of the first's, whose ``__file__`` names the first unit's folder, and
    pythonfmu3 does not run it again at all (so each unit's ``__init__`` calls this too).  Other
    FMUs' binaries are not touched (opened here, they too would stay loaded after their host frees
    them)."""
    if not sys.orig_argv or os.name != "posix":  # the binary started this interpreter, or Windows (DllMain)
        return
    for name in loaded_libraries():
        if name in _RELEASED or not _unit_binary(name):
            continue
        try:  # RTLD_NOLOAD: only a library this process has loaded
            library = ctypes.CDLL(name, mode=os.RTLD_NOLOAD | os.RTLD_LAZY)
            finalize = library.finalizePythonInterpreter
        except (OSError, AttributeError):
            continue
        finalize.argtypes, finalize.restype = [], None
        _RELEASED[name] = library
        atexit.register(finalize)


def load_wetcloth(resources: Path):
    """The wetcloth module this FMU runs (see the module docstring), imported if needed.  First
    of all, the unit's binary is made to exit safely (``release_at_exit``), also when this fails."""
    resources = resources.resolve()
    release_at_exit()
    if str(resources) in _LOADED:
        return _LOADED[str(resources)]
    manifest_path = resources / MANIFEST_NAME
    manifest = json.loads(manifest_path.read_text()) if manifest_path.exists() else None
    try:
        if "wetcloth" in sys.modules or manifest is None:
            module = importlib.import_module("wetcloth")
            package = Path(module.__file__).parent
            if manifest is not None and not _same_files(package, manifest["package_files"]):
                LOG.warning("this WetCloth FMU runs the wetcloth already imported in this process (%s), whose "
                            "sources differ from the copy the FMU was built with; results may differ from that "
                            "build's", package)
        elif _host_wetcloth(resources, manifest["package_files"]):
            module = _import(_path_without(resources))
        else:
            module = _import([str(resources)] + _path_without(resources))
    except ModuleNotFoundError as exc:
        if exc.name and exc.name.split(".")[0] == "wetcloth":
            raise
        raise missing_dependency(exc, manifest["requires"] if manifest else []) from None
    if manifest is not None:
        _check_variables(module, manifest, resources)
    _LOADED[str(resources)] = module
    return module


def _check_variables(module, manifest: dict, resources: Path) -> None:
    """Refuse a wetcloth whose FMU variables differ from those the model description lists (with the
    parameters of the colliders of a scene built into the unit, in ``resources``)."""
    from wetcloth.fmu import packed_scene
    from wetcloth.fmu.vocabulary import variable_specs

    packed = packed_scene.load(resources)
    names = [s.name for s in variable_specs(fmi_version=manifest["fmi_version"], packed=packed)]
    if names != manifest["variables"]:
        message = (f"this WetCloth FMU was built for the variables {manifest['variables']}, but the wetcloth imported "
                   f"from {Path(module.__file__).parent} defines {names}; rebuild it with `wetcloth build-fmu`")
        LOG.error("%s", message)
        raise RuntimeError(message)
