"""Build ``WetCloth.fmu`` (FMI 2.0, pythonfmu) or ``WetCloth3.fmu`` (FMI 3.0, pythonfmu3), extended at their seams.

pythonfmu's and pythonfmu3's ``FmuBuilder`` pack the slave script, project files and a
documentation folder; ``build_fmu`` stages what the unit needs:

* the slave script (``wetcloth_fmu_slave.py`` or ``wetcloth_fmu3_slave.py``, project-unique
  module names) and the bootstrap ``wetcloth_fmu_bootstrap.py`` (``bootstrap.py``);
* a copy of the wetcloth package with its compiled core (``_core``, built for this Python's version
  and platform), scene presets and exporter (``resources/wetcloth``), so the FMU runs with any
  such Python that has numpy (and pythonfmu);
* a manifest: the copy's file digests (by which the bootstrap names what differs in a wetcloth the
  host imported before the unit), the variable names (a wetcloth whose variables differ
  from the model description is refused) and the requirements (named when one is missing);
* with ``scene``: the scene's values as start values and its mesh file (``packed_scene``);
* ``documentation/index.html``, generated from the same variable list as the model description,
  and the icon (``model.png``; FMI 3.0: ``terminalsAndIcons/icon.png``).
"""

from __future__ import annotations

import hashlib
import html
import importlib.metadata
import importlib.util
import json
import shutil
import sys
import tempfile
import uuid
import zipfile
from pathlib import Path
from string import Template

import wetcloth
import wetcloth.fmu as fmu_package
from wetcloth import core_build
from wetcloth.files import whole_file
from wetcloth.fmu import MODEL_NAME, default_fmu_path, packed_scene
from wetcloth.fmu.bootstrap import MANIFEST_NAME, MODULE_NAME, bundle_digest, digest
from wetcloth.fmu.vocabulary import VariableSpec, fmi_unit_name, variable_specs

HERE = Path(__file__).resolve().parent
SLAVE_SCRIPTS = {2: HERE / "wetcloth_fmu_slave.py", 3: HERE / "wetcloth_fmu3_slave.py"}
DOCS = HERE / "docs"
#: Where the icon goes in the archive, by FMI version.
ICON_PATH = {2: "model.png", 3: "terminalsAndIcons/icon.png"}

#: FMI co-simulation capabilities written into ``modelDescription.xml``, by FMI version.
CAPABILITIES = {
    2: dict(canHandleVariableCommunicationStepSize=True, canGetAndSetFMUstate=True, canSerializeFMUstate=True,
            canBeInstantiatedOnlyOncePerProcess=False, canInterpolateInputs=False, needsExecutionTool=True),
    3: dict(canHandleVariableCommunicationStepSize=True, canGetAndSetFMUState=True, canSerializeFMUState=True,
            canBeInstantiatedOnlyOncePerProcess=False, needsExecutionTool=True),
}  # needsExecutionTool: a Python interpreter with numpy, see documentation/index.html

#: Subpackages of wetcloth the unit uses that an editable install keeps outside the package folder.
MAPPED_SUBPACKAGES = ("presets", "exporter")
#: What of the presets folder (the repository's ``models/``, which also holds built FMUs) is packed.
PRESET_PATTERNS = ("*.toml", "__init__.py")

_SKIP = shutil.ignore_patterns("__pycache__", "*.pyc")


def package_dir() -> Path:
    """The wetcloth package folder being packed."""
    return Path(wetcloth.__file__).resolve().parent


def _mapped_subpackages() -> dict[str, Path]:
    """Subpackages the unit needs that live outside the package folder (editable installs map them)."""
    found = {}
    for sub in MAPPED_SUBPACKAGES:
        spec = importlib.util.find_spec(f"wetcloth.{sub}")
        if spec is None or not spec.submodule_search_locations:
            continue
        location = Path(next(iter(spec.submodule_search_locations))).resolve()
        if package_dir() not in location.parents:
            found[sub] = location
    return found


def _files(folder: Path, patterns=("*",)) -> list[Path]:
    return sorted(p for pattern in patterns for p in folder.rglob(pattern) if p.is_file()
                  and "__pycache__" not in p.parts and p.suffix != ".pyc")


def source_files() -> list[Path]:
    """The files the FMU carries: the wetcloth package, its compiled core, presets and exporter (no caches)."""
    files = _files(package_dir())
    # the compiled core, one module per build (the unit's host loads the one its CPU runs)
    files += [module for module in core_build.module_files() if package_dir() not in module.parents]
    for sub, location in _mapped_subpackages().items():
        files += _files(location, PRESET_PATTERNS if sub == "presets" else ("*",))
    return files


