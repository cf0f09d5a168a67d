"""The scene: every parameter of a simulation, its unit, range and meaning, validated in one place.

One vocabulary: the field names below are the names used in scene files (TOML),
in ``wetcloth run --set name=value``, in ``load_scene(path, name=value)``, as FMU
variables and as batch-study axes.  Units are SI.
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import math
import numbers
import re
import sys
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from wetcloth import _core
from wetcloth.errors import ConfigError, Mistakes, ParameterError, did_you_mean, not_a_number
from wetcloth.mesh_file import ALLOWED as MESH_ALLOWED
from wetcloth.mesh_file import LARGEST_SIZE, MeshFile, is_mesh, resolve
from wetcloth.run_settings import SETTINGS as RUN_SETTINGS
from wetcloth.run_settings import check_run_table

#: FMU causality of a scene parameter: changeable at every communication point,
#: or fixed at instantiation.
INPUT = "input"
PARAMETER = "parameter"


def _param(default, unit: str, doc: str, lo=None, hi=None, lo_open=False, choices=(), fmu=PARAMETER, text=None,
           mesh=False):
    """A scene field with its unit, documentation and allowed range in the field metadata; ``text``: a
    string field that takes free text, and what it allows (checked with the scene as a whole); ``mesh``:
    a mesh's path that also takes, from Python, the mesh as arrays (a wetcloth.mesh_file.MeshFile)."""
    return field(
        default=default,
        metadata=dict(unit=unit, doc=doc, lo=lo, hi=hi, lo_open=lo_open, choices=tuple(choices), fmu=fmu, text=text,
                      mesh=mesh),
    )


INTEGRATORS = ("explicit_euler", "symplectic_euler", "implicit_euler", "bdf2")
EDGES = ("none", "x_min", "x_max", "y_min", "y_max")
SWITCH = ("on", "off")
#: What ``pinned_vertices`` allows, as its messages say.
PINS_ALLOWED = ("'' (none), the name of a point attribute of the mesh file (nonzero = pinned), or "
                "'box:x0,y0,z0,x1,y1,z1' (m, x0 <= x1, y0 <= y1, z0 <= z1)")


#: m: the smallest width and length of the rectangle.  A fabric's envelope is 0.4 to 2 mm thick (the presets'
#: thickness): a smaller piece is no sheet for the slab buoyancy and the self-collision's layers a thickness
#: apart.  Even on the finest grid (1024 particles) its springs' rest lengths (1 µm) and particles' masses then
#: stay far from zero, where a size near 0 divides by zero and leaves the cloth motionless.
SMALLEST_SIZE = 1e-3

#: The most particles along a side of the grid (nx, ny).
MOST_ALONG = 1024

#: s: the least max_step, so that a step still advances time at the latest time a state may hold (MAX_TIME =
#: 1e9 s, the core's stepping.hpp), where doubles lie 1e9 * 2.2e-16 = 2.2e-7 s apart at most: below that
#: t + max_step == t and a step never ends (max_step = 1e-300 s did so from t ~ 1e-284 s on).
SMALLEST_MAX_STEP = 1e-6

#: How far (m) Collider.distance looks for a mesh collider's surface.
MESH_REACH = 0.05

#: Collider shapes, in the order of the core's shape codes (fmu_src/core/include/wetcloth/colliders.hpp).
COLLIDER_SHAPES = ("plane", "box", "sphere", "cylinder", "mesh")


@dataclass(frozen=True)
class Collider:
    """A rigid collider (docs/model.md section 6.3), one ``[[collider]]`` table of a scene file: an analytic
    shape or a triangle mesh from a file.  Its fields are addressed as ``collider<k>_<field>`` (k from 1,
    in file order) everywhere else."""

    shape: str = _param("sphere", "-", "plane (half-space), box (axis-aligned), sphere, cylinder (vertical axis) "
                        "or mesh (a triangle mesh from `file`)", choices=COLLIDER_SHAPES)
    file: str = _param(
        "", "-", "a mesh collider's file (any format cloth_mesh reads; m, z up), moved by x, y, z: a closed mesh is "
        "a solid, an open one a shell (a bucket's wall) kept off on both sides; relative to the scene file",
        text="a mesh file's path (for shape = 'mesh'), or '' (from Python also a surface as arrays: "
             "wetcloth.mesh_file.surface)", mesh=True)
    x: float = _param(0.0, "m", "x of the centre (plane: of a point on it; mesh: where its file's origin goes)",
                      -1e4, 1e4)
    y: float = _param(0.0, "m", "y of the centre (plane: of a point on it)", -1e4, 1e4)
    z: float = _param(0.0, "m", "z of the centre (plane: of a point on it)", -1e4, 1e4)
    radius: float = _param(0.1, "m", "radius of a sphere or cylinder", 0.0, 1e4, lo_open=True)
    height: float = _param(0.1, "m", "height of a cylinder (along z, centred on z)", 0.0, 1e4, lo_open=True)
    size_x: float = _param(0.1, "m", "edge of a box along x", 0.0, 1e4, lo_open=True)
    size_y: float = _param(0.1, "m", "edge of a box along y", 0.0, 1e4, lo_open=True)
    size_z: float = _param(0.1, "m", "edge of a box along z", 0.0, 1e4, lo_open=True)
    normal_x: float = _param(0.0, "-", "x of a plane's outward normal (the solid lies behind it)", -1.0, 1.0)
    normal_y: float = _param(0.0, "-", "y of a plane's outward normal", -1.0, 1.0)
    normal_z: float = _param(1.0, "-", "z of a plane's outward normal", -1.0, 1.0)
    friction: float = _param(0.5, "-", "Coulomb friction coefficient of the collider", 0.0, 10.0)

    def row(self) -> list[float]:
        """The core's row (colliders.hpp: shape code, centre, radius, height, sizes, unit normal, friction).  The
        normal's length is summed in a fixed order, as the native unit sums it (``fmu/unit.cpp``'s
        collider_rows): the same bits (a BLAS dot product's order and fused multiply-adds vary by CPU)."""
        norm = np.sqrt(np.float64(self.normal_x * self.normal_x + self.normal_y * self.normal_y
                                  + self.normal_z * self.normal_z))
        normal = np.array([self.normal_x, self.normal_y, self.normal_z]) / norm
        return [float(COLLIDER_SHAPES.index(self.shape)), self.x, self.y, self.z, self.radius, self.height,
                self.size_x, self.size_y, self.size_z, *map(float, normal), self.friction]

    def distance(self, p: np.ndarray) -> np.ndarray:
        """Signed distance (m, negative inside) of points p (3, m) from the surface (as the core's; a
        mesh's up to MESH_REACH: points farther away get MESH_REACH)."""
        if self.shape == "mesh":
            from wetcloth.collider_meshes import distance_to_mesh

            return distance_to_mesh(self, p, MESH_REACH)
        d = p - np.array([[self.x], [self.y], [self.z]])
        if self.shape == "sphere":
            return np.sqrt((d * d).sum(axis=0)) - self.radius
        if self.shape == "plane":
            normal = np.array(self.row()[9:12])
            return normal @ d
        if self.shape == "cylinder":
            q = np.stack([np.hypot(d[0], d[1]) - self.radius, np.abs(d[2]) - 0.5 * self.height])
        else:
            q = np.abs(d) - 0.5 * np.array([[self.size_x], [self.size_y], [self.size_z]])
        outside = np.sqrt((np.maximum(q, 0.0) ** 2).sum(axis=0))
        return np.where(outside > 0.0, outside, q.max(axis=0))


