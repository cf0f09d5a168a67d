"""Build ``WetCloth.fmu`` with pythonfmu, extended at its seams.

pythonfmu's ``FmuBuilder`` packs the slave script, project files and a documentation folder;
``WetClothBuilder`` adds the FMU's ``model.png``.  ``build_fmu`` stages what the unit needs:

* the slave script ``wetcloth_fmu_slave.py`` (a project-unique module name);
* a copy of the wetcloth package with its scene presets (``resources/wetcloth``), so the FMU runs
  with any Python that has wetcloth's dependencies, and a manifest of the copy's file digests and
  of the variable names, by which the slave picks the host's identical wetcloth (keeping numba's
  kernel cache) and refuses a wetcloth whose variables differ from the model description;
* ``documentation/index.html``, generated from the same variable list as the model description.
"""

from __future__ import annotations

import hashlib
import html
import importlib.util
import json
import os
import shutil
import sys
import tempfile
import zipfile
from pathlib import Path
from string import Template

from pythonfmu import FmuBuilder

import wetcloth
from wetcloth.fmu.vocabulary import MODEL_NAME, VariableSpec, fmi_unit_name, variable_specs

HERE = Path(__file__).resolve().parent
SLAVE_SCRIPT = HERE / "wetcloth_fmu_slave.py"
MANIFEST_NAME = "wetcloth_fmu_manifest.json"
DOCS = HERE / "docs"
DEFAULT_OUT = Path("models") / f"{MODEL_NAME}.fmu"

#: FMI co-simulation capabilities written into ``modelDescription.xml``.
CAPABILITIES = dict(
    canHandleVariableCommunicationStepSize=True,
    canGetAndSetFMUstate=True,
    canSerializeFMUstate=True,
    canBeInstantiatedOnlyOncePerProcess=False,
    canInterpolateInputs=False,
    needsExecutionTool=True,  # a Python interpreter with numpy and numba, see documentation/index.html
)

#: Subpackages of wetcloth the unit uses that an editable install keeps outside the package folder.
MAPPED_SUBPACKAGES = ("presets", "exporter")
#: What of the presets folder (the repository's ``models/``, which also holds built FMUs) is packed.
PRESET_PATTERNS = ("*.toml", "__init__.py")

_SKIP = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc")


class WetClothBuilder(FmuBuilder):
    """pythonfmu's builder, plus the FMU's icon ``model.png`` at the archive root (FMI 2.0, 2.3)."""

    @staticmethod
    def build_FMU(script_file, dest=".", project_files=set(), documentation_folder=None, newargs=None,
                  icon=None, **options) -> Path:
        path = FmuBuilder.build_FMU(script_file, dest, project_files, documentation_folder, newargs, **options)
        if icon is not None:
            with zipfile.ZipFile(path, "a") as archive:
                archive.write(icon, arcname="model.png")
        return Path(path)


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
                  and "__pycache__" not in p.parts and p.suffix not in (".pyc", ".nbi", ".nbc"))


def source_files() -> list[Path]:
    """The files the FMU carries: the wetcloth package, its presets and exporter (no caches)."""
    files = _files(package_dir())
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


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _stage_package(stage: Path) -> dict[str, str]:
    """Copy wetcloth with its mapped subpackages into ``stage``; digests of the package folder's files.

    The digests cover the package folder only: the slave compares them with the host's wetcloth
    folder before importing anything, when the mapped subpackages cannot be located yet.
    """
    bundle = stage / "wetcloth"
    shutil.copytree(package_dir(), bundle, ignore=_SKIP)
    files = {p.relative_to(bundle).as_posix(): _digest(p) for p in sorted(bundle.rglob("*")) if p.is_file()}
    for sub, location in _mapped_subpackages().items():
        for p in _files(location, PRESET_PATTERNS if sub == "presets" else ("*",)):
            target = bundle / sub / p.relative_to(location)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(p, target)
    return files


def _range(spec: VariableSpec) -> str:
    if spec.min is None:
        return ""
    return f"{spec.min:g} .. {spec.max:g}"


def documentation_html(specs: list[VariableSpec]) -> str:
    """``documentation/index.html``: what the unit models, its variables and what it needs to run."""
    rows = []
    for s in specs:
        unit = fmi_unit_name(s.unit) or ""
        start = "" if s.start is None else repr(s.start) if s.type == "String" else f"{s.start:g}"
        cells = (s.name, s.causality, s.type, unit, start, _range(s), s.description)
        rows.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in cells) + "</tr>")
    template = Template((DOCS / "index.html.in").read_text(encoding="utf-8"))
    inputs = ", ".join(f"<code>{s.name}</code>" for s in specs if s.causality == "input")
    return template.substitute(
        model=MODEL_NAME, version=html.escape(wetcloth.__version__), rows="\n".join(rows), inputs=inputs,
        python=f"{sys.version_info.major}.{sys.version_info.minor}",
    )


def build_fmu(out: str | Path = DEFAULT_OUT) -> Path:
    """Build the FMI 2.0 co-simulation unit ``WetCloth.fmu`` at ``out``; return its path."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    specs = variable_specs()
    cached = "wetcloth_fmu_slave" in sys.modules
    with tempfile.TemporaryDirectory(prefix="wetcloth_fmu_") as tmp:
        stage = Path(tmp)
        script = stage / "src" / SLAVE_SCRIPT.name
        script.parent.mkdir()
        shutil.copy2(SLAVE_SCRIPT, script)
        files = _stage_package(stage / "src")
        manifest = stage / "src" / MANIFEST_NAME
        manifest.write_text(json.dumps(
            {"wetcloth_version": wetcloth.__version__, "variables": [s.name for s in specs], "files": files},
            indent=1))
        docs = stage / "documentation"
        docs.mkdir()
        (docs / "index.html").write_text(documentation_html(specs), encoding="utf-8")
        saved_path = list(sys.path)
        try:
            built = WetClothBuilder.build_FMU(
                script, dest=stage / f"{MODEL_NAME}.fmu", project_files=[stage / "src" / "wetcloth", manifest],
                documentation_folder=docs, icon=DOCS / "model.png", **CAPABILITIES,
            )
        finally:
            sys.path[:] = saved_path  # pythonfmu puts the script's folder first on sys.path
            if not cached:
                sys.modules.pop("wetcloth_fmu_slave", None)  # let each loaded FMU import its own script
        tmp_out = out.with_name(out.name + ".tmp")
        shutil.copyfile(built, tmp_out)
        os.replace(tmp_out, out)
    return out
