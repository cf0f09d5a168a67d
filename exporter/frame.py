"""One frame of the cloth as every writer sees it: float32 arrays, vertex normals, UVs and wetness colours.

All writers (PLY and OBJ through trimesh or meshio, USD through usd-core) take a :class:`Frame`, so
they write the same numbers: the normals, UVs and colours are computed here once, not per writer.
The faces they write are the simulation's triangles or, by default, quads: one per grid cell, made
of the cell's two triangles (:func:`quads_from_triangles`); for a cloth from a mesh file, by default
the file's own faces and UVs (:func:`cloth_faces`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from wetcloth.exporter.errors import ExportError

#: Matplotlib colour map that shows wetness: near white when dry, dark blue when saturated.
COLORMAP = "Blues"
#: Entries of the colour look-up table: wetness w gets entry round(w * (LUT_SIZE - 1)).
LUT_SIZE = 256
#: Face kinds a sequence can be written with; quads (one per grid cell) are the default.
FACES = ("quads", "triangles")


#: The 'Blues' colour map's anchors (ColorBrewer's 9-class Blues, 8-bit sRGB), evenly spaced from
#: wetness 0 to 1, as matplotlib defines it; the table interpolates them linearly as matplotlib does,
#: so frames need no matplotlib (Blender's Python has none).  tests/test_export.py checks it against
#: matplotlib's own table.
BLUES = ((247, 251, 255), (222, 235, 247), (198, 219, 239), (158, 202, 225), (107, 174, 214),
         (66, 146, 198), (33, 113, 181), (8, 81, 156), (8, 48, 107))


@lru_cache(maxsize=1)
def wetness_lut() -> np.ndarray:
    """The wetness colour table: (LUT_SIZE, 4) uint8 sRGB(A), entry k for wetness k / (LUT_SIZE - 1)."""
    anchors = np.asarray(BLUES, dtype=np.float64) / 255.0
    x = np.linspace(0.0, 1.0, LUT_SIZE)
    at = np.linspace(0.0, 1.0, len(anchors))
    # matplotlib's _create_lookup_table: the anchor below plus the fraction of the way to the next
    upper = np.clip(np.searchsorted(at, x[1:-1]), 1, len(at) - 1)
    fraction = (x[1:-1] - at[upper - 1]) / (at[upper] - at[upper - 1])
    inner = fraction[:, None] * (anchors[upper] - anchors[upper - 1]) + anchors[upper - 1]
    rgb = np.clip(np.concatenate([anchors[:1], inner, anchors[-1:]]), 0.0, 1.0)
    lut = np.round(np.column_stack([rgb, np.ones(LUT_SIZE)]) * 255.0).astype(np.uint8)
    lut.flags.writeable = False
    return lut


def wetness_colors(wetness: np.ndarray) -> np.ndarray:
    """RGBA colours (n, 4) uint8 (sRGB, alpha 255) of wetness values (n,) in 0..1."""
    index = np.rint(np.clip(wetness, 0.0, 1.0) * (LUT_SIZE - 1)).astype(np.intp)
    return wetness_lut()[index]


def sheet_uv(rest_xy: np.ndarray) -> np.ndarray:
    """UV coordinates (n, 2) float32 in 0..1 from the rest-sheet coordinates ``rest_xy`` (2, n) m."""
    rest_xy = np.asarray(rest_xy, dtype=np.float64)
    lo = rest_xy.min(axis=1, keepdims=True)
    span = rest_xy.max(axis=1, keepdims=True) - lo
    span[span == 0.0] = 1.0
    return ((rest_xy - lo) / span).T.astype(np.float32)


def cloth_faces(topology) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """A cloth's triangles (m, 3), UVs (n, 2) float32 and the faces of its mesh file ((k, 3) or (k, 4), or
    None for the built-in grid), from its ``wetcloth.topology.Topology``: the file's UVs where it has
    them, else those of the flat rest sheet (:func:`sheet_uv`)."""
    mesh = topology.mesh
    if mesh is None:
        return topology.triangles, sheet_uv(topology.rest_xy), None
    uv = sheet_uv(topology.rest_xy) if mesh.uv is None else np.asarray(mesh.uv, dtype=np.float32)
    return topology.triangles, uv, mesh.faces


def vertex_normals(positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit vertex normals (n, 3) float32 of a triangle mesh: the triangles' normals weighted by each
    triangle's angle at the vertex (Thuermer and Wuethrich 1998, as trimesh computes them).

    Degenerate triangles (zero area) are left out; a vertex with no other gets (0, 0, 1), the rest
    sheet's normal.  Numpy only: frames are written inside Blender too, which has no trimesh.
    """
    p = np.asarray(positions, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    corners = p[t]  # (m, 3, 3)
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area2 = np.linalg.norm(cross, axis=1)
    ok = area2 > 1e-12 * max(float(np.abs(p).max(initial=0.0)), 1.0) ** 2
    normal = cross[ok] / area2[ok, None]
    corners, t = corners[ok], t[ok]
    summed = np.zeros_like(p)
    for k in range(3):
        a = corners[:, (k + 1) % 3] - corners[:, k]
        b = corners[:, (k + 2) % 3] - corners[:, k]
        cosine = np.einsum("ij,ij->i", a, b) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1),
                                                         1e-300)
        np.add.at(summed, t[:, k], normal * np.arccos(np.clip(cosine, -1.0, 1.0))[:, None])
    length = np.linalg.norm(summed, axis=1)
    out = np.tile([0.0, 0.0, 1.0], (len(p), 1))
    good = length > 0.0
    out[good] = summed[good] / length[good, None]
    return out.astype(np.float32)


