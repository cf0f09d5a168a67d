"""WetCloth.fmu as built: a model description fmpy accepts without complaint, generated from Scene."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import subprocess
import sys
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu
from test_fmu_support import built_fmu, run_child

import wetcloth
from wetcloth.fmu import bootstrap
from wetcloth.fmu.description import extend_model_description, make_variable
from wetcloth.fmu.vocabulary import OUTPUTS, fmi_unit_name, parse_unit, variable_specs
from wetcloth.scene import INPUT, PARAMETERS, describe_range, read_scene_file
from wetcloth.simulation import OUTPUT_NAMES


@pytest.fixture(scope="module")
def fmu():
    return built_fmu()


@pytest.fixture(scope="module")
def md(fmu):
    return read_model_description(str(fmu))


def test_fmpy_validation_reports_no_problems(fmu):
    assert validate_fmu(str(fmu)) == []


def test_every_scene_field_is_a_variable_with_its_metadata(md):
    variables = {v.name: v for v in md.modelVariables}
    for name, f in PARAMETERS.items():
        v = variables[name]
        meta = f.metadata
        assert v.type == {"float": "Real", "int": "Integer", "str": "String"}[f.type], name
        if meta["fmu"] == INPUT:
            assert (v.causality, v.variability) == ("input", "continuous"), name
        else:
            assert (v.causality, v.variability, v.initial) == ("parameter", "fixed", "exact"), name
        start = v.start if v.type == "String" else float(v.start)
        assert start == f.default, name
        assert v.unit == fmi_unit_name(meta["unit"]) if v.type == "Real" else v.unit is None, name
        assert meta["doc"] in v.description and describe_range(f) in v.description, name
        if v.type != "String":  # a value that must be above lo declares the least normal double above it
            lowest = (math.nextafter(meta["lo"], math.inf) if meta["lo"] else sys.float_info.min) if meta["lo_open"] \
                else meta["lo"]
            assert float(v.min) == lowest and float(v.max) == meta["hi"], name
            if v.type == "Real":
                assert float(v.nominal) == (abs(f.default) or 1.0), name


#: docs/interface.md's promise, written out here rather than derived from the Scene, so that a renamed
#: variable or a changed unit fails: name -> (FMI type, causality, FMI unit or None).
INTERFACE = {
    "water_level": ("Real", "input", "m"), "water_density": ("Real", "input", "kg/m3"),
    "absorption_capacity": ("Real", "input", "kg/kg"), "absorption_rate": ("Real", "input", "1/s"),
    "wind_x": ("Real", "input", "m/s"), "wind_y": ("Real", "input", "m/s"), "wind_z": ("Real", "input", "m/s"),
    "air_density": ("Real", "parameter", "kg/m3"),
    "centroid_x": ("Real", "output", "m"), "centroid_y": ("Real", "output", "m"),
    "centroid_z": ("Real", "output", "m"), "depth": ("Real", "output", "m"),
    "wet_mass": ("Real", "output", "kg"), "water_mass": ("Real", "output", "kg"),
    "step_error": ("Real", "output", "m"),
    "nx": ("Integer", "parameter", None), "ny": ("Integer", "parameter", None),
    "width": ("Real", "parameter", "m"), "length": ("Real", "parameter", "m"),
    "areal_density": ("Real", "parameter", "kg/m2"), "thickness": ("Real", "parameter", "m"),
    "stretch_stiffness": ("Real", "parameter", "N/m"), "bend_stiffness": ("Real", "parameter", "N/m"),
    "damping": ("Real", "parameter", "N.s/m"), "water_viscosity": ("Real", "parameter", "Pa.s"),
    "drag_model": ("String", "parameter", None), "drag_normal": ("Real", "parameter", None),
    "drag_tangential": ("Real", "parameter", None), "drag_linear": ("Real", "parameter", "N.s/m3"),
    "buoyancy_model": ("String", "parameter", None), "initial_height": ("Real", "parameter", "m"),
    "initial_tilt": ("Real", "parameter", "deg"), "floor_level": ("Real", "parameter", "m"),
    "integrator": ("String", "parameter", None), "tolerance": ("Real", "parameter", None),
    "max_step": ("Real", "parameter", "s"), "mesh_output_dir": ("String", "parameter", None),
    "mesh_format": ("String", "parameter", None),
}


def test_interface_md_variables_keep_their_names_types_and_units(md):
    variables = {v.name: v for v in md.modelVariables}
    for name, (fmi_type, causality, unit) in INTERFACE.items():
        v = variables[name]
        assert (v.type, v.causality, v.unit) == (fmi_type, causality, unit), name
        assert v.description, name
        if causality != "output":
            assert v.start is not None, name
        if fmi_type != "String":
            assert causality == "output" or (v.min is not None and v.max is not None), name
    assert variables["nx"].min == variables["ny"].min == "2"  # docs/interface.md: Integer, >= 2
    assert (variables["drag_model"].start, variables["mesh_format"].start) == ("face", "ply")
    assert variables["mesh_output_dir"].start == ""  # "" = off


def test_outputs_and_mesh_parameters(md):
    variables = {v.name: v for v in md.modelVariables}
    outputs = {**OUTPUTS, "step_error": ("m", "")}
    for name, (unit, _) in outputs.items():
        v = variables[name]
        assert (v.type, v.causality, v.variability, v.initial) == ("Real", "output", "continuous", "calculated")
        assert v.unit == unit
    assert [u.variable.name for u in md.outputs] == list(outputs)
    assert sorted(u.variable.name for u in md.initialUnknowns) == sorted(outputs)
    depth = next(u for u in md.outputs if u.variable.name == "depth")
    assert [d.name for d in depth.dependencies] == ["water_level"]  # direct feedthrough, nothing else
    for name, start in (("mesh_output_dir", ""), ("mesh_format", "ply")):
        v = variables[name]
        assert (v.type, v.causality, v.variability, v.start) == ("String", "parameter", "fixed", start)
    assert len(md.modelVariables) == len(PARAMETERS) + 2 + len(outputs)  # FMI 2.0: no arrays, no time


def test_units_carry_si_base_exponents(md):
    units = {u.name: u for u in md.unitDefinitions}
    assert {fmi_unit_name(f.metadata["unit"]) for f in PARAMETERS.values() if f.type == "float"} - {None} <= set(units)
    expected = {"N.s/m": {"kg": 1, "s": -1}, "kg/m3": {"kg": 1, "m": -3}, "Pa.s": {"kg": 1, "m": -1, "s": -1},
                "1/s": {"s": -1}, "kg/kg": {}}
    for name, exponents in expected.items():
        base = units[name].baseUnit
        for key in ("kg", "m", "s", "A", "K", "mol", "cd", "rad"):
            assert getattr(base, key) == exponents.get(key, 0), (name, key)
    assert math.isclose(units["deg"].baseUnit.factor, math.pi / 180) and units["deg"].baseUnit.rad == 1


def test_capabilities_and_default_experiment(md):
    cs = md.coSimulation
    assert md.fmiVersion == "2.0" and md.modelName == "WetCloth" and cs.modelIdentifier == "WetCloth"
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate and cs.canHandleVariableCommunicationStepSize
    assert not cs.canBeInstantiatedOnlyOncePerProcess
    run = read_scene_file(None)["run"]
    assert float(md.defaultExperiment.stopTime) == run["duration"]
    assert math.isclose(float(md.defaultExperiment.stepSize), 1.0 / run["fps"])


def test_archive_holds_documentation_icon_and_bundled_wetcloth(fmu):
    with zipfile.ZipFile(fmu) as archive:
        names = set(archive.namelist())
        doc = archive.read("documentation/index.html").decode()
        icon = archive.read("model.png")
        slave_module = archive.read("resources/slavemodule.txt").decode().strip()
    assert slave_module == "wetcloth_fmu_slave" and "resources/wetcloth_fmu_slave.py" in names
    for name in list(PARAMETERS) + list(OUTPUT_NAMES) + ["mesh_output_dir", "mesh_format"]:
        assert f"<td>{name}</td>" in doc, name
    assert "numpy" in doc and "interpreter" in doc and "numba" not in doc  # what the unit needs to run
    assert icon.startswith(b"\x89PNG\r\n\x1a\n")
    for path in ("resources/wetcloth/simulation.py", "resources/wetcloth/presets/towel.toml",
                 "resources/wetcloth_fmu_bootstrap.py", "resources/wetcloth_fmu_manifest.json",
                 "resources/wetcloth/exporter/__init__.py", "resources/wetcloth/fmu/vocabulary.py",
                 "binaries/linux64/WetCloth.so"):
        assert path in names, path
    assert not any("__pycache__" in n or n.endswith(".fmu") for n in names)


def test_new_scene_fields_become_variables_without_code_changes():
    """Fields the lead adds later (here made up) appear with their metadata, type and causality."""

    def field(name, default, type_, **meta):
        f = dataclasses.field(default=default, metadata=dict(
            unit="-", doc=name, lo=None, hi=None, lo_open=False, choices=(), fmu="parameter") | meta)
        f.name, f.type = name, type_
        return f

    fields = list(PARAMETERS.values()) + [
        field("current_x", 0.0, "float", unit="m/s", doc="water current along x", lo=-10.0, hi=10.0, fmu="input"),
        field("wicking_rate", 0.0, "float", unit="m2/s", doc="diffusion of water in the fabric", lo=0.0, hi=1.0),
        field("layers", 1, "int", lo=1, hi=8),
        field("weave", "plain", "str", choices=("plain", "terry")),
    ]
    specs = {s.name: s for s in variable_specs(fields)}
    assert (specs["current_x"].causality, specs["current_x"].type, specs["current_x"].unit) == ("input", "Real", "m/s")
    assert (specs["wicking_rate"].causality, specs["wicking_rate"].min, specs["wicking_rate"].max) == ("parameter", 0.0, 1.0)
    assert (specs["layers"].type, specs["weave"].type, specs["weave"].start) == ("Integer", "String", "plain")
    assert "'plain', 'terry'" in specs["weave"].description
    # Their units get definitions too.
    root = ElementTree.Element("fmiModelDescription")
    ElementTree.SubElement(root, "CoSimulation")
    ElementTree.SubElement(ElementTree.SubElement(root, "ModelStructure"), "Outputs")
    ordered = variable_specs(fields)
    extend_model_description(root, ordered)
    units = {u.get("name"): u.find("BaseUnit").attrib for u in root.iter("Unit")}
    assert units["m/s"] == {"m": "1", "s": "-1"} and units["m2/s"] == {"m": "2", "s": "-1"}
    real = make_variable(specs["current_x"], lambda: 0.0, None).to_xml()[0]
    assert real.attrib == {"unit": "m/s", "min": "-10.0", "max": "10.0", "nominal": "1.0"}


def test_unknown_unit_symbol_is_refused_by_name():
    with pytest.raises(ValueError, match="'furlong'"):
        parse_unit("furlong/s")


def test_build_fmu_command_writes_a_valid_unit(tmp_path):
    out = tmp_path / "sub" / "Custom.fmu"
    done = subprocess.run([sys.executable, "-m", "wetcloth.cli", "build-fmu", "--out", str(out)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert str(out) in done.stdout and validate_fmu(str(out)) == []


CHILD_BUNDLED = r"""
import json, sys
# A host with numpy but without wetcloth, its dependencies beyond numpy, or a compiler.
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in getattr(f, "__module__", "").lower()
                    and "ScikitBuild" not in type(f).__name__]
