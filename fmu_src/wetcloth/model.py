"""The model: scene, topology and per-particle constants, packed for the compiled kernels.

The forces themselves are the compiled core's (``fmu_src/core/src/assembly.cpp``, one call per
force family); this class owns their arrays and gives Python callers (tests, benchmarks) the same
evaluations the step loop makes.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth import _core
from wetcloth._core import GRAVITY
from wetcloth.bundles import Cloth, Physics, make_work
from wetcloth.collider_meshes import meshes_of
from wetcloth.scene import Scene, collider_key_rows, grip_key_rows
from wetcloth.state import initial_state
from wetcloth.topology import STRETCH, Topology, build_topology, cloth_order, corner_shares

__all__ = ["GRAVITY", "Model"]


class Model:
    """Scene, topology and per-particle constants (dry mass kg, volume m3, Stokes coefficient N s/m)."""

    def __init__(self, scene: Scene, topology: Topology | None = None, skip_idle_work: bool = True):
        self.topology = topo = topology if topology is not None else build_topology(scene)
        self.skip_idle_work = skip_idle_work  # False: run the water kernels on dry cloth too (benchmarks)
        self.free = (~topo.pinned).astype(np.float64)  # 1 for moving particles, 0 for pinned
        self.grid_x, self.grid_y = (0, 0) if topo.listed else (topo.nx, topo.ny)
        if topo.listed:  # a mesh's face drag goes over its triangles, in the core's order, shared among their corners
            self.cloth_order = cloth_order(topo.triangles)
            self.corner_shares = corner_shares(topo.rest_pos, topo.triangles)[self.cloth_order]
        else:  # a grid's goes over its rows: the core takes no triangles from it (nor does the native unit's grid)
            self.cloth_order = np.zeros(0, dtype=np.int64)
            self.corner_shares = np.zeros((0, 3))
        self.work = make_work(topo.n, len(topo.spring_offset), self.grid_x, len(topo.pair_rest))
        # Where the grip's zero displacement holds the particles (m, (3, n)): their start positions (fixed
        # parameters only); empty when nothing is pinned, so that the grip has nothing to move.
        self.grip_origin = initial_state(scene, topo).pos if topo.pinned.any() else np.empty((3, 0))
        self.scene = scene

    @property
    def scene(self) -> Scene:
        return self._scene

    @scene.setter
    def scene(self, scene: Scene) -> None:
        """Take new parameters; those fixing the topology must not change."""
        topo = self.topology
        area = topo.area
        self._scene = scene
        self.dry_mass = scene.areal_density * area
        self.volume = scene.thickness * area
        self.stokes_coefficient = 6.0 * math.pi * np.sqrt(area / math.pi) * scene.water_viscosity
        self.floor_z = scene.floor_level + 0.5 * scene.thickness
        self.capacity = scene.absorption_capacity * self.dry_mass  # kg of water each particle holds at most
        self._set_wicking(scene)
        self.cloth = Cloth(
            grid_x=self.grid_x, grid_y=self.grid_y, offsets=topo.spring_offset, rest=topo.spring_rest,
            tension_only=topo.spring_tension_only, stiffness=topo.spring_stiffness, damping=topo.spring_damping,
            free=self.free, dry_mass=self.dry_mass, volume=self.volume, stokes_coefficient=self.stokes_coefficient,
            capacity=self.capacity, wick_offsets=self.wick_offsets, wick_conductance=self.wick_conductance,
            pairs=np.ascontiguousarray(topo.pairs, dtype=np.int64), pair_rest=topo.pair_rest,
            pair_stiffness=topo.pair_stiffness, pair_damping=topo.pair_damping,
            pair_tension_count=topo.pair_tension_count, pair_buckling_count=topo.pair_buckling_count,
            pair_hinge_count=topo.hinge_count,
            wick_pairs=self.wick_pairs, wick_pair_conductance=self.wick_pair_conductance,
            triangles=np.ascontiguousarray(topo.triangles[self.cloth_order], dtype=np.int64),
            corner_shares=self.corner_shares,
        )
        colliders, meshes = meshes_of(scene.colliders)
        wet = scene.wet_stiffness_factor != 0.0 and scene.absorption_capacity > 0.0
        self.physics = Physics(
            projected=scene.damping_model == "projected", wet_factor=scene.wet_stiffness_factor if wet else 0.0,
            water_level=scene.water_level, water_density=scene.water_density, thickness=scene.thickness,
            smooth=scene.buoyancy_model == "smooth", stokes=scene.drag_model == "stokes",
            drag_normal=scene.drag_normal, drag_tangential=scene.drag_tangential, drag_linear=scene.drag_linear,
            current_x=scene.current_x, current_y=scene.current_y, air_density=scene.air_density,
            wind_x=scene.wind_x, wind_y=scene.wind_y, wind_z=scene.wind_z, floor_z=self.floor_z,
            floor_friction=scene.floor_friction, absorption_capacity=scene.absorption_capacity,
            absorption_rate=scene.absorption_rate, drying_rate=scene.drying_rate, wicking_rate=scene.wicking_rate,
            wick_step_limit=self.wick_step_limit, skip_idle=self.skip_idle_work,
            colliders=colliders, meshes=meshes,
            grip_x=scene.grip_x, grip_y=scene.grip_y, grip_z=scene.grip_z,
            grip_keys=grip_key_rows(scene.grip_keys),
            grip_origin=self.grip_origin,
            collider_keys=collider_key_rows(scene.collider_keys),
            collider_motion=np.zeros((len(scene.colliders) if scene.collider_keys else 0, _core.MOTION_COLUMNS)),
        )

    def _set_wicking(self, scene: Scene) -> None:
        """Conductances (kg/s per unit saturation difference) of the links between neighbours (a grid's
        axis neighbours, a mesh's edges), and the sub-steps (s) that keep wicking's explicit update
        within the maximum principle."""
        topo = self.topology
        structural = [f for f, name in enumerate(topo.spring_family_names) if name.startswith("structural")]
        edges = topo.pair_kind == STRETCH
        self.wick_offsets = topo.spring_offset[structural]
        self.wick_pairs = np.ascontiguousarray(topo.pairs[:, edges])
        # Finite volumes: flux = D * (water per area at saturation) * d(sat)/dl * strip width.
        per_shape = scene.wicking_rate * scene.absorption_capacity * scene.areal_density
        self.wick_conductance = per_shape * topo.spring_shape[structural]
        self.wick_pair_conductance = per_shape * topo.pair_shape[edges]
        links = (topo.per_particle_sum(topo.spring_shape[structural], self.wick_offsets)
                 + topo.per_particle_pair_sum(topo.pair_shape, kinds=(STRETCH,)))
        # new sat_i = sat_i + dt sum_j g_ij (sat_j - sat_i) / Q_i is a weighted mean while dt <= Q_i / sum g_ij
        with np.errstate(divide="ignore"):
            self.wick_step_limit = float(np.min(topo.area / (scene.wicking_rate * links)))

    # ----------------------------------------------------------------- evaluations for Python callers
    def mass(self, water: np.ndarray) -> np.ndarray:
        """Particle masses (kg): dry fabric plus absorbed water."""
        return self.dry_mass + water

    @property
    def submerged(self) -> np.ndarray:
        """Submerged fraction (0..1) of each particle, from the last force evaluation."""
        return self.work.submerged

    def update_submerged(self, z: np.ndarray) -> float:
        """Set ``submerged`` from particle heights ``z`` (m; a read-only view too, as ``Simulation.state``'s);
        return its largest value."""
        return _core.submerged(self.physics, np.require(z, np.float64, ("C", "W")), self.work.submerged)

    def forces(self, pos: np.ndarray, vel: np.ndarray, water: np.ndarray) -> np.ndarray:
        """Total force (N, (3, n)) on every particle; also sets ``submerged``."""
        _core.forces(self.cloth, self.physics, self.work, pos, vel, water)
        return self.work.force

    def forces_and_blocks(self, pos: np.ndarray, vel: np.ndarray, water: np.ndarray, h: float) -> np.ndarray:
        """Forces as ``forces``, plus the pieces of the system matrix ``M - h dF/dv - h^2 dF/dx`` for step
        ``h`` (s) in ``work`` (see ``fmu_src/core/include/wetcloth/assembly.hpp``)."""
        _core.forces_and_blocks(self.cloth, self.physics, self.work, pos, vel, water, h)
        return self.work.force