COLLIDER_FIELDS: dict[str, dataclasses.Field] = {f.name: f for f in dataclasses.fields(Collider)}
_COLLIDER_NAME = re.compile(r"collider([1-9][0-9]*)_([a-z_]+)")


def _table_name(pattern: re.Pattern, fields: dict, name: str) -> tuple[int, str] | None:
    """(k, field) of the flattened name of table k's field (``pattern``: its number, then its field), else None."""
    m = pattern.fullmatch(name)
    return (int(m.group(1)), m.group(2)) if m and m.group(2) in fields else None


def collider_name(name: str) -> tuple[int, str] | None:
    """(k, field) of a flattened collider name such as 'collider1_radius', else None."""
    return _table_name(_COLLIDER_NAME, COLLIDER_FIELDS, name)


@dataclass(frozen=True)
class GripKey:
    """A key of the grip's displacement (docs/model.md section 6.4), one ``[[grip_key]]`` table of a scene
    file: the pinned particles are displaced by (x, y, z) at ``time``, linearly between keys (from 0 at
    t = 0 to the first).  Its fields are addressed as ``grip_key<k>_<field>`` (k from 1) everywhere else."""

    time: float = _param(None, "s", "time of the key (required: no default)", 0.0, 1e6, lo_open=True)
    x: float = _param(0.0, "m", "the grip's displacement along x at the key's time", -1e4, 1e4)
    y: float = _param(0.0, "m", "the grip's displacement along y at the key's time", -1e4, 1e4)
    z: float = _param(0.0, "m", "the grip's displacement along z (up) at the key's time", -1e4, 1e4)


GRIP_KEY_FIELDS: dict[str, dataclasses.Field] = {f.name: f for f in dataclasses.fields(GripKey)}
_GRIP_KEY_NAME = re.compile(r"grip_key([1-9][0-9]*)_([a-z]+)")


def grip_key_name(name: str) -> tuple[int, str] | None:
    """(k, field) of a flattened grip key name such as 'grip_key1_time', else None."""
    return _table_name(_GRIP_KEY_NAME, GRIP_KEY_FIELDS, name)


@dataclass(frozen=True)
class ColliderKey:
    """A key of a collider's motion (docs/model.md section 6.3), one ``[[collider_key]]`` table of a scene file:
    collider ``collider`` is displaced by (x, y, z) from where its table puts it at ``time``, linearly
    between its keys (from 0 at t = 0 to the first), the last key's after it, and turned about its centre
    by the rotation vector (rx, ry, rz) (axis times angle, degrees) from its table's orientation, by slerp
    between its keys (a constant angular velocity; consecutive keys less than 180 deg apart).  Its fields
    are addressed as ``collider_key<k>_<field>`` (k from 1) everywhere else."""

    collider: int = _param(None, "-", "the collider it moves: its number (1, 2, ... in file order; required)", 1, 10000)
    time: float = _param(None, "s", "time of the key (required: no default)", 0.0, 1e6, lo_open=True)
    x: float = _param(0.0, "m", "the collider's displacement along x at the key's time", -1e4, 1e4)
    y: float = _param(0.0, "m", "the collider's displacement along y at the key's time", -1e4, 1e4)
    z: float = _param(0.0, "m", "the collider's displacement along z (up) at the key's time", -1e4, 1e4)
    rx: float = _param(0.0, "deg", "x component of the collider's rotation vector (axis times angle) at the key's "
                       "time, about its centre", -1e6, 1e6)
    ry: float = _param(0.0, "deg", "y component of the collider's rotation vector at the key's time", -1e6, 1e6)
    rz: float = _param(0.0, "deg", "z component (about the vertical) of the collider's rotation vector at the "
                       "key's time", -1e6, 1e6)


COLLIDER_KEY_FIELDS: dict[str, dataclasses.Field] = {f.name: f for f in dataclasses.fields(ColliderKey)}
_COLLIDER_KEY_NAME = re.compile(r"collider_key([1-9][0-9]*)_([a-z]+)")


def collider_key_name(name: str) -> tuple[int, str] | None:
    """(k, field) of a flattened collider key name such as 'collider_key1_time', else None."""
    return _table_name(_COLLIDER_KEY_NAME, COLLIDER_KEY_FIELDS, name)


def grip_key_rows(keys) -> np.ndarray:
    """The core's rows of grip keys (grip.hpp: time s, x, y, z m); (0, 4) without keys."""
    return np.array([[k.time, k.x, k.y, k.z] for k in keys], dtype=np.float64).reshape(-1, 4)


def collider_key_order(keys) -> list[int]:
    """The places (from 0) of the collider keys in the core's order: by collider, then time."""
    return sorted(range(len(keys)), key=lambda j: (keys[j].collider, keys[j].time))


def collider_key_rows(keys) -> np.ndarray:
    """The core's rows of collider keys (collider_motion.hpp: collider from 0, time s, x, y, z m, rotation
    vector rad), in collider_key_order; (0, 8) without keys."""
    rows = [[k.collider - 1, k.time, k.x, k.y, k.z, math.radians(k.rx), math.radians(k.ry), math.radians(k.rz)]
            for k in (keys[j] for j in collider_key_order(keys))]
    return np.array(rows, dtype=np.float64).reshape(-1, 8)


def rotation_matrix(vector) -> np.ndarray:
    """The rotation (3 x 3) by |vector| rad about vector (3): exp([vector]) (Rodrigues).  (With numpy, not
    scipy.spatial.transform, whose import takes 0.3 s of a fresh process's first scene with collider keys.)"""
    r = np.asarray(vector, dtype=np.float64)
    angle = float(np.linalg.norm(r))
    if angle == 0.0:
        return np.eye(3)
    a = r / angle
    cross = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * cross + (1.0 - math.cos(angle)) * cross @ cross


