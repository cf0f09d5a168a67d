"""Build the native WetCloth unit: the co-simulation FMU compiled from wetcloth's C++ core, with no Python in it.

    wetcloth build-fmu --native              # models/WetClothNative.fmu  (FMI 2.0)
    wetcloth build-fmu --native --fmi 3      # models/WetClothNative3.fmu (FMI 3.0, the mesh as array outputs)
    wetcloth build-fmu --native --scene bucket   # a scene's start values, colliders and keys built in

The unit has the model name, variables, value references, units, ranges and model structure of the
pythonfmu units (``WetCloth.fmu``, ``WetCloth3.fmu``): its ``modelDescription.xml`` is made by the same
code (``description.py``, ``description3.py`` on pythonfmu's and pythonfmu3's model-description writers),
and the C++ side reads the same vocabulary through a generated source
(``wetcloth_fmu_variables.cpp``: every variable in value-reference order with its Scene field, range,
start value and the texts of its messages (a collider's number field: its place in the colliders' rows,
which the unit makes from the values set); with ``--scene``, the scene's colliders and keys as the arrays
the Python model hands the core, and a cloth from a mesh file as the arrays of its structure,
``native_mesh.py``, with its faces and UVs for the FMI 3.0 unit's constant outputs).  What it packs:

* ``binaries/linux64/WetCloth.so`` (FMI 3.0: ``binaries/x86_64-linux/``): ``fmu_src/core/src/**/*.cpp``,
  ``fmu_src/core/fmu/unit.cpp`` and ``fmi2.cpp`` (``fmi3.cpp``) compiled by the system C++ compiler
  (``$CXX``, else ``g++`` or ``c++``) for baseline x86-64, with the core's value-preserving flags (no
  fast-math, no contraction into fused multiply-adds: the Python extension's flags), libstdc++ and libgcc
  linked in statically and every symbol hidden but the FMI functions;
* ``sources/``: the same sources, the FMI headers and ``buildDescription.xml`` (FMI 3.0's layout; the
  FMI 2.0 model description lists them too), so that another tool (``fmpy.build.build_platform_binary``)
  compiles the unit elsewhere with ``sources/`` as the one include folder;
* ``documentation/index.html``: the variables, what the unit needs (nothing) and what it does not do
  (no mesh frames: ``mesh_output_dir`` must stay empty);
* the icon (``model.png``; FMI 3.0: ``terminalsAndIcons/icon.png``).

The C++ sources are those of the checkout wetcloth is installed from (``pip install -e .``): a wheel does
not carry them, and the build is refused there.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses
import functools
import hashlib
import html
import os
import platform
import re
import shutil
import subprocess
import tempfile
import time
import uuid
import zipfile
from pathlib import Path
from string import Template
from xml.etree import ElementTree

from tqdm.auto import tqdm

import wetcloth
from wetcloth.files import new_temporary, whole_file
from wetcloth.fmu import MODEL_NAME, native_mesh, packed_scene
from wetcloth.fmu.vocabulary import (MESH_CONSTANTS, MESH_FORMAT_RANGE, MESH_FORMATS, MESH_OUTPUTS, STEP_OUTPUTS,
                                     VariableSpec, variable_specs)
from wetcloth.progress import SHOW_AFTER

#: The order of the outputs in the core's ``record_outputs`` row (``stepping.hpp``).
CORE_OUTPUTS = ("centroid_x", "centroid_y", "centroid_z", "depth", "wet_mass", "water_mass")
#: Compiler flags: C++17, optimised, baseline x86-64, and the core's flags that keep values the same
#: whatever the compiler vectorises (CMakeLists.txt: no fast-math, no fused multiply-adds); the FMI
#: functions are the only symbols with default visibility.
CXX_FLAGS = ("-std=c++17", "-O3", "-DNDEBUG", "-fno-math-errno", "-ffp-contract=off", "-march=x86-64", "-fPIC",
             "-fvisibility=hidden", "-fvisibility-inlines-hidden")
#: Link flags: a shared object with libstdc++ and libgcc inside (none of their symbols exported), no
#: undefined symbol left, stripped.
LINK_FLAGS = ("-shared", "-static-libstdc++", "-static-libgcc", "-Wl,--exclude-libs,ALL", "-Wl,-z,defs",
              "-Wl,-O1", "-s")
#: Why a native unit takes only the value it was built with for a free-text parameter (``cloth_mesh``,
#: ``pinned_vertices``): '' without --scene, else the scene's.
NO_TEXT_REASON = ("the native unit runs the cloth and the pins built into it: build it with --scene from a scene "
                  "with another cloth_mesh or pinned_vertices, or use WetCloth.fmu")
#: The generated source of a unit: its variable table and what it is built with (``fmu/unit_data.hpp``).
VARIABLES_SOURCE = "wetcloth_fmu_variables.cpp"
#: The unit's fixed sources beside the generated one: compiled once for every unit, whatever its scene.
UNIT_FILES = ("unit.hpp", "unit_data.hpp", "unit.cpp", "instance.hpp")
#: Binary folder in the archive, by FMI version.
PLATFORM_FOLDER = {2: "linux64", 3: "x86_64-linux"}
#: What the model description says of the unit.
DESCRIPTION = ("Mass-spring cloth on water with buoyancy, drag and Buras-law absorption{mesh} (wetcloth, FMI {fmi}.0 "
               "co-simulation compiled from its C++ core: needs no Python; writes no mesh frames)")
CAPABILITIES = {
    2: dict(canHandleVariableCommunicationStepSize=True, canGetAndSetFMUstate=True, canSerializeFMUstate=True,
            canBeInstantiatedOnlyOncePerProcess=False, canInterpolateInputs=False, needsExecutionTool=False),
    3: dict(canHandleVariableCommunicationStepSize=True, canGetAndSetFMUState=True, canSerializeFMUState=True,
            canBeInstantiatedOnlyOncePerProcess=False, needsExecutionTool=False),
}
#: Where the icon goes in the archive, by FMI version (as builder.py puts it).
ICON_PATH = {2: "model.png", 3: "terminalsAndIcons/icon.png"}
DOCS = Path(__file__).resolve().parent / "docs"


class NativeBuildError(OSError):
    """The native unit cannot be built here (no C++ compiler, no core sources, a compile error...)."""


def native_fmu_path(fmi_version: int = 2) -> Path:
    """Where ``wetcloth build-fmu --native`` writes the unit: ``models/WetClothNative.fmu`` (FMI 2.0) or
    ``models/WetClothNative3.fmu`` (FMI 3.0), relative to the current folder."""
    if fmi_version not in (2, 3):
        raise ValueError(f"FMI version must be 2 or 3, got {fmi_version!r}")
    return Path("models") / f"{MODEL_NAME}Native{'' if fmi_version == 2 else fmi_version}.fmu"


# ----------------------------------------------------------------------------------------- what to compile
def core_dir() -> Path:
    """The C++ core's folder (``fmu_src/core`` beside the wetcloth package of an editable install)."""
    core = Path(wetcloth.__file__).resolve().parent.parent / "core"
    if not ((core / "include" / "wetcloth" / "core.hpp").is_file() and (core / "src").is_dir()
            and (core / "fmu" / "unit.cpp").is_file()):
        raise NativeBuildError(
            f"the native FMU is compiled from wetcloth's C++ core (fmu_src/core), which this installation of "
            f"wetcloth ({Path(wetcloth.__file__).resolve().parent}) does not have: a wheel carries no C++ sources. "
            "Install wetcloth from a source checkout (pip install -e .) to build it.")
    return core


