"""The native unit (``wetcloth build-fmu --native``): the FMU compiled from the C++ core, with no Python in it.

Built once per session (both FMI versions, the core's objects shared). Masters run in child processes (a
crash of the unit fails a test, not the suite): fmpy, libcosimpy, and a C master that dlopens the binary.

How close to the Python API: identical. The unit and wetcloth.Simulation run the same C++ core (the same
sources, compiled with value-preserving flags: no fast-math, no contraction into fused multiply-adds, so
the values do not depend on the instruction set either), and their outputs must be equal bit for bit.
"""

from __future__ import annotations

import ctypes
import json
import re
import math
import os
import shutil
import struct
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import explicit_near_the_smallest_step
from test_fmu_support import BLOW_UP, SMALL, assert_like_direct_runs, last_good_time, run_child

import wetcloth
from wetcloth._core import CLOCK_SIZE
from wetcloth.errors import ParameterError
from wetcloth.scene import check_value
from wetcloth.simulation import OUTPUT_NAMES

native = pytest.importorskip("wetcloth.fmu.native")

try:
    native.check_platform()
    native.core_dir()
    native.find_compiler()
except native.NativeBuildError as exc:  # pragma: no cover - machines without a compiler or the sources
    pytest.skip(f"the native unit cannot be built here: {exc}", allow_module_level=True)


# ----------------------------------------------------------------------------------------- agreement
def assert_agree(unit_rows, python_rows, label=""):
    """The unit's outputs against the Python API's (rows of OUTPUT_NAMES): identical (the same core)."""
    unit_rows, python_rows = np.asarray(unit_rows, dtype=float), np.asarray(python_rows, dtype=float)
    assert unit_rows.shape == python_rows.shape
    assert np.isfinite(unit_rows).all()
    np.testing.assert_array_equal(unit_rows, python_rows, err_msg=label)


def advance_as_the_unit(sim: wetcloth.Simulation, t: float) -> None:
    """Step to fmpy's communication point t as the unit does: fmpy passes the step t - t_prev, and the unit
    steps to t_prev + step (which may be an ulp from t) from the start time 0."""
    previous = getattr(sim, "_communication_point", 0.0)
    sim.advance(max(0.0, previous + (t - previous) - 0.0 - sim.time))
    sim._communication_point = t


# ----------------------------------------------------------------------------------------- the build
@pytest.fixture(scope="session")
def build(tmp_path_factory, native_objects):
    """Both units, built once; their extracted folders and model descriptions."""
    import fmpy

    folder = tmp_path_factory.mktemp("native_fmu")
    objects = native_objects
    units = {}
    for version in (2, 3):
        fmu = native.build_native_fmu(folder / f"WetClothNative{'' if version == 2 else 3}.fmu", version,
                                      build_dir=objects)
        directory = Path(fmpy.extract(str(fmu), unzipdir=str(folder / f"unzipped{version}")))
        units[version] = {"fmu": fmu, "dir": directory, "md": fmpy.read_model_description(str(fmu))}
    units["objects"] = objects
    units["folder"] = folder
    return units


def binary(build, version=2) -> Path:
    return build[version]["dir"] / "binaries" / native.PLATFORM_FOLDER[version] / "WetCloth.so"


# ----------------------------------------------------------------------------------------- the archive
def test_fmpy_validates_both_units_without_remarks(build):
    from fmpy.model_description import read_build_description
    from fmpy.validation import validate_fmu

    for version in (2, 3):
        assert validate_fmu(str(build[version]["fmu"])) == [], version
        # sources/buildDescription.xml (FMI 3.0's schema, checked) and, for FMI 2.0, the description's SourceFiles
        configurations = read_build_description(str(build[version]["fmu"]), validate=True)
        assert configurations[0].sourceFileSets[0].language == "C++17"
        files = configurations[0].sourceFileSets[0].sourceFiles
        assert {f"fmu/fmi{version}.cpp", "core/model.cpp", "core/stepping.cpp", native.VARIABLES_SOURCE} <= set(files)
        assert all((build[version]["dir"] / "sources" / f).is_file() for f in files)
    assert build[2]["md"].buildConfigurations[0].sourceFileSets[0].sourceFiles == [
        "fmu/fmi2.cpp" if f == "fmu/fmi3.cpp" else f for f in files]


def test_the_variables_are_those_of_the_python_units(build):
    """Same names, value references, types, causalities and starts as the pythonfmu units would write
    (the vocabulary's order), and the same model name."""
    from wetcloth.fmu.vocabulary import variable_specs

    for version in (2, 3):
        md = build[version]["md"]
        assert md.modelName == "WetCloth" and md.coSimulation.modelIdentifier == "WetCloth"
        assert md.coSimulation.needsExecutionTool in (False, "false")
        specs = variable_specs(fmi_version=version)
        assert [(v.name, v.valueReference, v.causality) for v in md.modelVariables] == [
            (s.name, k, "structuralParameter" if version == 3 and s.name in ("nx", "ny") else s.causality)
            for k, s in enumerate(specs)]


def test_the_binary_carries_no_python_and_exports_only_fmi_functions(build):
    for version in (2, 3):
        so = binary(build, version)
        libraries = subprocess.run(["ldd", str(so)], capture_output=True, text=True, check=True).stdout
        assert "libpython" not in libraries
        assert "libstdc++" not in libraries and "libgcc_s" not in libraries  # linked in statically
        symbols = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True,
                                 check=True).stdout.split()[2::3]
        assert symbols and all(s.startswith(f"fmi{version}") for s in symbols), symbols
        assert f"fmi{version}DoStep" in symbols
    if shutil.which("objdump"):  # baseline x86-64: no AVX register anywhere
        code = subprocess.run(["objdump", "-d", str(binary(build))], capture_output=True, text=True).stdout
        assert "%ymm" not in code and "%zmm" not in code


def test_its_documentation_says_it_writes_no_mesh_frames(build):
    for version in (2, 3):
        text = (build[version]["dir"] / "documentation" / "index.html").read_text()
        assert "writes no mesh frames" in text and "mesh_output_dir" in text and "no Python" in text


def test_wheel_installs_and_missing_compilers_are_refused_clearly(monkeypatch, tmp_path):
    monkeypatch.setattr(native.wetcloth, "__file__", str(tmp_path / "site-packages" / "wetcloth" / "__init__.py"))
    with pytest.raises(native.NativeBuildError, match="does not have: a wheel carries no C.. sources"):
        native.core_dir()
    monkeypatch.undo()
    monkeypatch.setenv("CXX", str(tmp_path / "no-such-compiler"))
    with pytest.raises(native.NativeBuildError, match="is not found"):
        native.build_native_fmu(tmp_path / "x.fmu")
    monkeypatch.delenv("CXX")
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(native.NativeBuildError, match="no C.. compiler found"):
        native.find_compiler()


