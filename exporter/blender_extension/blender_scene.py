"""The Blender scene as wetcloth sees it: one ``ClothJob`` (a Scene and where its cache goes) per Cloth object.

Geometry is read in world space at the first frame of the scene's range: the Cloth object's mesh
as stored (its modifiers apply after the cache) gives the grid or the mesh cloth (``geometry.cloth_of``),
handed to wetcloth as arrays in Blender's vertex order; Collider objects' evaluated meshes the
analytic or mesh colliders (``geometry.collider_of``, their triangles as arrays; an animated one's
moves as a collider key at every frame), the Water plane ``water_level`` (and, if it is animated, the
level over every frame).  Positions are read in metres (``world_matrix``: Blender units times the
scene's Unit Scale), and the cache is written back in the object's own coordinates.  The cloth's
object stands still over the range (``check_still``).  Parameters come from
``scene.wetcloth`` and the cloth's ``obj.wetcloth``; Blender keeps them as 32-bit floats, which
are read back as the shortest decimal that rounds to them (0.45, not 0.4499999881).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, replace

import bpy
import numpy as np

from wetcloth.exporter.blender_extension.caches import cache_names
from wetcloth.exporter.blender_extension.geometry import GridCloth, MeshCloth, cloth_of, collider_of
from wetcloth.errors import ParameterError
from wetcloth.exporter.blender_extension.parameters import FABRIC, FROM_CLOTH, SCENE
from wetcloth.scene import MAX_KEY_TURN, Scene, from_dict, rotation_matrix, rotation_vector

#: The scene settings the bake follows when they change over the frame range (as grip keys at every frame).
GRIP = ("grip_x", "grip_y", "grip_z")
#: What the scene parameters the Cloth object sets (parameters.FROM_CLOTH) are in Blender, for its refusals.
IN_BLENDER = {"nx": "its mesh", "ny": "its mesh", "width": "its mesh (its size)", "length": "its mesh (its size)",
              "initial_height": "its height (Location Z)", "initial_tilt": "its rotation about x",
              "pinned_edge": "its pin group", "cloth_mesh": "its mesh", "place_mesh": "its mesh",
              "pinned_vertices": "its pin group"}


@dataclass
class ClothJob:
    """One cloth to bake: its object, scene, cloth (grid or mesh) and where its USD file goes."""

    obj: bpy.types.Object
    scene: Scene
    cloth: GridCloth | MeshCloth
    directory: str  # absolute
    prefix: str
    to_local: np.ndarray
    water_levels: list | None


def clean(value):
    """A value Blender stored as float32, as the shortest decimal that rounds to it; others unchanged."""
    if isinstance(value, float):
        return float(str(np.float32(value)))
    return value


def world_matrix(obj) -> np.ndarray:
    """The object's 4 x 4 matrix from its coordinates to world space in metres: ``matrix_world`` (to Blender
    units) times the scene's *Unit Scale* (Scene > Units: metres per Blender unit)."""
    metres = clean(bpy.context.scene.unit_settings.scale_length)
    return np.diag([metres, metres, metres, 1.0]) @ np.array(obj.matrix_world)


def _vertices(obj, mesh) -> tuple[np.ndarray, np.ndarray]:
    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    edges = np.empty(len(mesh.edges) * 2, dtype=np.int64)
    mesh.edges.foreach_get("vertices", edges)
    matrix = world_matrix(obj)
    return co.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3], edges.reshape(-1, 2)


def _triangles(mesh) -> tuple[np.ndarray, np.ndarray]:
    """The mesh's loop triangles' vertices (t, 3) and the face (t,) each splits."""
    mesh.calc_loop_triangles()
    triangles = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int64)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    faces = np.empty(len(mesh.loop_triangles), dtype=np.int64)
    mesh.loop_triangles.foreach_get("polygon_index", faces)
    return triangles.reshape(-1, 3), faces


