"""Keys that carry a pinned particle into a collider are refused at validation (wetcloth.pinned_paths).

The scenes are the ``sweep`` preset's towel, hanging in the x-z plane (y = 0) from its pinned top row at
z = 0.85 m, x from -0.25 to 0.25 m.
"""

import re

import pytest
import trimesh

import wetcloth
from wetcloth.errors import ParameterError
from wetcloth.scene import Collider, ColliderKey, GripKey

TOP = 0.85  # m: the pinned row's height


def sweep(collider: Collider, *keys) -> wetcloth.Scene:
    """The sweep preset with ``collider`` instead of its ball and these keys (collider keys or grip keys)."""
    return wetcloth.load_scene("sweep").replace(
        colliders=(collider,), collider_keys=tuple(k for k in keys if isinstance(k, ColliderKey)),
        grip_keys=tuple(k for k in keys if isinstance(k, GripKey)))


def refusal(collider: Collider, *keys) -> ParameterError:
    with pytest.raises(ParameterError) as caught:
        sweep(collider, *keys)
    return caught.value


def reported(error: ParameterError) -> tuple[float, float]:
    """The time (s) the message says a pinned particle enters, and its greatest depth seen (m)."""
    found = re.search(r"from t = ([0-9.e+-]+) s, at least ([0-9.e+-]+) m deep", str(error))
    assert found, str(error)
    return float(found.group(1)), float(found.group(2))


def found_within(t: float, enters: float, late: float) -> bool:
    """Whether the reported time t (s, 4 digits) is the time a pinned particle enters, or at most ``late`` s
    after it (the check may see it only once it is half the thickness of motion in)."""
    digits = 5e-4
    return enters - digits <= t <= enters + late * (1 + 1e-6) + digits


def test_a_plane_keyed_through_the_pinned_edge_is_refused_when_it_reaches_it():
    """A half-space y < -0.3 + 0.6 t (its face's normal +y) keyed 0.6 m in 1 s reaches the pinned row (y = 0) at
    t = 0.5 s and ends 0.3 m beyond it."""
    scene = wetcloth.load_scene("sweep")
    plane = Collider(shape="plane", x=0.0, y=-0.3, z=0.35, normal_x=0.0, normal_y=1.0, normal_z=0.0)
    error = refusal(plane, ColliderKey(collider=1, time=1.0, y=0.6))
    assert error.name == "collider_key1"
    assert "pinned particle" in str(error) and "allowed: keys that keep every pinned particle outside" in str(error)
    t, depth = reported(error)
    sample = 0.5 * scene.thickness / 0.6  # s between samples
    assert found_within(t, 0.5, sample)
    assert depth == pytest.approx(0.3, rel=2e-3)  # (3 digits)


def found_within(t: float, enters: float, late: float) -> bool:
    """Whether the reported time t (s, 4 digits) is the time a pinned particle enters, or at most ``late`` s
    after it (the check may see it only once it is half the thickness of motion in)."""
    digits = 5e-4
    return enters - digits <= t <= enters + late * (1 + 1e-6) + digits


def test_a_plane_keyed_to_stop_short_of_the_pinned_edge_is_accepted():
    plane = Collider(shape="plane", x=0.0, y=-0.3, z=0.35, normal_x=0.0, normal_y=1.0, normal_z=0.0)
    sweep(plane, ColliderKey(collider=1, time=1.0, y=0.29))  # its face stops 1 cm before the pinned row


def ball(shape: str, z: float, folder) -> Collider:
    """A ball of 0.12 m radius at (-0.6, 0, z) m: a sphere, or a closed mesh (an icosphere of 642 vertices,
    within 1 mm of the sphere)."""
    if shape == "sphere":
        return Collider(shape="sphere", x=-0.6, y=0.0, z=z, radius=0.12)
    path = folder / "ball.ply"
    trimesh.creation.icosphere(subdivisions=3, radius=0.12).export(path)
    return Collider(shape="mesh", file=str(path), x=-0.6, y=0.0, z=z)


@pytest.mark.parametrize("shape", ["sphere", "mesh"])
@pytest.mark.parametrize("clearance, refused", [(-0.005, True), (0.005, False)])
def test_a_ball_passing_over_the_pinned_row_between_its_keys(shape, clearance, refused, tmp_path):
    """A 0.12 m ball keyed along x from x = -0.6 to 0.6 m, its bottom 5 mm below (or above) the pinned row:
    outside the towel at both keys, so only the samples between them can find it."""
    ball_ = ball(shape, TOP + 0.12 + clearance, tmp_path)
    key = ColliderKey(collider=1, time=1.0, x=1.2)
    if not refused:
        sweep(ball_, key)
        return
    error = refusal(ball_, key)
    assert error.name == "collider_key1"
    t, depth = reported(error)
    # The first pinned particle it reaches is the row's end at x = -0.25: the ball's centre is then within
    # sqrt(0.12^2 - 0.115^2) of it in x, at 1.2 m/s; the deepest is 5 mm, under a particle's own x.
    enters = (-0.25 - (0.12**2 - 0.115**2) ** 0.5 + 0.6) / 1.2
    assert found_within(t, enters, 0.5 * wetcloth.load_scene("sweep").thickness / 1.2)
    assert depth <= 0.005 * (1 + 1e-3) and depth > 0.004  # (the icosphere's faces lie up to 0.5 mm inside)


def test_a_stick_turned_through_the_pinned_row_is_refused_though_both_keys_are_clear():
    """A 0.6 m stick (a thin box) 0.2 m in front of the towel at the pinned row's height, turned 170 deg about
    z: half way its end sweeps through the row (its circle of radius 0.3 m about (0, 0.2) crosses y = 0 at
    x = +-0.224 m), and at both keys it lies along x, clear of the towel."""
    stick = Collider(shape="box", x=0.0, y=0.2, z=TOP, size_x=0.6, size_y=0.02, size_z=0.02)
    error = refusal(stick, ColliderKey(collider=1, time=1.0, rz=170.0))
    assert error.name == "collider_key1"
    assert 0.0 < reported(error)[0] < 1.0


def test_a_grip_keyed_into_a_still_ball_is_refused_naming_its_key():
    """The grip lifts the pinned row 0.3 m in 1 s (then 0.6 m by 2 s) into a still ball whose bottom is at
    0.98 m: the row enters at t = 0.13 / 0.3 s."""
    ball = Collider(shape="sphere", x=0.0, y=0.0, z=1.1, radius=0.12)
    error = refusal(ball, GripKey(time=1.0, z=0.3), GripKey(time=2.0, z=0.6))
    assert error.name == "grip_key1"
    t, _ = reported(error)
    assert found_within(t, 0.13 / 0.3, 0.5 * wetcloth.load_scene("sweep").thickness / 0.3)


def test_an_open_mesh_is_not_checked(tmp_path):
    """A shell has no inside: a square sheet collider keyed through the pinned row is accepted (its edges'
    pass keeps the free cloth off it)."""
    mesh = tmp_path / "square.obj"
    mesh.write_text("v -1 -0.3 0\nv 1 -0.3 0\nv 1 -0.3 2\nv -1 -0.3 2\nf 1 2 3\nf 1 3 4\n")
    sheet = Collider(shape="mesh", file=str(mesh))
    sweep(sheet, ColliderKey(collider=1, time=1.0, y=0.6))
