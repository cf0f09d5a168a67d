"""Colliders moved by keys (docs/model.md section 6.3, "Moving colliders"): ``[[collider_key]]`` tables
displace a collider linearly between key times; contact and friction act in the collider's frame."""

import math

import numpy as np
import pytest
import trimesh

import wetcloth
from wetcloth.errors import ConfigError, ParameterError
from wetcloth.scene import load_scene, parse_text

from test_mesh_colliders import _crossings

G = 9.81

#: A 0.1 m sheet of 5 x 5 particles lying flat on a box's top, 1 um above its contact distance, in air
#: without drag (air_density 0: only gravity, the springs and the box act).
TRAY = dict(nx=5, ny=5, width=0.1, length=0.1, initial_tilt=0.0, initial_height=0.2, thickness=0.002,
            water_level=-0.5, air_density=0.0)


def _tray(acceleration: float, duration: float, key_step: float, friction: float, integrator: str):
    """A sheet on a 0.4 m box whose keys (every key_step s) follow x = a t^2 / 2 for `duration` s."""
    box = dict(shape="box", size_x=0.4, size_y=0.4, size_z=0.2, z=0.1 - 0.001 - 1e-6, friction=friction)
    times = key_step * np.arange(1, round(duration / key_step) + 1)
    keys = tuple(dict(collider=1, time=float(t), x=0.5 * acceleration * t * t) for t in times)
    scene = load_scene(**TRAY, integrator=integrator, colliders=(box,), collider_keys=keys)
    return wetcloth.Simulation(scene)


@pytest.mark.parametrize("integrator", ["bdf2", "implicit_euler"])
def test_a_box_accelerating_below_mu_g_carries_the_sheet_along(integrator):
    """The box's keys put it on x = a t^2 / 2 (a = 2 m/s2 < mu g = 4.9 m/s2) every 20 ms for 0.6 s: it moves at
    a constant velocity between keys, which jumps by a dt at each key (a dt / 2 at t = 0).  Coulomb's law
    carries the sheet at the box's velocity between keys; after each jump dv it slides back on the box,
    decelerated relative to it by mu g, by dv^2 / (2 mu g), and is carried again.  So the sheet's displacement
    is the box's (0.36 m) less the sum of those slips (4.8 mm); the sheet is within 10 % of that sum of it (the
    end of each slide is resolved within one step: measured 1.5 % under BDF2, 5 % under implicit Euler)."""
    a, mu, duration, dt = 2.0, 0.5, 0.6, 0.02
    sim = _tray(a, duration, dt, mu, integrator)
    start = sim.state.pos.copy()
    sim.advance(duration)
    moved = (sim.state.pos - start).mean(axis=1)
    jumps = [0.5 * a * dt] + [a * dt] * (round(duration / dt) - 1)  # the last key's jump comes at the end
    slip = sum(dv * dv for dv in jumps) / (2 * mu * G)
    box = 0.5 * a * duration ** 2
    assert abs((box - moved[0]) - slip) <= 0.1 * slip, (box - moved[0], slip)
    assert abs(moved[1]) < 1e-9 and abs(moved[2]) < 1e-5  # straight along x, on the top


@pytest.mark.parametrize("integrator", ["bdf2", "implicit_euler", "symplectic_euler"])
def test_a_box_accelerating_above_mu_g_slides_under_the_sheet(integrator):
    """a = 2 mu g: the box always moves faster than the sheet (its velocity between keys, a (t_k + t_k+1)
    / 2, exceeds mu g t_k+1 for every key), so kinetic friction accelerates the sheet by mu g throughout:
    it moves mu g t^2 / 2 in t s (0.098 m in 0.2 s, the box 0.196 m), within 1 % as on an incline
    (tests/test_colliders.py; measured -0.0003 %, 0.2 %, -0.06 %)."""
    mu, duration = 0.5, 0.2
    sim = _tray(2 * mu * G, duration, 0.02, mu, integrator)
    start = sim.state.pos.copy()
    sim.advance(duration)
    moved = (sim.state.pos - start).mean(axis=1)[0]
    expected = 0.5 * mu * G * duration ** 2
    assert abs(moved - expected) <= 0.01 * expected, (moved, expected)


