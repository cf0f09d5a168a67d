"""The explicit step in plain, vectorised NumPy: the speed baseline of ``bench/step_speed.py`` and an
independent check of the compiled core (it uses index lists and ``Topology.triangles`` where the
kernels use offsets and grid rows).  Not used by the simulator.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth._core import TENSION_ROUNDING
from wetcloth.model import GRAVITY, Model
from wetcloth.state import State


def _contact_fraction(z0, z1, v0, v1, h, surface):
    """Fraction of a step each particle spends below ``surface``: its height is the cubic Hermite
    curve through the step's end heights and speeds, whose crossing is found by Newton's method
    from the straight line's (3 iterations, clamped to the step)."""
    below0, below1 = z0 < surface, z1 < surface
    a, b = z0 - surface, z1 - surface
    p0, p1 = h * v0, h * v1
    crossing = np.clip(np.divide(a, a - b, out=np.zeros_like(a), where=below0 != below1), 0.0, 1.0)
    for _ in range(3):
        t = crossing
        value = (2 * t**3 - 3 * t**2 + 1) * a + (t**3 - 2 * t**2 + t) * p0 + (3 * t**2 - 2 * t**3) * b + (t**3 - t**2) * p1
        slope = (6 * t**2 - 6 * t) * a + (3 * t**2 - 4 * t + 1) * p0 + (6 * t - 6 * t**2) * b + (3 * t**2 - 2 * t) * p1
        step = np.divide(value, slope, out=np.zeros_like(value), where=slope != 0)
        crossing = np.clip(t - step, 0.0, 1.0)
    return np.where(below0 & below1, 1.0, np.where(below0 == below1, 0.0, np.where(below1, 1.0 - crossing, crossing)))


def _corner_weights(rest_xy: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(m, 3) share of each triangle's force per corner, the weights of the particles' areas
    (docs/model.md section 4): 1/2 at the right angle of the rest sheet, 1/4 at the other two."""
    corners = [rest_xy[:, triangles[:, k]] for k in range(3)]
    weights = np.empty(triangles.shape, dtype=float)
    for k in range(3):
        e1 = corners[(k + 1) % 3] - corners[k]
        e2 = corners[(k + 2) % 3] - corners[k]
        right = np.abs((e1 * e2).sum(axis=0)) < 1e-9 * np.sqrt((e1 * e1).sum(axis=0) * (e2 * e2).sum(axis=0))
        weights[:, k] = np.where(right, 0.5, 0.25)
    return weights


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
        self.corner_weights = _corner_weights(topo.rest_xy, topo.triangles)

    def _scatter(self, index: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Sum (3, m) values into (3, n) at ``index``."""
        n = self.model.topology.n
        return np.stack([np.bincount(index, weights=values[c], minlength=n) for c in range(3)])

    def forces(self, pos: np.ndarray, vel: np.ndarray, water: np.ndarray) -> np.ndarray:
        model, sc = self.model, self.model.scene
        d = pos[:, self.i] - pos[:, self.j]
        length = np.sqrt((d * d).sum(axis=0))
        stretch = length - self.rest
        # Tension-only: no pull when compressed, the rounded onset below a strain of TENSION_ROUNDING.
        onset = TENSION_ROUNDING * self.rest
        rounded = np.clip(stretch, 0.0, onset) ** 2 / onset * (2.0 - np.clip(stretch, 0.0, onset) / onset)
        stretch = np.where(self.tension_only, np.where(stretch >= onset, stretch, rounded), stretch)
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
        if sc.air_density > 0:
            force += self._face_drag(pos, vel, s, air=True)
        return force

    def _face_drag(self, pos, vel, s, air=False):
        """The water's face drag on each triangle's submerged part (still water: no current), or with
        ``air`` the air's on the rest, relative to the wind, without the linear term (section 4.4): each
        corner takes its share of the triangle's drag at its own velocity."""
        sc = self.model.scene
        tri = self.model.topology.triangles
        a, b, c = (pos[:, tri[:, k]] for k in range(3))
        cross = np.cross(b - a, c - a, axis=0)
        twice_area = np.sqrt((cross * cross).sum(axis=0))
        normal = cross / twice_area
        share = 1.0 - s[tri].mean(axis=1) if air else s[tri].mean(axis=1)
        wet_area = 0.5 * twice_area * share
        flow = np.array([sc.wind_x, sc.wind_y, sc.wind_z]) if air else np.zeros(3)
        q = 0.5 * (sc.air_density if air else sc.water_density) * wet_area
        total = 0.0
        for k in range(3):
            u = flow[:, None] - vel[:, tri[:, k]]
            un = (u * normal).sum(axis=0)
            ut = u - un * normal
            ut_norm = np.sqrt((ut * ut).sum(axis=0))
            f = q * (sc.drag_normal * np.abs(un) * un * normal + sc.drag_tangential * ut_norm * ut)
            if not air:
                f += sc.drag_linear * wet_area * u
            total = total + self._scatter(tri[:, k], f * self.corner_weights[:, k])
        return total

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
            surface = sc.water_level + (0.5 * sc.thickness if sc.buoyancy_model == "smooth" else 0.0)
            touching = _contact_fraction(state.pos[2], pos[2], state.vel[2], vel[2], h, surface)
            full = sc.absorption_capacity * model.dry_mass
            decay = np.exp(-sc.absorption_rate * touching * h / sc.absorption_capacity)
            absorbing = (touching > 0) & (full - water > 1e-12 * full)
            new_water = np.where(absorbing, full - (full - water) * decay, water)
            vel *= (model.dry_mass + water) / (model.dry_mass + new_water)
            water = new_water
        return State(state.time + h, pos, vel, water)
