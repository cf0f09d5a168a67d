"""Runs in bpy (PyPI's bpy, background): installs the Wet Cloth extension and tries the scenes whose reading
tests/test_blender_extension_scene.py checks (how a Blender scene becomes a wetcloth scene).

    BLENDER_USER_RESOURCES=DIR .venv-blender/bin/python tests/blender/scene_probe.py SPEC.json RESULT.json

SPEC: {"zip": the extension, "work": a folder}.  RESULT: "install" (the operator's result) and, each a
bake's result and error:
  "hole": a subdivided plane with one face deleted: frames.json's scene, the faces played and the object's own;
  "no_faces": the same plane with every face deleted (a wire grid);
  "unit_scale": one scene (a tilted towel over a keyed ball in keyed water) built in metres and in a scene of
                Unit Scale 0.01 (everything 100 times larger in Blender units): frames.json's scene, the towel
                played at every frame;
  "animated": the towel keyed to slide along x, then parented to a keyed Empty, then keyed in place
              (keys that do not move it);
  "limits": for each setting in LIMITS, its panel limits (hard_min, soft_min) and a bake with it at hard_min;
  "unnamed": two cloths, 'Bib' with areal_density 0, then 'Bib' below the floor, then a ball 'Bib' passes
             through;
  "folded": the towel folded in half in the object, self-collision on, with its UV map (and the gaps of its
            layers at the last frame) and without.
"""

import json
import os
import sys

import bpy  # first: bpy makes bmesh importable
import bmesh  # noqa: E402
import numpy as np

from extension_probe import operator, reported, subdivided_plane

#: Frames of the bakes compared across Unit Scales.
FRAMES = 6
#: Float settings whose parameter's range excludes its lower bound: (cloth or scene, name).
LIMITS = (("cloth", "areal_density"), ("cloth", "thickness"), ("cloth", "stretch_stiffness"),
          ("scene", "water_density"))


def fresh(spec, name: str):
    """An empty scene of 3 frames at 24 fps, saved as WORK/name.blend, with a 0.6 m towel (cut 5 times) at 0.3 m."""
    bpy.ops.wm.read_homefile(use_empty=True)  # keeps the preferences (the add-on)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 24, 1.0
    scene.frame_start, scene.frame_end = 1, 3
    scene.wetcloth.self_collision = "off"
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(spec["work"], f"{name}.blend"))
    return scene, subdivided_plane(0.6, 0.3, 5, "Towel")


def delete(obj, context: str, faces=None):
    """Delete ``faces`` (indices; all if None) of the object's mesh, as Delete > Only Faces does (``context``)."""
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bm.faces.ensure_lookup_table()
    bmesh.ops.delete(bm, geom=bm.faces[:] if faces is None else [bm.faces[k] for k in faces], context=context)
    bm.to_mesh(obj.data)
    bm.free()


def manifest(spec):
    with open(os.path.join(spec["work"], "wetcloth_cache", "Towel", "frames.json")) as fh:
        return json.load(fh)


def hole(spec):
    scene, towel = fresh(spec, "hole")
    delete(towel, "FACES_ONLY", [12])
    out = operator(bpy.ops.wetcloth.bake)
    scene.frame_set(2)
    evaluated = towel.evaluated_get(bpy.context.evaluated_depsgraph_get())
    return out | {"scene": manifest(spec)["scene"], "played_faces": len(evaluated.data.polygons),
                  "own_faces": len(towel.data.polygons)}


def no_faces(spec):
    fresh(spec, "no_faces")
    delete(bpy.data.objects["Towel"], "FACES_ONLY")
    return operator(bpy.ops.wetcloth.bake)


def folded(spec):
    """The towel folded in half over x = 0 (its half at x > 0 laid back 4 mm above the other, as a modeller
    would leave it; its UV map, from the plane, stays the unfolded one), 5 mm above a dry floor, self-collision
    on: baked for 8 frames, with the gaps of the fold's two layers (the vertices over each other at the start)
    played at the last frame; then the same towel without its UV map."""
    scene, towel = fresh(spec, "folded")
    scene.wetcloth.self_collision = "on"
    scene.frame_end = 8  # a third of a second: it lands on the floor 5 mm below at about 0.03 s
    scene.wetcloth.water_level = scene.wetcloth.floor_level  # a dry floor
    towel.location.z = scene.wetcloth.floor_level + 0.005
    for v in towel.data.vertices:
        if v.co.x > 1e-6:
            v.co.x, v.co.z = -v.co.x, v.co.z + 0.004
    start = np.array([v.co[:] for v in towel.data.vertices])
    upper = np.flatnonzero(start[:, 2] > 0.002)
    lower = [int(np.argmin(np.linalg.norm(start - start[k] + [0.0, 0.0, 0.004], axis=1))) for k in upper]
    out = {"with_uv": operator(bpy.ops.wetcloth.bake)}
    end = np.array(played(towel, scene.frame_end))
    out["with_uv"]["gaps"] = (end[upper, 2] - end[lower, 2]).tolist()
    out["with_uv"]["thickness"] = manifest(spec)["scene"]["thickness"]
    while towel.data.uv_layers:
        towel.data.uv_layers.remove(towel.data.uv_layers[0])
    out["without_uv"] = operator(bpy.ops.wetcloth.bake)
    return out


