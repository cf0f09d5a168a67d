"""The Blender extension in a real Blender (bpy 5.0.1 from PyPI, .venv-blender): build the zip,
install it, bake a towel over a ball in a pool, and check what Blender plays against wetcloth.

``wetcloth blender-extension`` builds the zip; one Blender process (tests/blender/extension_probe.py,
with its own user folder) installs it, builds the scene (a subdivided plane as the cloth, a UV
sphere collider, a water plane), bakes 48 frames, saves and reopens, bakes again cancelled after
20 frames, moves the cache away, frees the bake, bakes with the water keyed to rise, with the grip
keyed to rise and over frames 11-40 at 29.97 fps, tries scenes it must refuse, and bakes a round mesh
cloth over a cup (a mesh collider).  The reference is
wetcloth itself, run here on the scene the bake recorded (frames.json; for the mesh cloth, with the
arrays Blender held): the same compiled core on the same machine.

Without ``.venv-blender/bin/python`` the tests are skipped with the reason (and fail under
WETCLOTH_REQUIRE_BLENDER=1, as ``make test`` sets), as in tests/test_blender.py.
"""

import json
import math
import os
import subprocess
import sys
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from support.blender import BLENDER_PYTHON, DEFAULT_BLENDER_PYTHON, probe_extension, require_blender_python
from wetcloth.cli import main as cli_main
from wetcloth.exporter.blender_extension.geometry import MeshCloth, cloth_of, collider_of
from wetcloth.exporter.blender_extension.parameters import SCENE
from wetcloth.scene import from_dict
from wetcloth.simulation import Simulation

PROBE = Path(__file__).with_name("blender") / "extension_probe.py"
FRAMES, FPS, CUTS = 48, 24, 11  # 13 x 13 particles
CANCEL_AFTER = 20
SPEC = {"frames": FRAMES, "fps": FPS, "cuts": CUTS, "sphere": {"radius": 0.2, "z": 0.0},
        "cloth": {"size": 0.6, "z": 0.215}, "water_z": 0.06, "rise": 0.1, "ball_rise": 0.05, "cancel_after": CANCEL_AFTER,
        "mesh_frames": 24, "round_cloth": {"segments": 24, "radius": 0.3, "z": 0.12, "inset": 0.05, "insets": 3},
        "cup": {"radius": 0.22, "depth": 0.16, "z": 0.0}, "grip_rise": 0.1,
        "range": [11, 40], "range_fps": 30, "range_fps_base": 1.001}
#: Blender plays float32 positions (USD points): within 6e-8 m of wetcloth's below 1 m; the cloth
#: plane's centre, read from float32 vertices, is within 1e-7 m of the origin.
POSITION_TOL = 1e-6
#: No particle centre closer to the ball than thickness/2 less 0.1 mm (as tests/test_colliders.py:
#: the contact puts particles back at exactly thickness/2 at the end of each step).
CONTACT_TOL = 1e-4


@pytest.fixture(scope="module")
def baked(tmp_path_factory):
    root = tmp_path_factory.mktemp("extension")
    report = probe_extension(root, PROBE, SPEC)
    return SimpleNamespace(report=report, root=root, zip=next(root.glob("wetcloth-*.zip")))


def as_float32_decimal(value: float) -> float:
    """What the extension reads from a Blender float (float32): the shortest decimal rounding to it."""
    return float(str(np.float32(value)))


def reference(manifest: dict, levels=None) -> tuple[list, list]:
    """wetcloth's positions (n, 3) and wetness at every frame of the bake's scene (frames.json),
    stepped as the bake steps: frame by frame, the water level of each frame until the next."""
    sim = Simulation(from_dict(manifest["scene"]))
    times = np.arange(manifest["frame_count"]) / manifest["fps"]
    positions, wetness = [sim.positions], [sim.wetness]
    for k in range(1, len(times)):
        if levels is not None:
            sim.set_inputs(water_level=as_float32_decimal(levels[k - 1]))
        sim.sample(times[k:k + 1])
        positions.append(sim.positions)
        wetness.append(sim.wetness)
    return positions, wetness


