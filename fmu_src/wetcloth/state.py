"""The simulation state: flat arrays that the kernels advance."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wetcloth.scene import Scene
from wetcloth.topology import Topology, initial_positions


@dataclass
class State:
    """Positions and velocities as (3, n) rows x, y, z (m, m/s); absorbed water per particle (kg)."""

    time: float
    pos: np.ndarray
    vel: np.ndarray
    water: np.ndarray

    def copy(self) -> "State":
        return State(self.time, self.pos.copy(), self.vel.copy(), self.water.copy())

    def assign(self, other: "State") -> None:
        """Overwrite this state's contents with ``other``'s (no new arrays)."""
        self.time = other.time
        self.pos[...] = other.pos
        self.vel[...] = other.vel
        self.water[...] = other.water

    def is_finite(self) -> bool:
        return bool(np.isfinite(self.pos).all() and np.isfinite(self.vel).all() and np.isfinite(self.water).all())


def initial_state(scene: Scene, topo: Topology) -> State:
    """The cloth at rest where ``topology.initial_positions`` puts it (the grid flat, centred over the
    origin at ``initial_height``, tilted about x; a mesh file as placed by ``place_mesh``), holding
    ``initial_saturation`` of its capacity of water."""
    pos = initial_positions(scene, topo)
    water = scene.initial_saturation * scene.absorption_capacity * scene.areal_density * topo.area
    return State(time=0.0, pos=pos, vel=np.zeros((3, topo.n)), water=water)