sys.path[:] = [p for p in sys.path if "fmu_src" not in p]
import importlib.abc
class Without(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("scipy", "numba", "meshio", "trimesh", "dask", "matplotlib", "tqdm", "pandas",
                                  "pyarrow", "SALib", "pxr"):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, Without())
import fmpy
res = fmpy.simulate_fmu(sys.argv[1], stop_time=0.2, output_interval=0.1, start_values={"nx": 5, "ny": 5})
print(json.dumps({"file": sys.modules["wetcloth"].__file__, "core": sys.modules["wetcloth._core"].__file__,
                  "depth": float(res["depth"][-1])}))
"""


def test_a_host_with_numpy_alone_runs_the_wetcloth_and_core_inside_the_fmu(fmu, tmp_path):
    """A Python with numpy (and fmpy, pythonfmu) but no wetcloth, scipy, meshio, trimesh, dask or pandas runs
    the copy inside the FMU, compiled core included, from the unit's own resources folder, and gets
    the Python API's outputs."""
    run, _ = run_child(CHILD_BUNDLED, fmu, cwd=tmp_path)
    result = run[-1]
    assert "/resources/wetcloth/" in result["file"] and Path(result["core"]).parent == Path(result["file"]).parent
    sim = wetcloth.Simulation(wetcloth.Scene(nx=5, ny=5))
    sim.advance(0.1)
    sim.advance(0.1)
    assert result["depth"] == sim.outputs()["depth"]  # the same compiled core, the same steps


