"""What the hanging sheet's frame-step solves pay for (issue 25): preconditioners compared on its
Newton systems, by CG iterations.

    .venv/bin/python bench/sheet_preconditioners.py [--time 1 2 3] [--side 81] [--newton 1]

Runs the sheet of bench/hanging_sheet.py (``implicit_euler``, frames of 1/30 s, self-collision on)
to each --time, forms the next step's Newton systems as the core does (forces_and_blocks with the
taut-spring slope, frames at the step's predicted end; after the first, each from the last iterate
moved by the exact correction, cut to 1/2 or 1/4 where the step's potential would rise), reads
the matrix A from the core's
system_matvec (75 products: 5 x 5 grid colours times 3 components) and counts the conjugate-gradient
iterations each preconditioner takes to the fixed steps' tolerance (the preconditioned residual's
largest component 3e-2 of its first, as plane_pcg):

- core, frame split: the core's preconditioner (apply), a V-cycle on each frame component's stencil;
- core, x y z split: the same with every particle's frame the x, y, z axes;
- exact frame split / exact x y z split: those three stencil systems solved exactly;
- exact coupled: the 3 x 3-block stencil (A without the springs the stencil does not reach) solved exactly;
- coupled V-cycle (1 or 2 sweeps; frame or x y z): multigrid on that coupled stencil in the frame's or
  the axes' coordinates, point Gauss-Seidel in particle order (a particle's three components
  together), bilinear interpolation of each component, Galerkin coarse levels, the coarsest solved
  exactly;
- coupled level 0: the same with only level 0 coupled and the split's Galerkin coarse levels.
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
import scipy.sparse.linalg as spl  # noqa: E402

import wetcloth  # noqa: E402
from hanging_sheet import FRAME, sheet  # noqa: E402
from wetcloth import _core  # noqa: E402

CG_TOLERANCE = 3e-2  # implicit.hpp's DESCENT_CG_TOLERANCE
SLACK_SLOPE = 1.0  # implicit.hpp's DESCENT_SLACK_SLOPE
COARSEST_SIDE = 12  # plane.hpp's


def pcg(a, b, precondition, max_iterations=300) -> int:
    """CG iterations on a x = b until max |P^-1 r| <= CG_TOLERANCE of its first value (plane_pcg's test)."""
    x, r = np.zeros_like(b), b.copy()
    z = precondition(r)
    p, rz, accuracy, count = z.copy(), r @ z, CG_TOLERANCE * np.abs(z).max(), 0
    while np.abs(z).max() > accuracy and count < max_iterations:
        ap = a @ p
        step = rz / (p @ ap)
        x += step * p
        r -= step * ap
        z = precondition(r)
        rz, previous = r @ z, rz
        p = z + rz / previous * p
        count += 1
    return count


def read_matrix(matvec, n: int, grid_x: int):
    """A (3n, 3n) from its products with 75 probes; neighbours lie within 2 grid lines (bending)."""
    ix, iy = np.arange(n) % grid_x, np.arange(n) // grid_x
    rows, cols, values = [], [], []
    for c in range(3):
        for a in range(5):
            for b in range(5):
                probe = np.zeros(3 * n)
                probe[c * n + np.nonzero((ix % 5 == a) & (iy % 5 == b))[0]] = 1.0
                column = matvec(probe)
                hit = np.nonzero(column)[0]
                owner = np.full(hit.size, -1)
                for dy in range(-2, 3):
                    for dx in range(-2, 3):
                        jx, jy = ix[hit % n] + dx, iy[hit % n] + dy
                        ok = (jx >= 0) & (jx < grid_x) & (jy >= 0) & (jy < n // grid_x) & (jx % 5 == a) & (jy % 5 == b)
                        owner[ok] = (jy * grid_x + jx)[ok]
                rows.append(hit)
                cols.append(c * n + owner)
                values.append(column[hit])
    return sp.csr_matrix((np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))), shape=(3 * n, 3 * n))