def _sphere_through_sheet():
    """A 15 x 15 sheet lying on the floor and a sphere (radius 8 cm) below the floor, 1 cm under the sheet,
    that rises 0.25 m in 1 s and stops."""
    sphere = dict(shape="sphere", radius=0.08, z=-0.5 - 0.08 - 0.01)
    scene = load_scene(nx=15, ny=15, width=0.4, length=0.4, initial_tilt=0.0, initial_height=-0.5 + 0.001 + 1e-6,
                       floor_level=-0.5, water_level=-1.0, colliders=(sphere,),
                       collider_keys=(dict(collider=1, time=1.0, z=0.25),))
    return scene


def test_a_rising_sphere_lifts_a_lying_sheet_and_no_particle_enters_it():
    """Every 0.05 s for 1.5 s no particle centre is closer to the sphere where it is than thickness/2 less
    0.1 mm (the tablecloth's bound: the contact puts particles at thickness/2 at each step's end); the sheet
    is lifted: at the end its highest particle lies on the sphere's top, at top + thickness/2 within 0.1 mm."""
    scene = _sphere_through_sheet()
    sim = wetcloth.Simulation(scene)
    body, gap = scene.colliders[0], 0.5 * scene.thickness
    for _ in range(30):
        sim.advance(0.05)
        lift = 0.25 * min(sim.time, 1.0)
        assert body.distance(sim.state.pos - np.array([[0.0], [0.0], [lift]])).min() >= gap - 1e-4
    top = body.z + 0.25 + body.radius
    assert abs(sim.state.pos[2].max() - (top + gap)) <= 1e-4


def _box_displacement(t):
    """The displacement (3) of the keys of test_a_box_mesh_moved_by_keys_gives_the_analytic_boxs_run at t s."""
    if t <= 0.2:
        return np.array([0.0, 0.0, 0.5 * t])
    if t <= 0.4:
        return np.array([0.5 * (t - 0.2), 0.0, 0.1 + 0.5 * (t - 0.2)])
    return np.array([0.1 + min(t - 0.4, 0.2), 0.0, 0.2])


def test_a_box_mesh_moved_by_keys_gives_the_analytic_boxs_run(tmp_path):
    """A closed box mesh (12 triangles) and the analytic box it is, both rising 0.2 m from under a sheet lying
    on the floor, carrying it sideways 0.3 m and stopping (the sheet slides on): the box's crossing and
    distance are the mesh's to rounding, so while no cloth edge meets a box edge the runs differ only by
    their step control's accepted errors, at most the allowed local error (tolerance x size) per step of
    each: the sheets agree within that sum every frame (measured 7e-10 m against a bound of 4e-4 m) until
    the sheet slides over the box's trailing rim (after 0.5 s), where the analytic box lets the cloth's edges
    through its corner (26 of them across its faces) and the mesh's edges keep them off (the edges' pass in
    its moving frame): no cloth edge crosses the mesh box in any frame."""
    mesh = trimesh.creation.box(extents=[0.3, 0.3, 0.1])
    path = tmp_path / "box.stl"
    mesh.export(path)
    base = dict(nx=7, ny=7, width=0.1, length=0.1, initial_tilt=0.0, initial_height=-0.5 + 0.001 + 1e-6,
                floor_level=-0.5, water_level=-1.0, air_density=0.0)
    keys = (dict(collider=1, time=0.2, z=0.1), dict(collider=1, time=0.4, z=0.2, x=0.1),
            dict(collider=1, time=0.6, z=0.2, x=0.3))
    z = -0.5 - 0.05 - 0.005
    box = wetcloth.Simulation(load_scene(**base, collider_keys=keys, colliders=(
        dict(shape="box", size_x=0.3, size_y=0.3, size_z=0.1, z=z, friction=0.3),)))
    solid = wetcloth.Simulation(load_scene(**base, collider_keys=keys, colliders=(
        dict(shape="mesh", file=str(path), z=z, friction=0.3),)))
    allowed = box.scene.tolerance * max(box.scene.width, box.scene.length)
    faces, triangles = np.asarray(mesh.faces), np.asarray(box.triangles)
    agreed = 0.0  # s: the time until which the runs agree
    for _ in range(24):
        box.advance(1 / 30)
        solid.advance(1 / 30)
        points = np.asarray(mesh.vertices) + [0.0, 0.0, z] + _box_displacement(box.time)
        assert _crossings(solid.state.pos.T, triangles, points, faces) == (0, 0), box.time
        if agreed < box.time - 1e-9 - 1 / 30 or _crossings(box.state.pos.T, triangles, points, faces) != (0, 0):
            continue  # the analytic box's sheet has met its edge: the runs part
        bound = (box.steps + solid.steps) * allowed
        assert np.abs(box.state.pos - solid.state.pos).max() <= bound, box.time
        agreed = box.time
    assert 0.5 <= agreed < 0.8  # through the carrying, then parted at the rim
    assert box.state.pos[0].mean() > 0.15  # carried along, not left behind


