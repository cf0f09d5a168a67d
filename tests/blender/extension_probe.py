"""Runs in bpy (PyPI's bpy, background): installs the Wet Cloth extension and bakes a scene with it.

    BLENDER_USER_RESOURCES=DIR .venv-blender/bin/python tests/blender/extension_probe.py SPEC.json RESULT.json

SPEC: {"zip": the extension, "work": a folder, "frames": frame count, "fps": .., "cuts": plane cuts,
       "sphere": {"radius", "z"}, "cloth": {"size", "z"}, "water_z": .., "cancel_after": .., "grip_rise": ..,
       "range": [first, last], "range_fps": .., "range_fps_base": ..}.
The scene: a plane subdivided into a grid (role Cloth) above a UV sphere (Collider) standing in a
water plane (Water surface), saved as WORK/scene.blend.  RESULT (the assertions are in
tests/test_blender_extension.py):
  "install": the operator's result and the add-on module; "names": the scripting names found;
  "bake": result, seconds, the evaluated cloth at every frame (world positions, wetness), the
          modifier, cache path as stored, material, frames.json;
  "rebake": the same bake again at once (its result, the first and last frame);
  "reopened": the same frames after saving and opening the .blend again;
  "cancelled": a bake with cancel_after: result, frames.json, the evaluated cloth at a frame baked
               and at the last frame;
  "moved": after moving the cache folder and opening the .blend: what the load check said, and what the
           panels draw for the towel (as [kind, name or text, icon]); "restored": the panels' drawing with
           the cache back;
  "freed": free_bake's result and the files left;
  "pinned": a short bake of the towel pinned by a vertex group, of denim, with a Solidify modifier of its own;
  "rising": a bake with the water keyed to rise by "rise" m: the levels at every frame, the cloth;
  "grip": a bake of the towel pinned by a vertex group with the grip keyed to rise by "grip_rise" m:
          the grip at every frame, the cloth, the pins; the errors of bakes with the wind or the
          towel's damping keyed;
  "range": a bake over the frames "range" at "range_fps" / "range_fps_base": frames.json, the cloth;
  "refusals": the errors of scenes it cannot bake;
  "mesh": a round cloth of quads and an n-gon (a filled circle inset a few times), two vertices pinned, over a
          cup (a cylinder without its top face: a mesh collider), baked for "mesh_frames" frames: the
          cloth's and the cup's arrays as Blender holds them, the evaluated cloth at every frame, the
          object's faces after the bake, frames.json, and whether meshio or trimesh were imported.
"""

import contextlib
import importlib.util
import io
import json
import os
import shutil
import sys
import time
import traceback
from types import SimpleNamespace

import bpy  # first: bpy makes bmesh importable
import bmesh  # noqa: E402
import numpy as np


def evaluated_cloth(obj, frame):
    bpy.context.scene.frame_set(frame)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    matrix = np.array(obj.matrix_world)
    world = co.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    wetness = None
    if "wetness" in mesh.attributes:
        values = np.empty(len(mesh.vertices), dtype=np.float32)
        mesh.attributes["wetness"].data.foreach_get("value", values)
        wetness = values.tolist()
    attribute = mesh.attributes.get("wetness")
    out = {"frame": frame, "positions": world.tolist(), "wetness": wetness,
           "wetness_domain": [attribute.domain, attribute.data_type] if attribute else None}
    evaluated.to_mesh_clear()
    return out


def subdivided_plane(size: float, z: float, cuts: int, name: str):
    """A Cloth object ``name``: a plane of side ``size`` m at height ``z`` m, its edges cut ``cuts`` times."""
    bpy.ops.mesh.primitive_plane_add(size=size, location=(0.0, 0.0, z))
    cloth = bpy.context.object
    cloth.name = name
    bm = bmesh.new()
    bm.from_mesh(cloth.data)
    bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=cuts, use_grid_fill=True)
    bm.to_mesh(cloth.data)
    bm.free()
    cloth.wetcloth.role = "CLOTH"
    return cloth


