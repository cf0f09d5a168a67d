"""Runs inside Blender's Python (bpy from PyPI): imports exported frames and reports what Blender sees.

    .venv-blender/bin/python tests/blender/probe.py SPEC.json RESULT.json

SPEC: {"sequences": {name: directory}, "frames": [frame numbers to look at], "work": directory,
       "render": [names of sequences to render], "startup": [names to load into the startup scene]}.
For every sequence it reports, as JSON (the assertions are in tests/test_blender.py):
  "import": PLY frames through bpy.ops.wm.ply_import (vertex/face counts, attributes, positions, wetness);
  "loader": the scene after running the sequence's load_in_blender.py as Blender's --python would
            (timeline, modifiers, material, and at each frame the evaluated positions and wetness);
  "reopened": the same frames after saving the .blend and opening it again, with no script run;
  "render": (if asked) Cycles renders of the reopened scene at the first and last looked-at frame;
  "startup": (if asked) the scene's objects after the loader ran in Blender's startup scene (cube,
             camera, light), once as a new file and once saved as a .blend first.
"""

import json
import os
import runpy
import sys
import traceback

import bpy
import numpy as np


def attributes(mesh):
    return {a.name: [a.domain, a.data_type] for a in mesh.attributes if not a.name.startswith(".")}


def float_attribute(mesh, name):
    if name not in mesh.attributes:
        return None
    values = np.empty(len(mesh.vertices), dtype=np.float32)
    mesh.attributes[name].data.foreach_get("value", values)
    return values.tolist()


def positions(mesh):
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3).tolist()


def describe_mesh(mesh):
    return {
        "vertices": len(mesh.vertices),
        "faces": len(mesh.polygons),
        "attributes": attributes(mesh),
        "uv_maps": [layer.name for layer in mesh.uv_layers],
        "positions": positions(mesh),
        "wetness": float_attribute(mesh, "wetness"),
    }


def import_ply_frames(directory, numbers):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    out = []
    for number in numbers:
        path = os.path.join(directory, f"cloth_{number:04d}.ply")
        before = set(bpy.data.objects)
        bpy.ops.wm.ply_import(filepath=path)
        new = [ob for ob in bpy.data.objects if ob not in before]
        out.append({"frame": number, "objects": len(new), **describe_mesh(new[0].data)})
    return out


def evaluated_frames(ob, numbers):
    scene = bpy.context.scene
    out = []
    for number in numbers:
        scene.frame_set(number)
        evaluated = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
        mesh = evaluated.to_mesh()
        out.append({"frame": number, **describe_mesh(mesh)})
        evaluated.to_mesh_clear()
    return out


def material_uses_wetness(ob):
    """True if a material of ``ob`` feeds an Attribute node named 'wetness' into its Principled BSDF."""
    for slot in ob.material_slots:
        tree = slot.material.node_tree if slot.material else None
        if tree is None:
            continue
        for node in tree.nodes:
            if node.type == "ATTRIBUTE" and node.attribute_name == "wetness" and any(
                    link.from_node == node for link in tree.links):
                return True
    return False


def scene_summary(ob, numbers):
    scene = bpy.context.scene
    return {
        "object": ob.name,
        "fps": scene.render.fps / scene.render.fps_base,
        "frame_start": scene.frame_start,
        "frame_end": scene.frame_end,
        "modifiers": [m.type for m in ob.modifiers],
        "materials": [slot.material.name for slot in ob.material_slots if slot.material],
        "material_uses_wetness": material_uses_wetness(ob),
        "frames": evaluated_frames(ob, numbers),
    }


def render_frames(numbers, work, name):
    """Cycles renders (CPU, 1 sample, 48 x 48) of the loaded scene at two frames, seen from the side.

    Returns the largest pixel difference between them and the share of pixels the cloth covers in
    each (pixels that differ from the top-left corner, which is background).
    """
    scene = bpy.context.scene
    camera = bpy.data.objects.new("probe camera", bpy.data.cameras.new("probe camera"))
    scene.collection.objects.link(camera)
    camera.location = (1.2, 0.0, 0.3)
    camera.rotation_euler = (1.45, 0.0, 1.5708)  # looking along -x, slightly down at the water plane
    scene.camera = camera
    sun = bpy.data.objects.new("probe sun", bpy.data.lights.new("probe sun", "SUN"))
    scene.collection.objects.link(sun)
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.cycles.device = "CPU"
    scene.render.resolution_x = scene.render.resolution_y = 48
    pixels = []
    for number in numbers:
        scene.frame_set(number)
        scene.render.filepath = os.path.join(work, f"{name}_{number}.png")
        bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(scene.render.filepath)
        pixels.append(np.array(image.pixels[:], dtype=np.float32).reshape(-1, 4)[:, :3])
    covered = [float((np.abs(p - p[-1]).max(axis=1) > 0.01).mean()) for p in pixels]
    return {"frames": numbers, "max_difference": float(np.abs(pixels[0] - pixels[1]).max()), "covered": covered}


def cloth_object():
    meshes = [ob for ob in bpy.context.scene.objects if ob.type == "MESH"]
    if len(meshes) != 1:
        raise RuntimeError(f"expected one mesh object, found {[ob.name for ob in meshes]}")
    return meshes[0]


def startup_objects(loader, work, name):
    """Object names after running the loader in the startup scene: a new file, then a saved one."""
    out = {}
    for case in ("new_file", "saved_file"):
        bpy.ops.wm.read_factory_settings()
        if case == "saved_file":
            bpy.ops.wm.save_as_mainfile(filepath=os.path.join(work, f"{name}_startup.blend"))
        runpy.run_path(loader, run_name="__main__")
        out[case] = sorted(ob.name for ob in bpy.context.scene.objects)
    return out


def probe(name, directory, numbers, work, render=False, startup=False):
    result = {}
    if os.path.exists(os.path.join(directory, "cloth_0001.ply")):
        result["import"] = import_ply_frames(directory, numbers[:2])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    runpy.run_path(os.path.join(directory, "load_in_blender.py"), run_name="__main__")
    result["loader"] = scene_summary(cloth_object(), numbers)
    blend = os.path.join(work, f"{name}.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.open_mainfile(filepath=blend)
    result["reopened"] = scene_summary(cloth_object(), numbers)
    if render:
        result["render"] = render_frames([numbers[0], numbers[-1]], work, name)
    if startup:
        result["startup"] = startup_objects(os.path.join(directory, "load_in_blender.py"), work, name)
    return result


def main(spec_path, result_path):
    with open(spec_path) as fh:
        spec = json.load(fh)
    results = {"blender": bpy.app.version_string, "sequences": {}}
    for name, directory in spec["sequences"].items():
        try:
            results["sequences"][name] = probe(name, directory, spec["frames"], spec["work"],
                                               render=name in spec.get("render", []),
                                               startup=name in spec.get("startup", []))
        except Exception:
            results["sequences"][name] = {"error": traceback.format_exc()}
    with open(result_path, "w") as fh:
        json.dump(results, fh)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
