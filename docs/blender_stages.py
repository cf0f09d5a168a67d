"""The two stages of a docs render script (``render_motion_blur.py``, ``render_folded_towel.py``).

In the project's Python the script simulates and exports a sequence into a temporary folder, then
runs itself again in Blender's Python (``.venv-blender``, bpy), which sets the stage (``set_stage``)
and renders the PNG.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
BLENDER_PYTHON = ROOT / ".venv-blender" / "bin" / "python"


def main(script: str, description: str, default_out: Path, export: Callable[[Path], None],
         render: Callable[[Path, Path, int], None], argv=None) -> int:
    """The command line of a render ``script`` (its ``__file__``): ``export(sequence folder)`` in this
    Python, then ``render(sequence folder, out PNG, samples)`` in Blender's."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--out", type=Path, default=default_out, help="PNG to write")
    parser.add_argument("--samples", type=int, default=32, help="Cycles samples per pixel (default 32)")
    parser.add_argument("--in-blender", type=Path, metavar="SEQUENCE", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.in_blender is not None:  # second stage, inside Blender's Python
        render(args.in_blender, args.out.resolve(), args.samples)
        return 0
    if not BLENDER_PYTHON.exists():
        print(f"{BLENDER_PYTHON} is missing: make .venv-blender/.installed", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        sequence = Path(tmp) / "towel"
        export(sequence)
        subprocess.run([str(BLENDER_PYTHON), script, "--in-blender", str(sequence), "--out", str(args.out.resolve()),
                        "--samples", str(args.samples)], check=True)
    print(f"wrote {args.out}")
    return 0


def set_stage(scene, *, camera: tuple, target: tuple, sun: tuple, sky: tuple, ground: str, ground_z: float,
              ground_color: tuple, ground_roughness: float, samples: int, size: tuple, lens: float = 50.0) -> None:
    """In Blender's Python, around the loaded cloth of ``scene`` (a ``bpy.types.Scene``): a camera at
    ``camera`` (m) looking at ``target`` (m) through a ``lens`` (mm); a sun of strength 4 turned by
    ``sun`` (Euler angles, rad); a plain ``sky`` colour (RGBA); a 6 x 6 m plane named ``ground`` at
    height ``ground_z`` (m) with a Principled material of ``ground_color`` (RGBA) and
    ``ground_roughness``; Cycles on the CPU, ``samples`` per pixel, denoised, ``size`` (width, height)
    pixels, the plain sRGB view (more contrast than AgX for a small still)."""
    import bpy
    from mathutils import Vector

    camera_object = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera_object)
    camera_object.data.lens = lens
    camera_object.location = camera
    camera_object.rotation_euler = (Vector(target) - camera_object.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera_object
    sun_object = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    scene.collection.objects.link(sun_object)
    sun_object.rotation_euler = sun
    sun_object.data.energy = 4.0
    world = bpy.data.worlds.new("sky")
    if bpy.app.version < (5, 0, 0):  # Blender 5 worlds and materials always use nodes
        world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = sky
    scene.world = world
    plane = bpy.data.meshes.new(ground)
    plane.from_pydata([(-3, -3, ground_z), (3, -3, ground_z), (3, 3, ground_z), (-3, 3, ground_z)], [], [(0, 1, 2, 3)])
    scene.collection.objects.link(bpy.data.objects.new(ground, plane))
    material = bpy.data.materials.new(ground)
    if bpy.app.version < (5, 0, 0):
        material.use_nodes = True
    bsdf = material.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = ground_color
    bsdf.inputs["Roughness"].default_value = ground_roughness
    plane.materials.append(material)

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = True
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.view_settings.view_transform = "Standard"