def rotation_vector(turn) -> np.ndarray:
    """The rotation vector (3, rad, angle in [0, pi]) of a rotation matrix (3 x 3): log(turn)."""
    cosine = min(1.0, max(-1.0, 0.5 * (float(np.trace(turn)) - 1.0)))
    w = np.array([turn[2, 1] - turn[1, 2], turn[0, 2] - turn[2, 0], turn[1, 0] - turn[0, 1]])
    angle = math.atan2(0.5 * float(np.linalg.norm(w)), cosine)  # (acos loses half the digits near 0 and pi)
    if angle < 1e-6:
        return 0.5 * w
    if math.sin(angle) > 1e-3:
        return 0.5 * angle / math.sin(angle) * w
    # near a half turn: the axis a from the symmetric part, turn + turn^T = 2 cos I + 2 (1 - cos) a a^T
    big = int(np.argmax(np.diag(turn)))
    axis = np.empty(3)
    axis[big] = math.sqrt(max(0.0, (turn[big, big] - cosine) / (1.0 - cosine)))
    for c in range(3):
        if c != big:
            axis[c] = 0.5 * (turn[c, big] + turn[big, c]) / ((1.0 - cosine) * axis[big])
    if float(w @ axis) < 0.0:  # (w = 2 sin a)
        axis = -axis
    return angle * axis


def turn_between(a, b) -> float:
    """The angle (deg) of the rotation from rotation vector a to b (3, deg each): of R_b R_a^T."""
    relative = rotation_matrix(np.radians(b)) @ rotation_matrix(np.radians(a)).T
    return math.degrees(float(np.linalg.norm(rotation_vector(relative))))


