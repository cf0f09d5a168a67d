"""PLY frames through trimesh: binary little-endian, vertex normals, RGBA colours and float ``wetness``.

Vertex properties, in order: x y z nx ny nz red green blue alpha wetness s t (UV), the same names
and order as :mod:`wetcloth.exporter.ply_meshio` writes.  Blender's PLY importer (4.2+) reads them
all: normals, the colour attribute ``Col``, the float attribute ``wetness`` and the UV map.

trimesh's PLY export writes every face with three corners (a ``Trimesh`` triangulates quads as
they are assigned), so trimesh writes the header and the vertices and this module adds the faces
(triangles or quads) in trimesh's own layout: ``property list uchar int vertex_indices``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh
from trimesh.exchange.ply import export_ply

from wetcloth.exporter.frame import Frame

#: The face element trimesh writes for a mesh without faces, and the line that follows it.
_NO_FACES = b"element face 0\nproperty list uchar int vertex_indices\n"


def to_trimesh(frame: Frame) -> trimesh.Trimesh:
    """A trimesh mesh of the frame's vertices, with wetness and UV as PLY vertex attributes and no faces."""
    return trimesh.Trimesh(
        vertices=frame.positions,
        faces=None,
        vertex_normals=frame.normals,
        vertex_colors=frame.colors,
        vertex_attributes={"wetness": frame.wetness, "s": frame.uv[:, 0], "t": frame.uv[:, 1]},
        process=False,
        validate=False,
    )


def ply_bytes(frame: Frame) -> bytes:
    """The frame as a binary PLY file: trimesh's header and vertices, then the frame's faces."""
    header, separator, vertices = export_ply(to_trimesh(frame), encoding="binary", vertex_normal=True).partition(
        b"end_header\n")
    if _NO_FACES not in header or not separator:
        raise RuntimeError("trimesh's PLY header has changed: no empty face element to fill in")
    faces = frame.faces
    face_element = _NO_FACES.replace(b" 0\n", f" {len(faces)}\n".encode(), 1)
    packed = np.empty(len(faces), dtype=[("count", "<u1"), ("index", "<i4", (faces.shape[1],))])
    packed["count"] = faces.shape[1]
    packed["index"] = faces
    return header.replace(_NO_FACES, face_element) + separator + vertices + packed.tobytes()


def write(path: Path, frame: Frame) -> None:
    """Write ``frame`` as one binary PLY file at ``path``."""
    Path(path).write_bytes(ply_bytes(frame))
