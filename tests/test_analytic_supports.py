"""The analytic colliders as supports inside fixed implicit steps (collider_analytic_supports.cpp,
docs/model.md section 6.3 "Supports in the solve"): a cloth draping over a ball or sliding down a slope at
frame-long steps never gains energy, and no particle ends a frame inside the particles' contact distance."""

import numpy as np
import pytest

import wetcloth
from wetcloth.energy import mechanical_energy
from wetcloth.scene import load_scene

#: J: the rounding of a frame's energy, a sum of about a thousand terms (kinetic, gravitational, elastic)
#: each below 1 J in double precision (1e3 * 2.2e-16 J), with a margin.
ENERGY_ROUNDING = 1e-12


def test_a_cloth_draping_over_a_ball_at_frame_steps_never_gains_energy():
    """The tablecloth_sphere preset on a 13 x 13 grid (same sheet, ball and friction), passive in still air,
    at fixed frame steps (implicit Euler, tolerance 0, max_step 1/30 s) for 2 s: its mechanical energy
    does not rise from one frame to the next beyond rounding (before, particles that met the ball within a
    frame-long step were pushed out after it, and frame 8 gained 0.073 J of 0.88), and every particle ends
    every frame at least thickness / 2 off the ball's surface (within 1e-12 m)."""
    scene = load_scene("tablecloth_sphere", nx=13, ny=13).replace(integrator="implicit_euler", tolerance=0.0,
                                                                   max_step=1.0 / 30.0)
    ball = scene.colliders[0]
    sim = wetcloth.Simulation(scene)
    energy = [mechanical_energy(sim)]
    closest = np.inf
    for _ in range(60):
        sim.advance(1.0 / 30.0)
        energy.append(mechanical_energy(sim))
        closest = min(closest, (np.linalg.norm(sim.positions - [ball.x, ball.y, ball.z], axis=1) - ball.radius).min())
    assert np.diff(energy).max() <= ENERGY_ROUNDING
    assert energy[-1] < 0.7 * energy[0]  # (it drapes: the sides fell over the ball)
    assert closest >= 0.5 * scene.thickness - 1e-12


def test_a_sheet_falls_onto_a_collider_within_one_frame_long_step():
    """A flat sheet 1 cm above a box's top, one fixed step of 1/24 s (free fall: 17 mm): it ends on the top,
    its centre within 1 mm beyond thickness / 2 (the descent's line search, met by the penalty's steep slope
    at the full step, once left it hovering 0.01 mm below its start)."""
    scene = load_scene(nx=15, ny=15, width=0.4, length=0.4, initial_tilt=0.0, water_level=-0.5, initial_height=0.06,
                       colliders=(dict(shape="box", size_x=0.3, size_y=0.3, size_z=0.2, z=-0.05),),
                       integrator="implicit_euler", tolerance=0.0, max_step=1.0 / 24.0)
    sim = wetcloth.Simulation(scene)
    sim.advance(1.0 / 24.0)
    centre = sim.state.pos[2, 7 * 15 + 7] - 0.05  # m above the top
    assert 0.5 * scene.thickness - 1e-12 <= centre <= 0.5 * scene.thickness + 1e-3


def test_the_tablecloth_at_frame_steps_of_1_24_s_never_gains_energy():
    """The tablecloth preset (a round mesh cloth falling onto a round table, passive in still air) at fixed
    steps of 1/24 s for 2 s: its mechanical energy does not rise from one frame to the next beyond rounding.
    A frame-long step in contact can converge to a worse local minimum of its incremental potential, one
    above the energy the step started with (implicit.cpp, DESCENT_RESTARTS): the solve then starts again
    from the lowest point between rest and there.  Without, a frame gained 0.073 J (90deede), and 4 steps were
    taken again; with them, none until the line search stopped creeping where the table's penalty is met within
    the step (implicit.cpp, line_search): the cloth then lands a step earlier, and the landing's lift-off at
    0.125 s, farther than thickness / 2 within its step (stepping.cpp), takes that step once again."""
    scene = load_scene("tablecloth").replace(integrator="implicit_euler", tolerance=0.0, max_step=1.0 / 24.0)
    sim = wetcloth.Simulation(scene)
    energy = [mechanical_energy(sim)]
    for _ in range(48):
        sim.advance(1.0 / 24.0)
        energy.append(mechanical_energy(sim))
    assert np.diff(energy).max() <= ENERGY_ROUNDING, np.diff(energy).max()
    assert sim.rejected_steps <= 1
    assert sim.solver_counts["descent_restarts"] > 0  # (the restarts are what keeps it: 11 over the 48 steps here)


@pytest.mark.parametrize("fps", [20.0, 12.0])
def test_the_tablecloth_at_frame_steps_beyond_1_24_s_lands_on_its_table(fps):
    """The tablecloth preset (placed 1 cm above its table) at fixed steps of 1/20 and 1/12 s: after 1 s every
    vertex within 0.3 m of the table's axis rests on the top, thickness / 2 above it, within 0.01 mm (as at
    1/30 s).  Each step's first Newton correction, without the table's penalty in its matrix, drove the cloth
    deep into the table; the line search's false-position guesses then crept from the start, the next
    corrections alike, and the cloth hovered 8.3 and 9.8 mm above the top (implicit.cpp, line_search)."""
    scene = load_scene("tablecloth").replace(integrator="implicit_euler", tolerance=0.0, max_step=1.0 / fps)
    table = scene.colliders[0]
    sim = wetcloth.Simulation(scene)
    sim.advance(1.0)
    pos = sim.state.pos
    on_top = np.hypot(pos[0] - table.x, pos[1] - table.y) < 0.3
    resting = table.z + 0.5 * table.height + 0.5 * scene.thickness
    assert np.abs(pos[2, on_top] - resting).max() <= 1e-5


@pytest.mark.parametrize("fps", [30.0, 24.0])
def test_a_sheet_sliding_down_a_slope_at_frame_steps_never_gains_energy(fps):
    """A 21 x 21 sheet of 0.6 m falling 0.3 m onto a tilted plane (friction 0.2) and sliding down it, passive in
    still air, at fixed frame steps of 1/30 and 1/24 s for 2 s: its mechanical energy does not rise from one
    frame to the next beyond rounding.  A frame whose incremental potential rose from rest toward the
    solve's end restarted descent at that end again (the line search along the path took its full length)
    and kept its rise: 0.0011 J and 0.003 J on b9b3af6 (bench/frame_step_energy.py "down a slope")."""
    scene = load_scene(nx=21, ny=21, width=0.6, length=0.6, initial_tilt=0.0, water_level=-10.0, floor_level=0.0,
                       absorption_rate=0.0, absorption_capacity=0.0, initial_height=0.5,
                       colliders=(dict(shape="plane", z=0.2, normal_x=0.3, normal_z=1.0, friction=0.2),),
                       integrator="implicit_euler", tolerance=0.0, max_step=1.0 / fps)
    sim = wetcloth.Simulation(scene)
    energy = [mechanical_energy(sim)]
    for _ in range(round(2.0 * fps)):
        sim.advance(1.0 / fps)
        energy.append(mechanical_energy(sim))
    assert np.diff(energy).max() <= ENERGY_ROUNDING, np.diff(energy).max()
    assert sim.solver_counts["descent_restarts"] > 0