@dataclass(frozen=True)
class Scene:
    """A cloth dropped onto water.  The defaults are the cotton towel of ``models/towel.toml``."""

    # --- cloth geometry and grid
    nx: int = _param(21, "-", "particles along the width (x)", 2, MOST_ALONG)
    ny: int = _param(29, "-", "particles along the length (y)", 2, MOST_ALONG)
    width: float = _param(0.5, "m", "cloth size along x", SMALLEST_SIZE, LARGEST_SIZE)
    length: float = _param(0.7, "m", "cloth size along y", SMALLEST_SIZE, LARGEST_SIZE)
    cloth_mesh: str = _param(
        "", "-", "the cloth's mesh file (OBJ, PLY, STL, OFF, VTK/VTU, glTF/GLB; triangles and quads), one particle "
        "per vertex; '' = the nx x ny rectangle (then nx, ny, width, length make the cloth); a relative path is "
        "relative to the scene file", text=MESH_ALLOWED, mesh=True)
    place_mesh: str = _param(
        "off", "-", "'off': the mesh file's coordinates as they are (m, z up); 'on': the mesh turned by initial_tilt "
        "about the x axis through its centroid, and its centroid raised to initial_height", choices=SWITCH)
    # --- fabric
    #: The lightest fabrics (tulle, tissue) weigh about 0.01 kg/m2; below 5 g/m2 a cloth in a 10 m/s wind took
    #: minutes a second or blew up (docs/open_problems.md).
    areal_density: float = _param(0.45, "kg/m2", "dry fabric mass per area", 0.005, 100.0)
    thickness: float = _param(
        0.002, "m", "envelope thickness: buoyant volume = area * thickness", 0.0, 1.0, lo_open=True
    )
    stretch_stiffness: float = _param(
        2000.0, "N/m", "spring stiffness per unit strain per unit width", 0.0, 1e8, lo_open=True
    )
    bend_stiffness: float = _param(
        20.0, "N/m", "bending-spring stiffness per unit strain per unit width; 0 = off (unused where bend_rigidity > 0)",
        0.0, 1e8,
    )
    bend_rigidity: float = _param(
        0.0, "N m", "bending rigidity (quadratic hinges instead of the bending springs); 0 = springs",
        0.0, 100.0,
    )
    damping: float = _param(0.2, "N s/m", "spring damping per unit strain rate per unit width", 0.0, 1e6)
    damping_model: str = _param(
        "projected", "-", "spring damping: 'projected' (along the spring) or 'thesis' (eq. 3.2)",
        choices=("projected", "thesis"),
    )
    # --- water
    water_level: float = _param(0.0, "m", "height of the water surface (z is up)", -1e4, 1e4, fmu=INPUT)
    water_density: float = _param(1000.0, "kg/m3", "density of the water", 0.0, 1e5, lo_open=True, fmu=INPUT)
    water_viscosity: float = _param(1.0e-3, "Pa s", "dynamic viscosity of the water (Stokes drag)", 0.0, 1e3)
    drag_model: str = _param("face", "-", "'face' (per-triangle, default) or 'stokes' (thesis eq. 3.5)", choices=("face", "stokes"))
    drag_normal: float = _param(1.2, "-", "face-drag coefficient across the cloth, C_n", 0.0, 100.0)
    drag_tangential: float = _param(0.03, "-", "face-drag coefficient along the cloth, C_t", 0.0, 100.0)
    drag_linear: float = _param(2.0, "N s/m3", "face-drag linear term c_lin per area", 0.0, 1e4)
    buoyancy_model: str = _param(
        "smooth", "-", "'smooth' (slab fraction, default) or 'thesis' (all or nothing)", choices=("smooth", "thesis")
    )
    # --- absorption (Buras law)
    absorption_capacity: float = _param(
        3.8, "kg/kg", "equilibrium water uptake per kg of dry fabric (Buras Q)", 0.0, 100.0, fmu=INPUT
    )
    absorption_rate: float = _param(
        0.15, "1/s", "initial uptake rate, kg water per kg dry fabric per s (Buras I)", 0.0, 1e4, fmu=INPUT
    )
    # --- beyond the thesis (docs/model.md section 5): each off at 0 and then skipped
    wicking_rate: float = _param(
        0.0, "m2/s", "diffusion constant of water through the fabric, driven by saturation; 0 = off", 0.0, 1.0
    )
    drying_rate: float = _param(0.0, "1/s", "fraction of its water a particle in air loses per second; 0 = off", 0.0, 100.0)
    wet_stiffness_factor: float = _param(
        0.0, "-", "stiffness scales by 1 + factor * saturation (negative softens); 0 = off", -0.9, 10.0
    )
    current_x: float = _param(0.0, "m/s", "water velocity along x, which the drag acts relative to", -10.0, 10.0, fmu=INPUT)
    current_y: float = _param(0.0, "m/s", "water velocity along y, which the drag acts relative to", -10.0, 10.0, fmu=INPUT)
    # --- air (docs/model.md section 4.4): face drag on the part of the cloth out of the water; on by default
    air_density: float = _param(
        1.2, "kg/m3", "density of the air above the water (face drag in air); 0 = off", 0.0, 1000.0
    )
    wind_x: float = _param(0.0, "m/s", "air velocity along x, which the drag in air acts relative to", -100.0, 100.0, fmu=INPUT)
    wind_y: float = _param(0.0, "m/s", "air velocity along y, which the drag in air acts relative to", -100.0, 100.0, fmu=INPUT)
    wind_z: float = _param(0.0, "m/s", "air velocity along z (up), which the drag in air acts relative to", -100.0, 100.0,
                           fmu=INPUT)
    initial_saturation: float = _param(0.0, "-", "absorbed water at t = 0, as a fraction of the capacity", 0.0, 1.0)
    # --- initial state and surroundings
    initial_height: float = _param(0.1, "m", "z of the cloth's centre at t = 0 (cloth at rest)", -1e4, 1e4)
    initial_tilt: float = _param(10.0, "deg", "rotation about the x axis at t = 0; 90 is vertical", -90.0, 90.0)
    floor_level: float = _param(-1.0, "m", "z of the tank floor", -1e4, 1e4)
    floor_friction: float = _param(0.5, "-", "Coulomb friction coefficient of the floor", 0.0, 10.0)
    # --- self-collision (docs/model.md section 6.2)
    self_collision: str = _param(
        "on", "-", "'on': the cloth never passes through itself and keeps its layers 0.9 to 1 thickness apart; "
        "'off' skips it (a cloth that cannot fold saves its small cost)", choices=SWITCH)
    self_friction: float = _param(0.4, "-", "Coulomb friction coefficient between layers of the cloth", 0.0, 10.0)
    pinned_edge: str = _param("none", "-", "edge held fixed in space: none, x_min, x_max, y_min, y_max", choices=EDGES)
    pinned_vertices: str = _param(
        "", "-", "vertices held fixed in space, with pinned_edge's: the name of a point attribute of the mesh file "
        "(nonzero = pinned), or 'box:x0,y0,z0,x1,y1,z1', the vertices in that box at t = 0 (m, inclusive); '' = none",
        text=PINS_ALLOWED)
    # --- the grip (docs/model.md section 6.4): moves the pinned particles; [[grip_key]] tables add keys
    grip_x: float = _param(0.0, "m", "displacement of the pinned particles along x (reached linearly over the next "
                           "advance)", -1e4, 1e4, fmu=INPUT)
    grip_y: float = _param(0.0, "m", "displacement of the pinned particles along y (reached linearly over the next "
                           "advance)", -1e4, 1e4, fmu=INPUT)
    grip_z: float = _param(0.0, "m", "displacement of the pinned particles along z, up (reached linearly over the "
                           "next advance)", -1e4, 1e4, fmu=INPUT)
    # --- time integration
    integrator: str = _param(
        "bdf2", "-", "time integrator: 'bdf2' (second order, implicit, steps set by the tolerance), "
        "'implicit_euler' (first order; with tolerance 0 and max_step one frame, frame-long steps that never "
        "fail), 'symplectic_euler', or 'explicit_euler' (the thesis scheme)", choices=INTEGRATORS)
    tolerance: float = _param(
        5e-6, "-", "local position error per step relative to the cloth size; 0 = fixed steps", 0.0, 1.0
    )
    max_step: float = _param(0.1, "s", "largest internal time step", SMALLEST_MAX_STEP, 1.0)
    # --- analytic colliders (docs/model.md section 6.3): [[collider]] tables, flattened as collider<k>_<field>
    colliders: tuple = field(default=(), metadata=dict(collider=True))
    # --- the grip's keys: [[grip_key]] tables, flattened as grip_key<k>_<field>
    grip_keys: tuple = field(default=(), metadata=dict(grip_key=True))
    # --- the colliders' keys (docs/model.md section 6.3): [[collider_key]] tables, flattened as collider_key<k>_<field>
    collider_keys: tuple = field(default=(), metadata=dict(collider_key=True))

    def __post_init__(self):
        validate(self)

    def replace(self, **overrides) -> "Scene":
        """A copy with some parameters changed (validated); collider fields by their flattened names.  A
        new ``colliders``, ``grip_keys`` or ``collider_keys`` replaces the scene's whole (``colliders=()``: none)."""
        return from_dict(_overridden(self.to_dict(), overrides))

    def to_dict(self) -> dict[str, Any]:
        """Every parameter by name, the colliders' fields flattened (collider1_shape, collider1_x, ...)."""
        values = {name: getattr(self, name) for name in PARAMETERS}
        for k, collider in enumerate(self.colliders, 1):
            values |= {f"collider{k}_{name}": getattr(collider, name) for name in COLLIDER_FIELDS}
        for k, key in enumerate(self.grip_keys, 1):
            values |= {f"grip_key{k}_{name}": getattr(key, name) for name in GRIP_KEY_FIELDS}
        for k, key in enumerate(self.collider_keys, 1):
            values |= {f"collider_key{k}_{name}": getattr(key, name) for name in COLLIDER_KEY_FIELDS}
        return values


_DATACLASS_INIT = Scene.__init__


@functools.wraps(_DATACLASS_INIT)
def _scene_init(self, *args, **values):
    """The dataclass's __init__, with a ParameterError naming the nearest parameters for unknown names."""
    mistakes = Mistakes()
    for name in values:
        if name not in _SCENE_FIELDS:
            with mistakes.collect():
                _field(name)  # a misspelled name: the nearest named
                raise ParameterError(name, "is a field of a listed table; Scene takes the tables as lists (colliders, "
                                           "grip_keys, collider_keys), load_scene and Scene.replace also by this name")
    mistakes.raise_if_any()
    _DATACLASS_INIT(self, *args, **values)


Scene.__init__ = _scene_init
_SCENE_FIELDS = {f.name for f in dataclasses.fields(Scene)}
PARAMETERS: dict[str, dataclasses.Field] = {f.name: f for f in dataclasses.fields(Scene)
                                            if f.name not in ("colliders", "grip_keys", "collider_keys")}
PARAMETER_LISTING = f"there are {len(PARAMETERS)}; 'wetcloth params' lists them"


