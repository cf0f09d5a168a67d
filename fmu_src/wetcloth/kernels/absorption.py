"""Water uptake (MODEL.md section 5): the Buras law, integrated exactly over a step."""

from __future__ import annotations

from numba import njit

from wetcloth.kernels import FASTMATH

#: A particle whose remaining uptake is below this fraction of its capacity counts as saturated.
SATURATED = 1e-12


@njit(cache=True, fastmath=FASTMATH)
def absorb(s, dry_mass, capacity, decay, water, vel):
    """Advance absorbed water (kg) of particles touching water (``s > 0``) by one step.

    ``dq/dt = I (1 - q/Q)`` over a step of length h is exactly
    ``q+ = Q - (Q - q) * decay`` with ``decay = exp(-I h / Q) = exp(-rate h / capacity)``.
    ``Q = capacity * dry_mass``.  Water arrives at rest: momentum is kept, so the particle
    slows by ``m / m+``.  Returns the number of particles still absorbing.
    """
    active = 0
    for i in range(s.shape[0]):
        if s[i] <= 0.0:
            continue
        full = capacity * dry_mass[i]
        missing = full - water[i]
        if missing <= SATURATED * full:
            continue
        active += 1
        new_water = full - missing * decay
        scale = (dry_mass[i] + water[i]) / (dry_mass[i] + new_water)
        water[i] = new_water
        vel[0, i] *= scale
        vel[1, i] *= scale
        vel[2, i] *= scale
    return active
