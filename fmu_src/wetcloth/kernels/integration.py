"""Per-particle update kernels of the integrators, and the conjugate-gradient solve of the implicit one."""

from __future__ import annotations

import math

from numba import njit

from wetcloth.kernels import FASTMATH
from wetcloth.kernels.springs import spring_matvec


@njit(cache=True, fastmath=FASTMATH)
def euler_update(pos, vel, force, dry_mass, water, free, h, symplectic, out_pos, out_vel):
    """One Euler step: ``v+ = v + h F/m``; ``x+ = x + h v+`` (symplectic) or ``x + h v`` (explicit).

    Pinned particles (``free == 0``) keep zero velocity.  Returns ``max |v+ - v|`` (m/s).
    """
    largest = 0.0
    for c in range(3):
        for i in range(pos.shape[1]):
            dv = h * free[i] * force[c, i] / (dry_mass[i] + water[i])
            v_new = (vel[c, i] + dv) * free[i]
            out_vel[c, i] = v_new
            out_pos[c, i] = pos[c, i] + h * (v_new if symplectic else vel[c, i])
            largest = max(largest, abs(v_new - vel[c, i]))
    return largest


@njit(cache=True, fastmath=FASTMATH)
def speed_and_finiteness(pos, vel, water):
    """(fastest particle's speed in m/s, whether every value is finite) of a state."""
    fastest = 0.0
    total = 0.0
    for i in range(pos.shape[1]):
        v2 = vel[0, i] ** 2 + vel[1, i] ** 2 + vel[2, i] ** 2
        fastest = max(fastest, v2)
        total += v2 + pos[0, i] + pos[1, i] + pos[2, i] + water[i]
    return math.sqrt(fastest), math.isfinite(total)


@njit(cache=True, fastmath=FASTMATH)
def largest_deviation(pos, anchor):
    """Largest coordinate difference (m) between two (3, n) position arrays."""
    largest = 0.0
    for c in range(3):
        for i in range(pos.shape[1]):
            largest = max(largest, abs(pos[c, i] - anchor[c, i]))
    return largest


@njit(cache=True, fastmath=FASTMATH)
def _system_matvec(offsets, direction, along, across, mass, blocks, free, p, out, buf):
    """out = A p with A = M + per-particle blocks + spring blocks, rows of pinned particles zeroed."""
    n = p.shape[1]
    for i in range(n):
        px, py, pz = p[0, i], p[1, i], p[2, i]
        out[0, i] = mass[i] * px + blocks[0, i] * px + blocks[3, i] * py + blocks[4, i] * pz
        out[1, i] = mass[i] * py + blocks[3, i] * px + blocks[1, i] * py + blocks[5, i] * pz
        out[2, i] = mass[i] * pz + blocks[4, i] * px + blocks[5, i] * py + blocks[2, i] * pz
    spring_matvec(offsets, direction, along, across, p, out, buf)
    for c in range(3):
        for i in range(n):
            out[c, i] *= free[i]


@njit(cache=True, fastmath=FASTMATH)
def _dot(a, b):
    total = 0.0
    for c in range(3):
        for i in range(a.shape[1]):
            total += a[c, i] * b[c, i]
    return total


@njit(cache=True, fastmath=FASTMATH)
def solve_pcg(offsets, direction, along, across, mass, blocks, diag, free, b, x, r, z, p, ap, buf, rtol, max_iterations):
    """Solve ``A x = b`` by Jacobi-preconditioned conjugate gradients; ``x`` holds the first guess.

    ``A`` as in ``_system_matvec``; ``diag`` (3, n) is its diagonal.  Stops when the residual
    norm falls below ``rtol * |b|``.  Returns (iterations, relative residual).
    """
    n = b.shape[1]
    _system_matvec(offsets, direction, along, across, mass, blocks, free, x, ap, buf)
    for c in range(3):
        for i in range(n):
            r[c, i] = free[i] * b[c, i] - ap[c, i]
            z[c, i] = r[c, i] / diag[c, i]
            p[c, i] = z[c, i]
    b_norm = math.sqrt(_dot(b, b))
    if b_norm == 0.0:
        b_norm = 1.0
    rz = _dot(r, z)
    residual = math.sqrt(_dot(r, r)) / b_norm
    iterations = 0
    while residual > rtol and iterations < max_iterations:
        _system_matvec(offsets, direction, along, across, mass, blocks, free, p, ap, buf)
        p_ap = _dot(p, ap)
        if p_ap <= 0.0:
            break
        alpha = rz / p_ap
        for c in range(3):
            for i in range(n):
                x[c, i] += alpha * p[c, i]
                r[c, i] -= alpha * ap[c, i]
                z[c, i] = r[c, i] / diag[c, i]
        rz_new = _dot(r, z)
        beta = rz_new / rz
        rz = rz_new
        for c in range(3):
            for i in range(n):
                p[c, i] = z[c, i] + beta * p[c, i]
        residual = math.sqrt(_dot(r, r)) / b_norm
        iterations += 1
    return iterations, residual
