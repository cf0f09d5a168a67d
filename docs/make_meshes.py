"""Make the example cloth meshes of models/meshes/ (reproducible: a fixed seed).

    .venv/bin/python docs/make_meshes.py            # models/meshes/round_tablecloth.ply (~2k vertices)
    .venv/bin/python docs/make_meshes.py --rings 50 --out /tmp/round_8k.ply   # the same disc, ~8k vertices

The round tablecloth is an irregular triangulated disc in the xy plane, centred on the origin (z = 0; a
scene places it with place_mesh = "on"): rings of points at even radii, each point moved at random by
up to a quarter of the spacing (the rim's only along it), triangulated by scipy.spatial.Delaunay and
oriented counter-clockwise seen from +z.  Its UVs (s, t) map the disc's bounding square onto 0..1.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
RADIUS = 0.7  # m
RINGS = 25  # ~2k vertices; the vertex count grows as pi * rings^2
SEED = 26


def round_cloth(radius: float = RADIUS, rings: int = RINGS, seed: int = SEED) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) m and triangles (m, 3) of an irregular disc of ``radius`` m with ``rings`` rings."""
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(seed)
    spacing = radius / rings
    points = [np.zeros((1, 2))]
    for k in range(1, rings + 1):
        count = round(2.0 * math.pi * k)
        angle = (np.arange(count) + rng.uniform(-0.25, 0.25, count)) * (2.0 * math.pi / count) + rng.uniform(0, 2 * math.pi)
        r = np.full(count, k * spacing) if k == rings else k * spacing + rng.uniform(-0.25, 0.25, count) * spacing
        points.append(np.column_stack([r * np.cos(angle), r * np.sin(angle)]))
    xy = np.concatenate(points)
    triangles = Delaunay(xy).simplices.astype(np.int64)
    a, b, c = (xy[triangles[:, k]] for k in range(3))
    clockwise = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0
    triangles[clockwise] = triangles[clockwise][:, [0, 2, 1]]
    return np.column_stack([xy, np.zeros(len(xy))]), triangles


def write(path: Path, points: np.ndarray, triangles: np.ndarray) -> None:
    """A binary PLY with the UVs as vertex properties s, t."""
    import meshio

    span = np.ptp(points[:, :2], axis=0)
    uv = (points[:, :2] - points[:, :2].min(axis=0)) / span
    meshio.write(path, meshio.Mesh(points, [("triangle", triangles.astype(np.int32))], point_data={"s": uv[:, 0], "t": uv[:, 1]}),
                 binary=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rings", type=int, default=RINGS, help=f"rings of points (default {RINGS}: ~2k vertices)")
    parser.add_argument("--out", type=Path, default=ROOT / "models" / "meshes" / "round_tablecloth.ply")
    args = parser.parse_args()
    points, triangles = round_cloth(rings=args.rings)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write(args.out, points, triangles)
    print(f"wrote {args.out}: {len(points)} vertices, {len(triangles)} triangles")


if __name__ == "__main__":
    main()
