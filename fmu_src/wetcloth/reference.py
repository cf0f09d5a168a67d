"""The explicit step in plain, vectorised NumPy: the speed baseline of ``bench/step_speed.py`` and an
independent check of the numba kernels (it uses index lists and ``Topology.triangles`` where the
kernels use offsets and grid rows).  Not used by the simulator.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth.model import GRAVITY, Model
from wetcloth.state import State


class NumpyReference:
    """Forces and one explicit-Euler step of a model, in NumPy (SI units)."""

    def __init__(self, model: Model):
        self.model = model
        topo = model.topology
        n = topo.n
        first, second, rest, stiffness, damping, tension_only = [], [], [], [], [], []
        for f, off in enumerate(topo.spring_offset):
            present = np.flatnonzero(topo.spring_stiffness[f, : n - off] > 0)
            first.append(present)
            second.append(present + off)
            rest.append(np.full(present.size, topo.spring_rest[f]))
            stiffness.append(topo.spring_stiffness[f, present])
            damping.append(topo.spring_damping[f, present])
            tension_only.append(np.full(present.size, topo.spring_tension_only[f]))
        self.i = np.concatenate(first)
        self.j = np.concatenate(second)
        self.rest = np.concatenate(rest)
        self.k = np.concatenate(stiffness)
        self.c = np.concatenate(damping)
        self.tension_only = np.concatenate(tension_only)

    def _scatter(self, index: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Sum (3, m) values into (3, n) at ``index``."""
        n = self.model.topology.n
        return np.stack([np.bincount(index, weights=values[c], minlength=n) for c in range(3)])

    def forces(self, pos: np.ndarray, vel: np.ndarray, water: np.ndarray) -> np.ndarray:
        model, sc = self.model, self.model.scene
        d = pos[:, self.i] - pos[:, self.j]
        length = np.sqrt((d * d).sum(axis=0))
        stretch = length - self.rest
        stretch = np.where(self.tension_only, np.maximum(stretch, 0.0), stretch)
        dv = vel[:, self.i] - vel[:, self.j]
        f = -(self.k * stretch / length) * d
        if sc.damping_model == "projected":
            f -= (self.c * (dv * d).sum(axis=0) / length**2) * d
        else:
            f -= self.c * dv
        force = self._scatter(self.i, f) - self._scatter(self.j, f)
        force[2] -= model.mass(water) * GRAVITY
        if sc.buoyancy_model == "smooth":
            s = np.clip((sc.water_level - pos[2]) / sc.thickness + 0.5, 0.0, 1.0)
        else:
            s = (pos[2] < sc.water_level).astype(float)
        force[2] += sc.water_density * GRAVITY * model.volume * s
        if sc.drag_model == "stokes":
            force -= model.stokes_coefficient * s * vel
        else:
            force += self._face_drag(pos, vel, s)
        return force

    def _face_drag(self, pos, vel, s):
        sc = self.model.scene
        tri = self.model.topology.triangles
        a, b, c = (pos[:, tri[:, k]] for k in range(3))
        cross = np.cross(b - a, c - a, axis=0)
        twice_area = np.sqrt((cross * cross).sum(axis=0))
        normal = cross / twice_area
        wet_area = 0.5 * twice_area * s[tri].mean(axis=1)
        u = -vel[:, tri].mean(axis=2)
        un = (u * normal).sum(axis=0)
        ut = u - un * normal
        ut_norm = np.sqrt((ut * ut).sum(axis=0))
        q = 0.5 * sc.water_density * wet_area
        f = q * (sc.drag_normal * np.abs(un) * un * normal + sc.drag_tangential * ut_norm * ut)
        f += sc.drag_linear * wet_area * u
        return sum(self._scatter(tri[:, k], f / 3.0) for k in range(3))

    def explicit_step(self, state: State, h: float) -> State:
        """One explicit-Euler step with floor contact and absorption, as ``Simulation`` takes it."""
        model, sc = self.model, self.model.scene
        force = self.forces(state.pos, state.vel, state.water)
        accel = force / model.mass(state.water) * model.free
        pos = state.pos + h * state.vel
        vel = (state.vel + h * accel) * model.free
        below = pos[2] < model.floor_z
        pos[2] = np.where(below, model.floor_z, pos[2])
        dvn = np.where(below & (vel[2] < 0), -vel[2], 0.0)
        vel[2] = np.where(below, np.maximum(vel[2], 0.0), vel[2])
        slide = np.hypot(vel[0], vel[1])
        keep = np.where(below & (slide > 0), np.maximum(0.0, 1 - sc.floor_friction * dvn / np.maximum(slide, 1e-300)), 1.0)
        vel[:2] *= keep
        water = state.water.copy()
        if sc.absorption_capacity > 0 and sc.absorption_rate > 0:
            s = np.clip((sc.water_level - pos[2]) / sc.thickness + 0.5, 0.0, 1.0)
            full = sc.absorption_capacity * model.dry_mass
            decay = math.exp(-sc.absorption_rate * h / sc.absorption_capacity)
            absorbing = (s > 0) & (full - water > 1e-12 * full)
            new_water = np.where(absorbing, full - (full - water) * decay, water)
            vel *= (model.dry_mass + water) / (model.dry_mass + new_water)
            water = new_water
        return State(state.time + h, pos, vel, water)
