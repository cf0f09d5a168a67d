"""Export options for render-ready output: quads or triangles, the first frame number, USD velocities,
the Blender import options in frames.json, and their flags on ``wetcloth run``.

Small grids and a few frames each; Blender itself is in tests/test_blender.py.
"""

import json

import meshio
import numpy as np
import pytest
import trimesh
from numpy.testing import assert_array_equal

import wetcloth
from wetcloth.cli import main as cli_main
from wetcloth.exporter import ExportError, open_sequence, quads_from_triangles, sheet_uv
from wetcloth.exporter.blender_options import OPTIONS
from wetcloth.model import GRAVITY
from wetcloth.runner import run


def grid_cells(nx: int, ny: int) -> np.ndarray:
    """Quads of an nx x ny grid written out from the layout (vertex i = row * nx + col), counter-clockwise
    from +z: (i, i + 1, i + nx + 1, i + nx) for every cell, row by row."""
    return np.array([[i, i + 1, i + nx + 1, i + nx] for row in range(ny - 1) for col in range(nx - 1)
                     for i in [row * nx + col]])


@pytest.mark.parametrize("nx, ny", [(2, 2), (6, 5), (3, 7)])
def test_quads_are_the_grid_cells_and_split_back_into_the_triangles(nx, ny):
    """One quad per cell, counter-clockwise like the triangles; split along its first diagonal (as
    trimesh does) it gives the simulation's two triangles of that cell."""
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=nx, ny=ny))
    quads = quads_from_triangles(sim.triangles, sheet_uv(sim.model.topology.rest_xy))
    assert_array_equal(quads, grid_cells(nx, ny))
    split = trimesh.geometry.triangulate_quads(quads)
    assert_array_equal(np.sort(split, axis=1), np.sort(sim.triangles, axis=1))


def test_triangles_that_are_not_a_grid_are_refused_as_quads_and_kept_as_triangles(tmp_path):
    """A single triangle has no partner: faces='quads' says what to do instead; 'triangles' writes it."""
    positions, uv = np.eye(3), np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    sequence = open_sequence(tmp_path / "quads", fps=10, triangles=[[0, 1, 2]], uv=uv)
    with pytest.raises(ExportError, match="do not pair into quads.*faces='triangles'"):
        sequence.write_frame(positions, np.zeros(3))
    with open_sequence(tmp_path / "triangles", fps=10, triangles=[[0, 1, 2]], uv=uv, faces="triangles") as sequence:
        path = sequence.write_frame(positions, np.zeros(3))
    assert_array_equal(trimesh.load(path, process=False).faces, [[0, 1, 2]])


@pytest.fixture(scope="module")
def triangles(tmp_path_factory):
    """One short run written with faces='triangles' in every format and writer."""
    root = tmp_path_factory.mktemp("triangles")
    scene = wetcloth.load_scene("thesis_fast", nx=4, ny=3)
    cases = {f"{fmt}_{writer}": (fmt, writer) for fmt in ("ply", "obj") for writer in ("trimesh", "meshio")}
    cases["usd"] = ("usd", "trimesh")
    sequences = {name: open_sequence(root / name, fmt=fmt, writer=writer, fps=10, scene=scene, faces="triangles")
                 for name, (fmt, writer) in cases.items()}
    states = []

    def on_frame(index, sim):
        states.append(sim.positions.astype(np.float32))
        for sequence in sequences.values():
            sequence.on_frame(index, sim)

    run(scene, 0.1, 10, on_frame=on_frame, progress=False)
    for sequence in sequences.values():
        sequence.close()
    sim = wetcloth.Simulation(scene)
    return root, sim.triangles, sheet_uv(sim.model.topology.rest_xy), states


@pytest.mark.parametrize("name", ["ply_trimesh", "ply_meshio", "obj_trimesh", "obj_meshio"])
def test_triangle_frames_read_back_as_the_simulations_triangles(triangles, name):
    """faces='triangles': trimesh and meshio read the simulation's triangles as written, with positions
    and, for OBJ through trimesh (which reads UVs only of triangles), the UVs."""
    root, expected, uv, states = triangles
    fmt = name[:3]
    path = root / name / f"cloth_0002.{fmt}"
    loaded = trimesh.load(path, process=False, maintain_order=True)
    assert_array_equal(loaded.faces, expected)
    assert np.abs(np.asarray(loaded.vertices) - states[1]).max() <= (0 if fmt == "ply" else 5e-10)
    if fmt == "obj":
        assert np.abs(np.asarray(loaded.visual.uv) - uv).max() <= 5e-10
    assert_array_equal(meshio.read(path, file_format=fmt).cells_dict["triangle"], expected)
    manifest = json.loads((root / name / "frames.json").read_text())
    assert (manifest["faces"], manifest["face_count"]) == ("triangles", len(expected))


