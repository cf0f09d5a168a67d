"""Analytic colliders (docs/model.md section 6.3): a plane, box, sphere or vertical cylinder that keeps the
cloth's particle centres thickness/2 outside it, with Coulomb friction, as the floor does."""

import math

import numpy as np
import pytest

import wetcloth
from wetcloth.errors import ConfigError, ParameterError
from wetcloth.scene import load_scene, parse_text
from support.sliding import STEP, assert_slides_coulomb_distance

#: A 0.4 m square sheet of 15 x 15 particles, flat, well above the water and the floor.
SHEET = dict(nx=15, ny=15, width=0.4, length=0.4, initial_tilt=0.0, water_level=-0.5)
CENTRE = 7 * 15 + 7  # the particle at the sheet's centre (x = y = 0)

#: Each shape with the height of its top at x = y = 0 (m), all tops at or below 0.15 m.
SHAPES = {
    "sphere": (dict(shape="sphere", radius=0.15), 0.15),
    "cylinder": (dict(shape="cylinder", radius=0.15, height=0.2, z=-0.05), 0.05),
    "box": (dict(shape="box", size_x=0.3, size_y=0.3, size_z=0.2, z=-0.05), 0.05),
}


@pytest.mark.parametrize("shape", SHAPES)
def test_a_sheet_dropped_onto_a_collider_drapes_over_it_and_never_enters_it(shape):
    """A sheet dropped from 1 cm above the top drapes over the shape.  In every frame (every 0.05 s for
    3 s) no particle centre is closer to the surface than thickness/2 less 0.1 mm (the contact puts
    particles back at exactly thickness/2 at the end of each step, which is where frames are taken);
    at the end the particle over the top lies on it, at top + thickness/2 within 0.1 mm, and is still
    (held there: velocity below 1 mm/s)."""
    collider, top = SHAPES[shape]
    scene = load_scene(**SHEET, initial_height=top + 0.01, colliders=(collider,))
    sim = wetcloth.Simulation(scene)
    gap = 0.5 * scene.thickness
    body = scene.colliders[0]
    for _ in range(60):
        sim.advance(0.05)
        assert body.distance(sim.state.pos).min() >= gap - 1e-4
    assert abs(sim.state.pos[2, CENTRE] - (top + gap)) <= 1e-4
    assert np.linalg.norm(sim.state.vel[:, CENTRE]) < 1e-3
    assert sim.state.pos[2].min() < top - 0.02  # it drapes: the edges hang down over the sides


@pytest.mark.parametrize("shape", ["cylinder", "box"])
def test_a_frame_long_step_into_the_top_near_its_edge_ends_on_the_top(shape):
    """One fixed step of 1/24 s takes the sheet, 1 cm above the top, 7 mm into it (g h^2 = 17 mm; an explicit
    step, whose solve has no supports to stop it before the top, so that the contact after the step meets it
    there).  A column of particles lies 3 mm inside the top's edge: nearer the side than the top at the step's
    end, the nearest face would push them out through the side, below the top, across the cloth.  Every
    particle whose path came in through the top ends on it, at top + thickness/2 (to rounding)."""
    collider, top = SHAPES[shape]
    shift = 0.147 - 12 * 0.4 / 14 + 0.2  # the sheet's column 12 (x = 0.1429 m) 3 mm inside the edge at 0.15
    moved = dict(collider, x=-shift)
    scene = load_scene(**SHEET, initial_height=top + 0.01, colliders=(moved,), integrator="symplectic_euler",
                       tolerance=0.0, max_step=1.0 / 24.0)
    sim = wetcloth.Simulation(scene)
    start = sim.state.pos.copy()
    sim.advance(1.0 / 24.0)
    x0, y0 = start[0] + shift, start[1]
    over = np.hypot(x0, y0) < 0.15 if shape == "cylinder" else (np.abs(x0) < 0.15) & (np.abs(y0) < 0.15)
    assert np.count_nonzero(np.abs(x0 - 0.147) < 1e-9) == 15  # the column is there
    gap = 0.5 * scene.thickness
    np.testing.assert_allclose(sim.state.pos[2, over], top + gap, rtol=0, atol=1e-12)


