"""Two layers of one cloth on a slope, shared by the layer friction tests and bench/layer_friction.py: a 0.1 m
sheet lying on a 0.3 m sheet, one mesh whose UVs lay the two side by side (so that self-collision takes the stack,
docs/model.md section 2.4), the large sheet held by pins or by a plane under it."""

from __future__ import annotations

import math

import numpy as np

import wetcloth
from wetcloth.mesh_file import make_mesh
from wetcloth.scene import from_dict
from wetcloth.topology import grid_cells

THICKNESS = 0.002  # m
HEIGHT = 0.3  # m, the large sheet's centre
PLANE_FRICTION = 5.0  # the plane's, far above any slope's tangent used here


def sheet(side: int, size: float, corner: tuple[float, float], z: float) -> tuple[np.ndarray, np.ndarray]:
    """A side x side grid of points (n, 3) over size x size m from ``corner`` at height z, and its quads (k, 4)."""
    x, y = np.meshgrid(corner[0] + np.linspace(0.0, size, side), corner[1] + np.linspace(0.0, size, side))
    return np.stack([x.ravel(), y.ravel(), np.full(x.size, z)], axis=1), grid_cells(side, side)


def stack_scene(angle: float, self_friction: float, held_by: str,
                **settings) -> tuple[wetcloth.Scene, int, np.ndarray]:
    """The two sheets (2 cm spacing; the small one a thickness plus 1 um above the large one, uphill and off its
    grid lines) tilted by ``angle`` deg about x, the large one held ``held_by`` "pins" (every vertex) or "plane"
    (of friction PLANE_FRICTION, its vertices 1 um above their contact distance); no air, water or floor near.
    Returns the scene, the large sheet's vertex count (its vertices come first) and the downhill direction."""
    large, large_quads = sheet(16, 0.3, (-0.15, -0.15), 0.0)
    small, small_quads = sheet(6, 0.1, (-0.043, 0.0237), THICKNESS + 1e-6)
    t = math.radians(angle)
    turn = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(t), -math.sin(t)], [0.0, math.sin(t), math.cos(t)]])
    points = np.vstack([large, small]) @ turn.T + [0.0, 0.0, HEIGHT]
    mesh = make_mesh(points, [np.vstack([large_quads, small_quads + len(large)])],
                     {"pin": np.r_[np.ones(len(large)), np.zeros(len(small))]},
                     np.vstack([large[:, :2], small[:, :2] + [0.5, 0.0]]))  # UVs: side by side
    values = dict(cloth_mesh=mesh, thickness=THICKNESS, water_level=-5.0, floor_level=-4.0, air_density=0.0,
                  self_friction=self_friction, **settings)
    normal = turn @ [0.0, 0.0, 1.0]
    if held_by == "pins":
        values["pinned_vertices"] = "pin"
    else:
        point = np.array([0.0, 0.0, HEIGHT]) - (0.5 * THICKNESS + 1e-6) * normal
        values |= dict(collider1_shape="plane", collider1_x=point[0], collider1_y=point[1], collider1_z=point[2],
                       collider1_normal_x=normal[0], collider1_normal_y=normal[1], collider1_normal_z=normal[2],
                       collider1_friction=PLANE_FRICTION)
    return from_dict(values), len(large), np.array([0.0, -math.cos(t), -math.sin(t)])
