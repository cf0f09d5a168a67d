"""Colliders turned by keys (docs/model.md section 6.3, "Moving colliders"): a key's rotation vector
(rx, ry, rz) deg turns the collider about its centre, by slerp between keys; contact, friction and holding
act in its frame, against the velocity of its surface, v + omega x (p - c - d)."""

import math

import numpy as np
import pytest
import trimesh

import wetcloth
from wetcloth.errors import ParameterError
from wetcloth.scene import load_scene, rotation_matrix

G = 9.81
MU = 0.5

#: A 0.1 m sheet of 5 x 5 particles lying flat 1 um above its contact distance on the top (z = 0.2 m - 1 um)
#: of a 0.6 m box centred 0.15 m from the sheet's centre along -x, in air without drag.
TRAY = dict(nx=5, ny=5, width=0.1, length=0.1, initial_tilt=0.0, initial_height=0.2, thickness=0.002,
            water_level=-0.5, air_density=0.0)
AXIS_X = -0.15
TURNTABLE = dict(shape="box", size_x=0.6, size_y=0.6, size_z=0.2, x=AXIS_X, z=0.1 - 0.001 - 1e-6, friction=MU)


def _turntable(omega: float, integrator: str, until: float) -> wetcloth.Simulation:
    """The tray's box turning at omega rad/s about the vertical through its centre from t = 0, keyed every
    0.1 s up to `until` s."""
    times = 0.1 * np.arange(1, round(until / 0.1) + 1)
    keys = tuple(dict(collider=1, time=float(t), rz=math.degrees(omega * t)) for t in times)
    return wetcloth.Simulation(load_scene(**TRAY, integrator=integrator, colliders=(TURNTABLE,), collider_keys=keys))