def played(obj, frame):
    """The object's evaluated vertices at ``frame`` in world space (Blender units)."""
    bpy.context.scene.frame_set(frame)
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    matrix = np.array(obj.matrix_world)
    return [(matrix[:3, :3] @ np.array(v.co) + matrix[:3, 3]).tolist() for v in evaluated.data.vertices]


def in_units(spec, unit: float):
    """A towel of 0.6 m cut 5 times at 0.3 m over a ball of 0.15 m keyed to rise 0.05 m, in water at 0.06 m keyed
    to rise 0.1 m, built in Blender units of ``unit`` m (Unit Scale): frames.json's scene and the towel played."""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 24, 1.0
    scene.frame_start, scene.frame_end = 1, FRAMES
    scene.wetcloth.self_collision = "off"
    scene.unit_settings.system, scene.unit_settings.scale_length = "METRIC", unit
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(spec["work"], "units.blend"))
    towel = subdivided_plane(0.6 / unit, 0.3 / unit, 5, "Towel")
    towel.rotation_euler.x = 0.2  # tilted: its matrix turns and moves
    for name, size, z, rise, role in (("Ball", 0.15, 0.0, 0.05, "COLLIDER"), ("Pool", 3.0, 0.06, 0.1, "WATER")):
        if role == "COLLIDER":
            bpy.ops.mesh.primitive_uv_sphere_add(radius=size / unit, location=(0.0, 0.0, z / unit))
        else:
            bpy.ops.mesh.primitive_plane_add(size=size / unit, location=(0.0, 0.0, z / unit))
        obj = bpy.context.object
        obj.name, obj.wetcloth.role = name, role
        obj.keyframe_insert("location", index=2, frame=1)
        obj.location.z += rise / unit
        obj.keyframe_insert("location", index=2, frame=FRAMES)
    out = operator(bpy.ops.wetcloth.bake)
    return out | {"scene": manifest(spec)["scene"], "played": [played(towel, f) for f in range(1, FRAMES + 1)]}


def unit_scale(spec):
    return {"metres": in_units(spec, 1.0), "centimetres": in_units(spec, 0.01)}


def animated(spec):
    out = {}
    _, towel = fresh(spec, "animated")
    towel.keyframe_insert("location", index=0, frame=1)
    towel.location.x = 1.0
    towel.keyframe_insert("location", index=0, frame=3)
    out["keyed"] = operator(bpy.ops.wetcloth.bake)
    _, towel = fresh(spec, "parented")
    empty = bpy.data.objects.new("Carrier", None)
    bpy.context.scene.collection.objects.link(empty)
    towel.parent = empty
    empty.keyframe_insert("location", index=2, frame=1)
    empty.location.z = 0.5
    empty.keyframe_insert("location", index=2, frame=3)
    out["parented"] = operator(bpy.ops.wetcloth.bake)
    _, towel = fresh(spec, "still")
    towel.keyframe_insert("location", frame=1)
    towel.keyframe_insert("location", frame=3)
    out["still"] = operator(bpy.ops.wetcloth.bake)
    return out


def limits(spec):
    out = {}
    for owner, name in LIMITS:
        scene, towel = fresh(spec, "limits")
        scene.frame_end = 1  # the scene read and its first frame only: max_step at its least takes long to step
        settings = towel.wetcloth if owner == "cloth" else scene.wetcloth
        prop = settings.bl_rna.properties[name]
        setattr(settings, name, prop.hard_min)
        out[name] = operator(bpy.ops.wetcloth.bake) | {"hard_min": prop.hard_min, "soft_min": prop.soft_min}
    return out


def unnamed(spec):
    out = {}
    fresh(spec, "unnamed")
    bib = subdivided_plane(0.6, 0.3, 3, "Bib")
    bib.location.x = 2.0
    bib.wetcloth["areal_density"] = 0.0  # as a file saved before the panel's limit held it (no clamping)
    out["fabric"] = operator(bpy.ops.wetcloth.bake)["error"]
    bib.wetcloth.areal_density = 0.45
    bib.location.z = -2.0
    out["floor"] = operator(bpy.ops.wetcloth.bake)["error"]
    bib.location.z = 0.3
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.2, location=(2.0, 0.0, 0.3))
    bpy.context.object.name = "Ball"
    bpy.context.object.wetcloth.role = "COLLIDER"
    out["overlap"] = operator(bpy.ops.wetcloth.bake)["error"]
    return out


def main(spec_path, result_path):
    with open(spec_path) as fh:
        spec = json.load(fh)
    result = {}
    with reported(result_path, result):
        result["install"] = operator(bpy.ops.extensions.package_install_files, filepath=spec["zip"],
                                     repo="user_default", enable_on_install=True)
        for case in (hole, no_faces, unit_scale, animated, limits, unnamed, folded):
            result[case.__name__] = case(spec)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
