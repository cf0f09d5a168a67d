"""Mesh colliders' arrays for the compiled core (``collider_mesh.cpp``; docs/model.md section 6.3).

A mesh collider is a rigid triangle mesh: a *solid* if it is closed (every edge in two faces, turned
consistently; its faces are then turned outwards), else a *shell*, such as a bucket's wall, that keeps
the cloth off both its sides.  For each mesh the core gets its vertices, its faces' unit normals and
the pseudo-normals of their edges and vertices (which tell inside from outside near an edge or a
corner), and a uniform grid of cells listing the triangles that reach into each, so that a particle
looks only at the triangles near it and a collider the cloth does not come near costs a box test.
"""

from __future__ import annotations

import functools
from collections import namedtuple

import numpy as np

from wetcloth._core import COLLIDER_COLUMNS, MESH_COLUMNS
from wetcloth.errors import ParameterError
from wetcloth.mesh_file import (FORMATS, MeshFile, content_key, fan_triangles, locate, merged, read_faces,
                                triangle_areas)

#: All mesh colliders' arrays, as the core's ColliderMeshes: ``headers`` (k, MESH_COLUMNS) each mesh's
#: first cell, grid origin (m), cell side (m), cells along x, y, z, solid flag and bounding box;
#: ``vertices`` (3, V) m; ``triangles`` (T, 3) int64; unit normals of the faces (T, 3), of their edges
#: (T, 3, 3; edge e from corner e to e + 1) and of the vertices (V, 3); ``cell_start`` (cells + 1) and
#: ``cell_items`` the triangles of each cell.
ColliderMeshes = namedtuple("ColliderMeshes", "headers vertices triangles face_normals edge_normals vertex_normals "
                                              "cell_start cell_items")

#: At most this many cells per mesh (a fine mesh gets cells of several triangles each).
MAX_CELLS = 64 ** 3


def no_meshes() -> ColliderMeshes:
    """The arrays of a scene without mesh colliders."""
    return pack([])


def _unit(v: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, length, out=np.zeros_like(v), where=length > 0)


def is_closed(triangles: np.ndarray, turned: bool = True) -> bool:
    """Whether ``triangles`` (T, 3) are some and every edge of them joins exactly two faces, which (with
    ``turned``) run along it in opposite directions: a closed surface (consistently turned)."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    if not turned:
        return len(t) > 0 and bool((np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)[1] == 2).all())
    unique, counts = np.unique(directed, axis=0, return_counts=True)
    if not len(t) or (counts != 1).any():
        return False  # an edge run the same way twice: inconsistent turns, or more than two faces
    reverse = {tuple(e) for e in unique[:, ::-1]}
    return all(tuple(e) in reverse for e in unique)


def outward(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """A closed mesh's triangles turned so that their normals point out (positive enclosed volume)."""
    a, b, c = (points[triangles[:, k]] for k in range(3))
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    return triangles if volume >= 0 else triangles[:, ::-1].copy()