def blender_order(blender_positions: np.ndarray, particles: np.ndarray) -> np.ndarray:
    """The particle at each Blender vertex, found where they start (each exactly one particle)."""
    distance = np.linalg.norm(blender_positions[:, None, :] - particles[None, :, :], axis=2)
    order = distance.argmin(axis=1)
    assert distance.min(axis=1).max() <= POSITION_TOL and len(set(order.tolist())) == len(order)
    return order


def check_against_reference(frames, manifest, levels=None):
    positions, wetness = reference(manifest, levels)
    order = blender_order(np.array(frames[0]["positions"]), positions[0])
    for frame, p, w in zip(frames, positions, wetness):
        assert np.abs(np.array(frame["positions"]) - p[order]).max() <= POSITION_TOL, frame["frame"]
        assert np.abs(np.array(frame["wetness"]) - w[order].astype(np.float32)).max() == 0.0, frame["frame"]


def test_the_zip_is_a_blender_extension_with_the_core_as_a_wheel(baked):
    """blender_manifest.toml (schema 1.0.0, id wetcloth, linux-x64, the wheels listed), the add-on's
    __init__.py and the wetcloth wheels (one per Python built for), each holding the compiled core, and
    a scipy and a pyamg wheel for each of their Pythons (a mesh cloth's preconditioner needs them)."""
    import tomllib

    with zipfile.ZipFile(baked.zip) as archive:
        names = archive.namelist()
        manifest = tomllib.loads(archive.read("blender_manifest.toml").decode())
        wheels = [name for name in names if name.startswith("wheels/")]
        ours = [name for name in wheels if name.startswith("wheels/wetcloth-")]
        for wheel in ours:
            with zipfile.ZipFile(archive.open(wheel)) as inner:
                assert any(name.startswith("wetcloth/_core") and name.endswith(".so") for name in inner.namelist())
    python_tags = sorted(name.split("-")[2] for name in ours)
    for dependency in ("scipy", "pyamg"):
        assert sorted(name.split("-")[2] for name in wheels if name.startswith(f"wheels/{dependency}-")) == python_tags
    assert len(wheels) == 3 * len(ours)
    assert baked.zip.name == "wetcloth-0.1.0.zip"
    assert (manifest["schema_version"], manifest["id"], manifest["type"]) == ("1.0.0", "wetcloth", "add-on")
    assert manifest["blender_version_min"] == "4.2.0" and "linux-x64" in manifest["platforms"]
    assert wheels and sorted(manifest["wheels"]) == sorted(f"./{w}" for w in wheels) and "__init__.py" in names


#: Runs in Blender's Python with a fresh user folder: installs the zip argv[1] as
#: `blender --command extension install-file -r user_default -e ZIP` does (the command's own handler);
#: prints its exit code, the add-ons enabled and whether the bake operator is there.
COMMAND_LINE_INSTALL = r"""
import json, sys
import bpy
from bl_pkg.bl_extension_cli import cli_extension_handler
code = cli_extension_handler(["install-file", "-r", "user_default", "-e", sys.argv[1]])
print(json.dumps({"code": code, "addons": [a for a in bpy.context.preferences.addons.keys() if "wetcloth" in a],
                  "bake": hasattr(bpy.types, "WETCLOTH_OT_bake")}))
"""


