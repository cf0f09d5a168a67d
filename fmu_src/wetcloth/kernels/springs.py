"""Spring forces (MODEL.md section 3) and their Jacobians for the implicit integrator.

A spring family joins particle ``i`` to ``i + offset``.  Each kernel first writes one value per
spring into a buffer (a loop the compiler vectorises), then adds the buffer to both ends
(``+b[i]`` at ``i``, ``-b[i - offset]`` at ``i``), which is again a plain vector loop.
"""

from __future__ import annotations

import math

from numba import njit

from wetcloth.kernels import FASTMATH

_TINY_LENGTH = 1e-12  # m; below this a spring has no direction


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _add_to_both_ends(b, off, out):
    """out[i] += b[i] for the spring's first particle, out[i+off] -= b[i] for its second."""
    n = out.shape[0]
    m = n - off
    for v in range(min(off, m)):
        out[v] += b[v]
    for v in range(off, m):
        out[v] += b[v] - b[v - off]
    for v in range(max(m, off), n):
        out[v] -= b[v - off]


@njit(cache=True, fastmath=FASTMATH)
def spring_forces(offsets, rest, tension_only, stiffness, damping, projected, wet_factor, saturation, pos, vel, force, buf):
    """Add tension (eq. 3.1) and damping (eq. 3.2) of every spring to ``force`` (N, (3, n)).

    Springs flagged ``tension_only`` push nothing when compressed.  ``projected`` damping acts
    along the spring only; otherwise the thesis form ``-k_d (v_i - v_j)``.  With ``wet_factor``
    non-zero the stiffness is scaled by ``1 + wet_factor * saturation`` (mean of both ends).
    ``buf`` is (3, n) scratch.
    """
    n = pos.shape[1]
    px, py, pz = pos[0], pos[1], pos[2]
    vx, vy, vz = vel[0], vel[1], vel[2]
    bx, by, bz = buf[0], buf[1], buf[2]
    for f in range(offsets.shape[0]):
        off = offsets[f]
        l0 = rest[f]
        tonly = tension_only[f]
        kf = stiffness[f]
        cf = damping[f]
        m = n - off
        for i in range(m):
            j = i + off
            dx = px[i] - px[j]
            dy = py[i] - py[j]
            dz = pz[i] - pz[j]
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            inv = 1.0 / length if length > _TINY_LENGTH else 0.0
            stretch = length - l0
            if tonly:
                stretch = max(stretch, 0.0)
            k = kf[i]
            if wet_factor != 0.0:
                k *= 1.0 + wet_factor * 0.5 * (saturation[i] + saturation[j])
            t = k * stretch * inv
            dvx = vx[i] - vx[j]
            dvy = vy[i] - vy[j]
            dvz = vz[i] - vz[j]
            if projected:
                t += cf[i] * (dvx * dx + dvy * dy + dvz * dz) * inv * inv
                bx[i] = -t * dx
                by[i] = -t * dy
                bz[i] = -t * dz
            else:
                bx[i] = -t * dx - cf[i] * dvx
                by[i] = -t * dy - cf[i] * dvy
                bz[i] = -t * dz - cf[i] * dvz
        _add_to_both_ends(bx, off, force[0])
        _add_to_both_ends(by, off, force[1])
        _add_to_both_ends(bz, off, force[2])