def find_compiler() -> str:
    """The C++ compiler: ``$CXX`` if set, else ``g++`` or ``c++`` on the PATH."""
    wanted = os.environ.get("CXX")
    candidates = [wanted] if wanted else ["g++", "c++"]
    for name in candidates:
        found = shutil.which(name)
        if found:
            return found
    if wanted:
        raise NativeBuildError(f"the C++ compiler CXX={wanted!r} is not found; set CXX to a C++17 compiler "
                               "(g++ 9 or newer) or unset it to use g++")
    raise NativeBuildError("no C++ compiler found (g++ or c++ on the PATH, or $CXX): the native FMU is compiled "
                           "from C++17 sources; install one (Debian/Ubuntu: apt-get install g++) or set CXX")


def _sources(core: Path, fmi_version: int) -> list[tuple[Path, str]]:
    """(file, name under ``sources/``) of every file the unit is compiled from, headers included; the
    generated source is added by the caller."""
    files = []
    for path in sorted((core / "include").rglob("*.hpp")):
        files.append((path, path.relative_to(core / "include").as_posix()))
    for path in sorted((core / "src").rglob("*.cpp")):
        files.append((path, "core/" + path.relative_to(core / "src").as_posix()))
    fmu = core / "fmu"
    for name in (*UNIT_FILES, f"fmi{fmi_version}.cpp"):
        files.append((fmu / name, f"fmu/{name}"))
    headers = sorted(fmu.glob(f"fmi{fmi_version}*.h"))
    if not headers:
        raise NativeBuildError(f"the FMI {fmi_version}.0 headers are missing from {fmu}")
    files += [(path, f"fmu/{path.name}") for path in headers]
    return files