def test_it_installs_from_the_command_line(baked, tmp_path):
    """`blender --command extension install-file -r user_default -e wetcloth-VERSION.zip` (docs/blender.md):
    exit code 0, the add-on enabled and its bake operator registered, in a user folder of its own."""
    python = require_blender_python()
    env = os.environ | {"BLENDER_USER_RESOURCES": str(tmp_path)}
    done = subprocess.run([str(python), "-c", COMMAND_LINE_INSTALL, str(baked.zip)], capture_output=True, text=True,
                          timeout=300, env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report == {"code": 0, "addons": ["bl_ext.user_default.wetcloth"], "bake": True}, done.stdout[-3000:]


def test_it_installs_and_registers_its_scripting_names(baked):
    """package_install_files (what Preferences > Install from Disk runs) enables it; the operators,
    the four roles and one scene property per scene parameter exist."""
    install, names = baked.report["install"], baked.report["names"]
    assert install["result"] == ["FINISHED"] and install["addons"] == ["bl_ext.user_default.wetcloth"]
    assert names["bake"] and names["free_bake"]
    assert names["roles"] == ["NONE", "CLOTH", "COLLIDER", "WATER"]
    assert set(SCENE) <= set(names["scene"])


def test_the_towel_drapes_over_the_ball_without_entering_it(baked):
    """48 frames from frame 1 at 24 fps (frames.json says so): what Blender plays is wetcloth's run of the
    same scene; no particle enters the ball; the middle lies on its top and the edges hang down to the water."""
    bake = baked.report["bake"]
    manifest = bake["manifest"]
    assert bake["result"] == ["FINISHED"] and manifest["frame_count"] == FRAMES and manifest["complete"]
    assert manifest["fps"] == FPS and manifest["first_frame"] == 1
    assert manifest["scene"]["collider1_shape"] == "sphere"
    check_against_reference(bake["frames"], manifest)
    gap = 0.5 * manifest["scene"]["thickness"]
    radius = manifest["scene"]["collider1_radius"]
    for frame in bake["frames"]:
        distance = np.linalg.norm(np.array(frame["positions"]), axis=1) - radius
        assert distance.min() >= gap - CONTACT_TOL
    last = np.array(bake["frames"][-1]["positions"])
    assert abs(last[:, 2].max() - (radius + gap)) <= CONTACT_TOL  # the middle on top of the ball
    assert last[:, 2].min() < SPEC["water_z"] + gap  # the edges reach the water


def test_the_cache_is_a_usd_file_beside_the_blend_with_wetness_and_the_wet_material(baked):
    bake = baked.report["bake"]
    assert bake["modifiers"] == ["MESH_SEQUENCE_CACHE"]
    assert bake["stored_path"] == "//wetcloth_cache/Towel/Towel.usd" and bake["object_path"] == "/wetcloth/Towel"
    assert bake["materials"] == ["wetcloth wetness"]
    frames = bake["frames"]
    assert all(frame["wetness_domain"] == ["POINT", "FLOAT"] for frame in frames)
    assert max(frames[0]["wetness"]) == 0.0 and max(frames[-1]["wetness"]) > 0.01


def test_baking_again_replaces_the_cache_with_the_same_frames(baked):
    """A second bake in the same session (Blender still reading the first one's file) succeeds and
    plays the same frames: the run is deterministic and the cache is replaced, not appended to."""
    rebake, bake = baked.report["rebake"], baked.report["bake"]["frames"]
    assert rebake["result"] == ["FINISHED"]
    assert [f["positions"] for f in rebake["frames"]] == [bake[0]["positions"], bake[-1]["positions"]]


def test_the_saved_file_plays_the_bake_again(baked):
    """Reopened: the same frames as after the bake, and the cloth moves between them; no cache missing."""
    reopened = baked.report["reopened"]
    assert reopened["missing"] == []
    for frame, before in zip(reopened["frames"], baked.report["bake"]["frames"]):
        assert frame["positions"] == before["positions"] and frame["wetness"] == before["wetness"]
    first, last = (np.array(reopened["frames"][k]["positions"]) for k in (0, -1))
    assert np.abs(last - first).max() > 0.1


def test_a_cancelled_bake_keeps_the_frames_it_baked(baked):
    """cancel_after=20 (what Esc does, from a script): 20 frames in the cache, frames.json marked
    incomplete, frame 20 as the full bake had it; later frames hold the last one baked."""
    cancelled, full = baked.report["cancelled"], baked.report["bake"]["frames"]
    assert cancelled["result"] == ["CANCELLED"]
    assert cancelled["manifest"]["frame_count"] == CANCEL_AFTER and not cancelled["manifest"]["complete"]
    at_cancel, at_end = cancelled["frames"]
    assert at_cancel["positions"] == full[CANCEL_AFTER - 1]["positions"]
    assert at_end["positions"] == at_cancel["positions"]


def test_a_moved_cache_is_reported_when_the_file_opens(baked):
    moved = baked.report["moved"]
    path = str(baked.root / "work" / "wetcloth_cache" / "Towel" / "Towel.usd")
    assert moved["missing"] == [["Towel", path]]
    assert "Wet Cloth: the cache of 'Towel' is missing" in moved["stderr"] and path in moved["stderr"]


def test_the_panel_shows_every_setting_under_its_name_and_a_missing_cache_in_red(baked):
    """The Wet Cloth panel, drawn for the towel into a recording layout: its role, preset, every fabric
    setting and the pin group, Bake and Free Bake; the Scene subpanel: the cache folder and every scene
    setting.  With the cache moved away, an ERROR line names the missing file (once as the towel's
    cache, once among the file's missing caches); with it back, a line names it, relative to the .blend."""
    from wetcloth.exporter.blender_extension.parameters import FABRIC, SCENE

    path = str(baked.root / "work" / "wetcloth_cache" / "Towel" / "Towel.usd")
    moved, restored = baked.report["moved"]["panel"], baked.report["restored"]["panel"]
    settings = [item[1] for item in moved if item[0] in ("prop", "prop_search")]
    assert settings == ["role", "preset", *FABRIC, "pin_group", "cache_directory", *SCENE]
    assert ["operator", "wetcloth.bake", "PHYSICS"] in moved and ["operator", "wetcloth.free_bake", "TRASH"] in moved
    assert [item for item in moved if item[0] == "label"] == [
        ["label", f"Cache missing: {path}", "ERROR"], ["label", f"Towel: cache missing ({path})", "ERROR"]]
    assert [item for item in restored if item[0] == "label"] == [
        ["label", "Cache: //wetcloth_cache/Towel/Towel.usd", "FILE"]]


def test_free_bake_removes_the_modifier_and_the_cache_files(baked):
    freed = baked.report["freed"]
    assert freed["result"] == ["FINISHED"] and freed["modifiers"] == [] and freed["left"] == []


def test_a_water_plane_keyed_to_rise_raises_the_water_level(baked):
    """The level follows the keys frame by frame (wetcloth with the same levels as inputs); the cloth
    ends wetter than under the still water."""
    rising = baked.report["rising"]
    levels = rising["levels"]
    assert levels[-1] - levels[0] == pytest.approx(SPEC["rise"], abs=1e-6)
    check_against_reference(rising["frames"], rising["manifest"], levels)
    still = baked.report["bake"]["frames"][-1]["wetness"]
    assert np.sum(rising["frames"][-1]["wetness"]) > np.sum(still)


def test_a_ball_keyed_to_rise_lifts_the_towel_without_it_entering(baked):
    """The ball's animated location becomes collider keys at every frame: what Blender plays is
    wetcloth's run with those keys, no particle enters the ball where it is at that frame, and the
    towel ends on its top.  A ball keyed to scale is refused, naming it."""
    moving = baked.report["moving"]
    manifest = moving["manifest"]
    assert moving["result"] == ["FINISHED"] and manifest["complete"], moving["error"]
    scene = from_dict(manifest["scene"])
    assert len(scene.collider_keys) == FRAMES - 1
    centres = np.array(moving["centres"])
    for k, (key, centre) in enumerate(zip(scene.collider_keys, centres[1:]), 1):
        assert key.collider == 1 and key.time == k / FPS
        assert key.z == as_float32_decimal(centre[2] - centres[0][2]) and key.x == key.y == 0.0
    assert centres[-1][2] - centres[0][2] == np.float32(SPEC["ball_rise"])
    check_against_reference(moving["frames"], manifest)
    gap = 0.5 * manifest["scene"]["thickness"]
    radius = manifest["scene"]["collider1_radius"]
    for frame, centre in zip(moving["frames"], centres):
        distance = np.linalg.norm(np.array(frame["positions"]) - centre, axis=1) - radius
        assert distance.min() >= gap - CONTACT_TOL, frame["frame"]
    last = np.array(moving["frames"][-1]["positions"])
    assert abs(last[:, 2].max() - (centres[-1][2] + radius + gap)) <= CONTACT_TOL  # on the risen ball's top
    assert "'Ball'" in moving["scaling"] and "scales at frame" in moving["scaling"]


def test_a_ball_keyed_to_rise_and_turn_turns_by_its_keys(baked):
    """The ball keyed to turn 0.5 rad about x while it rises: its keys' rotation vectors are Blender's
    turn from the first frame at every frame (rx its angle in degrees, to the float32 of Blender's
    matrices: 1e-5 deg), what Blender plays is wetcloth's run with those keys, and no particle enters
    the ball."""
    turned = baked.report["moving"]["turned"]
    manifest = turned["manifest"]
    assert turned["result"] == ["FINISHED"] and manifest["complete"], turned["error"]
    scene = from_dict(manifest["scene"])
    assert len(scene.collider_keys) == FRAMES - 1
    turns = np.array(turned["turns"])
    for key, turn in zip(scene.collider_keys, turns[1:]):
        angle = math.degrees(math.atan2(turn[2, 1], turn[1, 1]))
        assert abs(key.rx - angle) <= 1e-5 and key.ry == key.rz == 0.0
    assert scene.collider_keys[-1].rx == pytest.approx(math.degrees(0.5), abs=1e-5)
    check_against_reference(turned["frames"], manifest)
    gap, radius = 0.5 * manifest["scene"]["thickness"], manifest["scene"]["collider1_radius"]
    centres = baked.report["moving"]["centres"]
    for frame, centre in zip(turned["frames"], centres):
        distance = np.linalg.norm(np.array(frame["positions"]) - centre, axis=1) - radius
        assert distance.min() >= gap - CONTACT_TOL, frame["frame"]


def test_a_grip_keyed_to_rise_lifts_the_pinned_hem_by_its_keys(baked):
    """scene.wetcloth.grip_z keyed from 0 to 0.1 m with the towel pinned by a vertex group: the bake samples
    Blender's grip_z at every frame into grip keys (the scene's grip_z input 0), the pinned hem is at its
    start raised by the grip at every frame (within the float32 of the USD points) and ends 0.1 m higher,
    and what Blender plays is wetcloth's run of the scene with those keys.  A wind or a fabric setting keyed
    to change is refused, naming it: the bake would read it at the first frame only."""
    grip = baked.report["grip"]
    manifest = grip["manifest"]
    assert grip["result"] == ["FINISHED"] and manifest["complete"], grip["error"]
    scene = from_dict(manifest["scene"])
    grips = grip["grips"]
    assert scene.pinned_edge == "y_max" and scene.grip_z == 0.0 and len(scene.grip_keys) == FRAMES - 1
    for k, key in enumerate(scene.grip_keys, 1):
        assert (key.time, key.x, key.y, key.z) == (k / FPS, 0.0, 0.0, as_float32_decimal(grips[k]))
    assert grips[0] == 0.0 and grips[-1] == np.float32(SPEC["grip_rise"])
    hem = grip["pinned"]
    start = np.array(grip["frames"][0]["positions"])[hem]
    for frame, lift in zip(grip["frames"], grips):
        assert np.abs(np.array(frame["positions"])[hem] - start - [0.0, 0.0, lift]).max() <= POSITION_TOL, frame["frame"]
    check_against_reference(grip["frames"], manifest)
    assert "scene setting 'wind_x' changes at frame 2" in grip["wind"]
    assert "cloth 'Towel''s setting 'damping' changes at frame 2" in grip["damping"]


def test_a_bake_over_another_range_and_fps_starts_at_its_first_frame(baked):
    """Frames 11-40 at 30 / 1.001 fps (NTSC): frames.json says fps 30 / fps_base (Blender's float32 1.001),
    first frame 11 and 30 frames; the cloth Blender plays at frame 11 is wetcloth's t = 0 state, and at every
    frame its run of the scene frame by frame at that fps."""
    ranged = baked.report["range"]
    manifest = ranged["manifest"]
    first, last = SPEC["range"]
    assert ranged["result"] == ["FINISHED"] and manifest["complete"], ranged["error"]
    assert ranged["fps_base"] == np.float32(SPEC["range_fps_base"])
    assert manifest["fps"] == SPEC["range_fps"] / ranged["fps_base"]
    assert manifest["first_frame"] == first and manifest["frame_count"] == last - first + 1
    assert ranged["frames"][0]["frame"] == first
    start = Simulation(from_dict(manifest["scene"])).positions
    order = blender_order(np.array(ranged["frames"][0]["positions"]), start)
    assert np.abs(np.array(ranged["frames"][0]["positions"]) - start[order]).max() <= POSITION_TOL
    check_against_reference(ranged["frames"], manifest)


def test_pin_group_preset_and_the_cloths_own_modifiers(baked):
    """A vertex group holding the vertices of the largest y is pinned_edge y_max; the denim preset
    sets the fabric's parameters, its bend_rigidity (hinges) among them; the plane is baked from the mesh as
    stored, so a Solidify modifier of the towel's own stays, after the cache."""
    from wetcloth.exporter.blender_extension.fabrics import FABRIC_PARAMETERS, fabric_parameters

    pinned = baked.report["pinned"]
    assert pinned["result"] == ["CANCELLED"] and pinned["manifest"]["frame_count"] == 3
    scene = pinned["manifest"]["scene"]
    assert scene["pinned_edge"] == "y_max"
    assert {name: scene[name] for name in FABRIC_PARAMETERS} == fabric_parameters("DENIM")
    assert scene["bend_rigidity"] > 0.0
    assert pinned["modifiers"] == ["MESH_SEQUENCE_CACHE", "SOLIDIFY"]


def test_scenes_it_cannot_bake_are_refused_naming_the_object(baked):
    refused = baked.report["refusals"]
    assert "cloth 'Fin' cannot be the cloth" in refused["cloth"] and "belongs to 3 faces" in refused["cloth"]
    assert "collider 'Dots' has no faces" in refused["collider"]
    assert refused["towel_modifiers"] == ["MESH_SEQUENCE_CACHE"]  # a refused bake leaves the last one in place


def test_the_blender_python_is_the_makefiles(baked):
    """The probe ran in the bpy this suite pins, or in the one WETCLOTH_BLENDER_PYTHON names (the newest on
    PyPI, 5.3.0 on Python 3.13, passed this file on 2026-12-05: docs/blender.md section 8)."""
    assert BLENDER_PYTHON.exists()
    if BLENDER_PYTHON == DEFAULT_BLENDER_PYTHON:
        assert baked.report["blender"].startswith("5.0")
    else:
        found = subprocess.run([str(BLENDER_PYTHON), "-c", "import bpy; print(bpy.app.version_string)"],
                               capture_output=True, text=True, check=True).stdout.strip()
        assert baked.report["blender"] == found


def world(held: dict) -> np.ndarray:
    """An object's vertices (n, 3) in world space, as the extension reads them (float32 co, float64 after)."""
    matrix = np.array(held["matrix"])
    return np.array(held["co"]) @ matrix[:3, :3].T + matrix[:3, 3]


def closest_on_triangles(p: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Distance (m) from each point p (n, 3) to the nearest of the triangles corners (t, 3, 3), brute force:
    to the plane where the point projects inside the triangle, else to the nearest of its three edges."""
    a, b, c = (corners[None, :, k] for k in range(3))
    p = p[:, None]
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    height = ((p - a) * normal).sum(-1)
    q = p - height[..., None] * normal
    inside = np.ones(height.shape, dtype=bool)
    for u, w in ((a, b), (b, c), (c, a)):
        inside &= (np.cross(w - u, q - u) * normal).sum(-1) >= 0.0
    distance = np.where(inside, np.abs(height), np.inf)
    for u, w in ((a, b), (b, c), (c, a)):
        edge = w - u
        t = np.clip(((p - u) * edge).sum(-1) / (edge * edge).sum(-1), 0.0, 1.0)
        distance = np.minimum(distance, np.linalg.norm(p - u - t[..., None] * edge, axis=-1))
    return distance.min(axis=1)


def test_closest_on_triangles_is_the_distance_to_a_triangle():
    """The test's own distance: above the face, beside an edge, beyond a corner."""
    triangle = np.array([[[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]])
    points = np.array([[0.2, 0.2, 0.5], [0.5, -0.3, 0.0], [-0.3, -0.4, 0.0], [1.0, 1.0, 0.0]])
    assert closest_on_triangles(points, triangle) == pytest.approx([0.5, 0.3, 0.5, np.sqrt(0.5)], abs=1e-12)


def test_a_mesh_cloth_bakes_over_a_mesh_collider_as_wetcloth_runs_the_same_arrays(baked):
    """A round cloth of quads around a 24-gon, pinned at two rim vertices, over a cup (an open cylinder
    with a bottom: a mesh collider).  wetcloth, given the arrays Blender holds (through the extension's
    own numpy readers), runs the same frames: what Blender plays, vertex by vertex in Blender's order,
    is within POSITION_TOL (float32 USD points); pins stay where they started; no vertex comes closer
    to the cup's triangles than thickness/2 less CONTACT_TOL, and at the end it lies on the cup (this
    coarse cloth on the rim: a rim vertex 0.1 mm from a cloth face, the edges' contact distance of
    docs/model.md 6.3, where its particles are 16 mm from the cup); the object keeps its faces; neither meshio
    nor trimesh was imported, and the bundled scipy and pyamg (a larger mesh's multigrid levels) import."""
    mesh = baked.report["mesh"]
    assert mesh["result"] == ["FINISHED"] and mesh["manifest"]["complete"], mesh.get("error")
    assert mesh["imported"] == []
    assert mesh["importable"] == {"pyamg": True, "scipy": True}
    held, cup = mesh["cloth"], mesh["cup"]
    assert sorted(mesh["played_faces"]) == sorted(held["sizes"]) and max(held["sizes"]) == 24
    cloth, pins = cloth_of(world(held), np.array(held["edges"]), (held["sizes"], held["loops"]),
                           (held["triangles"], held["triangle_faces"]), mesh["pinned"], "Tablecloth")
    assert isinstance(cloth, MeshCloth) and len(mesh["pinned"]) == 2
    collider = collider_of(world(cup), np.array(cup["triangles"]), "Cup")
    recorded = mesh["manifest"]["scene"]
    assert (recorded["cloth_mesh"], recorded["collider1_file"]) == ("Tablecloth", "collider 'Cup'")
    scene = from_dict(recorded | cloth.scene_values() | {"pinned_edge": pins, "collider1_file": collider["file"]})
    sim = Simulation(scene)
    times = np.arange(SPEC["mesh_frames"]) / FPS
    start = np.array(mesh["frames"][0]["positions"])
    corners = world(cup)[np.array(cup["triangles"])]
    gap = 0.5 * scene.thickness
    for k, frame in enumerate(mesh["frames"]):
        if k:
            sim.sample(times[k:k + 1])
        played = np.array(frame["positions"])
        assert np.abs(played - sim.positions).max() <= POSITION_TOL, frame["frame"]
        assert np.abs(played[mesh["pinned"]] - start[mesh["pinned"]]).max() <= POSITION_TOL
        assert closest_on_triangles(played, corners).min() >= gap - CONTACT_TOL, frame["frame"]
    assert np.abs(played - start).max() > 0.05  # it fell
    # and lies on the cup: its particles on the cup's faces, or its faces on the cup's rim (edge contact)
    rim_on_cloth = closest_on_triangles(world(cup), played[np.array(held["triangles"])]).min()
    assert min(closest_on_triangles(played, corners).min(), rim_on_cloth) <= gap + CONTACT_TOL