@pytest.mark.parametrize("collider", [dict(shape="sphere", radius=0.05, z=0.0),
                                      dict(shape="box", size_x=0.08, size_y=0.08, size_z=0.08, z=-0.04)])
def test_keys_of_zero_displacement_change_nothing(collider):
    """A sheet dropped onto a collider whose keys all displace it by 0 runs as without keys, bit for bit
    (the same steps, positions and velocities): keys that do not change the velocity end no step, and a
    collider standing still is looked up, held and rubbed against as before."""
    base = dict(nx=7, ny=7, width=0.2, length=0.2, initial_tilt=5.0, initial_height=0.06, water_level=-0.5)
    still = wetcloth.Simulation(load_scene(**base, colliders=(collider,)))
    keyed = wetcloth.Simulation(load_scene(**base, colliders=(collider,), collider_keys=(
        dict(collider=1, time=0.3), dict(collider=1, time=0.7, x=0.0, y=0.0, z=0.0))))
    for sim in (still, keyed):
        sim.advance(1.0)
    assert keyed.steps == still.steps
    np.testing.assert_array_equal(keyed.state.pos, still.state.pos)
    np.testing.assert_array_equal(keyed.state.vel, still.state.vel)


def test_the_sweep_preset_pushes_the_towel_aside_without_entering_the_ball():
    """models/sweep.toml for 1.5 s: the ball, sweeping along y from 0.5 s, has pushed the hanging towel 0.2 m
    and more aside, and no particle centre came closer to it than thickness/2 less 0.1 mm at any 0.1 s."""
    scene = wetcloth.load_scene("sweep")
    sim = wetcloth.Simulation(scene)
    body, gap = scene.colliders[0], 0.5 * scene.thickness
    for _ in range(15):
        sim.advance(0.1)
        swept = 0.4 * min(max(sim.time - 0.5, 0.0), 1.5)
        assert body.distance(sim.state.pos - np.array([[0.0], [swept], [0.0]])).min() >= gap - 1e-4
    assert sim.state.pos[1].max() > 0.2


def test_collider_keys_are_addressed_by_one_name_each(tmp_path):
    """collider_key<k>_<field> in load_scene overrides, --set text, Scene.replace and to_dict; [[collider_key]]
    tables in a scene file; `wetcloth params` lists them; a batch study's axis sets them."""
    from wetcloth.commands.params import rows

    path = tmp_path / "scene.toml"
    path.write_text('nx = 5\nny = 5\ninitial_tilt = 0.0\ninitial_height = 0.3\n[[collider]]\nshape = "sphere"\n'
                    'radius = 0.1\n[[collider_key]]\ncollider = 1\ntime = 1.0\nz = 0.1\n')
    scene = load_scene(path, collider_key1_x=0.05)
    assert (scene.collider_keys[0].x, scene.collider_keys[0].z) == (0.05, 0.1)
    assert scene.to_dict()["collider_key1_time"] == 1.0
    later = scene.replace(collider_key2_collider=1, collider_key2_time=2.0, collider_key2_z=0.0)
    assert [k.time for k in later.collider_keys] == [1.0, 2.0]
    assert parse_text("collider_key1_time", "1.5") == 1.5
    assert scene.replace(collider_keys=()).collider_keys == ()
    names = [r["name"] for r in rows(str(path))]
    assert {"collider_key1_collider", "collider_key1_time", "collider_key1_z"} <= set(names)
    from wetcloth.batch.spec import Study
    from wetcloth.scene import from_dict

    study = Study.from_dict(dict(scene="sweep", duration=0.1, axes={"collider_key2_y": [0.4, 0.6]}))
    assert [from_dict(run.params).collider_keys[1].y for run in study.runs()] == [0.4, 0.6]