def build_scene(spec):
    bpy.ops.wm.read_homefile(use_empty=True)  # keeps the preferences (the add-on); factory settings would not
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = spec["fps"], 1.0
    scene.frame_start, scene.frame_end = 1, spec["frames"]
    cloth = subdivided_plane(spec["cloth"]["size"], spec["cloth"]["z"], spec["cuts"], "Towel")
    cloth.wetcloth.preset = "COTTON_TERRY_TOWEL"
    bpy.ops.mesh.primitive_uv_sphere_add(radius=spec["sphere"]["radius"], location=(0.0, 0.0, spec["sphere"]["z"]))
    bpy.context.object.name = "Ball"
    bpy.context.object.wetcloth.role = "COLLIDER"
    bpy.ops.mesh.primitive_plane_add(size=3.0, location=(0.0, 0.0, spec["water_z"]))
    bpy.context.object.name = "Pool"
    bpy.context.object.wetcloth.role = "WATER"
    scene.wetcloth.self_collision = "off"
    path = os.path.join(spec["work"], "scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    return path


def operator(call, **kwargs):
    """The operator's result and the messages it reported (bpy raises RuntimeError for errors)."""
    try:
        return {"result": sorted(call(**kwargs)), "error": None}
    except RuntimeError as exc:
        return {"result": ["ERROR"], "error": str(exc)}


class RecordingLayout:
    """Stands for a panel's layout (bpy.types.UILayout): records what its draw() puts in it."""

    def __init__(self, items: list):
        self.items = items

    def prop(self, data, name, **options):
        self.items.append(["prop", name, options.get("icon", "NONE")])

    def prop_search(self, data, name, search_data, search_name, **options):
        self.items.append(["prop_search", name, search_name])

    def label(self, text="", icon="NONE"):
        self.items.append(["label", text, icon])

    def operator(self, idname, icon="NONE", **options):
        self.items.append(["operator", idname, icon])

    def column(self, **options):
        return self

    def row(self, **options):
        return self


def drawn_panels(obj) -> list:
    """What the Wet Cloth panel and its Scene subpanel draw for obj, in order."""
    items = []
    context = SimpleNamespace(object=obj, scene=bpy.context.scene)
    for panel in (bpy.types.WETCLOTH_PT_physics, bpy.types.WETCLOTH_PT_scene):
        panel.draw(SimpleNamespace(layout=RecordingLayout(items)), context)
    return items


def cache_report(obj):
    modifier = obj.modifiers.get("Wet Cloth cache")
    if modifier is None:
        return {"modifiers": [m.type for m in obj.modifiers]}
    path = bpy.path.abspath(modifier.cache_file.filepath)
    manifest = os.path.join(os.path.dirname(path), "frames.json")
    return {"modifiers": [m.type for m in obj.modifiers], "stored_path": modifier.cache_file.filepath,
            "path": path, "object_path": modifier.object_path,
            "materials": [s.material.name for s in obj.material_slots if s.material],
            "manifest": json.load(open(manifest)) if os.path.isfile(manifest) else None}


def rising_water(spec, blend, frames):
    """A bake with the water plane keyed to rise: the level at every frame, and the cloth."""
    bpy.ops.wm.open_mainfile(filepath=blend)
    pool = bpy.data.objects["Pool"]
    pool.location.z = spec["water_z"]
    pool.keyframe_insert("location", index=2, frame=frames[0])
    pool.location.z = spec["water_z"] + spec["rise"]
    pool.keyframe_insert("location", index=2, frame=frames[-1])
    out = operator(bpy.ops.wetcloth.bake)
    towel = bpy.data.objects["Towel"]
    out |= cache_report(towel)
    out["levels"] = []
    for frame in frames:
        bpy.context.scene.frame_set(frame)
        out["levels"].append(pool.matrix_world.translation.z)
    out["frames"] = [evaluated_cloth(towel, f) for f in frames]
    return out


def moving_ball(spec, blend, frames):
    """A bake with the ball keyed to rise under the towel: the ball's centre and the cloth at every
    frame; then the ball keyed to turn about x too: the bake, its rotation matrix and the cloth at every
    frame; then keyed to scale too: the bake's error."""
    bpy.ops.wm.open_mainfile(filepath=blend)
    ball = bpy.data.objects["Ball"]
    ball.location.z = spec["sphere"]["z"]
    ball.keyframe_insert("location", index=2, frame=frames[0])
    ball.location.z = spec["sphere"]["z"] + spec["ball_rise"]
    ball.keyframe_insert("location", index=2, frame=frames[-1])
    out = operator(bpy.ops.wetcloth.bake)
    out |= cache_report(bpy.data.objects["Towel"])
    out["centres"] = []
    for frame in frames:
        bpy.context.scene.frame_set(frame)
        out["centres"].append(list(ball.matrix_world.translation))
    out["frames"] = [evaluated_cloth(bpy.data.objects["Towel"], f) for f in frames]
    ball.rotation_euler.x = 0.0
    ball.keyframe_insert("rotation_euler", index=0, frame=frames[0])
    ball.rotation_euler.x = 0.5
    ball.keyframe_insert("rotation_euler", index=0, frame=frames[-1])
    turned = operator(bpy.ops.wetcloth.bake)
    turned |= cache_report(bpy.data.objects["Towel"])
    turned["turns"] = []
    for frame in frames:
        bpy.context.scene.frame_set(frame)
        turned["turns"].append([list(row) for row in ball.matrix_world.to_3x3()])
    turned["frames"] = [evaluated_cloth(bpy.data.objects["Towel"], f) for f in frames]
    out["turned"] = turned
    ball.scale = (1.0, 1.0, 1.0)
    ball.keyframe_insert("scale", frame=frames[0])
    ball.scale = (1.2, 1.2, 1.2)
    ball.keyframe_insert("scale", frame=frames[-1])
    out["scaling"] = operator(bpy.ops.wetcloth.bake)["error"]
    return out


def pin_hem(towel) -> list[int]:
    """Pin the towel by a vertex group "Hem" of its vertices of the largest y; their indices."""
    top = max(v.co.y for v in towel.data.vertices)
    hem = [v.index for v in towel.data.vertices if abs(v.co.y - top) < 1e-6]
    towel.vertex_groups.new(name="Hem").add(hem, 1.0, "REPLACE")
    towel.wetcloth.pin_group = "Hem"
    return hem


def keyed_grip(spec, blend, frames):
    """The towel pinned by its hem with scene.wetcloth.grip_z keyed from 0 to spec["grip_rise"] m: the bake,
    Blender's grip_z and the cloth at every frame, the pinned vertices; then with the wind keyed too, and
    with only the towel's damping keyed: the bakes' errors."""
    bpy.ops.wm.open_mainfile(filepath=blend)
    towel = bpy.data.objects["Towel"]
    settings = bpy.context.scene.wetcloth
    out = {"pinned": pin_hem(towel)}
    for frame, z in ((frames[0], 0.0), (frames[-1], spec["grip_rise"])):
        settings.grip_z = z
        settings.keyframe_insert("grip_z", frame=frame)
    out |= operator(bpy.ops.wetcloth.bake)
    out |= cache_report(towel)
    out["grips"] = []
    for frame in frames:
        bpy.context.scene.frame_set(frame)
        out["grips"].append(settings.grip_z)
    out["frames"] = [evaluated_cloth(towel, f) for f in frames]
    for frame, wind in ((frames[0], 0.0), (frames[-1], 2.0)):
        settings.wind_x = wind
        settings.keyframe_insert("wind_x", frame=frame)
    out["wind"] = operator(bpy.ops.wetcloth.bake)["error"]
    bpy.context.scene.animation_data_clear()
    for frame, damping in ((frames[0], towel.wetcloth.damping), (frames[-1], 2 * towel.wetcloth.damping)):
        towel.wetcloth.damping = damping
        towel.wetcloth.keyframe_insert("damping", frame=frame)
    out["damping"] = operator(bpy.ops.wetcloth.bake)["error"]
    return out


def another_range(spec, blend):
    """The towel baked over frames spec["range"] at spec["range_fps"] / spec["range_fps_base"]: the bake,
    frames.json and the cloth at every frame of the range."""
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = spec["range"]
    scene.render.fps, scene.render.fps_base = spec["range_fps"], spec["range_fps_base"]
    towel = bpy.data.objects["Towel"]
    out = operator(bpy.ops.wetcloth.bake)
    out |= cache_report(towel)
    out["fps_base"] = scene.render.fps_base
    out["frames"] = [evaluated_cloth(towel, f) for f in range(spec["range"][0], spec["range"][1] + 1)]
    return out


def pinned_with_modifiers(blend):
    """The towel pinned by a vertex group (the vertices of its largest y), of the denim preset, with a
    Solidify modifier of its own: a short bake (cancel_after=3)."""
    bpy.ops.wm.open_mainfile(filepath=blend)
    towel = bpy.data.objects["Towel"]
    pin_hem(towel)
    towel.wetcloth.preset = "DENIM"
    towel.modifiers.new("Solidify", "SOLIDIFY")
    out = operator(bpy.ops.wetcloth.bake, cancel_after=3)
    out |= cache_report(towel)
    return out


def refusals(spec):
    """Errors of scenes the bake cannot take: a cloth with an edge in three faces, a collider with no faces."""
    out = {}
    bpy.ops.wm.open_mainfile(filepath=os.path.join(spec["work"], "scene.blend"))
    bpy.data.objects["Towel"].wetcloth.role = "NONE"
    mesh = bpy.data.meshes.new("Fin")
    mesh.from_pydata([(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 0), (-1, 0, 0), (-1, 1, 0), (0, 0, 1), (0, 1, 1)], [],
                     [(0, 2, 3, 1), (4, 0, 1, 5), (0, 6, 7, 1)])
    fin = bpy.data.objects.new("Fin", mesh)
    fin.location.z = 0.5
    bpy.context.scene.collection.objects.link(fin)
    fin.wetcloth.role = "CLOTH"
    out["cloth"] = operator(bpy.ops.wetcloth.bake)["error"]
    bpy.ops.wm.open_mainfile(filepath=os.path.join(spec["work"], "scene.blend"))
    mesh = bpy.data.meshes.new("Dots")
    mesh.from_pydata([(2, 2, 0), (2, 3, 0)], [(0, 1)], [])
    dots = bpy.data.objects.new("Dots", mesh)
    bpy.context.scene.collection.objects.link(dots)
    dots.wetcloth.role = "COLLIDER"
    out["collider"] = operator(bpy.ops.wetcloth.bake)["error"]
    out["towel_modifiers"] = [m.type for m in bpy.data.objects["Towel"].modifiers]  # its last bake, kept
    return out


def arrays(obj, evaluated=False):
    """An object's mesh as Blender holds it (evaluated: after its modifiers): local vertices, the world
    matrix, edges, each face's corner count, the corners' vertices, the loop triangles and their faces."""
    owner = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()) if evaluated else obj
    mesh = owner.to_mesh() if evaluated else obj.data
    mesh.calc_loop_triangles()
    out = {"co": [tuple(v.co) for v in mesh.vertices], "matrix": [list(row) for row in obj.matrix_world],
           "edges": [tuple(e.vertices) for e in mesh.edges], "sizes": [p.loop_total for p in mesh.polygons],
           "loops": [loop.vertex_index for loop in mesh.loops],
           "triangles": [tuple(t.vertices) for t in mesh.loop_triangles],
           "triangle_faces": [t.polygon_index for t in mesh.loop_triangles]}
    if evaluated:
        owner.to_mesh_clear()
    return out


