"""The extension's properties: ``obj.wetcloth`` (role, fabric preset, the fabric's parameters, pins,
a collider's friction) and ``scene.wetcloth`` (every other scene parameter, the cache folder).

Scene parameters are generated from ``wetcloth.scene.Scene``'s field metadata: each is a property
under the parameter's own name, with its unit and meaning as the tooltip and its range as limits.
Those the objects give are not properties: the cloth (a grid's size, height and tilt, or a mesh) comes
from the Cloth object, its pins from its pin group, the colliders from Collider objects.
"""

from __future__ import annotations

import bpy
from bpy.props import EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

from wetcloth.exporter.blender_extension.fabrics import FABRICS, fabric_parameters
from wetcloth.exporter.blender_extension.parameters import FABRIC, SCENE
from wetcloth.scene import COLLIDER_FIELDS, PARAMETERS

ROLES = [("NONE", "None", "Not part of the wet cloth simulation"),
         ("CLOTH", "Cloth", "Any mesh of triangles, quads and n-gons, each edge in at most two faces: the cloth"),
         ("COLLIDER", "Collider", "Any mesh the cloth collides with: closed (a solid) or open (a shell, such as "
                                  "a cup)"),
         ("WATER", "Water surface", "A horizontal plane: its height is water_level (keys on it: a rising or "
                                    "falling level)")]


#: Decimal places the panel shows of a float setting.
PRECISION = 6


def parameter_property(name: str, field=None):
    """A Blender property for scene parameter ``name`` from its field's metadata (unit, meaning, range)."""
    f = field or PARAMETERS[name]
    md = f.metadata
    label = name.replace("_", " ").capitalize()
    description = md["doc"] + ("" if md["unit"] == "-" else f" ({md['unit']})")
    if md["choices"]:
        return EnumProperty(name=label, description=description, default=f.default,
                            items=[(choice, choice, "") for choice in md["choices"]])
    if f.type == "str":
        return StringProperty(name=label, description=description, default=f.default)
    if f.type == "int":
        return IntProperty(name=label, description=description, default=f.default, min=int(md["lo"]),
                           max=int(md["hi"]))
    return FloatProperty(name=label, description=description, default=f.default, min=lower_limit(md),
                         max=md["hi"], precision=PRECISION, step=1)


def lower_limit(metadata: dict) -> float:
    """The least value of a float setting: its parameter's lower bound, or for a bound its range excludes
    (0 < thickness) the least value the panel shows above it (one unit of the last digit, PRECISION)."""
    return metadata["lo"] + (10.0 ** -PRECISION if metadata["lo_open"] else 0.0)


def _apply_preset(self, context) -> None:
    for name, value in fabric_parameters(self.preset).items():
        setattr(self, name, value)


def _object_annotations() -> dict:
    annotations = {
        "role": EnumProperty(name="Role", items=ROLES, default="NONE",
                             description="What the object is in the wet cloth simulation"),
        "preset": EnumProperty(name="Fabric", description="Fabric preset: sets the fabric's parameters (their "
                                                          "sources: docs/blender.md section 8.3)",
                               items=[(key, f.label, f.description) for key, f in FABRICS.items()],
                               default="COTTON_TERRY_TOWEL", update=_apply_preset),
        "pin_group": StringProperty(name="Pin group", description="Vertex group of the vertices held fixed"),
        "friction": parameter_property("friction", COLLIDER_FIELDS["friction"]),
    }
    annotations.update({name: parameter_property(name) for name in FABRIC})
    return annotations


def _scene_annotations() -> dict:
    annotations = {name: parameter_property(name) for name in SCENE}
    annotations["cache_directory"] = StringProperty(
        name="Cache folder", subtype="DIR_PATH", default="//wetcloth_cache", options={"PATH_SUPPORTS_BLEND_RELATIVE"},
        description="Where the bake writes one USD file per cloth (// is the .blend file's folder)")
    return annotations


WetclothObjectSettings = type("WetclothObjectSettings", (bpy.types.PropertyGroup,),
                              {"__annotations__": _object_annotations(), "__doc__": "Wet Cloth: the object's role"})
WetclothSceneSettings = type("WetclothSceneSettings", (bpy.types.PropertyGroup,),
                             {"__annotations__": _scene_annotations(), "__doc__": "Wet Cloth: the scene's settings"})
CLASSES = (WetclothObjectSettings, WetclothSceneSettings)


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.wetcloth = PointerProperty(type=WetclothObjectSettings)
    bpy.types.Scene.wetcloth = PointerProperty(type=WetclothSceneSettings)


def unregister() -> None:
    del bpy.types.Scene.wetcloth
    del bpy.types.Object.wetcloth
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
