"""A mesh given as arrays rather than a file (what the Blender extension hands wetcloth): ``cloth_mesh``
takes a MeshFile of wetcloth.mesh_file.make_mesh, a mesh collider's ``file`` one of
wetcloth.mesh_file.surface; they run as the same meshes read from files, with no meshio or trimesh."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

from wetcloth.errors import ParameterError
from wetcloth.exporter import open_sequence
from wetcloth.mesh_file import make_mesh, surface
from wetcloth.scene import from_dict
from wetcloth.simulation import Simulation

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "docs"))
from make_meshes import round_cloth  # noqa: E402

TIMES = np.array([0.25, 0.5])


def cup(segments: int = 16, radius: float = 0.3, height: float = 0.16):
    """An open cylinder with a bottom, from z = -height / 2 (a shell): points and triangles."""
    phi = np.arange(segments) * 2 * np.pi / segments
    ring = np.column_stack([radius * np.cos(phi), radius * np.sin(phi)])
    points = np.vstack([np.column_stack([ring, np.full(segments, z)]) for z in (-height / 2, height / 2)]
                       + [[[0.0, 0.0, -height / 2]]])
    i = np.arange(segments)
    j = (i + 1) % segments
    triangles = np.concatenate([np.column_stack([i, j, j + segments]), np.column_stack([i, j + segments, i + segments]),
                                np.column_stack([np.full(segments, 2 * segments), j, i])])
    return points, triangles


@pytest.fixture(scope="module")
def disc():
    points, triangles = round_cloth(rings=6)
    pins = np.zeros(len(points))
    pins[[np.argmin(points[:, 0]), np.argmax(points[:, 0])]] = 1.0  # a vertex at each end along x
    return points + [0.0, 0.0, 0.12], triangles, pins


def test_arrays_run_as_the_same_meshes_from_files(tmp_path, disc):
    """The disc (pinned by a point attribute) over a cup, from binary PLY files (float64, exact) and as
    arrays: the same mesh, so the same run to the last bit."""
    points, triangles, pins = disc
    cloth_file, cup_file = tmp_path / "disc.ply", tmp_path / "cup.ply"
    meshio.write(cloth_file, meshio.Mesh(points, [("triangle", triangles.astype(np.int32))], point_data={"pin": pins}),
                 binary=True)
    cup_points, cup_triangles = cup()
    meshio.write(cup_file, meshio.Mesh(cup_points, [("triangle", cup_triangles.astype(np.int32))]), binary=True)
    common = {"pinned_vertices": "pin", "self_collision": "off"}
    from_files = from_dict(common | {"cloth_mesh": str(cloth_file), "collider1_shape": "mesh",
                                     "collider1_file": str(cup_file)})
    from_arrays = from_dict(common | {"cloth_mesh": make_mesh(points, [triangles], {"pin": pins}),
                                      "collider1_shape": "mesh", "collider1_file": surface(cup_points, cup_triangles)})
    runs = [Simulation(scene) for scene in (from_files, from_arrays)]
    for sim in runs:
        sim.sample(TIMES)
    assert runs[0].model.topology.pinned.sum() == 2
    np.testing.assert_array_equal(runs[1].positions, runs[0].positions)
    assert np.abs(runs[1].positions - points).max() > 0.01  # it moved


def test_a_scene_keeps_its_arrays_and_records_their_names(tmp_path, disc):
    """replace() keeps the same mesh objects; frames.json names them by their source text."""
    points, triangles, _ = disc
    mesh, wall = make_mesh(points, [triangles], shown="Blender object 'Cloth'"), surface(*cup(), "collider 'Cup'")
    scene = from_dict({"cloth_mesh": mesh, "collider1_shape": "mesh", "collider1_file": wall})
    moved = scene.replace(water_level=-0.2)
    assert moved.cloth_mesh is mesh and moved.colliders[0].file is wall and moved.water_level == -0.2
    sequence = open_sequence(tmp_path / "frames", fmt="ply", scene=scene, faces="triangles")
    sequence.close()
    recorded = json.loads((tmp_path / "frames" / "frames.json").read_text())["scene"]
    assert (recorded["cloth_mesh"], recorded["collider1_file"]) == ("Blender object 'Cloth'", "collider 'Cup'")


def test_bad_arrays_are_refused_naming_the_parameter(disc):
    points, triangles, _ = disc
    with pytest.raises(ParameterError, match="collider1_file.*indices are not all in 0..32"):
        from_dict({"collider1_shape": "mesh", "collider1_file": surface(cup()[0], [[0, 1, 99]], "cup")})
    with pytest.raises(ParameterError, match="collider1_file.*'flat' has no faces with an area"):
        from_dict({"collider1_shape": "mesh", "collider1_file": surface(np.zeros((3, 3)), [[0, 1, 2]], "'flat'")})
    with pytest.raises(ParameterError, match="parameter 'nx': expected a number"):
        from_dict({"nx": make_mesh(points, [triangles])})
    with pytest.raises(ParameterError, match="cloth_mesh.*expected a string"):
        from_dict({"cloth_mesh": 3})


def test_the_arrays_path_imports_neither_meshio_nor_trimesh(tmp_path):
    """What Blender runs (it ships neither): a mesh cloth over a mesh collider, simulated and written to USD."""
    script = f"""
import sys, numpy as np
from wetcloth.mesh_file import make_mesh, surface
from wetcloth.scene import from_dict
from wetcloth.simulation import Simulation
from wetcloth.exporter import open_sequence
from wetcloth.topology import build_topology
from wetcloth.exporter.frame import cloth_faces
points = np.array([[0, 0, 0.2], [0.1, 0, 0.2], [0.1, 0.1, 0.2], [0, 0.1, 0.2], [0.05, 0.05, 0.21]])
cloth = make_mesh(points, [np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])])
floor = surface([[-1, -1, 0], [1, -1, 0], [0, 1, 0]], [[0, 1, 2]], "floor")
scene = from_dict({{"cloth_mesh": cloth, "colliders": [{{"shape": "mesh", "file": floor}}]}})
sim = Simulation(scene)
sim.sample(np.array([0.1]))
triangles, uv, _ = cloth_faces(build_topology(scene))
sequence = open_sequence({str(tmp_path / "usd")!r}, fmt="usd", scene=scene, faces="triangles")
sequence.write_frame(sim.positions, sim.wetness, time=sim.time)
sequence.close()
print(sorted(name for name in ("meshio", "trimesh") if name in sys.modules))
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