def round_cloth(shape: dict, name: str):
    """A Cloth object ``name``: a filled circle of shape["segments"] vertices, shape["radius"] m, at height
    shape["z"] m, inset shape["insets"] times by shape["inset"] m (rings of quads around an n-gon)."""
    bpy.ops.mesh.primitive_circle_add(vertices=shape["segments"], radius=shape["radius"], fill_type="NGON",
                                      location=(0.0, 0.0, shape["z"]))
    cloth = bpy.context.object
    cloth.name = name
    bm = bmesh.new()
    bm.from_mesh(cloth.data)
    for _ in range(shape["insets"]):  # rings of quads around the n-gon
        bmesh.ops.inset_region(bm, faces=[max(bm.faces, key=lambda f: len(f.verts))], thickness=shape["inset"],
                               use_boundary=True)
    bm.to_mesh(cloth.data)
    bm.free()
    cloth.wetcloth.role = "CLOTH"
    return cloth


def mesh_cloth_over_a_cup(spec):
    """A round cloth of quads around an n-gon, pinned at two rim vertices, over a cup (a mesh collider)."""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = spec["fps"], 1.0
    scene.frame_start, scene.frame_end = 1, spec["mesh_frames"]
    cup = spec["cup"]
    bpy.ops.mesh.primitive_cylinder_add(vertices=24, radius=cup["radius"], depth=cup["depth"], end_fill_type="NGON",
                                        location=(0.0, 0.0, cup["z"]))
    collider = bpy.context.object
    collider.name = "Cup"
    bm = bmesh.new()
    bm.from_mesh(collider.data)
    top = max(bm.faces, key=lambda f: f.calc_center_median().z)
    bmesh.ops.delete(bm, geom=[top], context="FACES_ONLY")
    bm.to_mesh(collider.data)
    bm.free()
    collider.wetcloth.role = "COLLIDER"
    cloth = round_cloth(spec["round_cloth"], "Tablecloth")
    rim = sorted(range(len(cloth.data.vertices)), key=lambda k: -cloth.data.vertices[k].co.length)
    pinned = [k for k in rim[:spec["round_cloth"]["segments"]] if abs(cloth.data.vertices[k].co.y) < 1e-6]
    group = cloth.vertex_groups.new(name="Pins")
    group.add(pinned, 1.0, "REPLACE")
    cloth.wetcloth.pin_group = "Pins"
    scene.wetcloth.self_collision = "off"
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(spec["work"], "mesh.blend"))
    out = {"cloth": arrays(cloth), "cup": arrays(collider, evaluated=True), "pinned": pinned}
    started = time.perf_counter()
    out |= operator(bpy.ops.wetcloth.bake)
    out["seconds"] = time.perf_counter() - started
    out |= cache_report(cloth)
    out["frames"] = [evaluated_cloth(cloth, f) for f in range(1, spec["mesh_frames"] + 1)]
    evaluated = cloth.evaluated_get(bpy.context.evaluated_depsgraph_get())
    out["played_faces"] = sorted(p.loop_total for p in evaluated.data.polygons)
    out["imported"] = sorted(name for name in ("meshio", "trimesh") if name in sys.modules)
    out["importable"] = {name: importlib.util.find_spec(name) is not None for name in ("pyamg", "scipy")}
    return out


