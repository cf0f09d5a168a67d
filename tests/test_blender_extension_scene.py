"""How a Blender scene becomes a wetcloth scene: which meshes are the grid cloth and which colliders are
analytic (numpy only), and, in a real Blender (tests/blender/scene_probe.py, run as
tests/test_blender_extension.py runs its probe), the scenes the bake refuses and the panel's limits.

Without ``.venv-blender/bin/python`` the Blender tests are skipped with the reason (and fail under
WETCLOTH_REQUIRE_BLENDER=1), as in tests/test_blender_extension.py.
"""

import math
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from support.blender import probe_extension
from test_blender_extension_parts import plane
from wetcloth.exporter.blender_extension.geometry import (GridCloth, MeshCloth, analytic_collider, cloth_of,
                                                          collider_of)
from wetcloth.scene import PARAMETERS, describe_range

PROBE = Path(__file__).with_name("blender") / "scene_probe.py"


def grid_faces(nx, ny, shuffle):
    """The cells of an nx x ny grid as Blender quads: corner counts and corner vertices (Blender's indices of
    plane()'s shuffled vertices), and their loop triangles (two per quad) with the face each splits."""
    blender_vertex = np.argsort(shuffle)
    cells = [row * nx + col for row in range(ny - 1) for col in range(nx - 1)]
    quads = np.array([[g, g + 1, g + nx + 1, g + nx] for g in cells])
    loops = blender_vertex[quads]
    triangles = np.vstack([loops[:, [0, 1, 2]], loops[:, [0, 2, 3]]])
    faces = np.concatenate([np.arange(len(quads))] * 2)
    return (np.full(len(quads), 4), loops.ravel()), (triangles, faces)


def without_face(polygons, triangles, k):
    """The faces and loop triangles of a mesh of quads with face ``k`` deleted (its edges and vertices kept)."""
    (sizes, loops), (tri, faces) = polygons, triangles
    keep = faces != k
    return ((np.delete(sizes, k), np.delete(loops.reshape(-1, 4), k, axis=0).ravel()),
            (tri[keep], faces[keep] - (faces[keep] > k)))


def test_a_plane_with_a_face_deleted_is_a_mesh_cloth_of_its_own_faces():
    """Its vertices and edges are still a grid's, but a grid would fill the hole: it is a mesh cloth of its
    35 faces; the whole plane stays the grid."""
    points, edges, shuffle = plane(7, 7, 0.6, 0.6)
    polygons, triangles = grid_faces(7, 7, shuffle)
    grid, _ = cloth_of(points, edges, polygons, triangles, [], "Towel")
    assert isinstance(grid, GridCloth)
    cloth, pins = cloth_of(points, edges, *without_face(polygons, triangles, 12), [], "Towel")
    assert isinstance(cloth, MeshCloth) and pins == "none"
    assert len(cloth.polygons[0]) == 35 and cloth.mesh.n == 49


def test_a_mesh_without_faces_is_refused_naming_the_object():
    points, edges, _ = plane(7, 7, 0.6, 0.6)
    none = (np.zeros(0, dtype=int), np.zeros(0, dtype=int))
    for wire in (edges, np.zeros((0, 2), dtype=int)):
        with pytest.raises(ValueError, match="cloth 'Towel' has no faces"):
            cloth_of(points, wire, none, (np.zeros((0, 3), dtype=int), np.zeros(0, dtype=int)), [], "Towel")


def cone(radius=0.2, depth=0.2, segments=32):
    """Add > Mesh > Cone: a ring of ``segments`` at z = -depth/2, the apex at depth/2, closed by a fan
    (base n-gon as triangles about its first vertex); vertices (n, 3) and triangles (t, 3)."""
    phi = np.arange(segments) * 2 * math.pi / segments
    ring = np.column_stack([radius * np.cos(phi), radius * np.sin(phi), np.full(segments, -depth / 2)])
    points = np.vstack([ring, [[0.0, 0.0, depth / 2]]])
    i = np.arange(segments)
    sides = np.column_stack([i, (i + 1) % segments, np.full(segments, segments)])
    base = np.column_stack([np.zeros(segments - 2, dtype=int), i[2:], i[1:-1]])
    return points, np.vstack([sides, base])


def test_a_cone_is_a_mesh_collider_not_a_cylinder():
    """A closed cone (one ring and its apex) is a solid mesh collider; a cylinder (two rings, cap centres)
    stays one."""
    points, triangles = cone()
    assert analytic_collider(points) is None
    assert collider_of(points, triangles, "Cone")["shape"] == "mesh"
    phi = np.arange(32) * 2 * math.pi / 32
    ring = np.column_stack([0.2 * np.cos(phi), 0.2 * np.sin(phi)])
    bottom, top = (np.column_stack([ring, np.full(32, z)]) for z in (-0.1, 0.1))
    centres = [[0, 0, -0.1], [0, 0, 0.1]]
    assert analytic_collider(np.vstack([bottom, top, centres]))["shape"] == "cylinder"
    assert analytic_collider(np.vstack([bottom, centres])) is None  # a cone whose base is a fan about its centre


@pytest.fixture(scope="module")
def probed(tmp_path_factory):
    """The extension's zip built as tests/test_blender_extension.py builds it, and scene_probe.py's report."""
    return SimpleNamespace(**probe_extension(tmp_path_factory.mktemp("scene"), PROBE, {}))


