"""The FMI 3.0 units of a cloth from a mesh file (`build-fmu --fmi 3 --scene`) pass its face structure and UVs
through as constant array outputs (issue 26): `faces` (UInt64, one row of vertex indices per face, as in the
file) and `uv` (Float64, n x 2), in the model description and through fmi3GetUInt64 / fmi3GetFloat64, in the
pythonfmu3 unit and the native one."""

from __future__ import annotations

import numpy as np
from test_fmu_support import run_child

from wetcloth.fmu import native
from wetcloth.fmu.builder import build_fmu

#: A child process: the FMI 3.0 unit at argv[1]: its `faces` and `uv` as its model description declares them
#: (dimensions, start) and as fmi3GetUInt64 / fmi3GetFloat64 give them after instantiation.
READ = r"""
import json, sys
import fmpy
from fmpy.fmi3 import FMU3Slave
directory = fmpy.extract(sys.argv[1])
md = fmpy.read_model_description(directory)
v = {x.name: x for x in md.modelVariables}
unit = FMU3Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier=md.coSimulation.modelIdentifier,
                 instanceName="mesh")
unit.instantiate()
out = {}
for name, get in (("faces", unit.getUInt64), ("uv", unit.getFloat64)):
    shape = [int(d.start) for d in v[name].dimensions]
    out[name] = {"type": v[name].type, "variability": v[name].variability, "causality": v[name].causality,
                 "shape": shape, "start": [float(x) for x in str(v[name].start).split()],
                 "got": [float(x) for x in get([v[name].valueReference], nValues=shape[0] * shape[1])]}
unit.freeInstance()  # never initialized: FMI allows no Terminate here
print(json.dumps(out))
"""


def quad_mesh(folder):
    """An OBJ of 4 x 3 vertices (the interior ones moved: it is no grid) in 6 quads, with per-vertex UVs that
    float32 holds exactly; the scene of it; its faces (from 0) and UVs."""
    points, uv = [], []
    for j in range(3):
        for i in range(4):
            inside = 0 < i < 3 and j == 1
            points.append((0.1 * i + (0.013 if inside else 0.0), 0.1 * j - (0.007 * i if inside else 0.0), 0.2))
            uv.append((i / 4 + j / 64, j / 8 + 0.25))
    faces = [(j * 4 + i, j * 4 + i + 1, (j + 1) * 4 + i + 1, (j + 1) * 4 + i) for j in range(2) for i in range(3)]
    text = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in points) + "".join(f"vt {u!r} {w!r}\n" for u, w in uv)
    text += "".join("f " + " ".join(f"{k + 1}/{k + 1}" for k in face) + "\n" for face in faces)
    (folder / "quads.obj").write_text(text)
    scene = folder / "quads.toml"
    scene.write_text('cloth_mesh = "quads.obj"\nwater_level = -0.5\n')
    return scene, faces, uv


def test_the_fmi3_units_of_a_mesh_cloth_give_its_faces_and_uvs_as_the_file_has_them(tmp_path, native_objects):
    """Both FMI 3.0 units of the quad mesh: `faces` is a constant UInt64 output [6, 4] equal to the file's quads,
    `uv` a constant Float64 output [12, 2] equal to its UVs, in the model description and through the API.
    (bb80f15: the units have no such variables.)"""
    scene, faces, uv = quad_mesh(tmp_path)
    units = {"pythonfmu3": build_fmu(tmp_path / "Quads3.fmu", fmi_version=3, scene=scene),
             "native": native.build_native_fmu(tmp_path / "QuadsNative3.fmu", 3, build_dir=native_objects,
                                               scene=scene)}
    for label, fmu in units.items():
        (read,), _ = run_child(READ, fmu, cwd=tmp_path)
        for name, kind, expected in (("faces", "UInt64", faces), ("uv", "Float64", uv)):
            got = read[name]
            assert (got["type"], got["variability"], got["causality"]) == (kind, "constant", "output"), label
            assert got["shape"] == list(np.shape(expected)), label
            assert got["start"] == got["got"] == np.ravel(expected).tolist(), (label, name)