# ----------------------------------------------------------------------------------------- the model arrays
CHECKER = r"""
// Exposes a wc::Simulation's arrays by name (the Python test compares them with wetcloth.Simulation's).
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>
#include "wetcloth/model.hpp"
#define API extern "C" __attribute__((visibility("default")))
using namespace wc;
struct Checked { std::unique_ptr<Simulation> sim; };

static void assign(Scene& scene, int count, const char** names, const double* numbers, const char** texts) {
    for (int k = 0; k < count; ++k) {
        for_each_field(scene, [&](const char* field, auto& member) {
            if (std::strcmp(field, names[k]) != 0) return;
            if (texts[k] != nullptr) {
                const Choices c = scene_choices(field);
                for (Index j = 0; j < c.count; ++j) if (std::strcmp(c.names[j], texts[k]) == 0) member = j;
            } else {
                member = static_cast<std::remove_reference_t<decltype(member)>>(numbers[k]);
            }
        });
    }
}

API void* check_new(int count, const char** names, const double* numbers, const char** texts, char* error) {
    Scene scene;
    assign(scene, count, names, numbers, texts);
    try { return new Checked{std::make_unique<Simulation>(scene)}; }
    catch (const std::exception& e) { std::snprintf(error, 1000, "%s", e.what()); return nullptr; }
}
API void check_free(void* h) { delete static_cast<Checked*>(h); }
API int check_set_inputs(void* h, int count, const char** names, const double* numbers) {
    Simulation& sim = *static_cast<Checked*>(h)->sim;
    Scene next = sim.scene();
    std::vector<const char*> texts(count, nullptr);
    assign(next, count, names, numbers, texts.data());
    return sim.set_inputs(next) ? 1 : 0;
}
API int check_advance(void* h, double duration) { return static_cast<int>(static_cast<Checked*>(h)->sim->advance(duration)); }
API long check_snapshot(void* h, unsigned char* out, long capacity) {
    const auto bytes = static_cast<Checked*>(h)->sim->snapshot();
    if (out && capacity >= static_cast<long>(bytes.size())) std::memcpy(out, bytes.data(), bytes.size());
    return static_cast<long>(bytes.size());
}
API int check_restore(void* h, const unsigned char* data, long size, char* error) {
    try { static_cast<Checked*>(h)->sim->restore(data, static_cast<std::size_t>(size)); return 0; }
    catch (const std::exception& e) { std::snprintf(error, 1000, "%s", e.what()); return 1; }
}

template <class T> static void put(std::vector<double>& v, const T* p, Index count) {
    for (Index i = 0; i < count; ++i) v.push_back(static_cast<double>(p[i]));
}

API long check_array(void* h, const char* name, double* out, long capacity) {
    const Simulation& sim = *static_cast<Checked*>(h)->sim;
    const Core& c = sim.core();
    const Index n = sim.n(), F = c.cloth.families, W = c.cloth.wick_families;
    const std::string key = name;
    std::vector<double> v;
    const Physics& p = c.phys;
    const Control& k = c.control;
    const Plane& pl = c.plane;
    const Contact& ct = c.contact;
    const Buffers& b = c.buf;
    if (key == "offsets") put(v, c.cloth.offsets, F);
    else if (key == "rest") put(v, c.cloth.rest, F);
    else if (key == "tension_only") put(v, c.cloth.tension_only, F);
    else if (key == "stiffness") put(v, c.cloth.stiffness, F * n);
    else if (key == "damping") put(v, c.cloth.damping, F * n);
    else if (key == "free") put(v, c.cloth.free, n);
    else if (key == "dry_mass") put(v, c.cloth.dry_mass, n);
    else if (key == "volume") put(v, c.cloth.volume, n);
    else if (key == "stokes_coefficient") put(v, c.cloth.stokes_coefficient, n);
    else if (key == "capacity") put(v, c.cloth.capacity, n);
    else if (key == "wick_offsets") put(v, c.cloth.wick_offsets, W);
    else if (key == "wick_conductance") put(v, c.cloth.wick_conductance, W * n);
    else if (key == "grid") v = {double(c.cloth.grid_x), double(c.cloth.grid_y)};
    else if (key == "physics") v = {double(p.projected), p.wet_factor, p.water_level, p.water_density, p.thickness,
        double(p.smooth), double(p.stokes), p.drag_normal, p.drag_tangential, p.drag_linear, p.current_x, p.current_y,
        p.air_density, p.wind_x, p.wind_y, p.wind_z,
        p.floor_z, p.floor_friction, p.absorption_capacity, p.absorption_rate, p.drying_rate, p.wicking_rate,
        p.wick_step_limit, double(p.skip_idle), p.grip_x, p.grip_y, p.grip_z};
    else if (key == "grip_origin") put(v, p.grip_origin, p.grip_origin != nullptr ? 3 * n : 0);
    else if (key == "control") v = {double(k.integrator), k.tolerance, k.allowed, k.max_step, k.newton_tolerance,
        k.cg_tolerance, k.omega_squared, k.buoyancy_omega_squared, k.damping_rate, k.spring_limit, k.drag_rate_offset,
        k.drag_rate_slope, k.smallest_step, k.growth, k.shrink, k.blow_up_speed, k.sleep_distance, k.sleep_after};
    else if (key == "plane.slots") put(v, pl.slots, F);
    else if (key == "plane.shares") put(v, pl.shares, 2 * F);
    else if (key == "plane.stiffness") put(v, pl.stiffness, F * n);
    else if (key == "plane.order") put(v, pl.order, pl.coarse_n);
    else if (key == "plane.rank") put(v, pl.rank, pl.rank_size);
    else if (key == "plane.levels") put(v, pl.grid.levels, 4 * pl.grid.level_count);
    else if (key == "plane.sizes") v = {double(pl.kd), double(pl.coarse_n), double(pl.grid.size)};
    else if (key == "plane.reference") put(v, pl.reference, 4);
    else if (key == "plane.reference_mass") put(v, pl.reference_mass, n);
    else if (key == "plane.frame") put(v, pl.frame, 9 * n);
    else if (key == "plane.normal") put(v, pl.normal, n);
    else if (key == "contact") v = {double(ct.enabled), ct.friction, ct.least_margin, ct.rest_gap, ct.margin[0]};
    else if (key == "contact.triangles") put(v, ct.triangles, 3 * ct.triangle_count);
    else if (key == "contact.edges") put(v, ct.edges, 2 * ct.edge_count);
    else if (key == "contact.rest") put(v, ct.rest, 3 * n);
    else if (key == "contact.reference") put(v, ct.reference, 3 * n);
    else if (key == "contact.zone") put(v, ct.zone, n);
    else if (key == "pos") put(v, b.pos, 3 * n);
    else if (key == "vel") put(v, b.vel, 3 * n);
    else if (key == "water") put(v, b.water, n);
    else if (key == "trial_pos") put(v, b.trial_pos, 3 * n);
    else if (key == "trial_vel") put(v, b.trial_vel, 3 * n);
    else if (key == "trial_water") put(v, b.trial_water, n);
    else if (key == "prev_pos") put(v, b.prev_pos, 3 * n);
    else if (key == "prev_vel") put(v, b.prev_vel, 3 * n);
    else if (key == "prev_water") put(v, b.prev_water, n);
    else if (key == "acceleration") put(v, b.acceleration, 3 * n);
    else if (key == "anchor") put(v, b.anchor, 3 * n);
    else if (key == "held") put(v, b.held, n);
    else if (key == "clock") put(v, c.clock, CLOCK_SIZE);
    else if (key == "outputs") { v.resize(6); sim.outputs(v.data()); }
    else return -1;
    if (out && capacity >= static_cast<long>(v.size())) std::memcpy(out, v.data(), v.size() * sizeof(double));
    return static_cast<long>(v.size());
}
"""


class Checker:
    """A wc::Simulation in this process (model.cpp and the core's objects, through ctypes)."""

    def __init__(self, library, **values):
        self.lib = library
        names = [k.encode() for k in values]
        numbers = [0.0 if isinstance(v, str) else float(v) for v in values.values()]
        texts = [v.encode() if isinstance(v, str) else None for v in values.values()]
        error = ctypes.create_string_buffer(1000)
        self.handle = library.check_new(len(names), (ctypes.c_char_p * len(names))(*names),
                                        (ctypes.c_double * len(names))(*numbers),
                                        (ctypes.c_char_p * len(names))(*texts), error)
        if not self.handle:
            raise ValueError(error.value.decode())

    def __getitem__(self, name: str) -> np.ndarray:
        size = self.lib.check_array(self.handle, name.encode(), None, 0)
        assert size >= 0, name
        out = np.zeros(size)
        self.lib.check_array(self.handle, name.encode(), out.ctypes.data_as(ctypes.c_void_p), size)
        return out

    @property
    def time(self) -> float:
        return float(self["clock"][0])

    def advance(self, duration: float) -> int:
        return self.lib.check_advance(self.handle, duration)

    def set_inputs(self, **values) -> int:
        names = [k.encode() for k in values]
        return self.lib.check_set_inputs(self.handle, len(names), (ctypes.c_char_p * len(names))(*names),
                                         (ctypes.c_double * len(names))(*map(float, values.values())))

    def snapshot(self) -> bytes:
        size = self.lib.check_snapshot(self.handle, None, 0)
        out = ctypes.create_string_buffer(size)
        self.lib.check_snapshot(self.handle, out, size)
        return out.raw

    def restore(self, data: bytes) -> str:
        error = ctypes.create_string_buffer(1000)
        return error.value.decode() if self.lib.check_restore(self.handle, data, len(data), error) else ""

    def close(self):
        self.lib.check_free(self.handle)


def compile_checker(folder: Path, objects_dir: Path):
    """The checker (CHECKER, a wc::Simulation behind C functions) compiled in ``folder`` against
    model.hpp and linked with the core's objects kept in ``objects_dir``; loaded through ctypes."""
    folder.mkdir(parents=True, exist_ok=True)
    source = folder / "checker.cpp"
    source.write_text(CHECKER)
    objects = native.core_objects(objects_dir)  # compiled once, then reused
    library = folder / "checker.so"
    subprocess.run([native.find_compiler(), *native.CXX_FLAGS, "-O1", f"-I{native.core_dir() / 'include'}",
                    "-shared", "-o", str(library), str(source), *map(str, objects)], check=True, capture_output=True)
    lib = ctypes.CDLL(str(library))
    lib.check_new.restype = ctypes.c_void_p
    lib.check_new.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_char_p]
    lib.check_free.argtypes = [ctypes.c_void_p]
    lib.check_array.restype = ctypes.c_long
    lib.check_array.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p, ctypes.c_long]
    lib.check_set_inputs.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p]
    lib.check_advance.argtypes = [ctypes.c_void_p, ctypes.c_double]
    lib.check_snapshot.restype = ctypes.c_long
    lib.check_snapshot.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_long]
    lib.check_restore.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_long, ctypes.c_char_p]
    return lib


@pytest.fixture(scope="module")
def checker_library(build):
    """The checker linked with the core's objects of the unit's build."""
    return compile_checker(build["folder"] / "checker", build["objects"])


#: Scenes whose set-up takes every branch: the towel; wicking and a current (presets); a grid large enough
#: for multigrid (wider than long: band order along the columns), pinned, without bending springs, with
#: Stokes drag, thesis damping, wet stiffening, water at the start and no air; fixed explicit steps in wind.
SCENES = [
    {},
    {"preset": "wicking"},
    {"preset": "current"},
    {"nx": 50, "ny": 45, "pinned_edge": "x_min", "bend_stiffness": 0.0, "drag_model": "stokes",
     "damping_model": "thesis", "wet_stiffness_factor": 0.5, "initial_saturation": 0.3, "self_collision": "off",
     "buoyancy_model": "thesis", "initial_tilt": -30.0, "air_density": 0.0},
    {"nx": 7, "ny": 3, "integrator": "explicit_euler", "tolerance": 0.0, "max_step": 0.001, "pinned_edge": "y_max",
     "wet_stiffness_factor": -0.5, "stretch_stiffness": 500.0, "damping": 0.0, "air_density": 3.0, "wind_x": 2.0,
     "wind_z": -0.5},
]


def scene_values(case: dict) -> dict:
    case = dict(case)
    preset = case.pop("preset", None)
    return wetcloth.load_scene(preset, **case).to_dict()


def python_arrays(sim: wetcloth.Simulation) -> dict[str, np.ndarray]:
    """The same arrays from the Python package."""
    cloth, plane, contact, buf = sim.model.cloth, sim._plane, sim._contact, sim._buffers
    control = sim._control
    arrays = {name: getattr(cloth, name) for name in ("offsets", "rest", "tension_only", "stiffness", "damping", "free",
                                                      "dry_mass", "volume", "stokes_coefficient", "capacity",
                                                      "wick_offsets", "wick_conductance")}
    arrays["grid"] = [cloth.grid_x, cloth.grid_y]
    physics = sim.model.physics  # its scalars (the native FMU has no colliders: none in these scenes)
    assert physics.colliders.size == 0 and len(physics.meshes.headers) == 0
    arrays["physics"] = [float(v) for f, v in zip(physics._fields, physics)
                         if f not in ("colliders", "meshes", "grip_keys", "grip_origin", "collider_keys",
                                      "collider_motion")]
    arrays["grip_origin"] = physics.grip_origin
    arrays["control"] = [float(getattr(control, f)) for f in control._fields if f != "scheme"]
    arrays |= {f"plane.{name}": getattr(plane, name) for name in ("slots", "shares", "stiffness", "order", "rank",
                                                                  "reference", "reference_mass", "frame", "normal")}
    arrays["plane.levels"] = plane.grid.levels
    arrays["plane.sizes"] = [plane.bands.shape[2] - 1, plane.order.shape[0], plane.grid.x.shape[1]]
    arrays["contact"] = [contact.enabled, contact.friction, contact.least_margin, contact.rest_gap, contact.margin[0]]
    arrays |= {f"contact.{name}": getattr(contact, name) for name in ("triangles", "edges", "rest", "reference", "zone")}
    arrays |= {name: getattr(buf, name) for name in buf._fields}
    arrays["clock"] = sim._clock
    return {k: np.ascontiguousarray(v, dtype=float).ravel() for k, v in arrays.items()}


