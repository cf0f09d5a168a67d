"""Runs inside Blender's Python (bpy from PyPI): the round trip of docs/blender.md section 9, a Blender mesh
with a pin vertex group out to wetcloth and its frames back onto the same object.

    .venv-blender/bin/python tests/blender/roundtrip_probe.py export SPEC.json RESULT.json
    .venv-blender/bin/python tests/blender/roundtrip_probe.py play SPEC.json RESULT.json

export: a subdivided plane 1 m above the origin, its top edge in the vertex group "pin"; the group as a
point attribute and the mesh as PLY (EXPORT_SNIPPET, the docs' code), the .blend saved.  play: the
saved .blend opened, the USD cache on the same object (PLAY_SNIPPET), the evaluated positions and UV
maps at the spec's frames reported (export reports the object's UV maps as exported).
"""

import json
import sys
import traceback

import bpy
import numpy as np

#: docs/blender.md section 9, step 1 (kept word for word there).
EXPORT_SNIPPET = '''
obj = bpy.context.active_object                     # the cloth, its pins in the vertex group "pin"
group = obj.vertex_groups["pin"]
weights = [next((g.weight for g in v.groups if g.group == group.index), 0.0) for v in obj.data.vertices]
obj.data.attributes.new("pinned", "FLOAT", "POINT")  # not the group's own name: Blender keeps those apart
obj.data.attributes["pinned"].data.foreach_set("value", weights)
bpy.ops.wm.ply_export(filepath=PLY, export_selected_objects=True, apply_modifiers=False, export_uv=False,
                      export_normals=False, export_colors="NONE", export_attributes=True,
                      export_triangulated_mesh=False, forward_axis="Y", up_axis="Z")
'''

#: docs/blender.md section 9, step 3.
PLAY_SNIPPET = '''
obj = bpy.data.objects["Cloth"]
bpy.ops.cachefile.open(filepath=USD)
modifier = obj.modifiers.new("wetcloth", "MESH_SEQUENCE_CACHE")
modifier.cache_file = bpy.data.cache_files[-1]
modifier.object_path = "/wetcloth/cloth"
modifier.read_data = {"VERT"}                       # positions only: the object keeps its UVs and materials
'''


def uv_maps(mesh) -> dict:
    """A mesh's UV maps: name -> the (u, v) of each face corner in Blender's order, as a flat list."""
    maps = {}
    for layer in mesh.uv_layers:
        values = np.empty(len(layer.data) * 2)
        layer.data.foreach_get("uv", values)
        maps[layer.name] = values.tolist()
    return maps


def evaluated(obj) -> tuple[list, dict]:
    """The object's evaluated (modifiers applied) vertex positions (n, 3) in its own coordinates, and UV maps."""
    owner = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = owner.to_mesh()
    out = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", out)
    result = out.reshape(-1, 3).tolist(), uv_maps(mesh)
    owner.to_mesh_clear()
    return result


def export(spec: dict) -> dict:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_plane_add(size=spec["size"], location=(0.0, 0.0, spec["height"]))
    obj = bpy.context.active_object
    obj.name = "Cloth"
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.subdivide(number_cuts=spec["cuts"])
    bpy.ops.object.mode_set(mode="OBJECT")
    group = obj.vertex_groups.new(name="pin")
    top = [v.index for v in obj.data.vertices if v.co.y > 0.5 * spec["size"] - 1e-6]
    group.add(top, 1.0, "REPLACE")
    exec(EXPORT_SNIPPET, {"bpy": bpy, "PLY": spec["ply"]})
    bpy.ops.wm.save_as_mainfile(filepath=spec["blend"])
    world = [list(obj.matrix_world @ v.co) for v in obj.data.vertices]
    return {"vertices": len(obj.data.vertices), "pinned": top, "world": world, "uv": uv_maps(obj.data)}


def play(spec: dict) -> dict:
    bpy.ops.wm.open_mainfile(filepath=spec["blend"])
    exec(PLAY_SNIPPET, {"bpy": bpy, "USD": spec["usd"]})
    obj = bpy.data.objects["Cloth"]
    frames, uv = {}, {}
    for frame in spec["frames"]:
        bpy.context.scene.frame_set(frame)
        frames[str(frame)], uv[str(frame)] = evaluated(obj)
    return {"frames": frames, "uv": uv}


def main() -> None:
    stage, spec_path, result_path = sys.argv[-3:]
    with open(spec_path) as f:
        spec = json.load(f)
    try:
        result = {"export": export, "play": play}[stage](spec)
    except Exception:
        result = {"error": traceback.format_exc()}
    with open(result_path, "w") as f:
        json.dump(result, f)


main()
