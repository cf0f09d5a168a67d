"""Where each scene parameter lives in Blender (no bpy): the Cloth object (its mesh), the cloth's
fabric settings (``obj.wetcloth``), or the scene's settings (``scene.wetcloth``)."""

from __future__ import annotations

from wetcloth.scene import PARAMETERS

#: Parameters the Cloth object (and its pin group) sets: a subdivided plane the grid's, any other mesh the
#: mesh's (geometry.cloth_of).
FROM_CLOTH = ("nx", "ny", "width", "length", "initial_height", "initial_tilt", "pinned_edge", "cloth_mesh",
              "place_mesh", "pinned_vertices")
#: Parameters of the fabric, set on each Cloth object (its preset fills all but initial_saturation).
FABRIC = ("areal_density", "thickness", "stretch_stiffness", "bend_stiffness", "bend_rigidity", "damping",
          "absorption_capacity", "absorption_rate", "initial_saturation")
#: The rest: settings of the whole scene (``water_level`` is the Water object's height if there is one).
SCENE = tuple(name for name in PARAMETERS if name not in FROM_CLOTH + FABRIC)
