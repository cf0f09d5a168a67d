"""The default settings meet about 1 mm of centroid error on the reference scenes.

The references (tests/data/reference_trajectories.npz) are symplectic Euler with fixed 5 us steps,
written by ``bench/work_precision.py --reference-only``; halving that step moves their centroid
by under 5 um, so they are converged far below the 1 mm asked of the defaults.
"""

from pathlib import Path

import pytest

import wetcloth
from wetcloth.accuracy import cases, errors, load_reference, simulate

STORED = Path(__file__).parent / "data" / "reference_trajectories.npz"
DEFAULTS = wetcloth.Scene()


@pytest.mark.parametrize("case", cases(), ids=lambda c: c.name)
def test_default_settings_are_within_a_millimetre_of_the_reference(case):
    run = simulate(case, integrator=DEFAULTS.integrator, tolerance=DEFAULTS.tolerance, max_step=DEFAULTS.max_step)
    err = errors(run, load_reference(STORED, case.name))
    assert err["centroid_error"] < 1e-3, err
    assert err["vertex_rms_error"] < 1e-3, err
    assert err["wet_mass_error"] < 1e-2, err


def test_a_coarse_fixed_step_is_measurably_worse():
    """The comparison can fail: implicit Euler with 10 ms steps misses the landing by centimetres."""
    case = cases()[0]
    run = simulate(case, integrator="implicit_euler", tolerance=0.0, max_step=0.01)
    assert errors(run, load_reference(STORED, case.name))["centroid_error"] > 5e-3
