"""Moving mesh colliders' edges (docs/model.md section 6.3): a keyed mesh keeps its edges off the cloth's edges
and its vertices off the cloth's triangles as a still one does (collider_edges.cpp, in the collider's table
frame), so a thin blade moving or turning through a coarse sheet does not slice between its particles."""

import math

import numpy as np
import pytest
import trimesh

import wetcloth
from wetcloth.scene import load_scene

from test_mesh_colliders import _crossings

#: The blade: a closed box mesh 0.7 m long, 4 mm thick, 0.2 m tall (its half extents, m).
HALF = np.array([0.35, 0.002, 0.1])
FLOOR = -0.5
#: Its centre starts 1 cm below the floor less its half height; it rises RISE m over DURATION s.
START_Z = FLOOR - 0.01 - HALF[2]
RISE, DURATION = 0.25, 0.5


def _rotation_z(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _blade_place(t, turn):
    """The blade's centre (3) and rotation (3, 3) at t s: rising linearly, turning by `turn` rad about z."""
    f = min(t / DURATION, 1.0)
    return np.array([0.0, 0.0, START_Z + f * RISE]), _rotation_z(f * turn)


def _rising_blade(tmp_path, turn_deg):
    """A 6 x 6 sheet 0.5 m wide (particles 10 cm apart) lying on the floor, the blade below it midway between
    two rows, keyed to rise RISE m (turning turn_deg about the vertical) over DURATION s."""
    blade = trimesh.creation.box(extents=2 * HALF)
    path = tmp_path / "blade.stl"
    blade.export(path)
    scene = load_scene(nx=6, ny=6, width=0.5, length=0.5, initial_tilt=0.0, initial_height=FLOOR + 0.001 + 1e-6,
                       floor_level=FLOOR, water_level=-1.0,
                       colliders=({"shape": "mesh", "file": str(path), "z": START_Z},),
                       collider_keys=(dict(collider=1, time=DURATION, z=RISE, rz=turn_deg),))
    return wetcloth.Simulation(scene), blade


@pytest.mark.parametrize("turn_deg", [0.0, 30.0])
def test_a_blade_rising_through_a_coarse_sheet_lifts_it_instead_of_slicing_it(tmp_path, turn_deg):
    """The blade (4 mm thick, the sheet's rows 10 cm apart: no particle is near it, so only the edges' pass can
    stop it) rises 0.25 m through the sheet lying on the floor in 0.5 s, straight or turning 30 degrees, then
    stands.  Every frame (1/30 s) for 0.8 s: no cloth edge crosses a blade triangle and no blade edge a cloth
    triangle (from the geometry: segment against triangle), and no particle lies inside the blade; at the end
    the sheet hangs over the blade's top (rows on both sides, its highest point within 2 cm above the top).
    Without the moving mesh's edges in the pass the blade passes between two rows and the sheet stays on
    the floor."""
    sim, blade = _rising_blade(tmp_path, turn_deg)
    assert np.abs(sim.state.pos[1]).min() > 0.04  # the blade lies between two rows
    faces, local = np.asarray(blade.faces), np.asarray(blade.vertices)
    for _ in range(24):
        sim.advance(1 / 30)
        centre, rotation = _blade_place(sim.time, math.radians(turn_deg))
        points = local @ rotation.T + centre
        assert _crossings(sim.state.pos.T, np.asarray(sim.triangles), points, faces) == (0, 0), sim.time
        table = (sim.state.pos.T - centre) @ rotation  # each particle in the blade's own frame
        assert not (np.abs(table) < HALF).all(axis=1).any(), sim.time
    top = START_Z + RISE + HALF[2]
    pos = sim.state.pos
    assert (pos[1] < 0).any() and (pos[1] > 0).any()
    assert top < pos[2].max() < top + 0.02


@pytest.mark.parametrize("turn_deg, duration", [(0.0, 0.5), (30.0, 0.25)])
def test_a_blade_rising_through_a_sheet_at_frame_steps_does_not_slice_it(tmp_path, turn_deg, duration):
    """The rising blade at fixed frame steps (implicit Euler, tolerance 0, at most 1/30 s), straight over 0.5 s
    or turning 30 degrees over 0.25 s: in its frame each particle moves up to 1.7 cm (straight) or 3.4 cm plus
    its turn (turning, the farther from the axis the more) in a step, far more than the kept list's least
    allowance, so only each particle's stride in the list's reach brings the pairs it meets within the step
    into the list (collider_edges.cpp, keep_list).  Every frame for 0.8 s: no cloth edge crosses a blade
    triangle and no blade edge a cloth triangle, and no particle lies inside the blade.  With the strides
    left out of the reach the blade crosses the sheet in 8 frames straight and 14 turning."""
    blade = trimesh.creation.box(extents=2 * HALF)
    path = tmp_path / "blade.stl"
    blade.export(path)
    scene = load_scene(nx=6, ny=6, width=0.5, length=0.5, initial_tilt=0.0, initial_height=FLOOR + 0.001 + 1e-6,
                       floor_level=FLOOR, water_level=-1.0, integrator="implicit_euler", tolerance=0.0,
                       max_step=1.0 / 30.0, colliders=({"shape": "mesh", "file": str(path), "z": START_Z},),
                       collider_keys=(dict(collider=1, time=duration, z=RISE, rz=turn_deg),))
    sim = wetcloth.Simulation(scene)
    faces, local = np.asarray(blade.faces), np.asarray(blade.vertices)
    for _ in range(24):
        sim.advance(1 / 30)
        f = min(sim.time / duration, 1.0)
        centre, rotation = np.array([0.0, 0.0, START_Z + f * RISE]), _rotation_z(f * math.radians(turn_deg))
        points = local @ rotation.T + centre
        assert _crossings(sim.state.pos.T, np.asarray(sim.triangles), points, faces) == (0, 0), sim.time
        table = (sim.state.pos.T - centre) @ rotation
        assert not (np.abs(table) < HALF).all(axis=1).any(), sim.time


def test_a_blade_sweeping_sideways_into_a_hanging_sheet_carries_it_instead_of_slicing_it(tmp_path):
    """A 6 x 6 sheet 0.5 m wide (particles 10 cm apart) hangs by its top edge in the x-z plane; a vertical
    blade 4 mm thick (in x, midway between two columns), 0.3 m long (in y) and 0.5 m tall, its top 15 cm below
    the pinned edge and its bottom below the sheet's, sweeps 0.6 m along y through it in 1 s and stands.
    Every frame for 1.5 s: no cloth edge crosses a blade triangle and no blade edge a cloth triangle, no
    particle inside the blade; the sheet's lowest row rides in front of the blade's leading edge (which ends
    at y = 0.45 m): its mean y beyond 0.3 m.  Without the moving mesh's edges the blade passes between two
    columns and the sheet hangs on at y = 0."""
    half = np.array([0.002, 0.15, 0.25])
    blade = trimesh.creation.box(extents=2 * half)
    path = tmp_path / "blade.stl"
    blade.export(path)
    centre0 = np.array([0.0, -0.3, 0.35])
    scene = load_scene(nx=6, ny=6, width=0.5, length=0.5, initial_tilt=90.0, initial_height=0.5, pinned_edge="y_max",
                       water_level=-0.5, floor_level=-1.0,
                       colliders=({"shape": "mesh", "file": str(path), "y": centre0[1], "z": centre0[2]},),
                       collider_keys=(dict(collider=1, time=1.0, y=0.6),))
    sim = wetcloth.Simulation(scene)
    assert np.abs(sim.state.pos[0]).min() > 0.04  # the blade lies between two columns
    bottom = np.isclose(sim.state.pos[2], sim.state.pos[2].min())  # the sheet's free lower edge
    faces, local = np.asarray(blade.faces), np.asarray(blade.vertices)
    for _ in range(45):
        sim.advance(1 / 30)
        centre = centre0 + [0.0, 0.6 * min(sim.time, 1.0), 0.0]
        points = local + centre
        assert _crossings(sim.state.pos.T, np.asarray(sim.triangles), points, faces) == (0, 0), sim.time
        assert not (np.abs(sim.state.pos.T - centre) < half).all(axis=1).any(), sim.time
    lowest = sim.state.pos[1, bottom]
    assert lowest.mean() > 0.3, lowest


def test_a_run_against_a_moving_mesh_restored_from_a_snapshot_repeats_bit_for_bit(tmp_path):
    """The turning, rising blade lifting the sheet: a run restored from a snapshot at 0.2 s into a new
    simulation (the moving mesh's kept list of pairs gathered afresh there, in its frame) ends at the same
    positions, velocities and step count, to the bit, as the run that went on with the list it had."""
    straight, _ = _rising_blade(tmp_path, 30.0)
    straight.advance(0.2)
    snapshot = straight.snapshot()
    straight.advance(0.2)
    restored, _ = _rising_blade(tmp_path, 30.0)
    restored.restore(snapshot)
    restored.advance(0.2)
    assert restored.steps == straight.steps
    assert np.array_equal(restored.state.pos, straight.state.pos)
    assert np.array_equal(restored.state.vel, straight.state.vel)
