"""Spring forces (docs/model.md section 3) and their Jacobians for the implicit integrator.

A spring family joins particle ``i`` to ``i + offset``.  Kernels work on views: with
``m = n - offset``, ``a[:m]`` is every spring's first end and ``a[offset:]`` its second, so every
loop indexes all its arrays with the same counter and the compiler vectorises it.  A loop
first writes one value per spring into a buffer, then the buffer is added to both ends.
"""

from __future__ import annotations

import math

from wetcloth.kernels import kernel

_TINY_LENGTH = 1e-12  # m; below this a spring has no direction
#: Tension-only springs pull with the stretch rounded over their first TENSION_ROUNDING of strain
#: (``pulling_stretch``; docs/model.md section 3): with the sharp kink at zero, Newton's iterations
#: flipped hundreds of near-slack springs between taut and slack at every step of a floating cloth.
TENSION_ROUNDING = 6e-4
#: Components (row, column) of the six slots of a symmetric 3x3 block: xx, yy, zz, xy, xz, yz.
_BLOCK_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


@kernel(inline="always")
def pulling_stretch(stretch, width):
    """(the stretch (m) a tension-only spring pulls with, its derivative (-)) for a stretch
    ``s = L - l0`` (m): zero for ``s <= 0``, the stretch itself for ``s >= width`` and between them
    the cubic ``(s^2 / w) (2 - s / w)``, which joins the two with a continuous slope.  It pulls less
    than ``max(s, 0)`` by ``s (1 - s/w)^2``, at most ``4 w / 27``."""
    if stretch >= width:
        return stretch, 1.0
    if stretch <= 0.0:
        return 0.0, 0.0
    r = stretch / width
    return stretch * r * (2.0 - r), r * (4.0 - 3.0 * r)


@kernel
def add_to_both_ends(b, off, out, sign):
    """out[i] += b[i] at each spring's first end and ``sign * b[i]`` at its second (i + off)."""
    m = out.shape[0] - off
    first = out[:m]
    second = out[off:]
    values = b[:m]
    for k in range(m):
        first[k] += values[k]
    for k in range(m):
        second[k] += sign * values[k]


@kernel(inline="always")
def _pair_views(off, pos, vel, saturation):
    """Views of positions, velocities and saturations at every spring's first and second ends."""
    m = pos.shape[1] - off
    return (pos[0, :m], pos[1, :m], pos[2, :m], pos[0, off:], pos[1, off:], pos[2, off:],
            vel[0, :m], vel[1, :m], vel[2, :m], vel[0, off:], vel[1, off:], vel[2, off:],
            saturation[:m], saturation[off:])


@kernel(inline="always")
def _spring_geometry(xi, yi, zi, xj, yj, zj, kf, si, sj, wet_factor):
    """Separation ``d = x_i - x_j`` (3 values, m), length ``L`` (m), ``1 / L`` (1/m; finite for a spring of
    no length) and stiffness ``kf`` (N/m) scaled by the saturations ``si``, ``sj`` of both ends.

    It takes values, not arrays: given ``_pair_views``'s tuple of views and an index, it kept LLVM from
    vectorising ``_tension``'s loop (measured 2.5x slower); with values both loops compile to the
    same instructions as when each had the lines written out."""
    dx = xi - xj
    dy = yi - yj
    dz = zi - zj
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    return dx, dy, dz, length, 1.0 / max(length, _TINY_LENGTH), kf * (1.0 + wet_factor * 0.5 * (si + sj))


@kernel
def _tension(off, l0, tension_only, projected, kf, cf, wet_factor, saturation, pos, vel, t):
    """t[k] (N/m): spring k's force on its first end is ``t[k] * (x_i - x_j)`` (plus thesis damping).

    Tension (eq. 3.1) ``-k (L - l0) / L``, for tension-only springs with the stretch of
    ``pulling_stretch`` (zero when compressed);
    projected damping ``-c ((v_i - v_j) . d) / L^2``; stiffness scaled by ``1 + wet_factor * sat``.
    """
    m = pos.shape[1] - off
    xi, yi, zi, xj, yj, zj, vxi, vyi, vzi, vxj, vyj, vzj, si, sj = _pair_views(off, pos, vel, saturation)
    damp = 1.0 if projected else 0.0
    width = TENSION_ROUNDING * l0
    for k in range(m):
        dx, dy, dz, length, inv, stiffness = _spring_geometry(xi[k], yi[k], zi[k], xj[k], yj[k], zj[k], kf[k], si[k], sj[k],
                                                              wet_factor)
        stretch = length - l0
        if tension_only:
            stretch = pulling_stretch(stretch, width)[0]
        rate = (vxi[k] - vxj[k]) * dx + (vyi[k] - vyj[k]) * dy + (vzi[k] - vzj[k]) * dz
        t[k] = -(stiffness * stretch * inv + damp * cf[k] * rate * inv * inv)