def test_a_missing_dependency_is_named_with_how_to_install_it():
    """A module the host's Python lacks is named in the error, with the pip command for the
    requirement that provides it."""
    error = bootstrap.missing_dependency(ModuleNotFoundError("No module named 'numpy'", name="numpy"),
                                         ["numpy>=1.26", "tqdm>=4.66"])
    assert "has no module 'numpy'" in str(error) and "-m pip install 'numpy>=1.26'" in str(error)


CHILD_MISMATCH = r"""
import json, shutil, sys, fmpy
from pathlib import Path
directory = Path(fmpy.extract(sys.argv[1]))
manifest = directory / "resources" / "wetcloth_fmu_manifest.json"
data = json.loads(manifest.read_text())
data["variables"].append("made_up_variable")
manifest.write_text(json.dumps(data))
try:
    fmpy.simulate_fmu(str(directory), stop_time=0.1, debug_logging=True)
except Exception as exc:
    print("RAISED", exc)
print("RELEASED", len(sys.modules["wetcloth_fmu_bootstrap"]._RELEASED))
"""


def test_unit_refuses_a_wetcloth_whose_variables_differ(fmu, tmp_path):
    """Refused before any instance exists, and the host still exits cleanly: the binary's exit is
    made safe (wetcloth.fmu.guard, item 3) before anything of the unit can fail.  Without that,
    this process died at exit with 'corrupted double-linked list' in about 1 run of 15."""
    done = subprocess.run([sys.executable, "-c", CHILD_MISMATCH, str(fmu)], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "RAISED" in done.stdout
    assert "RELEASED 1" in done.stdout, "the binary's exit handler was not put right before the refusal"
    assert "rebuild it with `wetcloth build-fmu`" in done.stdout + done.stderr


CHILD_TWO_UNITS = r"""
import json, sys, fmpy
for _ in range(2):  # two unpacked copies: two binaries, the second unit's script not run afresh
    fmpy.simulate_fmu(fmpy.extract(sys.argv[1]), stop_time=0.1, output_interval=0.1, start_values={"nx": 5, "ny": 5},
                      output=["centroid_z"])
bootstraps = [sys.modules[name] for name in ("wetcloth_fmu_bootstrap", "wetcloth.fmu.bootstrap") if name in sys.modules]
binaries = [name for name in bootstraps[0].loaded_libraries() if bootstraps[0]._unit_binary(name)]
released = sorted(set().union(*(b._RELEASED for b in bootstraps)))
print(json.dumps({"binaries": binaries, "released": released}))
"""


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_every_unit_binary_a_host_loads_is_made_to_exit_safely(fmi_version, tmp_path):
    """A second unit in one process (another unpacked copy) gets its binary's exit put right too
    (wetcloth.fmu.guard, item 3), though pythonfmu runs its script with the first unit's ``__file__``
    and pythonfmu3 does not run it again.  That binary was missed before: fmpy unloaded it when the
    unit was freed, its exit handlers ran then, and the host died at exit now and then ("corrupted
    double-linked list" after the whole suite had passed).  Put right, it stays loaded until
    Python's exit has released it, and the host exits cleanly (``run_child`` checks)."""
    records, _ = run_child(CHILD_TWO_UNITS, built_fmu(fmi_version), cwd=tmp_path)
    binaries, released = records[-1]["binaries"], records[-1]["released"]
    assert len(set(binaries)) == 2
    assert set(binaries) <= set(released)


CHILD_SECOND_UNIT_MISMATCH = r"""
import json, sys, fmpy
from pathlib import Path
first, second = Path(fmpy.extract(sys.argv[1])), Path(fmpy.extract(sys.argv[1]))
manifest = second / "resources" / "wetcloth_fmu_manifest.json"
data = json.loads(manifest.read_text())
data["variables"].append("made_up_variable")
manifest.write_text(json.dumps(data))
for folder in (first, second):
    try:
        res = fmpy.simulate_fmu(str(folder), stop_time=0.1, output_interval=0.1, start_values={"nx": 5, "ny": 5},
                                output=["centroid_z"])
        print("RAN", len(res))
    except Exception as exc:
        print("RAISED", exc)
"""


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_a_second_unit_is_checked_against_its_own_manifest(fmi_version, tmp_path):
    """The second unit in a process is refused if its model description lists other variables
    than the wetcloth running (here: its manifest altered), though its slave script does not run
    afresh (pythonfmu3) or runs with the first unit's ``__file__`` (pythonfmu): before, it ran with
    the first unit's variables (value references that need not match).  The host exits cleanly."""
    _, done = run_child(CHILD_SECOND_UNIT_MISMATCH, built_fmu(fmi_version), cwd=tmp_path)
    outcomes = [line for line in done.stdout.splitlines() if line.startswith(("RAN", "RAISED"))]
    assert outcomes[0] == "RAN 2" and outcomes[1].startswith("RAISED") and len(outcomes) == 2
    assert "rebuild it with `wetcloth build-fmu`" in done.stderr


CHILD_OTHER_SOURCES = r"""
import json, sys, fmpy
from pathlib import Path
import wetcloth  # the host's wetcloth, imported before the unit loads
directory = Path(fmpy.extract(sys.argv[1]))
manifest = directory / "resources" / "wetcloth_fmu_manifest.json"
data = json.loads(manifest.read_text())
data["package_files"]["simulation.py"] = "0" * 64  # as if the FMU had been built from other sources
manifest.write_text(json.dumps(data))
res = fmpy.simulate_fmu(str(directory), stop_time=0.1, output_interval=0.1, start_values={"nx": 5, "ny": 5})
print(json.dumps({"file": sys.modules["wetcloth"].__file__, "rows": len(res)}))
"""


def test_unit_warns_when_it_runs_an_imported_wetcloth_of_other_sources(fmu, tmp_path):
    """One wetcloth per process: the unit runs the one imported, and says so when it differs."""
    done = subprocess.run([sys.executable, "-c", CHILD_OTHER_SOURCES, str(fmu)], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    result = __import__("json").loads(done.stdout.strip().splitlines()[-1])
    assert result["file"] == wetcloth.__file__ and result["rows"] == 2
    assert done.stderr.count("whose sources differ from the copy the FMU was built with") == 1  # once a unit


def test_an_fmu_older_than_the_sources_is_stale(fmu, tmp_path):
    import os
    import shutil

    from wetcloth.fmu.builder import is_stale, source_files

    copy = tmp_path / "WetCloth.fmu"
    shutil.copy(fmu, copy)
    newest = max(p.stat().st_mtime for p in source_files())
    os.utime(copy, (newest + 10, newest + 10))
    assert not is_stale(copy)
    os.utime(copy, (newest - 10, newest - 10))
    assert is_stale(copy) and is_stale(tmp_path / "missing.fmu")
    assert any(p.name == "towel.toml" for p in source_files())
    assert any("exporter" in p.parts for p in source_files())