def describe_range(f: dataclasses.Field, name: str | None = None) -> str:
    """The allowed values of a field, as a user reads them: '0 < thickness <= 1 m' (``name``: the name
    to show, e.g. a collider's flattened 'collider1_radius')."""
    md = f.metadata
    if md.get("text"):
        return md["text"]
    if md["choices"]:
        return "one of " + ", ".join(repr(c) for c in md["choices"])
    unit = "" if md["unit"] == "-" else f" {md['unit']}"
    lo_sign = "<" if md["lo_open"] else "<="
    return f"{md['lo']:g} {lo_sign} {name or f.name} <= {md['hi']:g}{unit}"


def _unknown_listed_field(name: str, prefix: str, fields: list[str], what: str) -> str:
    """Why ``name`` (``prefix<k>_<field>``) names no field of a listed table (a collider, a key): a number
    that is 0 or has leading zeros (k counts from 1), a misspelled field (the nearest one named), else the
    layout and every field."""
    layout = f"a {what}'s fields are {prefix}<k>_<field> (k = 1, 2, ...) with <field> one of {', '.join(fields)}"
    match = re.fullmatch(rf"{prefix}(\d+)_(.+)", name)
    if match is None:
        return f"unknown {what} field; {layout}"
    number, field_name = match.groups()
    close = [field_name] if field_name in fields else difflib.get_close_matches(field_name, fields, n=1)
    k = max(int(number), 1)
    why = f"{what} numbers start at 1, without leading zeros" if number != str(k) else f"unknown {what} field"
    return f"{why}; did you mean '{prefix}{k}_{close[0]}'?" if close else f"{why}; {layout}"


def _field(name: str) -> dataclasses.Field:
    if name in PARAMETERS:
        return PARAMETERS[name]
    flat = collider_name(name)
    if flat is not None:
        return COLLIDER_FIELDS[flat[1]]
    key = grip_key_name(name)
    if key is not None:
        return GRIP_KEY_FIELDS[key[1]]
    moving = collider_key_name(name)
    if moving is not None:
        return COLLIDER_KEY_FIELDS[moving[1]]
    for prefix, fields, what in (("collider_key", COLLIDER_KEY_FIELDS, "collider key"),
                                 ("grip_key", GRIP_KEY_FIELDS, "grip key"), ("collider", COLLIDER_FIELDS, "collider")):
        if name.startswith(prefix):
            raise ParameterError(name, _unknown_listed_field(name, prefix, list(fields), what))
    raise ParameterError(name, did_you_mean(name, PARAMETERS, listing=PARAMETER_LISTING))


def parameter_field(name: str) -> dataclasses.Field:
    """The field (unit, range, doc in its metadata) of a parameter name, a collider's flattened names
    included; a ParameterError for an unknown name."""
    return _field(name)


def is_parameter(name: str) -> bool:
    """Whether ``name`` is a scene parameter or a collider field's flattened name (collider1_radius)."""
    return (name in PARAMETERS or collider_name(name) is not None or grip_key_name(name) is not None
            or collider_key_name(name) is not None)


def normalise(name: str, value):
    """``value`` in the type of parameter ``name``, by the one rule of every source (scene files,
    ``--set``, Python, studies, the FMU): a string parameter takes a string; a number parameter a
    number (Python's or NumPy's; never text or a boolean), a whole-number one also a float that is whole
    (3.0 -> 3)."""
    f = _field(name)
    if f.type == "str":
        if f.metadata.get("mesh") and isinstance(value, MeshFile):
            return value
        if not isinstance(value, str):
            raise ParameterError(name, f"expected a string, got {value!r}; allowed: {describe_range(f, name)}")
        return value
    if isinstance(value, bool) or not isinstance(value, numbers.Real):  # Real: NumPy's scalars too
        raise ParameterError(name, f"{not_a_number(value)}; allowed: {describe_range(f, name)}")
    if f.type == "int":
        if not isinstance(value, numbers.Integral) and not float(value).is_integer():
            raise ParameterError(name, f"expected a whole number, got {value!r}; allowed: {describe_range(f, name)}")
        return int(value)
    try:
        return float(value)
    except OverflowError:  # a whole number beyond any float (a TOML integer of 309 digits)
        raise ParameterError(name, f"a whole number beyond 1.8e308 is out of range; allowed: "
                                   f"{describe_range(f, name)}") from None