def _in_frame(pos: np.ndarray, centre, rotation_deg, shift=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Points pos (3, n) in a collider's table frame: c + R^T (p - c - d)."""
    c = np.asarray(centre, dtype=float).reshape(3, 1)
    turn = rotation_matrix(np.radians(rotation_deg))
    return c + turn.T @ (pos - c - np.asarray(shift, dtype=float).reshape(3, 1))


@pytest.mark.parametrize("integrator", ["bdf2", "implicit_euler"])
def test_a_turntable_below_mu_g_carries_the_sheet_round_with_it(integrator):
    """omega = 2 rad/s about the vertical: omega^2 r <= 0.83 m/s2 < mu g = 4.9 m/s2 over the sheet (r <= 0.21 m).
    The sheet, at rest when the table starts, is caught up by friction within 0.1 s (|omega r| / (mu g));
    from 0.3 s, when every particle moves with the table, each particle's position is its 0.3 s position
    turned by omega (t - 0.3) about the axis: the table carries it (a held particle exactly; one that slips
    and is stopped again errs by at most the step's allowed local error, tolerance x size, per step) within
    the steps' summed allowed errors over the next 0.5 s (measured 2e-6 m under BDF2 against a bound of 6e-5
    m, 3e-15 m under implicit Euler: every particle held).  The sheet stays on the top."""
    omega = 2.0
    sim = _turntable(omega, integrator, 1.0)
    sim.advance(0.3)
    start, steps = sim.state.pos.copy(), sim.steps
    centre = np.array([[AXIS_X], [0.0], [0.0]])
    relative = sim.state.vel - np.cross([0.0, 0.0, omega], (start - centre).T).T
    assert np.abs(relative).max() < 1e-3  # caught up
    sim.advance(0.5)
    turned = centre + rotation_matrix([0.0, 0.0, omega * 0.5]) @ (start - centre)
    allowed = sim.scene.tolerance * max(sim.scene.width, sim.scene.length)
    bound = (sim.steps - steps) * allowed
    assert np.abs(sim.state.pos - turned).max() <= bound, (np.abs(sim.state.pos - turned).max(), bound)
    assert np.abs(sim.state.pos[2] - 0.2).max() < 1e-5


def test_a_turntable_above_mu_g_throws_the_sheet_outward_off_its_top():
    """omega = 10 rad/s: omega^2 r >= 10 m/s2 > 2 mu g everywhere on the sheet (r >= 0.1 m): friction cannot
    hold it on its circle, so it slides outward (its mean distance from the axis grows every 0.05 s) and
    leaves the top (the 0.3 m half side): by 0.5 s it has slid off, its lowest particle 1 cm and more below
    the top.  No particle comes closer to the turning box than thickness/2 less 0.1 mm at any 0.05 s."""
    omega = 10.0
    sim = _turntable(omega, "bdf2", 1.0)
    gap = 0.5 * sim.scene.thickness
    box = sim.scene.colliders[0]
    radius = [np.hypot(sim.state.pos[0] - AXIS_X, sim.state.pos[1]).mean()]
    for _ in range(10):
        sim.advance(0.05)
        pos = sim.state.pos
        radius.append(np.hypot(pos[0] - AXIS_X, pos[1]).mean())
        local = _in_frame(pos, (box.x, box.y, box.z), (0.0, 0.0, math.degrees(omega * sim.time)))
        assert box.distance(local).min() >= gap - 1e-4
    assert np.all(np.diff(radius) > 0.0), radius
    assert sim.state.pos[2].min() < 0.2 - 0.01


def test_a_tilting_board_keeps_the_sheet_out():
    """A board (0.4 x 0.4 x 0.02 m box) under the lying sheet tilts about x by 40 deg in 0.4 s (past the
    friction angle, atan 0.5 = 27 deg), holds, and turns back to level by 1 s: at every 0.02 s no particle
    centre is inside the board's contact distance by more than 0.1 mm (the tablecloth's bound), looked at
    in the board's frame; the sheet slides down the slope (its centre moves along -y)."""
    board = dict(shape="box", size_x=0.4, size_y=0.4, size_z=0.02, z=0.2 - 0.001 - 1e-6 - 0.01, friction=MU)
    keys = (dict(collider=1, time=0.4, rx=40.0), dict(collider=1, time=0.6, rx=40.0), dict(collider=1, time=1.0))
    sim = wetcloth.Simulation(load_scene(**{**TRAY, "nx": 7, "ny": 7}, colliders=(board,), collider_keys=keys))
    body, gap = sim.scene.colliders[0], 0.5 * sim.scene.thickness
    angle = np.interp  # the board's tilt (deg) at t: linear in the keys' angle (one axis: slerp is linear)
    for _ in range(50):
        sim.advance(0.02)
        tilt = angle(sim.time, [0.0, 0.4, 0.6, 1.0], [0.0, 40.0, 40.0, 0.0])
        local = _in_frame(sim.state.pos, (body.x, body.y, body.z), (tilt, 0.0, 0.0))
        assert body.distance(local).min() >= gap - 1e-4, (sim.time, body.distance(local).min() - gap)
    assert sim.state.pos[1].mean() < -0.02


@pytest.mark.parametrize("integrator", ["bdf2", "implicit_euler"])
def test_a_box_mesh_turned_by_keys_gives_the_analytic_boxs_run(tmp_path, integrator):
    """A closed box mesh (12 triangles) and the analytic box it is, both rising under a sheet lying on the
    floor, then turning 60 deg about the vertical and 20 deg about x while moving sideways (the sheet rides
    its tilting top), in the same fixed 2 ms steps: the mesh's crossing and distance, looked up in its
    frame, are the box's to the rounding of its file's single precision vertices (|x| <= 0.15 m: 0.15 x 2^-24
    = 9e-9 m), so the sheets agree within twice that every 0.1 s (measured 8e-10 m)."""
    mesh = trimesh.creation.box(extents=[0.3, 0.3, 0.1])
    path = tmp_path / "box.stl"
    mesh.export(path)
    base = dict(nx=7, ny=7, width=0.1, length=0.1, initial_tilt=0.0, initial_height=-0.5 + 0.001 + 1e-6,
                floor_level=-0.5, water_level=-1.0, air_density=0.0, integrator=integrator, tolerance=0.0,
                max_step=0.002)
    keys = (dict(collider=1, time=0.2, z=0.1), dict(collider=1, time=0.4, z=0.2, rz=30.0),
            dict(collider=1, time=0.6, z=0.2, x=0.1, rx=20.0, rz=60.0))
    z = -0.5 - 0.05 - 0.005
    box = wetcloth.Simulation(load_scene(**base, collider_keys=keys, colliders=(
        dict(shape="box", size_x=0.3, size_y=0.3, size_z=0.1, z=z, friction=0.3),)))
    solid = wetcloth.Simulation(load_scene(**base, collider_keys=keys, colliders=(
        dict(shape="mesh", file=str(path), z=z, friction=0.3),)))
    bound = 2 * 0.15 * 2.0 ** -24
    for _ in range(8):
        box.advance(0.1)
        solid.advance(0.1)
        assert np.abs(box.state.pos - solid.state.pos).max() <= bound
    start_z = -0.5 + 0.001 + 1e-6
    assert box.state.pos[2].max() > start_z + 0.15  # lifted with the box, not left on the floor
    assert np.ptp(box.state.pos[2]) > 0.01  # tilted with it


def test_keys_of_zero_rotation_run_as_keys_without_rotation_fields():
    """models/sweep.toml's keys with rx = ry = rz = 0 written out run bit for bit as the preset (the same
    steps, positions and velocities): a collider that never turns takes the translating code."""
    plain = wetcloth.load_scene("sweep")
    written = plain.replace(**{f"collider_key{k}_{axis}": 0.0 for k in range(1, len(plain.collider_keys) + 1)
                               for axis in ("rx", "ry", "rz")})
    runs = [wetcloth.Simulation(scene) for scene in (plain, written)]
    for sim in runs:
        sim.advance(0.8)
    assert runs[0].steps == runs[1].steps
    np.testing.assert_array_equal(runs[0].state.pos, runs[1].state.pos)
    np.testing.assert_array_equal(runs[0].state.vel, runs[1].state.vel)


def test_a_turning_sphere_turns_only_its_friction():
    """A sphere spinning about the vertical under a sheet that lies on its top: its surface does not move,
    so the sheet's particles stay on it (no particle closer than thickness/2 less 0.1 mm), but friction
    drags the particles at its top round about the axis: the sheet turns the sphere's way (its particles'
    mean angle about the axis grows)."""
    sphere = dict(shape="sphere", radius=0.3, z=0.2 - 0.001 - 1e-6 - 0.3, friction=MU)
    keys = tuple(dict(collider=1, time=0.1 * k, rz=math.degrees(3.0 * 0.1 * k)) for k in range(1, 6))
    sim = wetcloth.Simulation(load_scene(**TRAY, colliders=(sphere,), collider_keys=keys))
    start = sim.state.pos.copy()
    body, gap = sim.scene.colliders[0], 0.5 * sim.scene.thickness
    for _ in range(5):
        sim.advance(0.05)
        assert body.distance(sim.state.pos).min() >= gap - 1e-4
    outer = np.hypot(start[0], start[1]) > 0.01
    turned = np.angle(np.exp(1j * (np.arctan2(sim.state.pos[1], sim.state.pos[0]) - np.arctan2(start[1], start[0]))))
    assert np.all(turned[outer] > 0.0)


@pytest.mark.parametrize("keys, name, words", [
    ((dict(collider=1, time=1.0, rz=2e6),), "collider_key1_rz", "allowed: -1e+06 <= collider_key1_rz <= 1e+06 deg"),
    ((dict(collider=1, time=1.0, rx=179.5),), "collider_key1_rx",
     "turns collider 1 by 179.5 deg from its table's orientation (t = 0)"),
    ((dict(collider=1, time=1.0, rz=90.0), dict(collider=1, time=2.0, rz=270.0)), "collider_key2_rx",
     "turns collider 1 by 180 deg from collider_key1; allowed: less than 179 deg between consecutive keys"),
    ((dict(collider=1, time=1.0, ry="a"),), "collider_key1_ry", "expected a number"),
])
def test_bad_turning_keys_are_named_with_their_allowed_range(keys, name, words):
    with pytest.raises(ParameterError) as exc:
        load_scene(nx=5, ny=5, initial_height=0.3, colliders=(dict(shape="box", size_x=0.1, size_y=0.1, size_z=0.1),),
                   collider_keys=keys)
    assert name in str(exc.value) and words in str(exc.value), str(exc.value)
