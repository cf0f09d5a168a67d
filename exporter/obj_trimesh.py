"""OBJ frames through trimesh: ``v x y z r g b`` (colour of the wetness), ``vn``, ``vt`` and ``f v/vt/vn``.

Faces are the frame's triangles or quads (``f a/a/a b/b/b c/c/c d/d/d``).

OBJ cannot carry a custom scalar, so wetness travels only as the vertex colour (Blender's OBJ
importer reads ``v x y z r g b`` into a colour attribute; the loader turns it back into wetness).
No material library is written: the frames reference none.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh
from trimesh.exchange.obj import export_obj
from trimesh.visual.texture import TextureVisuals

from wetcloth.exporter.frame import Frame

#: Decimals of every number in the file: positions within 5e-10 m of the float32 values.
DIGITS = 9


class UVColorVisuals(TextureVisuals):
    """UVs plus per-vertex colours, for trimesh's OBJ exporter.

    trimesh writes vertex colours on the ``v`` lines when ``visual.kind == "vertex"`` and UVs
    (``vt``, and ``f v/vt/vn``) when the visual has ``uv``; none of its own visuals has both.
    """

    def __init__(self, uv, vertex_colors):
        super().__init__(uv=uv)
        self.vertex_colors = vertex_colors

    @property
    def kind(self) -> str:
        return "vertex"


class PolygonTrimesh(trimesh.Trimesh):
    """A Trimesh that keeps faces of four corners as they are, for trimesh's OBJ exporter.

    ``Trimesh`` triangulates quads as they are assigned; the OBJ exporter itself writes each face
    row with as many corners as it has.  Only for writing: trimesh's geometry functions expect triangles.
    """

    @property
    def faces(self) -> np.ndarray:
        return self._data["faces"]

    @faces.setter
    def faces(self, values) -> None:
        self._data["faces"] = np.asanyarray(values, dtype=np.int64)


def obj_text(frame: Frame) -> str:
    """The frame as OBJ text (positions, colours, normals, UVs, faces; no material library)."""
    mesh = PolygonTrimesh(
        vertices=frame.positions,
        faces=frame.faces,
        vertex_normals=frame.normals,
        visual=UVColorVisuals(frame.uv, frame.colors),
        process=False,
        validate=False,
    )
    text = export_obj(mesh, include_normals=True, include_color=True, include_texture=True, digits=DIGITS)
    # trimesh names a default material for any textured mesh; the frames have no .mtl file.
    return "\n".join(line for line in text.split("\n") if not line.startswith(("mtllib ", "usemtl ")))


def write(path: Path, frame: Frame) -> None:
    """Write ``frame`` as one OBJ file at ``path``."""
    Path(path).write_text(obj_text(frame))