@pytest.mark.parametrize("far", [dict(shape="sphere", x=10.0, radius=0.5),
                                 dict(shape="box", z=-0.9, size_x=5.0, size_y=5.0, size_z=0.1),
                                 dict(shape="plane", z=-0.95, normal_z=1.0),
                                 dict(shape="cylinder", x=-3.0, y=2.0, radius=1.0, height=4.0)])
def test_a_collider_the_cloth_never_reaches_changes_nothing(far):
    """A towel dropped into water with a collider it never comes near: the run equals the run without
    it bit for bit (the contact only touches particles within thickness/2, the holding only those)."""
    base = dict(nx=9, ny=9, initial_height=0.1)
    plain = wetcloth.Simulation(load_scene(**base))
    with_far = wetcloth.Simulation(load_scene(**base, colliders=(far,)))
    for sim in (plain, with_far):
        sim.advance(1.5)
    np.testing.assert_array_equal(with_far.state.pos, plain.state.pos)
    np.testing.assert_array_equal(with_far.state.vel, plain.state.vel)
    assert with_far.steps == plain.steps


def _on_incline(angle_deg: float, friction: float, integrator: str = "bdf2", above: float = 1e-6, **fields):
    """A small sheet lying on a plane collider inclined by angle_deg about x, `above` (m; 1 micrometre) above
    its contact distance, in air without drag (air_density 0: only gravity and the plane act); other scene
    fields as given."""
    t = math.radians(angle_deg)
    normal = np.array([0.0, -math.sin(t), math.cos(t)])
    thickness, height = 0.002, 0.3
    point = np.array([0.0, 0.0, height]) - (0.5 * thickness + above) * normal
    plane = dict(shape="plane", x=point[0], y=point[1], z=point[2], normal_x=normal[0], normal_y=normal[1],
                 normal_z=normal[2], friction=friction)
    scene = load_scene(nx=5, ny=5, width=0.1, length=0.1, initial_tilt=angle_deg, initial_height=height,
                       thickness=thickness, water_level=-0.5, air_density=0.0, integrator=integrator,
                       colliders=(plane,), **fields)
    return wetcloth.Simulation(scene)


@pytest.mark.parametrize("angle", [15.0, 30.0])
def test_a_sheet_on_an_incline_stays_with_friction_at_or_above_tan_angle_and_slides_below(angle):
    """Coulomb: on a plane inclined by a, gravity pulls along it with g sin a and presses with g cos a,
    so friction >= tan a holds the sheet: it moves less than 0.01 mm in 1 s (the 1 um landing: 1.1 and
    1.4 um measured).  Friction 0.8 tan a lets it slide with (1 - 0.8) g sin a, 0.1 g sin a t^2 in t s:
    implicit Euler, BDF2 and symplectic Euler give that within 1 % (the first step's landing; measured
    0.13 %, -0.21 % and 0.1 % at 15 degrees, BDF2 in 23 adaptive steps with friction in the step).  (Before the contact kept the history along the plane, BDF2 slid 0.67 of
    it: its velocity update was 2/3 of the acceleration.)"""
    mu = math.tan(math.radians(angle))
    stays = _on_incline(angle, 1.001 * mu)
    start = stays.state.pos.copy()
    stays.advance(1.0)
    assert np.abs(stays.state.pos - start).max() < 1e-5
    t = math.radians(angle)
    downhill = np.array([0.0, -math.cos(t), -math.sin(t)])
    expected = 0.5 * 0.2 * 9.81 * math.sin(t) * 1.0 ** 2
    for integrator in ("implicit_euler", "bdf2", "symplectic_euler"):
        slides = _on_incline(angle, 0.8 * mu, integrator)
        start = slides.state.pos.copy()
        slides.advance(1.0)
        moved = downhill @ (slides.state.pos - start).mean(axis=1)
        assert 0.99 * expected < moved < 1.01 * expected, integrator