def check_value(name: str, value):
    """One parameter's value, normalised and checked against its range alone (no cross-parameter checks)."""
    value = normalise(name, value)
    f = _field(name)
    md = f.metadata
    if f.type == "str":
        if md.get("text"):
            return value
        if value not in md["choices"]:
            close = difflib.get_close_matches(value, md["choices"], n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ParameterError(name, f"{value!r} is not allowed{hint}; allowed: {describe_range(f, name)}")
        return value
    if not math.isfinite(value):
        raise ParameterError(name, f"{value!r} is not a finite number; allowed: {describe_range(f, name)}")
    below = value <= md["lo"] if md["lo_open"] else value < md["lo"]
    if below or value > md["hi"]:
        raise ParameterError(name, f"{value!r} is out of range; allowed: {describe_range(f, name)}")
    return value


def spelled_number(text: str, kinds: tuple = (int, float)):
    """The number ``text`` spells, as the first of ``kinds`` that reads it, or None.  Digits grouped by
    underscores spell none here: Python reads 1_0 as 10, a scene file (TOML) and a person do not."""
    if "_" in text:
        return None
    for kind in kinds:
        try:
            return kind(text.strip())
        except ValueError:
            continue
    return None


def parse_text(name: str, text: str):
    """A parameter's value from text (``--set name=text``): the number it spells for a number
    parameter (then the same rule as a TOML value: ``nx=3.0`` is 3), the text for a string one."""
    f = _field(name)
    if f.type == "str":
        return text
    value = spelled_number(text)
    if value is not None:
        return normalise(name, value)
    raise ParameterError(name, f"expected a number, got {text!r}; allowed: {describe_range(f, name)}")


def validate(scene: Scene) -> None:
    """Check every parameter against its range and the scene as a whole, normalising the values
    (3.0 -> 3 for nx, 1 -> 1.0 for width); raise ParameterError with every mistake found."""
    mistakes = Mistakes()
    for name in PARAMETERS:
        with mistakes.collect():
            object.__setattr__(scene, name, check_value(name, getattr(scene, name)))
    # Keys name colliders by their place among those given, a faulty one included (its own mistake is
    # reported, not one for each key that moves it).
    given = len(scene.colliders) if isinstance(scene.colliders, (tuple, list)) else 0
    object.__setattr__(scene, "colliders", _checked_colliders(scene.colliders, mistakes))
    object.__setattr__(scene, "grip_keys", _checked_grip_keys(scene, mistakes))
    object.__setattr__(scene, "collider_keys", _checked_collider_keys(scene, given, mistakes))
    mistakes.raise_if_any()
    start = _check_mesh_start(scene) if is_mesh(scene.cloth_mesh) else None
    if start is None:
        _check_grid_start(scene)
    if scene.colliders or scene.pinned_vertices.strip() or scene.pinned_edge != "none":
        from wetcloth.pinned_paths import check_pinned_outside
        from wetcloth.topology import pinned_mask, start_positions

        positions, mesh = start_positions(scene) if start is None else start
        pinned = pinned_mask(scene, positions, mesh)
        _check_collider_start(scene, positions)
        check_pinned_outside(scene, positions, pinned)


def _check_grid_start(scene: Scene) -> None:
    """The compiled core's rule on the grid's start, which the native units apply as well: its cells at most
    LONGEST_CELL (100) times longer one way than the other, and the cloth above the floor; a ParameterError
    naming the parameter to change (for long cells, the particle counts that would make them squarer)."""
    problem = _core.grid_start_problem(nx=scene.nx, ny=scene.ny, width=scene.width, length=scene.length,
                                       thickness=scene.thickness, initial_height=scene.initial_height,
                                       initial_tilt=scene.initial_tilt, floor_level=scene.floor_level)
    refuse_problem(problem)


def refuse_problem(problem: str) -> None:
    """Raise the ParameterError of a core rule's text ("parameter 'NAME': MESSAGE"), if any."""
    if problem:
        name, message = problem.removeprefix("parameter '").split("': ", 1)
        raise ParameterError(name, message)


def _check_mesh_start(scene: Scene):
    """The mesh cloth's positions at t = 0 (3, n) m and its mesh file; a ParameterError for a mesh file that
    cannot be read or used, a cloth that starts at or below the floor, or one that self-collision cannot
    take: folded over itself or in stacked layers in its file."""
    from wetcloth.topology import mesh_flat_sheet, start_positions

    positions, mesh = start_positions(scene)
    refuse_problem(_core.mesh_floor_problem(np.ascontiguousarray(positions, dtype=float), thickness=scene.thickness,
                                            floor_level=scene.floor_level, placed=scene.place_mesh == "on"))
    if scene.self_collision == "on":
        overlap = mesh_flat_sheet(mesh)[1]
        if overlap is not None:
            first, second = (int(mesh.face_of[t]) for t in overlap)
            raise ParameterError("cloth_mesh", f"{mesh.source!r}: faces {first} and {second} lie over each other "
                                 "seen across the cloth (it folds over itself or holds stacked layers), and "
                                 "self-collision, which measures the cloth laid out flat, would let them pass "
                                 "through each other; allowed with self_collision = 'on': a cloth laid out in one "
                                 "layer, or one whose per-vertex UVs lay it out flat without overlap (unwrap it), "
                                 "or set self_collision = 'off'")
    return positions, mesh


def _fields(collider: Collider) -> dict[str, Any]:
    """A collider's fields by name (not dataclasses.asdict, which would take a mesh given as arrays apart)."""
    return {name: getattr(collider, name) for name in COLLIDER_FIELDS}


def _checked_colliders(colliders, mistakes: Mistakes) -> tuple:
    """The colliders as Collider objects (from Collider or dicts of fields), each field checked under its
    flattened name."""
    if not isinstance(colliders, (tuple, list)):
        with mistakes.collect():
            raise ParameterError("colliders", f"expected a list of colliders, got {colliders!r}")
        return ()
    out = []
    for k, collider in enumerate(colliders, 1):
        values = _fields(collider) if isinstance(collider, Collider) else collider
        if not isinstance(values, dict):
            with mistakes.collect():
                raise ParameterError(f"collider{k}", f"expected a table of collider fields, got {values!r}")
            continue
        checked = {}
        for name, value in values.items():
            with mistakes.collect():
                checked[name] = check_value(f"collider{k}_{name}", value)
        if len(checked) != len(values):
            continue
        shape = checked.get("shape", "sphere")
        if shape == "mesh":
            with mistakes.collect():
                from wetcloth.collider_meshes import mesh_of

                mesh_of(Collider(**checked), f"collider{k}_file")  # readable, with faces
        elif checked.get("file", "") != "":
            with mistakes.collect():
                raise ParameterError(f"collider{k}_file", f"a {shape} collider takes no file (its shape is its own); "
                                                          f"allowed: a file with shape = 'mesh' only, else ''")
            continue
        if shape == "plane" and not any(
                checked.get(f"normal_{c}", COLLIDER_FIELDS[f"normal_{c}"].default) != 0.0 for c in "xyz"):
            with mistakes.collect():
                raise ParameterError(f"collider{k}_normal_z", "a plane's normal is zero; allowed: a nonzero "
                                                              "(normal_x, normal_y, normal_z)")
            continue
        out.append(Collider(**checked))
    return tuple(out)


def _checked_grip_keys(scene: Scene, mistakes: Mistakes) -> tuple:
    """The grip keys as GripKey objects (from GripKey or dicts of fields), each field checked under its
    flattened name; their times must increase, and something must be pinned for them to move."""
    keys = scene.grip_keys
    if not isinstance(keys, (tuple, list)):
        with mistakes.collect():
            raise ParameterError("grip_keys", f"expected a list of grip keys, got {keys!r}")
        return ()
    out = []
    for k, key in enumerate(keys, 1):
        values = dataclasses.asdict(key) if isinstance(key, GripKey) else key
        with mistakes.collect():
            if not isinstance(values, dict):
                raise ParameterError(f"grip_key{k}", f"expected a table of grip key fields, got {values!r}")
            if "time" not in values:
                raise ParameterError(f"grip_key{k}_time", "a grip key needs its time; allowed: "
                                     + describe_range(GRIP_KEY_FIELDS["time"], f"grip_key{k}_time"))
            checked = {name: check_value(f"grip_key{k}_{name}", value) for name, value in values.items()}
            if out and checked["time"] <= out[-1].time:
                raise ParameterError(f"grip_key{k}_time", f"{checked['time']!r} s is not after grip_key{k - 1}_time "
                                     f"= {out[-1].time!r} s; allowed: key times that increase")
            out.append(GripKey(**checked))
    if out and scene.pinned_edge == "none" and not scene.pinned_vertices.strip():
        with mistakes.collect():
            raise ParameterError("grip_key1", "the grip moves the pinned particles, and none are pinned; allowed: "
                                 "grip keys with pinned_edge one of 'x_min', 'x_max', 'y_min', 'y_max', or "
                                 "pinned_vertices set")
    return tuple(out)


def _checked_collider_keys(scene: Scene, colliders: int, mistakes: Mistakes) -> tuple:
    """The collider keys as ColliderKey objects (from ColliderKey or dicts of fields), each field checked under
    its flattened name; each names one of the scene's ``colliders`` [[collider]] tables, and the times of one
    collider's keys increase."""
    keys = scene.collider_keys
    if not isinstance(keys, (tuple, list)):
        with mistakes.collect():
            raise ParameterError("collider_keys", f"expected a list of collider keys, got {keys!r}")
        return ()
    out = []
    last: dict[int, tuple[int, float]] = {}  # each collider's latest key: (k, time)
    turned: dict[int, tuple[float, float, float]] = {}  # and its rotation vector (deg)
    for k, key in enumerate(keys, 1):
        values = dataclasses.asdict(key) if isinstance(key, ColliderKey) else key
        with mistakes.collect():
            if not isinstance(values, dict):
                raise ParameterError(f"collider_key{k}", f"expected a table of collider key fields, got {values!r}")
            for required in ("collider", "time"):
                if required not in values:
                    name = f"collider_key{k}_{required}"
                    raise ParameterError(name, f"a collider key needs its {required}; allowed: "
                                         + _key_range(required, name, colliders))
            checked = {name: check_value(f"collider_key{k}_{name}", value) for name, value in values.items()}
            collider = checked["collider"]
            if collider > colliders:
                raise ParameterError(f"collider_key{k}_collider", f"{collider} names no collider (the scene has "
                                     f"{colliders}); allowed: "
                                     + _key_range("collider", f"collider_key{k}_collider", colliders))
            if collider in last and checked["time"] <= last[collider][1]:
                before, time = last[collider]
                raise ParameterError(f"collider_key{k}_time", f"{checked['time']!r} s is not after "
                                     f"collider_key{before}_time = {time!r} s, the previous key of collider {collider}; "
                                     f"allowed: the times of one collider's keys increase")
            key = ColliderKey(**checked)
            before = turned.get(collider, (0.0, 0.0, 0.0))
            turn = turn_between(before, (key.rx, key.ry, key.rz))
            if turn >= MAX_KEY_TURN:
                after = (f"collider_key{last[collider][0]}" if collider in last
                         else f"its table's orientation (t = 0)")
                raise ParameterError(f"collider_key{k}_rx", f"(rx, ry, rz) = ({key.rx:g}, {key.ry:g}, {key.rz:g}) deg "
                                     f"turns collider {collider} by {turn:.6g} deg from {after}; allowed: less than "
                                     f"{MAX_KEY_TURN:g} deg between consecutive keys of one collider (the turn "
                                     f"between them is the shortest; add keys between)")
            last[collider] = (k, checked["time"])
            turned[collider] = (key.rx, key.ry, key.rz)
            out.append(key)
    return tuple(out)


#: The largest turn (deg, excluded) between consecutive keys of one collider: the slerp between them turns
#: the shorter way, which a half turn leaves undecided.
MAX_KEY_TURN = 179.0


def _key_range(field_name: str, name: str, colliders: int) -> str:
    """What a collider key's field allows: its range, the collider number within the scene's ``colliders``."""
    if field_name == "collider":
        return (f"1 <= {name} <= {colliders} (the scene's [[collider]] tables)" if colliders
                else "a collider key moves a [[collider]] of the scene, and it has none")
    return describe_range(COLLIDER_KEY_FIELDS[field_name], name)


def _check_collider_start(scene: Scene, pos: np.ndarray) -> None:
    """No collider may reach into the cloth at t = 0 (closer than thickness/2 to a particle at ``pos`` (3, n) m)."""
    if not scene.colliders:
        return
    gap = 0.5 * scene.thickness
    mistakes = Mistakes()
    for k, collider in enumerate(scene.colliders, 1):
        d = collider.distance(pos)
        i = int(np.argmin(d))
        if d[i] < gap * (1.0 - 1e-9):
            with mistakes.collect():
                raise ParameterError(
                    f"collider{k}",
                    f"the {collider.shape} overlaps the cloth at t = 0 (particle {i} at ({pos[0, i]:g}, {pos[1, i]:g}, "
                    f"{pos[2, i]:g}) m is {d[i]:g} m from its surface); allowed: every particle at least "
                    f"thickness/2 = {gap:g} m outside it (move the collider or the cloth: initial_height)")
    mistakes.raise_if_any()


def from_dict(values: dict[str, Any]) -> Scene:
    """A validated Scene from a mapping of parameter names to values (every mistake at once).  Colliders
    come as ``colliders`` (Collider objects or dicts), as flattened names (collider1_radius), or both
    (the flattened names then change the listed colliders' fields or add colliders, numbered on)."""
    values = dict(values)
    colliders = [_fields(c) if isinstance(c, Collider) else dict(c) if isinstance(c, dict) else c
                 for c in values.pop("colliders", ())]
    keys = [dataclasses.asdict(c) if isinstance(c, GripKey) else dict(c) if isinstance(c, dict) else c
            for c in values.pop("grip_keys", ())]
    moves = [dataclasses.asdict(c) if isinstance(c, ColliderKey) else dict(c) if isinstance(c, dict) else c
             for c in values.pop("collider_keys", ())]
    mistakes = Mistakes()
    flat: dict[int, dict[str, Any]] = {}
    flat_keys: dict[int, dict[str, Any]] = {}
    flat_moves: dict[int, dict[str, Any]] = {}
    for name in list(values):
        with mistakes.collect():
            _field(name)
            where = collider_name(name)
            if where is not None:
                flat.setdefault(where[0], {})[where[1]] = values.pop(name)
            key = grip_key_name(name)
            if key is not None:
                flat_keys.setdefault(key[0], {})[key[1]] = values.pop(name)
            move = collider_key_name(name)
            if move is not None:
                flat_moves.setdefault(move[0], {})[move[1]] = values.pop(name)
    for table, listed, label in ((flat_keys, keys, "grip_key"), (flat_moves, moves, "collider_key"),
                                 (flat, colliders, "collider")):
        for k in sorted(table):
            with mistakes.collect():
                if k > len(listed) + 1:
                    raise ParameterError(f"{label}{k}_{next(iter(table[k]))}", f"there is no {label.replace('_', ' ')} "
                                         f"{k - 1}: number {label.replace('_', ' ')}s 1, 2, ... without gaps")
                if k == len(listed) + 1:
                    listed.append({})
                listed[k - 1] = listed[k - 1] | table[k]
    mistakes.raise_if_any()
    return Scene(**values, colliders=tuple(colliders), grip_keys=tuple(keys), collider_keys=tuple(moves))


#: Keys of a scene file that are not scene parameters: a description and the ``[run]`` table.  (``[[collider]]``
#: and ``[[grip_key]]`` tables are read into flattened names, collider1_shape ..., by read_scene_file.)
RESERVED_KEYS = ("description", "run")


def preset_dir() -> Path:
    """Folder of the scene presets shipped with wetcloth (the repository's ``models/``)."""
    return Path(str(resources.files("wetcloth.presets")))


def resolve_scene_path(path: str | Path | None) -> Path:
    """A scene file from a path, or a preset name such as 'thesis_fast'; None is the default towel."""
    if path is None:
        return preset_dir() / "towel.toml"
    return resolve_preset_path(path, preset_dir(), "scene")


def resolve_preset_path(path: str | Path, folder: Path, what: str) -> Path:
    """``path`` if it is a file, else the preset ``folder``/NAME.toml it names; a FileNotFoundError naming
    the nearest presets (``what``: 'scene', 'study') if neither exists."""
    candidate = Path(path)
    if candidate.exists():
        return candidate
    preset = folder / (candidate.name if candidate.suffix == ".toml" else candidate.name + ".toml")
    if len(candidate.parts) == 1 and preset.exists():  # a bare name; a missing path names no preset
        return preset
    names = sorted(p.stem for p in folder.glob("*.toml"))
    hint = did_you_mean(candidate.stem, names, what=f"{what} preset", listing="presets: " + ", ".join(names))
    raise FileNotFoundError(f"{what} {str(path)!r} is not a file: {hint}")


def read_toml(path: Path, what: str = "scene file") -> dict[str, Any]:
    """A TOML file's contents; a ConfigError naming the file (``what``: 'scene file', 'study file')
    if it cannot be read or parsed."""
    try:
        with open(path, "rb") as fh:  # utf-8-sig: the byte-order mark some editors write (Notepad) is no text
            data = tomllib.loads(fh.read().decode("utf-8-sig"))
        huge = list(_beyond_floats(data))
        if not huge:
            return data
        message = f"'{huge[0]}' is a whole number beyond 1.8e308, outside every range ({len(huge)} such numbers)"
    except UnicodeDecodeError as exc:
        message = f"not a text (TOML) file: byte {exc.object[exc.start]:#04x} at position {exc.start} is not UTF-8"
    except ValueError as exc:  # TOMLDecodeError, and an integer of more digits than Python converts
        message = f"not valid TOML: {exc}"
    except OSError as exc:
        message = f"cannot be read: {exc.strerror or exc}"
    raise ConfigError(str(path), message, label=what)


def _beyond_floats(value, key: str = ""):
    """The keys (dotted; a list's items as key[i]) of whole numbers in TOML ``value`` too large for a
    float, which every check of a number would fail on."""
    if isinstance(value, dict):
        for name, item in value.items():
            yield from _beyond_floats(item, f"{key}.{name}" if key else name)
    elif isinstance(value, list):
        for i, item in enumerate(value):
            yield from _beyond_floats(item, f"{key}[{i}]")
    elif isinstance(value, int) and abs(value) > sys.float_info.max:
        yield key


#: The arrays of tables of a scene file ([[collider]], [[grip_key]]), read into flattened names
#: (collider1_shape, grip_key2_time, ...), and what each is called in errors.
TABLE_LISTS = {"collider": "colliders are [[collider]] tables", "grip_key": "grip keys are [[grip_key]] tables",
               "collider_key": "collider keys are [[collider_key]] tables"}


def _flattened_tables(key: str, value, folder: Path, mistakes: Mistakes) -> dict[str, Any]:
    """The fields of an array of tables ``key`` as flattened names (<key><k>_<field>), each checked; a
    collider's file relative to the scene file's ``folder``."""
    if not isinstance(value, list) or not all(isinstance(t, dict) for t in value):
        raise ParameterError(key, f"{TABLE_LISTS[key]} (an array of tables)")
    out = {}
    for k, table in enumerate(value, 1):
        if not table:  # it would vanish, and the tables after it would be numbered one less
            with mistakes.collect():
                raise ParameterError(f"{key}{k}", f"[[{key}]] table {k} is empty: give its fields, or delete it")
        for name, item in table.items():
            with mistakes.collect():
                flat = f"{key}{k}_{name}"
                out[flat] = check_value(flat, item)
                if key == "collider" and name == "file":
                    out[flat] = resolve(out[flat], folder)
    return out


def read_scene_file(path: str | Path | None) -> dict[str, Any]:
    """A scene file's contents, checked whole: parameters (normalised), ``description`` and the
    ``[run]`` table (see ``wetcloth.run_settings``).  A ConfigError names the file and every mistake."""
    resolved = resolve_scene_path(path)
    data = read_toml(resolved)
    mistakes = Mistakes(f"scene file {resolved}")
    for key, value in list(data.items()):
        with mistakes.collect():
            if key == "run":
                data[key] = check_run_table(value)
            elif key in TABLE_LISTS:
                del data[key]
                data.update(_flattened_tables(key, value, resolved.parent, mistakes))
            elif key == "description":
                if not isinstance(value, str):
                    raise ParameterError(key, f"must be text, got {value!r}")
            elif key in RUN_SETTINGS:
                raise ParameterError(key, f"is a run setting: put it in the [run] table ({key} = {value!r} under [run])")
            else:
                data[key] = check_value(key, value)
                if key == "cloth_mesh":  # relative to the scene file's folder
                    data[key] = resolve(data[key], resolved.parent)
    mistakes.raise_if_any()
    return data


def load_scene(path: str | Path | None = None, **overrides) -> Scene:
    """Load a scene from TOML (default: the towel preset), with parameter overrides."""
    data = read_scene_file(path)
    values = {k: v for k, v in data.items() if k not in RESERVED_KEYS}
    return from_dict(_overridden(values, overrides))


def _overridden(values: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """``values`` with ``overrides``: a new ``colliders``, ``grip_keys`` or ``collider_keys`` replaces the whole
    table list (its flattened names in ``values`` dropped; ``colliders=()``: none)."""
    for table, prefix in (("colliders", "collider"), ("grip_keys", "grip_key"), ("collider_keys", "collider_key")):
        if table in overrides:
            values = {name: v for name, v in values.items() if not re.fullmatch(rf"{prefix}[0-9]+_.+", name)}
    return values | overrides