def test_triangle_usd_has_three_corners_per_face(triangles):
    from pxr import Usd, UsdGeom

    root, expected, _, _ = triangles
    stage = Usd.Stage.Open(str(root / "usd" / "cloth.usd"))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/wetcloth/cloth"))
    assert_array_equal(np.asarray(mesh.GetFaceVertexCountsAttr().Get()), np.full(len(expected), 3))
    assert_array_equal(np.asarray(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3), expected)


def test_usd_polygons_are_written_instead_of_the_faces(tmp_path):
    """A quad and a pentagon of 7 vertices (a Blender object's own faces) over its 5 triangles."""
    from pxr import Usd, UsdGeom

    triangles = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 6], [1, 6, 2]])
    counts, indices = [4, 5], [0, 1, 2, 3, 1, 4, 5, 6, 2]
    sequence = open_sequence(tmp_path / "usd", fmt="usd", triangles=triangles, uv=np.zeros((7, 2)), faces="triangles",
                             polygons=(counts, indices))
    sequence.write_frame(np.random.default_rng(1).random((7, 3)), np.zeros(7))
    sequence.close()
    stage = Usd.Stage.Open(str(tmp_path / "usd" / "cloth.usd"))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/wetcloth/cloth"))
    assert list(mesh.GetFaceVertexCountsAttr().Get()) == counts
    assert list(mesh.GetFaceVertexIndicesAttr().Get()) == indices
    sequence = open_sequence(tmp_path / "bad", fmt="usd", triangles=triangles, uv=np.zeros((7, 2)), faces="triangles",
                             polygons=([3], [0, 1, 7]))
    with pytest.raises(ExportError, match="polygons index vertices outside 0..6"):
        sequence.write_frame(np.zeros((7, 3)), np.zeros(7))


def test_first_frame_numbers_the_files_the_usd_time_codes_and_the_manifest(tmp_path):
    """first_frame=101: files cloth_0101.ply.., USD time codes 101.. (frame 101 is t = 0), recorded in
    frames.json and as the Blender loader's first frame; a resumed run counts from it too."""
    from pxr import Usd, UsdGeom

    scene = wetcloth.load_scene(nx=3, ny=3)
    sim = wetcloth.Simulation(scene)
    with open_sequence(tmp_path / "ply", fps=10, scene=scene, first_frame=101) as ply, \
            open_sequence(tmp_path / "usd", fmt="usd", fps=10, scene=scene, first_frame=101) as usd:
        for _ in range(3):
            for sequence in (ply, usd):
                sequence.write_frame(sim.positions, sim.wetness)
        ply.resume_after(1)
        assert ply.write_frame(sim.positions, sim.wetness).name == "cloth_0102.ply"
    # resume_after removed cloth_0103.ply, the abandoned branch's: frames.json says 2 frames
    assert sorted(p.name for p in (tmp_path / "ply").glob("*.ply")) == ["cloth_0101.ply", "cloth_0102.ply"]
    for name, count in (("ply", 2), ("usd", 3)):
        manifest = json.loads((tmp_path / name / "frames.json").read_text())
        assert (manifest["first_frame"], manifest["frame_count"], manifest["first_time"]) == (101, count, 0.0)
        assert manifest["blender"]["first_frame"] == 101
    stage = Usd.Stage.Open(str(tmp_path / "usd" / "cloth.usd"))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (101.0, 103.0)
    points = UsdGeom.Mesh(stage.GetPrimAtPath("/wetcloth/cloth")).GetPointsAttr()
    assert points.GetTimeSamples() == [101.0, 102.0, 103.0]


