"""Water forces (docs/model.md section 4): submerged fraction, buoyancy, Stokes drag and face drag.

Face drag works per grid cell, each split into two triangles (i, i+1, i+nx+1) and
(i, i+nx+1, i+nx), the same split as ``Topology.triangles``: two right triangles, with the right
angle at i+1 and at i+nx.  Per-triangle values go into buffers of length ``n + nx + 1`` (cell
``i`` at slot ``i + nx + 1``; slots of non-cells stay zero), and each particle gathers its share
of its six triangles' values with the weights of its area (docs/model.md section 4): the right-angle
corner 1/2, the other two 1/4 each.  These sum to the quarter-cell areas of ``Topology.area``, so
a uniform load per area gives every particle the same acceleration.
"""

from __future__ import annotations

import math

from wetcloth.kernels import kernel


@kernel
def submerged_fractions(z, water_level, thickness, smooth, s):
    """Write each particle's submerged fraction (0..1) into ``s``; return the largest."""
    top = 0.0
    inv_thickness = 1.0 / thickness
    for i in range(z.shape[0]):
        if smooth:
            v = min(max((water_level - z[i]) * inv_thickness + 0.5, 0.0), 1.0)
        else:
            v = 1.0 if z[i] < water_level else 0.0
        s[i] = v
        top = max(top, v)
    return top


@kernel
def buoyancy(s, volume, density, gravity, force):
    """Add Archimedes' upward force ``rho g V s`` (eq. 3.4, corrected) to ``force[2]``."""
    fz = force[2]
    scale = density * gravity
    for i in range(s.shape[0]):
        fz[i] += scale * volume[i] * s[i]


@kernel
def stokes_drag(s, coefficient, current_x, current_y, vel, force):
    """Add ``-6 pi a eta s (v - v_water)`` (eq. 3.5); ``coefficient`` is 6 pi a eta (N s/m)."""
    for i in range(s.shape[0]):
        c = coefficient[i] * s[i]
        force[0, i] -= c * (vel[0, i] - current_x)
        force[1, i] -= c * (vel[1, i] - current_y)
        force[2, i] -= c * vel[2, i]


@kernel(inline="always")
def _triangle(k, a, b, c, density, c_normal, c_tangential, c_linear, current_x, current_y):
    """Drag on triangle k of a row and its Jacobian coefficients.

    ``a``, ``b``, ``c`` are the corners, each a tuple of views (x, y, z, vx, vy, vz, s) along the
    row.  Returns (Fx, Fy, Fz, normal_x, normal_y, normal_z, k_normal, k_tangential, k_linear,
    slip_x, slip_y, slip_z, k_slip): the force (N), the unit normal n, and its Jacobian
    ``dF/du = k_normal n n^T + k_tangential (I - n n^T) + k_linear I + k_slip s s^T`` (N s/m) with
    ``u`` the water's velocity relative to the triangle and ``s`` its in-plane part (the slip).
    Branch-free, so rows vectorise.
    """
    st = (a[6][k] + b[6][k] + c[6][k]) * (1.0 / 3.0)
    e1x = b[0][k] - a[0][k]
    e1y = b[1][k] - a[1][k]
    e1z = b[2][k] - a[2][k]
    e2x = c[0][k] - a[0][k]
    e2y = c[1][k] - a[1][k]
    e2z = c[2][k] - a[2][k]
    cx = e1y * e2z - e1z * e2y
    cy = e1z * e2x - e1x * e2z
    cz = e1x * e2y - e1y * e2x
    twice_area = math.sqrt(cx * cx + cy * cy + cz * cz)
    inv = 1.0 / max(twice_area, 1e-300)
    normal_x = cx * inv
    normal_y = cy * inv
    normal_z = cz * inv
    wet_area = 0.5 * twice_area * st
    ux = current_x - (a[3][k] + b[3][k] + c[3][k]) * (1.0 / 3.0)
    uy = current_y - (a[4][k] + b[4][k] + c[4][k]) * (1.0 / 3.0)
    uz = -(a[5][k] + b[5][k] + c[5][k]) * (1.0 / 3.0)
    un = ux * normal_x + uy * normal_y + uz * normal_z
    utx = ux - un * normal_x
    uty = uy - un * normal_y
    utz = uz - un * normal_z
    ut = math.sqrt(utx * utx + uty * uty + utz * utz)
    q = 0.5 * density * wet_area
    kn = q * c_normal * abs(un)
    kt = q * c_tangential * ut
    kl = c_linear * wet_area
    fx = kn * un * normal_x + kt * utx + kl * ux
    fy = kn * un * normal_y + kt * uty + kl * uy
    fz = kn * un * normal_z + kt * utz + kl * uz
    # d(|w| w)/dw = |w| I + w w^T / |w|: along w twice the force's coefficient, across it once.
    return (fx, fy, fz, normal_x, normal_y, normal_z, 2.0 * kn, kt, kl, utx, uty, utz,
            q * c_tangential / max(ut, 1e-300))


@kernel(inline="always")
def _corner(pos, vel, s, start, count):
    """Views (x, y, z, vx, vy, vz, s) of ``count`` particles from index ``start``."""
    stop = start + count
    return (pos[0, start:stop], pos[1, start:stop], pos[2, start:stop],
            vel[0, start:stop], vel[1, start:stop], vel[2, start:stop], s[start:stop])


