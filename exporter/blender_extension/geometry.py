"""What the Blender objects are, read from their vertices and faces in world space (m, z up); numpy only.

* the cloth (``cloth_of``): a subdivided rectangular plane (every cell a face) pinned along one whole
  edge or not at all is wetcloth's grid cloth (``grid_cloth``: its particle counts, size, centre and
  tilt, and which grid particle each Blender vertex is; ``pinned_edge``), which is exact for a plane and
  has the grid's faster solver; any other mesh of triangles, quads and n-gons is a mesh cloth (``MeshCloth``: its
  vertices in Blender's order, n-gons split into triangles, the pin group a point attribute);
* colliders (``collider_of``): a closed UV sphere, cube (axis-aligned) or cylinder (vertical axis) is
  the analytic collider of that shape (``analytic_collider``); any other mesh a mesh collider of its
  triangles (a solid if closed, else a shell).

Each refuses what it cannot take with a ValueError that names the object.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wetcloth.collider_meshes import is_closed
from wetcloth.errors import ParameterError
from wetcloth.mesh_file import MeshFile, make_mesh, surface

#: Positions agree when within this fraction of the object's size (Blender stores float32 coordinates).
RELATIVE_TOLERANCE = 1e-4
#: The point attribute of a mesh cloth that holds its pin group (1 pinned, 0 free): pinned_vertices.
PIN_ATTRIBUTE = "pin_group"
#: pinned_edge names of the grid's four edges: (column or row, which end).
EDGES = {"x_min": ("col", 0), "x_max": ("col", -1), "y_min": ("row", 0), "y_max": ("row", -1)}


@dataclass(frozen=True)
class GridCloth:
    """A plane of nx x ny vertices, width along x and length across it, tilted about x by ``tilt``
    (deg), centred at ``centre`` (m); ``order[k]`` is the grid particle (row * nx + col) of vertex k."""

    nx: int
    ny: int
    width: float
    length: float
    centre: tuple[float, float, float]
    tilt: float
    order: np.ndarray

    def scene_values(self) -> dict:
        """The scene parameters the plane sets (the simulation's cloth is centred on x = y = 0)."""
        return {"nx": self.nx, "ny": self.ny, "width": self.width, "length": self.length,
                "initial_height": self.centre[2], "initial_tilt": self.tilt}

    @property
    def shift(self) -> np.ndarray:
        """What is added to the simulation's positions (m) to put them in the world: the plane's x, y."""
        return np.array([self.centre[0], self.centre[1], 0.0])

    #: The cache's faces: the grid's cells (the plane's own quads).
    faces = "quads"
    polygons = None


@dataclass(frozen=True)
class MeshCloth:
    """Any mesh as the cloth: ``mesh`` its vertices in world space (m) in Blender's order (particle k is
    vertex k) and faces; ``pinned`` whether a pin group pins some of them (point attribute PIN_ATTRIBUTE);
    ``polygons`` the object's own faces (corner counts, vertices), which the cache is written with."""

    mesh: MeshFile
    pinned: bool
    polygons: tuple

    def scene_values(self) -> dict:
        """The scene parameters the mesh sets: the mesh where it is, its pins."""
        return {"cloth_mesh": self.mesh, "place_mesh": "off", "pinned_vertices": PIN_ATTRIBUTE if self.pinned else ""}

    @property
    def order(self) -> np.ndarray:
        return np.arange(self.mesh.n)

    @property
    def shift(self) -> np.ndarray:
        return np.zeros(3)

    #: The cache's faces if not its polygons: the simulation's triangles.
    faces = "triangles"


def _levels(values: np.ndarray, tol: float, what: str, name: str) -> tuple[np.ndarray, float]:
    """Index (0..count-1) of each value on a row of equally spaced levels, and the spacing."""
    ordered = np.sort(values)
    starts = np.concatenate([[0], np.flatnonzero(np.diff(ordered) > tol) + 1])
    levels = ordered[starts]
    if len(levels) < 2:
        raise ValueError(f"cloth {name!r}: the plane has no extent {what}")
    spacing = (levels[-1] - levels[0]) / (len(levels) - 1)
    if np.abs(levels - (levels[0] + spacing * np.arange(len(levels)))).max() > tol:
        raise ValueError(f"cloth {name!r}: its vertices are not equally spaced {what}; a cloth is a plane "
                         "subdivided evenly (Add > Mesh > Grid, or a Plane subdivided)")
    index = np.rint((values - levels[0]) / spacing).astype(np.int64)
    return index, spacing


def grid_cloth(positions, edges, name: str = "cloth") -> GridCloth:
    """The grid cloth of a subdivided plane: vertex ``positions`` (n, 3) in world space (m) and its
    ``edges`` (e, 2).  The plane's edges must run along x and across it (a plane turned about z or
    y is refused); it may be tilted about x (``initial_tilt``)."""
    p = np.asarray(positions, dtype=np.float64)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 4:
        raise ValueError(f"cloth {name!r}: needs a plane of at least 2 x 2 vertices, got {len(p)} vertices")
    size = float(np.ptp(p, axis=0).max())
    tol = RELATIVE_TOLERANCE * max(size, 1e-9)
    centre = p.mean(axis=0)
    _, _, axes = np.linalg.svd(p - centre, full_matrices=False)
    normal = axes[2]
    if abs(normal[0]) > RELATIVE_TOLERANCE or np.abs((p - centre) @ normal).max() > tol:
        raise ValueError(f"cloth {name!r}: not a flat plane with edges along x (a plane may be tilted about x "
                         "only; apply or clear its rotation about z and y)")
    across = np.cross(normal, [1.0, 0.0, 0.0])
    across /= np.linalg.norm(across)
    if across[1] < -1e-12 or (abs(across[1]) <= 1e-12 and across[2] < 0):
        across = -across
    step = p[edges[:, 1]] - p[edges[:, 0]]
    off_axis = np.minimum(np.abs(step @ across), np.abs(step[:, 0]))  # an edge runs along x or across
    if len(edges) and off_axis.max() > tol:
        raise ValueError(f"cloth {name!r}: its edges do not run along x and across it; a cloth is a subdivided "
                         "rectangular plane, which may be tilted about x only (clear its rotation about z)")
    col, dx = _levels(p[:, 0], tol, "along x", name)
    row, dy = _levels((p - centre) @ across, tol, "across x", name)
    nx, ny = int(col.max()) + 1, int(row.max()) + 1
    order = row * nx + col
    if nx * ny != len(p) or len(np.unique(order)) != len(p):
        raise ValueError(f"cloth {name!r}: its {len(p)} vertices do not fill a rectangular grid ({nx} x {ny}); "
                         "a cloth is a subdivided rectangular plane")
    hops = np.abs(col[edges[:, 0]] - col[edges[:, 1]]) + np.abs(row[edges[:, 0]] - row[edges[:, 1]])
    if len(edges) != nx * (ny - 1) + ny * (nx - 1) or (hops != 1).any():
        raise ValueError(f"cloth {name!r}: its edges are not those of a grid of quads ({nx} x {ny} vertices); "
                         "a cloth is a subdivided plane, not triangulated")
    tilt = math.degrees(math.atan2(across[2], across[1]))
    return GridCloth(nx=nx, ny=ny, width=dx * (nx - 1), length=dy * (ny - 1), centre=tuple(map(float, centre)),
                     tilt=tilt, order=order)


def pinned_edge(grid: GridCloth, vertices, group: str) -> str:
    """The ``pinned_edge`` that vertex group ``group`` (Blender vertex indices ``vertices``) is:
    'none' for no vertices, else the grid edge whose particles are exactly these."""
    chosen = set(int(grid.order[k]) for k in vertices)
    if not chosen:
        return "none"
    index = np.arange(grid.nx * grid.ny)
    col, row = index % grid.nx, index // grid.nx
    for edge, (axis, end) in EDGES.items():
        along = col if axis == "col" else row
        last = (grid.nx if axis == "col" else grid.ny) - 1
        if chosen == set(index[along == (last if end == -1 else 0)].tolist()):
            return edge
    raise ValueError(f"pin group {group!r}: its {len(chosen)} vertices are not one whole edge of the grid "
                     f"({', '.join(EDGES)}: the vertices of the first or last column along x, or the first or "
                     "last row along y)")


def face_blocks(sizes, loops, triangles, triangle_faces) -> list[np.ndarray]:
    """A Blender mesh's faces as make_mesh's blocks: its triangles and n-gons (split into Blender's
    loop triangles) as one (j, 3) block, its quads as one (j, 4) block.  ``sizes`` (k,) the corners of
    each face, ``loops`` the vertex of each corner, face after face; ``triangles`` (t, 3) the loop
    triangles' vertices and ``triangle_faces`` (t,) the face each splits."""
    sizes = np.asarray(sizes, dtype=np.int64)
    loops = np.asarray(loops, dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    quads = starts[sizes == 4][:, None] + np.arange(4)
    split = sizes[np.asarray(triangle_faces, dtype=np.int64)] != 4
    blocks = [np.asarray(triangles, dtype=np.int64).reshape(-1, 3)[split], loops[quads].reshape(-1, 4)]
    return [b for b in blocks if len(b)]


def check_cells(grid: GridCloth, sizes, loops, name: str = "cloth") -> None:
    """ValueError unless the faces (corner counts ``sizes``, corner vertices ``loops``) are the grid's
    cells, each once: a plane with a face deleted is no grid."""
    sizes = np.asarray(sizes, dtype=np.int64)
    cells = (grid.nx - 1) * (grid.ny - 1)
    if len(sizes) != cells or (sizes != 4).any():
        raise ValueError(f"cloth {name!r}: its {len(sizes)} faces are not the {cells} quads of its grid")
    corners = grid.order[np.asarray(loops, dtype=np.int64)].reshape(-1, 4)
    first = corners.min(axis=1)
    expected = first[:, None] + np.array([0, 1, grid.nx, grid.nx + 1])
    if (np.sort(corners, axis=1) != expected).any() or len(np.unique(first)) != cells:
        raise ValueError(f"cloth {name!r}: its faces are not the quads of its grid, each once")


def vertex_uv(loops, loop_uv, n: int) -> np.ndarray | None:
    """Per-vertex UVs (n, 2) from a UV map's per-corner ones ``loop_uv`` (corners, 2) at corner vertices
    ``loops``, where every vertex's corners agree (to 1e-6: no seam runs through the cloth) and every vertex
    has one; else (or with no map, ``loop_uv`` None) None."""
    if loop_uv is None:
        return None
    loops = np.asarray(loops, dtype=np.int64)
    loop_uv = np.asarray(loop_uv, dtype=float).reshape(-1, 2)
    uv = np.full((n, 2), np.nan)
    uv[loops] = loop_uv
    if np.isnan(uv).any() or np.abs(uv[loops] - loop_uv).max(initial=0.0) > 1e-6:
        return None
    return uv


def cloth_of(positions, edges, polygons, loop_triangles, pins, name: str = "cloth", loop_uv=None):
    """The cloth of a Cloth object: a GridCloth (and its pinned_edge) if the mesh is a subdivided plane
    (its faces the grid's cells, check_cells) and ``pins`` (the pin group's vertex indices) are none or one
    whole edge of it, else a MeshCloth (and 'none') of vertex ``positions`` (n, 3) in world space (m) and
    faces ``polygons`` (corner counts, corner vertices), n-gons split as ``loop_triangles`` (vertices,
    faces) are (face_blocks); ``edges`` (e, 2); its UVs those of ``loop_uv`` (the UV map's per-corner
    UVs, or None) where they are one per vertex (vertex_uv: what lays a cloth folded in the object out flat
    for self-collision).  A ValueError naming the object for a mesh no cloth can be (no faces,
    non-manifold, loose vertices)."""
    if not len(polygons[0]):
        raise ValueError(f"cloth {name!r} has no faces: a cloth is a surface (a mesh with faces; "
                         "Add > Mesh > Grid, or a Plane subdivided)")
    try:
        grid = grid_cloth(positions, edges, name)
        check_cells(grid, *polygons, name)
        return grid, pinned_edge(grid, pins, "pins")
    except ValueError:
        pass
    pinned = np.zeros(len(positions))
    pinned[np.asarray(pins, dtype=np.int64)] = 1.0
    try:
        uv = vertex_uv(polygons[1], loop_uv, len(positions))
        mesh = make_mesh(positions, face_blocks(*polygons, *loop_triangles), {PIN_ATTRIBUTE: pinned}, uv, name)
    except ParameterError as exc:
        raise ValueError(f"cloth {name!r} cannot be the cloth: {exc.problems[0][2]}") from None
    polygons = tuple(np.asarray(a, dtype=np.int64) for a in polygons)
    return MeshCloth(mesh=mesh, pinned=bool(pinned.any()), polygons=polygons), "none"


def collider_of(positions, triangles, name: str = "collider") -> dict:
    """The ``[[collider]]`` fields of a Collider object's world-space vertices (n, 3) m and triangles
    (t, 3): an analytic shape if it is a closed primitive (``analytic_collider``), else a mesh collider
    of these triangles (mesh_file.surface; x, y, z 0: the points are where the scene puts them)."""
    found = analytic_collider(positions) if is_closed(triangles, turned=False) else None
    if found is not None:
        return found
    if not len(np.asarray(triangles).reshape(-1, 3)):
        raise ValueError(f"collider {name!r} has no faces: a collider is a surface (a mesh with faces)")
    return dict(shape="mesh", file=surface(positions, triangles, f"collider {name!r}"), x=0.0, y=0.0, z=0.0)


def analytic_collider(positions) -> dict | None:
    """The ``[[collider]]`` fields (shape, x, y, z and its sizes, m) of a mesh's world-space vertices
    (n, 3) if they are 8 corners of an axis-aligned box, a cylinder's two rings about a vertical axis (as
    many vertices at its bottom as at its top: a cone is no cylinder; cap centres allowed), or more than 8
    vertices all as far from their centre (a UV sphere); else None."""
    p = np.unique(np.asarray(positions, dtype=np.float64).round(9), axis=0)
    if len(p) == 0:
        return None
    lo, hi = p.min(axis=0), p.max(axis=0)
    centre, extent = 0.5 * (lo + hi), hi - lo
    tol = RELATIVE_TOLERANCE * max(float(extent.max()), 1e-9)
    where = dict(x=float(centre[0]), y=float(centre[1]), z=float(centre[2]))
    at_bounds = (np.abs(p - lo) <= tol) | (np.abs(p - hi) <= tol)
    if len(p) == 8 and at_bounds.all() and (extent > tol).all():
        return dict(shape="box", **where, size_x=float(extent[0]), size_y=float(extent[1]), size_z=float(extent[2]))
    radial = np.hypot(p[:, 0] - centre[0], p[:, 1] - centre[1])
    ring = radial > tol
    bottom, top = (ring & (np.abs(p[:, 2] - z) <= tol) for z in (lo[2], hi[2]))
    if (at_bounds[:, 2].all() and bottom.sum() == top.sum() >= 3 and np.ptp(radial[ring]) <= tol
            and abs(extent[0] - extent[1]) <= tol and extent[2] > tol):
        return dict(shape="cylinder", **where, radius=float(radial[ring].mean()), height=float(extent[2]))
    distance = np.linalg.norm(p - centre, axis=1)
    if len(p) > 8 and np.ptp(distance) <= tol:  # (a turned cube's 8 corners are as far from its centre)
        return dict(shape="sphere", **where, radius=float(distance.mean()))
    return None