def test_usd_velocities_of_a_freely_falling_cloth_are_minus_g_t(tmp_path):
    """A flat cloth 1 m above the water falls freely for 0.3 s (its lowest point stays 0.5 m above the
    water; no air, air_density 0: free fall is the fall in vacuum; no force but gravity, the springs
    stay at rest length): every vertex moves at (0, 0, -g t).

    The USD keeps velocities per frame, in m/s as USD defines them whatever timeCodesPerSecond is.
    They are the simulation's velocities rounded to float32 (checked exactly), so they differ from
    -g t by at most half a float32 step, 2**-24 |g t|, plus what the simulation's own double
    arithmetic accumulates: one rounding of 2**-53 |v| per step over at most ~750 steps, and the
    spring forces of equally displaced particles after rounding (measured below 1e-13 m/s): 1e-12 m/s
    covers both.
    """
    from pxr import Usd, UsdGeom

    scene = wetcloth.load_scene("thesis_fast", nx=4, ny=3, initial_height=1.0, initial_tilt=0.0, air_density=0.0)
    expected = []
    with open_sequence(tmp_path / "fall", fmt="usd", fps=10, scene=scene) as sequence:
        def on_frame(index, sim):
            expected.append((sim.time, sim.velocities.astype(np.float32)))
            sequence.on_frame(index, sim)

        run(scene, 0.3, 10, on_frame=on_frame, progress=False)
    stage = Usd.Stage.Open(str(tmp_path / "fall" / "cloth.usd"))
    velocities = UsdGeom.Mesh(stage.GetPrimAtPath("/wetcloth/cloth")).GetVelocitiesAttr()
    assert velocities.GetTimeSamples() == [1.0, 2.0, 3.0, 4.0]
    for number, (time, simulated) in enumerate(expected, start=1):
        got = np.asarray(velocities.Get(number), dtype=np.float64)
        assert_array_equal(got, simulated)
        free_fall = np.zeros_like(got)
        free_fall[:, 2] = -GRAVITY * time
        assert np.abs(got - free_fall).max() <= 2.0**-24 * GRAVITY * time + 1e-12
    assert expected[-1][0] == pytest.approx(0.3) and got[:, 2].max() < -2.9  # m/s: it did fall


def test_blender_options_are_recorded_with_their_defaults(tmp_path):
    """frames.json (key ``blender``) and the loader get every option: the defaults, and the ones given."""
    scene = wetcloth.load_scene(nx=3, ny=3)
    open_sequence(tmp_path / "default", fps=10, scene=scene).close()
    defaults = json.loads((tmp_path / "default" / "frames.json").read_text())["blender"]
    assert defaults == {"solidify": 1.0, "subdivision": 1, "smooth": True, "material": True, "first_frame": 1,
                        "timeline": "auto"}
    assert set(defaults) == set(OPTIONS)
    chosen = {"subdivision": 2, "solidify": 0, "timeline": "keep", "first_frame": 1001}
    open_sequence(tmp_path / "chosen", fps=10, scene=scene, blender=chosen).close()
    recorded = json.loads((tmp_path / "chosen" / "frames.json").read_text())["blender"]
    assert recorded == defaults | chosen | {"solidify": 0.0}
    loader = (tmp_path / "chosen" / "load_in_blender.py").read_text()
    assert "'subdivision': 2" in loader and "'timeline': 'keep'" in loader


@pytest.mark.parametrize("kwargs, message", [
    (dict(faces="hexagons"), "unknown faces 'hexagons'; choose one of quads, triangles"),
    (dict(first_frame=-1), "first_frame must be a whole number from 0 to 1048574, got -1"),
    (dict(first_frame=1.5), "first_frame must be a whole number"),
    (dict(blender={"subdivision": 7}), "option subdivision must be a whole number from 0 to 6, got 7"),
    (dict(blender={"solidify": -1.0}), "option solidify must be a number from 0 to 100"),
    (dict(blender={"smooth": "yes"}), "option smooth must be true or false"),
    (dict(blender={"timeline": "always"}), "option timeline must be one of auto, set, keep"),
    (dict(blender={"colour": 1}), "unknown Blender import option 'colour'"),
    (dict(fmt="ply", polygons=([3], [0, 1, 2])), "polygons apply to usd only, not 'ply'"),
    (dict(fmt="usd", polygons=([3, 2], [0, 1, 2, 0, 1])), "polygons must be .corner counts, each 3 or more"),
    (dict(fmt="usd", polygons=([4], [0, 1, 2])), "polygons must be"),
])
def test_bad_export_options_are_refused_before_anything_is_written(tmp_path, kwargs, message):
    with pytest.raises(ExportError, match=message):
        open_sequence(tmp_path / "x", fps=30.0, **kwargs)
    assert not (tmp_path / "x").exists()


