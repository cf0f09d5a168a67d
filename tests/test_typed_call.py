"""``TypedCall``: a kernel called from Python without numba's per-call typing gives what the
dispatcher gives, and finds its compiled code again when the arguments change."""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from wetcloth.kernels.compilation import TypedCall, compile_kernel

Bundle = namedtuple("Bundle", "values weights")


def _weighted_sum(bundle, scale, count):
    total = 0.0
    for i in range(count):
        total += bundle.values[i] * bundle.weights[i]
    return scale * total


weighted_sum = compile_kernel(_weighted_sum, dict(nopython=True))


def test_same_objects_reuse_the_compiled_code_and_see_their_new_contents():
    call = TypedCall(weighted_sum)
    bundle = Bundle(np.arange(4.0), np.ones(4))
    assert call(bundle, 2.0, 4) == 12.0
    bundle.values[:] = 1.0  # same object, new contents
    assert call(bundle, 0.5, 3) == 1.5
    assert call._entry_point is not None


def test_other_objects_or_number_types_find_their_own_compiled_code():
    call = TypedCall(weighted_sum)
    assert call(Bundle(np.arange(3.0), np.ones(3)), 1.0, 3) == 3.0
    integers = Bundle(np.arange(3), np.full(3, 2))  # int64 arrays: another signature
    assert call(integers, 1.0, 3) == 6.0
    assert call(integers, 1, 3) == 6.0  # an int where a float was: typed again
    assert len(weighted_sum.overloads) >= 3


def test_new_objects_of_the_same_types_reuse_the_compiled_code():
    """A new bundle of arrays of the same kinds (as ``Simulation.sample``'s time arrays are at each
    call) is typed, and runs the compiled code found for the first."""
    call = TypedCall(weighted_sum)
    assert call(Bundle(np.arange(3.0), np.ones(3)), 1.0, 3) == 3.0
    entry_point, overloads = call._entry_point, len(weighted_sum.overloads)
    assert call(Bundle(np.arange(5.0), np.full(5, 2.0)), 1.0, 5) == 20.0
    assert call._entry_point is entry_point and len(weighted_sum.overloads) == overloads