def keep(m, rule):
    """The entries of m (particle-major: dof 3 i + component) whose components (row, column) pass rule."""
    m = m.tocoo()
    kept = rule(m.row % 3, m.col % 3)
    return sp.csr_matrix((m.data[kept], (m.row[kept], m.col[kept])), shape=m.shape)


def split(m):
    return keep(m, lambda a, b: a == b)


def interpolation(nx: int, ny: int):
    """Bilinear P from the grid keeping every other line (nx // 2 + 1 of nx) to (nx, ny), per component."""
    cx = nx // 2 + 1
    rows, cols, values = [], [], []
    for j in range(ny):
        for i in range(nx):
            for pi, wi in ([(i // 2, 1.0)] if i % 2 == 0 else [(i // 2, 0.5), (i // 2 + 1, 0.5)]):
                for pj, wj in ([(j // 2, 1.0)] if j % 2 == 0 else [(j // 2, 0.5), (j // 2 + 1, 0.5)]):
                    rows.append(j * nx + i)
                    cols.append(pj * cx + pi)
                    values.append(wi * wj)
    p = sp.csr_matrix((values, (rows, cols)), shape=(nx * ny, cx * (ny // 2 + 1)))
    return sp.kron(p, sp.eye(3)).tocsr(), cx, ny // 2 + 1


def v_cycle(fine, grid_x: int, grid_y: int, split_coarse: bool, sweeps: int):
    """b -> one symmetric V-cycle's x for `fine` (particle-major, every particle's three components)."""
    matrices, transfers, nx, ny = [fine.tocsr()], [], grid_x, grid_y
    while min(nx, ny) > COARSEST_SIDE:
        p, nx, ny = interpolation(nx, ny)
        above = split(matrices[-1]) if split_coarse and len(matrices) == 1 else matrices[-1]
        transfers.append(p)
        matrices.append((p.T @ above @ p).tocsr())
    lower = [sp.tril(m).tocsr() for m in matrices]
    upper = [sp.triu(m).tocsr() for m in matrices]
    coarsest = spl.splu(matrices[-1].tocsc())

    def cycle(level, b):
        if level == len(matrices) - 1:
            return coarsest.solve(b)
        m, x = matrices[level], np.zeros_like(b)
        for _ in range(sweeps):
            x += spl.spsolve_triangular(lower[level], b - m @ x, lower=True)
        x += transfers[level] @ cycle(level + 1, transfers[level].T @ (b - m @ x))
        for _ in range(sweeps):
            x += spl.spsolve_triangular(upper[level], b - m @ x, lower=False)
        return x

    return lambda b: cycle(0, b)


def compare(side: int, until: float, newton: int) -> None:
    sim = wetcloth.Simulation(sheet(side, "on", integrator="implicit_euler", tolerance=0.0, max_step=FRAME))
    for _ in range(round(until / FRAME)):
        sim.advance(FRAME)
    model, plane, buffers = sim.model, sim._plane, sim._buffers
    cloth, work, mass, free = model.cloth, model.work, sim._solver.mass, model.cloth.free
    n, grid_x = free.size, cloth.grid_x
    hat_vel = buffers.vel * free
    out_vel = hat_vel.copy()

    def matvec(p):
        out = np.zeros(3 * n)
        _core.system_matvec(cloth, work, mass, p, out)
        return out

    def core_apply(r):
        z = np.zeros(3 * n)
        _core.apply(plane, free, r, z)
        return z

    def residual(vel):  # Newton's right-hand side at vel, and the pieces of its matrix in work
        _core.forces_and_blocks(cloth, model.physics, work, buffers.pos + FRAME * vel, vel, buffers.water, FRAME,
                                SLACK_SLOPE)
        return (free * (FRAME * work.force - mass * (vel - hat_vel))).ravel()

    for iteration in range(newton):
        rhs = residual(out_vel)
        results = compare_on(cloth, work, plane, mass, free, buffers.pos + FRAME * out_vel, rhs, matvec, core_apply)
        print(f"t = {until:g} s, Newton iteration {iteration}: " + ", ".join(f"{k} {v}" for k, v in results.items()),
              flush=True)
        # The exact correction, cut as descent would: the longest of 1, 1/2, 1/4 where the step's
        # potential still falls (the residual's slope along it positive).
        moving = np.tile(free, 3) != 0
        a_full = read_matrix(matvec, n, grid_x)
        correction = np.zeros(3 * n)
        correction[moving] = spl.splu(a_full[moving][:, moving].tocsc()).solve(rhs[moving])
        for length in (1.0, 0.5, 0.25):
            trial = out_vel + length * correction.reshape(3, n)
            if correction @ residual(trial) > 0.0:
                break
        out_vel = trial


def compare_on(cloth, work, plane, mass, free, out_pos, rhs, matvec, core_apply) -> dict:
    """CG iterations of each preconditioner on the system whose pieces are in work."""
    n, grid_x = free.size, cloth.grid_x
    a_full = read_matrix(matvec, n, grid_x)
    families = len(cloth.offsets)
    saved = work.along.copy(), work.across.copy()
    for f in np.nonzero(np.asarray(plane.slots)[:families] < 0)[0]:  # springs the stencil does not reach
        work.along.reshape(families, n)[f] = 0.0
        work.across.reshape(families, n)[f] = 0.0
    a_stencil = read_matrix(matvec, n, grid_x)
    work.along[...], work.across[...] = saved
    results = {}
    frame = np.asarray(plane.frame).reshape(3, 3, n)  # [axis, x y z, particle]
    for name, axes in (("frame", None), ("x y z", np.eye(3)[:, :, None])):
        if axes is None:
            _core.follow_cloth(plane, cloth, out_pos)
        else:
            frame[...] = axes
        _core.set_systems_from_jacobian(plane, cloth, mass, work)
        results[f"core, {name} split"] = pcg(a_full, rhs, core_apply)
        # q: particle-major frame coordinates -> component-major x y z, 3 i + axis -> component n + i
        rows = np.concatenate([c * n + np.arange(n) for r in range(3) for c in range(3)])
        cols = np.concatenate([3 * np.arange(n) + r for r in range(3) for c in range(3)])
        q = sp.csr_matrix((np.concatenate([frame[r, c] for r in range(3) for c in range(3)]), (rows, cols)),
                          shape=(3 * n, 3 * n))
        local = (q.T @ a_stencil @ q).tocsr()
        held = np.repeat(free == 0, 3)  # a pinned particle's rows: the identity (its CG residual is 0)
        local = (sp.diags(1.0 * ~held) @ local @ sp.diags(1.0 * ~held) + sp.diags(1.0 * held)).tocsr()
        exact = spl.splu(split(local).tocsc())
        results[f"exact {name} split"] = pcg(a_full, rhs, lambda r, s=exact, q=q: q @ s.solve(q.T @ r))
        if axes is None:  # (the coupled system solved exactly is the same in either coordinates)
            coupled = spl.splu(local.tocsc())
            results["exact coupled"] = pcg(a_full, rhs, lambda r: q @ coupled.solve(q.T @ r))
        for label, split_coarse, sweeps in (("coupled V-cycle, 1 sweep", False, 1),
                                            ("coupled V-cycle, 2 sweeps", False, 2),
                                            ("coupled level 0, 1 sweep", True, 1),
                                            ("coupled level 0, 2 sweeps", True, 2)):
            cycle = v_cycle(local, grid_x, n // grid_x, split_coarse, sweeps)
            results[f"{label} ({name})"] = pcg(a_full, rhs, lambda r, c=cycle, q=q: q @ c(q.T @ r))
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--side", type=int, default=81)
    parser.add_argument("--time", type=float, nargs="+", default=[1.0, 2.0, 3.0], help="simulated seconds")
    parser.add_argument("--newton", type=int, default=1, help="Newton iterations of the step to compare on")
    args = parser.parse_args()
    print(f"{args.side} x {args.side} hanging sheet, Newton systems of the step after t; CG iterations to "
          f"{CG_TOLERANCE:g}")
    for until in args.time:
        compare(args.side, until, args.newton)


if __name__ == "__main__":
    main()
