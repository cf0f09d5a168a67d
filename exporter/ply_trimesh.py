"""PLY frames through trimesh: binary little-endian, vertex normals, RGBA colours and float ``wetness``.

Vertex properties, in order: x y z nx ny nz red green blue alpha wetness s t (UV), the same names
and order as :mod:`wetcloth.exporter.ply_meshio` writes.  Blender's PLY importer (4.2+) reads them
all: normals, the colour attribute ``Col``, the float attribute ``wetness`` and the UV map.
"""

from __future__ import annotations

from pathlib import Path

import trimesh
from trimesh.exchange.ply import export_ply

from wetcloth.exporter.frame import Frame


def to_trimesh(frame: Frame) -> trimesh.Trimesh:
    """A trimesh mesh of the frame, with wetness and UV as PLY vertex attributes (no re-processing)."""
    return trimesh.Trimesh(
        vertices=frame.positions,
        faces=frame.triangles,
        vertex_normals=frame.normals,
        vertex_colors=frame.colors,
        vertex_attributes={"wetness": frame.wetness, "s": frame.uv[:, 0], "t": frame.uv[:, 1]},
        process=False,
        validate=False,
    )


def write(path: Path, frame: Frame) -> None:
    """Write ``frame`` as one binary PLY file at ``path``."""
    Path(path).write_bytes(export_ply(to_trimesh(frame), encoding="binary", vertex_normal=True))
