"""The cloth's fixed structure: particle areas and masses, springs and triangles, built once per scene.

The built-in cloth (``cloth_mesh = ""``) is an ``nx`` x ``ny`` grid, particle ``i = row * nx + col``
(col along x, row along y).  Its springs are grouped in *families* that share one index offset:
spring ``i`` of a family joins particle ``i`` to particle ``i + offset``.  A missing spring (across
the grid's edge) has zero stiffness.  This layout lets every kernel loop over flat arrays with no
index lists.

A cloth from a mesh file (``cloth_mesh``, docs/model.md section 2.4) has one particle per vertex of
the file, in the file's order, and *listed springs*: explicit index pairs (``pairs``), tension-only
ones first, then the edges of its triangles, which also push back a little when compressed (docs/model.md
section 2.4).  A file whose vertices form the built-in grid exactly gets the grid's topology.
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass, replace

import numpy as np

from wetcloth.errors import ParameterError
from wetcloth.mesh_file import MeshFile, face_edges, is_mesh, make_mesh, read_mesh_file, triangle_areas
from wetcloth.scene import PINS_ALLOWED, Scene

#: Kinds of listed springs (``pair_kind``): along a face's edge, across a quad, bending, a hinge's term
#: (rest length 0, linear, listed last: ``hinge_terms``).
STRETCH, SHEAR, BEND, HINGE = 0, 1, 2, 3
#: A vertex's two edges carry a quad mesh's bending spring when they make an angle above this (deg).
BEND_ANGLE = 120.0
#: Relative tolerance of the test that a file's vertices form the built-in grid.
GRID_TOLERANCE = 1e-9


@dataclass(frozen=True)
class MeshFaces:
    """What a cloth from a mesh file exports: ``faces`` (k, 3) or (k, 4) int64 as in the file (a file
    that mixes triangles and quads: the triangles of their split), ``uv`` (n, 2) per-vertex UVs of
    the file or None, ``source`` the file's path."""

    faces: np.ndarray
    uv: np.ndarray | None
    source: str


@dataclass(frozen=True)
class Topology:
    """Connectivity and per-particle constants (SI units).

    For a mesh cloth ``nx`` = n, ``ny`` = 1 and ``dx`` = ``dy`` = the median edge length (m): they
    mean nothing else there, and its spring families are empty (F = 0)."""

    nx: int
    ny: int
    dx: float  # m, rest spacing along x
    dy: float  # m, rest spacing along y
    rest_pos: np.ndarray  # (3, n) m, rest positions (grid: rest_xy with z 0; mesh: the file's coordinates)
    rest_xy: np.ndarray  # (2, n) m, a flat parameterisation of the rest sheet, centred on 0
    area: np.ndarray  # (n,) m2, each particle's share of the sheet
    spring_offset: np.ndarray  # (F,) int64, index offset of each family
    spring_rest: np.ndarray  # (F,) m, rest length of each family
    spring_tension_only: np.ndarray  # (F,) bool: True for structural and shear springs
    spring_stiffness: np.ndarray  # (F, n) N/m, zero where a family has no spring
    spring_damping: np.ndarray  # (F, n) N s/m
    spring_shape: np.ndarray  # (F, n) strip area / rest length^2 (-): stiffness = modulus * shape
    spring_family_names: tuple[str, ...]
    triangles: np.ndarray  # (m, 3) int64, consistently oriented (grid: counter-clockwise seen from +z)
    pinned: np.ndarray  # (n,) bool
    pairs: np.ndarray  # (2, S) int64, listed springs' particles (tension-only ones first)
    pair_rest: np.ndarray  # (S,) m
    pair_stiffness: np.ndarray  # (S,) N/m
    pair_damping: np.ndarray  # (S,) N s/m
    pair_shape: np.ndarray  # (S,) strip area / rest length^2 (-)
    pair_kind: np.ndarray  # (S,) int8: STRETCH, SHEAR, BEND or HINGE (the hinges' terms last)
    pair_tension_count: int  # the first this many listed springs are tension-only
    mesh: MeshFaces | None  # None for the built-in grid
    size: float  # m, the cloth's larger side (grid: max(width, length); mesh: of rest_xy's bounding box)
    pair_buckling_count: int = 0  # the listed springs after the tension-only ones that buckle (a triangle's edges)

    @property
    def in_plane_count(self) -> int:
        """The listed springs in the cloth's plane (tension-only and buckling): the first this many."""
        return self.pair_tension_count + self.pair_buckling_count

    @property
    def hinge_count(self) -> int:
        """The listed springs that are the hinges' terms (``bend_rigidity``): the last this many."""
        return int(np.count_nonzero(self.pair_kind == HINGE))

    @property
    def n(self) -> int:
        return self.rest_pos.shape[1]

    @property
    def is_grid(self) -> bool:
        """True for the built-in grid (not for a file, even one that forms a grid)."""
        return self.mesh is None

    @property
    def listed(self) -> bool:
        """Whether the springs are listed (a mesh's) rather than a grid's families: the core's mesh path
        (a file whose vertices form the built-in grid takes the grid's)."""
        return self.pairs.shape[1] > 0

    def per_particle_sum(self, per_spring: np.ndarray, offsets: np.ndarray | None = None) -> np.ndarray:
        """Sum (n) over the springs touching each particle of a per-spring quantity (F, n), whose
        families have ``offsets`` (default: all families, ``spring_offset``)."""
        offsets = self.spring_offset if offsets is None else offsets
        n = self.n
        total = np.zeros(n)
        for values, off in zip(per_spring, offsets):
            total[: n - off] += values[: n - off]
            total[off:] += values[: n - off]
        return total

    def per_particle_pair_sum(self, values: np.ndarray, kinds=None) -> np.ndarray:
        """Sum (n) onto both ends of each listed spring of a per-listed-spring quantity (S,), over the
        springs of ``kinds`` (a sequence of STRETCH, SHEAR, BEND; default all)."""
        values = np.asarray(values, dtype=np.float64)
        if kinds is not None:
            values = np.where(np.isin(self.pair_kind, kinds), values, 0.0)
        n = self.n
        return np.bincount(self.pairs[0], values, minlength=n) + np.bincount(self.pairs[1], values, minlength=n)

    @property
    def spring_count(self) -> int:
        """Number of actual springs: the families' (zero-stiffness slots not counted) and the listed ones."""
        return int(np.count_nonzero(self.spring_stiffness)) + self.pairs.shape[1]


