"""Mesh colliders' arrays for the compiled core (``collider_mesh.cpp``; docs/model.md section 6.3).

A mesh collider is a rigid triangle mesh: a *solid* if it is closed (every edge in two faces, turned
consistently; its faces are then turned outwards), else a *shell*, such as a bucket's wall, that keeps
the cloth off both its sides.  For each mesh the core gets its vertices, its faces' unit normals and
the pseudo-normals of their edges and vertices (which tell inside from outside near an edge or a
corner), and a uniform grid of cells listing the triangles that reach into each, so that a particle
looks only at the triangles near it and a collider the cloth does not come near costs a box test.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from wetcloth._core import MESH_COLUMNS

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


def is_closed(triangles: np.ndarray) -> bool:
    """Whether every edge of ``triangles`` (T, 3) joins exactly two faces that run along it in opposite
    directions (a closed, consistently turned surface)."""
    directed = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    unique, counts = np.unique(directed, axis=0, return_counts=True)
    if (counts != 1).any():
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
