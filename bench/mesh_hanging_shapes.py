"""What sets a hanging mesh cloth's steps and Newton iterations (issue 26): triangle meshes of the
same size but differing regularity and triangle shape, hanging in air as in bench/mesh_cost.py.

    .venv/bin/python bench/mesh_hanging_shapes.py [--vertices 2500] [--duration 0.5]

Shapes: the grid; the grid's square split into right triangles, all cells alike ("split") or each
cell's diagonal chosen at random ("random diagonals": regular geometry, irregular connectivity);
its inner points moved at random by up to 0.1 or 0.25 of the spacing and triangulated by Delaunay
("jittered"), the latter then Lloyd-relaxed ("relaxed": better triangles, still irregular); the
disc of docs/make_meshes.py (jittered rings), the same Lloyd-relaxed, and its rings unjittered.
For each: the smallest angle of its triangles (degrees), the median acceleration its stretch
springs leave on its inner particles under a uniform strain of 1e-3 along y at rest (m/s2: 0 where
the springs pass the patch test), then, hanging by the box y >= 0.6 m and by the disc's cap's chord
(bench/mesh_cost.py's pins; self-collision off): steps, rejected steps, Newton and CG iterations
(deterministic), and the 5th percentile of the stretch springs' strain at the end (their
compression: slack springs shortened by the cloth's folding or its in-plane narrowing).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs"))
import make_meshes  # noqa: E402

import meshio  # noqa: E402
import numpy as np  # noqa: E402
from mesh_cost import CASES, PINS, square_file  # noqa: E402
from scipy.spatial import Delaunay  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth.topology import build_topology  # noqa: E402

LLOYD_ITERATIONS = 20


def counter_clockwise(xy: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """``triangles`` turned counter-clockwise in the plane of ``xy`` (n, 2)."""
    a, b, c = (xy[triangles[:, k]] for k in range(3))
    clockwise = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0
    triangles[clockwise] = triangles[clockwise][:, [0, 2, 1]]
    return triangles


def lloyd(xy: np.ndarray, fixed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points moved LLOYD_ITERATIONS times to the area-weighted mean of their Delaunay triangles'
    centroids (an approximate centroidal Voronoi relaxation), the ``fixed`` ones kept; and their triangles."""
    xy = xy.copy()
    for _ in range(LLOYD_ITERATIONS):
        triangles = Delaunay(xy).simplices
        a, b, c = (xy[triangles[:, k]] for k in range(3))
        area = 0.5 * np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
        weight = np.zeros(len(xy))
        moment = np.zeros_like(xy)
        for k in range(3):
            np.add.at(weight, triangles[:, k], area)
            np.add.at(moment, triangles[:, k], area[:, None] * (a + b + c) / 3.0)
        xy[~fixed] = moment[~fixed] / weight[~fixed, None]
    return xy, counter_clockwise(xy, Delaunay(xy).simplices.copy())


def write(path: Path, xy: np.ndarray, triangles: np.ndarray) -> str:
    meshio.write(path, meshio.Mesh(np.column_stack([xy, np.zeros(len(xy))]), [("triangle", triangles.astype(np.int32))]),
                 binary=True)
    return str(path)


def random_diagonals(path: Path, scene: wetcloth.Scene) -> str:
    """The scene's square as a triangle mesh file, each cell split along a diagonal chosen at random."""
    nx, ny = scene.nx, scene.ny
    xy = build_topology(scene).rest_xy.T.copy()
    col, row = np.tile(np.arange(nx), ny), np.repeat(np.arange(ny), nx)
    a = np.flatnonzero((col < nx - 1) & (row < ny - 1))
    flip = (np.random.default_rng(26).random(len(a)) < 0.5)[:, None]
    first = np.where(flip, np.stack([a, a + 1, a + nx], 1), np.stack([a, a + 1, a + nx + 1], 1))
    second = np.where(flip, np.stack([a + 1, a + nx + 1, a + nx], 1), np.stack([a, a + nx + 1, a + nx], 1))
    return write(path, xy, np.concatenate([first, second]))