def world_vertices(obj, depsgraph, triangles: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The evaluated mesh's vertex positions (n, 3) in world space (m) and edges (e, 2), or
    (``triangles``) its triangles (t, 3)."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        points, edges = _vertices(obj, mesh)
        return (points, _triangles(mesh)[0]) if triangles else (points, edges)
    finally:
        evaluated.to_mesh_clear()


def cloth_mesh(obj) -> tuple:
    """The cloth: its mesh as stored, in world space (m), its edges, its faces (corner counts, corner
    vertices) and loop triangles (vertices, faces), as geometry.cloth_of takes them.
    Not the evaluated mesh: the cache modifier comes first in the stack, so the object's own modifiers
    (Subdivision, Solidify) apply to the baked cloth, not to the mesh it is baked from."""
    mesh = obj.data
    positions, edges = _vertices(obj, mesh)
    sizes = np.empty(len(mesh.polygons), dtype=np.int64)
    mesh.polygons.foreach_get("loop_total", sizes)
    loops = np.empty(len(mesh.loops), dtype=np.int64)
    mesh.loops.foreach_get("vertex_index", loops)
    return positions, edges, (sizes, loops), _triangles(mesh)


def cloth_uv(obj) -> np.ndarray | None:
    """The cloth's active UV map, per face corner (corners, 2), or None without one."""
    layer = obj.data.uv_layers.active
    if layer is None:
        return None
    uv = np.empty(len(obj.data.loops) * 2)
    layer.data.foreach_get("uv", uv)
    return uv.reshape(-1, 2)


def pin_members(obj) -> list[int]:
    """The vertices of the cloth's pin group (weight above 0); ValueError if the group is missing."""
    if not obj.wetcloth.pin_group:
        return []
    group = obj.vertex_groups.get(obj.wetcloth.pin_group)
    if group is None:
        raise ValueError(f"cloth {obj.name!r}: no vertex group {obj.wetcloth.pin_group!r} (Pin group)")
    return [v.index for v in obj.data.vertices if any(g.group == group.index and g.weight > 0 for g in v.groups)]


def cache_directory(scene) -> str:
    """The absolute cache folder; ValueError for a folder relative to an unsaved .blend."""
    folder = scene.wetcloth.cache_directory
    if folder.startswith("//") and not bpy.data.filepath:
        raise ValueError("save the .blend file first: the bake writes its cache beside it "
                         f"(scene.wetcloth.cache_directory = {folder!r})")
    return os.path.normpath(bpy.path.abspath(folder))


def _water(scene, waters, depsgraph) -> tuple[float, list | None]:
    """The water level at the first frame and, if the Water object is animated, over every frame."""
    if not waters:
        return clean(scene.wetcloth.water_level), None
    if len(waters) > 1:
        raise ValueError(f"{len(waters)} objects have the role Water surface "
                         f"({', '.join(o.name for o in waters)}); there is one water surface")
    water = waters[0]
    if water.type != "MESH":
        raise ValueError(f"water surface {water.name!r} is not a mesh (a horizontal plane)")
    points, _ = world_vertices(water, depsgraph)
    if len(points) == 0 or np.ptp(points[:, 2]) > 1e-4 * max(np.ptp(points, axis=0).max(), 1e-9):
        raise ValueError(f"water surface {water.name!r} is not a horizontal plane (its vertices' heights differ)")
    level = clean(float(points[:, 2].mean()))
    if water.animation_data is None:
        return level, None
    local = np.append(water.data.vertices[0].co, 1.0)  # any vertex: the plane is level
    levels = []
    for frame in range(scene.frame_start, scene.frame_end):  # the level from frame k to k + 1
        scene.frame_set(frame)
        levels.append(clean(float((world_matrix(water) @ local)[2])))
    scene.frame_set(scene.frame_start)
    return level, levels


def _animated(obj) -> bool:
    """Whether the object or one of its parents has animation data (keys or drivers)."""
    while obj is not None:
        if obj.animation_data is not None:
            return True
        obj = obj.parent
    return False


def _collider_keys(scene, obj, number: int, centre) -> list[dict]:
    """Collider ``number``'s keys (docs/interface.md, collider keys) if the object is animated: at every
    later frame of the range, at (frame - frame_start) / fps s, its turn R from the first frame as a rotation
    vector (rx, ry, rz, deg; unwrapped: the representative nearest the previous frame's) and the
    displacement (m) of its centre (3, m: its collider's x, y, z at the first frame), R c + b - c for the
    frame's world motion p -> R p + b; none if it neither moves nor turns.  ValueError if it scales or turns
    by 179 deg or more between frames."""
    if not _animated(obj):
        return []
    fps = scene.render.fps / scene.render.fps_base
    scene.frame_set(scene.frame_start)
    to_first = np.linalg.inv(world_matrix(obj))
    c = np.asarray(centre, dtype=np.float64)
    keys, previous = [], np.zeros(3)
    for frame in range(scene.frame_start + 1, scene.frame_end + 1):
        scene.frame_set(frame)
        motion = world_matrix(obj) @ to_first  # world at the first frame -> world at this one (m)
        turn, shift = motion[:3, :3], motion[:3, 3]
        if np.abs(turn.T @ turn - np.eye(3)).max() > 1e-6 or np.linalg.det(turn) < 0.0:
            scene.frame_set(scene.frame_start)
            raise ValueError(f"collider {obj.name!r} scales at frame {frame}: colliders move and turn only "
                             "(its scale stays as at the first frame)")
        vector = _unwrapped(rotation_vector(turn), previous)
        if np.degrees(np.linalg.norm(rotation_vector(turn @ rotation_matrix(previous).T))) >= MAX_KEY_TURN:
            scene.frame_set(scene.frame_start)
            raise ValueError(f"collider {obj.name!r} turns by {MAX_KEY_TURN:g} deg or more between frames {frame - 1} "
                             f"and {frame}: at most that between frames (more frames per second)")
        previous = vector
        x, y, z = turn @ c + shift - c
        rx, ry, rz = np.degrees(vector)
        keys.append({"collider": number, "time": (frame - scene.frame_start) / fps,
                     "x": clean(float(x)), "y": clean(float(y)), "z": clean(float(z)),
                     "rx": clean(float(rx)), "ry": clean(float(ry)), "rz": clean(float(rz))})
    scene.frame_set(scene.frame_start)
    fields = ("x", "y", "z", "rx", "ry", "rz")
    return keys if any(k[f] for k in keys for f in fields) else []


def _settings(scene, cloths, colliders) -> dict:
    """Every setting the bake reads (scene.wetcloth's scene parameters, each cloth's fabric and each
    collider's friction) as it is now, by a name that says where it lives."""
    values = {f"scene setting {name!r}": getattr(scene.wetcloth, name) for name in SCENE}
    for obj in cloths:
        values |= {f"cloth {obj.name!r}'s setting {name!r}": getattr(obj.wetcloth, name) for name in FABRIC}
    for obj in colliders:
        values[f"collider {obj.name!r}'s setting 'friction'"] = obj.wetcloth.friction
    return values


def _grip_keys(scene, cloths, colliders) -> list[dict]:
    """The grip keys (docs/interface.md, grip keys) if the grip (GRIP) changes over the frame range (keys or
    drivers): at every later frame, at (frame - frame_start) / fps s, the grip's x, y, z there (m); none if
    it does not change.  ValueError naming any other setting (_settings) that changes: the bake reads those
    at the first frame only."""
    if scene.animation_data is None and not any(o.animation_data for o in cloths + colliders):
        return []
    fps = scene.render.fps / scene.render.fps_base
    scene.frame_set(scene.frame_start)
    first = _settings(scene, cloths, colliders)
    grips = [f"scene setting {name!r}" for name in GRIP]
    keys, moves = [], False
    for frame in range(scene.frame_start + 1, scene.frame_end + 1):
        scene.frame_set(frame)
        now = _settings(scene, cloths, colliders)
        moves = moves or any(now[name] != first[name] for name in grips)
        changed = [name for name, value in now.items() if value != first[name] and name not in grips]
        if changed:
            scene.frame_set(scene.frame_start)
            raise ValueError(f"{changed[0]} changes at frame {frame} (keys or a driver): the bake reads it at the "
                             f"first frame only; of the settings only {', '.join(GRIP)} may change (a water level "
                             "that changes: key a Water surface object)")
        x, y, z = (clean(now[name]) for name in grips)
        keys.append({"time": (frame - scene.frame_start) / fps, "x": x, "y": y, "z": z})
    scene.frame_set(scene.frame_start)
    return keys if moves else []


def _unwrapped(vector, previous) -> np.ndarray:
    """Of the rotation vectors of one rotation, vector + 2 pi k axis (k whole), the nearest to previous (3, rad)."""
    angle = float(np.linalg.norm(vector))
    if angle == 0.0:
        axis = previous / np.linalg.norm(previous) if np.linalg.norm(previous) > 0.0 else np.zeros(3)
    else:
        axis = vector / angle
    reach = round(float(np.linalg.norm(previous)) / (2 * math.pi)) + 1
    candidates = [vector + 2 * math.pi * k * axis for k in range(-reach, reach + 1)]
    return min(candidates, key=lambda v: float(np.linalg.norm(v - previous)))


def check_still(scene, cloths) -> None:
    """ValueError naming a cloth whose object moves, turns or scales over the frame range (keys, drivers,
    constraints or a parent's): the bake simulates it from the first frame and plays it where it stands."""
    moving = [o for o in cloths if _animated(o) or len(o.constraints)]
    if not moving:
        return
    scene.frame_set(scene.frame_start)
    first = [np.array(o.matrix_world) for o in moving]
    for frame in range(scene.frame_start + 1, scene.frame_end + 1):
        scene.frame_set(frame)
        for obj, matrix in zip(moving, first):
            if not np.array_equal(np.array(obj.matrix_world), matrix):
                scene.frame_set(scene.frame_start)
                raise ValueError(f"cloth {obj.name!r} moves at frame {frame} (its location, rotation or scale is "
                                 "keyed or driven, or its parent's): the bake drapes the cloth from where it is at "
                                 "the first frame and plays it there; bake with the cloth's object still (to move "
                                 "the cloth, pin it and key the grip, or key the colliders)")
    scene.frame_set(scene.frame_start)


def check_above_floor(obj, positions, thickness: float, floor_level: float) -> None:
    """ValueError naming the cloth if a vertex (world ``positions`` (n, 3), m) is not above the floor by
    half the fabric's thickness."""
    lowest = float(positions[:, 2].min())
    if lowest - 0.5 * thickness <= floor_level:
        raise ValueError(f"cloth {obj.name!r} starts at or below the floor: its lowest vertex is at z = {lowest:g} m, "
                         f"the scene setting floor_level {floor_level:g} m; allowed: every vertex above floor_level "
                         f"+ thickness/2 = {floor_level + 0.5 * thickness:g} m (raise the object: Location Z, or "
                         "lower floor_level)")


def _setting(name: str, colliders) -> str:
    """Where parameter ``name`` lives in Blender, as a cloth's refusal says it (``colliders``: the Collider
    objects, collider k the k-th)."""
    if name in FABRIC:
        return f"its setting {name!r}"
    if name in FROM_CLOTH:
        return IN_BLENDER[name]
    collider = re.fullmatch(r"collider(\d+)(_friction)?(_\w+)?", name)
    if collider and int(collider[1]) <= len(colliders):
        return f"collider {colliders[int(collider[1]) - 1].name!r}" + ("'s setting 'friction'" if collider[2] else "")
    if name.startswith(("collider_key", "grip_key")):
        return "the colliders' motion" if name.startswith("collider_key") else f"the grip's keys ({', '.join(GRIP)})"
    return f"scene setting {name!r}"


def _in_blender(message: str) -> str:
    """A wetcloth message with the scene parameters the Cloth object sets (IN_BLENDER; those with an '_', not
    words such as 'length') said as Blender's."""
    names = "|".join(name for name in IN_BLENDER if "_" in name)
    return re.sub(rf"\b({names})\b", lambda found: f"the cloth's {IN_BLENDER[found[1]].removeprefix('its ')}",
                  message)


def scene_of(obj, values: dict, colliders) -> Scene:
    """The cloth's wetcloth Scene of parameter ``values``; a ValueError naming the cloth and, for each
    mistake, the setting or object at fault (``colliders``: the Collider objects in order)."""
    try:
        return from_dict(values)
    except ParameterError as exc:
        raise ValueError("; ".join(f"cloth {obj.name!r}, {_setting(name, colliders)}: {_in_blender(message)}"
                                   for _, name, message in exc.problems)) from None


def cloth_jobs(context) -> list[ClothJob]:
    """One job per Cloth object of the scene; ValueError naming the object or parameter at fault."""
    scene = context.scene
    objects = [o for o in scene.objects if o.wetcloth.role != "NONE"]
    cloths = [o for o in objects if o.wetcloth.role == "CLOTH"]
    if not cloths:
        raise ValueError("no object has the role Cloth (Physics properties > Wet Cloth > Role)")
    for obj in cloths:
        if obj.type != "MESH":
            raise ValueError(f"cloth {obj.name!r} is not a mesh")
    check_still(scene, cloths)
    scene.frame_set(scene.frame_start)
    depsgraph = context.evaluated_depsgraph_get()
    depsgraph.update()
    water_level, water_levels = _water(scene, [o for o in objects if o.wetcloth.role == "WATER"], depsgraph)
    colliders, collider_keys = [], []
    collider_objects = [o for o in objects if o.wetcloth.role == "COLLIDER"]
    for obj in collider_objects:
        if obj.type != "MESH":
            raise ValueError(f"collider {obj.name!r} is not a mesh")
        collider = collider_of(*world_vertices(obj, depsgraph, triangles=True), obj.name)
        colliders.append({key: clean(value) for key, value in collider.items()} | {"friction": clean(obj.wetcloth.friction)})
        collider_keys += _collider_keys(scene, obj, len(colliders), (collider["x"], collider["y"], collider["z"]))
    grip_keys = _grip_keys(scene, cloths, collider_objects)
    settings = {name: clean(getattr(scene.wetcloth, name)) for name in SCENE} | {"water_level": water_level}
    if grip_keys:  # the keys hold the whole grip
        settings |= {name: 0.0 for name in GRIP}
    directory = cache_directory(scene)
    prefixes = cache_names([obj.name for obj in cloths])
    jobs = []
    for obj in cloths:
        members = pin_members(obj)
        mesh = cloth_mesh(obj)
        cloth, pins = cloth_of(*mesh, members, obj.name, cloth_uv(obj))
        if isinstance(cloth, GridCloth):
            cloth = replace(cloth, width=clean(cloth.width), length=clean(cloth.length),
                            centre=tuple(clean(c) for c in cloth.centre), tilt=clean(cloth.tilt))
        fabric = {name: clean(getattr(obj.wetcloth, name)) for name in FABRIC}
        check_above_floor(obj, mesh[0], fabric["thickness"], settings["floor_level"])
        shift = cloth.shift
        moved = [c | {"x": clean(c["x"] - shift[0]), "y": clean(c["y"] - shift[1])} for c in colliders]
        gripped = grip_keys if members else []  # the grip moves pins: a cloth without any takes no keys
        values = settings | fabric | cloth.scene_values() | {"pinned_edge": pins, "colliders": moved,
                                                             "collider_keys": collider_keys, "grip_keys": gripped}
        prefix = prefixes[obj.name]
        jobs.append(ClothJob(obj=obj, scene=scene_of(obj, values, collider_objects), cloth=cloth,
                             directory=os.path.join(directory, prefix), prefix=prefix,
                             to_local=np.linalg.inv(world_matrix(obj)), water_levels=water_levels))
    return jobs
