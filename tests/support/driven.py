"""The energy check of driven cloth at frame steps, recomputed outside the core: how much work the wind, the
current and the grip can have done on the cloth over a backward Euler step (docs/model.md section 7), also as seen
from a frame moving with a keyed collider, and whether a keyed collider moved over a span of time.  Shared by
tests/test_driven_energy.py and bench/driven_energy.py."""

from __future__ import annotations

import numpy as np

import wetcloth
from wetcloth import _core
from wetcloth.energy import total_energy
from wetcloth.model import GRAVITY


class DriveBound:
    """The most work (J) the wind, the current and the grip can have done on a Simulation's cloth over a backward
    Euler step of h s that ended at its state.  The drags are told apart from the other forces by models of the
    same scene without them: the air's drag F_a (all forces less those without air) is dotted with the wind and
    the water's F_w (less those without the water's drag too) with the current, each at least the drag's power as
    it opposes the motion relative to its fluid.  Over the pinned particles, the force R that held them on the
    grip's path, R = m (v+ - v) / h - F, is dotted with v+.

    Seen from a frame moving at a uniform velocity `frame` (m/s; the forces are the same there, the velocities
    less `frame`): the fluids flow at wind - frame and current - frame, the pinned particles move at v+ - frame,
    and a frame rising at frame_z adds h frame_z g M (M the cloth's mass: with the potential energy taken at the
    world's positions, gravity does that work on a cloth at rest in the frame; the cloth out of the water, whose
    surface would move in it).  A collider moving with that frame is still in it, where contact only takes
    energy (energy_in_frame)."""

    def __init__(self, scene: wetcloth.Scene):
        self.still_air = wetcloth.Simulation(scene.replace(air_density=0.0)).model
        self.still_water = wetcloth.Simulation(scene.replace(air_density=0.0, drag_normal=0.0, drag_tangential=0.0,
                                                             drag_linear=0.0, water_viscosity=0.0)).model
        self.wind = np.array([scene.wind_x, scene.wind_y, scene.wind_z])[:, None]
        self.current = np.array([scene.current_x, scene.current_y, 0.0])[:, None]

    def __call__(self, sim: wetcloth.Simulation, start_vel: np.ndarray, h: float,
                 frame: np.ndarray = np.zeros(3)) -> float:
        state = sim.state
        assert frame[2] == 0.0 or sim.model.update_submerged(state.pos[2]) == 0.0, "the water's surface would move"
        force = sim.model.forces(state.pos, state.vel, state.water).copy()
        without_air = self.still_air.forces(state.pos, state.vel, state.water).copy()
        without_drag = self.still_water.forces(state.pos, state.vel, state.water).copy()
        pinned = np.asarray(sim.model.cloth.free) == 0
        mass = np.asarray(sim.model.cloth.dry_mass) + state.water
        held = mass * (state.vel - start_vel) / h - force
        u = np.asarray(frame, dtype=float)[:, None]
        return h * float(((force - without_air) * (self.wind - u)).sum()
                         + ((without_air - without_drag) * (self.current - u)).sum()
                         + (held[:, pinned] * (state.vel - u)[:, pinned]).sum()
                         + frame[2] * GRAVITY * mass.sum())


def energy_noise(sim: wetcloth.Simulation, frame: np.ndarray) -> float:
    """The round-off (J) the core's energy check allows a Simulation's cloth at its state, seen from a frame moving
    at `frame` (m/s): ENERGY_NOISE times the sum of the energy's terms' magnitudes (kinetic, each particle's
    gravitational m g |z|, the springs' elastic, buoyancy's: energy.cpp's `magnitude`)."""
    state = sim.state
    mass = np.asarray(sim.model.cloth.dry_mass) + state.water
    gravity = GRAVITY * mass * state.pos[2]
    return _core.ENERGY_NOISE * (energy_in_frame(sim, frame) - float(gravity.sum()) + float(np.abs(gravity).sum()))


def energy_in_frame(sim: wetcloth.Simulation, frame: np.ndarray) -> float:
    """The cloth's energy (J, wetcloth.energy.total_energy's: mechanical and buoyancy's) seen from a frame moving at
    the uniform horizontal velocity `frame` (m/s): its kinetic energy that of the velocities less `frame`."""
    state = sim.state
    mass = np.asarray(sim.model.cloth.dry_mass) + state.water
    u = np.asarray(frame, dtype=float)[:, None]
    return total_energy(sim) + 0.5 * float((mass * ((state.vel - u) ** 2 - state.vel ** 2)).sum())


def collider_shift(scene: wetcloth.Scene, collider: int, t: float) -> np.ndarray:
    """Keyed collider `collider`'s (numbered from 1, as its keys) displacement (m) and rotation vector (rad) at t
    (s): linear between its keys, from zero at t = 0, the last key's after it ((6,); zeros without keys)."""
    keys = sorted((key for key in scene.collider_keys if key.collider == collider), key=lambda key: key.time)
    times = [0.0] + [key.time for key in keys]
    values = np.array([[0.0] * 6] + [[key.x, key.y, key.z, key.rx, key.ry, key.rz] for key in keys])
    return np.array([np.interp(t, times, values[:, c]) for c in range(6)])


def collider_moves(scene: wetcloth.Scene, start: float, end: float) -> bool:
    """Whether a keyed collider of the scene moves between start and end (s): its displacement or rotation
    (collider_shift) differs anywhere in the span."""
    for collider in {key.collider for key in scene.collider_keys}:
        inside = [start, end] + [key.time for key in scene.collider_keys if start < key.time < end]
        shifts = np.array([collider_shift(scene, collider, t) for t in inside])
        if np.ptp(shifts, axis=0).max() > 0.0:
            return True
    return False


def ball_reaches(scene: wetcloth.Scene, sim: wetcloth.Simulation, t: float, h: float) -> bool:
    """Whether keyed collider 1 (a sphere), moving from t (s) over a step of h s, may reach the cloth of `sim` (at
    t) within it, by the core's rule (colliders_near in collider_motion.cpp): some particle lies within thickness
    + h (its surface's speed + the fastest particle's) + g h^2 of its surface."""
    ball = scene.colliders[0]
    assert ball.shape == "sphere"
    velocity = (collider_shift(scene, 1, t + h) - collider_shift(scene, 1, t))[:3] / h
    centre = np.array([ball.x, ball.y, ball.z]) + collider_shift(scene, 1, t)[:3]
    speed = float(np.linalg.norm(sim.state.vel, axis=0).max())
    reach = scene.thickness + h * (float(np.linalg.norm(velocity)) + speed) + GRAVITY * h * h
    return bool((np.linalg.norm(sim.state.pos - centre[:, None], axis=0) - ball.radius <= reach).any())


def ball_velocity(scene: wetcloth.Scene, sim: wetcloth.Simulation, start: float, h: float) -> np.ndarray:
    """The frame the core weighs a step of h s from start (s) in: the velocity (m/s) of the scene's one keyed
    collider (numbered 1, a sphere, not turning) over it where the collider may reach the cloth of `sim` within it
    (ball_reaches), else zero (and without keys).  (Where a key changes that velocity within the span, its mean: the
    core then takes the span in parts.)"""
    if not scene.collider_keys or not ball_reaches(scene, sim, start, h):
        return np.zeros(3)
    assert {key.collider for key in scene.collider_keys} == {1}
    shift = (collider_shift(scene, 1, start + h) - collider_shift(scene, 1, start)) / h
    assert not shift[3:].any()
    return shift[:3]
