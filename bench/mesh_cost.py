"""Cost per vertex of a cloth from an irregular triangle mesh against the built-in rectangle (issue 26:
at most 1.5x).

    .venv/bin/python bench/mesh_cost.py [--vertices 10000] [--duration 0.5]

The mesh is docs/make_meshes.py's irregular disc (rings of jittered points, Delaunay) with about
``--vertices`` vertices and the area of the square it is compared with: a square grid of as many
particles.  Both drop flat from 5 cm onto water (the default towel's fabric, air and water), hang in air
from the part of them at y >= 0.6 m (pinned by a box: the disc by its cap, 0.72 m across, but the square by its
whole top edge, so that only the disc folds in as it falls), and hang in air by that cap's chord (the box
narrowed to |x| <= 0.36 m: the disc's pins are the same, the square's the middle of its top edge, so that both
fold in); CPU seconds, steps, Newton and CG iterations
for each (and the self-collision candidate lists built; ``--self-collision off`` leaves that stage out), and the
ratio of CPU time per vertex.  The mesh takes the core's listed springs and its
algebraic multigrid preconditioner (mesh_plane.cpp); the grid its families and geometric multigrid.
Between them the grid's own cloth as a quad mesh file ("quads"), its vertices numbered along the columns
(``--shuffle``: in a random order) rather than in the grid's order, so that it takes the mesh path:
listed springs, face drag over triangles, the algebraic multigrid.  ``--square-meshes`` adds two triangle
meshes of the grid's square between them: its cells split in two ("split": the mesh path with a triangle
mesh's springs, a regular one), and its inner points moved at random by up to a quarter of the spacing
and triangulated by Delaunay ("jittered": irregular in the square's outline; the hanging cases' boxes pin
the inner points moved into it too).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # idle BLAS threads would spin on the CPU clock

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs"))
import make_meshes  # noqa: E402

import meshio  # noqa: E402
import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth.topology import build_topology  # noqa: E402


def run(scene: wetcloth.Scene, duration: float) -> tuple[float, wetcloth.Simulation]:
    sim = wetcloth.Simulation(scene)
    start = time.process_time()
    sim.advance(duration)
    return time.process_time() - start, sim


def rectangle_file(path: Path, scene: wetcloth.Scene, shuffle: bool) -> Path:
    """The scene's rectangle as a quad mesh file at ``path``, its vertices along the columns or shuffled."""
    nx, ny = scene.nx, scene.ny
    if shuffle:  # file vertex k is grid vertex order[k]
        order = np.random.default_rng(26).permutation(nx * ny)
    else:
        order = np.arange(nx * ny).reshape(ny, nx).T.ravel()
    rank = np.argsort(order)
    col, row = np.tile(np.arange(nx), ny), np.repeat(np.arange(ny), nx)
    a = np.flatnonzero((col < nx - 1) & (row < ny - 1))
    cells = rank[np.stack([a, a + 1, a + nx + 1, a + nx], axis=1)]
    meshio.write(path, meshio.Mesh(build_topology(scene).rest_pos.T[order], [("quad", cells.astype(np.int32))]),
                 binary=True)
    return path


def square_file(path: Path, scene: wetcloth.Scene, jitter: float) -> Path:
    """The scene's square as a triangle mesh file at ``path``: its cells split (jitter 0), or its inner points
    moved by up to ``jitter`` times the spacing and triangulated by Delaunay."""
    from scipy.spatial import Delaunay

    nx, ny = scene.nx, scene.ny
    xy = build_topology(scene).rest_xy.T.copy()
    col, row = np.tile(np.arange(nx), ny), np.repeat(np.arange(ny), nx)
    if jitter == 0.0:
        a = np.flatnonzero((col < nx - 1) & (row < ny - 1))
        triangles = np.concatenate([np.stack([a, a + 1, a + nx + 1], 1), np.stack([a, a + nx + 1, a + nx], 1)])
    else:
        inner = (col > 0) & (col < nx - 1) & (row > 0) & (row < ny - 1)
        spacing = np.array([scene.width / (nx - 1), scene.length / (ny - 1)])
        xy[inner] += np.random.default_rng(26).uniform(-jitter, jitter, (int(inner.sum()), 2)) * spacing
        triangles = Delaunay(xy).simplices
        a, b, c = (xy[triangles[:, k]] for k in range(3))
        clockwise = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0
        triangles[clockwise] = triangles[clockwise][:, [0, 2, 1]]
    points = np.column_stack([xy, np.zeros(len(xy))])
    meshio.write(path, meshio.Mesh(points, [("triangle", triangles.astype(np.int32))]), binary=True)
    return path


