"""The Blender extension "Wet Cloth": bake a wetcloth simulation in the scene (docs/blender.md section 8).

Objects get a role (``obj.wetcloth.role``: a cloth, a collider, the water surface); the cloth a
fabric preset; ``scene.wetcloth`` holds the settings of the whole scene, one property per scene
parameter under its own name.  ``bpy.ops.wetcloth.bake()`` simulates every cloth over the scene's
frame range at its fps into one USD file per cloth, played by a Mesh Sequence Cache modifier;
``bpy.ops.wetcloth.free_bake()`` removes it.

Modules: ``fabrics`` and ``geometry`` (no bpy: presets, and reading a grid, colliders and pins from
vertices), ``baking`` (no bpy: the simulation loop that writes the cache), ``frame_loop`` (no bpy:
one frame and one timer tick of the bake, Esc and the progress), ``blender_scene`` (the
Blender scene as a wetcloth Scene), ``properties``, ``operators``, ``caches`` (the modifier, the
wet material, the check for missing caches when a file loads) and ``panel``.  Blender imports
only ``register`` and ``unregister``; ``build`` makes the extension's zip.
"""

from __future__ import annotations

import importlib

#: The modules that register something, in order.
_MODULES = ("properties", "operators", "caches", "panel")


def _modules():
    return [importlib.import_module(f"{__name__}.{name}") for name in _MODULES]


def register() -> None:
    from wetcloth.exporter.blender_extension.usd_path import make_usd_importable

    make_usd_importable()
    for module in _modules():
        module.register()


def unregister() -> None:
    for module in reversed(_modules()):
        module.unregister()