@pytest.mark.parametrize("above", [0.0, 1e-6, 2e-5])
@pytest.mark.parametrize("integrator, scheme, within", [("bdf2", 1.0, 0.02), ("implicit_euler", 31 / 30, 0.005)])
def test_a_sheet_landing_on_an_incline_at_frame_steps_has_friction_in_its_first_step(integrator, scheme, within,
                                                                                      above):
    """The sheet of the test above, on the plane of friction 0.8 tan 15 deg or 1 or 20 um above it, at fixed
    1/30 s steps, slides 0.1 g sin a t^2 in 1 s only if it slides with friction from the first step.  20 um above,
    beyond colliders.hpp's FRAME_TOUCH_SLACK, it lands within the first step on the plane's support (no normal force
    at the step's start, lag_arriving_normal_force): landed frictionless it kept g sin a h along the plane, 1.39x
    under BDF2 (its history carried it on), 1.22x under implicit Euler.  On the plane or 1 um above it touches it at
    rest: held there, its slip made at the step's end moved each particle as if alone against its springs, and the
    sheet slid nothing in the first step (-6.5 % from 31/30); its slip is now seen at the step's start, and it
    slides in the sliding set from there.  Implicit Euler moves each step with the velocity at its end, n (n + 1) /
    2 against n^2 / 2 steps' worth of a h^2: 31/30 of the slide at 30 steps.  Tolerances: BDF2's first step is
    backward Euler's, an error of order h^2 a in the slide (2 % at most; 0.2 % measured); implicit Euler's landing
    within its first step, 20 um of a 0.25 m slide, 0.5 % with room.  Until descent's line search stopped creeping
    toward the support met within the step (implicit.cpp, line_search), the first step ended on the support
    without sliding, one step late: -3.3 % from 31/30."""
    t = math.radians(15.0)
    sim = _on_incline(15.0, 0.8 * math.tan(t), integrator, above, tolerance=0.0, max_step=1 / 30)
    start = sim.state.pos.copy()
    sim.advance(1.0)
    moved = np.array([0.0, -math.cos(t), -math.sin(t)]) @ (sim.state.pos - start).mean(axis=1)
    expected = 0.1 * 9.81 * math.sin(t) * scheme
    assert abs(moved / expected - 1.0) < within, moved / expected - 1.0


@pytest.mark.parametrize("integrator", ["bdf2", "implicit_euler"])
@pytest.mark.parametrize("surface", ["incline", "box top"])
def test_a_sheet_pushed_along_a_collider_stops_after_coulombs_distance(surface, integrator):
    """As on the floor (tests/test_floor.py): a sheet lying still on a plane inclined by 20 degrees
    (friction 0.6 > tan 20 deg), pushed downhill at 0.5 m/s, stops after ``v0^2 / (2 a)`` with
    ``a = g (0.6 cos 20 - sin 20)`` (5.7 cm); on a box's top (friction 0.3), pushed along x, after
    ``v0^2 / (2 mu g)``; each as the scheme's update predicts (support.sliding).  The inclined
    plane checks that only the history along the collider's normal is replaced, whatever its direction."""
    if surface == "incline":
        sim = _on_incline(20.0, 0.6, integrator, tolerance=0.0, max_step=STEP)
        t = math.radians(20.0)
        direction, normal, mu = (0.0, -math.cos(t), -math.sin(t)), (0.0, -math.sin(t), math.cos(t)), 0.6
    else:
        box = dict(shape="box", size_x=0.4, size_y=0.4, size_z=0.2, z=0.1 - 0.001 - 1e-6, friction=0.3)
        sim = wetcloth.Simulation(load_scene(nx=5, ny=5, width=0.1, length=0.1, initial_tilt=0.0,
                                             initial_height=0.2, thickness=0.002, water_level=-0.5,
                                             air_density=0.0, integrator=integrator, tolerance=0.0,
                                             max_step=STEP, colliders=(box,)))
        direction, normal, mu = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.3
    sim.advance(0.1)  # lands (1 um) and is held
    assert_slides_coulomb_distance(sim, direction, normal, mu)


def test_collider_fields_are_addressed_by_one_name_each():
    """collider<k>_<field> in load_scene overrides, --set text and Scene.replace; to_dict flattens them."""
    scene = load_scene(**SHEET, initial_height=0.2, colliders=(dict(shape="sphere", radius=0.1),))
    assert scene.to_dict()["collider1_radius"] == 0.1
    assert scene.replace(collider1_radius=0.12).colliders[0].radius == 0.12
    assert parse_text("collider1_radius", "0.05") == 0.05
    added = scene.replace(collider2_shape="box", collider2_x=2.0)
    assert [c.shape for c in added.colliders] == ["sphere", "box"] and added.colliders[1].x == 2.0