# ----------------------------------------------------------------------------------------- the variable table
def _c_string(text: str) -> str:
    """A C string literal of ``text`` (UTF-8 as it is)."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _c_double(value) -> str:
    text = repr(float(value))
    return text if any(c in text for c in ".einf") else text + ".0"


def _c_array(name: str, kind: str, values) -> str:
    """The C++ array ``NAME[]`` of ``values`` ("double", "Index" or "Column" elements, with a trailing 0: C++ has
    no empty arrays) and its length ``NAME_SIZE``."""
    import numpy as np

    values = np.ascontiguousarray(values).ravel()
    text = ", ".join(_c_double(v) if kind == "double" else str(int(v)) for v in values)
    return (f"extern const std::size_t {name}_SIZE = {values.size};\n"
            f"extern const {kind} {name}[] = {{{text}{', ' if text else ''}0}};")


#: The fixtures' arrays in the generated source (``unit.cpp``'s scene_fixtures): C++ name, element type, and
#: where each comes from: the collider rows, a ColliderMeshes field (``collider_meshes``), the grip keys, the
#: collider keys and their k in the scene.
FIXTURE_ARRAYS = (("SCENE_COLLIDERS", "double", "rows"), ("SCENE_MESH_HEADERS", "double", "headers"),
                  ("SCENE_MESH_VERTICES", "double", "vertices"), ("SCENE_FACE_NORMALS", "double", "face_normals"),
                  ("SCENE_EDGE_NORMALS", "double", "edge_normals"), ("SCENE_VERTEX_NORMALS", "double", "vertex_normals"),
                  ("SCENE_MESH_TRIANGLES", "Index", "triangles"), ("SCENE_CELL_START", "Index", "cell_start"),
                  ("SCENE_CELL_ITEMS", "Index", "cell_items"), ("SCENE_GRIP_KEYS", "double", "grip_keys"),
                  ("SCENE_COLLIDER_KEYS", "double", "collider_keys"),
                  ("SCENE_COLLIDER_KEY_NUMBERS", "Index", "collider_key_numbers"))


def fixtures_source(scene=None, cloth: dict | None = None) -> str:
    """The C++ arrays of what a scene holds beside its variables (``Scene.colliders``, ``Scene.grip_keys``),
    as the Python model hands them to the core (``model.py``), for ``unit.cpp``'s scene_fixtures: each
    ``NAME[]`` (with a trailing 0: C++ has no empty arrays) and its length ``NAME_SIZE``; none without a
    ``scene`` (a ``wetcloth.Scene``); and a cloth from a mesh file, ``cloth`` (``native_mesh.cloth_arrays``
    of the scene; None: the grid)."""
    import numpy as np

    from wetcloth.collider_meshes import meshes_of, no_meshes
    from wetcloth.scene import collider_key_order, collider_key_rows, grip_key_rows

    rows, meshes = meshes_of(scene.colliders) if scene is not None else (np.zeros(0), no_meshes())
    keys = scene.collider_keys if scene is not None else ()
    sources = dict(meshes._asdict(), rows=rows, grip_keys=grip_key_rows(scene.grip_keys if scene is not None else ()),
                   collider_keys=collider_key_rows(keys),
                   collider_key_numbers=[j + 1 for j in collider_key_order(keys)])  # each row's k: collider_key<k>
    lines = [_c_array(name, kind, sources[source]) for name, kind, source in FIXTURE_ARRAYS]
    lines.append(native_mesh.cloth_source(cloth, _c_array, _c_double, _c_string))
    lines.append(native_mesh.pins_source(scene, _c_array, _c_double, _c_string))
    return "\n".join(lines)


#: Why a native unit takes only the scene's position for a mesh collider.
PLACED_MESH_REASON = ("the native unit's mesh colliders are built in where the scene puts them: build it with "
                      "--scene from a scene that puts it elsewhere, or use WetCloth.fmu")


def placed_meshes(scene) -> dict:
    """The ranges of the native unit's mesh colliders' x, y, z (its compiled arrays hold their vertices where the
    scene puts them): the scene's value alone, as ``native_mesh.fixed_ranges`` gives them (low, high, low open,
    text); none without a ``scene``."""
    ranges = {}
    for k, collider in enumerate(scene.colliders if scene is not None else (), 1):
        if collider.shape == "mesh":
            for c in "xyz":
                value = getattr(collider, c)
                ranges[f"collider{k}_{c}"] = (value, value, False, f"{value!r} ({PLACED_MESH_REASON})")
    return ranges


def _c_range(md: dict, name: str, text: str, fixed: dict) -> tuple[str, str, str, str, str]:
    """The C texts of a number variable's range (ranged, lo, hi, lo open, its text): from its field's metadata
    ``md`` and range ``text``, or ``fixed[name]`` (low, high, low open, text) where the unit allows less."""
    if name in fixed:
        low, high, low_open, text = fixed[name]
        return "true", _c_double(low), _c_double(high), str(bool(low_open)).lower(), _c_string(text)
    return "true", _c_double(md["lo"]), _c_double(md["hi"]), str(bool(md["lo_open"])).lower(), _c_string(text)


def variables_source(specs: list[VariableSpec], fmi_version: int, token: str = "", fixtures: str = "",
                     fixed: dict | None = None) -> str:
    """The generated C++ table of the unit's variables (value reference = index), with compile-time
    checks that ``model.hpp``'s Scene, its choices and inputs are those of ``wetcloth.scene``, and the
    scene's ``fixtures`` (``fixtures_source``).  A free-text parameter takes its start value alone;
    ``fixed``: the ranges a built-in mesh allows instead of Python's (``native_mesh.fixed_ranges``)."""
    from wetcloth.fmu.description3 import dimension_sources
    from wetcloth.scene import COLLIDER_FIELDS, INPUT, PARAMETERS, describe_range
    from wetcloth.simulation import OUTPUT_NAMES

    if tuple(OUTPUT_NAMES) != CORE_OUTPUTS:
        raise NativeBuildError(f"the outputs {OUTPUT_NAMES} are not in the order of the core's record_outputs "
                               f"{CORE_OUTPUTS}: update wetcloth/fmu/native.py and stepping.cpp together")
    structural = dimension_sources(specs) if fmi_version == 3 else set()
    fixed = fixed or {}
    rows, checks, texts = [], [], []
    constants = {"faces": _c_array("CONSTANT_FACES", "Index", []), "uv": _c_array("CONSTANT_UV", "double", [])}
    for vr, spec in enumerate(specs):
        real = integer = "nullptr"
        choices, count, start_text = "nullptr", "0", "nullptr"
        ranged, lo, hi, lo_open, range_text = "false", "0.0", "0.0", "false", '""'
        start, slot = "0.0", "-1"
        causality = {"parameter": "PARAMETER", "input": "INPUT", "output": "OUTPUT",
                     "independent": "INDEPENDENT"}[spec.causality]
        if spec.name in structural:
            causality = "STRUCTURAL_PARAMETER"
        kind = {"Real": "REAL", "Integer": "INTEGER", "String": "STRING", "UInt64": "UINT64"}[spec.type]
        if spec.collider:  # a collider's number field: its place in the colliders' rows (colliders.hpp)
            role, field_name = "COLLIDER", spec.name.split("_", 1)[1]
            slot = f"{spec.collider - 1} * COLLIDER_COLUMNS + C_{field_name.upper()}"
            field = COLLIDER_FIELDS[field_name]
            ranged, lo, hi, lo_open, range_text = _c_range(field.metadata, spec.name,
                                                           describe_range(field, spec.name), fixed)
            start = _c_double(spec.start)
        elif spec.scene:
            role = "SCENE"
            field = PARAMETERS[spec.name]
            md = field.metadata
            range_text = _c_string(describe_range(field))
            if spec.type == "Real":
                real = f"&Scene::{spec.name}"
            else:
                integer = f"&Scene::{spec.name}"
            if spec.type == "String":
                choices = f'scene_choices("{spec.name}").names'
                count = f'scene_choices("{spec.name}").count'
                start_text = _c_string(spec.start)
                allowed = md["choices"] or ("",)  # free text (a mesh file, pins by name): only '' natively
                if md["text"]:  # its one value: the start (the built-in mesh and pins)
                    range_text = _c_string(f"{spec.start!r} ({NO_TEXT_REASON})")
                    choices, count = f"TEXT_{spec.name.upper()}", "1"
                    texts.append(f"constexpr const char* TEXT_{spec.name.upper()}[] = {{{_c_string(spec.start)}}};")
                names = " && ".join(f'same_text(scene_choices("{spec.name}").names[{k}], {_c_string(c)})'
                                    for k, c in enumerate(allowed))
                checks.append(f'static_assert(scene_choices("{spec.name}").count == {len(allowed)} && {names},\n'
                              f'              "model.hpp: the choices of {spec.name} are not those of wetcloth.scene");')
            else:
                ranged, lo, hi, lo_open, range_text = _c_range(md, spec.name, describe_range(field), fixed)
                start = _c_double(spec.start)
            is_input = md["fmu"] == INPUT
            checks.append(f'static_assert({"" if is_input else "!"}scene_input("{spec.name}"), '
                          f'"model.hpp: {spec.name} is {"" if is_input else "not "}an input in wetcloth.scene");')
        elif spec.name == "mesh_output_dir":
            role, start_text = "MESH_OUTPUT_DIR", _c_string(spec.start)
            range_text = _c_string("'' (empty: this unit writes no mesh frames)")
        elif spec.name == "mesh_format":
            role, start_text, range_text = "MESH_FORMAT", _c_string(spec.start), _c_string(MESH_FORMAT_RANGE)
            choices, count = "MESH_FORMATS", str(len(MESH_FORMATS))
        elif spec.name in STEP_OUTPUTS:
            role = spec.name.upper()
        elif spec.causality == "output" and not spec.dimensions:
            if spec.name not in CORE_OUTPUTS:
                raise NativeBuildError(f"output {spec.name!r} is not one the core computes ({', '.join(CORE_OUTPUTS)})")
            role, slot = "OUTPUT", str(CORE_OUTPUTS.index(spec.name))
        elif spec.name in MESH_OUTPUTS and spec.name in ("positions", "wetness"):
            role = spec.name.upper()
        elif spec.name in MESH_CONSTANTS:
            role = spec.name.upper()
            constants[spec.name] = _c_array(f"CONSTANT_{role}", "double" if spec.type == "Real" else "Index", spec.start)
        elif spec.causality == "independent":
            role = "TIME"
        else:
            raise NativeBuildError(f"variable {spec.name!r} ({spec.causality}) is one the native unit does not know: "
                                   "teach fmu_src/core/fmu/unit.cpp and wetcloth/fmu/native.py about it")
        rows.append(f"    // {vr}: {spec.name}\n"
                    f"    {{{_c_string(spec.name)}, Type::{kind}, Causality::{causality}, Role::{role}, {real}, {integer}, "
                    f"{slot}, {start}, {start_text}, {ranged}, {lo}, {hi}, {lo_open}, {range_text}, {choices}, {count}}},")
    scene_names = [name for name in PARAMETERS]
    field_checks = "\n".join(f'static_assert(same_text(SCENE_FIELDS[{k}], {_c_string(name)}), '
                             f'"model.hpp: Scene field {k} is not wetcloth.scene\'s {name}");'
                             for k, name in enumerate(scene_names))
    formats = ", ".join(_c_string(f) for f in MESH_FORMATS)
    return f"""\
// Generated by wetcloth.fmu.native (wetcloth {wetcloth.__version__}) from wetcloth.fmu.vocabulary: the variables
// of the FMI {fmi_version}.0 unit in value-reference order (the index), as the pythonfmu units number them.
// Do not edit: `wetcloth build-fmu --native` writes it again.  What it defines, fmu/unit_data.hpp declares.
#include "fmu/unit.hpp"
#include "fmu/unit_data.hpp"
#include "wetcloth/stepping.hpp"

namespace wc::fmu {{

namespace {{
constexpr const char INSTANTIATION_TOKEN[] = {_c_string(token)};
constexpr const char* MESH_FORMATS[] = {{{formats}}};
{chr(10).join(texts)}

constexpr Variable VARIABLES[] = {{
{chr(10).join(rows)}
}};
}}  // namespace

const Variable* variables() {{ return VARIABLES; }}
std::size_t variable_count() {{ return sizeof(VARIABLES) / sizeof(VARIABLES[0]); }}
const char* instantiation_token() {{ return INSTANTIATION_TOKEN; }}
int fmi_version() {{ return {fmi_version}; }}

// The scene's colliders and grip keys (none unless built with --scene).
{fixtures or fixtures_source()}

// The FMI 3.0 constant array outputs: a mesh cloth's faces and UVs (none unless built with --scene of one).
{chr(10).join(constants.values())}

// model.hpp's Scene, its inputs and choices are wetcloth.scene's (a parameter added in Python must be ported).
static_assert(SCENE_FIELD_COUNT == {len(scene_names)}, "model.hpp's Scene does not have the {len(scene_names)} fields of wetcloth.scene");
{field_checks}
{chr(10).join(checks)}
static_assert(OUTPUT_COUNT == {len(CORE_OUTPUTS)}, "the core's outputs are not the unit's");

}}  // namespace wc::fmu
"""


