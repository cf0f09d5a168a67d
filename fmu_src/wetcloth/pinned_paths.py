"""Whether keys carry a pinned particle into a collider (docs/model.md section 6.3): refused at validation.

A pinned particle follows the grip, so no collider can push it out: a collider keyed through the pinned
edge, or a grip keyed into a collider, would crush the free cloth beside it into the collider's surface in
a pile of layers that self-collision then takes minutes to keep apart, and the pinned edge stays inside.
The check samples the motion between consecutive key times (of the collider and of the grip) so finely
that no point of the collider, nor a pinned particle, moves more than half the cloth's thickness between
samples, at most ``SAMPLES_MAX`` per interval, and asks the core for each pinned particle's signed
distance there.  An open mesh (a shell) has no inside and is not checked.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth.errors import ParameterError
from wetcloth.scene import Scene, collider_key_rows, turn_between

#: The most samples per interval between consecutive key times.
SAMPLES_MAX = 4096


def check_pinned_outside(scene: Scene, positions: np.ndarray, pinned: np.ndarray) -> None:
    """Raise ParameterError if a collider's keys or the grip's carry a pinned particle (``pinned`` (n,)
    bool of the particles at ``positions`` (3, n) m, t = 0) inside a collider, naming the key that does."""
    if not pinned.any() or not scene.colliders or not (scene.collider_keys or scene.grip_keys):
        return
    from wetcloth import _core
    from wetcloth.collider_meshes import is_closed, mesh_of, meshes_of

    rows, meshes = meshes_of(scene.colliders)
    keys = collider_key_rows(scene.collider_keys)
    pins = np.ascontiguousarray(positions[:, pinned])
    for k, collider in enumerate(scene.colliders):
        if collider.shape == "mesh" and not is_closed(mesh_of(collider)[1]):
            continue
        own = [(j, key) for j, key in enumerate(scene.collider_keys, 1) if key.collider == k + 1]
        if not own and not scene.grip_keys:
            continue
        centre = np.array([collider.x, collider.y, collider.z])
        reach = (float(np.linalg.norm(pins - centre[:, None], axis=0).max()) + _path_length(scene.grip_keys)
                 + _path_length([key for _, key in own]))
        first, deepest = None, 0.0  # (t, start position) of the first sample with a pinned particle inside; depth
        for t in _sample_times(scene, [key for _, key in own], reach):
            points = np.ascontiguousarray(pins + _grip_at(scene, t)[:, None])
            distance, normal = np.zeros(points.shape[1]), np.zeros_like(points)
            _core.collider_distance(rows, meshes, k, points, 1.0, distance, normal, keys, float(t))
            inside = int(np.argmin(distance))
            if distance[inside] < 0.0:
                first = first or (float(t), pins[:, inside])
                deepest = max(deepest, float(-distance[inside]))
        if first is not None:
            raise _refusal(scene, k, own, *first, deepest)


def _grip_at(scene: Scene, t: float) -> np.ndarray:
    """The grip keys' displacement (3, m) at t (s): 0 at t = 0, linear between keys, the last key's after it."""
    if not scene.grip_keys:
        return np.zeros(3)
    times = [0.0] + [key.time for key in scene.grip_keys]
    return np.array([np.interp(t, times, [0.0] + [getattr(key, c) for key in scene.grip_keys]) for c in "xyz"])


def _path_length(keys) -> float:
    """The length (m) of the path from 0 through the keys' displacements (x, y, z)."""
    at = [np.zeros(3)] + [np.array([key.x, key.y, key.z]) for key in keys]
    return float(sum(np.linalg.norm(b - a) for a, b in zip(at, at[1:])))


def _sample_times(scene: Scene, own: list, reach: float) -> np.ndarray:
    """Times (s) from 0 to the last key, each interval between consecutive key times (the collider's ``own``
    and the grip's) cut so finely that neither the collider's surface within ``reach`` (m) of its centre nor
    the grip moves more than half the thickness between samples."""
    spacing = 0.5 * scene.thickness
    collider_times = [0.0] + [key.time for key in own]
    places = [np.zeros(3)] + [np.array([key.x, key.y, key.z]) for key in own]
    turns = [(0.0, 0.0, 0.0)] + [(key.rx, key.ry, key.rz) for key in own]
    edges = sorted({0.0, *collider_times[1:], *(key.time for key in scene.grip_keys)})
    out = []
    for a, b in zip(edges, edges[1:]):
        j = int(np.searchsorted(collider_times, b))  # the collider's key interval (j-1, j) holds (a, b); none past it
        collider = 0.0
        if j < len(collider_times):
            fraction = (b - a) / (collider_times[j] - collider_times[j - 1])
            turn = math.radians(turn_between(turns[j - 1], turns[j]))
            collider = fraction * (float(np.linalg.norm(places[j] - places[j - 1])) + turn * reach)
        travel = collider + float(np.linalg.norm(_grip_at(scene, b) - _grip_at(scene, a)))
        count = min(SAMPLES_MAX, max(1, math.ceil(travel / spacing)))
        out.append(np.linspace(a, b, count, endpoint=False))
    out.append(np.array([edges[-1]]))
    return np.concatenate(out)


def _refusal(scene: Scene, k: int, own: list, t: float, start: np.ndarray, depth: float) -> ParameterError:
    """The error for a pinned particle (at ``start`` (3, m) at t = 0) inside collider k (from 0) from t (s), up
    to ``depth`` m: named after the collider's key (numbered ``own``) that ends the interval holding t, or the
    grip's if the collider is not keyed."""
    def ending(numbered: list) -> int:  # the number of the first key at or after t (the last, past them all)
        return next((j for j, key in numbered if key.time >= t), numbered[-1][0])

    name = (f"collider_key{ending(own)}" if own else f"grip_key{ending(list(enumerate(scene.grip_keys, 1)))}")
    mover = "the collider's keys" if own else "the grip's keys"
    return ParameterError(
        name, f"{mover} carry a pinned particle (at ({start[0]:.4g}, {start[1]:.4g}, {start[2]:.4g}) m at t = 0) "
              f"into collider {k + 1} (a {scene.colliders[k].shape}) from t = {t:.4g} s, up to {depth:.3g} m deep, "
              f"and nothing can push a pinned particle out; allowed: keys that keep every pinned particle outside "
              f"every collider")
