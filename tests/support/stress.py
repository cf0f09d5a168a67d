"""Stability checks shared by the stress benchmark and the stress tests.

A run is *stable* when it finishes without the blow-up guard firing and its kinetic energy never
exceeds what the scene could possibly release: the fall of every particle from its start to the
floor, plus buoyancy lifting every particle's volume from the floor to the highest surface.  The
model is passive (springs, drag, absorption and the floor only store or remove energy), so a run
above that bound has gained energy from the integrator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wetcloth.errors import BlowUpError
from wetcloth.model import GRAVITY
from wetcloth.scene import Scene
from wetcloth.simulation import Simulation


@dataclass
class StressResult:
    stable: bool
    reason: str  # "" when stable
    steps: int
    largest_kinetic_energy: float  # J
    energy_bound: float  # J
    wet_mass_decreased: bool


def energy_bound(sim: Simulation, highest_water_level: float) -> float:
    """Most kinetic energy (J) a passive cloth could gain in this scene."""
    sc, model = sim.scene, sim.model
    floor = model.floor_z
    # Absorbed water arrives at rest, so the heaviest the cloth can be is dry mass plus capacity.
    heaviest = model.dry_mass * (1.0 + sc.absorption_capacity)
    fall = float((heaviest * GRAVITY * np.maximum(sim.state.pos[2] - floor, 0.0)).sum())
    lift = float((sc.water_density * GRAVITY * model.volume).sum() * max(highest_water_level + sc.thickness - floor, 0.0))
    return fall + lift


def kinetic_energy(sim: Simulation) -> float:
    return float(0.5 * (sim.model.mass(sim.state.water) * (sim.state.vel**2).sum(axis=0)).sum())


def stress_run(scene: Scene, duration: float, water_levels: dict[float, float] | None = None,
               samples: int = 50) -> StressResult:
    """Run ``scene`` for ``duration`` s, jumping the water level at the given times (s -> m)."""
    sim = Simulation(scene)
    levels = dict(sorted((water_levels or {}).items()))
    bound = energy_bound(sim, max([scene.water_level, *levels.values()]))
    largest, previous_mass, decreased = 0.0, sim.outputs()["wet_mass"], False
    times = np.linspace(0.0, duration, samples + 1)[1:]
    try:
        for t in times:
            for when in [w for w in levels if w <= t]:
                sim.set_inputs(water_level=levels.pop(when))
            sim.advance(t - sim.time)
            largest = max(largest, kinetic_energy(sim))
            mass = sim.outputs()["wet_mass"]
            decreased |= mass < previous_mass
            previous_mass = mass
            if largest > bound:
                return StressResult(False, f"kinetic energy {largest:.3g} J above the bound {bound:.3g} J",
                                    sim.steps, largest, bound, decreased)
    except BlowUpError as exc:
        return StressResult(False, str(exc), sim.steps, largest, bound, decreased)
    return StressResult(True, "", sim.steps, largest, bound, decreased)
