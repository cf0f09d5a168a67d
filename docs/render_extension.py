"""Render docs/extension_bake.png: a towel baked by the Wet Cloth extension, draped over a ball in a pool.

    .venv/bin/python docs/render_extension.py [--out docs/extension_bake.png] [--samples 32]

Needs the Blender environment (``make .venv-blender/.installed``: bpy 5.0.1, Python 3.11).

1. Builds the extension (``wetcloth blender-extension``) into a temporary folder.
2. Runs itself again in Blender's Python, with a scratch Blender user folder: installs the zip as
   Preferences > Install from Disk does, builds the scene with the panel's roles (a 0.8 m plane
   subdivided into 25 x 25 as the Cloth, a cotton terry towel soaking up water ten times faster
   than the default (``absorption_rate`` 1.5 1/s), so that a few seconds show it, and wicking it as
   the preset does (its hem soaked and dark, the towel above dry); a 0.3 m UV
   sphere as a Collider; a plane at 0.12 m as the Water surface), saves it, bakes frames 1 to 240
   (10 s) at 24 fps with ``bpy.ops.wetcloth.bake()``, and renders frame 240 with Cycles (CPU,
   480 x 270, denoised) through a camera framed on the cloth, the water plane given a watery
   material.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import blender_stages
from blender_stages import BLENDER_PYTHON, ROOT

FRAMES, FPS = 240, 24
WIDTH, HEIGHT = 480, 270
WATER_Z, FLOOR_Z = 0.12, -0.3


def build_scene(work: Path):
    """The towel, ball and pool with their Wet Cloth roles, saved as WORK/towel.blend (runs in bpy)."""
    import bmesh
    import bpy

    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    scene.frame_start, scene.frame_end = 1, FRAMES
    bpy.ops.mesh.primitive_plane_add(size=0.8, location=(0.0, 0.0, 0.311))
    towel = bpy.context.object
    towel.name = "Towel"
    bm = bmesh.new()
    bm.from_mesh(towel.data)
    bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=23, use_grid_fill=True)
    bm.to_mesh(towel.data)
    bm.free()
    towel.wetcloth.role = "CLOTH"
    towel.wetcloth.preset = "COTTON_TERRY_TOWEL"
    towel.wetcloth.absorption_rate = 1.5
    solidify = towel.modifiers.new("Solidify", "SOLIDIFY")
    solidify.thickness, solidify.offset = 0.002, 0.0
    subdivision = towel.modifiers.new("Subdivision", "SUBSURF")
    subdivision.levels = subdivision.render_levels = 1
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.3, segments=64, ring_count=32, location=(0.0, 0.0, 0.0))
    ball = bpy.context.object
    ball.name = "Ball"
    ball.wetcloth.role = "COLLIDER"
    bpy.ops.object.shade_smooth()
    ball.data.materials.append(principled("ball", (0.55, 0.08, 0.05, 1.0), 0.35))
    bpy.ops.mesh.primitive_plane_add(size=6.0, location=(0.0, 0.0, WATER_Z))
    pool = bpy.context.object
    pool.name = "Pool"
    pool.wetcloth.role = "WATER"
    water = principled("water", (0.6, 0.8, 0.85, 1.0), 0.02)
    water.node_tree.nodes["Principled BSDF"].inputs["Transmission Weight"].default_value = 1.0
    water.node_tree.nodes["Principled BSDF"].inputs["IOR"].default_value = 1.33
    pool.data.materials.append(water)
    bpy.ops.wm.save_as_mainfile(filepath=str(work / "towel.blend"))
    return towel


def principled(name, color, roughness):
    import bpy

    material = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0, 0):
        material.use_nodes = True
    bsdf = material.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = color
    bsdf.inputs["Roughness"].default_value = roughness
    return material


def render(zip_path: Path, out: Path, samples: int) -> None:
    """Install, build, bake, frame and render (runs in Blender's Python)."""
    import bpy
    from mathutils import Vector

    bpy.ops.extensions.package_install_files(filepath=str(zip_path), repo="user_default", enable_on_install=True)
    towel = build_scene(zip_path.parent)
    bpy.ops.wetcloth.bake()
    scene = bpy.context.scene
    scene.frame_set(FRAMES)
    corners = [towel.matrix_world @ Vector(c) for c in towel.evaluated_get(bpy.context.evaluated_depsgraph_get()).bound_box]
    centre = sum(corners, Vector()) / 8.0
    blender_stages.set_stage(scene, camera=centre + Vector((0.95, -1.05, 0.42)), target=centre - Vector((0, 0, 0.1)),
                             lens=50.0, sun=(0.7, 0.15, 0.8), sky=(0.55, 0.62, 0.7, 1.0), ground="pool floor",
                             ground_z=FLOOR_Z, ground_color=(0.03, 0.1, 0.12, 1.0), ground_roughness=0.6,
                             samples=samples, size=(WIDTH, HEIGHT))
    bpy.data.lights["sun"].energy = 1.5  # the towel faces the sun: set_stage's 4 washes the white out
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.compression = 100
    scene.render.filepath = str(out)
    bpy.ops.render.render(write_still=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "extension_bake.png", help="PNG to write")
    parser.add_argument("--samples", type=int, default=32, help="Cycles samples per pixel (default 32)")
    parser.add_argument("--in-blender", type=Path, metavar="ZIP", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.in_blender is not None:
        render(args.in_blender, args.out.resolve(), args.samples)
        return 0
    if not BLENDER_PYTHON.exists():
        print(f"{BLENDER_PYTHON} is missing: make .venv-blender/.installed", file=sys.stderr)
        return 2
    from wetcloth.cli import main as cli_main

    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        cli_main(["blender-extension", "--out", str(work)])
        (work / "user").mkdir()
        subprocess.run([str(BLENDER_PYTHON), __file__, "--in-blender", str(next(work.glob("wetcloth-*.zip"))),
                        "--out", str(args.out.resolve()), "--samples", str(args.samples)], check=True,
                       env=os.environ | {"BLENDER_USER_RESOURCES": str(work / "user")})
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