def shapes_of(vertices: int) -> dict:
    """Scene settings of each shape (files in a new temporary folder)."""
    folder = Path(tempfile.mkdtemp())
    rings = round(math.sqrt(vertices / math.pi))
    side = round(math.sqrt(len(make_meshes.round_cloth(rings=rings)[0])))
    size = math.sqrt(math.pi) * make_meshes.RADIUS
    grid = dict(nx=side, ny=side, width=size, length=size)
    square = wetcloth.load_scene(**grid)
    files = {"split": str(square_file(folder / "split.ply", square, 0.0)),
             "random diagonals": random_diagonals(folder / "diagonals.ply", square),
             "jittered 0.1": str(square_file(folder / "jittered1.ply", square, 0.1)),
             "jittered 0.25": str(square_file(folder / "jittered.ply", square, 0.25))}
    xy = meshio.read(files["jittered 0.25"]).points[:, :2]
    edge = np.isclose(np.abs(xy), 0.5 * size).any(axis=1)
    files["relaxed 0.25"] = write(folder / "relaxed.ply", *lloyd(xy, edge))
    points, triangles = make_meshes.round_cloth(rings=rings)
    files["disc"] = write(folder / "disc.ply", points[:, :2], triangles)
    rim = np.isclose(np.linalg.norm(points[:, :2], axis=1), make_meshes.RADIUS)
    files["disc relaxed"] = write(folder / "disc_relaxed.ply", *lloyd(points[:, :2], rim))
    points, triangles = make_meshes.round_cloth(rings=rings, jitter=0.0)
    files["disc unjittered"] = write(folder / "disc_even.ply", points[:, :2], triangles)
    return {"grid": grid, **{kind: dict(cloth_mesh=path, place_mesh="on") for kind, path in files.items()}}


def smallest_angle(sim: wetcloth.Simulation) -> float:
    """The smallest angle of the cloth's triangles at rest (degrees; the grid's: 45)."""
    topo = sim.model.topology
    xy = topo.rest_xy.T
    corners = [xy[topo.triangles[:, k]] for k in range(3)]
    least = 180.0
    for k in range(3):
        u, v = corners[(k + 1) % 3] - corners[k], corners[(k + 2) % 3] - corners[k]
        cos = np.sum(u * v, axis=1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        least = min(least, float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).min()))
    return least


def strain_residual(sim: wetcloth.Simulation, strain: float = 1e-3) -> float:
    """Median acceleration (m/s2) the listed stretch springs leave on the particles of the middle
    90 % of the rest sheet's width and length under a uniform strain along y (0 for the grid)."""
    topo = sim.model.topology
    if not topo.listed:
        return 0.0
    count = topo.in_plane_count
    x = topo.rest_xy.T * np.array([1.0, 1.0 + strain])
    first, second = topo.pairs[:, :count]
    d = x[second] - x[first]
    length = np.linalg.norm(d, axis=1)
    pull = (topo.pair_stiffness[:count] * (length - topo.pair_rest[:count]) / length)[:, None] * d
    force = np.zeros_like(x)
    np.add.at(force, first, pull)
    np.add.at(force, second, -pull)
    centred = topo.rest_xy.T - topo.rest_xy.T.mean(axis=0)
    inner = np.all(np.abs(centred) < 0.45 * np.ptp(centred, axis=0), axis=1)
    return float(np.median(np.linalg.norm(force[inner], axis=1) / sim.model.dry_mass[inner]))


def compression(sim: wetcloth.Simulation) -> float:
    """5th percentile of the in-plane (tension-only and buckling) springs' strain now (negative: shortened)."""
    topo = sim.model.topology
    if topo.listed:
        first, second = topo.pairs[:, :topo.in_plane_count]
        rest = topo.pair_rest[:topo.in_plane_count]
    else:  # the grid's families: particle j joined to j + offset where the family's stiffness is nonzero
        families = np.flatnonzero(topo.spring_tension_only)
        ends = [np.flatnonzero(topo.spring_stiffness[f]) for f in families]
        first = np.concatenate(ends)
        second = np.concatenate([j + topo.spring_offset[f] for f, j in zip(families, ends)])
        rest = np.concatenate([np.full(len(j), topo.spring_rest[f]) for f, j in zip(families, ends)])
    pos = sim.positions
    return float(np.percentile(np.linalg.norm(pos[second] - pos[first], axis=1) / rest - 1.0, 5))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vertices", type=int, default=2500)
    parser.add_argument("--duration", type=float, default=0.5, help="simulated seconds (default 0.5)")
    args = parser.parse_args()
    shapes = shapes_of(args.vertices)
    print(f"hanging in air {args.duration} s, self-collision off; strain residual at 1e-3 along y")
    for label, pins in PINS.items():
        print(f"{label} ({pins})")
        for kind, shape in shapes.items():
            sim = wetcloth.Simulation(wetcloth.load_scene(**CASES[label], **shape, pinned_vertices=pins, self_collision="off"))
            angle, residual = smallest_angle(sim), strain_residual(sim)
            sim.advance(args.duration)
            c = sim.solver_counts
            print(f"  {kind:<17} {sim.model.topology.n:6d} vertices  smallest angle {angle:5.1f}  residual {residual:6.1f} m/s2  "
                  f"steps {sim.steps:5d}  rejected {sim.rejected_steps:4d}  Newton {c['newton_iterations']:5d}  "
                  f"CG {c['cg_iterations']:6d}  strain p5 {compression(sim):+.1e}", flush=True)


if __name__ == "__main__":
    main()
