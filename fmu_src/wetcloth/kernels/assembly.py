"""The total force on every particle and, for the implicit schemes, the pieces of its Jacobian.

Each force family is one kernel call, skipped when the scene does not need it: no spring kernel
without springs, no water kernels while no particle touches the water.  A new force family (a
contact or barrier term, say) is one more call here, adding to ``force`` and, for the implicit
schemes, to the per-particle blocks or to the per-spring blocks that the system matrix uses.

The kernels take three bundles (named tuples, which numba compiles like structs):
``Cloth`` (the fixed grid and per-particle constants), ``Physics`` (the scene's parameters, which
inputs may change between calls) and ``Work`` (scratch and result arrays, allocated once).
"""

from __future__ import annotations

from collections import namedtuple

from wetcloth.kernels import kernel
from wetcloth.kernels.springs import spring_forces, spring_forces_and_blocks
from wetcloth.kernels.water import buoyancy, face_drag, face_drag_and_blocks, stokes_drag, submerged_fractions

GRAVITY = 9.81  # m/s2, acting along -z

#: The fixed cloth: grid size, spring families (offset, rest length m, tension only, stiffness N/m,
#: damping N s/m per spring), 1 for moving particles, dry mass kg, envelope volume m3, Stokes
#: coefficient 6 pi a eta (N s/m), water capacity kg, wicking links (offsets, conductance kg/s).
Cloth = namedtuple("Cloth", "grid_x grid_y offsets rest tension_only stiffness damping free dry_mass volume "
                            "stokes_coefficient capacity wick_offsets wick_conductance")
#: Scene parameters as the kernels use them (SI units; flags as bools).  ``wet_factor`` is 0
#: unless wetness-dependent stiffness is active; ``floor_z`` is the lowest particle centre.
Physics = namedtuple("Physics", "projected wet_factor water_level water_density thickness smooth stokes "
                                "drag_normal drag_tangential drag_linear current_x current_y floor_z "
                                "floor_friction absorption_capacity absorption_rate drying_rate wicking_rate "
                                "wick_step_limit skip_idle")
#: Scratch and results: ``force`` (3, n) N; ``submerged`` (n) the submerged fraction of each
#: particle; ``saturation`` (n); ``blocks`` (6, n) per-particle symmetric 3x3 blocks (xx, yy, zz,
#: xy, xz, yz) of the system matrix; ``diagonal_blocks`` (6, n) the springs' part of its diagonal
#: blocks; ``direction`` (F, 3, n), ``along``, ``across`` (F, n) each spring's block; ``rhs`` (3, n);
#: ``buf`` (4, n); ``cells`` (2, 9, n + nx + 1) face-drag rows; ``wick_buffer`` (6, n).
Work = namedtuple("Work", "force submerged saturation blocks diagonal_blocks direction along across rhs buf cells "
                          "wick_buffer")


@kernel
def _start_with_gravity(cloth, water, force):
    n = force.shape[1]
    for i in range(n):
        force[0, i] = 0.0
        force[1, i] = 0.0
        force[2, i] = -(cloth.dry_mass[i] + water[i]) * GRAVITY


@kernel
def _update_saturation(cloth, phys, water, saturation):
    if phys.wet_factor != 0.0:
        for i in range(water.shape[0]):
            saturation[i] = water[i] / cloth.capacity[i]


@kernel
def submerged(phys, z, out):
    """Fill ``out`` with each particle's submerged fraction (0..1); return the largest."""
    return submerged_fractions(z, phys.water_level, phys.thickness, phys.smooth, out)


@kernel
def forces(cloth, phys, work, pos, vel, water):
    """Total force (N) on every particle into ``work.force``; the submerged fractions into
    ``work.submerged``."""
    force = work.force
    _start_with_gravity(cloth, water, force)
    if cloth.offsets.shape[0] > 0:
        _update_saturation(cloth, phys, water, work.saturation)
        spring_forces(cloth.offsets, cloth.rest, cloth.tension_only, cloth.stiffness, cloth.damping, phys.projected,
                      phys.wet_factor, work.saturation, pos, vel, force, work.buf)
    if submerged(phys, pos[2], work.submerged) > 0.0 or not phys.skip_idle:
        _water_forces(cloth, phys, work, pos, vel, 0.0, False)


@kernel
def forces_and_blocks(cloth, phys, work, pos, vel, water, h):
    """Forces as ``forces``, plus the pieces of the system matrix ``M - h dF/dv - h^2 dF/dx``.

    Leaves in ``work.rhs`` the term ``h^2 K v``, in ``work.blocks`` the per-particle symmetric
    blocks (drag, buoyancy) of ``-h C - h^2 K``, in ``work.diagonal_blocks`` the springs' part of the
    system's 3x3 diagonal blocks, and each spring's block in ``direction``, ``along``, ``across``.
    Compressed springs contribute no negative stiffness: the matrix is positive definite.
    """
    force = work.force
    _start_with_gravity(cloth, water, force)
    work.rhs[...] = 0.0
    work.diagonal_blocks[...] = 0.0
    work.blocks[...] = 0.0
    if cloth.offsets.shape[0] > 0:
        _update_saturation(cloth, phys, water, work.saturation)
        spring_forces_and_blocks(
            cloth.offsets, cloth.rest, cloth.tension_only, cloth.stiffness, cloth.damping, phys.projected,
            phys.wet_factor, work.saturation, pos, vel, h, force, work.rhs, work.diagonal_blocks, work.direction,
            work.along, work.across, work.buf,
        )
    if submerged(phys, pos[2], work.submerged) > 0.0 or not phys.skip_idle:
        _water_forces(cloth, phys, work, pos, vel, h, True)


@kernel
def _water_forces(cloth, phys, work, pos, vel, h, blocks_wanted):
    s = work.submerged
    force = work.force
    blocks = work.blocks
    buoyancy(s, cloth.volume, phys.water_density, GRAVITY, force)
    if phys.stokes:
        stokes_drag(s, cloth.stokes_coefficient, phys.current_x, phys.current_y, vel, force)
        if blocks_wanted:
            for i in range(s.shape[0]):
                c = h * cloth.stokes_coefficient[i] * s[i]
                blocks[0, i] += c
                blocks[1, i] += c
                blocks[2, i] += c
    elif blocks_wanted:
        face_drag_and_blocks(cloth.grid_x, cloth.grid_y, pos, vel, s, phys.water_density, phys.drag_normal,
                             phys.drag_tangential, phys.drag_linear, phys.current_x, phys.current_y, h, force, blocks,
                             work.cells, phys.skip_idle)
    else:
        face_drag(cloth.grid_x, cloth.grid_y, pos, vel, s, phys.water_density, phys.drag_normal,
                  phys.drag_tangential, phys.drag_linear, phys.current_x, phys.current_y, force, work.cells,
                  phys.skip_idle)
    if blocks_wanted and phys.smooth:
        # dF_z/dz = -rho g V / thickness inside the surface slab (0 < s < 1).
        scale = h * h * phys.water_density * GRAVITY / phys.thickness
        for i in range(s.shape[0]):
            if 0.0 < s[i] < 1.0:
                stiffness = scale * cloth.volume[i]
                blocks[2, i] += stiffness
                work.rhs[2, i] -= stiffness * vel[2, i]
