"""How stiff in bending a triangle mesh's bending springs make the cloth, at each resolution of the
round tablecloth's disc (issue 26: its drape's folds, and so its hem, change with refinement).

    .venv/bin/python bench/mesh_bending.py [--rings 25 35 50 70] [--radii 0.1 0.05 0.02] [--hinge]

docs/make_meshes.py's disc of each ``--rings`` (25: the tablecloth preset's ~2k vertices; 35, 50, 70:
~4k, 8k, 16k) with models/tablecloth.toml's fabric, its springs as the cloth gets them
(wetcloth.topology.build_topology), laid without stretch onto a cylinder of each ``--radii`` (m; the
curvature 1 / radius, the sheet's x across the axis): the bending springs' energy (1/2 k (|d| - l)^2, their
both-ways law) per area of the disc's inner part (r < 0.5 m, clear of the rim), J/m2.  A bending law with a
mesh-independent rigidity D would give D / (2 radius^2) on every mesh; the springs across two triangles'
opposite corners shorten by the square of the fold angle, so theirs grows as radius^-4 and falls with the
edge length h as h^4 (the ratios printed: each mesh's energy against the first's, and the energy's growth
from the largest radius to the smallest against the quadratic law's).  ``--hinge``: the same of
the hinges of ``bend_rigidity`` (summed over the whole disc, their springs' energies cancelling
within each hinge), as a multiple of D / (2 radius^2) (1 on equilateral triangles).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs"))
import make_meshes  # noqa: E402

import numpy as np  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth.topology import BEND, HINGE, STRETCH, build_topology  # noqa: E402

INNER = 0.5  # m: the disc's part whose springs are summed


def bending_energies(rings: int, radii: list[float]) -> tuple[int, float, list[float]]:
    """Vertex count, median stretch spring length (m) and the bending energy per area (J/m2) at each radius."""
    points, triangles = make_meshes.round_cloth(rings=rings)
    path = Path(tempfile.mkdtemp()) / "disc.ply"
    make_meshes.write(path, points, triangles)
    topo = build_topology(wetcloth.load_scene("tablecloth", cloth_mesh=str(path), bend_rigidity=0.0))
    bend = topo.pair_kind == BEND
    i, j = topo.pairs[:, bend]
    k, rest = topo.pair_stiffness[bend], topo.pair_rest[bend]
    x, y = points[:, 0], points[:, 1]
    inner = (np.hypot(x[i], y[i]) < INNER) & (np.hypot(x[j], y[j]) < INNER)
    energies = []
    for radius in radii:
        bent = np.column_stack([radius * np.sin(x / radius), y, radius * (1.0 - np.cos(x / radius))])
        length = np.linalg.norm(bent[i] - bent[j], axis=1)
        energies.append(float((0.5 * k * (length - rest) ** 2)[inner].sum() / (np.pi * INNER**2)))
    return len(points), float(np.median(topo.pair_rest[topo.pair_kind == STRETCH])), energies


def hinge_energies(rings: int, radii: list[float]) -> list[float]:
    """The quadratic hinges' bending energy per area of the disc at each radius, over D / (2 radius^2)."""
    points, triangles = make_meshes.round_cloth(rings=rings)
    path = Path(tempfile.mkdtemp()) / "disc.ply"
    make_meshes.write(path, points, triangles)
    topo = build_topology(wetcloth.load_scene("tablecloth", cloth_mesh=str(path), bend_rigidity=1.0))
    hinge = topo.pair_kind == HINGE
    (i, j), k = topo.pairs[:, hinge], topo.pair_stiffness[hinge]
    x, y = points[:, 0], points[:, 1]
    ratios = []
    for radius in radii:
        bent = np.column_stack([radius * np.sin(x / radius), y, radius * (1.0 - np.cos(x / radius))])
        energy = (0.5 * k * ((bent[i] - bent[j]) ** 2).sum(axis=1)).sum() / (np.pi * make_meshes.RADIUS**2)
        ratios.append(float(energy / (0.5 / radius**2)))
    return ratios


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rings", type=int, nargs="+", default=[25, 35, 50, 70])
    parser.add_argument("--radii", type=float, nargs="+", default=[0.1, 0.05, 0.02])
    parser.add_argument("--hinge", action="store_true", help="also the quadratic hinges' energy")
    args = parser.parse_args()
    first = None
    for rings in args.rings:
        n, h, energies = bending_energies(rings, args.radii)
        first = first or energies
        growth = (energies[-1] / energies[0]) / (args.radii[0] / args.radii[-1]) ** 2
        print(f"{n:6d} vertices, edges {1e3 * h:4.1f} mm: bending energy per area "
              + "  ".join(f"{e:.3e}" for e in energies) + " J/m2 at radii " + " ".join(f"{r:g}" for r in args.radii)
              + " m;  against the first mesh " + " ".join(f"{e / f:.3f}" for e, f in zip(energies, first))
              + f";  growth over the quadratic law's {growth:.1f}x", flush=True)
        if args.hinge:
            print("        quadratic hinges: energy per area / (D / (2 radius^2)) "
                  + " ".join(f"{e:.3f}" for e in hinge_energies(rings, args.radii)), flush=True)


if __name__ == "__main__":
    main()
