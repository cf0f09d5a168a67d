"""The spring kernels against their previous implementation, on the towel at three grid sizes.

    .venv/bin/python bench/spring_assembly.py [--sizes 9x9 21x29 64x64] [--repeat 15]

Each grid is the default towel (``models/towel.toml``) with ``nx`` x ``ny`` particles, advanced 1 s
(the landing: springs taut and slack, cloth in the water).  On its state, timed in one process,
alternately, best of ``--repeat`` batches:

* ``spring_forces_and_blocks`` (once per Newton iteration of the implicit schemes) at
  h = 1/45 s (BDF2's 2/3 of a 1/30 s step);
* ``spring_matvec`` (once per conjugate-gradient iteration) on the blocks that call left;
* ``spring_forces`` (the explicit schemes' step).

The previous implementation (commit 4a27671: one loop per row and spring end, each helper a kernel
called by symbol) is copied below, compiled as every kernel is (``wetcloth.kernels.kernel``, not
cached).  Each batch runs the kernel ``calls`` times in one compiled loop, itself called through
``TypedCall``, so that neither numba's typing of the arguments nor Python is timed.

Before timing, both implementations run on the same arrays, with projected damping (the towel's)
and with thesis damping and wetness-dependent stiffness (every branch), and must agree to 1e-12 of
each output's largest entry (they differ by the order of floating-point sums only).
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np

import wetcloth
from wetcloth.kernels import OPTIONS, springs
from wetcloth.kernels.compilation import TypedCall, compile_kernel
from wetcloth.kernels.springs import TENSION_ROUNDING, _pair_views, _spring_geometry, pulling_stretch

STEP = 1.0 / 45.0  # s, BDF2's h for a 1/30 s step
AGREEMENT = 1e-12  # of each output's largest entry


# ------------------------------------------------------------ the previous implementation (4a27671)
def kernel(function):
    """``function`` compiled as ``wetcloth.kernels.kernel`` compiles it, but not cached: a cached kernel
    binds its callees again by module name, and this script's is ``__main__`` only when run."""
    return compile_kernel(function, dict(OPTIONS, cache=False))


@kernel
def old_add_to_both_ends(b, off, out, sign):
    m = out.shape[0] - off
    first = out[:m]
    second = out[off:]
    values = b[:m]
    for k in range(m):
        first[k] += values[k]
    for k in range(m):
        second[k] += sign * values[k]


@kernel
def old_tension(off, l0, tension_only, projected, kf, cf, wet_factor, saturation, pos, vel, t):
    m = pos.shape[1] - off
    xi, yi, zi, xj, yj, zj, vxi, vyi, vzi, vxj, vyj, vzj, si, sj = _pair_views(off, pos, vel, saturation)
    damp = 1.0 if projected else 0.0
    width = TENSION_ROUNDING * l0
    for k in range(m):
        dx, dy, dz, length, inv, stiffness = _spring_geometry(xi[k], yi[k], zi[k], xj[k], yj[k], zj[k], kf[k], si[k],
                                                              sj[k], wet_factor)
        stretch = length - l0
        if tension_only:
            stretch = pulling_stretch(stretch, width)[0]
        rate = (vxi[k] - vxj[k]) * dx + (vyi[k] - vyj[k]) * dy + (vzi[k] - vzj[k]) * dz
        t[k] = -(stiffness * stretch * inv + damp * cf[k] * rate * inv * inv)


@kernel
def old_apply_pair_term(off, t, a, out, buf):
    m = a.shape[0] - off
    ai, aj = a[:m], a[off:]
    for k in range(m):
        buf[k] = t[k] * (ai[k] - aj[k])
    old_add_to_both_ends(buf, off, out, -1.0)


@kernel
def old_thesis_damping(off, cf, vel, force, negated, scratch):
    m = vel.shape[1] - off
    for k in range(m):
        negated[k] = -cf[k]
    for c in range(3):
        old_apply_pair_term(off, negated, vel[c], force[c], scratch)


@kernel
def old_spring_forces(offsets, rest, tension_only, stiffness, damping, projected, wet_factor, saturation, pos, vel,
                      force, buf):
    t, scratch, negated = buf[0], buf[1], buf[2]
    for f in range(offsets.shape[0]):
        off = offsets[f]
        old_tension(off, rest[f], tension_only[f], projected, stiffness[f], damping[f], wet_factor, saturation, pos, vel,
                    t)
        for c in range(3):
            old_apply_pair_term(off, t, pos[c], force[c], scratch)
        if not projected:
            old_thesis_damping(off, damping[f], vel, force, negated, scratch)


