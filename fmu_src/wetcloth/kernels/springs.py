"""Spring forces (docs/model.md section 3) and their Jacobians for the implicit integrator.

A spring family joins particle ``i`` to ``i + offset``.  Kernels work on views: with
``m = n - offset``, ``a[:m]`` is every spring's first end and ``a[offset:]`` its second, so every
loop indexes all its arrays with the same counter and the compiler vectorises it.

Per family, one loop writes each spring's coefficients into rows of their own; then a few loops add
the springs' terms to their ends, each filling several rows at once (x, y, z, or a block's six
slots), so that no input is read again for every row.  The helpers are inlined
(``inline="always"``): a separately compiled kernel costs a call.  A loop vectorises only while it
writes few rows: LLVM checks at run time that no row written overlaps another array.  The previous
coefficient loop, which also stored the relative velocity (seven rows), ran scalar; with six it
vectorises (eight failed too).  Measured against the previous implementation, one loop per row and
spring end with a kernel call for each: ``bench/spring_assembly.py``.
"""

from __future__ import annotations

import math

from wetcloth.kernels import kernel

_TINY_LENGTH = 1e-12  # m; below this a spring has no direction
#: Tension-only springs pull with the stretch rounded over their first TENSION_ROUNDING of strain
#: (``pulling_stretch``; docs/model.md section 3): with the sharp kink at zero, Newton's iterations
#: flipped hundreds of near-slack springs between taut and slack at every step of a floating cloth.
TENSION_ROUNDING = 6e-4


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


@kernel(inline="always")
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
def _end_rows(out, off, end):
    """The x, y, z rows of ``out`` (3, n) at every spring's first end (``end`` 0) or second end (1),
    and the sign (+1, -1) a spring's term on its first end takes there."""
    m = out.shape[1] - off
    start = end * off
    return out[0, start:start + m], out[1, start:start + m], out[2, start:start + m], 1.0 - 2.0 * end


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


@kernel(inline="always")
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


@kernel(inline="always")
def _add_pair_term(off, scale, coefficient, a, out):
    """out += scale * coefficient[k] * (a_i - a_j) at each spring's first end and the opposite at
    its second; ``a`` and ``out`` are (3, n).  One loop per end adds all three rows."""
    m = a.shape[1] - off
    xi, yi, zi, xj, yj, zj = a[0, :m], a[1, :m], a[2, :m], a[0, off:], a[1, off:], a[2, off:]
    for end in range(2):
        ox, oy, oz, sign = _end_rows(out, off, end)
        for k in range(m):
            c = scale * coefficient[k]
            ox[k] += sign * (c * (xi[k] - xj[k]))
            oy[k] += sign * (c * (yi[k] - yj[k]))
            oz[k] += sign * (c * (zi[k] - zj[k]))


@kernel(inline="always")
def _add_spring_forces(off, t, projected, cf, pos, vel, force):
    """Add the tension ``t[k] (x_i - x_j)`` of ``_tension`` and, unless ``projected``, the thesis
    damping (eq. 3.2) ``-c (v_i - v_j)`` to ``force`` at each spring's first end, the opposite at its
    second."""
    _add_pair_term(off, 1.0, t, pos, force)
    if not projected:
        _add_pair_term(off, -1.0, cf, vel, force)


@kernel
def spring_forces(offsets, rest, tension_only, stiffness, damping, projected, wet_factor, saturation, pos, vel, force, buf):
    """Add tension (eq. 3.1) and damping (eq. 3.2) of every spring to ``force`` (N, (3, n)).

    Springs flagged ``tension_only`` push nothing when compressed.  ``projected`` damping acts
    along the spring only; otherwise the thesis form ``-k_d (v_i - v_j)``.  With ``wet_factor``
    non-zero the stiffness is scaled by ``1 + wet_factor * saturation`` (mean of both ends).
    ``buf`` is scratch of at least one row of n.
    """
    t = buf[0]
    for f in range(offsets.shape[0]):
        off = offsets[f]
        _tension(off, rest[f], tension_only[f], projected, stiffness[f], damping[f], wet_factor, saturation, pos, vel, t)
        _add_spring_forces(off, t, projected, damping[f], pos, vel, force)


