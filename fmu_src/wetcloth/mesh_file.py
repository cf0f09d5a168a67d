"""A cloth's mesh file (scene parameter ``cloth_mesh``): its vertices, faces, UVs and point attributes.

From Python a mesh may also be given as arrays, with no file: ``cloth_mesh`` takes the MeshFile that
``make_mesh`` builds (checked as a file's mesh is), a mesh collider's ``file`` the one ``surface`` builds
(checked where a collider file's triangles are, ``collider_meshes.mesh_of``).  The Blender extension
bakes its objects so, as Blender ships neither meshio nor trimesh.

OBJ, PLY, OFF and VTK/VTU are read with meshio, which keeps the file's vertex order, its quads and
its point data; glTF/GLB (which meshio does not read) and STL with trimesh.  A file of another suffix is
read with meshio if meshio knows the suffix (gmsh .msh, Medit .mesh, Abaqus .inp, ...), else with trimesh
if trimesh does (a suffix neither knows is refused).  A file meshio fails to parse is read with trimesh
where trimesh knows its suffix too (a binary PLY with face colours, for one).  An STL file stores each
triangle's own corners: its exactly equal vertices are merged, numbered in order of first appearance.
An OBJ file's normals (``vn``) are not read, nor its UVs (``vt``) unless each face corner's ``vt``
index is its ``v`` index (UVs per vertex; at a UV seam they are per corner, which a particle cannot
have).  Triangles and quads may be mixed; a face of more corners, a mesh without faces, a mesh more than
LARGEST_SIZE across (a file in millimetres read as metres) or less than scene.SMALLEST_SIZE, a coordinate
or point attribute that is not a finite number, a zero-area face, a vertex in no face, two vertices at the
same place (a seam: the cloth would fall apart along it) and an edge in more than two faces are refused
with a ParameterError naming ``cloth_mesh`` (the springs need each edge in at most two faces).  A mesh
given as arrays (make_mesh) is checked as a file's.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import io
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wetcloth.errors import ParameterError

NAME = "cloth_mesh"
#: File suffixes read with meshio and with trimesh.
MESHIO_SUFFIXES = (".obj", ".ply", ".off", ".vtk", ".vtu")
TRIMESH_SUFFIXES = (".stl", ".gltf", ".glb")
SUFFIXES = MESHIO_SUFFIXES + TRIMESH_SUFFIXES
#: The formats a mesh file may have, as messages say.
FORMATS = ", ".join(SUFFIXES) + " or another that meshio or trimesh reads, e.g. gmsh .msh"
#: What ``cloth_mesh`` allows, as its messages say (the scene parameter's range text).
ALLOWED = ("'' (the nx x ny rectangle) or the path of a mesh file (" + FORMATS + ") of triangles "
           "and quads with an area each, every vertex in a face, no two vertices at the same place and every edge in "
           "at most two faces (from Python "
           "also such a mesh as arrays: wetcloth.mesh_file.make_mesh)")
#: m: the largest extent of a cloth along any axis (a mesh's, and the rectangle's width and length: scene.py).
LARGEST_SIZE = 100.0
#: A face is degenerate when a triangle of it has area below this fraction of the median edge length squared.
DEGENERATE_AREA = 1e-10
#: Folders where a relative mesh path is looked for after the working directory (a unit's resources).
SEARCH_FOLDERS: list[Path] = []
#: Point-data names read as per-vertex UVs (meshio's OBJ 'vt', PLY's usual texture names).
UV_NAMES = (("obj:vt",), ("texture_u", "texture_v"), ("s", "t"), ("u", "v"))


@dataclass(frozen=True, eq=False)
class MeshFile:
    """A cloth mesh as read, or given as arrays (compared by identity, as a scene's value).

    ``points`` (n, 3) float64 m; ``faces`` (k, 3) or (k, 4) int64 in file order
    (mixed triangles and quads: the triangles of their split); ``triangles`` (m, 3) int64 (each quad
    (a, b, c, d) split into (a, b, c), (a, c, d)), oriented consistently; ``face_of`` (m,) the face of
    each triangle; ``corners`` (k,) 3 or 4; ``uv`` (n, 2) or None; ``attributes`` name -> (n,) point data;
    ``source`` the path; ``blocks`` the faces as read, runs of triangles (j, 3) and quads (j, 4) in file order."""

    points: np.ndarray
    faces: np.ndarray
    triangles: np.ndarray
    face_of: np.ndarray
    corners: np.ndarray
    uv: np.ndarray | None
    attributes: dict
    source: str
    blocks: tuple

    @property
    def n(self) -> int:
        return len(self.points)


def _error(message: str) -> ParameterError:
    return ParameterError(NAME, f"{message}; allowed: {ALLOWED}")


def locate(path: str | Path) -> Path:
    """A mesh file's path: as given if absolute or found from the working directory, else in the first
    of SEARCH_FOLDERS that holds it (else as given)."""
    path = Path(path)
    if path.is_absolute() or path.exists():
        return path
    return next((folder / path for folder in SEARCH_FOLDERS if (folder / path).is_file()), path)


def read_mesh_file(path: "str | Path | MeshFile") -> MeshFile:
    """The checked mesh of file ``path`` (see ``locate``; read again only when the file changes), or
    ``path`` itself if it is a mesh given as arrays (a MeshFile)."""
    if isinstance(path, MeshFile):
        return path
    path = locate(path)
    try:
        digest = content_key(path)
    except OSError as exc:
        raise _error(f"{str(path)!r} cannot be read: {exc.strerror or exc}") from None
    return _read_cached(str(path.resolve()), digest, str(path))


def content_key(path: str | Path) -> str:
    """The blake2b digest of a file's bytes, the mesh caches' key: a rewrite that keeps the file's size and
    modification time (cp -p, tar) still changes it."""
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "blake2b").hexdigest()


@functools.lru_cache(maxsize=8)
def _read_cached(resolved: str, digest: str, shown: str) -> MeshFile:
    points, blocks, attributes, uv = read_faces(resolved, shown, NAME, ALLOWED)
    return make_mesh(points, blocks, attributes, uv, shown)


def read_faces(path: str, shown: str, name: str, allowed: str):
    """A mesh file's vertices (n, 3) m, its faces as runs (j, k) of k corners in file order, its point
    attributes and UVs (or None), unchecked: the one reader of cloth and collider files (meshio, then
    trimesh, by the suffix, see the module).  A file no reader understands raises a ParameterError naming
    ``name``, ``allowed`` its range."""
    suffix, reader = Path(path).suffix.lower(), reader_of(path)
    if reader is None:
        raise ParameterError(name, f"{shown!r}: unknown mesh format {suffix!r}: neither meshio nor trimesh reads "
                                   f"it; allowed: {allowed}")
    failures = []
    for attempt in (reader, "trimesh") if reader == "meshio" else (reader,):
        if attempt != reader and not _trimesh_reads(path):  # trimesh is imported only once meshio has failed
            break
        try:
            return _quietly(_read_meshio if attempt == "meshio" else _read_trimesh, path)
        except Exception as exc:  # the readers raise many kinds of errors for a damaged file
            label = attempt if attempt != reader or reader == "meshio" or suffix in TRIMESH_SUFFIXES else \
                f"trimesh (meshio has no reader for {suffix!r})"
            failures.append(f"{label}: {type(exc).__name__}: {exc}")
    raise ParameterError(name, f"{shown!r} cannot be read as a mesh by {'; nor by '.join(failures)}; "
                               f"allowed: {allowed}") from None


def _quietly(read, path: str):
    """read(path) with what the reader prints kept off stdout and stderr, and its sys.exit (meshio's on a
    file it cannot parse) raised as a ValueError of the reason it printed to stdout (its "Couldn't read
    file" line on stderr, wrapped at 80 columns, adds nothing)."""
    reason = io.StringIO()
    try:
        with contextlib.redirect_stdout(reason), contextlib.redirect_stderr(io.StringIO()):
            return read(path)
    except SystemExit:
        raise ValueError(" ".join(reason.getvalue().split()) or "it cannot parse the file") from None


def reader_of(path: str) -> str | None:
    """'meshio' or 'trimesh', the first reader of a mesh file by its suffix (see the module), or None if
    neither knows the suffix.  Compound suffixes count (meshio's '.vol.gz')."""
    suffix = Path(path).suffix.lower()
    if suffix in MESHIO_SUFFIXES:
        return "meshio"
    if suffix in TRIMESH_SUFFIXES:
        return "trimesh"
    import meshio

    if any(tail in meshio.extension_to_filetypes for tail in _suffix_tails(path)):
        return "meshio"
    return "trimesh" if _trimesh_reads(path) else None


def _suffix_tails(path: str) -> list[str]:
    """A path's suffixes from the last one on: '.gz', '.vol.gz', ... (lower case)."""
    suffixes = Path(path).suffixes
    return ["".join(suffixes[-k:]).lower() for k in range(1, len(suffixes) + 1)]


def _trimesh_reads(path: str) -> bool:
    """Whether trimesh knows a suffix of the path."""
    import trimesh

    return any(tail.lstrip(".") in trimesh.available_formats() for tail in _suffix_tails(path))


def _ply_header_ends(path: str) -> bool:
    """Whether a PLY file's header ends (a line 'end_header') before the file does."""
    with open(path, "rb") as fh:
        return any(line.strip() == b"end_header" for line in fh)


def _read_meshio(path: str):
    import meshio

    if path.lower().endswith(".ply") and not _ply_header_ends(path):  # meshio reads past its end for ever
        raise ValueError("its header has no end_header line (the file is cut short)")
    mesh = meshio.read(_obj_buffer(path), file_format="obj") if path.lower().endswith(".obj") else meshio.read(path)
    blocks = []
    for block in mesh.cells:
        if block.type in ("triangle", "quad") or block.type.startswith("polygon"):
            blocks.append(np.asarray(block.data, dtype=np.int64))
        elif block.dim == 2:
            raise ValueError(f"faces of type {block.type!r}: only triangles, quads and polygons are read")
    points = np.asarray(mesh.points, dtype=np.float64)
    attributes = {name: np.asarray(values) for name, values in mesh.point_data.items()}
    return points, blocks, attributes, _uv_of(attributes, len(points))


def _obj_buffer(path: str) -> io.StringIO:
    """An OBJ file's text without its normals, and without its UVs unless they are per vertex (each face
    corner's ``vt`` index its ``v`` index): meshio takes ``vn`` and ``vt`` rows as point data, and refuses
    a file (most that modellers write) with another count of them than of vertices."""
    with open(path, encoding="utf-8") as fh:
        lines = fh.read().splitlines()
    per_vertex = True
    for line in lines:
        words = line.split()
        if words[:1] == ["f"]:
            corners = [item.split("/") for item in words[1:]]
            per_vertex = per_vertex and all(len(c) > 1 and c[1] in ("", c[0]) for c in corners)
    dropped = ("vn",) if per_vertex else ("vn", "vt")
    return io.StringIO("\n".join(line for line in lines if (line.split(maxsplit=1) or [""])[0] not in dropped))


def _uv_of(attributes: dict, n: int) -> np.ndarray | None:
    for names in UV_NAMES:
        if all(name in attributes for name in names):
            values = (attributes[names[0]] if len(names) == 1
                      else np.stack([attributes[name] for name in names], axis=1))
            values = np.asarray(values, dtype=np.float64).reshape(n, -1)
            if values.shape[1] >= 2:
                return values[:, :2].copy()
    return None


def _read_trimesh(path: str):
    import trimesh

    mesh = trimesh.load(path, force="mesh", process=False)
    points = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)
    attributes = {name: np.asarray(values).reshape(len(points), -1)[:, 0]
                  for name, values in getattr(mesh, "vertex_attributes", {}).items()}
    uv = getattr(mesh.visual, "uv", None)
    uv = None if uv is None or len(uv) != len(points) else np.asarray(uv, dtype=np.float64)
    if path.lower().endswith(".stl"):
        points, faces = merged(points, faces)
    return points, [faces], attributes, uv


def merged(points: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exactly equal vertices of ``points`` merged, numbered in order of first appearance, and ``faces``
    (an integer array of any shape) indexing them."""
    _, first, inverse = np.unique(points, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)  # unique rows by first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return points[first[order]], rank[inverse.ravel()][faces]


def make_mesh(points, blocks, attributes=None, uv=None, shown: str = "<arrays>") -> MeshFile:
    """The checked mesh of ``points`` (n, 3) m and faces ``blocks`` (a list of (j, 3) and (j, 4) integer
    arrays in file order), with point ``attributes`` (name -> (n,) or (n, k) numbers) and ``uv`` (n, 2) or
    None; ``shown`` names it in errors.  A file's mesh (read_faces) is checked here too."""
    points, blocks, attributes, uv = _arrays(points, blocks, {} if attributes is None else attributes, uv, shown)
    n = len(points)
    corners = np.concatenate([np.full(len(b), b.shape[1]) for b in blocks])
    triangles, face_of = fan_triangles(blocks)
    unused = np.setdiff1d(np.arange(n), triangles)
    if len(unused):
        raise _error(f"{shown!r}: vertex {int(unused[0])} belongs to no face ({len(unused)} such vertices); "
                     "remove loose vertices (a particle needs a face for its mass)")
    _check_size(shown, points)
    _check_areas(shown, points, triangles, face_of)
    _check_coincident(shown, points)
    _check_manifold(shown, blocks)
    triangles = _oriented(triangles)
    mixed = len({b.shape[1] for b in blocks}) > 1
    faces = triangles if mixed else np.concatenate(blocks)
    for array in (points, faces, triangles, face_of, corners, uv, *blocks, *attributes.values()):
        if array is not None:  # shared by every reader of the (cached) file
            array.flags.writeable = False
    return MeshFile(points=points, faces=faces, triangles=triangles, face_of=face_of, corners=corners,
                    uv=uv, attributes=attributes, source=shown, blocks=tuple(blocks))


def _arrays(points, blocks, attributes: dict, uv, shown: str):
    """make_mesh's arguments as arrays, checked: points (n, 3) float64 of finite coordinates ((n, 2) given:
    z = 0), blocks of faces (j, 3) and (j, 4) int64 indexing them (whole numbers; empty blocks left out),
    attributes of n finite numbers each (a row per vertex) and uv (n, 2) float64 of finite numbers or None."""
    try:
        points = np.array(points, dtype=np.float64)
        blocks = [np.asarray(b) for b in blocks]
        attributes = {name: np.array(values) for name, values in attributes.items()}
        uv = None if uv is None else np.asarray(uv)
    except (TypeError, ValueError) as exc:
        raise _error(f"{shown!r}: its points, faces, attributes or uv are not arrays ({exc})") from None
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise _error(f"{shown!r} has no vertex coordinates: its points are of shape {points.shape}, not (n, 3)")
    n = len(points)
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(n)])
    if not np.isfinite(points).all():
        bad = int(np.flatnonzero(~np.isfinite(points).all(axis=1))[0])
        raise _error(f"{shown!r}: vertex {bad} has a coordinate that is not a finite number ({points[bad].tolist()})")
    blocks = [b for b in blocks if b.size]
    if not blocks:
        raise _error(f"{shown!r} has no faces (a cloth needs triangles or quads)")
    for b in blocks:
        if b.ndim != 2 or b.shape[1] < 3:
            raise _error(f"{shown!r} has faces of shape {b.shape}: a face lists 3 or 4 vertex indices")
        if b.shape[1] > 4:
            raise _error(f"{shown!r} has faces of {b.shape[1]} corners (polygon): split them into triangles or "
                         "quads in your modeller (e.g. Blender's Triangulate Faces)")
        if b.dtype.kind not in "iuf" or (b.dtype.kind == "f" and not (np.isfinite(b) & (b == np.round(b))).all()):
            raise _error(f"{shown!r} has face indices that are not whole numbers (of type {b.dtype})")
    blocks = [b.astype(np.int64) for b in blocks]
    if any(b.min() < 0 or b.max() >= n for b in blocks):
        raise _error(f"{shown!r} has faces whose vertex indices are outside 0..{n - 1}")
    for name, values in attributes.items():
        if values.ndim == 0 or len(values) != n:
            raise _error(f"{shown!r}: its point attribute {name!r} has {values.size} values, not one per vertex ({n})")
        if not _finite_numbers(values):
            raise _error(f"{shown!r}: its point attribute {name!r} has values that are not finite numbers "
                         f"(of type {values.dtype}); remove the attribute or give it numbers")
    if uv is not None and (uv.shape != (n, 2) or not _finite_numbers(uv)):
        raise _error(f"{shown!r}: its uv (of shape {uv.shape}, type {uv.dtype}) are not ({n}, 2) finite numbers, "
                     "a row per vertex")
    return np.ascontiguousarray(points), blocks, attributes, None if uv is None else uv.astype(np.float64)


