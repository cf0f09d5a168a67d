"""The cloth's energy (wetcloth.energy, the core's energy.cpp), mechanical and buoyancy's, is the potential of its
forces: at rest velocities, in still air and still water, minus its gradient is the force of the springs, gravity
and buoyancy on every particle, for each spring law (tension-only, both ways, buckling, hinges' terms) and each
buoyancy model.  And the fixed-step mode does not let it grow where nothing drives the cloth (driven cloth:
test_driven_energy.py)."""

from __future__ import annotations

import numpy as np
import pytest

import wetcloth
from wetcloth.energy import buoyancy_energy, total_energy

#: Central differences of the energy over a displacement of STEP (m): their error, E''' STEP^2 / 6 with E''' at
#: most about k / w (the rounded onset's w = TENSION_ROUNDING l, some micrometres) times the ~10 springs of a
#: particle, stays far below the 1e-6 N allowed, as does the round-off of differencing a few joules
#: (1e-16 J / STEP = 1e-8 N).
STEP = 1e-8


def energy_gradient(sim: wetcloth.Simulation, particles: np.ndarray) -> np.ndarray:
    """dE/dx (N, (3, len(particles))) of the cloth's energy by central differences at its state."""
    gradient = np.empty((3, len(particles)))
    pos = sim._buffers.pos  # written in place: the energy at displaced positions
    for column, i in enumerate(particles):
        for c in range(3):
            start = pos[c, i]
            pos[c, i] = start + STEP
            up = total_energy(sim)
            pos[c, i] = start - STEP
            down = total_energy(sim)
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
    # floating on water: buoyancy, smooth over the surface slab, and the thesis's step at the surface
    ("towel", dict(nx=9, ny=11, absorption_rate=0.0)),
    ("towel", dict(nx=9, ny=11, absorption_rate=0.0, buoyancy_model="thesis")),
], ids=["grid", "hinged", "triangles", "wet grid", "wet hinged", "smooth buoyancy", "thesis buoyancy"])
def test_the_energy_is_the_potential_of_the_springs_gravity_and_buoyancy(scene):
    """A cloth after 0.4 s (springs stretched, slack and compressed), velocities then zeroed and, where its
    stiffness follows its wetness, each particle given water up to its capacity at random: at a dozen particles,
    minus the energy's gradient is the force the core computes (no damping or drag at rest in still air and
    water; colliders are not among these forces), to 1e-6 N of forces up to a few newtons.  (Buoyancy's
    potential is smooth but for kinks in its slope at the slab's faces, and the thesis's at the surface, which
    no particle lies within STEP of.)"""
    preset, values = scene
    sim = wetcloth.Simulation(wetcloth.load_scene(preset, **values))
    sim.advance(0.4)
    floats = "absorption_rate" in values
    assert (buoyancy_energy(sim) > 0) == floats  # only the floating towels are in the water
    sim._buffers.vel[:] = 0.0
    if values.get("wet_stiffness_factor"):
        sim._buffers.water[:] = np.random.default_rng(3).uniform(0.0, 1.0, sim.state.water.shape) * sim.model.capacity
    particles = np.random.default_rng(7).choice(sim.positions.shape[0], 12, replace=False)
    force = sim.model.forces(sim.state.pos, sim.state.vel, sim.state.water)[:, particles]
    assert np.abs(force).max() > 1e-3  # the springs pull
    np.testing.assert_allclose(-energy_gradient(sim, particles), force, rtol=0, atol=1e-6)


def test_a_towel_dropped_onto_still_water_at_frame_steps_never_gains_energy():
    """The fixed-step mode (backward Euler at 1/24 s frames) takes a step again in halves where it ends above its
    start's energy, mechanical and buoyancy's, also in still water (stepping.cpp, gained_energy).  The towel dropped
    from 30 cm without uptake: its energy falls in every one of 96 frames (to 1e-9 J of summing's round-off);
    before the check covered water, 2 frames rose, by up to 0.083 J (measured), as the towel struck the water."""
    scene = wetcloth.load_scene("towel", absorption_rate=0.0, initial_height=0.3, integrator="implicit_euler",
                                tolerance=0.0, max_step=1 / 24)
    sim = wetcloth.Simulation(scene)
    energies = [total_energy(sim)]
    for _ in range(96):
        sim.advance(1 / 24)
        energies.append(total_energy(sim))
    assert buoyancy_energy(sim) > 0  # it floats
    assert np.diff(energies).max() < 1e-9, np.diff(energies).max()


def test_a_towel_floating_at_rest_takes_no_step_again_for_noise():
    """A step counts as gaining energy only beyond ENERGY_NOISE of its energy's scale (stepping.cpp): a towel
    floating on water at 1/30 s frames changes its energy by 2e-19 to 6e-16 J a step once settled (measured), the
    noise of solves stopped within their tolerance; before the threshold this one took 177 steps again in 3 s."""
    scene = wetcloth.load_scene("towel", nx=15, ny=21, absorption_rate=0.0, absorption_capacity=0.0,
                                initial_height=0.02, initial_tilt=0.0, integrator="implicit_euler", tolerance=0.0,
                                max_step=1 / 30)
    sim = wetcloth.Simulation(scene)
    sim.advance(3.0)
    assert buoyancy_energy(sim) > 0  # it floats
    assert sim.rejected_steps == 0