@kernel(inline="always")
def _coefficients(off, l0, tension_only, projected, kf, cf, wet_factor, saturation, pos, vel, h, t, u, along, across):
    """Per spring: force coefficient ``t`` (as ``_tension``, without thesis damping), unit direction
    ``u`` (3, n) and the system-matrix block ``along u u^T + across (I - u u^T)`` (kg): six rows, no
    more, or the loop does not vectorise (see the module's docstring)."""
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
        ex = dx * inv
        ey = dy * inv
        ez = dz * inv
        ux[k] = ex
        uy[k] = ey
        uz[k] = ez
        stretch = length - l0
        slope = 1.0
        if tension_only:
            stretch, slope = pulling_stretch(stretch, width)
        rate = (vxi[k] - vxj[k]) * ex + (vyi[k] - vyj[k]) * ey + (vzi[k] - vzj[k]) * ez
        t[k] = -(stiffness * stretch * inv + damp_along * cf[k] * rate * inv)
        # Geometric stiffness k s / L only while pulling, so every block stays positive.
        along[k] = h * cf[k] + h2 * stiffness * slope
        across[k] = damp_across * h * cf[k] + h2 * stiffness * max(stretch, 0.0) * inv


@kernel(inline="always")
def _add_stiffness_times_velocity(off, h, projected, cf, along, across, u, vel, rhs):
    """Add ``h^2 K v`` to ``rhs`` at both ends of each spring: with ``dv = v_i - v_j``, its first end
    gets ``-(h^2 k_across) dv - h^2 (k_along - k_across) (u . dv) u``, its second the opposite.
    ``h^2 k`` is the stiffness part of ``along`` and ``across``: their damping part taken off."""
    m = vel.shape[1] - off
    vxi, vyi, vzi, vxj, vyj, vzj = vel[0, :m], vel[1, :m], vel[2, :m], vel[0, off:], vel[1, off:], vel[2, off:]
    ux, uy, uz = u[0], u[1], u[2]
    thesis = 0.0 if projected else 1.0
    for end in range(2):
        rx, ry, rz, sign = _end_rows(rhs, off, end)
        for k in range(m):
            damping = h * cf[k]
            k_across = across[k] - thesis * damping
            dvx = vxi[k] - vxj[k]
            dvy = vyi[k] - vyj[k]
            dvz = vzi[k] - vzj[k]
            along_part = (along[k] - damping - k_across) * (dvx * ux[k] + dvy * uy[k] + dvz * uz[k])
            rx[k] -= sign * (k_across * dvx + along_part * ux[k])
            ry[k] -= sign * (k_across * dvy + along_part * uy[k])
            rz[k] -= sign * (k_across * dvz + along_part * uz[k])


@kernel(inline="always")
def _springs_from(along, across, u, first):
    """Views of ``along``, ``across`` and the rows of ``u`` from spring ``first`` on."""
    return along[first:], across[first:], u[0, first:], u[1, first:], u[2, first:]


@kernel(inline="always")
def _spring_block(k, springs):
    """Spring k's block ``across I + (along - across) u u^T`` (kg) as its six slots xx, yy, zz, xy, xz, yz;
    ``springs`` is ``_springs_from``'s views."""
    along, across, ux, uy, uz = springs
    iso = across[k]
    aniso = along[k] - iso
    x, y, z = ux[k], uy[k], uz[k]
    return iso + aniso * x * x, iso + aniso * y * y, iso + aniso * z * z, aniso * x * y, aniso * x * z, aniso * y * z


