"""A candidate list is built without searching the windows of the finest tier shown to hold no pair
(self_contact/flat_windows.hpp: their projection onto the plane across their mean normal is one to one, and
their triangles' projected altitudes, or their least stretch times the rest sheet's gap, reach past the
search's reach).  Its lists must hold what a search of every pair finds: here the checker's own brute-force
distances (``close_pairs``), on sheets that swing, fold, curl, ripple or are squeezed."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import wetcloth
from wetcloth import _core
from test_self_collision import CURRENT_OVER_PIN, close_pairs, make_meshes

#: Pairs this close (m) to the list's reach are left out of the comparison: the core's distances and the
#: checker's round differently (both are exact to about 1e-16 m on positions of a metre).
BORDER = 1e-12


def grid_sheet(nx: int = 21, ny: int = 21) -> wetcloth.Simulation:
    """A flat, horizontal sheet of nx x ny particles, 1 m square (a spacing of 1/(nx - 1) m)."""
    return wetcloth.Simulation(wetcloth.load_scene(nx=nx, ny=ny, width=1.0, length=1.0, initial_tilt=0.0,
                                                   initial_height=0.5))


def diagonals_mesh(folder, side: int = 21) -> wetcloth.Simulation:
    """A flat, horizontal mesh of side x side points, 1 m square, its squares cut by alternating diagonals
    (a mesh, not the grid's families; convex, so its windows can be judged)."""
    i, j = np.meshgrid(np.arange(side), np.arange(side), indexing="ij")
    points = np.stack([i.ravel() / (side - 1), j.ravel() / (side - 1), np.zeros(side * side)], axis=1)
    triangles = []
    for a in range(side - 1):
        for b in range(side - 1):
            p, q, r, t = a * side + b, (a + 1) * side + b, (a + 1) * side + b + 1, a * side + b + 1
            triangles += [(p, q, r), (p, r, t)] if (a + b) % 2 else [(p, q, t), (q, r, t)]
    path = folder / "diagonals.ply"
    make_meshes.write(path, points, np.array(triangles))
    return wetcloth.Simulation(wetcloth.load_scene(cloth_mesh=str(path), place_mesh="on", initial_height=0.5))


def bent_along_y(flat: np.ndarray, shape) -> np.ndarray:
    """The flat sheet (3, n) with each row at distance s along y from the sheet's low edge moved to the point
    shape(s) = (y, z) (m): a sheet bent about lines along x."""
    out = flat.copy()
    s = flat[1] - flat[1].min()
    y, z = shape(s)
    out[1] = flat[1].min() + y
    out[2] = flat[2] + z
    return out


def hairpin(flat: np.ndarray, fold_at: float, radius: float) -> np.ndarray:
    """Folded back over itself about a half cylinder of `radius` (m) starting `fold_at` (m) along y: the part
    beyond it lies 2 radius above the part before."""
    def shape(s):
        arc = np.clip(s - fold_at, 0.0, np.pi * radius)
        beyond = np.maximum(s - fold_at - np.pi * radius, 0.0)
        y = np.minimum(s, fold_at) + radius * np.sin(arc / radius) - beyond
        z = radius * (1.0 - np.cos(arc / radius))
        return y, z
    return bent_along_y(flat, shape)


def curled(flat: np.ndarray, start: float, radius: float, pitch: float) -> np.ndarray:
    """The edge beyond `start` (m along y) rolled up in a spiral of `radius` (m) growing by `pitch` (m) a turn."""
    def shape(s):
        along = np.maximum(s - start, 0.0)
        # The spiral's angle for the arc length along it (radius r(phi) = radius + pitch phi / (2 pi)), by steps.
        phi = np.zeros_like(along)
        for _ in range(60):
            r = radius + pitch * phi / (2.0 * np.pi)
            phi = phi + (along - arc_length(phi)) / r
        r = radius + pitch * phi / (2.0 * np.pi)
        y = np.minimum(s, start) + r * np.sin(phi)
        z = radius - r * np.cos(phi)
        return y, z

    def arc_length(phi):
        a, b = radius, pitch / (2.0 * np.pi)
        return a * phi + 0.5 * b * phi ** 2  # (the spiral's slope term left out: small for pitch << radius)

    return bent_along_y(flat, shape)


def squeezed(flat: np.ndarray, low: float, high: float, factor: float) -> np.ndarray:
    """Compressed along y by `factor` between `low` and `high` (m along y from the low edge)."""
    def shape(s):
        inside = np.clip(s, low, high) - low
        return np.minimum(s, low) + factor * inside + np.maximum(s - high, 0.0), np.zeros_like(s)
    return bent_along_y(flat, shape)


def waves(flat: np.ndarray, amplitude: float, seed: int) -> np.ndarray:
    """Moved by a sum of random plane waves of up to `amplitude` (m) along every axis."""
    rng = np.random.default_rng(seed)
    out = flat.copy()
    xy = flat[:2].T
    for _ in range(6):
        direction = rng.normal(size=2)
        k = 2.0 * np.pi / rng.uniform(0.05, 0.5) * direction / np.linalg.norm(direction)
        out += rng.uniform(0.0, amplitude) * rng.normal(size=(3, 1)) / np.sqrt(3.0) * np.sin(xy @ k + rng.uniform(0, 6.3))
    return out


def swinging(duration: float) -> tuple[wetcloth.Simulation, np.ndarray]:
    """The 41 x 41 sheet, 1 m square, hanging from its y_max edge, released horizontal: its positions after
    `duration` s."""
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=41, ny=41, width=1.0, length=1.0, pinned_edge="y_max",
                                                  initial_tilt=0.0, initial_height=2.0, water_level=-10.0,
                                                  floor_level=-20.0))
    sim.advance(duration)
    return sim, sim.state.pos.copy()


