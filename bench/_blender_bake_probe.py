"""Inside bpy (run by bench/blender_bake.py): install the Wet Cloth extension, build the bench scene
and time ``bpy.ops.wetcloth.bake()`` ("repeats" times in the spec).  With "round" in the spec the cloth
is the tests' round mesh cloth (tests/blender/extension_probe.py), and the result holds its arrays.

    BLENDER_USER_RESOURCES=DIR .venv-blender/bin/python bench/_blender_bake_probe.py SPEC.json RESULT.json
"""

import json
import os
import sys
import time
from pathlib import Path

import bpy

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "blender"))
from extension_probe import arrays, round_cloth, subdivided_plane  # noqa: E402


def build_scene(spec):
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = spec["fps"], 1.0
    scene.frame_start, scene.frame_end = 1, spec["frames"]
    if "round" in spec:
        cloth = round_cloth(spec["round"], "Towel")
    else:
        cloth = subdivided_plane(spec["size"], spec["height"], spec["cuts"], "Towel")
    bpy.ops.mesh.primitive_uv_sphere_add(radius=spec["radius"], location=(0.0, 0.0, 0.0))
    bpy.context.object.wetcloth.role = "COLLIDER"
    bpy.ops.mesh.primitive_plane_add(size=3.0, location=(0.0, 0.0, spec["water"]))
    bpy.context.object.wetcloth.role = "WATER"
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(spec["work"], "bench.blend"))
    return cloth


def main(spec_path, result_path):
    spec = json.load(open(spec_path))
    bpy.ops.extensions.package_install_files(filepath=spec["zip"], repo="user_default", enable_on_install=True)
    cloth = build_scene(spec)
    seconds = []
    for _ in range(spec["repeats"]):
        started = time.perf_counter()
        bpy.ops.wetcloth.bake()
        seconds.append(time.perf_counter() - started)
    path = bpy.path.abspath(cloth.modifiers["Wet Cloth cache"].cache_file.filepath)
    json.dump({"seconds": seconds, "manifest": os.path.join(os.path.dirname(path), "frames.json"),
               "blender": bpy.app.version_string, "cloth": arrays(cloth) if "round" in spec else None},
              open(result_path, "w"))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