def _edge_weights(count: int) -> np.ndarray:
    """1 inside, 1/2 on the edges: a particle's share of the cells along one axis."""
    w = np.ones(count)
    w[0] = w[-1] = 0.5
    return w


def build_topology(scene: Scene) -> Topology:
    """The topology and per-spring constants of ``scene``: the nx x ny grid, or its ``cloth_mesh``."""
    mesh = None if not is_mesh(scene.cloth_mesh) else read_mesh_file(scene.cloth_mesh)
    if mesh is None:
        topo = _grid(scene, scene.nx, scene.ny, scene.width, scene.length)
        if scene.bend_rigidity != 0.0:  # hinges bend listed springs only: the grid's quads as a mesh
            topo = _hinged_grid(scene, topo)
    else:
        faces = MeshFaces(faces=mesh.faces, uv=mesh.uv, source=mesh.source)
        grid = file_grid(mesh) if scene.bend_rigidity == 0.0 else None  # (hinges bend listed springs only)
        if grid is not None:  # the grid's own springs and preconditioner, the file's faces for export
            topo = replace(_grid(scene, *grid), rest_pos=mesh.points.T.copy(), mesh=faces)
        else:
            topo = _mesh(scene, mesh, faces)
    return replace(topo, pinned=pinned_mask(scene, initial_positions(scene, topo), mesh))


def _grid(scene: Scene, nx: int, ny: int, width: float, length: float) -> Topology:
    """The topology of an nx x ny grid of size width x length (m), nothing pinned."""
    n = nx * ny
    dx = width / (nx - 1)
    dy = length / (ny - 1)
    col = np.tile(np.arange(nx), ny)
    row = np.repeat(np.arange(ny), nx)
    rest_xy = np.stack([col * dx - 0.5 * width, row * dy - 0.5 * length])
    wc = _edge_weights(nx)[col]
    wr = _edge_weights(ny)[row]
    area = dx * dy * wc * wr

    # Each spring stands for a strip of the sheet of area a_s; with rest length l its constant
    # is k = stiffness * a_s / l**2 (= stiffness * width / length), likewise for damping.
    diag = np.hypot(dx, dy)
    families = [
        # name, offset, rest length, strip area per spring, exists, tension only, bending
        ("structural_x", 1, dx, dx * dy * wr, col < nx - 1, True, False),
        ("structural_y", nx, dy, dy * dx * wc, row < ny - 1, True, False),
        ("shear_up_right", nx + 1, diag, np.full(n, 0.5 * dx * dy), (col < nx - 1) & (row < ny - 1), True, False),
        ("shear_up_left", nx - 1, diag, np.full(n, 0.5 * dx * dy), (col > 0) & (row < ny - 1), True, False),
        ("bend_x", 2, 2 * dx, 2 * dx * dy * wr, col < nx - 2, False, True),
        ("bend_y", 2 * nx, 2 * dy, 2 * dy * dx * wc, row < ny - 2, False, True),
    ]
    names, offsets, rests, tension, ks, cs, shapes = [], [], [], [], [], [], []
    for name, offset, rest, strip_area, exists, tension_only, bending in families:
        modulus = scene.bend_stiffness if bending else scene.stretch_stiffness
        if modulus == 0.0 or not exists.any():
            continue
        names.append(name)
        offsets.append(offset)
        rests.append(rest)
        tension.append(tension_only)
        ks.append(np.where(exists, modulus * strip_area / rest**2, 0.0))
        cs.append(np.where(exists, scene.damping * strip_area / rest**2, 0.0))
        shapes.append(np.where(exists, strip_area / rest**2, 0.0))

    cells = grid_cells(nx, ny)
    triangles = np.concatenate([cells[:, [0, 1, 2]], cells[:, [0, 2, 3]]])
    return Topology(
        nx=nx,
        ny=ny,
        dx=dx,
        dy=dy,
        rest_pos=np.vstack([rest_xy, np.zeros(n)]),
        rest_xy=rest_xy,
        area=area,
        spring_offset=np.array(offsets, dtype=np.int64),
        spring_rest=np.array(rests, dtype=np.float64),
        spring_tension_only=np.array(tension, dtype=np.bool_),
        spring_stiffness=np.array(ks, dtype=np.float64).reshape(len(ks), n),
        spring_damping=np.array(cs, dtype=np.float64).reshape(len(cs), n),
        spring_shape=np.array(shapes, dtype=np.float64).reshape(len(shapes), n),
        spring_family_names=tuple(names),
        triangles=triangles.astype(np.int64),
        pinned=np.zeros(n, dtype=bool),
        **_no_pairs(),
        mesh=None,
        size=max(width, length),
    )


def _hinged_grid(scene: Scene, grid: Topology) -> Topology:
    """The built-in grid (``grid``, its topology) bent by hinges (``bend_rigidity``): the listed springs of a mesh
    file of its quads (docs/model.md section 2.4), placed, pinned and exported as the grid (``mesh`` None)."""
    mesh = make_mesh(grid.rest_pos.T, [grid_cells(scene.nx, scene.ny)], shown="the nx x ny rectangle")
    return replace(_mesh(scene, mesh, None), rest_xy=grid.rest_xy)