def case(name: str, folder) -> tuple[wetcloth.Simulation, np.ndarray]:
    """The sheet and its positions (3, n) of the named case (files in `folder`)."""
    if name.startswith("mesh"):
        sim = diagonals_mesh(folder)
        flat = sim.state.pos.copy()
        return sim, (hairpin(flat, 0.43, 0.003) if name == "mesh hairpin" else waves(flat, 0.03, 4))
    if name.startswith("swinging"):
        return swinging(float(name.split()[1]))
    if name == "folded by a current":
        sim = wetcloth.Simulation(wetcloth.load_scene(**(CURRENT_OVER_PIN | {"nx": 11, "ny": 15, "bend_stiffness": 2.0})))
        sim.advance(2.0)
        return sim, sim.state.pos.copy()
    sim = grid_sheet()
    flat = sim.state.pos.copy()
    if name == "hairpin":
        return sim, hairpin(flat, 0.43, 0.003)
    if name == "curled edge":
        return sim, curled(flat, 0.8, 0.008, 0.004)
    if name == "squeezed":
        return sim, squeezed(flat, 0.3, 0.55, 0.8)
    if name == "squeezed whole":  # (the altitudes across the diagonals 31.2 mm, under the reach 31.8 mm)
        return sim, squeezed(flat, 0.0, 1.0, 0.8)
    return sim, waves(flat, float(name.split()[1]), int(name.split()[2]))


CASES = ["swinging 0.3", "swinging 0.6", "swinging 0.9", "folded by a current", "hairpin", "curled edge", "squeezed",
         "squeezed whole",
         "waves 0.002 1", "waves 0.01 2", "waves 0.03 3"]


@pytest.mark.parametrize("name", CASES)
def test_a_list_built_past_the_shown_windows_holds_every_pair_a_full_search_finds(name, tmp_path):
    """Built at the case's positions for the widest margin whose list is empty (up to what keeps the fabric's
    neighbours out: WIDE_REACH of the rest sheet's gap), the list's margin must be the one the checker's
    nearest pair sets, and its pairs exactly those the checker finds within its reach (the thickness plus
    twice the margin), leaving out pairs that lie closer than the thickness in the flat rest sheet (the
    fabric itself).  The windows are judged (the sheets are convex), and the cases test the judgement: the
    swinging sheet has most of its windows shown, every bent, squeezed or folded case has pairs within the
    widest reach (which set its margin) and windows not shown."""
    sim, x = case(name, tmp_path)
    built = listed_against_checker(sim, x)
    if name.startswith("swinging"):
        assert built.windows == 13 * 13 and built.unproven <= 0.25 * built.windows, built.unproven  # 14 x 14 cells
    elif not name.startswith("waves"):
        assert built.unproven > 0 and built.nearest < np.inf, (built.unproven, built.nearest)
    assert built.unproven >= 0
    assert built.margin == pytest.approx(built.expected_margin, abs=BORDER)
    assert built.expected <= built.listed <= built.expected | built.borderline, (len(built.expected), len(built.listed))


class Built(NamedTuple):
    """A list built at some positions against the checker: its pairs, the checker's within its reach and those
    at it to rounding (BORDER); the windows not shown, of how many; the list's margin (m), the margin the
    checker's nearest pair (m) sets."""
    listed: set
    expected: set
    borderline: set
    unproven: int
    windows: int
    margin: float
    nearest: float
    expected_margin: float


