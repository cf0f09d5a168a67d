"""Render docs/folded_towel.png: the saturated towel dropped edge-on into a pool, folded on the floor.

    .venv/bin/python docs/render_folded_towel.py [--out docs/folded_towel.png] [--samples 32]

Needs the Blender environment (``make .venv-blender/.installed``: bpy 5.0.1, Python 3.11).

1. Simulates the edge-on drop of ``tests/test_self_collision.py`` (a saturated 15 x 21 towel tilted
   80 degrees, its lower edge in a 0.6 m pool) for 6 s and exports it as USD at 2 fps, the same as
   ``wetcloth run towel --duration 6 --fps 2 --set nx=15 --set ny=21 --set initial_tilt=80 --set
   initial_saturation=1 --set floor_level=-0.6 --set initial_height=-0.2 --export DIR --format usd``.
   By 4 s it lies folded on the floor, its layers resting a thickness apart (self-collision on).
2. Runs itself again in Blender's Python: the sequence's ``load_in_blender.py`` with its defaults
   (Subdivision, Solidify, smooth shading, the wetness material), a camera, a sun and the tank
   floor; Cycles on the CPU, 480 x 270 pixels, denoised; the last frame (t = 6 s).
"""

from __future__ import annotations

import sys
from pathlib import Path

import blender_stages
from blender_stages import ROOT
FPS = 2.0
DURATION = 6.0  # s
SCENE = dict(nx=15, ny=21, initial_tilt=80.0, initial_saturation=1.0, floor_level=-0.6, initial_height=-0.2)
WIDTH, HEIGHT = 480, 270


def export(directory: Path) -> None:
    """The edge-on drop as a USD sequence (runs in the project's Python)."""
    import wetcloth
    from wetcloth.exporter import open_sequence
    from wetcloth.runner import run

    scene = wetcloth.load_scene("towel", **SCENE)
    with open_sequence(directory, fmt="usd", fps=FPS, scene=scene) as sequence:
        run(scene, DURATION, FPS, on_frame=sequence.on_frame, progress=False)


def render(directory: Path, out: Path, samples: int) -> None:
    """The last frame, rendered into ``out`` (runs in Blender's Python)."""
    import runpy

    import bpy
    from mathutils import Vector

    bpy.ops.wm.read_factory_settings(use_empty=True)
    runpy.run_path(str(directory / "load_in_blender.py"))["load"]()  # the defaults an artist gets
    scene = bpy.context.scene
    cloth = next(o for o in scene.objects if o.type == "MESH")
    scene.frame_set(scene.frame_end)
    bpy.context.view_layer.update()
    corners = [cloth.matrix_world @ Vector(c) for c in cloth.bound_box]
    centre = sum(corners, Vector()) / 8.0

    blender_stages.set_stage(scene, camera=centre + Vector((0.75, -0.65, 0.55)), target=centre, lens=40.0,
                             sun=(0.6, 0.2, 0.9), sky=(0.25, 0.28, 0.32, 1.0), ground="floor",
                             ground_z=SCENE["floor_level"], ground_color=(0.05, 0.12, 0.16, 1.0), ground_roughness=0.4,
                             samples=samples, size=(WIDTH, HEIGHT))
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.compression = 100
    scene.render.filepath = str(out)
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    sys.exit(blender_stages.main(__file__, __doc__.splitlines()[0], ROOT / "docs" / "folded_towel.png", export, render))