def test_a_plane_with_a_hole_bakes_and_plays_its_own_faces(probed):
    hole = probed.hole
    assert hole["result"] == ["FINISHED"], hole["error"]
    assert hole["scene"]["cloth_mesh"] == "Towel" and hole["own_faces"] == 35 and hole["played_faces"] == 35


def test_a_wire_grid_is_refused_naming_the_object(probed):
    assert probed.no_faces["result"] == ["ERROR"] and "cloth 'Towel' has no faces" in probed.no_faces["error"]


def test_a_scene_in_centimetres_is_simulated_in_metres_and_played_in_its_units(probed):
    """One scene built in metres and, 100 times larger, at Unit Scale 0.01: the same wetcloth scene (the
    towel's size, height and tilt, the ball and its keys, in metres, to float32 rounding) and the same cloth
    played, 100 times larger in Blender units: within 1e-5 m (measured 2e-6 m at the sixth frame, the
    float32 rounding of the two scenes' inputs carried through the contact; the water's wrong level or a key
    in centimetres would be centimetres off)."""
    metres, centimetres = probed.unit_scale["metres"], probed.unit_scale["centimetres"]
    assert metres["result"] == centimetres["result"] == ["FINISHED"], centimetres["error"]
    scene = centimetres["scene"]
    assert scene["width"] == pytest.approx(0.6, rel=1e-6) and scene["collider1_radius"] == pytest.approx(0.15, rel=1e-6)
    assert scene["initial_tilt"] == pytest.approx(math.degrees(0.2), rel=1e-6)
    for name, value in metres["scene"].items():
        if isinstance(value, float):
            assert scene[name] == pytest.approx(value, rel=1e-6, abs=1e-7), name
        else:
            assert scene[name] == value, name
    assert scene["collider_key5_z"] == pytest.approx(0.05, rel=1e-6) and "collider_key6_z" not in scene
    played_m, played_cm = np.array(metres["played"]), np.array(centimetres["played"])
    assert np.abs(played_m[-1] - played_m[0]).max() > 0.01  # it moved
    assert np.abs(played_cm * 0.01 - played_m).max() <= 1e-5


def test_a_cloth_whose_object_moves_is_refused_naming_it(probed):
    """Keyed to slide, or carried by a keyed parent: refused at the frame it moves; keys that hold it still bake."""
    animated = probed.animated
    for case in ("keyed", "parented"):
        assert animated[case]["result"] == ["ERROR"]
        assert "cloth 'Towel' moves at frame 2" in animated[case]["error"]
        assert "bake with the cloth's object still" in animated[case]["error"]
    assert animated["still"]["result"] == ["FINISHED"], animated["still"]["error"]


@pytest.mark.parametrize("name", ["areal_density", "thickness", "stretch_stiffness", "water_density"])
def test_the_panel_stops_settings_at_the_lower_bound_of_their_range(probed, name):
    """hard_min and soft_min at the parameter's lower bound where its range includes it (0.005 <= areal_density),
    above it where the range excludes it (0 < thickness): Blender's float32 of the least value allowed; and a
    bake at hard_min is not refused."""
    limit = probed.limits[name]
    lo, lo_open = PARAMETERS[name].metadata["lo"], PARAMETERS[name].metadata["lo_open"]
    assert np.float32(limit["soft_min"]) == np.float32(limit["hard_min"]), limit
    if lo_open:
        assert lo < limit["hard_min"] <= lo + 1e-5, limit  # the least value the panel shows above it
    else:
        assert np.float32(limit["hard_min"]) == np.float32(lo), limit
    assert limit["result"] == ["FINISHED"], limit["error"]


def test_a_refusal_names_the_cloth_and_its_blender_setting(probed):
    """Of two cloths, 'Bib''s fabric setting out of range names 'Bib' and the setting; 'Bib' below the
    floor names 'Bib' and its height, not wetcloth's initial_height; so does a ball through 'Bib'."""
    fabric, floor = probed.unnamed["fabric"], probed.unnamed["floor"]
    assert "cloth 'Bib', its setting 'areal_density': 0.0 is out of range" in fabric
    assert describe_range(PARAMETERS["areal_density"]) in fabric
    assert "cloth 'Bib' starts at or below the floor" in floor and "Location Z" in floor
    assert "initial_height" not in floor
    overlap = probed.unnamed["overlap"]
    assert "cloth 'Bib', collider 'Ball': the sphere overlaps the cloth" in overlap
    assert "initial_height" not in overlap and "Location Z" in overlap


def test_a_towel_folded_in_blender_bakes_with_its_uv_map_and_is_refused_without(probed):
    """Folded in half in the object (4 mm between its layers) 5 mm above a dry floor, self-collision on: its UV
    map (the plane's, unfolded) lays it out flat, so it bakes, and landed on the floor its upper layer lies on
    the lower one at the last frame, at least 0.9 of the thickness above it (docs/model.md section 6.2; less
    1 um of float32 rounding; measured 1.99 mm of 2), where it would fall through onto the floor without
    self-collision; without a UV map, refused naming the cloth and two faces that lie over each other."""
    folded = probed.folded
    assert folded["with_uv"]["result"] == ["FINISHED"], folded["with_uv"]["error"]
    assert min(folded["with_uv"]["gaps"]) > 0.9 * folded["with_uv"]["thickness"] - 1e-6
    assert folded["without_uv"]["result"] == ["ERROR"]
    assert re.search(r"cloth 'Towel'.*faces \d+ and \d+ lie over each other", folded["without_uv"]["error"])
