"""Runs inside Blender's Python (bpy from PyPI): imports exported frames and reports what Blender sees.

    .venv-blender/bin/python tests/blender/probe.py SPEC.json RESULT.json

SPEC: {"work": directory, "jobs": {name: job}}; a job is
  {"directory": the sequence, "frames": [scene frames to look at],
   "options": keywords for the loader's load(...), or "argv": options for its command line (after "--"),
   "scene": {"fps": .., "frame_start": .., "frame_end": ..} to load into a saved .blend with these
            settings instead of a new file,
   "import": bool, "reopen": bool, "render": bool, "startup": bool, "subframe": bool}.
For every job it reports, as JSON (the assertions are in tests/test_blender.py):
  "import": (if asked) PLY frames through bpy.ops.wm.ply_import (counts, attributes, positions, wetness);
  "loader": the scene after running the sequence's load_in_blender.py (timeline, modifiers, material,
            the cloth's own faces and shading, and at each frame the evaluated mesh: positions,
            wetness, velocities, attributes);
  "subframe": (if asked) the evaluated positions halfway between the first two looked-at frames;
  "reopened": (if asked) the same frames after saving the .blend and opening it again, no script run;
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


def point_attribute(mesh, name, width):
    if name not in mesh.attributes:
        return None
    values = np.empty(len(mesh.vertices) * width, dtype=np.float32)
    mesh.attributes[name].data.foreach_get("value" if width == 1 else "vector", values)
    return values.reshape(-1, width).tolist() if width > 1 else values.tolist()


def positions(mesh):
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3).tolist()


def describe_mesh(mesh):
    return {
        "vertices": len(mesh.vertices),
        "faces": len(mesh.polygons),
        "corners": sorted({p.loop_total for p in mesh.polygons}),
        "smooth": sorted({p.use_smooth for p in mesh.polygons}),
        "attributes": attributes(mesh),
        "uv_maps": [layer.name for layer in mesh.uv_layers],
        "positions": positions(mesh),
        "wetness": point_attribute(mesh, "wetness", 1),
        "velocity": point_attribute(mesh, "velocity", 3),
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


def evaluated(ob, number, subframe=0.0):
    bpy.context.scene.frame_set(number, subframe=subframe)
    mesh_object = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    described = describe_mesh(mesh_object.to_mesh())
    mesh_object.to_mesh_clear()
    return {"frame": number + subframe, **described}


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


def describe_modifier(modifier):
    settings = {"SUBSURF": ("levels", "render_levels"), "SOLIDIFY": ("thickness", "offset")}.get(modifier.type, ())
    return {"type": modifier.type, **{name: getattr(modifier, name) for name in settings}}


def scene_summary(ob, numbers):
    scene = bpy.context.scene
    return {
        "object": ob.name,
        "fps": scene.render.fps / scene.render.fps_base,
        "frame_start": scene.frame_start,
        "frame_end": scene.frame_end,
        "modifiers": [describe_modifier(m) for m in ob.modifiers],
        "materials": [slot.material.name for slot in ob.material_slots if slot.material],
        "material_uses_wetness": material_uses_wetness(ob),
        "own_mesh": {key: value for key, value in describe_mesh(ob.data).items()
                     if key in ("vertices", "faces", "corners", "smooth")},
        "frames": [evaluated(ob, number) for number in numbers],
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


def run_loader(loader, options=None, argv=None):
    """The loader as ``blender --python load_in_blender.py [-- argv]`` runs it, or its load(**options)."""
    if options is not None:
        runpy.run_path(loader)["load"](**options)
        return
    saved_argv = sys.argv
    sys.argv = ["blender", "--python", loader] + (["--"] + argv if argv is not None else [])
    try:
        runpy.run_path(loader, run_name="__main__")
    finally:
        sys.argv = saved_argv


def startup_objects(loader, work, name, job):
    """Object names after running the loader in the startup scene: a new file, then a saved one."""
    out = {}
    for case in ("new_file", "saved_file"):
        bpy.ops.wm.read_factory_settings()
        if case == "saved_file":
            bpy.ops.wm.save_as_mainfile(filepath=os.path.join(work, f"{name}_startup.blend"))
        run_loader(loader, job.get("options"), job.get("argv"))
        out[case] = sorted(ob.name for ob in bpy.context.scene.objects)
    return out


def probe(name, job, work):
    directory, numbers = job["directory"], job["frames"]
    loader = os.path.join(directory, "load_in_blender.py")
    result = {}
    if job.get("import"):
        result["import"] = import_ply_frames(directory, numbers[:2])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if "scene" in job:  # a saved file with its own frame rate and range
        scene = bpy.context.scene
        scene.render.fps, scene.frame_start, scene.frame_end = (job["scene"][key] for key in
                                                                ("fps", "frame_start", "frame_end"))
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(work, f"{name}_shot.blend"))
    run_loader(loader, job.get("options"), job.get("argv"))
    cloth = cloth_object()
    result["loader"] = scene_summary(cloth, numbers)
    if job.get("subframe"):
        result["subframe"] = evaluated(cloth, numbers[0], subframe=0.5)
    if job.get("reopen") or job.get("render"):
        blend = os.path.join(work, f"{name}.blend")
        bpy.ops.wm.save_as_mainfile(filepath=blend)
        bpy.ops.wm.read_factory_settings(use_empty=True)
        bpy.ops.wm.open_mainfile(filepath=blend)
        result["reopened"] = scene_summary(cloth_object(), numbers)
    if job.get("render"):
        result["render"] = render_frames([numbers[0], numbers[-1]], work, name)
    if job.get("startup"):
        result["startup"] = startup_objects(loader, work, name, job)
    return result


def main(spec_path, result_path):
    with open(spec_path) as fh:
        spec = json.load(fh)
    results = {"blender": bpy.app.version_string, "jobs": {}}
    for name, job in spec["jobs"].items():
        try:
            results["jobs"][name] = probe(name, job, spec["work"])
        except Exception:
            results["jobs"][name] = {"error": traceback.format_exc()}
    with open(result_path, "w") as fh:
        json.dump(results, fh)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
