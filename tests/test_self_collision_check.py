"""The self-collision list's check keeps its windows' fits at the end of the step it checked and reuses them
for the next step, which starts there (tiers.hpp, StepFits): it must decide exactly as a check that fits both
ends afresh."""

from __future__ import annotations

import numpy as np

import wetcloth
from wetcloth import _core
from support.hanging import HANGING


def swinging_states() -> tuple[wetcloth.Simulation, list[np.ndarray]]:
    """A 21 x 21 sheet hanging from one edge, released horizontal: its positions (3, n) m at 0.20, 0.21 and
    0.22 s (it swings down, turns and bends, so the check looks at its windows, not only at a translation)."""
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=21, ny=21, **HANGING))
    states = []
    for duration in (0.2, 0.01, 0.01):
        sim.advance(duration)
        states.append(sim.state.pos.copy())
    return sim, states


def test_a_check_starting_where_the_last_ended_decides_as_a_fresh_one():
    """The list is built (the widest margin that keeps it empty) at the midpoint of the motion from the first
    state to the second; the next motion runs from the second state to the third moved on by a factor f of
    its own motion.  The largest f for which the list holds (bisected to 1e-12), once right after a check of
    the first motion (which ended where the next starts: its fits are reused) and once after a check that
    ended elsewhere (both ends fitted afresh), must be the same number: the reused fits are the same figures
    bit for bit.  It must lie within the bisection's range (1, the third state, to 200), so the check is made
    at its limit and both answers occur."""
    sim, (x0, x1, x2) = swinging_states()
    contact, thickness = sim._contact, sim.scene.thickness
    widest = max(contact.least_margin, 0.5 * (_core.WIDE_REACH * contact.rest_gap - thickness))
    contact.reference[...] = 0.5 * (x0 + x1)
    lists = _core.ContactState()
    _core.build_widest(contact, thickness, contact.least_margin, widest, lists=lists)
    assert _core.covers(contact, x0, x1, lists=lists)

    def holds(f: float, reused: bool) -> bool:
        if reused:
            _core.covers(contact, x0, x1, lists=lists)  # ends at x1, where the next motion starts
        else:
            _core.covers(contact, x1, x0, lists=lists)  # ends elsewhere
        return _core.covers(contact, x1, x1 + f * (x2 - x1), lists=lists)

    limits = []
    for reused in (True, False):
        low, high = 1.0, 200.0
        assert holds(low, reused) and not holds(high, reused)
        while high - low > 1e-12 * high:
            middle = 0.5 * (low + high)
            low, high = (middle, high) if holds(middle, reused) else (low, middle)
        limits.append(low)
    assert limits[0] == limits[1], limits


def test_lists_kept_from_one_rest_sheet_cut_the_tiers_again_for_another():
    """The tiers are cut from the rest sheet once and kept (prepare_tiers compares the rest positions, triangles
    and edges bit for bit), and the far pairs' search keeps each tier's cells' elements with them.  Lists that
    served one rest sheet, given another (the same grid stretched along x, the more the farther out: x + x^2
    from its side, so that particles change cells), must find the same allowances and fine cells as fresh
    lists; those differ from the first sheet's, so kept tiers would show."""
    sim, (x0, x1, _) = swinging_states()
    first, thickness = sim._contact, sim.scene.thickness
    rest = first.rest.copy()
    rest[0] += (rest[0] - rest[0].min()) ** 2
    second = first._replace(rest=rest)
    n = first.rest.shape[1]
    first.reference[...] = 0.5 * (x0 + x1)

    def built(contact, lists):
        widest = max(contact.least_margin, 0.5 * (_core.WIDE_REACH * contact.rest_gap - thickness))
        _core.build_widest(contact, thickness, contact.least_margin, widest, lists=lists)
        return list(lists.allowances), list(lists.fine_cells(n))

    kept = _core.ContactState()
    on_first = built(first, kept)
    on_second_kept = built(second, kept)
    on_second_fresh = built(second, _core.ContactState())
    assert on_second_kept == on_second_fresh
    assert on_second_fresh != on_first


def test_a_window_bent_into_an_arc_deviates_by_half_the_range_of_its_offsets():
    """A 6 x 6 sheet (5 cm spacing) is one window of the finest tier (two cells of three spacings each way).
    Bent about an axis along x into an arc of radius 1 m, symmetric about its middle row, it keeps its frame
    (the rotation is the identity), so each particle's offset from its flat place is (0, R sin(v/R) - v,
    R (1 - cos(v/R))) for its distance v along y from the middle.  The window's deviation must be half the
    diagonal of the box around those offsets, within 1e-12 m (the window's sums and frames round positions of
    about a metre: some 1e-14 m): the translation to the box's centre.  The centroids' translation left the farthest offset from
    their mean, 11 % more here (on a continuous arc, two thirds of the sagitta against a half)."""
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=6, ny=6, width=0.25, length=0.25, initial_tilt=0.0))
    contact = sim._contact
    flat = sim.state.pos.copy()  # (3, n), horizontal
    contact.reference[...] = flat
    lists = _core.ContactState()
    _core.build(contact, sim.scene.thickness, contact.least_margin, lists=lists)
    radius = 1.0
    v = flat[1] - flat[1].mean()
    offsets = np.stack([np.zeros_like(v), radius * np.sin(v / radius) - v, radius * (1.0 - np.cos(v / radius))])
    bent = flat + offsets
    expected = 0.5 * np.linalg.norm(np.ptp(offsets, axis=1))
    from_mean = np.linalg.norm(offsets - offsets.mean(axis=1, keepdims=True), axis=0).max()
    deviation = _core.deviation(contact, 0, flat, bent, lists=lists)
    assert abs(deviation - expected) <= 1e-12, (deviation, expected)
    assert from_mean > 1.1 * expected, (from_mean, expected)