@pytest.mark.parametrize("colliders, name, words", [
    ((dict(shape="cone"),), "collider1_shape", "one of 'plane', 'box', 'sphere', 'cylinder'"),
    ((dict(shape="sphere", radius=0.0),), "collider1_radius", "0 < collider1_radius <= 10000 m"),
    ((dict(shape="sphere", z=-2.0), dict(shape="cylinder", height=-1.0)), "collider2_height",
     "0 < collider2_height <= 10000 m"),
    ((dict(shape="sphere", radiuss=0.1),), "collider1_radiuss", "unknown collider field; did you mean 'collider1_radius'?"),
    ((dict(shape="sphere", colour=0.1),), "collider1_colour", "unknown collider field; a collider's fields are "
     "collider<k>_<field> (k = 1, 2, ...) with <field> one of shape, file, x"),
    ((dict(shape="sphere", z=0.1, radius=0.05),), "collider1", "overlaps the cloth at t = 0"),
    ((dict(shape="plane", normal_z=0.0),), "collider1_normal_z", "normal is zero"),
])
def test_bad_colliders_are_named_with_their_allowed_range(colliders, name, words):
    with pytest.raises(ParameterError) as info:
        load_scene(**SHEET, initial_height=0.1, colliders=colliders)
    assert name in str(info.value) and words in str(info.value)


def test_a_scene_file_with_collider_tables(tmp_path):
    """[[collider]] tables read in order as collider1, collider2; a mistake names the file and the field."""
    path = tmp_path / "scene.toml"
    path.write_text('initial_height = 0.3\n[[collider]]\nshape = "sphere"\nradius = 0.1\n'
                    '[[collider]]\nshape = "box"\nx = 2.0\n')
    scene = load_scene(path, collider2_size_z=0.5)
    assert [c.shape for c in scene.colliders] == ["sphere", "box"] and scene.colliders[1].size_z == 0.5
    path.write_text('[[collider]]\nshape = "sphere"\nradius = -1\n')
    with pytest.raises(ConfigError, match="collider1_radius"):
        load_scene(path)


def test_the_tablecloth_preset_has_its_sphere():
    scene = load_scene("tablecloth_sphere")
    assert [c.shape for c in scene.colliders] == ["sphere"]
    assert scene.to_dict()["collider1_radius"] == 0.3


def test_a_horizontal_plane_collider_acts_as_the_floor():
    """A tilted sheet dropped in air onto a plane collider at z = -0.1 m lands, slides and comes to rest
    as on a floor at the same level with the same friction (the floor moved out of the way): the same
    rule (projection, impulse, holding at rest), so the same steps and positions; asserted to 1e-12 m,
    the rounding of the two ways of computing the contact height."""
    base = dict(nx=15, ny=15, width=0.4, length=0.4, initial_tilt=20.0, water_level=-0.9, initial_height=0.1)
    floor = wetcloth.Simulation(load_scene(**base, floor_level=-0.1))
    plane = wetcloth.Simulation(load_scene(**base, floor_level=-0.5,
                                           colliders=(dict(shape="plane", z=-0.1, friction=0.5),)))
    for sim in (floor, plane):
        sim.advance(3.0)
    assert floor.sleeping and plane.sleeping
    np.testing.assert_allclose(plane.state.pos, floor.state.pos, rtol=0, atol=1e-12)
    assert plane.steps == floor.steps


def test_params_and_study_axes_know_the_collider_names():
    """``wetcloth params SCENE`` lists every field of the scene's colliders; a study may vary them."""
    from wetcloth.batch.axes import check_name, typed
    from wetcloth.commands.params import rows

    listed = {r["name"]: r for r in rows("tablecloth_sphere")}
    assert listed["collider1_radius"]["value"] == 0.3 and listed["collider1_height"]["value"] == 0.1
    assert "0 < collider1_radius <= 10000 m" == listed["collider1_radius"]["range"]
    check_name("collider1_radius", "axes")
    assert typed("collider1_radius", 1, "axes") == 1.0
