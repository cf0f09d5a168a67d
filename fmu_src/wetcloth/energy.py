"""The cloth's mechanical energy: kinetic, gravitational and the springs' elastic energy (J).

What the fixed-step mode promises not to grow (docs/model.md section 7) and what the hanging-sheet
benchmark reports.  Water's forces (buoyancy, drag) and its uptake are not counted: it is the energy
of a cloth in air.
"""

from __future__ import annotations

import numpy as np

from wetcloth import _core


def mechanical_energy(sim) -> float:
    """Kinetic + gravitational (zero at z = 0) + elastic energy (J) of a Simulation's cloth, each spring
    (a grid's families, a mesh's listed springs: tension-only, buckling, both ways) with its dry stiffness and
    the integral of its law (docs/model.md sections 2.4 and 3).  The core's (energy.cpp), which the fixed-step
    mode also weighs self-collision's pushes with."""
    cloth, state = sim.model.cloth, sim.state
    mass = np.asarray(cloth.dry_mass) + state.water
    return float(_core.mechanical_energy(cloth, mass, state.pos, state.vel))
