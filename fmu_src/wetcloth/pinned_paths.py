"""Whether keys carry a pinned particle into a collider (docs/model.md section 6.3): refused at validation.

A pinned particle follows the grip, so no collider can push it out: a collider keyed through the pinned
edge, or a grip keyed into a collider, would crush the free cloth beside it into the collider's surface in
a pile of layers that self-collision then takes minutes to keep apart, and the pinned edge stays inside.

The check walks each interval between consecutive key times (the collider's and the grip's: the motion is
uniform within one) by conservative advancement.  A signed distance changes no faster than the pinned
particle moves relative to the collider's surface, at most ``speed``: the collider's velocity, its angular
velocity times the particles' greatest distance from its centre, and the grip's velocity.  So from a
sample whose least distance is ``d`` no particle reaches the surface within ``|d| / speed``; the next sample
lies that far on, or half the cloth's thickness of motion on if that is farther (a particle may dip less
than that deep unseen, as the contact keeps the free cloth that far off), at most ``SAMPLES_MAX`` samples
an interval.  The core gives the distances where the keys have moved the collider.  An open mesh (a
shell) has no inside and is not checked.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth.errors import ParameterError
from wetcloth.scene import Scene, collider_key_rows, grip_key_rows, turn_between

#: The most samples in one interval between consecutive key times.
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
    grip = grip_key_rows(scene.grip_keys)
    pins = np.ascontiguousarray(positions[:, pinned])
    for k, collider in enumerate(scene.colliders):
        if collider.shape == "mesh" and not is_closed(mesh_of(collider)[1]):
            continue
        own = [(j, key) for j, key in enumerate(scene.collider_keys, 1) if key.collider == k + 1]
        if not own and not scene.grip_keys:
            continue

        def least_distance(t: float) -> tuple[float, int]:
            """The pinned particles' least signed distance (m) from the collider at t (s), and whose it is."""
            points = np.ascontiguousarray(pins + _grip_at(grip, t)[:, None])
            distance, normal = np.zeros(points.shape[1]), np.zeros_like(points)
            _core.collider_distance(rows, meshes, k, points, 1.0, distance, normal, keys, t)
            i = int(np.argmin(distance))
            return float(distance[i]), i

        centre = np.array([collider.x, collider.y, collider.z])
        reach = (float(np.linalg.norm(pins - centre[:, None], axis=0).max()) + _path_length(scene.grip_keys)
                 + _path_length([key for _, key in own]))
        first, deepest = None, 0.0  # (t, start position) of the first sample with a pinned particle inside; depth
        for a, b, speed in _intervals(scene, grip, [key for _, key in own], reach):
            t, samples = a, 0
            while True:
                d, i = least_distance(t)
                if d < 0.0:
                    first = first or (t, pins[:, i])
                    deepest = max(deepest, -d)
                samples += 1
                if t >= b:
                    break
                wait = max(abs(d), 0.5 * scene.thickness) / speed if speed > 0.0 else math.inf
                t = b if samples == SAMPLES_MAX - 1 else min(b, t + wait)
        if first is not None:
            raise _refusal(scene, k, own, *first, deepest)


def _grip_at(grip: np.ndarray, t: float) -> np.ndarray:
    """The displacement (3, m) at t (s) of the grip keys ``grip`` (rows of grip_key_rows), as the core moves the
    grip: 0 at t = 0, linear between keys, the last key's after it."""
    if not len(grip):
        return np.zeros(3)
    from wetcloth import _core

    return np.array(_core.grip_key_displacement(grip, t))


def _path_length(keys) -> float:
    """The length (m) of the path from 0 through the keys' displacements (x, y, z)."""
    at = [np.zeros(3)] + [np.array([key.x, key.y, key.z]) for key in keys]
    return float(sum(np.linalg.norm(b - a) for a, b in zip(at, at[1:])))


def _intervals(scene: Scene, grip: np.ndarray, own: list, reach: float) -> list[tuple[float, float, float]]:
    """(start, end, speed): the intervals (s) between consecutive key times, the collider's ``own`` and the
    grip's (``grip``: scene's grip_key_rows), from 0 to the last (one of zero length at 0 without any), and the greatest speed (m/s) within
    each of a point within ``reach`` (m) of the collider's centre relative to its surface plus the grip's."""
    collider_times = [0.0] + [key.time for key in own]
    places = [np.zeros(3)] + [np.array([key.x, key.y, key.z]) for key in own]
    turns = [(0.0, 0.0, 0.0)] + [(key.rx, key.ry, key.rz) for key in own]
    edges = sorted({0.0, *collider_times[1:], *(key.time for key in scene.grip_keys)})
    out = [(0.0, 0.0, 0.0)] if len(edges) == 1 else []
    for a, b in zip(edges, edges[1:]):
        j = int(np.searchsorted(collider_times, b))  # the collider's key interval (j-1, j) holds (a, b); none past it
        speed = float(np.linalg.norm(_grip_at(grip, b) - _grip_at(grip, a))) / (b - a)
        if j < len(collider_times):
            span = collider_times[j] - collider_times[j - 1]
            turn = math.radians(turn_between(turns[j - 1], turns[j]))
            speed += (float(np.linalg.norm(places[j] - places[j - 1])) + turn * reach) / span
        out.append((a, b, speed))
    return out


def _refusal(scene: Scene, k: int, own: list, t: float, start: np.ndarray, depth: float) -> ParameterError:
    """The error for a pinned particle (at ``start`` (3, m) at t = 0) inside collider k (from 0) from t (s), at
    least ``depth`` m deep: named after the collider's key (numbered ``own``) that ends the interval holding t,
    or the grip's if the collider is not keyed."""
    def ending(numbered: list) -> int:  # the number of the first key at or after t (the last, past them all)
        return next((j for j, key in numbered if key.time >= t), numbered[-1][0])

    name = (f"collider_key{ending(own)}" if own else f"grip_key{ending(list(enumerate(scene.grip_keys, 1)))}")
    mover = "the collider's keys" if own else "the grip's keys"
    x, y, z = (round(float(c), 9) + 0.0 for c in start)  # (no 2e-17 m from the cloth's tilt; no -0)
    return ParameterError(
        name, f"{mover} carry a pinned particle (at ({x:.4g}, {y:.4g}, {z:.4g}) m at t = 0) "
              f"into collider {k + 1} (a {scene.colliders[k].shape}) from t = {t:.4g} s, at least {depth:.3g} m deep, "
              f"and nothing can push a pinned particle out; allowed: keys that keep every pinned particle outside "
              f"every collider")
