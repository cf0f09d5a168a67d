"""Per-particle update kernels of the integrators, and the conjugate-gradient solve of the implicit one."""

from __future__ import annotations

import math

from wetcloth.kernels import kernel
from wetcloth.kernels.springs import spring_matvec


@kernel
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


@kernel
def speed_and_finiteness(pos, vel, water):
    """(fastest particle's speed in m/s, whether every value is finite) of a state."""
    fastest = 0.0
    total = 0.0
    for i in range(pos.shape[1]):
        v2 = vel[0, i] ** 2 + vel[1, i] ** 2 + vel[2, i] ** 2
        fastest = max(fastest, v2)
        total += v2 + pos[0, i] + pos[1, i] + pos[2, i] + water[i]
    return math.sqrt(fastest), math.isfinite(total)


@kernel
def largest_deviation(pos, anchor):
    """Largest coordinate difference (m) between two (3, n) position arrays."""
    largest = 0.0
    for c in range(3):
        for i in range(pos.shape[1]):
            largest = max(largest, abs(pos[c, i] - anchor[c, i]))
    return largest


@kernel
def copy(source, target):
    """target[...] = source, for two C-contiguous arrays of the same shape (1-d or 2-d)."""
    a = source.reshape(-1)
    b = target.reshape(-1)
    for k in range(a.shape[0]):
        b[k] = a[k]


@kernel
def total(a):
    """Sum of a 1-d array."""
    s = 0.0
    for k in range(a.shape[0]):
        s += a[k]
    return s


@kernel
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


@kernel
def _dot(a, b):
    total = 0.0
    for c in range(3):
        for i in range(a.shape[1]):
            total += a[c, i] * b[c, i]
    return total


@kernel(inline="always")
def symmetric_adjugate(a, b, c, d, e, f):
    """The adjugate of the symmetric 3x3 matrix [[a, d, e], [d, b, f], [e, f, c]] and its determinant:
    (c11, c22, c33, c12, c13, c23, det); the inverse is the adjugate over det."""
    c11 = b * c - f * f
    c22 = a * c - e * e
    c33 = a * b - d * d
    c12 = e * f - d * c
    c13 = d * f - b * e
    c23 = d * e - a * f
    return c11, c22, c33, c12, c13, c23, a * c11 + d * c12 + e * c13


@kernel
def invert_blocks(blocks, inverse):
    """Invert symmetric 3x3 blocks (6, n: xx, yy, zz, xy, xz, yz) into ``inverse`` (same layout).

    A block that is not positive definite (a pinned particle's, whose rows are zero) gets the
    identity, so the preconditioner stays defined; its residual is zero anyway."""
    for i in range(blocks.shape[1]):
        c11, c22, c33, c12, c13, c23, det = symmetric_adjugate(blocks[0, i], blocks[1, i], blocks[2, i], blocks[3, i],
                                                               blocks[4, i], blocks[5, i])
        if not det > 0.0:
            c11, c22, c33, c12, c13, c23, det = 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0
        scale = 1.0 / det
        inverse[0, i] = c11 * scale
        inverse[1, i] = c22 * scale
        inverse[2, i] = c33 * scale
        inverse[3, i] = c12 * scale
        inverse[4, i] = c13 * scale
        inverse[5, i] = c23 * scale


@kernel
def apply_block_inverse(inverse, r, z):
    """z = B^-1 r with B^-1 the (6, n) inverted diagonal blocks."""
    for i in range(r.shape[1]):
        rx, ry, rz = r[0, i], r[1, i], r[2, i]
        z[0, i] = inverse[0, i] * rx + inverse[3, i] * ry + inverse[4, i] * rz
        z[1, i] = inverse[3, i] * rx + inverse[1, i] * ry + inverse[5, i] * rz
        z[2, i] = inverse[4, i] * rx + inverse[5, i] * ry + inverse[2, i] * rz


@kernel
def _combine_first_guesses(offsets, direction, along, across, mass, blocks, inverse, free, b, x, r, z, p, ap, buf):
    """Replace the first guess ``x`` by the combination ``c1 x + c2 B^-1 b`` that minimises the energy
    ``x.A x / 2 - b.x`` (what conjugate gradients minimise), and leave its residual in ``r``.

    The given guess (the explicit step) is right for smooth motion, which the springs barely
    resist; the block-Jacobi solve ``B^-1 b`` is right for stiff, local motion.  Their best
    combination is at least as good as either, for two products with ``A``."""
    n = b.shape[1]
    apply_block_inverse(inverse, b, z)
    for c in range(3):
        for i in range(n):
            z[c, i] *= free[i]
    _system_matvec(offsets, direction, along, across, mass, blocks, free, x, ap, buf)
    _system_matvec(offsets, direction, along, across, mass, blocks, free, z, p, buf)
    a11, a12, a22 = _dot(x, ap), _dot(x, p), _dot(z, p)
    b1, b2 = _dot(b, x), _dot(b, z)
    det = a11 * a22 - a12 * a12
    if det > 1e-12 * a11 * a22:
        c1, c2 = (b1 * a22 - b2 * a12) / det, (a11 * b2 - a12 * b1) / det
    elif a22 > 0.0:  # the two guesses are (nearly) parallel: the best multiple of the second
        c1, c2 = 0.0, b2 / a22
    else:  # no force at all
        c1, c2 = 0.0, 0.0
    for c in range(3):
        for i in range(n):
            x[c, i] = c1 * x[c, i] + c2 * z[c, i]
            r[c, i] = free[i] * b[c, i] - c1 * ap[c, i] - c2 * p[c, i]


@kernel(inline="always")
def conjugate_gradient_step(alpha, p, ap, x, r):
    """One conjugate-gradient update along the search direction ``p`` (``ap`` = A p), in place:
    ``x += alpha p``, ``r -= alpha A p``."""
    for c in range(3):
        for i in range(x.shape[1]):
            x[c, i] += alpha * p[c, i]
            r[c, i] -= alpha * ap[c, i]


@kernel(inline="always")
def next_search_direction(beta, z, p):
    """The next conjugate-gradient search direction, in place: ``p = z + beta p``."""
    for c in range(3):
        for i in range(p.shape[1]):
            p[c, i] = z[c, i] + beta * p[c, i]


@kernel
def solve_pcg(offsets, direction, along, across, mass, blocks, inverse, free, b, x, r, z, p, ap, buf, rtol,
              max_iterations):
    """Solve ``A x = b`` by block-Jacobi-preconditioned conjugate gradients from a first guess.

    ``A`` as in ``_system_matvec``; ``inverse`` (6, n) holds the inverses of its 3x3 diagonal blocks
    (``invert_blocks``).  ``x`` holds a first guess, which is improved by
    ``_combine_first_guesses`` before iterating.  Stops when the residual norm falls below
    ``rtol * |b|``.  Returns (iterations, relative residual).
    """
    n = b.shape[1]
    _combine_first_guesses(offsets, direction, along, across, mass, blocks, inverse, free, b, x, r, z, p, ap, buf)
    apply_block_inverse(inverse, r, z)
    for c in range(3):
        for i in range(n):
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
        conjugate_gradient_step(rz / p_ap, p, ap, x, r)
        apply_block_inverse(inverse, r, z)
        rz_new = _dot(r, z)
        next_search_direction(rz_new / rz, z, p)
        rz = rz_new
        residual = math.sqrt(_dot(r, r)) / b_norm
        iterations += 1
    return iterations, residual
