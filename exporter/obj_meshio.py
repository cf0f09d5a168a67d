"""OBJ frames through meshio, with what Blender needs added: the same content as ``obj_trimesh``.

meshio's OBJ writer writes ``v``, ``vn`` (point_data ``obj:vn``), ``vt`` (``obj:vt``) and ``f a b c``
(``f a b c d`` for quads).
It has no vertex colours and its faces do not reference the normals and UVs, so Blender would
drop both.  This module writes through meshio and then adds the colours to the ``v`` lines
(``v x y z r g b``, as trimesh and Blender's importer have it) and turns each face corner ``a``
into ``a/a/a``.
"""

from __future__ import annotations

import io
from pathlib import Path

import meshio

from wetcloth.exporter.frame import Frame
from wetcloth.exporter.obj_trimesh import DIGITS
from wetcloth.exporter.ply_meshio import CELL_TYPES


def _corner(token: str) -> str:
    return f"{token}/{token}/{token}"


def obj_text(frame: Frame) -> str:
    """The frame as OBJ text (positions, colours, normals, UVs, faces)."""
    mesh = meshio.Mesh(
        frame.positions,
        [(CELL_TYPES[frame.faces.shape[1]], frame.faces)],
        point_data={"obj:vn": frame.normals, "obj:vt": frame.uv},
    )
    buffer = io.StringIO()
    meshio.write(buffer, mesh, file_format="obj")
    lines = buffer.getvalue().split("\n")
    rgb = frame.colors[:, :3] / 255.0
    colours = iter([f" {r:.{DIGITS}f} {g:.{DIGITS}f} {b:.{DIGITS}f}" for r, g, b in rgb.tolist()])
    out = []
    for line in lines:
        if line.startswith("v "):
            line += next(colours)
        elif line.startswith("f "):
            line = "f " + " ".join(map(_corner, line.split()[1:]))
        out.append(line)
    if next(colours, None) is not None:  # meshio wrote fewer vertices than the frame has
        raise RuntimeError("meshio's OBJ output has fewer 'v' lines than the frame has vertices")
    return "\n".join(out)


def write(path: Path, frame: Frame) -> None:
    """Write ``frame`` as one OBJ file at ``path``."""
    Path(path).write_text(obj_text(frame))


