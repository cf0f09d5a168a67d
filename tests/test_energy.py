"""The cloth's mechanical energy (wetcloth.energy, the core's energy.cpp) is the potential of its forces: at rest
velocities, in still air and out of the water, minus its gradient is the force of the springs and gravity on
every particle, for each spring law (tension-only, both ways, buckling, hinges' terms)."""

from __future__ import annotations

import numpy as np
import pytest

import wetcloth
from wetcloth.energy import mechanical_energy

#: Central differences of the energy over a displacement of STEP (m): their error, E''' STEP^2 / 6 with E''' at
#: most about k / w (the rounded onset's w = TENSION_ROUNDING l, some micrometres) times the ~10 springs of a
#: particle, stays far below the 1e-6 N allowed, as does the round-off of differencing a few joules
#: (1e-16 J / STEP = 1e-8 N).
STEP = 1e-8


def energy_gradient(sim: wetcloth.Simulation, particles: np.ndarray) -> np.ndarray:
    """dE/dx (N, (3, len(particles))) of the cloth's energy by central differences at its state."""
    gradient = np.empty((3, len(particles)))
    pos = sim.state.pos
    for column, i in enumerate(particles):
        for c in range(3):
            start = pos[c, i]
            pos[c, i] = start + STEP
            up = mechanical_energy(sim)
            pos[c, i] = start - STEP
            down = mechanical_energy(sim)
            pos[c, i] = start
            gradient[c, column] = (up - down) / (2 * STEP)
    return gradient


HANGING = dict(initial_tilt=0.0, initial_height=2.0, water_level=-10.0, floor_level=-20.0, air_density=0.0)


@pytest.mark.parametrize("scene", [
    # the grid's families: tension-only and both-ways springs
    ("towel", dict(nx=9, ny=11, pinned_edge="y_max", **HANGING)),
    # its quads as a mesh: listed tension-only springs and hinges' terms
    ("towel", dict(nx=9, ny=11, pinned_edge="y_max", bend_rigidity=6e-5, **HANGING)),
    # a triangle mesh (the round tablecloth falling onto its table): buckling springs
    ("tablecloth", dict(air_density=0.0)),
    # wet cloths whose springs stiffen with their ends' saturation: a grid, and its quads as a hinged mesh
    ("towel", dict(nx=9, ny=11, pinned_edge="y_max", wet_stiffness_factor=2.0, **HANGING)),
    ("towel", dict(nx=9, ny=11, pinned_edge="y_max", bend_rigidity=6e-5, wet_stiffness_factor=-0.5, **HANGING)),
], ids=["grid", "hinged", "triangles", "wet grid", "wet hinged"])
def test_the_energy_is_the_potential_of_the_springs_and_gravity(scene):
    """A cloth after 0.4 s (springs stretched, slack and compressed), velocities then zeroed and, where its
    stiffness follows its wetness, each particle given water up to its capacity at random: at a dozen particles,
    minus the energy's gradient is the force the core computes (no damping at rest, no drag in vacuum, no water
    around it; colliders are not among these forces), to 1e-6 N of forces up to a few newtons."""
    preset, values = scene
    sim = wetcloth.Simulation(wetcloth.load_scene(preset, **values))
    sim.advance(0.4)
    sim.state.vel[:] = 0.0
    if values.get("wet_stiffness_factor"):
        sim.state.water[:] = np.random.default_rng(3).uniform(0.0, 1.0, sim.state.water.shape) * sim.model.capacity
    particles = np.random.default_rng(7).choice(sim.positions.shape[0], 12, replace=False)
    force = sim.model.forces(sim.state.pos, sim.state.vel, sim.state.water)[:, particles]
    assert np.abs(force).max() > 1e-3  # the springs pull
    np.testing.assert_allclose(-energy_gradient(sim, particles), force, rtol=0, atol=1e-6)