def quads_from_triangles(triangles: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Quads (m / 2, 4) int64 made of the triangles (m, 3) taken in pairs that share their longest edge.

    The longest edge is measured in the rest sheet (``uv``, (n, 2)): on the simulation's grid it is
    each cell's diagonal, so every cell becomes one quad.  Quad (a, b, c, d) is the triangles
    (a, b, c) and (c, d, a), both as counter-clockwise as the triangles were: splitting it along
    a-c (as trimesh and most readers triangulate quads) gives the simulation's triangles back.
    Quads come in the order of their first triangle.  Raises ExportError if the triangles do not
    pair up this way (a mesh that is not a triangulated grid).
    """
    uv = np.asarray(uv, dtype=np.float64)
    if uv.ndim != 2 or uv.shape[1] != 2:
        raise ExportError(f"uv must have shape (n, 2), got {uv.shape}")
    _check_indices("triangles", np.asarray(triangles), (3,), len(uv))
    triangles = np.asarray(triangles, dtype=np.int64)
    edge = np.stack([uv[triangles[:, (k + 1) % 3]] - uv[triangles[:, k]] for k in range(3)], axis=1)
    longest = np.argmax(np.einsum("mkj,mkj->mk", edge, edge), axis=1)  # edge k runs from corner k to k + 1
    # each triangle rotated so that its longest edge runs from its corner 2 to its corner 0
    rolled = triangles[np.arange(len(triangles))[:, None], (longest[:, None] + 1 + np.arange(3)) % 3]
    # the longest edge as one number, the same for both of its directions
    diagonal = np.minimum(rolled[:, 0], rolled[:, 2]) * (int(triangles.max(initial=0)) + 1) + np.maximum(
        rolled[:, 0], rolled[:, 2])
    order = np.argsort(diagonal, kind="stable")
    first, second = order[0::2], order[1::2]  # pairs of equal diagonals, the lower triangle index first
    paired = (len(triangles) > 0 and len(triangles) % 2 == 0
              and (rolled[first, 0] == rolled[second, 2]).all()  # the same edge, run in opposite directions
              and (rolled[first, 2] == rolled[second, 0]).all()
              and (np.diff(diagonal[first]) != 0).all())  # and no third triangle shares it
    if not paired:
        raise ExportError("the triangles do not pair into quads (two per grid cell, sharing the cell's "
                          "diagonal); write them with faces='triangles'")
    quads = np.column_stack([rolled[first, 0], rolled[first, 1], rolled[first, 2], rolled[second, 1]])
    return quads[np.argsort(first)]


@dataclass(frozen=True)
class Frame:
    """The cloth at one time, ready to write.

    positions (n, 3) float32 m; normals (n, 3) float32 unit; uv (n, 2) float32 0..1;
    wetness (n,) float32 0..1 (absorbed water over capacity); colors (n, 4) uint8 sRGBA of the
    wetness; triangles (m, 3) int32, counter-clockwise seen from +z in the rest sheet (the normals
    are theirs); faces (k, 3) or (k, 4) int32: what the writers write, the triangles or quads made
    of them; velocities (n, 3) float32 m/s, or None where the frame has none.
    """

    positions: np.ndarray
    normals: np.ndarray
    uv: np.ndarray
    wetness: np.ndarray
    colors: np.ndarray
    triangles: np.ndarray
    faces: np.ndarray
    velocities: np.ndarray | None = None

    @property
    def vertex_count(self) -> int:
        return len(self.positions)


def _check_indices(name: str, faces: np.ndarray, corners: tuple[int, ...], n: int) -> None:
    if faces.ndim != 2 or faces.shape[1] not in corners or not np.issubdtype(faces.dtype, np.integer):
        shape = " or ".join(f"(m, {k})" for k in corners)
        raise ExportError(f"{name} must be integers of shape {shape}, got {faces.dtype} {faces.shape}")
    if faces.size and (faces.min() < 0 or faces.max() >= n):
        raise ExportError(f"{name} index vertices outside 0..{n - 1}")


#: The largest magnitude a float32 holds: the files store float32, so a larger value would be written as inf.
FLOAT32_MAX = float(np.finfo(np.float32).max)


def check_float32(name: str, values: np.ndarray) -> None:
    """ExportError naming ``name`` unless every value is finite and within float32's range."""
    if not np.isfinite(values).all():
        raise ExportError(f"{name} contain non-finite values; the frame cannot be written")
    if values.size and np.abs(values).max() > FLOAT32_MAX:
        raise ExportError(f"{name} contain values beyond float32's range (magnitude at most {FLOAT32_MAX:.4g}), "
                          f"largest {np.abs(values).max():.4g}; the frame cannot be written")


def make_frame(positions, wetness, triangles, uv, faces=None, velocities=None) -> Frame:
    """Check and convert one frame's data: positions (n, 3) m, wetness (n,) 0..1, triangles (m, 3),
    uv (n, 2); faces (k, 3 or 4) to write instead of the triangles (e.g. their quads); velocities (n, 3) m/s.

    Raises ExportError naming the array when a shape or value is wrong.
    """
    positions = np.asarray(positions, dtype=np.float64)
    wetness = np.asarray(wetness, dtype=np.float64)
    triangles = np.asarray(triangles)
    faces = triangles if faces is None else np.asarray(faces)
    uv = np.asarray(uv, dtype=np.float64)
    n = len(positions)
    if positions.ndim != 2 or positions.shape[1] != 3 or n == 0:
        raise ExportError(f"positions must have shape (n, 3) with n > 0, got {positions.shape}")
    check_float32("positions", positions)
    if wetness.shape != (n,):
        raise ExportError(f"wetness must have shape ({n},) like the positions, got {wetness.shape}")
    if not np.isfinite(wetness).all() or wetness.min() < 0.0 or wetness.max() > 1.0:
        raise ExportError("wetness must be finite and within 0..1")
    _check_indices("triangles", triangles, (3,), n)
    _check_indices("faces", faces, (3, 4), n)
    if uv.shape != (n, 2):
        raise ExportError(f"uv must have shape ({n}, 2), got {uv.shape}")
    check_float32("uv", uv)
    if velocities is not None:
        velocities = np.asarray(velocities, dtype=np.float64)
        if velocities.shape != (n, 3):
            raise ExportError(f"velocities must have shape ({n}, 3) like the positions, got {velocities.shape}")
        check_float32("velocities", velocities)
        velocities = velocities.astype(np.float32)
    return Frame(
        positions=positions.astype(np.float32),
        normals=vertex_normals(positions, triangles),
        uv=uv.astype(np.float32),
        wetness=wetness.astype(np.float32),
        colors=wetness_colors(wetness),
        triangles=triangles.astype(np.int32),
        faces=faces.astype(np.int32),
        velocities=velocities,
    )
