"""The Blender extension's parts that need no Blender: reading a grid or a mesh cloth, pins and colliders
from vertices and faces, where each scene parameter lives, the zip's build checks, and
the bake's ticks (Esc, progress)."""

import itertools
import json
import math
import zipfile

import numpy as np
import pytest

import wetcloth
from wetcloth.cli import main as cli_main
from wetcloth.exporter.blender_extension import build
from wetcloth.exporter.blender_extension.frame_loop import BAKE_EVENTS, tick
from wetcloth.exporter.blender_extension.geometry import (PIN_ATTRIBUTE, GridCloth, MeshCloth, analytic_collider,
                                                          cloth_of, collider_of, face_blocks, grid_cloth, pinned_edge)
from wetcloth.exporter.blender_extension.parameters import FABRIC, FROM_CLOTH, SCENE
from wetcloth.scene import PARAMETERS, from_dict
from wetcloth.simulation import Simulation
from wetcloth.topology import grid_cells


def plane(nx, ny, width, length, centre=(0.0, 0.0, 0.0), tilt=0.0, seed=0):
    """A subdivided plane as Blender could store it: vertices (shuffled) and the grid's edges."""
    col, row = np.meshgrid(np.arange(nx), np.arange(ny))
    col, row = col.ravel(), row.ravel()
    a = col * width / (nx - 1) - width / 2
    b = row * length / (ny - 1) - length / 2
    t = math.radians(tilt)
    points = np.column_stack([a, b * math.cos(t), b * math.sin(t)]) + centre
    shuffle = np.random.default_rng(seed).permutation(nx * ny)
    position_of = np.empty_like(shuffle)
    position_of[shuffle] = np.arange(nx * ny)
    grid = row * nx + col
    edges = [(g, g + 1) for g in grid if g % nx < nx - 1] + [(g, g + nx) for g in grid if g // nx < ny - 1]
    return points[shuffle], position_of[np.array(edges)], shuffle


@pytest.mark.parametrize("tilt", [0.0, 25.0, -40.0])
def test_a_subdivided_plane_is_the_grid_cloth_with_its_vertex_order(tilt):
    """The plane's counts, size, height and tilt; and each vertex is the particle wetcloth puts there
    (the simulation of those parameters, moved by the plane's x and y, lands on the vertices)."""
    points, edges, shuffle = plane(7, 5, 0.6, 0.4, centre=(0.3, -0.2, 0.5), tilt=tilt)
    grid = grid_cloth(points, edges, "towel")
    assert (grid.nx, grid.ny) == (7, 5)
    assert grid.width == pytest.approx(0.6, abs=1e-12) and grid.length == pytest.approx(0.4, abs=1e-12)
    assert grid.tilt == pytest.approx(tilt, abs=1e-9) and grid.centre[2] == pytest.approx(0.5, abs=1e-12)
    assert (grid.order == shuffle).all()
    sim = Simulation(from_dict(grid.scene_values() | {"floor_level": -1.0}))
    assert np.abs(sim.positions[grid.order] + grid.shift - points).max() < 1e-12


@pytest.mark.parametrize("change, message", [
    ("rotate", "rotation about z"),
    ("uneven", "not equally spaced"),
    ("diagonal", "not those of a grid of quads"),
    ("hole", "do not fill a rectangular grid"),
])
def test_anything_but_a_grid_plane_is_refused_naming_the_object(change, message):
    points, edges, _ = plane(5, 4, 0.5, 0.3)
    if change == "rotate":  # 30 degrees about z
        c, s = math.cos(0.5), math.sin(0.5)
        points = points @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T
    elif change == "uneven":
        points[:, 0] = np.where(points[:, 0] > 0.2, points[:, 0] + 0.05, points[:, 0])
    elif change == "diagonal":
        edges = np.vstack([edges, [[0, 1]]])
    else:
        keep = ~((np.abs(points[:, 0]) < 1e-9) & (np.abs(points[:, 1]) < 0.06))
        points = points[keep]
        edges = np.zeros((0, 2), dtype=int)
    with pytest.raises(ValueError, match=f"cloth 'sheet'.*{message}"):
        grid_cloth(points, edges, "sheet")


def test_a_pin_group_that_is_one_edge_is_that_pinned_edge():
    points, edges, shuffle = plane(5, 4, 0.5, 0.3)
    grid = grid_cloth(points, edges)
    blender_vertex = np.argsort(shuffle)  # Blender vertex of each grid particle
    assert pinned_edge(grid, [], "pins") == "none"
    assert pinned_edge(grid, blender_vertex[[0, 5, 10, 15]], "pins") == "x_min"
    assert pinned_edge(grid, blender_vertex[15:20], "pins") == "y_max"
    with pytest.raises(ValueError, match="pin group 'pins'.*not one whole edge"):
        pinned_edge(grid, blender_vertex[[0, 1]], "pins")


def uv_sphere(radius, centre, segments=32, rings=16):
    theta = np.linspace(0, math.pi, rings + 1)[1:-1]
    phi = np.arange(segments) * 2 * math.pi / segments
    t, p = np.meshgrid(theta, phi)
    ring = np.column_stack([np.sin(t.ravel()) * np.cos(p.ravel()), np.sin(t.ravel()) * np.sin(p.ravel()),
                            np.cos(t.ravel())])
    return np.vstack([ring, [[0, 0, 1], [0, 0, -1]]]) * radius + centre


def test_primitives_are_the_analytic_colliders():
    """Positions are compared after rounding to 1e-9 m (merging a mesh's coincident vertices)."""
    sphere = analytic_collider(uv_sphere(0.3, (1.0, 2.0, 0.5)))
    assert sphere["shape"] == "sphere" and sphere["radius"] == pytest.approx(0.3, abs=1e-9)
    assert (sphere["x"], sphere["y"], sphere["z"]) == pytest.approx((1.0, 2.0, 0.5), abs=1e-9)
    corners = np.array(list(itertools.product([-0.1, 0.3], [0.0, 0.2], [1.0, 1.5])))
    box = analytic_collider(corners)
    assert box["shape"] == "box" and (box["size_x"], box["size_y"], box["size_z"]) == pytest.approx((0.4, 0.2, 0.5))
    phi = np.arange(32) * 2 * math.pi / 32
    ring = np.column_stack([0.25 * np.cos(phi), 0.25 * np.sin(phi)])
    can = np.vstack([np.column_stack([ring, np.full(32, z)]) for z in (0.0, 0.4)] + [[[0, 0, 0], [0, 0, 0.4]]])
    cylinder = analytic_collider(can)
    assert cylinder["shape"] == "cylinder" and cylinder["radius"] == pytest.approx(0.25)
    assert cylinder["height"] == pytest.approx(0.4) and cylinder["z"] == pytest.approx(0.2)
    tilted = corners @ np.array([[1, 0, 0], [0, math.cos(0.3), -math.sin(0.3)], [0, math.sin(0.3), math.cos(0.3)]]).T
    assert analytic_collider(tilted) is None


def cylinder_wall(segments=16, radius=0.2, height=0.3, bottom=True):
    """An open cylinder (a cup if ``bottom``): rings at z = 0 and height, quads split in two, a fan bottom."""
    phi = np.arange(segments) * 2 * math.pi / segments
    ring = np.column_stack([radius * np.cos(phi), radius * np.sin(phi)])
    points = np.vstack([np.column_stack([ring, np.full(segments, z)]) for z in (0.0, height)] + [[[0, 0, 0]]])
    i = np.arange(segments)
    j = (i + 1) % segments
    triangles = [np.column_stack([i, j, j + segments]), np.column_stack([i, j + segments, i + segments])]
    if bottom:
        triangles.append(np.column_stack([np.full(segments, 2 * segments), j, i]))
    return points, np.concatenate(triangles)


def test_other_meshes_and_open_primitives_are_mesh_colliders_of_their_triangles():
    """An open cylinder has a closed can's vertices, but it is a shell (a cup), not the solid cylinder; a
    turned box is no analytic box.  Both collide as meshes of the triangles given, where they are."""
    points, triangles = cylinder_wall()
    cup = collider_of(points, triangles, "cup")
    assert cup["shape"] == "mesh" and (cup["x"], cup["y"], cup["z"]) == (0.0, 0.0, 0.0)
    assert np.array_equal(cup["file"].points, points) and np.array_equal(cup["file"].triangles, triangles)
    assert cup["file"].source == "collider 'cup'"
    corners = np.array(list(itertools.product([-0.1, 0.3], [0.0, 0.2], [1.0, 1.5])))
    closed = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                       [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    assert collider_of(corners, closed, "crate")["shape"] == "box"
    tilted = corners @ np.array([[1, 0, 0], [0, math.cos(0.3), -math.sin(0.3)], [0, math.sin(0.3), math.cos(0.3)]]).T
    assert collider_of(tilted, closed, "crate")["shape"] == "mesh"
    with pytest.raises(ValueError, match="collider 'dots' has no faces"):
        collider_of(corners, np.zeros((0, 3)), "dots")


def test_faces_keep_quads_and_split_ngons_into_their_loop_triangles():
    """A quad, a triangle and a pentagon (with its 3 loop triangles) in Blender's corner lists."""
    sizes = [4, 3, 5]
    loops = [0, 1, 2, 3, 1, 4, 2, 2, 4, 5, 6, 3]
    loop_triangles = [[0, 1, 2], [0, 2, 3], [1, 4, 2], [2, 4, 5], [2, 5, 6], [2, 6, 3]]
    triangles, quads = face_blocks(sizes, loops, loop_triangles, [0, 0, 1, 2, 2, 2])
    assert quads.tolist() == [[0, 1, 2, 3]]
    assert triangles.tolist() == [[1, 4, 2], [2, 4, 5], [2, 5, 6], [2, 6, 3]]


def test_a_plane_turned_about_z_or_pinned_off_an_edge_is_a_mesh_cloth_in_blenders_order():
    """The grid takes a plane along x pinned on one edge; a plane turned about z, or pinned at two
    vertices, is a mesh cloth of the same vertices, in the same order, its pins a point attribute."""
    points, edges, shuffle = plane(5, 4, 0.5, 0.3)
    grid_particle = shuffle  # of each Blender vertex
    blender_vertex = np.argsort(shuffle)
    cells = np.array([[g, g + 1, g + 6, g + 5] for g in range(15) if g % 5 < 4])
    quads = blender_vertex[cells]
    faces = ([4] * len(quads), quads.ravel()), (np.zeros((0, 3)), [])  # (polygons, loop triangles of n-gons)
    cloth, pins = cloth_of(points, edges, *faces, blender_vertex[[0, 5, 10, 15]], "sheet")
    assert isinstance(cloth, GridCloth) and pins == "x_min" and (cloth.order == grid_particle).all()
    cloth, pins = cloth_of(points, edges, *faces, blender_vertex[[0, 1]], "sheet")
    assert isinstance(cloth, MeshCloth) and pins == "none"
    assert np.array_equal(cloth.mesh.points, points) and (cloth.order == np.arange(20)).all()
    assert np.array_equal(cloth.polygons[1], quads.ravel())  # the cache's faces: the object's own
    assert np.flatnonzero(cloth.mesh.attributes[PIN_ATTRIBUTE]).tolist() == sorted(blender_vertex[[0, 1]].tolist())
    assert cloth.scene_values()["pinned_vertices"] == PIN_ATTRIBUTE
    c, s = math.cos(0.5), math.sin(0.5)
    turned = points @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T
    cloth, pins = cloth_of(turned, edges, *faces, [], "sheet")
    assert isinstance(cloth, MeshCloth) and cloth.scene_values()["pinned_vertices"] == ""
    sim = Simulation(from_dict(cloth.scene_values() | {"floor_level": -1.0}))
    assert np.array_equal(sim.positions, turned)  # particle k is Blender vertex k, where Blender has it


def test_a_cloth_no_spring_can_join_is_refused_naming_the_object():
    """Three quads on one edge (non-manifold), and a loose vertex."""
    points = np.array([[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0], [-1, 0, 0], [-1, 1, 0], [0, 0, 1], [0, 1, 1.0]])
    fin = np.array([[0, 2, 3, 1], [4, 0, 1, 5], [0, 6, 7, 1]])
    no_ngons = (np.zeros((0, 3)), [])
    with pytest.raises(ValueError, match="cloth 'Fin' cannot be the cloth: .*belongs to 3 faces"):
        cloth_of(points, np.zeros((0, 2)), ([4, 4, 4], fin.ravel()), no_ngons, [], "Fin")
    with pytest.raises(ValueError, match="cloth 'Dot' cannot be the cloth: .*belongs to no face"):
        cloth_of(points, np.zeros((0, 2)), ([4, 4], fin[:2].ravel()), no_ngons, [], "Dot")


def test_a_cloth_folded_in_blender_takes_its_uv_map_where_it_has_one_uv_per_vertex():
    """A 7 x 5 plane folded in half over x = 0 (its half at x > 0 laid back 4 mm above the other), its UV map
    the unfolded plane as Blender's plane has it, per face corner: the mesh cloth gets one UV per vertex, and
    its scene is taken with self-collision on.  A seam (a vertex whose corners differ) or no map leaves it
    without UVs, and the folded cloth is refused, naming it."""
    points, edges, shuffle = plane(7, 5, 0.6, 0.4, centre=(0.0, 0.0, 0.5))
    blender_vertex = np.argsort(shuffle)
    quads = blender_vertex[grid_cells(7, 5)]
    faces = ([4] * len(quads), quads.ravel()), (np.zeros((0, 3)), [])
    flat_uv = (points[:, :2] - points[:, :2].min(axis=0)) / 0.6
    loop_uv = flat_uv[quads.ravel()]
    x = points[:, 0]
    folded = points.copy()
    folded[:, 0] = np.where(x > 0.0, -x, x)
    folded[:, 2] += np.where(x > 0.0, 0.004, 0.0)
    cloth, _ = cloth_of(folded, edges, *faces, [], "Towel", loop_uv)
    assert isinstance(cloth, MeshCloth)
    np.testing.assert_array_equal(cloth.mesh.uv, flat_uv)
    assert from_dict(cloth.scene_values() | {"self_collision": "on"}).self_collision == "on"
    seam = loop_uv.copy()
    seam[np.flatnonzero(np.bincount(quads.ravel())[quads.ravel()] == 4)[0]] += 0.01  # one corner of an inner vertex
    for uv in (seam, None):
        cloth, _ = cloth_of(folded, edges, *faces, [], "Towel", uv)
        assert cloth.mesh.uv is None
        with pytest.raises(wetcloth.ParameterError, match=r"'cloth_mesh'.*'Towel'.*lie over each other"):
            from_dict(cloth.scene_values() | {"self_collision": "on"})


def test_each_scene_parameter_has_one_place():
    """Every scene parameter is set by the cloth object, its fabric or the scene, and by one only."""
    places = FROM_CLOTH + FABRIC + SCENE
    assert sorted(places) == sorted(PARAMETERS) and len(set(places)) == len(places)


@pytest.mark.parametrize("pythons, first, last", [
    (["cp311"], "4.2.0", "5.1.0"), (["cp313"], "5.1.0", None), (["cp311", "cp313"], "4.2.0", None)])
def test_the_manifest_names_the_wheels_and_the_blenders_whose_python_they_are(pythons, first, last):
    """Blender 4.2 to 5.0 run Python 3.11, 5.1 and later 3.13: the manifest allows the versions whose
    Python has a wheel (blender_version_max is the first it does not)."""
    import tomllib

    names = [f"wetcloth-0.1.0-{tag}-{tag}-linux_x86_64.whl" for tag in pythons]
    manifest = tomllib.loads(build.manifest("0.1.0", names, "linux-x64"))
    assert manifest["wheels"] == [f"./wheels/{name}" for name in names]
    assert manifest["platforms"] == ["linux-x64"] and manifest["id"] == "wetcloth"
    assert (manifest["blender_version_min"], manifest.get("blender_version_max")) == (first, last)
    assert len(manifest["tagline"]) <= 64 and not manifest["tagline"].endswith(".")  # Blender's rules


@pytest.mark.parametrize("name, message", [
    ("numpy-1.26.4-cp311-cp311-linux_x86_64.whl", "not a wetcloth wheel"),
    ("wetcloth-9.9.9-cp311-cp311-linux_x86_64.whl", "version 9.9.9"),
    ("wetcloth-0.1.0-cp312-cp312-linux_x86_64.whl", "built for cp312"),
])
def test_a_wheel_blender_cannot_load_is_refused(tmp_path, capsys, name, message):
    wheel = tmp_path / name
    with zipfile.ZipFile(wheel, "w"):
        pass
    assert cli_main(["blender-extension", "--out", str(tmp_path / "out"), "--wheel", str(wheel)]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out" / "wetcloth-0.1.0.zip").exists()


def test_an_interpreter_that_cannot_be_run_is_named(tmp_path, capsys):
    """``--python`` of a missing file or of one that is no program: b60f040 said only "[Errno 2] No such file or
    directory" (and "[Errno 13] Permission denied")."""
    text = tmp_path / "python.txt"
    text.write_text("not a program")
    for python, why in ((tmp_path / "no-python", "No such file or directory"), (text, "Permission denied")):
        assert cli_main(["blender-extension", "--out", str(tmp_path / "out"), "--python", str(python)]) == 2
        assert f"Python interpreter {python} cannot be run: {why}; give the path of a Python" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def fake_python(folder, name: str, version: str):
    """An executable standing for a Python of ``version`` (``3.11``): it prints that version's wheel tag,
    which is all ``python_tag`` asks of an interpreter."""
    path = folder / name
    path.write_text(f"#!/bin/sh\necho cp{version.replace('.', '')}\n")
    path.chmod(0o755)
    return path


def test_two_pythons_of_one_version_are_refused_before_building(tmp_path, capsys, monkeypatch):
    """``--python`` twice with one version: bb80f15 built the first wheel (a minute), then pip's second build
    of the same file name failed with "pip wheel ... failed (exit 0)". A Python no Blender ships is refused
    as early, named with its version."""
    from wetcloth.exporter.blender_extension import build

    def no_building(*args):
        raise AssertionError("built a wheel before checking the Pythons")

    monkeypatch.setattr(build, "build_wheel", no_building)
    first, second, other = (fake_python(tmp_path, name, version)
                            for name, version in (("python3.11", "3.11"), ("py311", "3.11"), ("python3.12", "3.12")))
    out = tmp_path / "out"
    assert cli_main(["blender-extension", "--out", str(out), "--python", str(first), "--python", str(second)]) == 2
    assert (f"two wheels for one Python (--python {first}: cp311, --python {second}: cp311); give one per Python"
            in capsys.readouterr().err)
    assert cli_main(["blender-extension", "--out", str(out), "--python", str(first), "--python", str(other)]) == 2
    assert (f"--python {other}: Python 3.12; Blender ships Python 3.11 (4.2 to 5.0) or 3.13 (5.1 and later)"
            in capsys.readouterr().err)
    assert not out.exists()


def test_given_wheels_are_bundled_as_they_are_one_per_python_with_dependencies_for_each(tmp_path, capsys):
    """The wetcloth wheels given, and a scipy and a pyamg wheel (the versions this Python runs) for each
    one's Python (from the wheel cache, downloaded there by pip the first time)."""
    from importlib import metadata

    wheels = []
    for tag in ("cp311", "cp313"):
        wheels.append(tmp_path / f"wetcloth-0.1.0-{tag}-{tag}-linux_x86_64.whl")
        with zipfile.ZipFile(wheels[-1], "w") as archive:
            archive.writestr("wetcloth/__init__.py", tag)
            archive.writestr("wetcloth-0.1.0.dist-info/METADATA", "Name: wetcloth\nVersion: 0.1.0\n")
    given = [arg for wheel in wheels for arg in ("--wheel", str(wheel))]
    assert cli_main(["blender-extension", "--out", str(tmp_path), *given]) == 0
    with zipfile.ZipFile(tmp_path / "wetcloth-0.1.0.zip") as archive:
        names = archive.namelist()
        bundled = {name: [n for n in names if n.startswith(f"wheels/{name}-")] for name in ("scipy", "pyamg")}
        dependencies = [n for found in bundled.values() for n in found]
        assert sorted(set(names) - set(dependencies)) == ["__init__.py", "blender_manifest.toml"] + [
            f"wheels/{wheel.name}" for wheel in wheels]
        assert all(archive.read(f"wheels/{wheel.name}") == wheel.read_bytes() for wheel in wheels)
        for name, found in bundled.items():
            version = metadata.version(name)
            assert [n.split("-")[1:3] for n in sorted(found)] == [[version, "cp311"], [version, "cp313"]]
    assert cli_main(["blender-extension", "--out", str(tmp_path / "again"), *given[:2], *given[:2]]) == 2
    assert "two wheels for one Python" in capsys.readouterr().err


def test_a_bake_reports_the_largest_error_its_steps_estimated(tmp_path):
    """The bake's summary line gives each cloth's largest step error: with frame steps, the largest
    ``error_estimate`` of a run advanced frame by frame (here, in the same process)."""
    from wetcloth.exporter.blender_extension.baking import ClothBake

    points, edges, _ = plane(5, 5, 0.4, 0.4, centre=(0.0, 0.0, 1.0))
    grid = grid_cloth(points, edges)
    scene = from_dict(grid.scene_values() | dict(integrator="implicit_euler", tolerance=0.0, max_step=0.125,
                                                 pinned_edge="y_max", floor_level=-1.0))
    bake = ClothBake(scene, grid, tmp_path, "cloth", fps=8.0, frame_start=1, frame_count=7)
    while not bake.finished:
        bake.step()
    bake.close()
    sim = Simulation(scene)
    errors = []
    for _ in range(6):
        sim.advance(0.125)
        errors.append(sim.error_estimate)
    assert bake.largest_error == max(errors) > 0.0


class OneClothBaking:
    """The operator's Baking for one ClothBake without Blender, each frame taking 0.04 s of ``clock``."""

    def __init__(self, bake):
        self.bake, self.total, self.now = bake, bake.frame_count, 0.0

    done = property(lambda self: self.bake.done)
    finished = property(lambda self: self.bake.finished)

    def step(self):
        self.bake.step()
        self.now += 0.04

    def clock(self) -> float:
        return self.now


def hanging_sheet_baking(folder, frame_count: int) -> OneClothBaking:
    """A 5 x 5 sheet hanging from its y_max edge, baked into ``folder`` at 24 fps."""
    from wetcloth.exporter.blender_extension.baking import ClothBake

    points, edges, _ = plane(5, 5, 0.4, 0.4, centre=(0.0, 0.0, 1.0))
    grid = grid_cloth(points, edges)
    scene = from_dict(grid.scene_values() | dict(pinned_edge="y_max", floor_level=-1.0))
    return OneClothBaking(ClothBake(scene, grid, folder, "cloth", fps=24.0, frame_start=1, frame_count=frame_count))


def test_a_tick_bakes_for_its_budget_and_esc_keeps_the_frames_baked(tmp_path):
    """The modal bake's ticks (frame_loop.tick, as the operator calls it with its 0.1 s budget): three
    frames of 0.04 s per timer tick (0.00, 0.04, 0.08 s are under 0.1 s), the status bar counting them;
    other events pass without a frame; Esc stops at once, the status cleared: the cache holds the frames
    baked, frames.json marked incomplete."""
    baking = hanging_sheet_baking(tmp_path, 20)
    assert "MOUSEMOVE" not in BAKE_EVENTS
    progress = []
    for _ in range(3):
        stopped, status = tick(baking, "TIMER", 0.1, clock=baking.clock)
        assert stopped is None and status == f"Wet Cloth: frame {baking.done} of 20 (Esc cancels, keeping the frames baked)"
        progress.append(baking.done)
    assert progress == [3, 6, 9]
    assert tick(baking, "ESC", 0.1, clock=baking.clock) == ("cancelled", None) and baking.done == 9
    baking.bake.close()
    manifest = json.loads((tmp_path / "frames.json").read_text())
    assert manifest["frame_count"] == 9 and not manifest["complete"]


def test_ticks_finish_the_bake_or_stop_it_after_cancel_after_frames(tmp_path):
    """Ticks until the last frame: the bake finishes (stopped None), the status cleared on that tick and
    frames.json complete; with cancel_after=5 the tick that bakes the fifth frame stops it as Esc does."""
    results = []
    for cancel_after, folder in ((0, tmp_path / "whole"), (5, tmp_path / "cut")):
        baking = hanging_sheet_baking(folder, 8)
        ticks = []
        while not ticks or ticks[-1][1] is not None:
            ticks.append(tick(baking, "TIMER", 0.1, cancel_after, clock=baking.clock))
        baking.bake.close()
        manifest = json.loads((folder / "frames.json").read_text())
        results.append((ticks[-1], len(ticks), manifest["frame_count"], manifest["complete"]))
    assert results == [((None, None), 3, 8, True), (("cancelled", None), 2, 5, False)]
