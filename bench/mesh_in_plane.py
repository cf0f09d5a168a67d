"""Whether the in-plane model of the preconditioner fits an irregular mesh worse than a grid: CG on the
in-plane rest-stiffness system of a flat cloth, preconditioned by exact solves of its scalar components.

    .venv/bin/python bench/mesh_in_plane.py [--rings 25]

The system is ``M + s K`` on the (x, y) displacements of a flat cloth at rest, K the stiffness of its
in-plane springs (tension-only and buckling; each k u u^T between its ends, u its direction); s = (beta h)^2 for BDF2 steps of
1/600 and 1/30 s.  Its preconditioners solve two scalar systems exactly (scipy's splu): half of every
spring in each (the core's rest-stiffness systems, mesh_plane.cpp) or each spring's own share u_x^2,
u_y^2.  CG iterations to a 1e-6 relative preconditioned residual (a random right-hand side), on
docs/make_meshes.py's irregular disc of ``--rings`` rings and on a square grid of as many particles with
its springs listed.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs"))
sys.path.insert(0, str(ROOT / "tests"))
import make_meshes  # noqa: E402
from support.listed import listed_from_grid  # noqa: E402

import wetcloth  # noqa: E402
from wetcloth.model import Model  # noqa: E402
from wetcloth.topology import build_topology  # noqa: E402


def in_plane(topology, mass: np.ndarray, scale: float):
    """(M + s K (2n x 2n), half-and-half components, own-direction components), scipy."""
    n, t = topology.n, topology.in_plane_count
    i, j = topology.pairs[:, :t]
    k = topology.pair_stiffness[:t]
    d = topology.rest_pos[:2, j] - topology.rest_pos[:2, i]
    u = d / np.linalg.norm(d, axis=0)

    def laplacian(w):
        return sp.coo_matrix((np.concatenate([w, w, -w, -w]), (np.concatenate([i, j, i, j]),
                                                             np.concatenate([i, j, j, i]))), shape=(n, n)).tocsr()

    blocks = [[laplacian(k * u[a] * u[b]) for b in range(2)] for a in range(2)]
    system = (sp.diags(np.concatenate([mass, mass])) + scale * sp.bmat(blocks)).tocsr()
    half = sp.diags(mass) + scale * laplacian(0.5 * k)
    return system, (half, half), (sp.diags(mass) + scale * blocks[0][0], sp.diags(mass) + scale * blocks[1][1])


def iterations(system, components, rtol: float = 1e-6) -> int:
    """Preconditioned CG iterations until max |P^-1 r| <= rtol times its first value."""
    n = system.shape[0] // 2
    solves = [sla.splu(c.tocsc()).solve for c in components]

    def precondition(r):
        return np.concatenate([solves[0](r[:n]), solves[1](r[n:])])

    b = np.random.default_rng(0).standard_normal(2 * n)
    x, r = np.zeros_like(b), b.copy()
    z = precondition(r)
    p, rz, first = z.copy(), r @ z, np.abs(z).max()
    for count in range(1, 10000):
        ap = system @ p
        alpha = rz / (p @ ap)
        x += alpha * p
        r -= alpha * ap
        z = precondition(r)
        if np.abs(z).max() <= rtol * first:
            return count
        rz, previous = r @ z, rz
        p = z + rz / previous * p
    raise RuntimeError("no convergence")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rings", type=int, default=25)
    args = parser.parse_args()
    points, triangles = make_meshes.round_cloth(rings=args.rings)
    path = Path(tempfile.mkdtemp()) / "disc.ply"
    make_meshes.write(path, points, triangles)
    disc = Model(wetcloth.load_scene(cloth_mesh=str(path), place_mesh="on"))
    side, size = round(math.sqrt(len(points))), math.sqrt(math.pi) * make_meshes.RADIUS
    square = wetcloth.load_scene(nx=side, ny=side, width=size, length=size)
    cloths = (("irregular disc", disc.topology, disc.dry_mass),
              ("grid, listed", listed_from_grid(build_topology(square)), Model(square).dry_mass))
    for name, topology, mass in cloths:
        for step in (1 / 600, 1 / 30):
            system, half, own = in_plane(topology, mass, (2 / 3 * step) ** 2)
            print(f"{name:<15} {topology.n:6d} vertices  h = {step:.4f} s: CG iterations, half and half "
                  f"{iterations(system, half):3d}, own direction {iterations(system, own):3d}", flush=True)


if __name__ == "__main__":
    main()