def is_stale(fmu: str | Path) -> bool:
    """True when ``fmu`` is missing or older than any of the sources it is built from."""
    fmu = Path(fmu)
    if not fmu.exists():
        return True
    built = fmu.stat().st_mtime
    return any(p.stat().st_mtime > built for p in source_files())


def _stage_package(stage: Path) -> tuple[dict[str, str], dict[str, str]]:
    """Copy wetcloth with its mapped subpackages into ``stage``; digests of the package folder's own
    files (compared with a host's wetcloth folder) and of every bundled file."""
    bundle = stage / "wetcloth"
    shutil.copytree(package_dir(), bundle, ignore=_SKIP)
    package_files = {p.relative_to(bundle).as_posix(): digest(p) for p in _files(bundle)}
    for module in core_build.module_files():
        if not (bundle / module.name).exists():  # an editable install keeps them outside the package folder
            shutil.copy2(module, bundle / module.name)
    for sub, location in _mapped_subpackages().items():
        for p in _files(location, PRESET_PATTERNS if sub == "presets" else ("*",)):
            target = bundle / sub / p.relative_to(location)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(p, target)
    bundle_files = {p.relative_to(bundle).as_posix(): digest(p) for p in _files(bundle)}
    return package_files, bundle_files


def _requirements() -> list[str]:
    """wetcloth's installed requirements (named when a host lacks one), without the extras."""
    try:
        return [r for r in importlib.metadata.requires("wetcloth") or [] if "extra ==" not in r]
    except importlib.metadata.PackageNotFoundError:
        return []


def _range(spec: VariableSpec) -> str:
    if spec.min is None:
        return ""
    return f"{'> ' if spec.min_open else ''}{spec.min:g} .. {spec.max:g}"


def documentation_row(s: VariableSpec, meaning: str | None = None) -> str:
    """A variable's row of the documentation's table (HTML): name and shape, causality, type, unit, start value,
    range and ``meaning`` (default: its description)."""
    unit = fmi_unit_name(s.unit) or ""
    start = ("" if s.start is None else "(in the model description)" if s.variability == "constant"
             else repr(s.start) if s.type == "String" else f"{s.start:g}")
    shape = f" [{', '.join(map(str, s.dimensions))}]" if s.dimensions else ""
    cells = (s.name + shape, s.causality, s.type, unit, start, _range(s), s.description if meaning is None else meaning)
    return "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in cells) + "</tr>"


def documentation_html(specs: list[VariableSpec], fmi_version: int = 2) -> str:
    """``documentation/index.html``: what the unit models, its variables and what it needs to run."""
    rows = [documentation_row(s) for s in specs]
    template = Template((DOCS / "index.html.in").read_text(encoding="utf-8"))
    inputs = ", ".join(f"<code>{s.name}</code>" for s in specs if s.causality == "input")
    arrays = ", ".join(f"<code>{s.name}</code> [{', '.join(map(str, s.dimensions))}]" for s in specs if s.dimensions)
    return template.substitute(
        model=MODEL_NAME, version=html.escape(wetcloth.__version__), rows="\n".join(rows), inputs=inputs,
        python=f"{sys.version_info.major}.{sys.version_info.minor}", fmi=f"{fmi_version}.0",
        api=f"fmi{fmi_version}", icon="../" + ICON_PATH[fmi_version],
        builder={2: '<a href="https://github.com/NTNU-IHB/PythonFMU">pythonfmu</a>',
                 3: '<a href="https://github.com/StephenSmith25/PythonFMU3">pythonfmu3</a>'}[fmi_version],
        arrays="" if not arrays else (f"<li>The cloth mesh of the current step comes as array outputs: {arrays} "
                                      "(vertex <code>row * nx + col</code>, as in the exported frames); their "
                                      "sizes are the structural parameters <code>nx</code> and <code>ny</code>.</li>"),
    )


def _top_level(folder: Path, files: list[Path]) -> list[Path]:
    """The entries of ``folder`` that hold ``files`` (project files are copied whole, folders with their contents)."""
    return list(dict.fromkeys(folder / f.relative_to(folder).parts[0] for f in files))


def _pythonfmu_builder(fmi_version: int):
    """pythonfmu's (FMI 2.0) or pythonfmu3's (FMI 3.0) ``FmuBuilder``."""
    if fmi_version == 2:
        from pythonfmu import FmuBuilder
    else:
        from pythonfmu3 import FmuBuilder
    return FmuBuilder


#: The binaries folders (FMI 2.0 and 3.0 names) of a platform, by ``(sys.platform, machine)``.
PLATFORM_FOLDERS = {("linux", "x86_64"): {"linux64", "x86_64-linux"}, ("win32", "amd64"): {"win64", "x86_64-windows"},
                    ("darwin", "x86_64"): {"darwin64", "x86_64-darwin"}, ("darwin", "arm64"): {"aarch64-darwin"},
                    ("linux", "aarch64"): {"aarch64-linux"}}