# ------------------------------------------------------------------------------------------ CLI
def cli_run(tmp_path, *options: str) -> int:
    return cli_main(["run", "thesis_float", "--duration", "0.2", "--fps", "10", "--set", "nx=3", "--set", "ny=3",
                     "--csv", str(tmp_path / "o.csv"), "--plot", str(tmp_path / "p.png"), "--no-progress", *options])


def test_cli_faces_and_first_frame(tmp_path):
    out = tmp_path / "frames"
    assert cli_run(tmp_path, "--export", str(out), "--faces", "triangles", "--first-frame", "5") == 0
    assert sorted(p.name for p in out.glob("*.ply")) == ["cloth_0005.ply", "cloth_0006.ply", "cloth_0007.ply"]
    manifest = json.loads((out / "frames.json").read_text())
    assert (manifest["faces"], manifest["first_frame"], manifest["face_count"]) == ("triangles", 5, 8)
    assert len(trimesh.load(out / "cloth_0005.ply", process=False).faces) == 8


def test_cli_refuses_a_bad_first_frame_in_one_line(tmp_path, capsys):
    assert cli_run(tmp_path, "--export", str(tmp_path / "frames"), "--first-frame", "-3") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "error: --first-frame must be a whole number from 0" in err


def test_cli_overwrite_replaces_an_earlier_export(tmp_path):
    """``--overwrite``: an earlier run's frames (described by its frames.json) give way to the new run's;
    other files in the directory stay."""
    out = tmp_path / "frames"
    assert cli_run(tmp_path, "--export", str(out)) == 0
    (out / "notes.txt").write_text("keep me")
    assert cli_run(tmp_path, "--export", str(out)) == 2  # refused without --overwrite
    assert cli_run(tmp_path, "--export", str(out), "--format", "obj", "--duration", "0.1", "--overwrite") == 0
    assert sorted(p.name for p in out.iterdir()) == ["cloth_0001.obj", "cloth_0002.obj", "frames.json",
                                                     "load_in_blender.py", "notes.txt"]
    assert json.loads((out / "frames.json").read_text())["format"] == "obj"


def test_cli_overwrite_leaves_frames_that_no_frames_json_describes(tmp_path, capsys):
    """Frame-like files that no wetcloth export describes (no frames.json) are someone else's: refused
    even with --overwrite, and left as they are."""
    out = tmp_path / "frames"
    out.mkdir()
    (out / "cloth_0001.ply").write_bytes(b"someone else's frame")
    assert cli_run(tmp_path, "--export", str(out), "--overwrite") == 2
    assert (out / "cloth_0001.ply").read_bytes() == b"someone else's frame"
    assert str(out) in capsys.readouterr().err


def test_a_run_of_part_of_a_frame_more_exports_whole_frames_only(tmp_path):
    """0.35 s at 10 fps: four frames at t = k / fps (USD time codes 1..4, the first frame t = 0; frames.json's
    last time 0.3 s), the CSV's last row at 0.35 s.  Before, the sample at 0.35 s was written as a fifth frame,
    which a frame sequence plays at 0.4 s (the hostile trial's finding)."""
    from pxr import Usd, UsdGeom

    scene = wetcloth.load_scene(nx=3, ny=3)
    with open_sequence(tmp_path / "usd", fmt="usd", fps=10, scene=scene) as usd:
        result = run(scene, 0.35, 10, on_frame=usd.on_frame, progress=False, warn=None)
    manifest = json.loads((tmp_path / "usd" / "frames.json").read_text())
    assert (manifest["frame_count"], manifest["last_time"]) == (4, pytest.approx(0.3))
    stage = Usd.Stage.Open(str(tmp_path / "usd" / "cloth.usd"))
    assert UsdGeom.Mesh(stage.GetPrimAtPath("/wetcloth/cloth")).GetPointsAttr().GetTimeSamples() == [1.0, 2.0, 3.0, 4.0]
    assert [row["time"] for row in result.rows] == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.35])