# ----------------------------------------------------------------------------------------- descriptions
def _start_getter(spec: VariableSpec):
    return functools.partial(lambda value: value, spec.values if spec.variability == "constant" else spec.start)


def fixed_spec(spec: VariableSpec, fixed: tuple) -> VariableSpec:
    """``spec`` with the range a native unit's built-in mesh fixes (``native_mesh.fixed_ranges``: lo, hi, lo_open,
    text), its description's "allowed:" saying the same as its declared min and max."""
    lo, hi, lo_open, text = fixed
    description = re.sub(r"\(allowed: .*\)$", lambda _: f"(allowed: {text})", spec.description)
    return dataclasses.replace(spec, min=lo, max=hi, min_open=lo_open, description=description)


def model_description(specs: list[VariableSpec], fmi_version: int, token: str, sources: list[str]) -> bytes:
    """``modelDescription.xml``: pythonfmu's (pythonfmu3's) writer with wetcloth's extensions (units, ranges,
    dependencies; ``description.py``, ``description3.py``), for a unit that needs no execution tool;
    FMI 2.0 also lists the source files."""
    from wetcloth.fmu.unit import default_run

    title = DESCRIPTION.format(fmi=fmi_version, mesh=", and its mesh at every step" if fmi_version == 3 else "")
    if fmi_version == 2:
        from pythonfmu import DefaultExperiment, Fmi2Slave

        from wetcloth.fmu import description

        class Native(Fmi2Slave):  # stands in for the unit while its description is written
            author, license, version = "wetcloth", "MIT", wetcloth.__version__
            default_experiment = DefaultExperiment(0.0, *default_run())

            def do_step(self, current_time, step_size):
                return True

        Native.description = title
        slave = Native(instance_name="description")
        slave.modelName = MODEL_NAME
        for spec in specs:
            slave.register_variable(description.make_variable(spec, _start_getter(spec), None))
        root = description.extend_model_description(slave.to_xml(CAPABILITIES[2]), specs)
        root.set("guid", token)
        cosim = root.find("CoSimulation")
        files = ElementTree.SubElement(cosim, "SourceFiles")
        for name in sources:
            ElementTree.SubElement(files, "File", name=name)
    else:
        from pythonfmu3 import DefaultExperiment, Fmi3Slave

        from wetcloth.fmu import description3

        class Native3(Fmi3Slave):
            def do_step(self, current_time, step_size):
                return True

        slave = Native3(instance_name="description")
        slave.modelName = MODEL_NAME
        slave.author, slave.license, slave.version = "wetcloth", "MIT", wetcloth.__version__
        slave.description = title
        slave.default_experiment = DefaultExperiment(0.0, *default_run())
        slave.register_units(description3.units(specs))
        references = {spec.name: i for i, spec in enumerate(specs)}
        structural = description3.dimension_sources(specs)
        for spec in specs:
            slave.register_variable(description3.make_variable(spec, _start_getter(spec), None, references, structural))
        root = description3.extend_model_description(slave.to_xml(CAPABILITIES[3]), specs)
        root.set("instantiationToken", token)
    root.set("generationTool", f"wetcloth {wetcloth.__version__} (native unit, wetcloth.fmu.native)")
    ElementTree.indent(root, space="\t")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ElementTree.tostring(root, encoding="utf-8") + b"\n"