@njit(cache=True, fastmath=FASTMATH)
def spring_forces_and_blocks(
    offsets, rest, tension_only, stiffness, damping, projected, wet_factor, saturation,
    pos, vel, h, force, rhs, diag, direction, along, across, buf,
):
    """Forces as ``spring_forces`` plus what one backward-Euler Newton step needs.

    With step ``h`` (s), each spring's block of the system matrix ``M - h C - h^2 K`` is
    ``along * u u^T + across * (I - u u^T)`` (kg; ``u`` its unit direction, stored in
    ``direction`` (F, 3, n)).  Adds ``h^2 K v`` to ``rhs`` and each block's diagonal to ``diag``
    at both ends (the Jacobi preconditioner).  The geometric stiffness of a compressed spring
    is dropped so that every block stays positive semi-definite.
    """
    n = pos.shape[1]
    px, py, pz = pos[0], pos[1], pos[2]
    vx, vy, vz = vel[0], vel[1], vel[2]
    bx, by, bz = buf[0], buf[1], buf[2]
    h2 = h * h
    for f in range(offsets.shape[0]):
        off = offsets[f]
        l0 = rest[f]
        tonly = tension_only[f]
        kf = stiffness[f]
        cf = damping[f]
        ux, uy, uz = direction[f, 0], direction[f, 1], direction[f, 2]
        al = along[f]
        ac = across[f]
        m = n - off
        # forces
        for i in range(m):
            j = i + off
            dx = px[i] - px[j]
            dy = py[i] - py[j]
            dz = pz[i] - pz[j]
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            inv = 1.0 / length if length > _TINY_LENGTH else 0.0
            ux[i] = dx * inv
            uy[i] = dy * inv
            uz[i] = dz * inv
            stretch = length - l0
            taut = stretch > 0.0
            if tonly and not taut:
                stretch = 0.0
            k = kf[i]
            if wet_factor != 0.0:
                k *= 1.0 + wet_factor * 0.5 * (saturation[i] + saturation[j])
            k_along = k if (taut or not tonly) else 0.0
            k_across = k * stretch * inv if taut else 0.0  # geometric stiffness k (1 - l0/L)
            dvx = vx[i] - vx[j]
            dvy = vy[i] - vy[j]
            dvz = vz[i] - vz[j]
            dv_along = ux[i] * dvx + uy[i] * dvy + uz[i] * dvz
            t = k * stretch
            c = cf[i]
            if projected:
                t += c * dv_along
                bx[i] = -t * ux[i]
                by[i] = -t * uy[i]
                bz[i] = -t * uz[i]
                al[i] = h * c + h2 * k_along
                ac[i] = h2 * k_across
            else:
                bx[i] = -t * ux[i] - c * dvx
                by[i] = -t * uy[i] - c * dvy
                bz[i] = -t * uz[i] - c * dvz
                al[i] = h * c + h2 * k_along
                ac[i] = h * c + h2 * k_across
        _add_to_both_ends(bx, off, force[0])
        _add_to_both_ends(by, off, force[1])
        _add_to_both_ends(bz, off, force[2])
        # h^2 K v: the stiffness part of the blocks applied to the relative velocity
        for i in range(m):
            j = i + off
            dvx = vx[i] - vx[j]
            dvy = vy[i] - vy[j]
            dvz = vz[i] - vz[j]
            length_term = ac[i] - (h * cf[i] if not projected else 0.0)
            stiff_along = al[i] - h * cf[i]
            dv_along = ux[i] * dvx + uy[i] * dvy + uz[i] * dvz
            bx[i] = -(length_term * dvx + (stiff_along - length_term) * dv_along * ux[i])
            by[i] = -(length_term * dvy + (stiff_along - length_term) * dv_along * uy[i])
            bz[i] = -(length_term * dvz + (stiff_along - length_term) * dv_along * uz[i])
        _add_to_both_ends(bx, off, rhs[0])
        _add_to_both_ends(by, off, rhs[1])
        _add_to_both_ends(bz, off, rhs[2])
        # Jacobi diagonal: the block's diagonal at both ends
        for i in range(m):
            d = al[i] - ac[i]
            bx[i] = ac[i] + d * ux[i] * ux[i]
            by[i] = ac[i] + d * uy[i] * uy[i]
            bz[i] = ac[i] + d * uz[i] * uz[i]
        _add_to_both_ends_positive(bx, off, diag[0])
        _add_to_both_ends_positive(by, off, diag[1])
        _add_to_both_ends_positive(bz, off, diag[2])


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _add_to_both_ends_positive(b, off, out):
    """out[i] += b[i] and out[i+off] += b[i]: a quantity shared by both ends."""
    n = out.shape[0]
    m = n - off
    for v in range(min(off, m)):
        out[v] += b[v]
    for v in range(off, m):
        out[v] += b[v] + b[v - off]
    for v in range(max(m, off), n):
        out[v] += b[v - off]


@njit(cache=True, fastmath=FASTMATH)
def spring_matvec(offsets, direction, along, across, p, out, buf):
    """Add the springs' part of the system matrix times ``p`` ((3, n)) to ``out``."""
    n = p.shape[1]
    px, py, pz = p[0], p[1], p[2]
    bx, by, bz = buf[0], buf[1], buf[2]
    for f in range(offsets.shape[0]):
        off = offsets[f]
        ux, uy, uz = direction[f, 0], direction[f, 1], direction[f, 2]
        al = along[f]
        ac = across[f]
        m = n - off
        for i in range(m):
            j = i + off
            tx = px[i] - px[j]
            ty = py[i] - py[j]
            tz = pz[i] - pz[j]
            proj = (al[i] - ac[i]) * (ux[i] * tx + uy[i] * ty + uz[i] * tz)
            bx[i] = ac[i] * tx + proj * ux[i]
            by[i] = ac[i] * ty + proj * uy[i]
            bz[i] = ac[i] * tz + proj * uz[i]
        _add_to_both_ends(bx, off, out[0])
        _add_to_both_ends(by, off, out[1])
        _add_to_both_ends(bz, off, out[2])