@kernel
def _apply_pair_term(off, t, a, out, buf):
    """out += t[k] * (a_i - a_j) at each spring's first end and the opposite at its second."""
    m = a.shape[0] - off
    ai, aj = a[:m], a[off:]
    for k in range(m):
        buf[k] = t[k] * (ai[k] - aj[k])
    add_to_both_ends(buf, off, out, -1.0)


@kernel
def _thesis_damping(off, cf, vel, force, negated, scratch):
    """Add the thesis damping (eq. 3.2) ``-c (v_i - v_j)`` to ``force`` at each spring's first end and
    the opposite at its second; ``negated`` and ``scratch`` are (n) scratch."""
    m = vel.shape[1] - off
    for k in range(m):
        negated[k] = -cf[k]
    for c in range(3):
        _apply_pair_term(off, negated, vel[c], force[c], scratch)


@kernel
def spring_forces(offsets, rest, tension_only, stiffness, damping, projected, wet_factor, saturation, pos, vel, force, buf):
    """Add tension (eq. 3.1) and damping (eq. 3.2) of every spring to ``force`` (N, (3, n)).

    Springs flagged ``tension_only`` push nothing when compressed.  ``projected`` damping acts
    along the spring only; otherwise the thesis form ``-k_d (v_i - v_j)``.  With ``wet_factor``
    non-zero the stiffness is scaled by ``1 + wet_factor * saturation`` (mean of both ends).
    ``buf`` is (3, n) scratch.
    """
    t, scratch, negated = buf[0], buf[1], buf[2]
    for f in range(offsets.shape[0]):
        off = offsets[f]
        _tension(off, rest[f], tension_only[f], projected, stiffness[f], damping[f], wet_factor, saturation, pos, vel, t)
        for c in range(3):
            _apply_pair_term(off, t, pos[c], force[c], scratch)
        if not projected:
            _thesis_damping(off, damping[f], vel, force, negated, scratch)


@kernel
def _blocks(off, l0, tension_only, projected, kf, cf, wet_factor, saturation, pos, vel, h, t, u, along, across, rate):
    """Per spring: force coefficient ``t`` (as ``_tension``, without thesis damping), unit direction
    ``u`` (3, n), the system-matrix block ``along u u^T + across (I - u u^T)`` and the relative
    velocity along the spring ``rate``."""
    m = pos.shape[1] - off
    xi, yi, zi, xj, yj, zj, vxi, vyi, vzi, vxj, vyj, vzj, si, sj = _pair_views(off, pos, vel, saturation)
    ux, uy, uz = u[0], u[1], u[2]
    damp_along = 1.0 if projected else 0.0
    damp_across = 0.0 if projected else 1.0
    width = TENSION_ROUNDING * l0
    h2 = h * h
    for k in range(m):
        dx, dy, dz, length, inv, stiffness = _spring_geometry(xi[k], yi[k], zi[k], xj[k], yj[k], zj[k], kf[k], si[k], sj[k],
                                                              wet_factor)
        ux[k] = dx * inv
        uy[k] = dy * inv
        uz[k] = dz * inv
        stretch = length - l0
        slope = 1.0
        if tension_only:
            stretch, slope = pulling_stretch(stretch, width)
        rate[k] = (vxi[k] - vxj[k]) * ux[k] + (vyi[k] - vyj[k]) * uy[k] + (vzi[k] - vzj[k]) * uz[k]
        t[k] = -(stiffness * stretch * inv + damp_along * cf[k] * rate[k] * inv)
        # Geometric stiffness k s / L only while pulling, so every block stays positive.
        along[k] = h * cf[k] + h2 * stiffness * slope
        across[k] = damp_across * h * cf[k] + h2 * stiffness * max(stretch, 0.0) * inv