@kernel
def _gather_cells(t1, t2, nx, out, scale):
    """out[v] += scale * (particle v's area-weighted share of the six triangles around it).

    Particle v is corner a (weight 1/4) of both triangles of cell v, the right-angle corner b (1/2)
    of cell v-1's first triangle, corner d (1/4) of both triangles of cell v-nx-1, and the
    right-angle corner c (1/2) of cell v-nx's second triangle."""
    n = out.shape[0]
    pad = nx + 1
    a1, b1, d1 = t1[pad:pad + n], t1[pad - 1:pad - 1 + n], t1[:n]
    a2, d2, c2 = t2[pad:pad + n], t2[:n], t2[1:1 + n]
    quarter, half = 0.25 * scale, 0.5 * scale
    for v in range(n):
        out[v] += quarter * (a1[v] + d1[v] + a2[v] + d2[v]) + half * (b1[v] + c2[v])


@kernel(inline="always")
def _drag_row(k_count, a, b, c, density, c_normal, c_tangential, c_linear, current_x, current_y, out, blocks_wanted):
    """Triangles (a[k], b[k], c[k]): force and, if wanted, Jacobian blocks into ``out`` (9, k)."""
    fx_, fy_, fz_ = out[0], out[1], out[2]
    xx, yy, zz, xy, xz, yz = out[3], out[4], out[5], out[6], out[7], out[8]
    for k in range(k_count):
        fx, fy, fz, normal_x, normal_y, normal_z, kn, kt, kl, sx, sy, sz, ks = _triangle(
            k, a, b, c, density, c_normal, c_tangential, c_linear, current_x, current_y)
        fx_[k] = fx
        fy_[k] = fy
        fz_[k] = fz
        if blocks_wanted:
            diff = kn - kt
            iso = kt + kl
            xx[k] = iso + diff * normal_x * normal_x + ks * sx * sx
            yy[k] = iso + diff * normal_y * normal_y + ks * sy * sy
            zz[k] = iso + diff * normal_z * normal_z + ks * sz * sz
            xy[k] = diff * normal_x * normal_y + ks * sx * sy
            xz[k] = diff * normal_x * normal_z + ks * sx * sz
            yz[k] = diff * normal_y * normal_z + ks * sy * sz


@kernel(inline="always")
def _dry(s, start, stop):
    """Whether no particle from ``start`` to ``stop`` touches water."""
    for i in range(start, stop):
        if s[i] > 0.0:
            return False
    return True


@kernel
def _drag_rows(nx, ny, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y, cells,
               blocks_wanted, skip_dry_rows):
    """Fill ``cells`` (2, 9, n + nx + 1) with both triangles' force and, if wanted, Jacobian blocks
    (xx, yy, zz, xy, xz, yz) for every cell.  Rows of cells none of whose particles touches water
    have no drag: with ``skip_dry_rows``, those above the highest wet row and below the lowest are
    zeroed, not computed.  The rows between are computed in one run along the grid, as if every
    particle began a cell (fewer, longer loops: on a floating 9 x 9 cloth face drag with its blocks
    took 4.0-4.6 us a call this way, 6.6 us row by row; 32 x 32: 54-59 against 64 us).  The last
    column's, which are no cells, are then zeroed (dry triangles have zero drag anyway: their wet
    area is zero)."""
    pad = nx + 1
    first, last = 0, ny - 2
    if skip_dry_rows:
        while first <= last and _dry(s, first * nx, first * nx + 2 * nx):
            first += 1
        while last >= first and _dry(s, last * nx, last * nx + 2 * nx):
            last -= 1
    cells[:, :, pad:pad + first * nx] = 0.0
    cells[:, :, pad + (last + 1) * nx:] = 0.0
    if first > last:
        return
    start = first * nx
    count = (last - first + 1) * nx - 1
    a = _corner(pos, vel, s, start, count)
    b = _corner(pos, vel, s, start + 1, count)
    c = _corner(pos, vel, s, start + nx, count)
    d = _corner(pos, vel, s, start + nx + 1, count)
    lo, hi = pad + start, pad + start + count
    _drag_row(count, a, b, d, density, c_normal, c_tangential, c_linear, current_x, current_y, cells[0, :, lo:hi],
              blocks_wanted)
    _drag_row(count, a, d, c, density, c_normal, c_tangential, c_linear, current_x, current_y, cells[1, :, lo:hi],
              blocks_wanted)
    for r in range(first, last):
        cells[:, :, pad + r * nx + nx - 1] = 0.0


@kernel
def _drag_forces(nx, ny, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y, force, cells,
                 blocks_wanted, skip_dry_rows):
    """Every cell's drag (and, if wanted, its Jacobian) into ``cells``; the forces gathered into ``force``."""
    _drag_rows(nx, ny, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y, cells,
               blocks_wanted, skip_dry_rows)
    for comp in range(3):
        _gather_cells(cells[0, comp], cells[1, comp], nx, force[comp], 1.0)


@kernel
def face_drag(nx, ny, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y, force, cells,
              skip_dry_rows=True):
    """Add the face-model drag (docs/model.md section 4) to ``force``; ``cells`` is (2, 9, n + nx + 1) scratch."""
    _drag_forces(nx, ny, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y, force, cells,
                 False, skip_dry_rows)


@kernel
def face_drag_and_blocks(nx, ny, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y, h, force,
                         blocks, cells, skip_dry_rows=True):
    """Face drag as ``face_drag``, plus ``h`` times its lumped velocity Jacobian added to ``blocks``.

    ``blocks`` (6, n) holds symmetric 3x3 blocks as xx, yy, zz, xy, xz, yz.  Each triangle's
    Jacobian goes to its particles with the force's weights (row-sum lumping: exact for a uniform
    velocity).
    """
    _drag_forces(nx, ny, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y, force, cells,
                 True, skip_dry_rows)
    for comp in range(6):
        _gather_cells(cells[0, 3 + comp], cells[1, 3 + comp], nx, blocks[comp], h)