def build_description(fmi_version: int, sources: list[str]) -> bytes:
    """``sources/buildDescription.xml`` (FMI 3.0's layout, for FMI 2.0 too): one C++17 source set, the
    ``sources`` folder as its include folder."""
    root = ElementTree.Element("fmiBuildDescription", fmiVersion="3.0")
    config = ElementTree.SubElement(root, "BuildConfiguration", modelIdentifier=MODEL_NAME,
                                    description=f"the native WetCloth unit (FMI {fmi_version}.0): wetcloth's C++ core "
                                                "and its FMI functions; link libstdc++ statically to carry no "
                                                "dependency beyond the C library")
    files = ElementTree.SubElement(config, "SourceFileSet", language="C++17",
                                   compilerOptions=" ".join(f for f in CXX_FLAGS if f not in ("-std=c++17", "-fPIC")))
    for name in sources:
        ElementTree.SubElement(files, "SourceFile", name=name)
    ElementTree.SubElement(files, "PreprocessorDefinition", name="NDEBUG")
    ElementTree.SubElement(files, "IncludeDirectory", name=".")
    ElementTree.SubElement(config, "Library", name="m", description="the C math library")
    ElementTree.indent(root, space="\t")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ElementTree.tostring(root, encoding="utf-8") + b"\n"


