"""One frame of the cloth as every writer sees it: float32 arrays, vertex normals, UVs and wetness colours.

All writers (PLY and OBJ through trimesh or meshio, USD through usd-core) take a :class:`Frame`, so
they write the same numbers: the normals, UVs and colours are computed here once, not per writer.
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


@lru_cache(maxsize=1)
def wetness_lut() -> np.ndarray:
    """The wetness colour table: (LUT_SIZE, 4) uint8 sRGB(A), entry k for wetness k / (LUT_SIZE - 1)."""
    import matplotlib

    rgba = matplotlib.colormaps[COLORMAP](np.linspace(0.0, 1.0, LUT_SIZE))
    lut = np.round(rgba * 255.0).astype(np.uint8)
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


def vertex_normals(positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit vertex normals (n, 3) float32 of a triangle mesh, as trimesh computes them (angle-weighted).

    A vertex whose triangles are all degenerate gets trimesh's fallback (a zero-area normal is
    replaced so the result stays unit length).
    """
    import trimesh

    mesh = trimesh.Trimesh(vertices=positions, faces=triangles, process=False, validate=False)
    return np.asarray(mesh.vertex_normals, dtype=np.float32)


@dataclass(frozen=True)
class Frame:
    """The cloth at one time, ready to write.

    positions (n, 3) float32 m; normals (n, 3) float32 unit; uv (n, 2) float32 0..1;
    wetness (n,) float32 0..1 (absorbed water over capacity); colors (n, 4) uint8 sRGBA of the
    wetness; triangles (m, 3) int32, counter-clockwise seen from +z in the rest sheet.
    """

    positions: np.ndarray
    normals: np.ndarray
    uv: np.ndarray
    wetness: np.ndarray
    colors: np.ndarray
    triangles: np.ndarray

    @property
    def vertex_count(self) -> int:
        return len(self.positions)


def make_frame(positions, wetness, triangles, uv) -> Frame:
    """Check and convert one frame's data: positions (n, 3) m, wetness (n,) 0..1, triangles (m, 3), uv (n, 2).

    Raises ExportError naming the array when a shape or value is wrong.
    """
    positions = np.asarray(positions, dtype=np.float64)
    wetness = np.asarray(wetness, dtype=np.float64)
    triangles = np.asarray(triangles)
    uv = np.asarray(uv, dtype=np.float32)
    n = len(positions)
    if positions.ndim != 2 or positions.shape[1] != 3 or n == 0:
        raise ExportError(f"positions must have shape (n, 3) with n > 0, got {positions.shape}")
    if not np.isfinite(positions).all():
        raise ExportError("positions contain non-finite values; the frame cannot be written")
    if wetness.shape != (n,):
        raise ExportError(f"wetness must have shape ({n},) like the positions, got {wetness.shape}")
    if not np.isfinite(wetness).all() or wetness.min() < 0.0 or wetness.max() > 1.0:
        raise ExportError("wetness must be finite and within 0..1")
    if triangles.ndim != 2 or triangles.shape[1] != 3 or not np.issubdtype(triangles.dtype, np.integer):
        raise ExportError(f"triangles must be integers of shape (m, 3), got {triangles.dtype} {triangles.shape}")
    if triangles.size and (triangles.min() < 0 or triangles.max() >= n):
        raise ExportError(f"triangles index vertices outside 0..{n - 1}")
    if uv.shape != (n, 2):
        raise ExportError(f"uv must have shape ({n}, 2), got {uv.shape}")
    return Frame(
        positions=positions.astype(np.float32),
        normals=vertex_normals(positions, triangles),
        uv=uv,
        wetness=wetness.astype(np.float32),
        colors=wetness_colors(wetness),
        triangles=triangles.astype(np.int32),
    )
