"""The default settings meet 1 mm of centroid error and 1e-3 of wet-mass error on the reference scenes,
and the tolerance controls the error.

The references are computed in this process (no arrays from another CPU): BDF2 with fixed steps of
2.5e-4 s (``support.accuracy.reference``); halving that step moves their centroids by 6-27 um and
their wet mass by up to 1.8e-4 (docs/benchmarks.md, Method), so they are converged
well below what is asked of the defaults (``test_the_sinking_reference_is_converged``).
"""

import pytest

import wetcloth
from support.accuracy import REFERENCE_STEP, cases, errors, reference, simulate

DEFAULTS = wetcloth.Scene()
CASES = {case.name: case for case in cases()}


@pytest.fixture(scope="session")
def references():
    return {name: reference(case) for name, case in CASES.items()}


@pytest.mark.parametrize("name", list(CASES))
def test_default_settings_are_within_a_millimetre_of_the_reference(name, references):
    run = simulate(CASES[name], integrator=DEFAULTS.integrator, tolerance=DEFAULTS.tolerance,
                   max_step=DEFAULTS.max_step)
    err = errors(run, references[name])
    assert err["centroid_error"] < 1e-3, err
    assert err["vertex_rms_error"] < 1e-3, err
    assert err["wet_mass_error"] < 1e-3, err


def test_a_tighter_tolerance_gives_a_smaller_error(references):
    """BDF2's error estimate is real: a tenfold tighter tolerance cuts the landing's centroid error
    several times over (third-order local error: about 10^(2/3) = 4.6 times in the limit)."""
    case = CASES["landing"]
    loose, tight = (errors(simulate(case, integrator="bdf2", tolerance=tol, max_step=0.1), references["landing"])
                    for tol in (1e-4, 1e-5))
    assert tight["centroid_error"] < loose["centroid_error"] / 3, (loose, tight)


def test_a_coarse_fixed_step_is_measurably_worse(references):
    """The comparison can fail: implicit Euler with 10 ms steps misses the landing by centimetres."""
    run = simulate(CASES["landing"], integrator="implicit_euler", tolerance=0.0, max_step=0.01)
    assert errors(run, references["landing"])["centroid_error"] > 5e-3


def test_the_sinking_reference_is_converged(references):
    """The errors above mean something only if the reference's own error is well below the bounds:
    halving its step moves the sinking scene (its hardest: the impact, the uptake) by at most a
    tenth of the centroid bound and a quarter of the wet-mass bound (measured 27 um and 1.8e-4; with
    its Newton corrections solved to 1e-1 instead of 1e-2 the centroid moved 0.17 mm)."""
    halved = reference(CASES["sinking"], step=REFERENCE_STEP / 2)
    err = errors(references["sinking"], halved)
    assert err["centroid_error"] < 1e-4, err
    assert err["wet_mass_error"] < 2.5e-4, err