_DOCUMENTATION = Template("""\
<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>$model $version, native: cloth that meets water (FMI $fmi co-simulation)</title>
<style>
body { font-family: sans-serif; max-width: 60em; margin: 2em auto; line-height: 1.4; }
table { border-collapse: collapse; font-size: 90%; }
td, th { border: 1px solid #bbb; padding: 0.2em 0.5em; vertical-align: top; }
th { background: #e8eef4; }
code { background: #f3f3f3; }
</style>
</head>
<body>
<h1>$model $version (native)</h1>
<p><img src="$icon" alt="a towel on water, coloured by wetness" width="128" style="float: right"></p>
<p>A rectangular cloth (by default a 50 x 70 cm cotton towel) dropped onto water. It floats, absorbs water
where it touches it, gets heavier and sinks, wettest parts first: a grid of <code>nx</code> x <code>ny</code>
particles joined by structural, shear and bending springs, with buoyancy, hydrodynamic drag and Buras-law
absorption. All quantities are SI; z is up.</p>

<h2>This unit</h2>
<ul>
<li>It is compiled from wetcloth's C++ core: it needs <b>no Python</b> and no other library than the C
library (libstdc++ and libgcc are linked in). The binary is for Linux on any x86-64 CPU; <code>sources/</code>
holds the C++17 sources and <code>sources/buildDescription.xml</code> to compile it elsewhere.</li>
<li>It <b>writes no mesh frames</b>: <code>mesh_output_dir</code> must stay empty (any other value is refused
with an error naming it). The Python unit built by <code>wetcloth build-fmu</code> writes them.$arrays</li>
<li>Each <code>${api}DoStep</code> takes as many internal steps as the integrator needs (adaptive error
control with <code>tolerance</code> &gt; 0), so any communication step size is accurate. The inputs
($inputs) may change at every communication point; <code>depth</code> shows a new water level at once.</li>
<li>Errors are FMI error statuses, never a crash, with a message to the master's logger (always, with debug
logging on or off) that names the variable and its allowed range. A value out of its range is refused by
the set call (<code>${api}Error</code>; the previous value is kept) and stays pending:
<code>${api}ExitInitializationMode</code> returns <code>${api}Error</code>, and during the run every
<code>${api}DoStep</code> returns Discard, until a valid value is set. Parameters that are valid one by one
but not together (a cloth that starts below <code>floor_level</code>) make the initialization fail. A step
that blows up returns Discard with a message naming the time; the unit stays at the start of that step with
its last good outputs. A <code>${api}DoStep</code> before initialization, after
<code>${api}Terminate</code>, from another time than the unit's or at a time or step that is not finite is
refused and changes nothing.</li>
<li>FMU states (get, set, serialize) hold the whole unit (every particle array, the step controller, the
inputs), so a resumed run repeats the uninterrupted one bit for bit, in this instance or another. Serialized
states carry a version and a checksum; bytes the unit did not write, a state of a cloth of another grid
than the initialized unit's, and a state the cloth cannot be in (a value that is not finite; a time beyond
1e9 s; a coordinate beyond 1e6 m or below the floor; a speed of 1000 m/s or more; water beyond 0 to 100
times the dry mass; asleep but moving) are refused with an error, and the instance stays as it was.</li>
</ul>

<h2>Variables</h2>
<p>Parameters are fixed at initialization; inputs are continuous Reals. Ranges are inclusive except where the
description says <code>&lt;</code>.</p>
<table>
<tr><th>name</th><th>causality</th><th>type</th><th>unit</th><th>start</th><th>range</th><th>description</th></tr>
$rows
</table>
</body>
</html>
""")


def documentation_html(specs: list[VariableSpec], fmi_version: int) -> str:
    """``documentation/index.html`` of the native unit (the variables as ``builder.documentation_html``
    lists them; what the unit needs and does not do)."""
    from wetcloth.fmu.builder import documentation_row

    rows = []
    for s in specs:
        meaning = s.description
        if s.name == "mesh_output_dir":
            meaning = "must stay empty: this unit writes no mesh frames (the Python unit does)"
        elif s.name == "mesh_format":
            meaning += "; no effect in this unit, which writes no frames"
        rows.append(documentation_row(s, meaning))
    inputs = ", ".join(f"<code>{s.name}</code>" for s in specs if s.causality == "input")
    arrays = ", ".join(f"<code>{s.name}</code> [{', '.join(map(str, s.dimensions))}]" for s in specs if s.dimensions)
    return _DOCUMENTATION.substitute(
        model=MODEL_NAME, version=html.escape(wetcloth.__version__), fmi=f"{fmi_version}.0", api=f"fmi{fmi_version}",
        icon="../" + ICON_PATH[fmi_version], rows="\n".join(rows), inputs=inputs,
        arrays="" if not arrays else (f" The cloth mesh of the current step comes as array outputs instead: {arrays} "
                                      + ("(the vertices of the mesh file built in, in its order)."
                                         if any(isinstance(d, int) for s in specs for d in s.dimensions) else
                                         "(vertex <code>row * nx + col</code>); their sizes are the structural "
                                         "parameters <code>nx</code> and <code>ny</code>.")))