@contextlib.contextmanager
def reported(result_path, result: dict):
    """Write ``result`` as JSON to ``result_path`` when the block ends, with the traceback that stopped it, if
    one did, under "error"."""
    try:
        yield
    except Exception:
        result["error"] = traceback.format_exc()
    with open(result_path, "w") as fh:
        json.dump(result, fh)


def main(spec_path, result_path):
    spec = json.load(open(spec_path))
    result = {"blender": bpy.app.version_string}
    frames = list(range(1, spec["frames"] + 1))
    with reported(result_path, result):
        result["install"] = operator(bpy.ops.extensions.package_install_files, filepath=spec["zip"],
                                     repo="user_default", enable_on_install=True)
        result["install"]["addons"] = [name for name in bpy.context.preferences.addons.keys() if "wetcloth" in name]
        blend = build_scene(spec)
        result["names"] = {"bake": hasattr(bpy.ops.wetcloth, "bake"), "free_bake": hasattr(bpy.ops.wetcloth, "free_bake"),
                           "roles": [item.identifier for item in
                                     bpy.types.Object.bl_rna.properties["wetcloth"].fixed_type.properties["role"].enum_items],
                           "scene": sorted(bpy.context.scene.wetcloth.bl_rna.properties.keys())}
        started = time.perf_counter()
        result["bake"] = operator(bpy.ops.wetcloth.bake)
        result["bake"]["seconds"] = time.perf_counter() - started
        towel = bpy.data.objects["Towel"]
        result["bake"] |= cache_report(towel)
        result["bake"]["frames"] = [evaluated_cloth(towel, f) for f in frames]
        result["rebake"] = operator(bpy.ops.wetcloth.bake)  # in the same session: over its own open cache
        result["rebake"]["frames"] = [evaluated_cloth(towel, f) for f in (frames[0], frames[-1])]
        bpy.ops.wm.save_mainfile()
        bpy.ops.wm.open_mainfile(filepath=blend)
        towel = bpy.data.objects["Towel"]
        result["reopened"] = {"frames": [evaluated_cloth(towel, f) for f in frames],
                              "missing": bpy.app.driver_namespace.get("wetcloth_missing_caches")}
        result["cancelled"] = operator(bpy.ops.wetcloth.bake, cancel_after=spec["cancel_after"])
        result["cancelled"] |= cache_report(towel)
        result["cancelled"]["frames"] = [evaluated_cloth(towel, f) for f in (spec["cancel_after"], frames[-1])]
        bpy.ops.wm.save_mainfile()
        cache = os.path.dirname(cache_report(towel)["path"])
        shutil.move(cache, cache + "_moved")
        stderr = io.StringIO()
        with contextlib.redirect_stderr(stderr):
            bpy.ops.wm.open_mainfile(filepath=blend)
        result["moved"] = {"missing": bpy.app.driver_namespace.get("wetcloth_missing_caches"),
                           "stderr": stderr.getvalue(), "panel": drawn_panels(bpy.data.objects["Towel"])}
        shutil.move(cache + "_moved", cache)
        bpy.ops.wm.open_mainfile(filepath=blend)
        result["restored"] = {"panel": drawn_panels(bpy.data.objects["Towel"])}
        result["freed"] = operator(bpy.ops.wetcloth.free_bake)
        result["freed"] |= {"modifiers": [m.type for m in bpy.data.objects["Towel"].modifiers],
                            "left": sorted(os.listdir(os.path.dirname(cache))) if os.path.isdir(os.path.dirname(cache)) else None}
        result["rising"] = rising_water(spec, blend, frames)
        result["moving"] = moving_ball(spec, blend, frames)
        result["pinned"] = pinned_with_modifiers(blend)
        result["grip"] = keyed_grip(spec, blend, frames)
        result["range"] = another_range(spec, blend)
        result["refusals"] = refusals(spec)
        result["mesh"] = mesh_cloth_over_a_cup(spec)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