@kernel
def spring_forces_and_blocks(
    offsets, rest, tension_only, stiffness, damping, projected, wet_factor, saturation,
    pos, vel, h, force, rhs, diagonal_blocks, direction, along, across, buf,
):
    """Forces as ``spring_forces`` plus what one backward-Euler Newton step needs.

    With step ``h`` (s), each spring's block of the system matrix ``M - h C - h^2 K`` is
    ``along * u u^T + across * (I - u u^T)`` (kg; ``u`` its unit direction, stored in
    ``direction`` (F, 3, n)).  Adds ``h^2 K v`` to ``rhs`` and each block to ``diagonal_blocks``
    (6, n: xx, yy, zz, xy, xz, yz) at both ends: the matrix's 3x3 diagonal blocks, from which the
    block-Jacobi preconditioner is made.  ``buf`` is (4, n) scratch.
    """
    n = pos.shape[1]
    t, rate, scratch, value = buf[0], buf[1], buf[2], buf[3]
    for f in range(offsets.shape[0]):
        off = offsets[f]
        m = n - off
        u = direction[f]
        al = along[f]
        ac = across[f]
        cf = damping[f]
        _blocks(off, rest[f], tension_only[f], projected, stiffness[f], cf, wet_factor, saturation, pos, vel, h, t,
                u, al, ac, rate)
        for c in range(3):
            _apply_pair_term(off, t, pos[c], force[c], scratch)
        if not projected:
            _thesis_damping(off, cf, vel, force, t, scratch)
        # The stiffness part of the blocks times the relative velocity,
        # h^2 K v = -(h^2 k_across) dv - h^2 (k_along - k_across) (u . dv) u.
        thesis = 0.0 if projected else 1.0
        for k in range(m):
            value[k] = -(ac[k] - thesis * h * cf[k])  # -h^2 k_across
        for c in range(3):
            _apply_pair_term(off, value, vel[c], rhs[c], scratch)
        for k in range(m):
            t[k] = -((al[k] - h * cf[k]) + value[k]) * rate[k]
        for c in range(3):
            uc = u[c]
            for k in range(m):
                scratch[k] = t[k] * uc[k]
            add_to_both_ends(scratch, off, rhs[c], -1.0)
        # The spring's block, at both ends: across on the diagonal plus (along - across) u u^T.
        for slot in range(6):
            a, b = _BLOCK_PAIRS[slot]
            ua, ub = u[a], u[b]
            iso = 1.0 if slot < 3 else 0.0
            for k in range(m):
                scratch[k] = iso * ac[k] + (al[k] - ac[k]) * ua[k] * ub[k]
            add_to_both_ends(scratch, off, diagonal_blocks[slot], 1.0)


@kernel
def spring_matvec(offsets, direction, along, across, p, out, buf):
    """Add the springs' part of the system matrix times ``p`` ((3, n)) to ``out``; ``buf`` (4, n)."""
    n = p.shape[1]
    proj, scratch = buf[0], buf[1]
    for f in range(offsets.shape[0]):
        off = offsets[f]
        m = n - off
        u = direction[f]
        al = along[f]
        ac = across[f]
        _projection(off, u, al, ac, p, proj)
        for c in range(3):
            pc = p[c]
            pi, pj = pc[:m], pc[off:]
            uc = u[c]
            for k in range(m):
                scratch[k] = ac[k] * (pi[k] - pj[k]) + proj[k] * uc[k]
            add_to_both_ends(scratch, off, out[c], -1.0)


@kernel
def _projection(off, u, al, ac, p, proj):
    """proj[k] = (along - across) * (u . (p_i - p_j)) for each spring."""
    m = p.shape[1] - off
    xi, yi, zi = p[0, :m], p[1, :m], p[2, :m]
    xj, yj, zj = p[0, off:], p[1, off:], p[2, off:]
    ux, uy, uz = u[0], u[1], u[2]
    for k in range(m):
        proj[k] = (al[k] - ac[k]) * (ux[k] * (xi[k] - xj[k]) + uy[k] * (yi[k] - yj[k]) + uz[k] * (zi[k] - zj[k]))
