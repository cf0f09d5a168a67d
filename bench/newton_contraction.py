"""How fast BDF2's Newton iterations can converge on a sinking cloth, and which approximation of the
Jacobian limits them.

    .venv/bin/python bench/newton_contraction.py [--run 10] [--times 22 28]

A Newton iteration that solves with an approximate matrix ``A`` instead of the true
``A* = M - bh dF/dv - bh^2 dF/dx`` cuts the error at best by the spectral radius of
``I - A^-1 A*`` per iteration (its contraction).  Here, at states of one run of
``models/studies/sink_map.toml`` (a 9 x 9 cloth: the matrices are dense, 243 x 243), for a step of
0.1 s (the study's output interval, ``bh = 2h/3``): ``A*`` from forward differences of the
core's ``forces``, ``A`` as the conjugate gradients apply it (``_system_matvec``, column by column),
and the contraction each approximation gives alone (the true matrix with only that part as
assembled): the springs' and buoyancy's, the face drag's; and with the face drag's velocity Jacobian
spread over each triangle's corners as ``w w^T`` (w the corners' shares of its force: symmetric,
exact for a uniform velocity, blind to motions whose weighted mean is zero) instead of lumped onto
the diagonal (row sums).
"""

from __future__ import annotations

import argparse

import numpy as np

import wetcloth
from wetcloth._core import _system_matvec, forces, forces_and_blocks
from wetcloth.scene import from_dict

from _sink_map import sink_map_runs

STEP = 0.1  # s
#: The corners of a cell's two triangles (offsets from its lower-left particle, in units of (1, nx))
#: and their shares of the triangle's force (the core's ``water.cpp``: the right-angle corner 1/2).
TRIANGLES = (((0, 0), (1, 0), (1, 1)), ((0, 0), (1, 1), (0, 1)))
SHARES = ((0.25, 0.5, 0.25), (0.25, 0.25, 0.5))


def jacobians(model, physics, pos, vel, water, eps=1e-7):
    """(dF/dx, dF/dv) (3n x 3n, components major) by forward differences of the forces kernel."""
    n = pos.shape[1]

    def force(p, v):
        forces(model.cloth, physics, model.work, p, v, water)
        return model.work.force.ravel().copy()

    base = force(pos, vel)
    dx, dv = np.zeros((3 * n, 3 * n)), np.zeros((3 * n, 3 * n))
    for k in range(3 * n):
        c, i = divmod(k, n)
        p, v = pos.copy(), vel.copy()
        p[c, i] += eps
        v[c, i] += 0.1 * eps
        dx[:, k] = (force(p, vel) - base) / eps
        dv[:, k] = (force(pos, v) - base) / (0.1 * eps)
    return dx, dv


def assembled(model, physics, pos, vel, water, mass, bh):
    """The matrix the conjugate gradients solve with, column by column."""
    n = pos.shape[1]
    forces_and_blocks(model.cloth, physics, model.work, pos, vel, water, bh)
    w = model.work
    matrix, unit, out = np.zeros((3 * n, 3 * n)), np.zeros((3, n)), np.zeros((3, n))
    for k in range(3 * n):
        unit[...] = 0.0
        unit.ravel()[k] = 1.0
        _system_matvec(model.cloth.offsets, w.direction, w.along, w.across, mass, w.blocks, np.ones(n), unit, out,
                       np.zeros_like(w.buf))
        matrix[:, k] = out.ravel()
    return matrix


def consistent_drag(model, bh):
    """``bh sum_t (w w^T) x B_t`` from the triangles' drag Jacobians B_t (N s/m) that the last
    ``forces_and_blocks`` left in ``work.cells``."""
    nx, ny, n = model.topology.nx, model.topology.ny, model.topology.n
    cells = model.work.cells
    matrix = np.zeros((3 * n, 3 * n))
    for cell_y in range(ny - 1):
        for cell_x in range(nx - 1):
            corner = cell_y * nx + cell_x
            for t, (offsets, shares) in enumerate(zip(TRIANGLES, SHARES)):
                xx, yy, zz, xy, xz, yz = cells[t, 3:9, nx + 1 + corner]
                block = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
                particles = [corner + dx + dy * nx for dx, dy in offsets]
                for p, wp in zip(particles, shares):
                    for q, wq in zip(particles, shares):
                        matrix[p::n, q::n] += bh * wp * wq * block
    return matrix


def contraction(approximate, true):
    return float(np.abs(np.linalg.eigvals(np.eye(len(true)) - np.linalg.solve(approximate, true))).max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", type=int, default=10, help="index of the sink_map run (default: capacity 5, rate 0.3)")
    parser.add_argument("--times", type=float, nargs="+", default=[22.0, 28.0])
    args = parser.parse_args()
    _, runs = sink_map_runs()
    params = runs[args.run].params
    print(f"sink_map run {args.run}: absorption_capacity {params['absorption_capacity']:g}, "
          f"absorption_rate {params['absorption_rate']:g}; step {STEP:g} s")
    sim = wetcloth.Simulation(from_dict(params))
    model = sim.model
    bh = 2.0 / 3.0 * STEP
    no_drag = model.physics._replace(drag_normal=0.0, drag_tangential=0.0, drag_linear=0.0)
    for t in sorted(args.times):
        sim.sample([t])
        pos, vel, water = sim.state.pos.copy(), sim.state.vel.copy(), sim.state.water.copy()
        mass = np.tile(model.dry_mass + water, 3)
        dx, dv = jacobians(model, model.physics, pos, vel, water)
        dx_rest, dv_rest = jacobians(model, no_drag, pos, vel, water)
        true = np.diag(mass) - bh * dv - bh * bh * dx
        true_rest = np.diag(mass) - bh * dv_rest - bh * bh * dx_rest
        approximate_rest = assembled(model, no_drag, pos, vel, water, model.dry_mass + water, bh)
        approximate = assembled(model, model.physics, pos, vel, water, model.dry_mass + water, bh)
        drag_part = approximate - approximate_rest
        consistent = approximate_rest + consistent_drag(model, bh)
        print(f"t = {t:g} s, depth {sim.outputs()['depth']:.3f} m: contraction {contraction(approximate, true):.3f} "
              f"as assembled, of which {contraction(approximate, true_rest + drag_part):.3f} from the springs' and "
              f"buoyancy's approximation alone and {contraction(approximate, approximate_rest + (true - true_rest)):.3f} "
              f"from the drag's alone; {contraction(consistent, true):.3f} with the drag's velocity Jacobian as w w^T")


if __name__ == "__main__":
    main()
