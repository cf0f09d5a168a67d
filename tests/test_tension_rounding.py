"""The rounded onset of tension-only springs (docs/model.md section 3): no force when compressed
or at rest length, the thesis law beyond a strain of TENSION_ROUNDING, and between them a pull
that is weaker by at most ``4 w / 27`` and whose slope is continuous and never negative."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from wetcloth._core import TENSION_ROUNDING, pulling_stretch

REST = 0.025  # m, a towel spring
WIDTH = TENSION_ROUNDING * REST


@given(st.floats(-1e3, 0.0))
def test_compressed_or_at_rest_it_does_not_pull(relative):
    assert pulling_stretch(relative * WIDTH, WIDTH) == (0.0, 0.0)


@given(st.floats(1.0, 1e3))
def test_beyond_the_rounding_the_thesis_law_holds_exactly(relative):
    stretch = relative * WIDTH
    assert pulling_stretch(stretch, WIDTH) == (stretch, 1.0)


@given(st.floats(0.0, 1.0))
def test_within_the_rounding_it_pulls_less_by_at_most_four_27ths_of_the_width(relative):
    stretch = relative * WIDTH
    value, slope = pulling_stretch(stretch, WIDTH)
    assert stretch - 4 * WIDTH / 27 * (1 + 1e-12) <= value <= stretch
    assert 0.0 <= slope <= 4.0 / 3.0 * (1 + 1e-12)  # the cubic's steepest slope, at 2w/3


def test_value_and_slope_are_continuous_and_the_slope_is_the_derivative():
    """At both joins the two sides agree to round-off; inside, the slope equals the central
    difference of the value (a cubic: the difference errs by step^2 / w^2 ~ 1e-6)."""
    for join in (0.0, WIDTH):
        below, above = pulling_stretch(join - 1e-12 * WIDTH, WIDTH), pulling_stretch(join + 1e-12 * WIDTH, WIDTH)
        assert abs(above[0] - below[0]) <= 1e-11 * WIDTH
        assert abs(above[1] - below[1]) <= 1e-11
    step = 1e-3 * WIDTH
    for k in range(1, 20):
        stretch = k / 20 * WIDTH
        difference = (pulling_stretch(stretch + step, WIDTH)[0] - pulling_stretch(stretch - step, WIDTH)[0]) / (2 * step)
        assert abs(difference - pulling_stretch(stretch, WIDTH)[1]) <= 1e-5