def _finite_numbers(values: np.ndarray) -> bool:
    return values.dtype.kind in "biuf" and bool(np.isfinite(values).all())


def fan_triangles(blocks: list) -> tuple[np.ndarray, np.ndarray]:
    """Triangles (m, 3) of the faces in file order, each face (a, b, c, ...) fanned from its first corner:
    (a, b, c), (a, c, d), ...; and the face (m,) each came from."""
    triangles, face_of, start = [], [], 0
    for b in blocks:
        k = b.shape[1]
        fan = np.stack([b[:, [0, j, j + 1]] for j in range(1, k - 1)], axis=1).reshape(-1, 3)
        triangles.append(fan)
        face_of.append(np.repeat(np.arange(start, start + len(b)), k - 2))
        start += len(b)
    return np.concatenate(triangles).astype(np.int64), np.concatenate(face_of).astype(np.int64)


def triangle_areas(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Areas (m,) m2 of triangles (m, 3) of points (n, 3) m."""
    p = points[triangles]
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)


def _check_areas(shown: str, points: np.ndarray, triangles: np.ndarray, face_of: np.ndarray) -> None:
    edges = points[triangles[:, [1, 2, 0]]] - points[triangles]
    scale = float(np.median(np.linalg.norm(edges, axis=2)))
    areas = triangle_areas(points, triangles)
    flat = np.flatnonzero(areas <= DEGENERATE_AREA * scale**2)
    if len(flat):
        face = int(face_of[flat[0]])
        raise _error(f"{shown!r}: face {face} has zero area (a triangle of corners "
                     f"{triangles[flat[0]].tolist()} of area {areas[flat[0]]:.3g} m2; "
                     f"{len(np.unique(face_of[flat]))} such faces); remove degenerate faces (Blender: Merge by Distance)")


def _check_size(shown: str, points: np.ndarray) -> None:
    """Refuse a mesh larger than LARGEST_SIZE along an axis (a file in millimetres or centimetres read as metres),
    or smaller than scene.SMALLEST_SIZE along every axis (as the rectangle's width and length may not be)."""
    from wetcloth.scene import SMALLEST_SIZE

    extent = points.max(axis=0) - points.min(axis=0)
    if extent.max() < SMALLEST_SIZE:
        raise _error(f"{shown!r} is {extent.max():g} m across (coordinates are metres, at least {SMALLEST_SIZE:g} m): "
                     "scale it to its size in metres (Blender: the exporter's Scale, or Apply Scale)")
    if extent.max() > LARGEST_SIZE:
        raise _error(f"{shown!r} is {extent.max():g} m across (coordinates are metres, up to {LARGEST_SIZE:g} m): "
                     "a file in millimetres or centimetres must be scaled to metres (Blender: the exporter's Scale "
                     "0.001 or 0.01, or Apply Scale)")


def _check_coincident(shown: str, points: np.ndarray) -> None:
    """Refuse two vertices at exactly the same place: the faces on either side of them would not be joined
    (a seam: glTF and PLY writers split a vertex where its UVs or normals differ)."""
    _, first, inverse = np.unique(points, axis=0, return_index=True, return_inverse=True)
    again = np.flatnonzero(first[inverse.ravel()] != np.arange(len(points)))
    if len(again):
        vertex = int(again[0])
        raise _error(f"{shown!r}: vertices {int(first[inverse.ravel()[vertex]])} and {vertex} are at the same place "
                     f"({points[vertex].tolist()} m; {len(again)} such vertices): the cloth would fall apart along "
                     "that seam; weld them (Blender: Merge by Distance), and write the file without split normals "
                     "or UV seams (glTF and PLY writers split vertices there; OBJ does not)")


def face_edges(blocks) -> tuple[np.ndarray, np.ndarray]:
    """One row per edge of every face of ``blocks`` (arrays of faces of 3 or 4 corners, in file order),
    (lower index, higher index), and the face of each row; a face's rows follow its corners (edge j
    from corner j to corner j + 1)."""
    edges, owner, start = [], [], 0
    for b in blocks:
        k = b.shape[1]
        e = np.stack([b, np.roll(b, -1, axis=1)], axis=2).reshape(-1, 2)
        edges.append(np.sort(e, axis=1))
        owner.append(np.repeat(np.arange(start, start + len(b)), k))
        start += len(b)
    return np.concatenate(edges), np.concatenate(owner)


def _check_manifold(shown: str, blocks: list) -> None:
    edges, _ = face_edges(blocks)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    over = np.flatnonzero(counts > 2)
    if len(over):
        a, b = unique[over[0]].tolist()
        raise _error(f"{shown!r}: the edge between vertices {a} and {b} belongs to {counts[over[0]]} faces "
                     f"({len(over)} such edges): the springs cannot join more; split the mesh there")


def _oriented(triangles: np.ndarray) -> np.ndarray:
    """The triangles with a consistent orientation: each connected piece keeps its first triangle's, and
    a triangle that runs a shared edge the same way as its neighbour is turned over.  A piece that
    cannot be oriented (a Moebius strip) keeps the orientation its faces reach first."""
    m = len(triangles)
    directed = np.stack([triangles, np.roll(triangles, -1, axis=1)], axis=2).reshape(-1, 2)
    key = np.sort(directed, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    same = (key[order[1:]] == key[order[:-1]]).all(axis=1)
    first, second = order[:-1][same], order[1:][same]  # half-edges of one edge, in two triangles
    t1, t2 = first // 3, second // 3
    parallel = directed[first, 0] == directed[second, 0]  # both run the edge the same way
    neighbours = [[] for _ in range(m)]
    for a, b, p in zip(t1.tolist(), t2.tolist(), parallel.tolist()):
        neighbours[a].append((b, p))
        neighbours[b].append((a, p))
    flip = np.zeros(m, dtype=bool)
    seen = np.zeros(m, dtype=bool)
    for start in range(m):
        if seen[start]:
            continue
        seen[start] = True
        stack = [start]
        while stack:
            t = stack.pop()
            for u, p in neighbours[t]:
                if not seen[u]:
                    seen[u] = True
                    flip[u] = flip[t] ^ p
                    stack.append(u)
    out = triangles.copy()
    out[flip] = out[flip][:, [0, 2, 1]]
    return out


def mesh_area(mesh: MeshFile) -> float:
    """The mesh's area (m2): the sum of its triangles'."""
    return float(triangle_areas(mesh.points, mesh.triangles).sum())


def surface(points, triangles, shown: str = "<arrays>") -> MeshFile:
    """A mesh collider's surface given as arrays (its ``file`` from Python): ``points`` (V, 3) m where the
    scene puts them (before the collider's x, y, z), ``triangles`` (T, 3) indices into them; ``shown``
    names it in errors.  Any triangles: collider_meshes.mesh_of checks them as a file's."""
    points = np.array(points, dtype=np.float64)
    triangles = np.array(triangles, dtype=np.int64).reshape(-1, 3)
    for array in (points, triangles):
        array.flags.writeable = False
    return MeshFile(points=points, faces=triangles, triangles=triangles, face_of=np.arange(len(triangles)),
                    corners=np.full(len(triangles), 3), uv=None, attributes={}, source=shown, blocks=(triangles,))


def is_mesh(value) -> bool:
    """Whether a ``cloth_mesh`` value is a mesh (a file's path, or a MeshFile given as arrays), else the nx x ny
    rectangle."""
    return isinstance(value, MeshFile) or (bool(value) and not value.isspace())


def as_text(value):
    """A ``cloth_mesh`` or collider ``file`` value as text (a mesh given as arrays: its ``source``)."""
    return value.source if isinstance(value, MeshFile) else value


def resolve(value: str, base: str | Path | None) -> str:
    """``value`` made absolute against folder ``base`` if it is relative (no change without a base)."""
    if isinstance(value, MeshFile) or not is_mesh(value) or base is None or os.path.isabs(value):
        return value
    return str((Path(base) / value).resolve())
