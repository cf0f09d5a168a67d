"""A layer of cloth lying on another on a slope (docs/model.md section 6.2): it stays within the layers' friction and
slides without it, whether the layer under it is pinned or lies on a plane collider whose friction holds it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.layers import stack_scene

import wetcloth
from wetcloth._core import GRAVITY

ANGLE = 15.0  # deg
DURATION = 0.2  # s
FRAME = 1 / 30  # s
FRAME_STEPS = dict(integrator="implicit_euler", tolerance=0.0, max_step=FRAME)


def _slides(self_friction: float, held_by: str, **settings) -> tuple[wetcloth.Simulation, np.ndarray, np.ndarray]:
    """The two sheets of support.layers run DURATION s: the simulation and each particle's slide downhill (m),
    the large sheet's, then the small sheet's."""
    scene, large, downhill = stack_scene(ANGLE, self_friction, held_by, **settings)
    sim = wetcloth.Simulation(scene)
    start = sim.positions.copy()
    sim.advance(DURATION)
    slide = (sim.positions - start) @ downhill
    return sim, slide[:large], slide[large:]


@pytest.mark.parametrize("held_by", ["pins", "plane"])
@pytest.mark.parametrize("settings", [{}, FRAME_STEPS], ids=["default", "frame_steps"])
def test_a_layer_within_friction_stays_on_the_layer_under_it(held_by, settings):
    """At self_friction 1.001 tan a neither sheet moves: under 0.01 mm in 0.2 s (Coulomb: not at all; 0.002 mm
    measured, what the layers' stick lets creep).  At frame steps on the plane both slid before the layer under the
    top one was held on the plane (colliders.hpp, FRAME_TOUCH_SLACK) and the candidate list was built before the
    first step: the top one 1.4 mm, the bottom one 0.8 mm."""
    _, large, small = _slides(1.001 * math.tan(math.radians(ANGLE)), held_by, **settings)
    assert np.abs(small).max() < 1e-5
    assert np.abs(large).max() < 1e-5


def test_a_frictionless_layer_slides_off_a_plane_held_layer_as_backward_euler_frames():
    """Frictionless, the top sheet slides as one body at g sin a, and backward Euler's frame steps move it
    a h^2 n (n + 1) / 2 in n steps (each step with the velocity at its end, k a h): within 1 % (0.07 % measured).
    The bottom sheet stays on its plane of friction 5 (under 0.01 mm).  Before, it hovered a micrometre above the
    plane, never held, and slid 2.2 mm in one frame, and the plane's friction, met by the first iterate of a
    frame's solve through the bottom sheet, held the top one: 0.24 of the slide (colliders.hpp FRAME_TOUCH_SLACK,
    collider_supports.hpp drop_departed)."""
    sim, large, small = _slides(0.0, "plane", **FRAME_STEPS)
    steps = round(DURATION / FRAME)
    assert (sim.steps, sim.rejected_steps) == (steps, 0)
    acceleration = GRAVITY * math.sin(math.radians(ANGLE))
    expected = acceleration * FRAME**2 * steps * (steps + 1) / 2
    assert small.mean() == pytest.approx(expected, rel=0.01)
    assert np.ptp(small) < 0.01 * expected  # as one body
    assert np.abs(large).max() < 1e-5


@pytest.mark.parametrize("held_by", ["pins", "plane"])
def test_a_frictionless_layer_slides_off_the_layer_under_it_by_default(held_by):
    """The default (BDF2, adaptive): the top sheet slides g sin a t^2 / 2 within 5 %: the self-collision stage's
    inelastic pushes, where its edges pass over the bottom sheet's, take 1.3 % (pinned) and 2.9 % (on the plane)
    of it.  On the plane it took 22 % while the stage still pushed the plane's particles into it (each push
    carried the bottom layer into the plane and back: 3-8 times the pushes; self_contact/response.hpp)."""
    _, large, small = _slides(0.0, held_by)
    expected = 0.5 * GRAVITY * math.sin(math.radians(ANGLE)) * DURATION**2
    assert small.mean() == pytest.approx(expected, rel=0.05)
    assert np.abs(large).max() < 1e-5


@pytest.mark.parametrize("held_by", ["pins", "plane"])
def test_a_layer_below_its_friction_slides_at_coulombs_acceleration_at_frame_steps(held_by):
    """At self_friction 0.9 tan a the top sheet accelerates at (1 - 0.9) g sin a: from the end of its third frame to
    that of its tenth its velocity along the slope grows by 7 frames' worth of it, within 5 % (the frames' gains
    scatter by 10 % as its edges pass over the bottom sheet's; over the 7, -0.6 % pinned and -2.4 % on the plane
    measured).  Its first two frames, where the layers meet (the stage's landing: the scene starts them 1 um
    apart), are left out.  Before the layers' normal forces were taken again within the step (collider_supports.hpp,
    relag_self_normal_force) it stopped in its eighth frame, as its edges passed over the bottom sheet's and the
    pairs' lagged normal forces summed to 1.25 times its weight."""
    scene, large, downhill = stack_scene(ANGLE, 0.9 * math.tan(math.radians(ANGLE)), held_by, **FRAME_STEPS)
    sim = wetcloth.Simulation(scene)
    speeds = []
    for _ in range(10):
        sim.advance(FRAME)
        speeds.append((sim.velocities[large:] @ downhill).mean())
    coulomb = 0.1 * GRAVITY * math.sin(math.radians(ANGLE)) * 7 * FRAME
    assert speeds[9] - speeds[2] == pytest.approx(coulomb, rel=0.05)