def normals(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit normals of the faces (T, 3), their edges (T, 3, 3: the mean of the two faces' that share an
    edge; a border edge's own face's) and the vertices (V, 3: weighted by each face's angle there)."""
    corners = [points[triangles[:, k]] for k in range(3)]
    face = _unit(np.cross(corners[1] - corners[0], corners[2] - corners[0]))
    vertex = np.zeros_like(points)
    for k in range(3):
        u = _unit(corners[(k + 1) % 3] - corners[k])
        w = _unit(corners[(k + 2) % 3] - corners[k])
        angle = np.arccos(np.clip(np.einsum("ij,ij->i", u, w), -1.0, 1.0))
        np.add.at(vertex, triangles[:, k], angle[:, None] * face)
    keys = np.sort(np.stack([triangles, np.roll(triangles, -1, axis=1)], axis=2), axis=2).reshape(-1, 2)
    _, edge_id = np.unique(keys, axis=0, return_inverse=True)
    summed = np.zeros((edge_id.max() + 1, 3))
    np.add.at(summed, edge_id, np.repeat(face, 3, axis=0))
    edge = _unit(summed[edge_id]).reshape(-1, 3, 3)
    return face, edge, _unit(vertex)


def _cells(points: np.ndarray, triangles: np.ndarray, lo: np.ndarray, side: float, dims: np.ndarray):
    """Each cell's triangles (those whose box reaches into it), as (start, items) over the dims grid."""
    corners = points[triangles]  # (T, 3, 3)
    first = np.clip(np.floor((corners.min(axis=1) - lo) / side).astype(np.int64), 0, dims - 1)
    last = np.clip(np.floor((corners.max(axis=1) - lo) / side).astype(np.int64), 0, dims - 1)
    cells, items = [], []
    for t in range(len(triangles)):
        x, y, z = (np.arange(first[t, c], last[t, c] + 1) for c in range(3))
        ids = ((z[:, None, None] * dims[1] + y[None, :, None]) * dims[0] + x[None, None, :]).ravel()
        cells.append(ids)
        items.append(np.full(len(ids), t))
    cells, items = np.concatenate(cells), np.concatenate(items)
    order = np.argsort(cells, kind="stable")
    start = np.zeros(int(np.prod(dims)) + 1, dtype=np.int64)
    np.add.at(start, cells + 1, 1)
    return np.cumsum(start), items[order]


def pack(meshes: list[tuple[np.ndarray, np.ndarray]]) -> ColliderMeshes:
    """The core's arrays for ``meshes``, each (points (V, 3) m where the scene puts them, triangles (T, 3))."""
    headers, vertices, triangles, face, edge, vertex, starts, items = [], [], [], [], [], [], [], []
    vertex_offset = triangle_offset = cell_offset = item_offset = 0
    for points, tris in meshes:
        points = np.asarray(points, dtype=np.float64)
        tris = np.asarray(tris, dtype=np.int64)
        solid = is_closed(tris)
        if solid:
            tris = outward(points, tris)
        f, e, v = normals(points, tris)
        lo, hi = points.min(axis=0), points.max(axis=0)
        edges = np.linalg.norm(points[tris] - points[np.roll(tris, -1, axis=1)], axis=2)
        extent = np.maximum(hi - lo, 1e-12)
        side = max(float(np.median(edges)), float(np.prod(extent) / MAX_CELLS) ** (1 / 3), 1e-9)
        dims = np.maximum(np.ceil(extent / side).astype(np.int64), 1)
        while np.prod(dims) > MAX_CELLS:  # a flat or thin mesh's box: coarser cells
            side *= 1.25
            dims = np.maximum(np.ceil(extent / side).astype(np.int64), 1)
        start, listed = _cells(points, tris, lo, side, dims)
        headers.append([cell_offset, *lo, side, *dims, float(solid), *lo, *hi])
        vertices.append(points)
        triangles.append(tris + vertex_offset)
        face.append(f), edge.append(e), vertex.append(v)
        starts.append(start[:-1] + item_offset)
        items.append(listed + triangle_offset)
        item_offset += len(listed)
        vertex_offset += len(points)
        triangle_offset += len(tris)
        cell_offset += int(np.prod(dims))
    return ColliderMeshes(
        headers=np.array(headers, dtype=np.float64).reshape(-1, MESH_COLUMNS),
        vertices=np.ascontiguousarray(np.concatenate(vertices).T if vertices else np.zeros((3, 0))),
        triangles=np.concatenate(triangles) if triangles else np.zeros((0, 3), dtype=np.int64),
        face_normals=np.concatenate(face) if face else np.zeros((0, 3)),
        edge_normals=np.concatenate(edge) if edge else np.zeros((0, 3, 3)),
        vertex_normals=np.concatenate(vertex) if vertex else np.zeros((0, 3)),
        cell_start=np.append(np.concatenate(starts), item_offset).astype(np.int64) if starts else np.zeros(1, np.int64),
        cell_items=np.concatenate(items).astype(np.int64) if items else np.zeros(0, np.int64),
    )


def mesh_of(collider, name: str = "collider_file") -> tuple[np.ndarray, np.ndarray]:
    """A mesh collider's points (V, 3) m, moved by its x, y, z, and triangles (T, 3), from its file
    (read as a cloth's is, mesh_file.read_faces; faces of any number of corners fanned into triangles,
    exactly equal vertices merged so that a closed surface reads as closed) or its surface given as
    arrays (mesh_file.surface: as given); faces of no area left out.  A ParameterError names ``name`` for a file that is missing, unreadable or has no faces,
    and for arrays without faces or with indices out of range."""
    if isinstance(collider.file, MeshFile):
        points, triangles = _given(collider.file, name)
        return points + np.array([collider.x, collider.y, collider.z]), triangles
    path = locate(collider.file) if collider.file else None
    try:
        digest = content_key(path) if path is not None and path.is_file() else None
    except OSError as exc:
        raise ParameterError(name, f"{str(path)!r} cannot be read: {exc.strerror or exc}; "
                                   f"allowed: the path of a mesh file ({FORMATS})") from None
    if digest is None:
        raise ParameterError(name, f"a mesh collider needs its mesh file; {str(collider.file)!r} is not a file; "
                                   f"allowed: the path of a mesh file ({FORMATS})")
    points, triangles = _read(str(path.resolve()), digest, name)
    return points + np.array([collider.x, collider.y, collider.z]), triangles


@functools.lru_cache(maxsize=8)
def _read(path: str, digest: str, name: str) -> tuple[np.ndarray, np.ndarray]:
    allowed = "a mesh file (" + FORMATS + ") of faces"
    points, blocks, _, _ = read_faces(path, path, name, allowed)
    blocks = [b for b in blocks if len(b)]
    faces = fan_triangles(blocks)[0] if blocks else np.zeros((0, 3), dtype=np.int64)
    return _with_area(*merged(points, faces), repr(path), allowed, name)


def _with_area(points: np.ndarray, faces: np.ndarray, shown: str, allowed: str, name: str):
    """``points`` and the ``faces`` that have an area; a ParameterError naming ``name`` if none has or a
    coordinate is not a finite number."""
    if len(faces):
        faces = faces[triangle_areas(points, faces) > 0.0]
    if not len(faces) or not np.isfinite(points).all():
        raise ParameterError(name, f"{shown} has no faces with an area, or coordinates that are not finite numbers; "
                                   f"allowed: {allowed}")
    points.flags.writeable = faces.flags.writeable = False  # shared by every reader (a cached file)
    return points, faces


def _given(mesh, name: str) -> tuple[np.ndarray, np.ndarray]:
    """The points and triangles with an area of a surface given as arrays (mesh_file.surface)."""
    allowed = "a surface of points (V, 3) and triangles (T, 3) indexing them (wetcloth.mesh_file.surface)"
    points, faces = np.array(mesh.points, dtype=np.float64), np.array(mesh.triangles, dtype=np.int64)
    if points.ndim != 2 or points.shape[1] != 3 or (len(faces) and (faces.min() < 0 or faces.max() >= len(points))):
        raise ParameterError(name, f"{mesh.source}: points of shape {points.shape} and triangles whose indices are "
                                   f"not all in 0..{len(points) - 1}; allowed: {allowed}")
    return _with_area(points, faces, mesh.source, allowed, name)


def meshes_of(colliders) -> tuple[np.ndarray, ColliderMeshes]:
    """The core's collider rows (k, 13) of a scene's ``colliders`` and its mesh colliders' arrays (each mesh
    collider's row holds its index among them in the radius column)."""
    rows = np.array([c.row() for c in colliders], dtype=np.float64).reshape(-1, COLLIDER_COLUMNS)
    meshes = []
    for k, collider in enumerate(colliders):
        if collider.shape == "mesh":
            rows[k, 4] = len(meshes)
            meshes.append(mesh_of(collider, f"collider{k + 1}_file"))
    return rows, _packed(_key(meshes)) if meshes else no_meshes()


@functools.lru_cache(maxsize=4)
def _packed(key) -> ColliderMeshes:
    """pack() of the meshes in key (their bytes and shapes): a scene whose other parameters change (an FMU
    input) reuses the same arrays."""
    return pack([(np.frombuffer(p).reshape(ps), np.frombuffer(t, dtype=np.int64).reshape(ts)) for p, t, ps, ts in key])


def distance_to_mesh(collider, points: np.ndarray, reach: float) -> np.ndarray:
    """The core's signed distance (m) of points (3, m) from mesh collider ``collider``'s surface, up to
    ``reach`` m (farther points get reach)."""
    from wetcloth import _core

    row = np.zeros((1, COLLIDER_COLUMNS))
    row[0, 0] = 4  # MESH, its mesh the first
    points = np.ascontiguousarray(points, dtype=np.float64)
    distance, normal = np.zeros(points.shape[1]), np.zeros_like(points)
    _core.collider_distance(row, _packed(_key([mesh_of(collider, "collider_file")])), 0, points, reach, distance, normal)
    return distance


def _key(meshes) -> tuple:
    """A hashable key of meshes [(points, triangles)] for _packed."""
    return tuple((p.tobytes(), t.tobytes(), p.shape, t.shape) for p, t in meshes)
