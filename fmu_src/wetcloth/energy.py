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
    (a grid's families, a mesh's listed springs: tension-only, buckling, both ways) with the integral of its law
    and its stiffness as the forces take it (grown with ``wet_stiffness_factor`` on a wet cloth; docs/model.md
    sections 2.4 and 3).  The core's (energy.cpp), which the fixed-step mode also weighs its steps with."""
    cloth, state = sim.model.cloth, sim.state
    mass = np.asarray(cloth.dry_mass) + state.water
    return float(_core.mechanical_energy(cloth, sim.model.physics.wet_factor, mass, state.water, state.pos,
                                         state.vel))
