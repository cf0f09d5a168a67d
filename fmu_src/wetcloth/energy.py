"""The cloth's energy (J): mechanical (kinetic, gravitational, the springs' elastic) and buoyancy's potential.

Their sum is what the fixed-step mode promises not to grow by more than the wind, the current and the grip
do on the cloth (docs/model.md section 7); the mechanical energy alone is what the hanging-sheet benchmark
reports.  Drag and the water's uptake are not counted.
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


def buoyancy_energy(sim) -> float:
    """Buoyancy's potential energy (J) of a Simulation's cloth: rho g times each particle's volume times the depth
    integral of its submerged fraction (docs/model.md sections 4.1 and 4.2), so that minus its gradient is the
    buoyancy force; 0 for a cloth wholly above the water.  The core's (energy.cpp)."""
    return float(_core.buoyancy_energy(sim.model.cloth, sim.model.physics, sim.state.pos))


def total_energy(sim) -> float:
    """Mechanical energy and buoyancy's potential (J) of a Simulation's cloth: what the fixed-step mode does not
    let grow by more than what drives the cloth does (docs/model.md section 7)."""
    return mechanical_energy(sim) + buoyancy_energy(sim)