def grid_cells(nx: int, ny: int) -> np.ndarray:
    """The cells (m, 4) int64 of the nx x ny grid (particle i = row * nx + col): corners i, i + 1, i + nx + 1,
    i + nx, counter-clockwise seen from +z."""
    index = np.arange(nx * ny)
    a = np.flatnonzero((index % nx < nx - 1) & (index // nx < ny - 1))
    return np.stack([a, a + 1, a + nx + 1, a + nx], axis=1)


def _no_pairs() -> dict:
    return dict(pairs=np.zeros((2, 0), dtype=np.int64), pair_rest=np.zeros(0), pair_stiffness=np.zeros(0),
                pair_damping=np.zeros(0), pair_shape=np.zeros(0), pair_kind=np.zeros(0, dtype=np.int8),
                pair_tension_count=0)


# ----------------------------------------------------------------------------------------- mesh cloth
def file_grid(mesh: MeshFile) -> tuple[int, int, float, float] | None:
    """(nx, ny, width, length) if the file's vertices form the built-in grid exactly (quads only, vertex
    i = row * nx + col with x fastest, in a plane z = const, uniform spacings; the quads its cells),
    else None."""
    if len(mesh.blocks) != 1 or mesh.blocks[0].shape[1] != 4:
        return None
    p = mesh.points
    n = len(p)
    size = float(np.ptp(p[:, :2], axis=0).max())
    tol = GRID_TOLERANCE * size
    off_row = np.flatnonzero(np.abs(p[:, 1] - p[0, 1]) > tol)
    nx = int(off_row[0]) if len(off_row) else n
    ny = n // nx
    if nx < 2 or ny < 2 or nx * ny != n or np.ptp(p[:, 2]) > tol:
        return None
    width, length = p[nx - 1, 0] - p[0, 0], p[n - 1, 1] - p[0, 1]
    if width <= tol or length <= tol:
        return None
    col, row = np.tile(np.arange(nx), ny), np.repeat(np.arange(ny), nx)
    expected = np.stack([p[0, 0] + col * (width / (nx - 1)), p[0, 1] + row * (length / (ny - 1))], axis=1)
    if np.abs(p[:, :2] - expected).max() > tol:
        return None
    cells = grid_cells(nx, ny)
    faces = mesh.blocks[0]
    if len(faces) != len(cells):
        return None
    same = np.array_equal(np.unique(np.sort(faces, axis=1), axis=0), np.unique(np.sort(cells, axis=1), axis=0))
    return (nx, ny, float(width), float(length)) if same else None


def face_areas(mesh: MeshFile) -> np.ndarray:
    """Each face's area (k,) m2: a quad's is that of its two triangles."""
    return np.bincount(mesh.face_of, triangle_areas(mesh.points, mesh.triangles), minlength=len(mesh.corners))


def vertex_areas(mesh: MeshFile) -> np.ndarray:
    """Each vertex's area (n,) m2: its shares of the triangles (a quad's: its split), by the same mixed
    Voronoi areas that share their face drag (``corner_shares``), so that a uniform load per area gives
    every particle the same acceleration (docs/model.md section 2.4)."""
    t = mesh.triangles
    share = corner_shares(mesh.points.T, t) * triangle_areas(mesh.points, t)[:, None]
    return np.bincount(t.ravel(), share.ravel(), minlength=mesh.n)


def flat_coordinates(points: np.ndarray, area: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The points (n, 3) projected onto their best-fitting plane (area-weighted principal axes, centred on the
    area-weighted centroid) (2, n) m.  The plane's normal points along the triangles' mean normal; its first
    axis is the x axis's projection (the y axis's for a plane nearly across x), so a mesh in the xy plane keeps
    its x and y."""
    centroid = area @ points / area.sum()
    d = points - centroid
    normal = np.linalg.eigh((d.T * area) @ d)[1][:, 0]
    p = points[triangles]
    if normal @ np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]).sum(axis=0) < 0.0:
        normal = -normal
    axis = np.eye(3)[0] if abs(normal[0]) < 0.9 else np.eye(3)[1]
    first = axis - (axis @ normal) * normal
    first /= np.linalg.norm(first)
    second = np.cross(normal, first)
    return np.stack([d @ first, d @ second])


#: How far inside another face a point of a face must lie, seen along the cloth's best-fitting plane (the
#: least of its barycentric coordinates there), for flat_overlap to call the two overlapping.
OVERLAP_DEPTH = 1e-3


def flat_overlap(rest_xy: np.ndarray, triangles: np.ndarray) -> tuple[int, int] | None:
    """Two triangles (rows of ``triangles`` (m, 3)) that share no vertex and overlap in the flat rest sheet
    ``rest_xy`` (2, n) m, a point of the first (its centroid, or a point halfway from there to a corner) inside
    the second by OVERLAP_DEPTH, or None: a mesh that folds over itself or holds stacked layers, which
    self-collision cannot take (its pairs and bounds are set in the flat rest sheet, docs/model.md section
    6.2).  (Four points, not the centroid alone: a quad sheet folded onto itself along a grid line puts the
    centroids of one layer's triangles on the diagonals of the other's quads.)"""
    from scipy.spatial import cKDTree

    corners = rest_xy.T[triangles]  # (m, 3, 2)
    centroid = corners.mean(axis=1)
    samples = np.concatenate([centroid[:, None], 0.5 * (corners + centroid[:, None])], axis=1).reshape(-1, 2)
    reach = np.linalg.norm(corners - centroid[:, None], axis=2).max(axis=1)
    near = cKDTree(samples).query_ball_point(centroid, reach, return_sorted=False)  # per container: the samples in reach
    count = np.fromiter(map(len, near), dtype=np.int64, count=len(near))
    container = np.repeat(np.arange(len(near)), count)
    sample = np.fromiter(itertools.chain.from_iterable(near), dtype=np.int64, count=int(count.sum()))
    inside = sample // 4
    shared = (triangles[inside][:, :, None] == triangles[container][:, None, :]).any(axis=(1, 2))
    container, inside, sample = container[~shared], inside[~shared], sample[~shared]
    a, b, c = (corners[container, k] for k in range(3))
    e1, e2, q = b - a, c - a, samples[sample] - a
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    scale = np.einsum("ij,ij->i", e1, e1) + np.einsum("ij,ij->i", e2, e2)
    solid = np.abs(det) > 1e-12 * scale  # (a face seen edge-on contains nothing)
    det = np.where(solid, det, 1.0)
    u = (q[:, 0] * e2[:, 1] - q[:, 1] * e2[:, 0]) / det
    v = (e1[:, 0] * q[:, 1] - e1[:, 1] * q[:, 0]) / det
    hit = np.flatnonzero(solid & (u > OVERLAP_DEPTH) & (v > OVERLAP_DEPTH) & (1.0 - u - v > OVERLAP_DEPTH))
    return (int(inside[hit[0]]), int(container[hit[0]])) if len(hit) else None


def uv_layout(mesh: MeshFile, area: np.ndarray) -> np.ndarray | None:
    """The mesh laid out flat by its per-vertex UVs (2, n) m, each connected part scaled to its edges' lengths
    (the least-squares scale of its UV edges to its edges) and centred on the area-weighted centroid, or None
    where the file has no UVs or a part's UV triangles are not all turned the same way (a fold in the map)."""
    if mesh.uv is None:
        return None
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    edges = face_edges(mesh.blocks)[0]
    n = mesh.n
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    parts, part = connected_components(graph, directed=False)
    uv = np.asarray(mesh.uv, dtype=float)
    along = np.linalg.norm(mesh.points[edges[:, 1]] - mesh.points[edges[:, 0]], axis=1)
    mapped = np.linalg.norm(uv[edges[:, 1]] - uv[edges[:, 0]], axis=1)
    edge_part = part[edges[:, 0]]
    scale = (np.bincount(edge_part, along * mapped, parts)
             / np.maximum(np.bincount(edge_part, mapped * mapped, parts), np.finfo(float).tiny))
    a, b, c = (uv[mesh.triangles[:, k]] for k in range(3))
    turn = np.sign((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    triangle_part = part[mesh.triangles[:, 0]]
    if np.any(turn == 0) or np.any(np.bincount(triangle_part, turn, parts) ** 2
                                   != np.bincount(triangle_part, minlength=parts) ** 2):
        return None
    laid = uv * scale[part][:, None]
    return (laid - area @ laid / area.sum()).T


def flat_sheet(mesh: MeshFile, area: np.ndarray) -> tuple[np.ndarray, tuple[int, int] | None]:
    """The flat rest sheet (2, n) m of a mesh cloth and two of its triangles that overlap there (flat_overlap;
    None if none do): its points projected onto their best-fitting plane (flat_coordinates), or, where those
    lie over themselves and its UVs lay it out flat without overlap (uv_layout), the UVs' layout (a towel
    folded in its file, unwrapped flat in its UV map)."""
    projected = flat_coordinates(mesh.points, area, mesh.triangles)
    overlap = flat_overlap(projected, mesh.triangles)
    laid = uv_layout(mesh, area) if overlap is not None else None
    if laid is not None and flat_overlap(laid, mesh.triangles) is None:
        return laid, None
    return projected, overlap


@functools.lru_cache(maxsize=8)
def mesh_flat_sheet(mesh: MeshFile) -> tuple[np.ndarray, tuple[int, int] | None]:
    """flat_sheet of ``mesh`` (its layout read-only), once per mesh: the scene's check (scene.py) and its topology
    both want it, and a study checks every run's scene (18 ms each on the 2k-vertex tablecloth)."""
    laid, overlap = flat_sheet(mesh, vertex_areas(mesh))
    laid.setflags(write=False)
    return laid, overlap


def _mesh(scene: Scene, mesh: MeshFile, faces: MeshFaces | None) -> Topology:
    n = mesh.n
    area = vertex_areas(mesh)
    springs = listed_springs(mesh, scene)
    length = float(np.median(springs["pair_rest"][springs["pair_kind"] == STRETCH]))
    empty = np.zeros((0, n))
    rest_xy = mesh_flat_sheet(mesh)[0]
    return Topology(
        nx=n, ny=1, dx=length, dy=length, rest_pos=mesh.points.T.copy(), rest_xy=rest_xy, area=area,
        spring_offset=np.zeros(0, dtype=np.int64), spring_rest=np.zeros(0), spring_tension_only=np.zeros(0, dtype=bool),
        spring_stiffness=empty, spring_damping=empty.copy(), spring_shape=empty.copy(), spring_family_names=(),
        triangles=mesh.triangles.copy(), pinned=np.zeros(n, dtype=bool), **springs, mesh=faces,
        size=float(np.ptp(rest_xy, axis=1).max()),
    )


def listed_springs(mesh: MeshFile, scene: Scene) -> dict:
    """The listed springs of a mesh (docs/model.md section 2.4), as Topology's ``pair_*`` fields.

    Stretch springs along every edge, tension-only along the edges of quads only, buckling (both ways,
    the push bounded: spring_law.hpp) along those of a triangle; shear springs along each quad's diagonals,
    tension-only; then, unless ``bend_rigidity`` is set, bending springs join a and b across a vertex v whose
    edges (v, a), (v, b) lie on quads only, share no face and make an angle above BEND_ANGLE (strip
    a_s(v, a) + a_s(v, b)), and the opposite corners of two triangles that share an edge (strip: their areas).
    A quad spreads three times its area evenly over its 4 edges and 2 diagonals, a triangle its stiffness
    over its edges as ``triangle_edge_shapes`` says; an edge's strip area a_s sums its faces'.
    k = modulus * a_s / l^2, c = damping * a_s / l^2 (a_s / l^2: the shape).  With ``bend_rigidity`` D > 0
    every face bends by hinges instead (``bend_stiffness`` unused), their terms last (``hinge_terms``):
    k = D * shape, c = (damping / stretch_stiffness) * k."""
    p = mesh.points
    area = face_areas(mesh)
    rows, owner = face_edges(mesh.blocks)
    quad = mesh.corners[owner] == 4
    edges, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    strip = np.bincount(inverse, np.where(quad, 0.5, 1.0) * area[owner], minlength=len(edges))
    edge_length = np.linalg.norm(p[edges[:, 1]] - p[edges[:, 0]], axis=1)
    on_triangle = np.bincount(inverse, ~quad, minlength=len(edges)) > 0
    # the second row of each edge shared by two faces
    second = np.full(len(edges), -1)
    others = np.flatnonzero(np.arange(len(rows)) != first[inverse])
    second[inverse[others]] = others
    face1, face2 = owner[first], np.where(second >= 0, owner[np.maximum(second, 0)], -1)

    # a stretch spring's strip (k l^2 / modulus): its quads' as the strips, its triangles' shares of their membrane
    row_strip = np.where(quad, 0.5 * area[owner], 0.0)
    start = 0
    for block in mesh.blocks:
        if block.shape[1] == 3:  # its rows: edge j (corner j to j + 1) of each triangle in turn
            here = slice(start, start + block.size)
            row_strip[here] = (triangle_edge_shapes(p, block) * edge_length[inverse[here]].reshape(-1, 3) ** 2).ravel()
        start += block.size
    stretch = np.bincount(inverse, row_strip, minlength=len(edges))
    groups = [(edges[~on_triangle], stretch[~on_triangle], STRETCH)]
    quads = [b for b in mesh.blocks if b.shape[1] == 4]
    if quads:
        q = np.concatenate(quads)
        quad_area = area[mesh.corners == 4]
        diagonals = np.concatenate([q[:, [0, 2]], q[:, [1, 3]]])
        groups.append((np.sort(diagonals, axis=1), np.tile(0.5 * quad_area, 2), SHEAR))
    groups.append((edges[on_triangle], stretch[on_triangle], STRETCH))
    shared = np.flatnonzero(second >= 0)  # the edges two faces share
    if scene.bend_stiffness != 0.0 and scene.bend_rigidity == 0.0:
        groups.append(_vertex_bends(p, edges, strip, face1, face2, ~on_triangle))
        groups.append(_triangle_bends(mesh, rows, first, second, face1, face2, area))

    pairs = np.concatenate([g[0] for g in groups]).T.astype(np.int64)
    kind = np.concatenate([np.full(len(g[0]), g[2], dtype=np.int8) for g in groups])
    rest = np.linalg.norm(p[pairs[1]] - p[pairs[0]], axis=1)
    shape = np.concatenate([g[1] for g in groups]) / rest**2
    if scene.bend_rigidity != 0.0:
        if len(shared) == 0:
            raise ParameterError("bend_rigidity", f"{scene.bend_rigidity!r} N m bends a cloth across the edges that two "
                                                  f"faces share, and {mesh.source} has none; allowed: 0 N m (no bending)")
        hinge_pairs, hinge_shape = hinge_terms(mesh, edges[shared], face1[shared], face2[shared])
        pairs = np.concatenate([pairs, hinge_pairs], axis=1)
        kind = np.concatenate([kind, np.full(len(hinge_shape), HINGE, dtype=np.int8)])
        rest = np.concatenate([rest, np.zeros(len(hinge_shape))])
        shape = np.concatenate([shape, hinge_shape])
    modulus = np.select([kind == BEND, kind == HINGE], [scene.bend_stiffness, scene.bend_rigidity], scene.stretch_stiffness)
    damping = np.where(kind == HINGE, scene.damping / scene.stretch_stiffness * scene.bend_rigidity, scene.damping)
    buckling = int(np.count_nonzero(on_triangle))
    return dict(pairs=pairs, pair_rest=rest, pair_stiffness=modulus * shape, pair_damping=damping * shape,
                pair_shape=shape, pair_kind=kind, pair_tension_count=int(np.count_nonzero(kind < BEND)) - buckling,
                pair_buckling_count=buckling)


def _triangle_bends(mesh: MeshFile, rows, first, second, face1, face2, area):
    """Bending springs across the edges two triangles share, between the corners opposite the edge (strip: the
    two triangles' areas)."""
    opposite = np.full(len(rows), -1)
    start = 0
    for b in mesh.blocks:
        if b.shape[1] == 3:  # edge j (corner j to j + 1) faces corner j + 2
            opposite[start:start + 3 * len(b)] = np.roll(b, -2, axis=1).ravel()
        start += b.size
    corners = mesh.corners
    shared = np.flatnonzero((second >= 0) & (corners[face1] == 3) & (corners[np.maximum(face2, 0)] == 3))
    across = np.column_stack([opposite[first[shared]], opposite[second[shared]]])
    return np.sort(across, axis=1), area[face1[shared]] + area[face2[shared]], BEND


def hinge_terms(mesh: MeshFile, edges: np.ndarray, face1: np.ndarray,
                face2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The quadratic bending of a mesh (docs/model.md section 2.4) as springs of rest length 0: their pairs (2, P)
    int64 and shapes k / D (P,) 1/m^2 (a pair that several terms share once).  Its terms:

    - a hinge across each edge (i, j) (``edges`` (h, 2)) that faces ``face1`` and ``face2`` (h,) share, unfolded
      flat from the rest mesh: D |e|^2 / (2 (c1 A1 + c2 A2)) (g2 - g1)^2, g the two faces' slopes across the
      edge (a triangle's linear interpolant's, a quad's bilinear one's at its centre), c = 1 for a triangle (Bergou
      et al. 2006's hinge, linearised about the flat sheet) and 1/2 for a quad (its area shared by its two pairs
      of opposite edges): across a regular grid of quads, D / 2 (H_xx^2 + H_yy^2) per area for a bend H;
    - each quad's twist (corners 0..3 in turn), D A / (|a|^2 |b|^2) (t0 x0 - t1 x1 + t2 x2 - t3 x3)^2, a and b the
      mean of its opposite edges, t_m the area of the triangle of its other three corners over A / 2 (1 on a
      parallelogram; so that an affine field stores nothing): D H_xy^2 per area on a rectangle, so that quads
      store D |H|^2 / 2 whichever way they bend.

    A flat or rigidly moved sheet stores nothing: each term is |sum_m w_m x_m|^2 with sum_m w_m = 0, the sum over
    its pairs of -w_a w_b |x_a - x_b|^2, springs of stiffness -2 S w_a w_b for a term of weight S (some negative;
    each term's sum positive semidefinite)."""
    p = mesh.points
    faces = _padded_faces(mesh)
    area = face_areas(mesh)
    i, j = edges[:, 0], edges[:, 1]
    edge = p[j] - p[i]
    length = np.linalg.norm(edge, axis=1)
    u = edge / length[:, None]

    def unfolded(f, side):
        """Face f's corners (h, 4) and their coordinates (h, 4, 2) along the edge from i and across it on
        ``side`` (toward the face's centroid) in the hinge unfolded flat (m)."""
        corners = faces[f]
        a = p[np.maximum(corners, 0)] - p[i][:, None, :]
        along = _dot(a, u[:, None, :])
        off = a - along[..., None] * u[:, None, :]
        inward = off[:, 0] + off[:, 1] + off[:, 2] + off[:, 3] * (corners[:, 3:] >= 0)
        inward /= np.linalg.norm(inward, axis=1)[:, None]
        return corners, np.stack([along, side * _dot(off, inward[:, None, :])], axis=2)

    corners1, flat1 = unfolded(face1, -1.0)
    corners2, flat2 = unfolded(face2, 1.0)
    share = np.where(mesh.corners == 3, 1.0, 0.5) * area  # c A of each face
    weight = share[face1] + share[face2]
    slots = np.concatenate([corners1, corners2], axis=1)
    w = np.concatenate([-_across_slope(flat1, mesh.corners[face1]), _across_slope(flat2, mesh.corners[face2])], axis=1)
    terms = [(slots, w, 0.5 * length**2 / weight)]
    quads = np.flatnonzero(mesh.corners == 4)
    if len(quads):
        q = faces[quads]
        x = [p[q[:, m]] for m in range(4)]
        a, b = 0.5 * (x[1] - x[0] + x[2] - x[3]), 0.5 * (x[3] - x[0] + x[2] - x[1])
        # the weights that take nothing from an affine map: each corner's the area of the triangle of the other
        # three (signed about the quad's normal: a dart's too), signs alternating, over half the quad's
        normal = np.cross(x[2] - x[0], x[3] - x[1])
        normal /= np.linalg.norm(normal, axis=1)[:, None]
        left = [_dot(np.cross(x[(m + 2) % 4] - x[(m + 1) % 4], x[(m + 3) % 4] - x[(m + 1) % 4]), normal) for m in range(4)]
        twist = np.column_stack([left[0], -left[1], left[2], -left[3]]) / area[quads][:, None]
        terms.append((q, twist, area[quads] / (_dot(a, a) * _dot(b, b))))
    pairs, shapes = [], []
    for slots, w, strength in terms:
        for m, k in itertools.combinations(range(slots.shape[1]), 2):
            keep = (slots[:, m] >= 0) & (slots[:, k] >= 0) & (slots[:, m] != slots[:, k])
            pairs.append(np.sort(slots[keep][:, [m, k]], axis=1))
            shapes.append(-2.0 * strength[keep] * w[keep, m] * w[keep, k])
    unique, inverse = np.unique(np.concatenate(pairs), axis=0, return_inverse=True)
    return unique.T.astype(np.int64), np.bincount(inverse.ravel(), np.concatenate(shapes), minlength=len(unique))


def _padded_faces(mesh: MeshFile) -> np.ndarray:
    """Every face's corners (k, 4) in the file's order, a triangle's fourth -1."""
    faces = np.full((len(mesh.corners), 4), -1, dtype=np.int64)
    start = 0
    for b in mesh.blocks:
        faces[start:start + len(b), :b.shape[1]] = b
        start += len(b)
    return faces


def _across_slope(flat: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """The weights (h, 4) on a face's corners of its slope across the edge (the second coordinate of ``flat``
    (h, 4, 2) m): a triangle's linear interpolant's (its fourth weight 0), a quad's bilinear one's at its centre."""
    x = [flat[:, m] for m in range(4)]
    # a triangle (a, b, c): grad = [b - a; c - a]^-1 (z_b - z_a, z_c - z_a)
    (b0, b1), (c0, c1) = (x[1] - x[0]).T, (x[2] - x[0]).T
    det = np.where(corners == 3, b0 * c1 - b1 * c0, 1.0)
    wb, wc = -c0 / det, b0 / det
    triangle = np.column_stack([-(wb + wc), wb, wc, np.zeros(len(flat))])
    # a quad: grad = [a b]^-T (z_xi, z_eta), a and b the mean of its opposite edges, z_xi and z_eta likewise
    a, b = 0.5 * (x[1] - x[0] + x[2] - x[3]), 0.5 * (x[3] - x[0] + x[2] - x[1])
    quad_det = np.where(corners == 4, a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], 1.0)
    along_xi, along_eta = -b[:, 0] / quad_det, a[:, 0] / quad_det
    xi, eta = np.array([-1.0, 1.0, 1.0, -1.0]), np.array([-1.0, -1.0, 1.0, 1.0])  # z_xi and z_eta's weights, doubled
    quad = 0.5 * (along_xi[:, None] * xi + along_eta[:, None] * eta)
    return np.where((corners == 3)[:, None], triangle, quad)


#: The isotropic membrane a triangle's three edge springs stand for, per unit Young's modulus: Poisson's
#: ratio 1/3, the one that three springs can give (their stiffness tensor is fully symmetric), so
#: C_1111 = C_2222 = 9/8, C_1122 = C_1212 = 3/8 (C_1112 = C_1222 = 0), as (C_1111, C_1112, C_1122, C_1222,
#: C_2222) weighted by the square roots of their multiplicities (1, 4, 6, 4, 1) in the tensor's norm.
_MULTIPLICITY = np.sqrt([1.0, 4.0, 6.0, 4.0, 1.0])
_ISOTROPIC = np.array([9 / 8, 0.0, 3 / 8, 0.0, 9 / 8]) * _MULTIPLICITY
#: Subsets of a triangle's three springs, to fit the membrane with non-negative stiffnesses.
_SUBSETS = [s for size in (3, 2, 1) for s in itertools.combinations(range(3), size)]


def triangle_edge_shapes(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Each triangle's (m, 3) stiffness per unit modulus of its edges j (corner j to corner j + 1), as shape
    k / modulus (-): the springs whose stiffness tensor under a uniform strain, sum_e (k_e l_e^2 / A) n_e^4,
    comes nearest (least squares over its components, non-negative k; van Gelder 1998) to the isotropic
    membrane's (_ISOTROPIC), so that a mesh of any triangles stretches as the sheet it stands for.  Element-wise
    arithmetic in a fixed order only (no LAPACK, no einsum), so that every numpy (Blender's too) gives the same
    bits for the same mesh."""
    p = points[triangles]
    d = np.roll(p, -1, axis=1) - p  # (m, 3 edges, 3)
    length = np.sqrt(_dot(d, d))
    cross = np.cross(d[:, 0], -d[:, 2])
    double_area = np.sqrt(_dot(cross, cross))
    e1 = d[:, 0] / length[:, :1]
    e2 = np.cross(cross / double_area[:, None], e1)
    c = _dot(d, e1[:, None, :]) / length
    s = _dot(d, e2[:, None, :]) / length
    cc, ss = c * c, s * s  # products, not powers: numpy's pow differs between versions
    basis = np.stack([cc * cc, cc * c * s, cc * ss, c * ss * s, ss * ss], axis=1) * _MULTIPLICITY[:, None]  # (m, 5, 3)
    best = np.zeros((len(p), 3))
    best_misfit = np.full(len(p), np.inf)
    for subset in _SUBSETS:
        b = [basis[:, :, i] for i in subset]  # each (m, 5)
        normal = [[_dot(bi, bj) for bj in b] for bi in b]
        right = [_dot(bi, _ISOTROPIC) for bi in b]
        with np.errstate(divide="ignore", invalid="ignore"):  # a singular fit gives nan: never the best
            x = _cramer(normal, right)
        fitted = b[0] * x[0][:, None]
        for bi, xi in zip(b[1:], x[1:]):
            fitted = fitted + bi * xi[:, None]
        residual = fitted - _ISOTROPIC
        misfit = _dot(residual, residual)
        better = np.logical_and.reduce([xi >= 0.0 for xi in x]) & (misfit < best_misfit)
        best[better] = 0.0
        for i, xi in zip(subset, x):
            best[better, i] = xi[better]
        best_misfit[better] = misfit[better]
    return best * (0.5 * double_area)[:, None] / (length * length)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Sum over the last axis of a * b, term by term in order (the same bits on every numpy and CPU)."""
    a, b = np.broadcast_arrays(a, b)
    total = a[..., 0] * b[..., 0]
    for k in range(1, a.shape[-1]):
        total = total + a[..., k] * b[..., k]
    return total


def _determinant(m: list) -> np.ndarray:
    """The determinant of a 1 x 1, 2 x 2 or 3 x 3 matrix of arrays (rows of columns), written out."""
    if len(m) == 1:
        return m[0][0]
    if len(m) == 2:
        return m[0][0] * m[1][1] - m[0][1] * m[1][0]
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


def _cramer(m: list, right: list) -> list:
    """The solution of m x = right for up to 3 unknowns (arrays), by Cramer's rule."""
    det = _determinant(m)
    return [_determinant([[right[r] if c == i else m[r][c] for c in range(len(m))] for r in range(len(m))]) / det
            for i in range(len(m))]


def _vertex_bends(p, edges, strip, face1, face2, quad_only):
    """Bending springs across the vertices of the quads (see listed_springs)."""
    e = np.flatnonzero(quad_only)
    centre = np.concatenate([edges[e, 0], edges[e, 1]])
    end = np.concatenate([edges[e, 1], edges[e, 0]])
    edge = np.concatenate([e, e])
    order = np.argsort(centre, kind="stable")
    centre, end, edge = centre[order], end[order], edge[order]
    limit = math.cos(math.radians(BEND_ANGLE))
    found_a, found_b = [], []
    for gap in range(1, int(np.bincount(centre).max(initial=1))):
        i = np.flatnonzero(centre[:-gap] == centre[gap:])
        a, b = i, i + gap
        ea, eb = edge[a], edge[b]
        share = ((face1[ea] == face1[eb]) | (face1[ea] == face2[eb])
                 | ((face2[ea] >= 0) & ((face2[ea] == face1[eb]) | (face2[ea] == face2[eb]))))
        u, w = p[end[a]] - p[centre[a]], p[end[b]] - p[centre[b]]
        cos = np.einsum("ij,ij->i", u, w) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1))
        keep = ~share & (cos < limit)
        found_a.append(a[keep])
        found_b.append(b[keep])
    a = np.concatenate(found_a) if found_a else np.zeros(0, dtype=np.int64)
    b = np.concatenate(found_b) if found_b else np.zeros(0, dtype=np.int64)
    return np.sort(np.stack([end[a], end[b]], axis=1), axis=1).reshape(-1, 2), strip[edge[a]] + strip[edge[b]], BEND


# ----------------------------------------------------------------------------------------- placement, pins
def initial_positions(scene: Scene, topo: Topology) -> np.ndarray:
    """Particle positions (3, n) m at t = 0 (docs/model.md section 2.4).  The built-in grid: flat,
    centred over the origin at ``initial_height``, tilted by ``initial_tilt`` about x.  A mesh file: its
    coordinates (place_mesh 'off'), or (place_mesh 'on') turned by ``initial_tilt`` about the x axis
    through its area-weighted centroid, and shifted so that the centroid is at ``initial_height``."""
    tilt = math.radians(scene.initial_tilt)
    pos = np.empty((3, topo.n))
    if topo.mesh is None:
        x, y = topo.rest_xy
        pos[0] = x
        pos[1] = y * math.cos(tilt)
        pos[2] = scene.initial_height + y * math.sin(tilt)
        return pos
    return placed(scene, topo.rest_pos, topo.area)


def placed(scene: Scene, rest_pos: np.ndarray, area: np.ndarray) -> np.ndarray:
    """A mesh's rest positions (3, n) m placed by the rule of ``initial_positions``."""
    if scene.place_mesh == "off":
        return rest_pos.copy()
    tilt = math.radians(scene.initial_tilt)
    centre = rest_pos @ area / area.sum()
    y, z = rest_pos[1] - centre[1], rest_pos[2] - centre[2]
    return np.stack([rest_pos[0].copy(), centre[1] + y * math.cos(tilt) - z * math.sin(tilt),
                     scene.initial_height + y * math.sin(tilt) + z * math.cos(tilt)])


def start_positions(scene: Scene) -> tuple[np.ndarray, MeshFile | None]:
    """The particle positions (3, n) m at t = 0 and the mesh file (None for the built-in grid), without
    building the springs (for the scene's checks)."""
    if not is_mesh(scene.cloth_mesh):
        return initial_positions(scene, _grid(scene, scene.nx, scene.ny, scene.width, scene.length)), None
    mesh = read_mesh_file(scene.cloth_mesh)
    return placed(scene, mesh.points.T, vertex_areas(mesh)), mesh


def pinned_mask(scene: Scene, positions: np.ndarray, mesh: MeshFile | None) -> np.ndarray:
    """The pinned particles (n,) bool: ``pinned_edge`` (the built-in grid only) and ``pinned_vertices``
    (a point attribute of the mesh file, nonzero pinned, or a box over ``positions`` (3, n) m at t = 0)."""
    n = positions.shape[1]
    pinned = np.zeros(n, dtype=bool)
    if scene.pinned_edge != "none":
        if mesh is not None:
            raise ParameterError("pinned_edge", f"{scene.pinned_edge!r} is an edge of the nx x ny rectangle, but the "
                                                "cloth comes from cloth_mesh (pin its vertices with pinned_vertices: "
                                                "a point attribute or a box); allowed here: 'none'")
        col, row = np.arange(n) % scene.nx, np.arange(n) // scene.nx
        pinned |= {"x_min": col == 0, "x_max": col == scene.nx - 1, "y_min": row == 0,
                   "y_max": row == scene.ny - 1}[scene.pinned_edge]
    spec = scene.pinned_vertices.strip()
    if spec.startswith("box:"):
        pinned |= _box(spec, positions)
    elif spec:
        pinned |= _attribute(spec, mesh)
    return pinned


def _pin_error(message: str) -> ParameterError:
    return ParameterError("pinned_vertices", f"{message}; allowed: {PINS_ALLOWED}")


def _box(spec: str, positions: np.ndarray) -> np.ndarray:
    try:
        values = [float(v) for v in spec[4:].split(",")]
    except ValueError:
        values = []
    if len(values) != 6 or not all(map(math.isfinite, values)):
        raise _pin_error(f"{spec!r} is not a box of six numbers")
    lo, hi = np.array(values[:3])[:, None], np.array(values[3:])[:, None]
    if (lo > hi).any():
        raise _pin_error(f"{spec!r}: a lower corner is above the upper one")
    inside = ((positions >= lo) & (positions <= hi)).all(axis=0)
    if not inside.any():
        span = ", ".join(f"{c} {positions[k].min():g} .. {positions[k].max():g}" for k, c in enumerate("xyz"))
        raise _pin_error(f"the box {spec!r} holds no vertex of the cloth at t = 0 (it spans {span} m)")
    return inside


def _attribute(name: str, mesh: MeshFile | None) -> np.ndarray:
    if mesh is None:
        raise _pin_error(f"{name!r} names a point attribute, but the cloth is the nx x ny rectangle (cloth_mesh "
                         "is empty): pin it with a box")
    values = mesh.attributes.get(name)
    if values is None:
        available = ", ".join(repr(k) for k in mesh.attributes) or "none"
        raise _pin_error(f"{name!r} is not a point attribute of {mesh.source!r} (its point attributes: {available})")
    values = np.asarray(values).reshape(mesh.n, -1)
    if values.shape[1] != 1:
        raise _pin_error(f"the point attribute {name!r} of {mesh.source!r} has {values.shape[1]} components, "
                         "not one")
    return values[:, 0] != 0


def cloth_order(triangles: np.ndarray) -> np.ndarray:
    """The order (m,) in which the core takes a mesh's ``triangles`` (m, 3) for its face drag and frames: by
    their least vertex, stably, so that neighbouring triangles meet neighbouring particles' records in the
    cache (a file's order, Delaunay's for one, may jump across the mesh).  The native unit's own sort
    (model.cpp) gives the same order."""
    return np.argsort(triangles.min(axis=1), kind="stable")


def corner_shares(rest_pos: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Each corner's share (m, 3) of its triangle, by the rest sheet's mixed Voronoi areas (Meyer et al.
    2003): in a triangle without an obtuse angle the part of it nearer that corner than the others; in an
    obtuse one 1/2 to the obtuse corner and 1/4 to each other.  A grid's right triangles give the grid's
    1/2 to the right-angle corner and 1/4 to the others.  (The core shares a triangle's drag so.)"""
    p = [rest_pos[:, triangles[:, k]].T for k in range(3)]  # corners (m, 3) each
    shares = np.empty((len(triangles), 3))
    cot = np.empty_like(shares)
    for k in range(3):
        u, w = p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]
        cot[:, k] = np.einsum("ij,ij->i", u, w) / np.linalg.norm(np.cross(u, w), axis=1)
    for k in range(3):
        far1, far2 = (k + 1) % 3, (k + 2) % 3  # Voronoi: (|e_k,far1|^2 cot(far2) + |e_k,far2|^2 cot(far1)) / 8
        shares[:, k] = (np.sum((p[far1] - p[k]) ** 2, axis=1) * cot[:, far2]
                        + np.sum((p[far2] - p[k]) ** 2, axis=1) * cot[:, far1]) / 8.0
    area = 0.5 * np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0]), axis=1)
    shares /= area[:, None]
    obtuse = cot < 0.0  # cot of the angle at each corner
    for k in range(3):
        rows = obtuse[:, k]
        shares[rows] = 0.25
        shares[rows, k] = 0.5
    return shares
