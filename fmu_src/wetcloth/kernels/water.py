"""Water forces (MODEL.md section 4): submerged fraction, buoyancy, Stokes drag and face drag.

Face drag works per grid cell, each split into two triangles (i, i+1, i+nx+1) and
(i, i+nx+1, i+nx), the same split as ``Topology.triangles``.  Per-triangle values go into
buffers of length ``n + nx + 1`` (cell ``i`` at slot ``i + nx + 1``; slots of non-cells stay
zero), and each particle gathers a third of its six triangles' values.
"""

from __future__ import annotations

import math

from numba import njit

from wetcloth.kernels import FASTMATH


@njit(cache=True, fastmath=FASTMATH)
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


@njit(cache=True, fastmath=FASTMATH)
def buoyancy(s, volume, density, gravity, force):
    """Add Archimedes' upward force ``rho g V s`` (eq. 3.4, corrected) to ``force[2]``."""
    fz = force[2]
    scale = density * gravity
    for i in range(s.shape[0]):
        fz[i] += scale * volume[i] * s[i]


@njit(cache=True, fastmath=FASTMATH)
def stokes_drag(s, coefficient, current_x, current_y, vel, force):
    """Add ``-6 pi a eta s (v - v_water)`` (eq. 3.5); ``coefficient`` is 6 pi a eta (N s/m)."""
    for i in range(s.shape[0]):
        c = coefficient[i] * s[i]
        force[0, i] -= c * (vel[0, i] - current_x)
        force[1, i] -= c * (vel[1, i] - current_y)
        force[2, i] -= c * vel[2, i]


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _triangle(a, b, c, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y):
    """Drag on one triangle and its Jacobian coefficients.

    Returns (Fx, Fy, Fz, nx, ny, nz, k_normal, k_tangential, k_linear): the force (N), the unit
    normal, and ``dF/du = k_normal n n^T + k_tangential (I - n n^T) + k_linear I`` (N s/m) with
    ``u`` the water's velocity relative to the triangle.
    """
    st = (s[a] + s[b] + s[c]) * (1.0 / 3.0)
    if st == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0
    e1x = pos[0, b] - pos[0, a]
    e1y = pos[1, b] - pos[1, a]
    e1z = pos[2, b] - pos[2, a]
    e2x = pos[0, c] - pos[0, a]
    e2y = pos[1, c] - pos[1, a]
    e2z = pos[2, c] - pos[2, a]
    cx = e1y * e2z - e1z * e2y
    cy = e1z * e2x - e1x * e2z
    cz = e1x * e2y - e1y * e2x
    twice_area = math.sqrt(cx * cx + cy * cy + cz * cz)
    if twice_area == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0
    inv = 1.0 / twice_area
    nx = cx * inv
    ny = cy * inv
    nz = cz * inv
    wet_area = 0.5 * twice_area * st
    ux = current_x - (vel[0, a] + vel[0, b] + vel[0, c]) * (1.0 / 3.0)
    uy = current_y - (vel[1, a] + vel[1, b] + vel[1, c]) * (1.0 / 3.0)
    uz = -(vel[2, a] + vel[2, b] + vel[2, c]) * (1.0 / 3.0)
    un = ux * nx + uy * ny + uz * nz
    utx = ux - un * nx
    uty = uy - un * ny
    utz = uz - un * nz
    ut = math.sqrt(utx * utx + uty * uty + utz * utz)
    q = 0.5 * density * wet_area
    kn = q * c_normal * abs(un)
    kt = q * c_tangential * ut
    kl = c_linear * wet_area
    fx = kn * un * nx + kt * utx + kl * ux
    fy = kn * un * ny + kt * uty + kl * uy
    fz = kn * un * nz + kt * utz + kl * uz
    # d(|w| w)/dw has norm 2|w|: the Jacobian's coefficients are twice the force's.
    return fx, fy, fz, nx, ny, nz, 2.0 * kn, 2.0 * kt, kl


@njit(cache=True, fastmath=FASTMATH, inline="always")
def _gather_cells(t1, t2, nx, out, scale):
    """out[v] += scale * (the values of the six triangles around particle v)."""
    pad = nx + 1
    for v in range(out.shape[0]):
        k = pad + v
        out[v] += scale * (t1[k] + t1[k - 1] + t1[k - nx - 1] + t2[k] + t2[k - nx - 1] + t2[k - nx])


@njit(cache=True, fastmath=FASTMATH)
def face_drag(nx, ny, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y, force, cells):
    """Add the face-model drag (MODEL.md section 4) to ``force``; ``cells`` is (2, 9, n + nx + 1) scratch."""
    pad = nx + 1
    for r in range(ny - 1):
        for col in range(nx - 1):
            i = r * nx + col
            f1 = _triangle(i, i + 1, i + nx + 1, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y)
            f2 = _triangle(i, i + nx + 1, i + nx, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y)
            for comp in range(3):
                cells[0, comp, pad + i] = f1[comp]
                cells[1, comp, pad + i] = f2[comp]
    for comp in range(3):
        _gather_cells(cells[0, comp], cells[1, comp], nx, force[comp], 1.0 / 3.0)


@njit(cache=True, fastmath=FASTMATH)
def face_drag_and_blocks(nx, ny, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y, h, force, blocks, cells):
    """Face drag as ``face_drag``, plus ``h`` times its lumped velocity Jacobian added to ``blocks``.

    ``blocks`` (6, n) holds symmetric 3x3 blocks as xx, yy, zz, xy, xz, yz.  Each triangle's
    Jacobian goes one third to each of its particles (row-sum lumping: exact for a uniform
    velocity).  The tangential part uses its larger eigenvalue in every in-plane direction.
    """
    pad = nx + 1
    for r in range(ny - 1):
        for col in range(nx - 1):
            i = r * nx + col
            for t in range(2):
                if t == 0:
                    res = _triangle(i, i + 1, i + nx + 1, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y)
                else:
                    res = _triangle(i, i + nx + 1, i + nx, pos, vel, s, density, c_normal, c_tangential, c_linear, current_x, current_y)
                fx, fy, fz, nxx, nyy, nzz, kn, kt, kl = res
                cells[t, 0, pad + i] = fx
                cells[t, 1, pad + i] = fy
                cells[t, 2, pad + i] = fz
                d = kn - kt
                iso = kt + kl
                cells[t, 3, pad + i] = iso + d * nxx * nxx
                cells[t, 4, pad + i] = iso + d * nyy * nyy
                cells[t, 5, pad + i] = iso + d * nzz * nzz
                cells[t, 6, pad + i] = d * nxx * nyy
                cells[t, 7, pad + i] = d * nxx * nzz
                cells[t, 8, pad + i] = d * nyy * nzz
    for comp in range(3):
        _gather_cells(cells[0, comp], cells[1, comp], nx, force[comp], 1.0 / 3.0)
    for comp in range(6):
        _gather_cells(cells[0, 3 + comp], cells[1, 3 + comp], nx, blocks[comp], h / 3.0)
