"""The model: a scene's constants and scratch buffers, and the total force on every particle.

Each force family is one kernel call, skipped when the scene does not need it: no spring
kernel without springs, no water kernels while no particle touches the water.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth.kernels.springs import spring_forces, spring_forces_and_blocks
from wetcloth.kernels.water import buoyancy, face_drag, face_drag_and_blocks, stokes_drag, submerged_fractions
from wetcloth.scene import Scene
from wetcloth.topology import Topology, build_topology

GRAVITY = 9.81  # m/s2, acting along -z


class Model:
    """Scene, topology and per-particle constants (dry mass kg, volume m3, Stokes coefficient N s/m)."""

    def __init__(self, scene: Scene, topology: Topology | None = None, skip_idle_work: bool = True):
        self.topology = topo = topology if topology is not None else build_topology(scene)
        self.skip_idle_work = skip_idle_work  # False: run the water kernels on dry cloth too (benchmarks)
        n = topo.n
        self.free = (~topo.pinned).astype(np.float64)  # 1 for moving particles, 0 for pinned
        self.s = np.zeros(n)  # submerged fraction of each particle, from the last force evaluation
        self.saturation = np.zeros(n)  # water / capacity, used by wetness-dependent stiffness
        self.force = np.zeros((3, n))
        self._buf = np.zeros((4, n))
        self._cells = np.zeros((2, 9, n + topo.nx + 1))
        families = len(topo.spring_offset)
        self.direction = np.zeros((families, 3, n))
        self.along = np.zeros((families, n))
        self.across = np.zeros((families, n))
        self.blocks = np.zeros((6, n))
        self.diagonal_blocks = np.zeros((6, n))
        self.rhs = np.zeros((3, n))
        self.scene = scene

    @property
    def scene(self) -> Scene:
        return self._scene

    @scene.setter
    def scene(self, scene: Scene) -> None:
        """Take new parameters; those fixing the topology must not change."""
        area = self.topology.area
        self._scene = scene
        self.dry_mass = scene.areal_density * area
        self.volume = scene.thickness * area
        self.stokes_coefficient = 6.0 * math.pi * np.sqrt(area / math.pi) * scene.water_viscosity
        self.floor_z = scene.floor_level + 0.5 * scene.thickness
        self.capacity = scene.absorption_capacity * self.dry_mass  # kg of water each particle holds at most
        self._set_wicking(scene)

    def _set_wicking(self, scene: Scene) -> None:
        """Conductances (kg/s per unit saturation difference) of the axis neighbours' links, and the
        sub-steps (s) that keep wicking's explicit update within the maximum principle."""
        topo = self.topology
        structural = [f for f, name in enumerate(topo.spring_family_names) if name.startswith("structural")]
        self.wick_offsets = topo.spring_offset[structural]
        # Finite volumes: flux = D * (water per area at saturation) * d(sat)/dl * strip width.
        self.wick_conductance = (scene.wicking_rate * scene.absorption_capacity * scene.areal_density
                                 * topo.spring_shape[structural])
        links = np.zeros(topo.n)
        for offset, shape in zip(self.wick_offsets, topo.spring_shape[structural]):
            links[: topo.n - offset] += shape[: topo.n - offset]
            links[offset:] += shape[: topo.n - offset]
        # new sat_i = sat_i + dt sum_j g_ij (sat_j - sat_i) / Q_i is a weighted mean while dt <= Q_i / sum g_ij
        with np.errstate(divide="ignore"):
            self.wick_step_limit = float(np.min(topo.area / (scene.wicking_rate * links)))

    def mass(self, water: np.ndarray) -> np.ndarray:
        """Particle masses (kg): dry fabric plus absorbed water."""
        return self.dry_mass + water

    def touches_water(self, z: np.ndarray) -> float:
        """Fill ``self.s`` from heights ``z``; return the largest submerged fraction."""
        sc = self.scene
        return submerged_fractions(z, sc.water_level, sc.thickness, sc.buoyancy_model == "smooth", self.s)

    def wetness_active(self) -> bool:
        """Whether wetness-dependent stiffness needs the saturation this step."""
        return self.scene.wet_stiffness_factor != 0.0 and self.scene.absorption_capacity > 0.0

    def _update_saturation(self, water: np.ndarray) -> None:
        if self.wetness_active():
            np.divide(water, self.capacity, out=self.saturation)

    def _wet_factor(self) -> float:
        return self.scene.wet_stiffness_factor if self.wetness_active() else 0.0

    def _springs(self):
        t = self.topology
        return t.spring_offset, t.spring_rest, t.spring_tension_only, t.spring_stiffness, t.spring_damping

    def forces(self, pos: np.ndarray, vel: np.ndarray, water: np.ndarray) -> np.ndarray:
        """Total force (N, (3, n)) on every particle; also leaves the submerged fractions in ``self.s``."""
        sc = self.scene
        force = self.force
        force[:2] = 0.0
        np.multiply(self.mass(water), -GRAVITY, out=force[2])
        if self.topology.spring_offset.size:
            self._update_saturation(water)
            spring_forces(*self._springs(), sc.damping_model == "projected", self._wet_factor(), self.saturation, pos,
                          vel, force, self._buf)
        if self.touches_water(pos[2]) > 0.0 or not self.skip_idle_work:
            self._water_forces(pos, vel, force, h=None)
        return force

    def forces_and_blocks(self, pos: np.ndarray, vel: np.ndarray, water: np.ndarray, h: float) -> np.ndarray:
        """Forces as ``forces``, plus the pieces of the backward-Euler system for step ``h`` (s).

        Leaves in ``self.rhs`` the term ``h^2 K v``, in ``self.blocks`` the per-particle
        symmetric blocks (drag, buoyancy) of ``-h C - h^2 K``, in ``self.diagonal_blocks`` the springs'
        part of the system's 3x3 diagonal blocks, and per-spring blocks in ``self.direction``, ``self.along``, ``self.across``.
        """
        sc = self.scene
        force = self.force
        force[:2] = 0.0
        np.multiply(self.mass(water), -GRAVITY, out=force[2])
        self.rhs[...] = 0.0
        self.diagonal_blocks[...] = 0.0
        self.blocks[...] = 0.0
        if self.topology.spring_offset.size:
            self._update_saturation(water)
            spring_forces_and_blocks(
                *self._springs(), sc.damping_model == "projected", self._wet_factor(), self.saturation, pos, vel, h,
                force, self.rhs, self.diagonal_blocks, self.direction, self.along, self.across, self._buf,
            )
        if self.touches_water(pos[2]) > 0.0 or not self.skip_idle_work:
            self._water_forces(pos, vel, force, h=h)
        return force

    def _water_forces(self, pos, vel, force, h):
        sc = self.scene
        s = self.s
        buoyancy(s, self.volume, sc.water_density, GRAVITY, force)
        if sc.drag_model == "stokes":
            stokes_drag(s, self.stokes_coefficient, sc.current_x, sc.current_y, vel, force)
            if h is not None:
                self.blocks[:3] += h * self.stokes_coefficient * s
        elif h is None:
            face_drag(
                self.topology.nx, self.topology.ny, pos, vel, s, sc.water_density, sc.drag_normal,
                sc.drag_tangential, sc.drag_linear, sc.current_x, sc.current_y, force, self._cells, self.skip_idle_work,
            )
        else:
            face_drag_and_blocks(
                self.topology.nx, self.topology.ny, pos, vel, s, sc.water_density, sc.drag_normal,
                sc.drag_tangential, sc.drag_linear, sc.current_x, sc.current_y, h, force, self.blocks, self._cells,
                self.skip_idle_work,
            )
        if h is not None and sc.buoyancy_model == "smooth":
            # dF_z/dz = -rho g V / thickness inside the surface slab (0 < s < 1).
            partial = (s > 0.0) & (s < 1.0)
            stiffness = np.where(partial, sc.water_density * GRAVITY * self.volume / sc.thickness, 0.0)
            self.blocks[2] += h * h * stiffness
            self.rhs[2] -= h * h * stiffness * vel[2]
