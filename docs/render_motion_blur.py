"""Render docs/motion_blur.png: the towel falling onto the water, without and with motion blur.

    .venv/bin/python docs/render_motion_blur.py [--out docs/motion_blur.png] [--samples 32]

Needs the Blender environment (``make .venv-blender/.installed``: bpy 5.0.1, Python 3.11).

1. Simulates the towel dropped from 1.2 m, tilted 20 degrees, for 0.5 s and exports it as USD at
   24 fps, the same as ``wetcloth run towel --duration 0.5 --fps 24 --set initial_height=1.2
   --set initial_tilt=20 --export DIR --format usd``: quads, wetness and per-vertex velocities.
2. Runs itself again in Blender's Python: the sequence's ``load_in_blender.py`` with its defaults
   (Subdivision, Solidify, smooth shading, the wetness material), a camera, a sun and a water
   plane; Cycles on the CPU, 480 x 270 pixels, denoised; frame 10 (t = 0.375 s, the towel falling
   at 3.7 m/s) once without and once with motion blur (shutter: half a frame).  Cycles blurs the
   USD mesh along its ``velocity`` attribute, the exported velocities.
3. Puts the two renders side by side (left: no motion blur, right: motion blur) in one PNG.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import blender_stages
from blender_stages import ROOT
FPS = 24.0
FRAME = 10  # t = (FRAME - 1) / FPS = 0.375 s
WIDTH, HEIGHT = 480, 270


def export(directory: Path) -> None:
    """The falling towel as a USD sequence (runs in the project's Python)."""
    import wetcloth
    from wetcloth.exporter import open_sequence
    from wetcloth.runner import run

    scene = wetcloth.load_scene("towel", initial_height=1.2, initial_tilt=20.0)
    with open_sequence(directory, fmt="usd", fps=FPS, scene=scene) as sequence:
        run(scene, 0.5, FPS, on_frame=sequence.on_frame, progress=False)


def render(directory: Path, out: Path, samples: int) -> None:
    """Both stills, side by side in ``out`` (runs in Blender's Python)."""
    import runpy

    import bpy
    import numpy as np

    bpy.ops.wm.read_factory_settings(use_empty=True)
    runpy.run_path(str(directory / "load_in_blender.py"))["load"]()  # the defaults an artist gets
    scene = bpy.context.scene

    blender_stages.set_stage(scene, camera=(1.7, -0.5, 0.6), target=(0.0, 0.0, 0.38), sun=(0.7, 0.3, 0.8),
                             sky=(0.12, 0.16, 0.24, 1.0), ground="water", ground_z=0.0,
                             ground_color=(0.02, 0.09, 0.11, 1.0), ground_roughness=0.05, samples=samples,
                             size=(WIDTH, HEIGHT))
    scene.render.motion_blur_shutter = 0.5
    scene.frame_set(FRAME)
    pixels = []
    with tempfile.TemporaryDirectory() as tmp:
        for blur in (False, True):
            scene.render.use_motion_blur = blur
            scene.render.filepath = str(Path(tmp) / f"blur_{int(blur)}.png")
            bpy.ops.render.render(write_still=True)
            image = bpy.data.images.load(scene.render.filepath)
            pixels.append(np.array(image.pixels[:], dtype=np.float32).reshape(HEIGHT, WIDTH, 4))
    gap = np.ones((HEIGHT, 8, 4), dtype=np.float32)
    both = np.concatenate([pixels[0], gap, pixels[1]], axis=1)
    result = bpy.data.images.new("motion blur", width=both.shape[1], height=HEIGHT, alpha=True)
    result.pixels.foreach_set(both.ravel())
    result.filepath_raw = str(out)
    result.file_format = "PNG"
    result.save()


if __name__ == "__main__":
    sys.exit(blender_stages.main(__file__, __doc__.splitlines()[0], ROOT / "docs" / "motion_blur.png", export, render))