def assert_bitwise(ours: np.ndarray, theirs: np.ndarray, name: str):
    assert ours.shape == theirs.shape, (name, ours.shape, theirs.shape)
    assert ours.tobytes() == theirs.tobytes(), (name, np.flatnonzero(ours != theirs)[:5])


@pytest.mark.parametrize("case", SCENES, ids=lambda c: "-".join(f"{k}={v}" for k, v in c.items()) or "towel")
def test_model_arrays_agree_with_the_python_package_to_the_bit(checker_library, case):
    values = scene_values(case)
    ours = Checker(checker_library, **values)
    try:
        sim = wetcloth.Simulation(wetcloth.scene.from_dict(values))
        theirs = python_arrays(sim)
        for name, array in theirs.items():
            assert_bitwise(ours[name], array, name)
        # Inputs change Physics, Control and the capacity (and wicking's conductances) as set_inputs does.
        inputs = dict(water_level=0.03, water_density=1020.0, absorption_capacity=2.5, absorption_rate=0.4,
                      current_x=0.2, current_y=-0.1, wind_x=3.0, wind_y=-1.5, wind_z=0.4, grip_x=0.1, grip_y=-0.2,
                      grip_z=0.3)
        assert ours.set_inputs(**inputs) == 1 and ours.set_inputs(**inputs) == 0
        sim.set_inputs(**inputs)
        theirs = python_arrays(sim)
        for name in ("capacity", "wick_conductance", "physics", "control", "dry_mass", "anchor", "clock"):
            assert_bitwise(ours[name], theirs[name], f"{name} after set_inputs")
    finally:
        ours.close()


