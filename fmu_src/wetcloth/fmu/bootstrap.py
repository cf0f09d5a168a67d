"""Which wetcloth a WetCloth FMU runs, found quickly and explained (the FMU's ``wetcloth_fmu_bootstrap.py``).

The builder copies this file to the FMU's ``resources/`` under that name; the slave script calls
``load_wetcloth`` before it imports anything of wetcloth.  Standard library only: it runs before
the host is known to have wetcloth's dependencies.

pythonfmu's binary runs the slave in the Python of the process that loads the FMU (fmpy,
libcosimpy, any Python master).  One wetcloth per process:

1. a wetcloth already imported there is used, with a warning if its files differ from the FMU's
   copy (its sources, and the compiled core it loaded);
2. else the copy inside the FMU (``resources/wetcloth``), with its compiled core: it needs no more
   than numpy from the host, and nothing is compiled at start.  It is imported through a finder
   placed first on ``sys.meta_path`` (``BundleFinder``), so that no installed wetcloth, not even an
   editable install whose own finder redirects ``wetcloth`` to a working tree, takes its place; a
   later ``import wetcloth`` in the host gets the same copy (one wetcloth per process).

Any failure to start (a dependency the host's Python lacks, named with how to install it; the
unit's copy failing to import in this host, its compiled core missing a name...) is logged on Python's
logger ``wetcloth.fmu`` (stderr unless the host configured logging), also while the master's FMI
logging is off: pythonfmu's binaries drop the exception's text, and pythonfmu3's logs nothing.
"""

from __future__ import annotations

import atexit
import ctypes
import hashlib
import importlib
import importlib.abc
import importlib.machinery
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


class BundleFinder(importlib.abc.MetaPathFinder):
    """Finds ``wetcloth`` and its submodules in the unit's own copy only (first on ``sys.meta_path``)."""

    def __init__(self, resources: Path) -> None:
        self.resources = resources

    def find_spec(self, fullname, path=None, target=None):
        if fullname != "wetcloth" and not fullname.startswith("wetcloth."):
            return None
        if fullname == "wetcloth":
            search = [str(self.resources)]
        else:
            parent = sys.modules.get(fullname.rpartition(".")[0])
            search = list(getattr(parent, "__path__", None) or [])
        spec = importlib.machinery.PathFinder.find_spec(fullname, search)
        if spec is None:  # not in the unit's copy: no other wetcloth's module may stand in
            raise ModuleNotFoundError(f"No module named {fullname!r} in this WetCloth FMU's copy of wetcloth "
                                      f"({self.resources / 'wetcloth'})", name=fullname)
        return spec


def _import_bundle(resources: Path):
    """``import wetcloth`` from the unit's ``resources/wetcloth``, whatever else is installed (``BundleFinder``)."""
    finder = BundleFinder(resources)
    sys.meta_path.insert(0, finder)
    try:
        return importlib.import_module("wetcloth")
    except BaseException:
        sys.meta_path.remove(finder)
        for name in [n for n in sys.modules if n == "wetcloth" or n.startswith("wetcloth.")]:
            del sys.modules[name]  # a half-imported copy would be taken for the process's wetcloth
        raise


def differences(module, manifest: dict) -> list[str]:
    """The files of the imported ``module`` (wetcloth) that differ from the unit's copy: the package's
    sources and every compiled core module it loaded (``_core*``), by SHA-256."""
    package = Path(module.__file__).parent
    found = sorted(rel for rel, value in manifest["package_files"].items()
                   if not _same_files(package, {rel: value}))
    bundle = manifest.get("bundle_files", {})
    for name, loaded in list(sys.modules.items()):
        if name.startswith("wetcloth._core") and getattr(loaded, "__file__", None):
            rel = Path(loaded.__file__).name
            if rel not in bundle or digest(Path(loaded.__file__)) != bundle[rel]:
                found.append(f"{rel} (compiled core)")
    return found


def missing_dependency(exc: ModuleNotFoundError, requires: list[str]) -> ImportError:
    """An ImportError (also logged) naming the module the host's Python lacks and how to install it."""
    wanted = next((r for r in requires if r.split(";")[0].replace("-", "_").lower().startswith(
        (exc.name or "").split(".")[0].lower())), exc.name)
    message = (f"WetCloth FMU cannot start: the Python that loads it ({sys.executable}, Python "
               f"{sys.version_info.major}.{sys.version_info.minor}) has no module {exc.name!r}. Install it there: "
               f"{sys.executable} -m pip install '{wanted}'  (docs/fmi.md lists what the unit needs)")
    LOG.error("%s", message)
    failure = ImportError(message, name=exc.name)
    failure.wetcloth_logged = True  # logged here: load_wetcloth passes it on as it is
    return failure


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
    of all, the unit's binary is made to exit safely (``release_at_exit``), also when this fails.
    Any failure is logged (``wetcloth.fmu``) and raised as an ImportError saying that the unit cannot
    start."""
    resources = resources.resolve()
    release_at_exit()
    if str(resources) in _LOADED:
        return _LOADED[str(resources)]
    try:
        manifest_path = resources / MANIFEST_NAME
        manifest = json.loads(manifest_path.read_text()) if manifest_path.exists() else None
        try:
            if "wetcloth" in sys.modules or manifest is None:
                module = importlib.import_module("wetcloth")
                changed = [] if manifest is None else differences(module, manifest)
                if changed:
                    LOG.warning("this WetCloth FMU runs the wetcloth already imported in this process (%s), whose "
                                "sources differ from the copy the FMU was built with (%s); results may differ "
                                "from that build's", Path(module.__file__).parent,
                                ", ".join(changed[:5]) + (f" and {len(changed) - 5} more" if len(changed) > 5 else ""))
            else:
                module = _import_bundle(resources)
        except ModuleNotFoundError as exc:
            if exc.name and exc.name.split(".")[0] == "wetcloth":
                raise
            raise missing_dependency(exc, manifest["requires"] if manifest else []) from None
        if manifest is not None:
            _check_variables(module, manifest, resources)
    except Exception as exc:
        message = str(exc) if getattr(exc, "wetcloth_logged", False) else (
            f"WetCloth FMU cannot start: {type(exc).__name__}: {exc} (the Python that loads it: {sys.executable}, "
            f"Python {sys.version_info.major}.{sys.version_info.minor}; the unit's resources: {resources})")
        if not getattr(exc, "wetcloth_logged", False):
            LOG.error("%s", message)
        failure = ImportError(message, name=getattr(exc, "name", None))
        failure.wetcloth_logged = True
        raise failure from exc
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
        failure = RuntimeError(message)
        failure.wetcloth_logged = True
        raise failure
