"""Stability under stress: the adaptive mode never blows up, and random valid scenes stay physical."""

import itertools

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import wetcloth
from wetcloth.scene import PARAMETERS
from support.stress import stress_run

BASE = dict(nx=7, ny=7)
DURATION = 0.3  # s: landing, the water jump at 0.15 s, and what follows


@pytest.mark.parametrize("integrator, stiffnesses", [
    # Explicit Euler needs h < damping / stiffness: 2e-7 s at 1e6 N/m, 1.7 million steps for 0.3 s
    # (18 s a run); bench/stability.py covers it, the suite stops at 1e4 N/m.
    ("explicit_euler", [1e1, 1e4]),
    ("symplectic_euler", [1e1, 1e4, 1e6]),
    ("implicit_euler", [1e1, 1e4, 1e6]),
    ("bdf2", [1e1, 1e4, 1e6]),
])
def test_adaptive_mode_survives_the_stress_sweep(integrator, stiffnesses):
    """Stiffness 1e1..1e6 N/m, gauze to canvas, no to near-instant absorption, water jumping 5 cm
    up or down mid-run: every run finishes, within the energy bound, with non-decreasing wet mass."""
    failures = []
    for k, density, rate, jump in itertools.product(stiffnesses, [0.05, 5.0], [0.0, 1000.0],
                                                    [None, {0.15: 0.05}, {0.15: -0.05}]):
        scene = wetcloth.load_scene(**BASE, integrator=integrator, stretch_stiffness=k, areal_density=density,
                                    absorption_rate=rate)
        result = stress_run(scene, DURATION, water_levels=jump)
        if not result.stable or result.wet_mass_decreased:
            failures.append((k, density, rate, jump, result.reason))
    assert not failures


def test_fixed_steps_beyond_the_limit_are_caught_not_written():
    """The stress check itself can fail: explicit Euler with fixed steps 20x its limit is unstable.
    (At 10x, 1 ms, it sits on the edge: steps of 0.86 ms, which the equal division of an output
    interval into steps may give, let it pass.)"""
    scene = wetcloth.load_scene(**BASE, integrator="explicit_euler", tolerance=0.0, max_step=2e-3)
    result = stress_run(scene, DURATION)
    assert not result.stable and result.reason


def _bounded(name, lo=None, hi=None):
    f = PARAMETERS[name].metadata
    return st.floats(min_value=f["lo"] if lo is None else lo, max_value=f["hi"] if hi is None else hi,
                     exclude_min=f["lo_open"] and lo is None, allow_nan=False)


SCENES = st.fixed_dictionaries({
    "nx": st.integers(2, 6),
    "ny": st.integers(2, 6),
    "width": _bounded("width", 0.05, 2.0),
    "length": _bounded("length", 0.05, 2.0),
    "areal_density": _bounded("areal_density", 0.02, 5.0),
    "thickness": _bounded("thickness", 1e-4, 0.02),
    "stretch_stiffness": _bounded("stretch_stiffness", 10.0, 1e5),
    "bend_stiffness": _bounded("bend_stiffness", 0.0, 100.0),
    "damping": _bounded("damping", 0.0, 5.0),
    "damping_model": st.sampled_from(["projected", "thesis"]),
    "drag_model": st.sampled_from(["face", "stokes"]),
    "buoyancy_model": st.sampled_from(["smooth", "thesis"]),
    "absorption_capacity": _bounded("absorption_capacity", 0.0, 10.0),
    "absorption_rate": _bounded("absorption_rate", 0.0, 100.0),
    "initial_height": _bounded("initial_height", -0.3, 0.3),
    "initial_tilt": _bounded("initial_tilt"),
    # Explicit Euler is left out: with little damping it is unstable at any step (docs/model.md section 7 keeps it
    # as the thesis baseline only); the sweep above covers it with the default damping.
    "integrator": st.sampled_from(["symplectic_euler", "implicit_euler", "bdf2"]),
    "tolerance": _bounded("tolerance", 1e-5, 1e-2),
})


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(values=SCENES)
def test_random_valid_scenes_stay_finite_bounded_and_never_lose_water(values):
    """Any valid scene in the adaptive mode: finite state, kinetic energy within what the scene can
    release (support/stress.py), and wet mass never decreasing."""
    try:
        scene = wetcloth.load_scene(**values, floor_level=-1.5)
    except wetcloth.ParameterError:
        return  # e.g. a steep tilt starting below the floor: refused up front, as it should be
    result = stress_run(scene, 0.2, samples=20)
    assert result.stable, result.reason
    assert not result.wet_mass_decreased
