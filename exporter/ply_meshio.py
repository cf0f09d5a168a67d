"""PLY frames through meshio: the same vertex properties as :mod:`wetcloth.exporter.ply_trimesh`.

meshio writes every one-dimensional ``point_data`` array as a PLY vertex property of its dtype,
in insertion order, so the normals, colours, wetness and UV go in as named columns:
x y z nx ny nz red green blue alpha wetness s t.  Faces are meshio ``triangle`` or ``quad`` cells.
"""

from __future__ import annotations

from pathlib import Path

import meshio

from wetcloth.exporter.frame import Frame

#: meshio's cell type for faces of 3 and 4 corners.
CELL_TYPES = {3: "triangle", 4: "quad"}


def point_data(frame: Frame) -> dict:
    """The frame's per-vertex data as meshio ``point_data`` columns, in PLY property order."""
    n, c = frame.normals, frame.colors
    return {
        "nx": n[:, 0], "ny": n[:, 1], "nz": n[:, 2],
        "red": c[:, 0], "green": c[:, 1], "blue": c[:, 2], "alpha": c[:, 3],
        "wetness": frame.wetness,
        "s": frame.uv[:, 0], "t": frame.uv[:, 1],
    }


def write(path: Path, frame: Frame) -> None:
    """Write ``frame`` as one binary PLY file at ``path``."""
    cells = [(CELL_TYPES[frame.faces.shape[1]], frame.faces)]
    mesh = meshio.Mesh(frame.positions, cells, point_data=point_data(frame))
    meshio.write(path, mesh, file_format="ply", binary=True)