# ----------------------------------------------------------------------------------------- compiling
def _digest(*parts: bytes) -> str:
    h = hashlib.sha256()
    for part in parts:
        h.update(hashlib.sha256(part).digest())
    return h.hexdigest()


def _compiler_identity(compiler: str) -> bytes:
    try:
        done = subprocess.run([compiler, "--version"], capture_output=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise NativeBuildError(f"the C++ compiler {compiler} does not run: {exc}") from None
    if done.returncode != 0:
        raise NativeBuildError(f"the C++ compiler {compiler} does not run: {done.stderr.decode(errors='replace')[-500:]}")
    return compiler.encode() + done.stdout


def default_build_dir() -> Path:
    """Where compiled objects are kept between builds: ``$XDG_CACHE_HOME/wetcloth/native-objects`` (by default
    under ``~/.cache``).  Objects are named by the digest of what made them, so builds of other sources
    and other versions share it safely; ones unused for ``KEEP_OBJECTS_DAYS`` days are removed."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "wetcloth" / "native-objects"


#: Days an object in the build folder is kept without being used.
KEEP_OBJECTS_DAYS = 30


def _forget_unused(objects: Path) -> None:
    """Remove the objects in ``objects`` (and their lock files) that no build has used for KEEP_OBJECTS_DAYS days."""
    oldest = time.time() - KEEP_OBJECTS_DAYS * 86400.0
    for path in [*objects.glob("*.o"), *objects.glob("*.lock")]:
        try:
            unused = path.stat().st_mtime < oldest
        except FileNotFoundError:  # another build's object, listed under its temporary name, renamed since
            continue
        if unused:
            path.unlink(missing_ok=True)


@contextlib.contextmanager
def _compiling(target: Path):
    """Hold ``target``'s lock file (``.lock`` beside it) while it is looked for and compiled: another build
    of the same object (another process sharing the folder) waits for it and reuses it instead of compiling
    it at the same time.  Where the folder takes no lock (some network file systems), the builds compile
    it side by side, as before: each object is written whole (``os.replace``)."""
    import fcntl

    with open(target.with_suffix(".lock"), "a") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX)
        except OSError:
            yield
            return
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def compile_objects(compiler: str, sources: list[Path], include_dirs: list[Path], objects: Path,
                    depends: list[Path], jobs: int | None = None, bar=None) -> list[Path]:
    """Compile each source into ``objects`` (in parallel), reusing an object compiled before from the same
    compiler, flags, source and ``depends`` (the headers it may include); the object files, in order.
    ``bar``: a tqdm bar moved by one per source."""
    objects.mkdir(parents=True, exist_ok=True)
    identity = _compiler_identity(compiler)
    headers = b"".join(p.read_bytes() for p in depends)
    flags = [*CXX_FLAGS, *(f"-I{d}" for d in include_dirs)]
    tasks = []
    for source in sources:
        key = _digest(identity, " ".join(CXX_FLAGS).encode(), source.read_bytes(), headers)[:20]
        tasks.append((source, objects / f"{source.stem}-{key}.o"))

    def run(task):
        source, target = task
        try:
            with _compiling(target):
                if target.exists():
                    os.utime(target)  # used now: kept by _forget_unused
                    return None
                partial = new_temporary(target, ".tmp.o")  # created new (a random name): never a link planted there
                done = subprocess.run([compiler, *flags, "-c", str(source), "-o", str(partial)], capture_output=True,
                                      text=True)
                if done.returncode != 0:
                    partial.unlink(missing_ok=True)
                    return f"{source}:\n{done.stderr[-6000:]}"
                os.replace(partial, target)
                return None
        finally:
            if bar is not None:
                bar.update(1)

    workers = jobs or max(1, os.cpu_count() or 1)
    with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
        failures = [f for f in pool.map(run, tasks) if f]
    if failures:
        raise NativeBuildError("the native FMU does not compile (are all of the core's sources finished?): "
                               + "\n".join(failures))
    return [target for _, target in tasks]


def core_sources() -> list[Path]:
    """The core's C++ sources (``fmu_src/core/src/**/*.cpp``)."""
    return sorted((core_dir() / "src").rglob("*.cpp"))


def core_objects(objects: Path, compiler: str | None = None, jobs: int | None = None, bar=None) -> list[Path]:
    """The core's object files (``core_sources``, the unit's flags), compiled into ``objects`` or reused
    from there (``bar``: as compile_objects')."""
    core = core_dir()
    headers = sorted((core / "include").rglob("*.hpp"))
    return compile_objects(compiler or find_compiler(), core_sources(), [core / "include"], Path(objects), headers,
                           jobs, bar)


def link(compiler: str, objects: list[Path], out: Path, fmi_version: int) -> Path:
    """Link the objects into the unit's shared object, exporting the fmi2 (fmi3) functions only."""
    script = out.with_suffix(".map")
    script.write_text(f"{{ global: fmi{fmi_version}*; local: *; }};\n")
    done = subprocess.run([compiler, *LINK_FLAGS, f"-Wl,--version-script={script}", "-o", str(out),
                           *map(str, objects)], capture_output=True, text=True)
    if done.returncode != 0:
        raise NativeBuildError(f"linking the native FMU failed:\n{done.stderr[-6000:]}")
    return out


def check_platform() -> None:
    if platform.system() != "Linux" or platform.machine() not in ("x86_64", "AMD64"):
        raise NativeBuildError(f"the native FMU is built for Linux on x86-64; this is {platform.system()} on "
                               f"{platform.machine()}")


# ----------------------------------------------------------------------------------------- the unit
def build_native_fmu(out: str | Path | None = None, fmi_version: int = 2, build_dir: str | Path | None = None,
                     jobs: int | None = None, scene: str | Path | None = None, progress: bool = False) -> Path:
    """Build the native unit (FMI ``fmi_version`` 2 or 3) at ``out`` (default ``native_fmu_path``); return
    its path.  ``build_dir`` (default ``default_build_dir()``) keeps the compiled objects for the next build,
    which recompiles only what changed.  ``scene``: a scene file (or preset name) whose values become the
    start values, its colliders and grip keys built in.  ``progress``: a bar of the sources compiled.
    NativeBuildError if it cannot be built here.  A scene's cloth from a mesh file is built in (``native_mesh``)."""
    if fmi_version not in (2, 3):
        raise ValueError(f"FMI version must be 2 or 3, got {fmi_version!r}")
    packed = None if scene is None else packed_scene.pack(scene)
    check_platform()
    core = core_dir()
    compiler = find_compiler()
    out = Path(native_fmu_path(fmi_version) if out is None else out)
    specs = variable_specs(fmi_version=fmi_version, packed=packed)
    files = _sources(core, fmi_version)
    sources = [*(name for _, name in files if name.endswith(".cpp")), VARIABLES_SOURCE]
    # The instantiation token: a digest of the table and every source, so that a rebuild of the same
    # sources carries the same token and another build another.
    from wetcloth.scene import load_scene

    loaded = None if scene is None else load_scene(scene)
    cloth = None if loaded is None else native_mesh.cloth_arrays(loaded)
    fixtures = fixtures_source(loaded, cloth)
    fixed = {**native_mesh.fixed_ranges(cloth), **placed_meshes(loaded)}
    specs = [fixed_spec(spec, fixed[spec.name]) if spec.name in fixed else spec
             for spec in specs]  # the model description declares what the unit takes
    body = variables_source(specs, fmi_version, fixtures=fixtures, fixed=fixed).encode()
    token = "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, "wetcloth-native:" + _digest(
        body, " ".join(CXX_FLAGS).encode(), *(p.read_bytes() for p, _ in files)))) + "}"
    generated_text = variables_source(specs, fmi_version, token, fixtures, fixed)
    with tempfile.TemporaryDirectory(prefix="wetcloth_native_") as tmp:
        stage = Path(tmp)
        generated = stage / VARIABLES_SOURCE
        generated.write_text(generated_text, encoding="utf-8")
        objects_dir = Path(build_dir) if build_dir is not None else default_build_dir()
        # The unit's fixed sources depend on no scene, so every unit reuses their objects; the generated
        # source alone is compiled for each.
        fmu_headers = [*sorted((core / "include").rglob("*.hpp")),
                       *(core / "fmu" / name for name in UNIT_FILES if name.endswith(".hpp")),
                       *sorted((core / "fmu").glob(f"fmi{fmi_version}*.h"))]
        unit_sources = [core / "fmu" / "unit.cpp", core / "fmu" / f"fmi{fmi_version}.cpp", generated]
        with tqdm(total=len(core_sources()) + len(unit_sources), desc=f"compiling {out.name}", unit="file",
                  delay=SHOW_AFTER, disable=not progress) as bar:
            objects = core_objects(objects_dir, compiler, jobs, bar)
            objects += compile_objects(compiler, unit_sources, [core / "include", core], objects_dir, fmu_headers,
                                       jobs, bar)
        binary = link(compiler, objects, stage / f"{MODEL_NAME}.so", fmi_version)
        _forget_unused(objects_dir)

        out.parent.mkdir(parents=True, exist_ok=True)
        with whole_file(out) as tmp_out, zipfile.ZipFile(tmp_out, "w", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("modelDescription.xml", model_description(specs, fmi_version, token, sources))
            archive.write(binary, f"binaries/{PLATFORM_FOLDER[fmi_version]}/{MODEL_NAME}.so")
            for path, name in files:
                archive.write(path, f"sources/{name}")
            archive.writestr(f"sources/{VARIABLES_SOURCE}", generated_text)
            archive.writestr("sources/buildDescription.xml", build_description(fmi_version, sources))
            archive.writestr("documentation/index.html", documentation_html(specs, fmi_version))
            if packed is not None:  # what was built in, for a master to check (batch.engines.fmu_series)
                archive.writestr(f"resources/{packed_scene.SCENE_NAME}", packed_scene.text(packed))
            archive.write(DOCS / "model.png", ICON_PATH[fmi_version])
    return out