def packed_platforms() -> set[str]:
    """The ``binaries/`` folders of the platform whose compiled core the unit packs (this Python's)."""
    import platform

    return PLATFORM_FOLDERS.get((sys.platform, platform.machine().lower()), set())


def _only_packed_platforms(built: Path, out: Path) -> Path:
    """A copy of the archive ``built`` at ``out`` without pythonfmu's binaries for platforms whose compiled core
    the unit does not carry (pythonfmu ships win64 and linux64 binaries, the core is this platform's only): a
    master on another platform then finds no binary for it, rather than one that cannot start."""
    keep = packed_platforms()
    with zipfile.ZipFile(built) as source, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as target:
        for info in source.infolist():
            parts = info.filename.split("/")
            if parts[0] == "binaries" and len(parts) > 2 and parts[1] not in keep:
                continue
            target.writestr(info, source.read(info))
    return out


def content_token(fmi_version: int, files: list[Path]) -> str:
    """The unit's GUID (FMI 3.0: instantiationToken): a UUID 5 of a digest of what it is built from
    (the slave script, the bootstrap, the manifest with every bundled file's digest and the variable
    names, the documentation), so that a rebuild of the same sources carries the same token and
    another build another (as the native units' tokens, ``native.py``)."""
    text = f"wetcloth-pythonfmu{fmi_version}:" + ",".join(f"{p.name}={digest(p)}" for p in files)
    return "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, hashlib.sha256(text.encode()).hexdigest())) + "}"


def build_fmu(out: str | Path | None = None, fmi_version: int = 2, scene: str | Path | None = None) -> Path:
    """Build the co-simulation unit (FMI ``fmi_version`` 2 or 3) at ``out`` (default
    ``default_fmu_path(fmi_version)``); return its path.  ``scene``: a scene file (or preset name) whose
    values become the start values, its mesh file packed into the resources (``packed_scene``)."""
    if fmi_version not in SLAVE_SCRIPTS:
        raise ValueError(f"FMI version must be one of {sorted(SLAVE_SCRIPTS)}, got {fmi_version!r}")
    packed = None if scene is None else packed_scene.pack(scene)
    out = Path(default_fmu_path(fmi_version) if out is None else out)
    out.parent.mkdir(parents=True, exist_ok=True)
    specs = variable_specs(fmi_version=fmi_version, packed=packed)
    slave = SLAVE_SCRIPTS[fmi_version]
    cached = slave.stem in sys.modules
    with tempfile.TemporaryDirectory(prefix="wetcloth_fmu_") as tmp:
        stage = Path(tmp)
        source = stage / "src"
        source.mkdir()
        script = source / slave.name
        shutil.copy2(slave, script)
        bootstrap = source / f"{MODULE_NAME}.py"
        shutil.copy2(HERE / "bootstrap.py", bootstrap)
        package_files, bundle_files = _stage_package(source)
        scene_files = [] if packed is None else packed_scene.write(packed, source)
        manifest = source / MANIFEST_NAME
        manifest.write_text(json.dumps({
            "wetcloth_version": wetcloth.__version__, "fmi_version": fmi_version,
            "variables": [s.name for s in specs], "requires": _requirements(),
            "bundle_digest": bundle_digest(bundle_files), "package_files": package_files,
            "bundle_files": bundle_files}, indent=1))
        docs = stage / "documentation"
        docs.mkdir()
        (docs / "index.html").write_text(documentation_html(specs, fmi_version), encoding="utf-8")
        saved_path = list(sys.path)
        fmu_package.BUILD_TOKEN = content_token(fmi_version, [script, bootstrap, manifest, docs / "index.html",
                                                              *scene_files])
        try:
            built = Path(_pythonfmu_builder(fmi_version).build_FMU(
                script, dest=stage / "fmu", project_files=[source / "wetcloth", manifest, bootstrap,
                                                           *_top_level(source, scene_files)],
                documentation_folder=docs, **CAPABILITIES[fmi_version]))
        finally:
            fmu_package.BUILD_TOKEN = None
            sys.path[:] = saved_path  # the builders put the script's folder first on sys.path
            if not cached:
                sys.modules.pop(slave.stem, None)  # let each loaded FMU import its own script
                sys.modules.pop(MODULE_NAME, None)
        built = _only_packed_platforms(built, stage / "unit.fmu")
        with zipfile.ZipFile(built, "a") as archive:
            archive.write(DOCS / "model.png", arcname=ICON_PATH[fmi_version])
        with whole_file(out) as tmp_out:
            shutil.copyfile(built, tmp_out)
    return out