@kernel(inline="always")
def _block_rows(blocks, lo, hi):
    """The six rows of ``blocks`` (6, n) for particles lo..hi-1."""
    return (blocks[0, lo:hi], blocks[1, lo:hi], blocks[2, lo:hi], blocks[3, lo:hi], blocks[4, lo:hi],
            blocks[5, lo:hi])


@kernel(inline="always")
def _add_slots(rows, j, block):
    """rows[s][j] += block[s] for the six slots."""
    xx, yy, zz, xy, xz, yz = rows
    xx[j] += block[0]
    yy[j] += block[1]
    zz[j] += block[2]
    xy[j] += block[3]
    xz[j] += block[4]
    yz[j] += block[5]


@kernel(inline="always")
def _add_blocks(off, along, across, u, blocks):
    """Add each spring's block to ``blocks`` (6, n: xx, yy, zz, xy, xz, yz) at both its ends.

    Particle i is the first end of spring i (if i < m = n - off) and the second end of spring
    i - off (if i >= off).  Particles off..m-1 are both and get their two blocks in one pass, so
    each of the six slots is read and written once, not once per end (measured faster on the 21 x 29
    and 64 x 64 towels: bench/spring_assembly.py)."""
    n = blocks.shape[1]
    m = n - off
    head, tail = min(off, m), max(off, m)
    springs = _springs_from(along, across, u, 0)
    rows = _block_rows(blocks, 0, head)
    for j in range(head):  # first ends only
        _add_slots(rows, j, _spring_block(j, springs))
    shifted = _springs_from(along, across, u, off)
    rows = _block_rows(blocks, off, m)
    for j in range(m - off):  # particle off + j: first end of spring off + j, second end of spring j
        a = _spring_block(j, shifted)
        b = _spring_block(j, springs)
        _add_slots(rows, j, (a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3], a[4] + b[4], a[5] + b[5]))
    springs = _springs_from(along, across, u, tail - off)
    rows = _block_rows(blocks, tail, n)
    for j in range(n - tail):  # second ends only
        _add_slots(rows, j, _spring_block(j, springs))


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
    block-Jacobi preconditioner is made.  ``buf`` is scratch of at least one row of n.

    Per family: ``_coefficients``, then forces and ``h^2 K v`` one loop per spring end each, the blocks
    in one pass over the particles (``_add_blocks``).
    """
    t = buf[0]
    for f in range(offsets.shape[0]):
        off = offsets[f]
        u = direction[f]
        cf = damping[f]
        _coefficients(off, rest[f], tension_only[f], projected, stiffness[f], cf, wet_factor, saturation, pos, vel, h, t,
                      u, along[f], across[f])
        _add_spring_forces(off, t, projected, cf, pos, vel, force)
        _add_stiffness_times_velocity(off, h, projected, cf, along[f], across[f], u, vel, rhs)
        _add_blocks(off, along[f], across[f], u, diagonal_blocks)


@kernel(inline="always")
def _projection(off, u, al, ac, p, proj):
    """proj[k] = (along - across) * (u . (p_i - p_j)) for each spring."""
    m = p.shape[1] - off
    xi, yi, zi = p[0, :m], p[1, :m], p[2, :m]
    xj, yj, zj = p[0, off:], p[1, off:], p[2, off:]
    ux, uy, uz = u[0], u[1], u[2]
    for k in range(m):
        proj[k] = (al[k] - ac[k]) * (ux[k] * (xi[k] - xj[k]) + uy[k] * (yi[k] - yj[k]) + uz[k] * (zi[k] - zj[k]))


@kernel
def spring_matvec(offsets, direction, along, across, p, out, buf):
    """Add the springs' part of the system matrix times ``p`` ((3, n)) to ``out``; ``buf`` (2, n) scratch.

    One loop per row and spring end, through a scratch row: loops writing all three rows at once
    (as ``_add_pair_term``) measured 1.07x faster on the 9 x 9 towel, 1.1x on the 21 x 29 and 2x
    slower on the 64 x 64 (shared machine)."""
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