HANGING = dict(initial_tilt=0.0, initial_height=2.0, water_level=-10.0, floor_level=-20.0)
CASES = {  # scene settings of each case (the hanging ones add their PINS)
    "landing on water": dict(initial_tilt=0.0, initial_height=0.05),
    "hanging in air": HANGING,
    "hanging by a chord": HANGING,
}
PIN = "box:-9,0.6,-9,9,9,9"  # the hanging case's pins: every particle at y >= 0.6 m
CHORD = math.sqrt(make_meshes.RADIUS**2 - 0.6**2) + 1e-9  # m, half the chord of the disc's cap y >= 0.6 m (0.36)
PINS = {"hanging in air": PIN, "hanging by a chord": f"box:{-CHORD},0.6,-9,{CHORD},9,9"}


def shapes_of(vertices: int, shuffle: bool, square_meshes: bool) -> dict:
    """Scene settings of each shape: the grid, its quad mesh, the square's triangle meshes (if
    ``square_meshes``) and the disc of about ``vertices`` vertices (files in a new temporary folder)."""
    rings = round(math.sqrt(vertices / math.pi))
    points, triangles = make_meshes.round_cloth(radius=make_meshes.RADIUS, rings=rings)
    side = round(math.sqrt(len(points)))
    size = math.sqrt(math.pi) * make_meshes.RADIUS  # the square of the disc's area
    path = Path(tempfile.mkdtemp()) / "disc.ply"
    make_meshes.write(path, points, triangles)
    grid = dict(nx=side, ny=side, width=size, length=size)
    quads = dict(cloth_mesh=str(rectangle_file(path.with_name("square.ply"), wetcloth.load_scene(**grid), shuffle)),
                 place_mesh="on")
    shapes = {"grid": grid, "quads": quads}
    if square_meshes:
        square = wetcloth.load_scene(**grid)
        for kind, jitter in (("split", 0.0), ("jittered", 0.25)):
            shapes[kind] = dict(cloth_mesh=str(square_file(path.with_name(f"{kind}.ply"), square, jitter)), place_mesh="on")
    shapes["mesh"] = dict(cloth_mesh=str(path), place_mesh="on")
    return shapes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vertices", type=int, default=10000)
    parser.add_argument("--duration", type=float, default=0.5, help="simulated seconds (default 0.5)")
    parser.add_argument("--shuffle", action="store_true", help="the quad mesh's vertices in a random order")
    parser.add_argument("--square-meshes", action="store_true", help="also the square split into triangles, and jittered")
    parser.add_argument("--self-collision", choices=("on", "off"), default="on",
                        help="off: without its cost (the disc hanging rebuilds its candidate list at most steps)")
    parser.add_argument("--repeat", type=int, default=1, help="rounds, the shapes in turn; the best of each (default 1)")
    args = parser.parse_args()
    shapes = shapes_of(args.vertices, args.shuffle, args.square_meshes)
    disc = wetcloth.Simulation(wetcloth.load_scene(**shapes["mesh"])).model.topology.n
    side = shapes["grid"]["nx"]
    rings = round(math.sqrt(args.vertices / math.pi))
    print(f"disc of {disc} vertices ({rings} rings) against a {side} x {side} grid, {args.duration} s")
    for label, base in CASES.items():
        results, best = {}, {}
        extra = dict(pinned_vertices=PINS[label]) if label in PINS else {}
        extra["self_collision"] = args.self_collision
        for _ in range(args.repeat):
            for kind, shape in shapes.items():
                seconds, sim = run(wetcloth.load_scene(**base, **shape, **extra), args.duration)
                if kind not in best or seconds < best[kind][0]:
                    best[kind] = seconds, sim
        for kind, (seconds, sim) in best.items():
            n = sim.model.topology.n
            results[kind] = seconds / n
            c = sim.solver_counts
            lists = f"  lists built {sim.contact_counts['rebuilds']:4d}" if args.self_collision == "on" else ""
            print(f"  {label:<17} {kind}: {n:6d} vertices  {seconds:7.1f} s CPU  steps {sim.steps:5d}  rejected "
                  f"{sim.rejected_steps:4d}  Newton {c['newton_iterations']:5d}  CG {c['cg_iterations']:6d}{lists}", flush=True)
        ratios = ", ".join(f"{kind} / grid {results[kind] / results['grid']:.2f}x" for kind in results if kind != "grid")
        print(f"  {label:<17} per vertex: {ratios}", flush=True)

if __name__ == "__main__":
    main()