def fnv1a(data: bytes) -> int:
    h = 0xcbf29ce484222325
    for byte in data:
        h = ((h ^ byte) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return h


def test_snapshots_of_another_grid_or_not_finite_are_refused_and_change_nothing(checker_library):
    a = Checker(checker_library, nx=9, ny=9)
    b = Checker(checker_library, nx=9, ny=11)
    try:
        assert checker_library.check_advance(a.handle, 0.3) == 0
        data = a.snapshot()
        before = a["pos"]
        assert "another grid: 9 x 9 particles, this simulation has 9 x 11" in b.restore(data)
        # A NaN among the positions (checksum made to fit): refused, nothing changed.
        magic = len(b"wetcloth-native-snapshot\n")
        body = bytearray(data[magic + 12:])
        offset = 16 + 8 * 40 + 8 * (CLOCK_SIZE + 3 + 1) + 8 * 5  # families, count, scene, clock, reference, margin; 6th x
        body[offset:offset + 8] = struct.pack("<d", float("nan"))
        bad = data[:magic + 4] + struct.pack("<Q", fnv1a(bytes(body))) + bytes(body)
        checker_library.check_advance(a.handle, 0.1)
        moved = a["pos"]
        assert "not finite" in a.restore(bad)
        assert_bitwise(a["pos"], moved, "pos after a refused snapshot")
        assert "checksum" in a.restore(data[:-8] + bytes(byte ^ 0xFF for byte in data[-8:]))  # last 8 bytes flipped
        assert a.restore(data) == ""
        assert_bitwise(a["pos"], before, "pos after restoring")
    finally:
        a.close()
        b.close()


def test_a_snapshot_restores_the_reused_jacobian_systems_and_the_run_repeats(checker_library):
    """On a multigrid grid the adaptive steps reuse in-plane systems built from the Jacobian
    (reused_plane.hpp); a snapshot carries what they were built from, so that the run after a restore,
    into the same simulation or a fresh one, repeats the uninterrupted run bit for bit, as in Python
    (tests/test_preconditioner.py), and the snapshot is the Python package's."""
    scene = dict(nx=41, ny=41, width=1.0, length=1.0, pinned_edge="y_max", initial_tilt=0.0, initial_height=2.0,
                 water_level=-10.0, floor_level=-20.0, self_collision="off")
    a = Checker(checker_library, **scene)
    b = Checker(checker_library, **scene)
    try:
        assert a.advance(0.3) == 0
        data = a.snapshot()
        assert a.advance(0.2) == 0
        expected = a["pos"]
        for restored in (a, b):
            assert restored.restore(data) == ""
            assert restored.advance(0.2) == 0
            assert_bitwise(restored["pos"], expected, "pos after restoring")
        sim = wetcloth.Simulation(wetcloth.load_scene(**scene))
        sim.advance(0.3)
        sim.advance(0.2)
        assert_bitwise(a["pos"], np.ascontiguousarray(sim._buffers.pos).ravel(), "pos against the Python package")
    finally:
        a.close()
        b.close()


# ----------------------------------------------------------------------------------------- fmpy
def test_fmpy_runs_the_towel_as_the_python_api_does(build):
    import fmpy

    result = fmpy.simulate_fmu(str(build[2]["dir"]), stop_time=3.0, output_interval=1 / 30,
                               model_description=build[2]["md"])
    assert math.isclose(result["time"][-1], 3.0)
    scene = wetcloth.load_scene()
    sim = wetcloth.Simulation(scene)
    rows = []
    for t in result["time"]:
        advance_as_the_unit(sim, t)
        rows.append([*(sim.outputs()[n] for n in OUTPUT_NAMES), sim.error_estimate])
    assert_agree([[row[n] for n in (*OUTPUT_NAMES, "step_error")] for row in result], rows, "fmpy FMI 2.0")
    assert np.count_nonzero(result["step_error"]) == len(result) - 1  # every step estimated its error



def python_run_with_inputs(values: dict, signal: np.ndarray, times) -> list:
    """The outputs (rows of OUTPUT_NAMES) of the Python API on scene ``values`` at ``times``, the inputs of
    ``signal`` (time, then one column per input) set at each communication point as fmpy sets them."""
    from fmpy.simulation import Input

    sim = wetcloth.Simulation(wetcloth.load_scene(**values))
    names = signal.dtype.names[1:]

    def apply(t):
        inputs, _ = Input.interpolate(time=t, t=signal["time"], table=np.array([signal[n] for n in names]),
                                      after_event=True)
        sim.set_inputs(**dict(zip(names, map(float, inputs))))

    apply(0.0)
    rows = [[sim.outputs()[n] for n in OUTPUT_NAMES]]
    for previous, t in zip(times[:-1], times[1:]):
        apply(previous)
        advance_as_the_unit(sim, t)
        rows.append([sim.outputs()[n] for n in OUTPUT_NAMES])
    return rows

def test_the_wind_inputs_act_as_in_the_python_api(build):
    """wind_x, wind_y, wind_z are inputs (m/s), as current_x is; air_density a parameter (kg/m3): through
    fmpy, a hanging sheet in a wind that rises at 0.5 s gives the Python API's outputs with the same
    inputs set at the same communication points (fmpy sets them before each step), bit for bit."""
    import fmpy

    for version in (2, 3):
        variables = {v.name: v for v in build[version]["md"].modelVariables}
        for name in ("wind_x", "wind_y", "wind_z"):
            assert (variables[name].causality, variables[name].unit) == ("input", "m/s"), name
        assert (variables["air_density"].causality, variables["air_density"].unit) == ("parameter", "kg/m3")
    signal = np.array([(0.0, 0.0, 0.0, 0.0), (0.5, 0.0, 0.0, 0.0), (0.5, 1.0, 3.0, -0.5), (1.0, 1.0, 3.0, -0.5)],
                      dtype=[("time", float), ("wind_x", float), ("wind_y", float), ("wind_z", float)])
    values = {"nx": 9, "ny": 13, "initial_tilt": 90.0, "pinned_edge": "y_max", "initial_height": 0.5,
              "air_density": 1.5}
    result = fmpy.simulate_fmu(str(build[2]["dir"]), stop_time=1.0, output_interval=0.05, start_values=values,
                               input=signal, model_description=build[2]["md"])
    rows = python_run_with_inputs(values, signal, result["time"])
    assert_agree([[row[n] for n in OUTPUT_NAMES] for row in result], rows, "fmpy FMI 2.0 in wind")
    assert result["centroid_y"][-1] - result["centroid_y"][10] > 0.01  # the wind pushed it along y


def test_the_grip_inputs_act_as_in_the_python_api(build):
    """grip_x, grip_y, grip_z are inputs (m): through fmpy, a hanging sheet whose grip is moved from 0.3 s
    on (each value reached linearly over the communication step after it is set) gives the Python API's
    outputs with the same inputs set at the same communication points, bit for bit."""
    import fmpy

    for version in (2, 3):
        variables = {v.name: v for v in build[version]["md"].modelVariables}
        for name in ("grip_x", "grip_y", "grip_z"):
            assert (variables[name].causality, variables[name].unit) == ("input", "m"), name
    signal = np.array([(0.0, 0.0, 0.0, 0.0), (0.3, 0.0, 0.0, 0.0), (1.0, 0.1, -0.05, 0.3)],
                      dtype=[("time", float), ("grip_x", float), ("grip_y", float), ("grip_z", float)])
    values = {"nx": 9, "ny": 13, "initial_tilt": 90.0, "pinned_edge": "y_max", "initial_height": 0.5}
    result = fmpy.simulate_fmu(str(build[2]["dir"]), stop_time=1.0, output_interval=0.05, start_values=values,
                               input=signal, model_description=build[2]["md"])
    rows = python_run_with_inputs(values, signal, result["time"])
    assert_agree([[row[n] for n in OUTPUT_NAMES] for row in result], rows, "fmpy FMI 2.0 with the grip")
    assert result["centroid_z"][-1] - result["centroid_z"][0] > 0.15  # the grip lifted it


#: A child process: the unit at argv[1] initialised with parameter argv[2] = argv[3]; prints the status and
#: the errors logged.
OVERLAP = r"""
import json, sys
import fmpy
from fmpy import calloc, free
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE)
directory = fmpy.extract(sys.argv[1])
md = fmpy.read_model_description(directory)
var = {v.name: v for v in md.modelVariables}
messages = []
callbacks = fmi2CallbackFunctions()
callbacks.logger = fmi2CallbackLoggerTYPE(lambda env, instance, status, category, message:
                                          messages.append((int(status), message.decode())))
callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName="overlap")
fmu.instantiate(callbacks=callbacks, loggingOn=False)
fmu.setupExperiment(startTime=0.0)
fmu.setReal([var[sys.argv[2]].valueReference], [float(sys.argv[3])])
fmu.enterInitializationMode()
try:
    fmu.exitInitializationMode()
    status = 0
except FMICallException as exc:
    status = int(exc.status)
print(json.dumps({"status": status, "errors": [m for s, m in messages if s >= 3]}))
fmu.freeInstance()
"""


def test_a_unit_built_with_a_scene_runs_its_colliders_and_grip_keys_as_the_python_api(build, tmp_path):
    """`build-fmu --native --scene`: the scene's colliders (a sphere; the bucket, a mesh collider read from a
    file) and grip keys (the lift) are compiled into the unit, which runs through fmpy as the Python API
    does, bit for bit; each scene's run differs from the same scene without them.  A start value that puts
    the cloth into the sphere fails the initialization with the Python API's message."""
    import fmpy

    for preset in ("tablecloth_sphere", "bucket", "lift"):
        fmu = native.build_native_fmu(tmp_path / f"{preset}.fmu", 2, build_dir=build["objects"], scene=preset)
        result = fmpy.simulate_fmu(str(fmu), stop_time=1.2, output_interval=0.1)
        scene = wetcloth.load_scene(preset)
        rows = {}
        for label, fixed in (("as built", scene), ("without", scene.replace(colliders=(), grip_keys=()))):
            sim, rows[label] = wetcloth.Simulation(fixed), []
            for t in result["time"]:
                advance_as_the_unit(sim, t)
                rows[label].append([sim.outputs()[n] for n in OUTPUT_NAMES])
        assert_agree([[row[n] for n in OUTPUT_NAMES] for row in result], rows["as built"], preset)
        assert np.abs(np.subtract(rows["as built"], rows["without"])).max() > 1e-3, preset
        declared = {v.name: v for v in fmpy.read_model_description(str(fmu)).modelVariables}
        for k, collider in enumerate(scene.colliders, 1):  # a mesh collider is built in where the scene puts it
            for c in "xyz":
                variable = declared[f"collider{k}_{c}"]
                assert (float(variable.min) == float(variable.max) == getattr(collider, c)) is (collider.shape == "mesh")
    fmu = native.build_native_fmu(tmp_path / "sphere.fmu", 2, build_dir=build["objects"], scene="tablecloth_sphere")
    records, _ = run_child(OVERLAP, fmu, "initial_height", "0.05")
    with pytest.raises(ParameterError) as exc:
        wetcloth.load_scene("tablecloth_sphere", initial_height=0.05)
    assert records[-1] == {"status": 3, "errors": [f"initialization refused: {exc.value}"]}


#: A child process: the unit at argv[1] run through fmpy to argv[2] s with the grip inputs of the JSON rows argv[3]
#: ((time, grip_y, grip_z), linear between them); prints the messages logged with an error status.
GRIP_SIGNAL = r"""
import json, sys
import numpy as np
import fmpy
rows = [tuple(r) for r in json.loads(sys.argv[3])]
signal = np.array(rows, dtype=[("time", float), ("grip_y", float), ("grip_z", float)])
messages = []
fmpy.simulate_fmu(sys.argv[1], stop_time=float(sys.argv[2]), output_interval=0.05, input=signal,
                  logger=lambda component, instance, status, category, message: messages.append((status, message.decode())))
print(json.dumps({"errors": [m for s, m in messages if s >= 2]}))
"""


def test_a_blow_up_from_the_grip_pressing_pinned_particles_into_a_collider_says_so(build, tmp_path):
    """The unit of the sweep scene, its grip inputs carrying the pinned edge into the ball after it has swept
    (test_grip.py's case): the step that blows up is refused with the Python API's cause, the grip pressing a
    pinned particle into collider 1."""
    from test_grip import PRESSED_AFTER, PRESSING, RAMP

    fmu = native.build_native_fmu(tmp_path / "sweep.fmu", 2, build_dir=build["objects"], scene="sweep")
    rows = [(0.0, 0.0, 0.0), (PRESSED_AFTER, 0.0, 0.0), (PRESSED_AFTER + RAMP, PRESSING["grip_y"], PRESSING["grip_z"])]
    records, _ = run_child(GRIP_SIGNAL, fmu, PRESSED_AFTER + 0.5, json.dumps(rows))
    errors = records[-1]["errors"]
    assert errors and "BlowUpError" in errors[0], errors
    assert re.search(r"Likely cause: the grip presses pinned particle \d+ into collider 1 \(a sphere\), whose contact "
                     r"puts it back 0\.001 m off its surface at every step", errors[0]), errors[0]


def test_a_unit_of_another_scene_compiles_its_generated_source_alone(build, tmp_path, monkeypatch):
    """What a unit is built with is one generated source (native.VARIABLES_SOURCE): the units of two scenes
    link the same objects of the core and of the unit's fixed sources (unit.cpp, fmi2.cpp), which a build
    reuses, and each its own object of the generated source.  (708bb22: unit.cpp and fmi2.cpp depended on
    the generated header, and every unit compiled them again, 10 s.)"""
    linked, link = [], native.link
    monkeypatch.setattr(native, "link", lambda compiler, objects, out, version: linked.append(objects) or
                        link(compiler, objects, out, version))
    for k, (nx, ny) in enumerate(((6, 7), (7, 6))):
        path = tmp_path / f"scene{k}.toml"
        path.write_text(f"nx = {nx}\nny = {ny}\n")
        native.build_native_fmu(tmp_path / f"scene{k}.fmu", 2, build_dir=build["objects"], scene=str(path))
    generated = [{p for p in objects if p.name.startswith(Path(native.VARIABLES_SOURCE).stem + "-")}
                 for objects in linked]
    assert all(len(g) == 1 for g in generated) and generated[0] != generated[1]
    assert set(linked[0]) - generated[0] == set(linked[1]) - generated[1]
    assert {p.name.split("-")[0] for p in linked[0]} >= {"unit", "fmi2", "stepping"}


def compiles_counted(monkeypatch, pause: float = 0.0) -> list:
    """The compiler runs of native.compile_objects from now on (each held ``pause`` s more), as a list."""
    runs, run = [], subprocess.run

    def counted(command, **kwargs):
        if "-c" in command:  # (not the compiler's --version, its identity)
            runs.append(command)
            time.sleep(pause)
        return run(command, **kwargs)

    monkeypatch.setattr(native.subprocess, "run", counted)
    return runs


def test_builds_sharing_a_folder_compile_each_object_once(tmp_path, monkeypatch):
    """Two builds (threads here; the lock file is per open file, so processes alike) ask for the same
    object at once: one compiles it while the other waits for its lock, then finds and reuses it."""
    import threading

    source = tmp_path / "small.cpp"
    source.write_text("int small() { return 1; }\n")
    runs = compiles_counted(monkeypatch, pause=0.5)
    found = []
    builders = [threading.Thread(target=lambda: found.append(native.compile_objects(
        native.find_compiler(), [source], [], tmp_path / "objects", [], jobs=1))) for _ in range(2)]
    for builder in builders:
        builder.start()
    for builder in builders:
        builder.join()
    assert len(runs) == 1 and found[0] == found[1] and found[0][0].is_file()


def test_a_folder_that_takes_no_lock_still_builds(tmp_path, monkeypatch):
    """Where flock fails (some network file systems), the object is compiled without the lock."""
    import fcntl

    def refused(*_):
        raise OSError(37, "No locks available")

    monkeypatch.setattr(fcntl, "flock", refused)
    source = tmp_path / "small.cpp"
    source.write_text("int small() { return 1; }\n")
    runs = compiles_counted(monkeypatch)
    objects = native.compile_objects(native.find_compiler(), [source], [], tmp_path / "objects", [], jobs=1)
    assert len(runs) == 1 and objects[0].is_file()


def test_a_unit_built_with_a_scene_turns_its_colliders_by_their_keys_as_the_python_api(build, tmp_path):
    """`build-fmu --native --scene` of a turntable (a box turning 2 rad/s about the vertical under a sheet off
    its axis, tests/test_turning_colliders.py): its keys' rotation columns are compiled in, and the unit
    runs through fmpy as the Python API does, bit for bit; the sheet turns with it (its centroid moves)."""
    import fmpy

    path = tmp_path / "turntable.toml"
    keys = "".join(f"[[collider_key]]\ncollider = 1\ntime = {0.1 * k:.1f}\nrz = {math.degrees(0.2 * k)!r}\n"
                   for k in range(1, 11))
    path.write_text("nx = 5\nny = 5\nwidth = 0.1\nlength = 0.1\ninitial_tilt = 0.0\ninitial_height = 0.2\n"
                    "thickness = 0.002\nwater_level = -0.5\nair_density = 0.0\n[[collider]]\nshape = \"box\"\n"
                    "size_x = 0.6\nsize_y = 0.6\nsize_z = 0.2\nx = -0.15\nz = 0.098999\nfriction = 0.5\n" + keys)
    fmu = native.build_native_fmu(tmp_path / "turntable.fmu", 2, build_dir=build["objects"], scene=str(path))
    result = fmpy.simulate_fmu(str(fmu), stop_time=1.0, output_interval=0.1)
    sim, rows = wetcloth.Simulation(wetcloth.load_scene(path)), []
    for t in result["time"]:
        advance_as_the_unit(sim, t)
        rows.append([sim.outputs()[n] for n in OUTPUT_NAMES])
    assert_agree([[row[n] for n in OUTPUT_NAMES] for row in result], rows, "turntable")
    assert abs(sim.outputs()["centroid_y"]) > 0.05


def test_the_unit_steps_exactly_as_the_cores_simulation(build, checker_library):
    """Whatever the Python package runs on: the unit adds nothing to the core's arithmetic (the outputs of
    fmpy's run are those of a wc::Simulation stepped to the same points, bit for bit)."""
    import fmpy

    values = {"nx": 9, "ny": 13, "absorption_rate": 0.5}
    result = fmpy.simulate_fmu(str(build[2]["dir"]), stop_time=2.0, output_interval=1 / 30, start_values=values,
                               model_description=build[2]["md"])
    core = Checker(checker_library, **values)
    try:
        previous, rows = 0.0, []
        for t in result["time"]:
            assert core.advance(max(0.0, previous + (t - previous) - 0.0 - core.time)) == 0
            previous = t
            rows.append(core["outputs"])
    finally:
        core.close()
    for column, name in enumerate(OUTPUT_NAMES):
        assert_bitwise(result[name].astype(float), np.array(rows)[:, column].copy(), name)


def test_fmi3_mesh_outputs_are_the_python_api_positions_and_wetness(build):
    from wetcloth.fmu.cosim import simulate

    values = {"nx": 9, "ny": 13, "initial_saturation": 0.2, "absorption_rate": 0.5}
    result = simulate(build[3]["fmu"], duration=1.0, fps=20, start_values=values,
                      output=[*OUTPUT_NAMES, "step_error", "positions", "wetness"])
    assert result["positions"].shape == (21, 13, 9, 3) and result["wetness"].shape == (21, 13, 9)
    scene = wetcloth.load_scene(**values)
    sim = wetcloth.Simulation(scene)
    rows, positions, wetness = [], [], []
    for t in result["time"]:
        advance_as_the_unit(sim, t)
        rows.append([*(sim.outputs()[n] for n in OUTPUT_NAMES), sim.error_estimate])
        positions.append(sim.positions)
        wetness.append(sim.wetness)
    assert_agree([[row[n] for n in (*OUTPUT_NAMES, "step_error")] for row in result], rows, "FMI 3.0")
    np.testing.assert_array_equal(result["positions"].reshape(21, -1, 3), positions)
    np.testing.assert_array_equal(result["wetness"].reshape(21, -1), wetness)
    assert result["wetness"][-1].max() > 0.2  # the cloth took up water


def test_fmpy_compiles_the_unit_from_its_sources(build, tmp_path, monkeypatch):
    """sources/ is complete: fmpy's CMake build of it (unoptimised, for speed) runs the same steps."""
    import fmpy
    from fmpy.build import build_platform_binary

    if not shutil.which("cmake"):
        pytest.skip("fmpy builds from sources with cmake, which is not installed")
    unzipped = Path(fmpy.extract(str(build[2]["fmu"]), unzipdir=str(tmp_path / "unit")))
    prebuilt = unzipped / "binaries" / "linux64" / "WetCloth.so"
    prebuilt.unlink()
    monkeypatch.setenv("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
    (tmp_path / "cmake").mkdir()
    build_platform_binary(unzipped, tmp_path / "cmake", configuration="Debug")
    assert prebuilt.is_file()
    values = {"nx": 9, "ny": 9}
    ours = fmpy.simulate_fmu(str(unzipped), stop_time=0.5, output_interval=0.1, start_values=values)
    theirs = fmpy.simulate_fmu(str(build[2]["dir"]), stop_time=0.5, output_interval=0.1, start_values=values,
                               model_description=build[2]["md"])
    # Baseline x86-64 has no fused multiply-add to contract into, and nothing else changes a value between
    # -O0 and -O3 without fast-math: the same numbers.
    for name in OUTPUT_NAMES:
        np.testing.assert_array_equal(ours[name], theirs[name], err_msg=name)


# ----------------------------------------------------------------------------------------- libcosimpy
LIBCOSIM = r"""
import json, sys
from fmpy import read_model_description
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimManipulator import CosimManipulator
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave
fmu, values = sys.argv[1], json.loads(sys.argv[2])
md = read_model_description(fmu)
vr = {v.name: v.valueReference for v in md.modelVariables}
outputs = [v.name for v in md.modelVariables if v.causality == "output"]
execution = CosimExecution.from_step_size(50_000_000)
index = execution.add_local_slave(CosimLocalSlave(fmu_path=fmu, instance_name="cloth"))
observer = CosimObserver.create_last_value()
execution.add_observer(observer)
override = CosimManipulator.create_override()
execution.add_manipulator(override)
for name, value in values.items():
    execution.integer_initial_value(index, vr[name], value)
rows = []
for k in range(12):
    if k == 5:
        assert override.slave_real_values(index, [vr["water_level"]], [0.02])
    assert execution.step()
    rows.append({"time": execution.status().current_time * 1e-9,
                 **dict(zip(outputs, observer.last_real_values(index, [vr[n] for n in outputs])))})
print(json.dumps({"rows": rows}), flush=True)
"""


def test_libcosim_runs_the_native_unit(build, tmp_path):
    pytest.importorskip("libcosimpy")
    records, _ = run_child(LIBCOSIM, build[2]["fmu"], json.dumps(SMALL), cwd=tmp_path)
    rows = records[-1]["rows"]
    assert len(rows) == 12
    assert_like_direct_runs(rows, 5, 0.02, 0.05)
    assert rows[-1]["centroid_z"] > rows[4]["centroid_z"] + 0.01  # the new level reached the cloth


# ----------------------------------------------------------------------------------------- a C master
C_MASTER = r"""
/* A co-simulation master in C: load the unit, set a parameter, step the towel 90 s at 0.1 s, print the outputs. */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include "fmi2FunctionTypes.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    fprintf(stderr, "%s [%d %s] %s\n", name, (int)status, category, message);
}

#define LOAD(type, name) type* name = (type*)dlsym(lib, #name); if (!name) { fprintf(stderr, "no %s\n", #name); return 2; }

int main(int argc, char** argv) {
    if (argc != 6) return 2;
    void* lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 2; }
    LOAD(fmi2InstantiateTYPE, fmi2Instantiate)
    LOAD(fmi2SetRealTYPE, fmi2SetReal)
    LOAD(fmi2GetRealTYPE, fmi2GetReal)
    LOAD(fmi2SetupExperimentTYPE, fmi2SetupExperiment)
    LOAD(fmi2EnterInitializationModeTYPE, fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationModeTYPE, fmi2ExitInitializationMode)
    LOAD(fmi2DoStepTYPE, fmi2DoStep)
    LOAD(fmi2TerminateTYPE, fmi2Terminate)
    LOAD(fmi2FreeInstanceTYPE, fmi2FreeInstance)
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("towel", fmi2CoSimulation, argv[2], "", &callbacks, fmi2False, fmi2False);
    if (!c) return 3;
    const fmi2ValueReference parameter = (fmi2ValueReference)atoi(argv[3]);
    const fmi2Real value = atof(argv[4]);
    fmi2ValueReference outputs[6];
    for (int k = 0; k < 6; ++k) outputs[k] = (fmi2ValueReference)(atoi(argv[5]) + k);
    if (fmi2SetReal(c, &parameter, 1, &value) != fmi2OK) return 4;
    if (fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK) return 5;
    if (fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK) return 6;
    for (int k = 0; k < 900; ++k) {
        const double t = k * 0.1;
        if (fmi2DoStep(c, t, 0.1, fmi2True) != fmi2OK) return 7;
        fmi2Real y[6];
        if (fmi2GetReal(c, outputs, 6, y) != fmi2OK) return 8;
        printf("%.17g %.17g %.17g %.17g %.17g %.17g\n", y[0], y[1], y[2], y[3], y[4], y[5]);
    }
    if (fmi2Terminate(c) != fmi2OK) return 9;
    fmi2FreeInstance(c);
    dlclose(lib);
    return 0;
}
"""


def test_a_c_master_runs_the_towel_for_90_s_without_python(build, tmp_path):
    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        pytest.skip("no C compiler")
    source = tmp_path / "master.c"
    source.write_text(C_MASTER)
    master = tmp_path / "master"
    subprocess.run([compiler, "-std=c99", "-O1", f"-I{build[2]['dir'] / 'sources' / 'fmu'}", "-o", str(master),
                    str(source), "-ldl"], check=True, capture_output=True, text=True)
    md = build[2]["md"]
    vr = {v.name: v.valueReference for v in md.modelVariables}
    env = {"PATH": "/usr/bin:/bin", "LANG": "C"}  # no Python anywhere near: not on the path, no PYTHONPATH
    done = subprocess.run([str(master), str(binary(build)), md.guid, str(vr["absorption_rate"]), "0.3",
                           str(vr["centroid_x"])], capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    got = np.array([[float(x) for x in line.split()] for line in done.stdout.splitlines()])
    assert got.shape == (900, 6)
    scene = wetcloth.load_scene(absorption_rate=0.3)
    sim = wetcloth.Simulation(scene)
    expected = []
    for k in range(900):
        sim.advance(k * 0.1 + 0.1 - sim.time)
        expected.append([sim.outputs()[n] for n in OUTPUT_NAMES])
    assert_agree(got, expected, "C master")
    assert got[-1, OUTPUT_NAMES.index("depth")] > 0.5  # the towel sank


# ----------------------------------------------------------------------------------------- errors
ERRORS = r"""
import json, math, sys
import fmpy
from fmpy import calloc, free
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE)
directory = sys.argv[1]
md = fmpy.read_model_description(directory)
var = {v.name: v for v in md.modelVariables}
messages = []

def logger(env, instance, status, category, message):
    messages.append((int(status), message.decode()))

callbacks = fmi2CallbackFunctions()
callbacks.logger = fmi2CallbackLoggerTYPE(logger)
callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)

def status(call, *args):
    try:
        call(*args)
        return 0
    except FMICallException as exc:
        return int(exc.status)

def new(name):
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName=name)
    fmu.instantiate(callbacks=callbacks, loggingOn=False)  # errors are logged with logging off too
    fmu.setupExperiment(startTime=0.0)
    return fmu

def set(fmu, name, value):
    v = var[name]
    return status({"Real": fmu.setReal, "Integer": fmu.setInteger, "String": fmu.setString}[v.type],
                  [v.valueReference], [value])

def outputs(fmu):
    return fmu.getReal([var[n].valueReference for n in ("centroid_x", "centroid_y", "centroid_z", "depth",
                                                         "wet_mass", "water_mass")])

def since(k):
    return [m for s, m in messages[k:] if s >= 3]

r = {}
fmu = new("bad")
for name, value in [("width", -1.0), ("water_level", float("nan")), ("nx", 1), ("integrator", "bdf3"),
                    ("mesh_format", "stl"), ("drag_model", "fast")]:
    k = len(messages)
    r[f"set {name}"] = [set(fmu, name, value), since(k)]
k = len(messages)
r["init refused"] = [status(fmu.enterInitializationMode), status(fmu.exitInitializationMode), since(k)]
for name, value in [("width", 0.5), ("water_level", 0.0), ("nx", 9), ("integrator", "bdf2"), ("mesh_format", "ply"),
                    ("drag_model", "face")]:
    set(fmu, name, value)
k = len(messages)
r["init ok"] = [status(fmu.exitInitializationMode), since(k)]
r["step ok"] = status(fmu.doStep, 0.0, 0.1)
k = len(messages)
r["input nan"] = [set(fmu, "water_level", float("nan")), status(fmu.doStep, 0.1, 0.1), since(k),
                  all(math.isfinite(x) for x in outputs(fmu))]
r["input fixed"] = [set(fmu, "width", 0.6), set(fmu, "mesh_format", "obj"), since(k)[-2:]]
set(fmu, "width", 0.5); set(fmu, "mesh_format", "ply")
r["input ok again"] = [set(fmu, "water_level", 0.01), status(fmu.doStep, 0.1, 0.1), fmu.getReal([var["water_level"].valueReference])[0]]
k = len(messages)
r["calls"] = [status(fmu.doStep, float("inf"), 0.1), status(fmu.doStep, 0.5, 0.1), status(fmu.doStep, 0.2, -1.0),
              status(fmu.setReal, [var["depth"].valueReference], [1.0]), status(fmu.setReal, [999], [1.0]),
              status(fmu.setInteger, [var["width"].valueReference], [1]), status(fmu.doStep, 0.2, 0.1), since(k)]
r["terminate"] = [status(fmu.terminate), status(fmu.terminate), status(fmu.doStep, 0.3, 0.1)]
fmu.freeInstance()

mesh = new("mesh")
k = len(messages)
r["mesh_output_dir"] = [set(mesh, "mesh_output_dir", "out/frames"), status(mesh.enterInitializationMode),
                        status(mesh.exitInitializationMode), since(k), set(mesh, "mesh_output_dir", ""),
                        status(mesh.exitInitializationMode)]
mesh.freeInstance()

rigid = new("rigid")
k = len(messages)
r["bend_rigidity"] = [set(rigid, "bend_rigidity", 1e-4), status(rigid.enterInitializationMode),
                      status(rigid.exitInitializationMode), since(k)]
rigid.freeInstance()

floor = new("floor")
set(floor, "initial_height", -0.99)
k = len(messages)
r["whole scene"] = [status(floor.enterInitializationMode), status(floor.exitInitializationMode), since(k)]
floor.freeInstance()

cells = new("cells")
set(cells, "length", 0.0011)
k = len(messages)
r["long cells"] = [status(cells.enterInitializationMode), status(cells.exitInitializationMode), since(k)]
cells.freeInstance()

for case, damping in [("stiff explicit", 2.7e5), ("near the smallest step", float(sys.argv[3]))]:
    explicit = new(case)
    set(explicit, "integrator", "explicit_euler")
    set(explicit, "damping", damping)
    k = len(messages)
    r[case] = [status(explicit.enterInitializationMode), status(explicit.exitInitializationMode)]
    if case == "near the smallest step":  # a current that would take the bound below it, refused, then undone
        r[case] += [status(explicit.doStep, 0.0, 2e-8), set(explicit, "current_x", 10.0),
                    status(explicit.doStep, 2e-8, 2e-8), set(explicit, "current_x", 0.0),
                    status(explicit.doStep, 2e-8, 2e-8)]
    r[case].append(since(k))
    explicit.freeInstance()

blow = new("blow up")
values = json.loads(sys.argv[2])
for name, value in values.items():
    set(blow, name, value)
blow.enterInitializationMode(); blow.exitInitializationMode()
t, statuses = 0.0, []
for i in range(20):
    s = status(blow.doStep, t, 0.05)
    statuses.append(s)
    if s:
        break
    t += 0.05
k = len(messages)
r["blow up"] = [statuses, t, blow.getRealStatus(2), blow.getBooleanStatus(3), all(math.isfinite(x) for x in outputs(blow)),
                [m for s, m in messages if "BlowUpError" in m]]
blow.freeInstance()

gripped = new("blow up while the grip moves")
set(gripped, "pinned_edge", "y_max")
gripped.enterInitializationMode(); gripped.exitInitializationMode()
t, statuses, k = 0.0, [], len(messages)
for grip_z in (0.02, 0.04, 0.06, 1e3):  # the grip lifts the pinned edge 2 cm a step, then flings it 1 km
    set(gripped, "grip_z", grip_z)
    statuses.append(status(gripped.doStep, t, 0.05))
    t += 0.05
r["blow up while the grip moves"] = [statuses, all(math.isfinite(x) for x in outputs(gripped)), since(k)]
gripped.freeInstance()
print(json.dumps(r))
"""


@pytest.fixture(scope="module")
def errors(build):
    near_damping = explicit_near_the_smallest_step(1e-6).damping  # (the stability rule's edge, N s/m)
    records, _ = run_child(ERRORS, build[2]["dir"], json.dumps(BLOW_UP), repr(near_damping))
    return records[-1]


def python_message(name, value) -> str:
    with pytest.raises(ParameterError) as exc:
        check_value(name, value)
    return str(exc.value)


def test_bad_values_are_fmi2_errors_naming_the_parameter_and_its_range(errors):
    for name, value in [("width", -1.0), ("water_level", float("nan")), ("nx", 1), ("integrator", "bdf3"),
                        ("drag_model", "fast")]:
        status, messages = errors[f"set {name}"]
        assert status == 3, name  # fmi2Error
        assert len(messages) == 1 and messages[0].startswith(python_message(name, value)), (name, messages)
        assert "(value refused:" in messages[0]
    assert "(did you mean 'bdf2'?)" in errors["set integrator"][1][0]
    assert errors["set mesh_format"][0] == 3
    assert "parameter 'mesh_format': 'stl' is not allowed; allowed: one of 'ply', 'obj'" in errors["set mesh_format"][1][0]
    enter, exit_, messages = errors["init refused"]
    assert (enter, exit_) == (0, 3)
    assert messages[0].startswith("initialization refused: parameter 'width': -1.0 is out of range")
    assert all(name in messages[0] for name in ("'nx'", "'integrator'", "'water_level'", "'mesh_format'"))
    assert errors["init ok"] == [0, []] and errors["step ok"] == 0


def test_bad_inputs_during_the_run_discard_steps_until_fixed(errors):
    set_status, step_status, messages, finite = errors["input nan"]
    assert (set_status, step_status, finite) == (3, 2, True)
    assert messages[0].startswith(python_message("water_level", float("nan")))
    assert messages[1].startswith("step refused at t = 0.1 s: parameter 'water_level': nan is not a finite number")
    fixed_width, fixed_format, messages = errors["input fixed"]
    assert (fixed_width, fixed_format) == (3, 3)
    assert "parameter 'width' is fixed once the simulation starts; only inputs may change" in messages[0]
    assert "parameter 'mesh_format' is fixed once the unit is initialized" in messages[1]
    assert errors["input ok again"] == [0, 0, 0.01]


def test_calls_the_master_must_not_make_are_errors_and_change_nothing(errors):
    *statuses, messages = errors["calls"]
    assert statuses == [3, 2, 3, 3, 3, 3, 0]  # inf time, wrong time (Discard), negative step, output, vr, type; ok
    text = "\n".join(messages)
    assert "finite communication point" in text and "restore an FMU state to go back in time" in text
    assert "'depth' is an output" in text and "value reference 999" in text and "'width' is a Real" in text
    assert errors["terminate"] == [0, 0, 3]


def test_a_unit_of_the_grid_declares_and_takes_no_bend_rigidity(build, errors):
    """Built without hinges, its families have none (a unit built from a scene with bend_rigidity lists the
    grid's springs and hinges: tests/test_fmu_native_mesh.py): the model description declares bend_rigidity 0
    only, and a value above 0 is an FMI error naming it and what is allowed."""
    declared = {v.name: v for v in build[2]["md"].modelVariables}["bend_rigidity"]
    assert float(declared.min) == float(declared.max) == 0.0
    statuses, messages = errors["bend_rigidity"][:3], errors["bend_rigidity"][3]
    assert statuses == [3, 0, 3]  # the set call, and the initialization it left refused (as for other values)
    assert messages[0].startswith("parameter 'bend_rigidity': 0.0001 is out of range; allowed: 0 N m in this native "
                                  "unit of the built-in grid, built without hinges")
    assert messages[1].startswith("initialization refused: parameter 'bend_rigidity'")


def test_mesh_output_dir_is_refused_with_a_logged_message(errors):
    set_status, enter, exit_, messages, cleared, retried = errors["mesh_output_dir"]
    assert (set_status, enter, exit_) == (3, 0, 3)
    assert messages[0].startswith("parameter 'mesh_output_dir': 'out/frames' is not allowed: this unit")
    assert "writes no mesh frames" in messages[0]
    assert messages[1].startswith("initialization refused: parameter 'mesh_output_dir'")
    assert (cleared, retried) == (0, 0)


def test_parameters_that_do_not_fit_together_fail_the_initialization(errors):
    enter, exit_, messages = errors["whole scene"]
    assert (enter, exit_) == (0, 3)
    with pytest.raises(ParameterError) as exc:
        wetcloth.load_scene(initial_height=-0.99)
    assert messages == [f"initialization refused: {exc.value}"]


def test_cells_far_longer_than_wide_fail_the_initialization_as_in_the_python_api(errors):
    enter, exit_, messages = errors["long cells"]
    assert (enter, exit_) == (0, 3)
    with pytest.raises(ParameterError, match="'ny': the grid's cells are") as exc:
        wetcloth.load_scene(length=0.0011)
    assert messages == [f"initialization refused: {exc.value}"]


def test_an_explicit_scheme_below_the_smallest_step_is_refused_as_in_the_python_api(errors):
    """The rule of tests/test_sanity.py, in the native unit: refused at initialization; an input that would take
    the bound below the smallest step refused (steps discarded until it is set back, as for any refused input);
    the messages the Python API's."""
    near = explicit_near_the_smallest_step(1e-6)
    stiff, near_run = errors["stiff explicit"], errors["near the smallest step"]
    with pytest.raises(ParameterError) as refused:
        wetcloth.Simulation(wetcloth.load_scene(integrator="explicit_euler", damping=2.7e5))
    assert stiff == [0, 3, [f"initialization refused: {refused.value}"]]
    sim = wetcloth.Simulation(near)
    sim.advance(2e-8)
    with pytest.raises(ParameterError) as input_refused:
        sim.set_inputs(current_x=10.0)
    assert near_run[:7] == [0, 0, 0, 3, 2, 0, 0], near_run
    assert near_run[7][0].startswith(f"{input_refused.value} (value refused: current_x stays 0.0)"), near_run[7]
    assert near_run[7][1].startswith("step refused at t = 2e-08 s: "), near_run[7]


def test_a_blow_up_is_discarded_naming_the_time_and_the_unit_stays_finite(errors):
    statuses, t, last_successful, terminated, finite, messages = errors["blow up"]
    assert statuses[-1] == 2 and set(statuses[:-1]) <= {0}  # fmi2Discard
    assert t == pytest.approx(last_good_time(BLOW_UP, 0.05)) and last_successful == t
    assert terminated and finite
    assert len(messages) == 1
    assert messages[0].startswith(f"step from t = {t:g} s by 0.05 s failed: BlowUpError: the cloth state ")
    assert "Last good time:" in messages[0] and messages[0].endswith(f"The unit stays at t = {t:g} s with its last "
                                                                     "good outputs.")
    # In the Python API's words (its advice names the explicit scheme's stability bound).
    exc = python_blow_up(wetcloth.scene.from_dict(BLOW_UP), t + 0.05, {})
    assert "explicit_euler is stable on this cloth at rest at steps up to" in str(exc)
    assert f"BlowUpError: {exc} The unit stays at" in messages[0], (messages[0], str(exc))


def test_a_blow_up_while_the_grip_moves_is_discarded_too(errors):
    """A grip input that flings the pinned edge 1 km in a step blows it up; the unit goes back to the step's
    start, where the grip was moving the pinned particles (their velocities not zero).  (Before, it could not: "snapshot of a state the cloth cannot be in: ... pinned particles do not
    move", and the step was an fmi2Error.)"""
    statuses, finite, messages = errors["blow up while the grip moves"]
    assert statuses == [0, 0, 0, 2]  # fmi2Discard of the step that flings the grip 1 km
    assert finite
    assert len(messages) == 1 and "BlowUpError" in messages[0] and "could not go back" not in messages[0]


# ----------------------------------------------------------------------------------------- FMU states
STATES = r"""
import json, sys
import fmpy
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
directory, version = sys.argv[1], int(sys.argv[2])
md = fmpy.read_model_description(directory)
vr = {v.name: v.valueReference for v in md.modelVariables}
outputs = [vr[n] for n in ("centroid_x", "centroid_y", "centroid_z", "depth", "wet_mass", "water_mass")]
messages = []

def status(call, *args):
    try:
        call(*args)
        return 0
    except FMICallException as exc:
        return int(exc.status)

if version == 2:
    from fmpy import calloc, free
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                           fmi2CallbackLoggerTYPE)
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(lambda env, name, status, category, message: messages.append(message.decode()))
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    def new(name, **values):
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName=name)
        fmu.instantiate(callbacks=callbacks, loggingOn=False)
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        for key, value in values.items():
            (fmu.setInteger if key in ("nx", "ny") else fmu.setReal)([vr[key]], [value])
        fmu.exitInitializationMode()
        return fmu
    def read(fmu):
        return fmu.getReal(outputs)
    get, set_, ser, deser, free_ = "getFMUstate", "setFMUstate", "serializeFMUstate", "deSerializeFMUstate", "freeFMUstate"
else:
    from fmpy.fmi3 import FMU3Slave
    def new(name, **values):
        fmu = FMU3Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName=name)
        fmu.instantiate(loggingOn=False, logMessage=lambda env, status, category, message: messages.append(message.decode()))
        for key, value in values.items():
            (fmu.setUInt64 if key in ("nx", "ny") else fmu.setFloat64)([vr[key]], [value])
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        return fmu
    def read(fmu):
        return fmu.getFloat64(outputs)
    get, set_, ser, deser, free_ = "getFMUState", "setFMUState", "serializeFMUState", "deserializeFMUState", "freeFMUState"

def run(fmu, t, steps, h=0.1, level_at=3):
    rows = []
    for k in range(steps):
        if k == level_at:
            (fmu.setReal if version == 2 else fmu.setFloat64)([vr["water_level"]], [0.02])
        assert status(fmu.doStep, t, h) == 0
        t += h
        row = list(read(fmu))
        if version == 3:
            n = 21 * 29
            row += list(fmu.getFloat64([vr["positions"], vr["wetness"]], nValues=4 * n))
        rows.append(row)
    return rows

r = {}
a = new("a", initial_tilt=30.0, absorption_rate=0.5)
run(a, 0.0, 10, level_at=None)  # the landing: steps, contacts, the preconditioner's factors
state = getattr(a, get)()
data = getattr(a, ser)(state)
first = run(a, 1.0, 15)
getattr(a, set_)(state)
second = run(a, 1.0, 15)
b = new("b", initial_tilt=30.0, absorption_rate=0.5)
restored = getattr(b, deser)(data)
getattr(b, set_)(restored)
third = run(b, 1.0, 15)
r["repeat"] = [first == second, first == third, len({tuple(x) for x in first}) == len(first)]
# A state of another grid is refused; the unit keeps its own state and steps on.
small = new("small", nx=9, ny=9)
small_state = getattr(small, deser)(getattr(small, ser)(getattr(small, get)()))
getattr(b, set_)(state)
before = list(read(b))
k = len(messages)
r["other grid"] = [status(getattr(b, set_), small_state), messages[k:]]
r["unchanged"] = list(read(b)) == before
r["steps on"] = run(b, 1.0, 15) == first
r["bad bytes"] = [status(getattr(b, deser), bytes(data[:-3])), status(getattr(b, deser), b"x" * 64),
                  status(getattr(b, deser), bytes(data[:100]) + bytes(100) + bytes(data[200:]))]
r["after bad bytes"] = status(b.doStep, 2.5, 0.1)
print(json.dumps(r))
"""


@pytest.mark.parametrize("version", [2, 3])
def test_fmu_states_repeat_the_run_bit_for_bit_and_refuse_another_grid(build, version):
    records, done = run_child(STATES, build[version]["dir"], version)
    r = records[-1]
    assert r["repeat"] == [True, True, True]  # the same instance and a fresh one, from bytes
    status, messages = r["other grid"]
    assert status == 3 and r["unchanged"] and r["steps on"]  # fmi2Error / fmi3Error, and the unit is usable
    assert messages == ["FMU state refused, the unit is unchanged: the state is of a cloth of nx x ny = 9 x 9 "
                        "particles, this unit runs 21 x 29 (fixed once it is initialized)"]
    assert r["bad bytes"] == [3, 3, 3] and r["after bad bytes"] == 0


# ----------------------------------------------------------------------------------------- the trial's findings
#: A child process: the unit at argv[1] run through fmpy to argv[2] s (output interval 0.05 s), with the input
#: rows of the JSON argv[3] ({"names": [...], "rows": [[time, value, ...], ...]}, linear between them, a
#: repeated time a jump) and start values of the JSON argv[4]; prints the messages logged with a blow-up.
BLOW_UP_RUN = r"""
import json, sys
import numpy as np
import fmpy
inputs, start = json.loads(sys.argv[3]), json.loads(sys.argv[4])
signal = None
if inputs["rows"]:
    signal = np.array([tuple(r) for r in inputs["rows"]], dtype=[("time", float)] + [(n, float) for n in inputs["names"]])
messages = []
fmpy.simulate_fmu(sys.argv[1], stop_time=float(sys.argv[2]), output_interval=0.05, input=signal, start_values=start,
                  logger=lambda component, instance, status, category, message: messages.append(message.decode()))
print(json.dumps({"blow_ups": [m for m in messages if "BlowUpError" in m]}))
"""


def python_blow_up(scene: wetcloth.Scene, stop: float, inputs: dict) -> wetcloth.BlowUpError:
    """The BlowUpError of ``scene`` advanced as fmpy steps a unit (0.05 s) with ``inputs`` ({time: values}:
    set from that time on)."""
    sim = wetcloth.Simulation(scene)
    with pytest.raises(wetcloth.BlowUpError) as exc:
        for k in range(round(stop / 0.05)):
            t = k * 0.05
            for at, values in inputs.items():
                if t >= at - 1e-12:
                    sim.set_inputs(**values)
            advance_as_the_unit(sim, t + 0.05)
    return exc.value


def test_a_blow_up_from_a_fast_grip_input_names_it_as_the_python_api_does(build, tmp_path):
    """The lift's unit, its grip_z input jumping from 0 to 9999 m at t = 0.1 s (the trial's finding 1): the
    step that blows up is refused naming the grip inputs' move, in the Python API's words (before, the native
    unit blamed the step and stretch_stiffness)."""
    fmu = native.build_native_fmu(tmp_path / "lift.fmu", 2, build_dir=build["objects"], scene="lift")
    rows = {"names": ["grip_z"], "rows": [[0.0, 0.0], [0.1, 0.0], [0.1, 9999.0], [0.3, 9999.0]]}
    records, _ = run_child(BLOW_UP_RUN, fmu, 0.3, json.dumps(rows), "{}")
    blow_ups = records[-1]["blow_ups"]
    exc = python_blow_up(wetcloth.load_scene("lift"), 0.3, {0.1: {"grip_z": 9999.0}})
    assert "Likely cause: the grip's inputs (grip_z) move the pinned particles 1e+04 m over the 0.05 s" in str(exc)
    assert len(blow_ups) == 1 and f"BlowUpError: {exc} The unit stays at" in blow_ups[0], (blow_ups, str(exc))


def test_a_blow_up_from_a_fast_collider_key_names_it_as_the_python_api_does(build, tmp_path):
    """The sweep scene with its ball's first key 100 m away 1 us after the start: the unit built from it
    refuses the first step naming collider_key1's move, in the Python API's words."""
    scene_file = tmp_path / "sweep_fast.toml"
    text = (wetcloth.scene.preset_dir() / "sweep.toml").read_text()
    assert "time = 0.5\ny = 0.0" in text
    scene_file.write_text(text.replace("time = 0.5\ny = 0.0", "time = 1e-6\ny = 100.0", 1))
    blames_as_python(build, scene_file, "Likely cause: collider_key1 moves collider 1 100 m in 1e-06 s from t = 0 s: "
                                        "1e+08 m/s")


def blames_as_python(build, scene_file, says: str) -> None:
    """The native unit of scene_file refuses its first 0.1 s with the Python API's BlowUpError, which `says`."""
    fmu = native.build_native_fmu(scene_file.with_suffix(".fmu"), 2, build_dir=build["objects"], scene=scene_file)
    records, _ = run_child(BLOW_UP_RUN, fmu, 0.1, json.dumps({"names": [], "rows": []}), "{}")
    blow_ups = records[-1]["blow_ups"]
    exc = python_blow_up(wetcloth.load_scene(scene_file), 0.1, {})
    assert says in str(exc)
    assert len(blow_ups) == 1 and f"BlowUpError: {exc} The unit stays at" in blow_ups[0], (blow_ups, str(exc))


def test_a_blow_up_from_a_fast_collider_key_among_interleaved_keys_names_the_scenes_key(build, tmp_path):
    """The sweep scene with a second ball and keys of the two interleaved (collider 2, 1, 2), the second flinging
    the first ball 100 m in 1 us: the unit names it collider_key2, as the Python API does (before, its place among
    the keys by collider, then time: collider_key1)."""
    scene_file = tmp_path / "interleaved.toml"
    text = (wetcloth.scene.preset_dir() / "sweep.toml").read_text()
    keys = text.index("[[collider_key]]")
    scene_file.write_text(text[:keys] + """[[collider]]
shape = "sphere"
x = 2.0
radius = 0.1

[[collider_key]]
collider = 2
time = 0.5
x = 2.1

[[collider_key]]
collider = 1
time = 1e-6
y = 100.0

[[collider_key]]
collider = 2
time = 1.0
x = 2.2

""" + text[text.index("[run]"):])
    blames_as_python(build, scene_file, "Likely cause: collider_key2 moves collider 1 100 m in 1e-06 s from t = 0 s")


#: A child process: the unit of FMI version argv[2] extracted at argv[1], driven through the calls of the
#: trial's findings 2 to 4 (the blow-up's values: the JSON argv[3]); prints what each returned and logged.
TRIAL_CALLS = r"""
import ctypes, json, math, sys
import fmpy
from test_fmu_support import call_status as status
directory, version, blow_up = sys.argv[1], int(sys.argv[2]), json.loads(sys.argv[3])
md = fmpy.read_model_description(directory)
vr = {v.name: v.valueReference for v in md.modelVariables}
messages = []

def since(k):
    return [[s, m] for s, m in messages[k:]]

if version == 2:
    from fmpy.fmi2 import FMU2Slave
    from test_fmu_support import message_callbacks
    callbacks = message_callbacks(messages)
    def instance(name):
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName=name)
        fmu.instantiate(callbacks=callbacks, loggingOn=False)
        return fmu
    def setup(fmu, tolerance):
        return status(fmu.setupExperiment, tolerance=tolerance, startTime=0.0)
    def start(fmu, **values):
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        for key, value in values.items():
            set_value(fmu, key, value)
        fmu.exitInitializationMode()
    def set_value(fmu, key, value):
        if isinstance(value, str):
            return status(fmu.setString, [vr[key]], [value])
        return status(fmu.setInteger if key in ("nx", "ny") else fmu.setReal, [vr[key]], [value])
    def step(fmu, t, h):
        s = status(fmu.doStep, t, h)
        return [s, bool(fmu.getBooleanStatus(3))]  # fmi2Terminated
else:
    from fmpy.fmi3 import FMU3Slave, fmi3Boolean, fmi3Float64
    def instance(name):
        fmu = FMU3Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier="WetCloth", instanceName=name)
        fmu.instantiate(loggingOn=False, logMessage=lambda env, s, category, m: messages.append((int(s), m.decode())))
        return fmu
    def setup(fmu, tolerance):
        return status(fmu.enterInitializationMode, tolerance=tolerance, startTime=0.0)
    def start(fmu, **values):
        for key, value in values.items():
            set_value(fmu, key, value)
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
    def set_value(fmu, key, value):
        if isinstance(value, str):
            return status(fmu.setString, [vr[key]], [value])
        return status(fmu.setUInt64 if key in ("nx", "ny") else fmu.setFloat64, [vr[key]], [value])
    def step(fmu, t, h):
        flags = [fmi3Boolean(), fmi3Boolean(), fmi3Boolean(), fmi3Float64()]
        s = status(fmu.fmi3DoStep, fmu.component, t, h, fmi3Boolean(False), *map(ctypes.byref, flags))
        return [s, bool(flags[1].value)]  # terminateSimulation

r = {}
# finding 3: the experiment's tolerance
for value in (float("nan"), -1.0, 0.0):
    fmu = instance("tolerance")
    k = len(messages)
    r[f"tolerance {value}"] = [setup(fmu, value), since(k)]
    fmu.freeInstance()
fmu = instance("tolerance")
k = len(messages)
r["tolerance 1e-4"] = [setup(fmu, 1e-4), since(k)]
if version == 2:  # (FMI 3.0 enters initialization mode with it: no second call)
    k = len(messages)
    r["tolerance again"] = [setup(fmu, 1e-3), since(k)]
else:
    r["tolerance again"] = [0, []]
fmu.freeInstance()
# findings 2 and 4: a pending refused value, a step at the wrong time
fmu = instance("pending")
start(fmu, nx=9, ny=9)
r["first step"] = step(fmu, 0.0, 0.1)
k = len(messages)
r["refused input"] = [set_value(fmu, "water_level", float("nan")), step(fmu, 0.1, 0.1), since(k)]
k = len(messages)
r["wrong time"] = [step(fmu, 0.5, 0.1), since(k)]
r["fixed"] = [set_value(fmu, "water_level", 0.01), step(fmu, 0.1, 0.1)]
fmu.freeInstance()
# a blow-up: the run cannot go on
fmu = instance("blow up")
start(fmu, **blow_up)
t, result = 0.0, None
for i in range(40):
    result = step(fmu, t, 0.05)
    if result[0]:
        break
    t += 0.05
r["blow up"] = result
fmu.freeInstance()
print(json.dumps(r))
"""


@pytest.fixture(scope="module", params=[2, 3])
def trial_calls(build, request):
    """TRIAL_CALLS' record, and the FMI version it drove."""
    records, _ = run_child(TRIAL_CALLS, build[request.param]["dir"], request.param, json.dumps(BLOW_UP),
                           env=os.environ | {"PYTHONPATH": str(Path(__file__).parent)})
    return records[-1], request.param


def test_the_experiment_tolerance_is_checked_and_said_to_be_unused(trial_calls):
    """The trial's finding 3: a defined tolerance that is NaN or <= 0 is an FMI error naming it; a valid one is
    taken with a warning (the unit's accuracy is its parameter 'tolerance's), once (before, both were ignored
    silently)."""
    r, version = trial_calls
    call = "fmi2SetupExperiment" if version == 2 else "fmi3EnterInitializationMode"
    for value, text in ((math.nan, "nan"), (-1.0, "-1.0"), (0.0, "0.0")):
        status, messages = r[f"tolerance {value}"]
        assert status == 3, value  # Error
        assert messages == [[3, f"{call}: tolerance {text} is not allowed; allowed: a tolerance > 0 where "
                                 "toleranceDefined is true (or none). The unit's accuracy is set by its own parameter "
                                 "'tolerance', not by the experiment's"]], value
    status, messages = r["tolerance 1e-4"]
    assert status == 0 and len(messages) == 1 and messages[0][0] == 1  # a warning, with fmi2Warning / fmi3Warning
    assert messages[0][1].startswith(f"{call}: the experiment's tolerance 0.0001 is not used: the unit's accuracy is "
                                     "set by its own parameter 'tolerance'")
    assert r["tolerance again"] == [0, []]  # once


def test_a_step_refused_for_a_pending_value_does_not_end_the_run(trial_calls):
    """The trial's finding 2: after a doStep discarded because a refused input is pending, the run can go on
    once a valid value is set: fmi2Terminated (FMI 3.0: doStep's terminateSimulation) is false; after a
    blow-up, where it cannot, true (before, true after any Discard)."""
    r, _ = trial_calls
    assert r["first step"] == [0, False]
    set_status, (step_status, terminated), messages = r["refused input"]
    assert (set_status, step_status, terminated) == (3, 2, False)
    assert messages[-1][1].startswith("step refused at t = 0.1 s: parameter 'water_level': nan")
    assert r["fixed"] == [0, [0, False]]
    assert r["blow up"] == [2, True]


def test_a_step_at_the_wrong_time_says_so_while_a_value_is_pending(trial_calls):
    """The trial's finding 4: a doStep from another time than the unit's, while a refused value is pending, is
    refused naming both times (before: "step refused at t = 0.5 s: parameter 'water_level' ...")."""
    r, _ = trial_calls
    (step_status, terminated), messages = r["wrong time"]
    assert (step_status, terminated) == (2, False)
    assert messages == [[3, "doStep from t = 0.5 s, but the unit is at t = 0.1 s; restore an FMU state to go back "
                            "in time"]]


def test_forgetting_unused_objects_passes_over_one_renamed_while_listed(tmp_path, monkeypatch):
    """Builds sharing an objects folder: another build's object, listed under its temporary name, may be renamed
    before it is looked at (a FileNotFoundError failed a build in the fresh-clone CI); old objects still go."""
    import time as clock

    old, new = tmp_path / "old.o", tmp_path / "new.o"
    old.write_bytes(b"")
    new.write_bytes(b"")
    long_ago = clock.time() - (native.KEEP_OBJECTS_DAYS + 1) * 86400.0
    os.utime(old, (long_ago, long_ago))
    listed = [tmp_path / "x.o.tmp.o", old, new]  # the first renamed away between the listing and its stat
    monkeypatch.setattr(type(tmp_path), "glob", lambda self, pattern: listed if pattern == "*.o" else [])
    native._forget_unused(tmp_path)
    assert not old.exists() and new.exists()
