"""Make the example cloth meshes of models/meshes/ (reproducible: a fixed seed).

    .venv/bin/python docs/make_meshes.py            # models/meshes/round_tablecloth.ply (~2k vertices)
    .venv/bin/python docs/make_meshes.py --rings 50 --out /tmp/round_8k.ply   # the same disc, ~8k vertices
    .venv/bin/python docs/make_meshes.py --bucket   # models/meshes/bucket.ply, a collider

The round tablecloth is an irregular triangulated disc in the xy plane, centred on the origin (z = 0; a
scene places it with place_mesh = "on"): rings of points at even radii, each point moved at random by
up to a quarter of the spacing (the rim's only along it), triangulated by scipy.spatial.Delaunay and
oriented counter-clockwise seen from +z.  Its UVs (s, t) map the disc's bounding square onto 0..1.

The bucket is an open shell (a mesh collider): a round wall of BUCKET_RADIUS and BUCKET_HEIGHT on a
round bottom at z = 0, centred on the z axis, its top open.
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


def round_cloth(radius: float = RADIUS, rings: int = RINGS, seed: int = SEED,
                jitter: float = 0.25) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) m and triangles (m, 3) of an irregular disc of ``radius`` m with ``rings`` rings, each
    point moved at random by up to ``jitter`` times the spacing (0: rings of evenly spaced points)."""
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(seed)
    spacing = radius / rings
    points = [np.zeros((1, 2))]
    for k in range(1, rings + 1):
        count = round(2.0 * math.pi * k)
        angle = (np.arange(count) + rng.uniform(-jitter, jitter, count)) * (2.0 * math.pi / count) + rng.uniform(0, 2 * math.pi)
        r = np.full(count, k * spacing) if k == rings else k * spacing + rng.uniform(-jitter, jitter, count) * spacing
        points.append(np.column_stack([r * np.cos(angle), r * np.sin(angle)]))
    xy = np.concatenate(points)
    triangles = Delaunay(xy).simplices.astype(np.int64)
    a, b, c = (xy[triangles[:, k]] for k in range(3))
    clockwise = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0
    triangles[clockwise] = triangles[clockwise][:, [0, 2, 1]]
    return np.column_stack([xy, np.zeros(len(xy))]), triangles


BUCKET_RADIUS, BUCKET_HEIGHT = 0.16, 0.3  # m
BUCKET_SEGMENTS, BUCKET_ROWS = 48, 12  # around, and up the wall


def bucket(radius: float = BUCKET_RADIUS, height: float = BUCKET_HEIGHT, segments: int = BUCKET_SEGMENTS,
           rows: int = BUCKET_ROWS) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) m and triangles (m, 3) of an open-topped bucket: the bottom's centre, then rows + 1
    rings of ``segments`` points from z = 0 to ``height``."""
    angle = np.arange(segments) * (2.0 * math.pi / segments)
    rings = [np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.full(segments, z)])
             for z in np.linspace(0.0, height, rows + 1)]
    points = np.concatenate([np.zeros((1, 3)), *rings])
    ring = lambda r, k: 1 + r * segments + k % segments  # noqa: E731 (point k of ring r)
    k = np.arange(segments)
    triangles = [np.column_stack([np.zeros(segments, dtype=np.int64), ring(0, k + 1), ring(0, k)])]  # bottom, normal -z
    for r in range(rows):
        triangles.append(np.column_stack([ring(r, k), ring(r, k + 1), ring(r + 1, k + 1)]))
        triangles.append(np.column_stack([ring(r, k), ring(r + 1, k + 1), ring(r + 1, k)]))
    return points, np.concatenate(triangles).astype(np.int64)


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
    parser.add_argument("--out", type=Path, default=None, help="the file (default: models/meshes/...)")
    parser.add_argument("--bucket", action="store_true", help="the bucket collider instead of the cloth")
    args = parser.parse_args()
    name = "bucket.ply" if args.bucket else "round_tablecloth.ply"
    args.out = args.out or ROOT / "models" / "meshes" / name
    points, triangles = bucket() if args.bucket else round_cloth(rings=args.rings)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write(args.out, points, triangles)
    print(f"wrote {args.out}: {len(points)} vertices, {len(triangles)} triangles")


if __name__ == "__main__":
    main()