def listed_against_checker(sim: wetcloth.Simulation, x: np.ndarray) -> Built:
    """Build the list at positions x (3, n) for the widest margin whose list is empty, and the checker's pairs."""
    contact, thickness = sim._contact, sim.scene.thickness
    widest = max(contact.least_margin, 0.5 * (_core.WIDE_REACH * contact.rest_gap - thickness))
    contact.reference[...] = x
    lists = _core.ContactState()
    _core.build_widest(contact, thickness, contact.least_margin, widest, lists=lists)
    unproven, windows, _, _ = _core.unproven_windows(contact, x, thickness + 2.0 * widest, lists=lists)
    with np.errstate(over="ignore"):  # the grid's parallel edges: segment_distances' unused interior
        fabric = set(close_pairs(contact.rest.T, sim.triangles, contact.edges, thickness))
        found = {pair: gap for pair, gap in close_pairs(x.T, sim.triangles, contact.edges,
                                                        thickness + 2.0 * widest).items() if pair not in fabric}
    nearest = min(found.values(), default=np.inf)
    margin = float(contact.margin[0])
    reach = thickness + 2.0 * margin
    listed = {("point_triangle", int(a), int(b)) for a, b in np.asarray(lists.point_triangle).T}
    listed |= {("edge_edge", int(a), int(b)) for a, b in np.asarray(lists.edge_edge).T}
    return Built(listed, {pair for pair, gap in found.items() if gap < reach - BORDER},
                 {pair for pair, gap in found.items() if abs(gap - reach) <= BORDER}, unproven, windows, margin, nearest,
                 max(contact.least_margin, min(widest, 0.5 * (nearest - thickness))))


@settings(max_examples=25, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(amplitude=st.floats(0.0, 0.05), seed=st.integers(0, 1000), fold_at=st.floats(0.1, 0.9),
       radius=st.floats(0.0005, 0.05), folded=st.booleans(), squeeze=st.floats(0.6, 1.0), whole=st.booleans())
def test_a_randomly_bent_sheet_lists_every_pair_a_full_search_finds(amplitude, seed, fold_at, radius, folded, squeeze,
                                                                     whole):
    """Random sheets: rippled by waves of up to 5 cm, squeezed along y by down to 0.6 over a third of it or all
    of it, and perhaps folded back over themselves about a cylinder of 0.5 to 50 mm radius.  Whatever the windows shown,
    the list's margin is the one the checker's nearest pair sets and it holds exactly the checker's pairs within
    its reach (those at it, to rounding, either way)."""
    sim = grid_sheet()
    flat = sim.state.pos.copy()
    x = squeezed(flat, 0.0, 1.0, squeeze) if whole else squeezed(flat, 0.3, 0.63, squeeze)
    if folded:
        x = hairpin(x, fold_at, radius)
    built = listed_against_checker(sim, waves(x, amplitude, seed) if amplitude > 0.0 else x)
    assert built.unproven >= 0
    assert built.margin == pytest.approx(built.expected_margin, abs=BORDER)
    assert built.expected <= built.listed <= built.expected | built.borderline, (len(built.expected), len(built.listed))


def tier0_cells(contact) -> np.ndarray:
    """Each particle's cell (2, n) of the finest tier on a grid: three spacings, from half a spacing before the
    sheet."""
    rest = contact.rest[:2]
    low = rest.min(axis=1, keepdims=True)
    spacing = np.array([[np.diff(np.unique(np.round(r, 12)))[0]] for r in rest])
    return np.floor((rest - low + 0.5 * spacing) / (3.0 * spacing)).astype(int)


@pytest.mark.parametrize("name", ["hairpin", "curled edge", "squeezed", "waves 0.03 3", "mesh hairpin", "mesh waves"])
def test_every_pair_within_reach_of_a_window_lies_in_one_not_shown(name, tmp_path):
    """The proof itself: each pair the checker finds within the reach whose particles fit one window of the
    finest tier (their cells span at most two along each axis) has all its particles in windows not shown
    (a mesh's windows too: its lists' build does not use them where its particles have allowances of their
    own, as this one's do)."""
    sim, x = case(name, tmp_path)
    contact, thickness = sim._contact, sim.scene.thickness
    reach = thickness + 2.0 * max(contact.least_margin, 0.5 * (_core.WIDE_REACH * contact.rest_gap - thickness))
    lists = _core.ContactState()
    contact.reference[...] = x
    _core.build(contact, thickness, contact.least_margin, lists=lists)  # (cuts the tiers)
    unproven, _, inside, _ = _core.unproven_windows(contact, x, reach, lists=lists)
    inside = np.asarray(inside, dtype=bool)
    cells = tier0_cells(contact)
    with np.errstate(over="ignore"):
        fabric = set(close_pairs(contact.rest.T, sim.triangles, contact.edges, thickness))
    checked = 0
    with np.errstate(over="ignore"):  # the grid's parallel edges: segment_distances' unused interior
        close = close_pairs(x.T, sim.triangles, contact.edges, reach)
    for (kind, a, b), gap in close.items():
        if (kind, a, b) in fabric:
            continue
        members = np.concatenate([[a], sim.triangles[b]]) if kind == "point_triangle" else np.concatenate(
            [contact.edges[a], contact.edges[b]])
        if np.all(np.ptp(cells[:, members], axis=1) < 2):
            checked += 1
            assert inside[members].all(), (kind, a, b, gap)
    assert checked > 0 and unproven > 0, (checked, unproven)