@pytest.mark.parametrize("keys, name, words", [
    ((dict(collider=2, time=1.0),), "collider_key1_collider", "2 names no collider (the scene has 1); allowed: "
                                                              "1 <= collider_key1_collider <= 1"),
    ((dict(collider=1, time=1.0), dict(collider=1, time=0.5)), "collider_key2_time",
     "0.5 s is not after collider_key1_time = 1.0 s, the previous key of collider 1; allowed: the times of one "
     "collider's keys increase"),
    ((dict(collider=1),), "collider_key1_time", "a collider key needs its time; allowed: 0 < collider_key1_time"),
    ((dict(time=1.0),), "collider_key1_collider", "a collider key needs its collider; allowed: 1 <= "
                                                  "collider_key1_collider <= 1"),
    ((dict(collider=1, time=-1.0),), "collider_key1_time", "allowed: 0 < collider_key1_time <= 1e+06 s"),
    ((dict(collider=1, time=1.0, x=2e4),), "collider_key1_x", "allowed: -10000 <= collider_key1_x <= 10000 m"),
    ((dict(collider=1.5, time=1.0),), "collider_key1_collider", "expected a whole number"),
])
def test_bad_collider_keys_are_named_with_their_allowed_range(keys, name, words):
    with pytest.raises(ParameterError) as exc:
        load_scene(nx=5, ny=5, initial_height=0.3, colliders=(dict(shape="sphere", radius=0.1),), collider_keys=keys)
    assert name in str(exc.value) and words in str(exc.value), str(exc.value)


def test_a_faulty_collider_is_one_mistake_not_one_for_each_of_its_keys():
    """A collider with a bad field is reported once: its keys still name it by its place among the tables
    given (before, each key also got 'names no collider (the scene has 0)')."""
    with pytest.raises(ParameterError) as exc:
        load_scene("sweep", collider1_radius=-1.0)
    assert str(exc.value).startswith("parameter 'collider1_radius': -1.0 is out of range"), str(exc.value)
    assert "names no collider" not in str(exc.value) and "mistakes" not in str(exc.value), str(exc.value)


def test_bad_collider_key_names_and_tables_are_refused(tmp_path):
    with pytest.raises(ParameterError, match="collider_key1_speed.*unknown collider key field.*one of collider, "
                                             "time, x, y, z"):
        load_scene(collider_key1_speed=1.0)
    with pytest.raises(ParameterError, match="a collider key moves a \\[\\[collider\\]\\] of the scene, and it has none"):
        load_scene(collider_keys=(dict(time=1.0),))
    path = tmp_path / "scene.toml"
    path.write_text("collider_key = 3\n")
    with pytest.raises(ConfigError, match="collider keys are \\[\\[collider_key\\]\\] tables"):
        load_scene(path)


def test_a_unit_built_with_a_scene_moves_its_colliders_by_their_keys(tmp_path):
    """`wetcloth build-fmu --scene sweep`: the unit carries the scene's [[collider_key]] tables (they are not
    variables) and, run for 1.2 s, gives the Python run's outputs advanced to fmpy's communication points
    (equal to round-off, 1e-12 m); without the keys the ball never reaches the towel."""
    from test_fmu_support import RUN_UNIT, run_child

    from wetcloth.fmu.builder import build_fmu

    fmu = build_fmu(tmp_path / "Sweep.fmu", scene="sweep")
    run, _ = run_child(RUN_UNIT, fmu, "1.2", "centroid_y", cwd=tmp_path)
    centroids = []
    for scene in (load_scene("sweep"), load_scene("sweep").replace(collider_keys=())):
        sim = wetcloth.Simulation(scene)
        for k in range(1, 13):
            sim.advance(k * 0.1 - sim.time)
        centroids.append(sim.outputs()["centroid_y"])
    assert run[-1]["centroid_y"] == pytest.approx(centroids[0], rel=0, abs=1e-12)
    assert centroids[0] - centroids[1] > 0.01


def test_the_native_unit_compiles_in_the_collider_keys():
    """`build-fmu --native --scene`: the scene's collider keys become the unit's SCENE_COLLIDER_KEYS rows
    (collider from 0, time, x, y, z, rx, ry, rz in rad; by collider and time), as the Python model hands them
    to the core."""
    from wetcloth.fmu.native import fixtures_source

    header = fixtures_source(load_scene("sweep"))
    assert "SCENE_COLLIDER_KEYS_SIZE = 16;" in header
    assert ("SCENE_COLLIDER_KEYS[] = {0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.6, 0.0, 0.0, 0.0, 0.0, 0};"
            in header)
    assert "SCENE_COLLIDER_KEYS_SIZE = 0;" in fixtures_source(load_scene("tablecloth_sphere"))
