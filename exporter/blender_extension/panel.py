"""The "Wet Cloth" panel in Physics properties: the object's role and its settings, the scene's
settings (every scene parameter under its own name), Bake and Free Bake, and missing caches."""

from __future__ import annotations

import os

import bpy

from wetcloth.exporter.blender_extension import caches
from wetcloth.exporter.blender_extension.parameters import FABRIC, SCENE


class WETCLOTH_PT_physics(bpy.types.Panel):
    bl_label = "Wet Cloth"
    bl_idname = "WETCLOTH_PT_physics"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "physics"

    @classmethod
    def poll(cls, context):
        return context.object is not None

    def draw(self, context):
        layout = self.layout
        obj, scene = context.object, context.scene
        settings = obj.wetcloth
        layout.prop(settings, "role")
        if settings.role == "CLOTH":
            layout.prop(settings, "preset")
            column = layout.column(align=True)
            for name in FABRIC:
                column.prop(settings, name)
            layout.prop_search(settings, "pin_group", obj, "vertex_groups")
            path = caches.cache_path(obj)
            if path is not None:
                if os.path.isfile(path):
                    layout.label(text=f"Cache: {bpy.path.relpath(path) if bpy.data.filepath else path}", icon="FILE")
                else:
                    layout.label(text=f"Cache missing: {path}", icon="ERROR")
        elif settings.role == "COLLIDER":
            layout.prop(settings, "friction")
        elif settings.role == "WATER":
            layout.label(text="water_level: this plane's height (keys on it: a rising or falling level)")
        row = layout.row(align=True)
        row.operator("wetcloth.bake", icon="PHYSICS")
        row.operator("wetcloth.free_bake", icon="TRASH")
        for name, path in caches.missing_caches():
            layout.label(text=f"{name}: cache missing ({path})", icon="ERROR")


class WETCLOTH_PT_scene(bpy.types.Panel):
    bl_label = "Scene"
    bl_idname = "WETCLOTH_PT_scene"
    bl_parent_id = "WETCLOTH_PT_physics"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "physics"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        settings = context.scene.wetcloth
        column = self.layout.column(align=True)
        column.prop(settings, "cache_directory")
        for name in SCENE:
            column.prop(settings, name)


CLASSES = (WETCLOTH_PT_physics, WETCLOTH_PT_scene)

register, unregister = bpy.utils.register_classes_factory(CLASSES)