@kernel
def old_blocks(off, l0, tension_only, projected, kf, cf, wet_factor, saturation, pos, vel, h, t, u, along, across, rate):
    m = pos.shape[1] - off
    xi, yi, zi, xj, yj, zj, vxi, vyi, vzi, vxj, vyj, vzj, si, sj = _pair_views(off, pos, vel, saturation)
    ux, uy, uz = u[0], u[1], u[2]
    damp_along = 1.0 if projected else 0.0
    damp_across = 0.0 if projected else 1.0
    width = TENSION_ROUNDING * l0
    h2 = h * h
    for k in range(m):
        dx, dy, dz, length, inv, stiffness = _spring_geometry(xi[k], yi[k], zi[k], xj[k], yj[k], zj[k], kf[k], si[k],
                                                              sj[k], wet_factor)
        ux[k] = dx * inv
        uy[k] = dy * inv
        uz[k] = dz * inv
        stretch = length - l0
        slope = 1.0
        if tension_only:
            stretch, slope = pulling_stretch(stretch, width)
        rate[k] = (vxi[k] - vxj[k]) * ux[k] + (vyi[k] - vyj[k]) * uy[k] + (vzi[k] - vzj[k]) * uz[k]
        t[k] = -(stiffness * stretch * inv + damp_along * cf[k] * rate[k] * inv)
        along[k] = h * cf[k] + h2 * stiffness * slope
        across[k] = damp_across * h * cf[k] + h2 * stiffness * max(stretch, 0.0) * inv


_BLOCK_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


@kernel
def old_spring_forces_and_blocks(offsets, rest, tension_only, stiffness, damping, projected, wet_factor, saturation,
                                 pos, vel, h, force, rhs, diagonal_blocks, direction, along, across, buf):
    n = pos.shape[1]
    t, rate, scratch, value = buf[0], buf[1], buf[2], buf[3]
    for f in range(offsets.shape[0]):
        off = offsets[f]
        m = n - off
        u = direction[f]
        al = along[f]
        ac = across[f]
        cf = damping[f]
        old_blocks(off, rest[f], tension_only[f], projected, stiffness[f], cf, wet_factor, saturation, pos, vel, h, t,
                   u, al, ac, rate)
        for c in range(3):
            old_apply_pair_term(off, t, pos[c], force[c], scratch)
        if not projected:
            old_thesis_damping(off, cf, vel, force, t, scratch)
        thesis = 0.0 if projected else 1.0
        for k in range(m):
            value[k] = -(ac[k] - thesis * h * cf[k])
        for c in range(3):
            old_apply_pair_term(off, value, vel[c], rhs[c], scratch)
        for k in range(m):
            t[k] = -((al[k] - h * cf[k]) + value[k]) * rate[k]
        for c in range(3):
            uc = u[c]
            for k in range(m):
                scratch[k] = t[k] * uc[k]
            old_add_to_both_ends(scratch, off, rhs[c], -1.0)
        for slot in range(6):
            a, b = _BLOCK_PAIRS[slot]
            ua, ub = u[a], u[b]
            iso = 1.0 if slot < 3 else 0.0
            for k in range(m):
                scratch[k] = iso * ac[k] + (al[k] - ac[k]) * ua[k] * ub[k]
            old_add_to_both_ends(scratch, off, diagonal_blocks[slot], 1.0)


@kernel
def old_projection(off, u, al, ac, p, proj):
    m = p.shape[1] - off
    xi, yi, zi = p[0, :m], p[1, :m], p[2, :m]
    xj, yj, zj = p[0, off:], p[1, off:], p[2, off:]
    ux, uy, uz = u[0], u[1], u[2]
    for k in range(m):
        proj[k] = (al[k] - ac[k]) * (ux[k] * (xi[k] - xj[k]) + uy[k] * (yi[k] - yj[k]) + uz[k] * (zi[k] - zj[k]))


@kernel
def old_spring_matvec(offsets, direction, along, across, p, out, buf):
    n = p.shape[1]
    proj, scratch = buf[0], buf[1]
    for f in range(offsets.shape[0]):
        off = offsets[f]
        m = n - off
        u = direction[f]
        al = along[f]
        ac = across[f]
        old_projection(off, u, al, ac, p, proj)
        for c in range(3):
            pc = p[c]
            pi, pj = pc[:m], pc[off:]
            uc = u[c]
            for k in range(m):
                scratch[k] = ac[k] * (pi[k] - pj[k]) + proj[k] * uc[k]
            old_add_to_both_ends(scratch, off, out[c], -1.0)


