"""The tank floor: a rigid plane with Coulomb friction."""

from __future__ import annotations

import math

from wetcloth.kernels import kernel


@kernel
def floor_contact(z_min, friction, pos, vel):
    """Keep particle centres at or above ``z_min`` (m); stop their fall and apply friction.

    The normal velocity change ``dv_n`` removed by the floor reduces the sliding speed by
    ``friction * dv_n`` (an inelastic Coulomb impulse), never reversing it.  Returns the
    number of particles in contact.
    """
    touching = 0
    for i in range(pos.shape[1]):
        if pos[2, i] >= z_min:
            continue
        touching += 1
        pos[2, i] = z_min
        dvn = -vel[2, i] if vel[2, i] < 0.0 else 0.0
        vel[2, i] = max(vel[2, i], 0.0)
        slide = math.sqrt(vel[0, i] ** 2 + vel[1, i] ** 2)
        if slide > 0.0:
            keep = max(0.0, 1.0 - friction * dvn / slide)
            vel[0, i] *= keep
            vel[1, i] *= keep
    return touching
