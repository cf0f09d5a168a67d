"""USD's Python module (``pxr``) in Blender: the Blender application has it on its path; bpy as a
Python module (PyPI's bpy) ships it in its own Python folder, which is not on ``sys.path``."""

from __future__ import annotations

import glob
import os
import sys


def make_usd_importable() -> None:
    """Put Blender's bundled ``pxr`` on ``sys.path`` if it is not importable yet; ImportError if Blender has none."""
    try:
        import pxr  # noqa: F401
        return
    except ImportError:
        pass
    import bpy

    pattern = os.path.join(bpy.utils.resource_path("LOCAL"), "python", "lib", "python3*", "site-packages")
    for folder in sorted(glob.glob(pattern)):
        if os.path.isdir(os.path.join(folder, "pxr")):
            sys.path.append(folder)
            import pxr  # noqa: F401
            return
    raise ImportError(f"Wet Cloth needs Blender's USD module (pxr), which is not in {pattern}")