# ------------------------------------------------------------------------------------ the benchmark
def repeated(function):
    """A compiled loop calling ``function`` (a kernel) ``calls`` times with the arguments ``args`` (a tuple)."""

    @numba.njit(nogil=True)
    def repeat(calls, args):
        for _ in range(calls):
            function(*args)

    return TypedCall(repeat)


KERNELS = {  # name: (new, previous, indices of the arguments it writes)
    "spring_forces_and_blocks": (springs.spring_forces_and_blocks, old_spring_forces_and_blocks, (11, 12, 13, 14, 15, 16)),
    "spring_matvec": (springs.spring_matvec, old_spring_matvec, (5,)),
    "spring_forces": (springs.spring_forces, old_spring_forces, (10,)),
}


def towel_state(nx: int, ny: int) -> tuple:
    """The towel's model and state after 1 s."""
    sim = wetcloth.Simulation(wetcloth.load_scene("towel", nx=nx, ny=ny))
    sim.advance(1.0)
    return sim.model, sim.state


def arguments(name: str, model, state, projected: bool, wet_factor: float) -> list:
    """Fresh arguments (outputs zeroed) of kernel ``name`` on the model's arrays."""
    c, w = model.cloth, model.work
    n = state.pos.shape[1]
    saturation = w.saturation if wet_factor == 0.0 else np.random.default_rng(1).uniform(0.0, 1.0, n)
    common = [c.offsets, c.rest, c.tension_only, c.stiffness, c.damping, projected, wet_factor, saturation,
              state.pos, state.vel]
    if name == "spring_forces":
        return common + [np.zeros((3, n)), np.zeros((4, n))]
    blocks = common + [STEP, np.zeros((3, n)), np.zeros((3, n)), np.zeros((6, n)), np.zeros_like(w.direction),
                       np.zeros_like(w.along), np.zeros_like(w.across), np.zeros((4, n))]
    if name == "spring_forces_and_blocks":
        return blocks
    springs.spring_forces_and_blocks(*blocks)
    p = np.random.default_rng(2).normal(size=(3, n))
    return [c.offsets, blocks[14], blocks[15], blocks[16], p, np.zeros((3, n)), np.zeros((4, n))]


def check_agreement(model, state) -> None:
    """Both implementations write the same arrays, to AGREEMENT, with every damping and stiffness branch."""
    for name, (new, old, outputs) in KERNELS.items():
        for projected, wet_factor in ((True, 0.0), (False, 0.5)):
            a = arguments(name, model, state, projected, wet_factor)
            b = arguments(name, model, state, projected, wet_factor)
            new(*a)
            old(*b)
            for i in outputs:
                scale = np.abs(b[i]).max()
                error = np.abs(a[i] - b[i]).max() / scale
                if not error <= AGREEMENT:
                    raise SystemExit(f"{name} (projected={projected}): output {i} differs by {error:.1e} of its "
                                     f"largest entry {scale:.3g}")


def best_times(name: str, model, state, calls: int, repeat: int) -> tuple[float, float]:
    """Best us per call of the new and the previous kernel, timed alternately."""
    new, old, _ = KERNELS[name]
    timed = {}
    for label, function in (("new", new), ("old", old)):
        args = tuple(arguments(name, model, state, True, model.physics.wet_factor))
        loop = repeated(function)
        loop(1, args)  # compiles
        timed[label] = (loop, args)
    best = {label: float("inf") for label in timed}
    for _ in range(repeat):
        for label, (loop, args) in timed.items():
            start = time.perf_counter()
            loop(calls, args)
            best[label] = min(best[label], (time.perf_counter() - start) / calls * 1e6)
    return best["new"], best["old"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", nargs="+", default=["9x9", "21x29", "64x64"], help="grids nx x ny")
    parser.add_argument("--repeat", type=int, default=15)
    args = parser.parse_args()
    print(f"{'grid':>7s} {'springs':>7s}  {'kernel':26s} {'new us':>8s} {'old us':>8s} {'speed-up':>8s}")
    for size in args.sizes:
        nx, ny = (int(v) for v in size.split("x"))
        model, state = towel_state(nx, ny)
        check_agreement(model, state)
        count = model.topology.spring_count
        calls = max(20, 2_000_000 // state.pos.shape[1] // 10)
        for name in KERNELS:
            new, old = best_times(name, model, state, calls, args.repeat)
            print(f"{size:>7s} {count:7d}  {name:26s} {new:8.2f} {old:8.2f} {old / new:7.2f}x")
    print(f"outputs agree to {AGREEMENT:g} of their largest entries; best of {args.repeat} batches, alternating")


if __name__ == "__main__":
    main()
