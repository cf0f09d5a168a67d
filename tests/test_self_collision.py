"""Self-collision (docs/model.md section 6.2): folding cloths never pass through themselves and keep
their layers 0.9 to 1 thickness apart; the stage costs nothing where nothing folds, is off on request,
and keeps FMU rollback exact.

Crossings are counted by a checker written here from scratch (signed volumes, numpy; none of the
product's geometry): an edge crosses a triangle it shares no particle with when its two ends lie
strictly on opposite sides of the triangle's plane and the line through it passes strictly inside
the triangle (the three signed volumes of the edge with the triangle's edges share one sign).
Touching and coplanar configurations (a zero volume) are not counted: the stage keeps layers a
thickness (2 mm) apart, so an intersection-free frame has no volume anywhere near zero, while a
cloth passing through itself crosses with volumes of the order of (grid spacing)^3.

The folding scenes are small (11 x 15 to 15 x 21 particles, a few seconds) but fold for real: the
same scenes with ``self_collision = "off"`` pass through themselves (``test_the_current_scene_crosses_
itself_without_the_stage``), so a zero count with the stage on is not for want of folds.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

import wetcloth
from wetcloth import _core
from wetcloth.energy import mechanical_energy
from wetcloth.fmu.checkpoint import Checkpoint, from_bytes, leaves_of, snapshot_from, to_bytes

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "docs"))
import make_meshes  # noqa: E402

# --------------------------------------------------------------------------- the independent checker


def mesh_edges(triangles: np.ndarray) -> np.ndarray:
    """The distinct edges (k, 2) of a triangle mesh, lower index first."""
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    edges.sort(axis=1)
    return np.unique(edges, axis=0)


def _volume(a, b, c, d):
    """Six times the signed volume of the tetrahedron (a, b, c, d) (rows of 3-vectors)."""
    return np.einsum("...i,...i->...", np.cross(b - a, c - a), d - a)


def crossings(pos: np.ndarray, triangles: np.ndarray) -> int:
    """Number of (edge, triangle) pairs without a shared particle where the edge passes through the
    triangle; ``pos`` (n, 3) m.  Pairs are first narrowed to those whose bounding spheres (about the
    edge's midpoint and the triangle's centroid) meet, which every crossing pair does."""
    edges = mesh_edges(triangles)
    middles = pos[edges].mean(axis=1)
    centroids = pos[triangles].mean(axis=1)
    reach = (np.linalg.norm(pos[edges[:, 0]] - middles, axis=1).max()
             + np.linalg.norm(pos[triangles] - centroids[:, None], axis=2).max())
    near = cKDTree(middles).sparse_distance_matrix(cKDTree(centroids), reach, output_type="ndarray")
    e, t = edges[near["i"]], triangles[near["j"]]
    apart = ~(e[:, :, None] == t[:, None, :]).any(axis=(1, 2))
    e, t = e[apart], t[apart]
    p, q = pos[e[:, 0]], pos[e[:, 1]]
    a, b, c = pos[t[:, 0]], pos[t[:, 1]], pos[t[:, 2]]
    opposite = _volume(a, b, c, p) * _volume(a, b, c, q) < 0
    around = np.stack([_volume(p, q, a, b), _volume(p, q, b, c), _volume(p, q, c, a)])
    inside = np.all(around > 0, axis=0) | np.all(around < 0, axis=0)
    return int(np.count_nonzero(opposite & inside))


def point_triangle_distances(points: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Distance (m) from each point to the triangle (a, b, c) in the same row (all (k, 3)): to the
    plane where the point projects inside the triangle, else to the nearest of its three sides."""
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    height = np.einsum("ij,ij->i", points - a, normal)
    foot = points - height[:, None] * normal
    turns = [np.einsum("ij,ij->i", np.cross(v - u, foot - u), normal) for u, v in ((a, b), (b, c), (c, a))]
    inside = (turns[0] >= 0) & (turns[1] >= 0) & (turns[2] >= 0)
    sides = []
    for u, v in ((a, b), (b, c), (c, a)):
        along = np.clip(np.einsum("ij,ij->i", points - u, v - u) / np.einsum("ij,ij->i", v - u, v - u), 0.0, 1.0)
        sides.append(np.linalg.norm(points - (u + along[:, None] * (v - u)), axis=1))
    return np.minimum(np.where(inside, np.abs(height), np.inf), np.min(sides, axis=0))


def segment_distances(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Distance (m) between the segments p1 q1 and p2 q2 in the same row (all (k, 3)): the least of the four
    distances from an end to the other segment and, where the closest points of the two lines lie inside
    both segments, their distance (a convex function of the two positions along the segments is least
    inside or on a side)."""
    def dot(u, v):
        return np.einsum("ij,ij->i", u, v)

    def to_segment(x, a, b):
        along = np.clip(dot(x - a, b - a) / dot(b - a, b - a), 0.0, 1.0)
        return np.linalg.norm(x - (a + along[:, None] * (b - a)), axis=1)

    ends = np.min([to_segment(p1, p2, q2), to_segment(q1, p2, q2), to_segment(p2, p1, q1), to_segment(q2, p1, q1)],
                  axis=0)
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, b, c, f = dot(d1, d1), dot(d2, d2), dot(d1, d2), dot(d1, r), dot(d2, r)
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s, t = (b * f - c * e) / denom, (a * f - b * c) / denom
    inside = (denom > 1e-12 * a * e) & (s > 0) & (s < 1) & (t > 0) & (t < 1)
    between = np.linalg.norm(p1 + np.nan_to_num(s)[:, None] * d1 - p2 - np.nan_to_num(t)[:, None] * d2, axis=1)
    return np.where(inside, np.minimum(ends, between), ends)


def close_pairs(pos: np.ndarray, triangles: np.ndarray, edges: np.ndarray, within: float) -> dict:
    """The (particle, triangle) pairs and (edge, edge) pairs (indices into ``edges``, lower first) that share
    no particle and lie closer than ``within`` (m) at ``pos`` (n, 3), by the checker's own distances:
    {("point_triangle" or "edge_edge", first, second): distance (m)}.  Pairs are first narrowed to those
    whose bounding spheres, grown by ``within``, meet."""
    centroids = pos[triangles].mean(axis=1)
    radius = np.linalg.norm(pos[triangles] - centroids[:, None], axis=2).max()
    near = cKDTree(pos).sparse_distance_matrix(cKDTree(centroids), radius + within, output_type="ndarray")
    p, t = near["i"], near["j"]
    keep = ~(triangles[t] == p[:, None]).any(axis=1)
    p, t = p[keep], t[keep]
    corners = triangles[t]
    d = point_triangle_distances(pos[p], pos[corners[:, 0]], pos[corners[:, 1]], pos[corners[:, 2]])
    close = {("point_triangle", int(a), int(b)): float(g) for a, b, g in zip(p, t, d) if g < within}
    middles = pos[edges].mean(axis=1)
    half = np.linalg.norm(pos[edges[:, 0]] - middles, axis=1).max()
    tree = cKDTree(middles)
    near = tree.sparse_distance_matrix(tree, 2.0 * half + within, output_type="ndarray")
    a, b = near["i"], near["j"]
    keep = (a < b) & ~(edges[a][:, :, None] == edges[b][:, None, :]).any(axis=(1, 2))
    a, b = a[keep], b[keep]
    d = segment_distances(pos[edges[a, 0]], pos[edges[a, 1]], pos[edges[b, 0]], pos[edges[b, 1]])
    close |= {("edge_edge", int(i), int(j)): float(g) for i, j, g in zip(a, b, d) if g < within}
    return close


def layer_separation(pos: np.ndarray, triangles: np.ndarray, reach: float) -> float:
    """Smallest distance (m) between a particle and a triangle that does not hold it, looked for up to
    ``reach`` (m; ``inf`` if none is that close).  This bounds every distance between two particles not
    joined by an edge (the second is a corner of such a triangle) and sees a particle resting on the
    middle of a triangle of another layer, which particle pairs alone would miss."""
    centroids = pos[triangles].mean(axis=1)
    radius = np.linalg.norm(pos[triangles] - centroids[:, None], axis=2).max()
    near = cKDTree(centroids).query_ball_point(pos, radius + reach)
    rows = np.array([(p, t) for p, ts in enumerate(near) for t in ts if p not in triangles[t]]).reshape(-1, 2)
    if not len(rows):
        return np.inf
    corners = triangles[rows[:, 1]]
    distances = point_triangle_distances(pos[rows[:, 0]], pos[corners[:, 0]], pos[corners[:, 1]], pos[corners[:, 2]])
    return float(distances.min())


def test_the_checker_counts_a_sheet_through_a_sheet():
    """Two unit squares (two triangles each), one through the middle of the other: the two upright
    edges that do not lie in the crossing line pierce the flat sheet (the diagonals meet in a point,
    which is not counted); lifted 1 mm clear, nothing crosses."""
    triangles = np.array([[0, 1, 2], [1, 3, 2], [4, 5, 6], [5, 7, 6]])
    flat = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]
    upright = [[0.2, 0.5, -0.5], [0.8, 0.5, -0.5], [0.2, 0.5, 0.5], [0.8, 0.5, 0.5]]
    pos = np.array(flat + upright, dtype=float)
    assert crossings(pos, triangles) == 2
    pos[4:, 2] += 0.501
    assert crossings(pos, triangles) == 0


# --------------------------------------------------------------------------- folding scenes

#: The issue's edge-on drop: a saturated 15 x 21 towel tilted 80 degrees, lower edge already in a
#: 0.6 m pool, folding over on the floor (its layers meet from 3.5 s and rest on each other from 4 s).
EDGE_ON_POOL = dict(nx=15, ny=21, initial_tilt=80.0, initial_saturation=1.0, floor_level=-0.6, initial_height=-0.2)
#: A towel dropped from 40 cm with a 45 degree tilt onto a floor in air (the water far below).
TILTED_IN_AIR = dict(nx=15, ny=21, initial_tilt=45.0, water_level=-5.0, floor_level=0.0, initial_height=0.4)
#: A towel floating at the surface, its y_min edge pinned, carried back over that edge by a 0.6 m/s
#: current: its free half folds onto the pinned half within a second.
CURRENT_OVER_PIN = dict(nx=15, ny=21, initial_tilt=0.0, initial_height=-0.05, pinned_edge="y_min", current_y=-0.6)


def run_frames(values: dict, duration: float, frame: float = 0.25) -> tuple[wetcloth.Simulation, list[np.ndarray]]:
    """The simulation after ``duration`` s, and its positions (n, 3) at every ``frame`` s."""
    sim = wetcloth.Simulation(wetcloth.load_scene(**values))
    frames = []
    for _ in range(round(duration / frame)):
        sim.advance(frame)
        frames.append(sim.positions)
    return sim, frames


@pytest.fixture(scope="module")
def current_over_pin():
    return run_frames(CURRENT_OVER_PIN, 2.0)


@pytest.fixture(scope="module")
def edge_on_pool():
    return run_frames(EDGE_ON_POOL, 6.0)


def test_a_towel_folded_onto_the_floor_comes_to_rest():
    """Dropped edge-on into a 0.6 m pool, the towel folds onto the floor in layers resting on each
    other.  At 30 s its layers move less than 1 um per 0.1 s, at fewer than 20 steps per simulated
    second: it came to rest and fell asleep (within half a millimetre for a second), and asleep
    nothing is computed.  Measured: asleep from about 10 s on, 0 steps in its last second."""
    scene = wetcloth.load_scene(**EDGE_ON_POOL)
    sim = wetcloth.Simulation(scene)
    sim.advance(29.0)
    steps = sim.steps
    sim.advance(0.9)
    before = sim.positions
    sim.advance(0.1)
    assert np.abs(sim.positions - before).max() < 1e-6
    assert sim.steps - steps < 20
    z = sim.positions[:, 2]
    assert z.min() < scene.floor_level + scene.thickness, "on the floor"
    assert np.ptp(z) > 10 * scene.thickness, "folded into a heap, not lying flat"
    assert sim.contact_counts["point_triangle_candidates"] > 0, "with layers close enough to touch"


#: The sensitivity example's costliest run before layers could rest (models/studies/towel_sink_sensitivity.toml):
#: a 5 x 7 towel that sinks onto the floor with a crease over itself.
CREASED_ON_THE_FLOOR = dict(nx=5, ny=7, absorption_rate=1.125810802334678, absorption_capacity=7.626402264460921,
                            areal_density=0.4749810270965099, thickness=0.0018784462329000235,
                            initial_tilt=14.63916840031743, drag_normal=1.3815833739936352)


def test_a_crease_resting_on_the_layer_below_stops_costing_steps():
    """Sunk onto the floor (about 14 s), this towel lies with a crease over itself.  Its creased
    particles used to be pulled into the layer below by gravity and pushed back by self-collision in
    every step, 960 steps of 1 ms every simulated second to its end; held on the layer as the floor
    holds the particles lying on it (self_contact/resting.cpp), they come to rest.  Run as the batch
    runner does (samples every 0.1 s): from 25 s to 30 s fewer than 100 steps a second (measured 10),
    and no edge crosses a triangle in any sample.  (The crease forms on this machine; where rounding
    lets the towel land without one, the bound holds all the more.)"""
    sim = wetcloth.Simulation(wetcloth.load_scene(**CREASED_ON_THE_FLOOR))
    crossed = 0
    for _ in range(250):
        sim.advance(0.1)
        crossed += crossings(sim.positions, sim.triangles)
    steps = sim.steps
    for _ in range(50):
        sim.advance(0.1)
        crossed += crossings(sim.positions, sim.triangles)
    assert (sim.steps - steps) / 5.0 < 100
    assert crossed == 0
    assert np.abs(sim.velocities).max() < 1e-3


#: A run of the sensitivity example (run 495 of its 512) whose towel sank onto the floor with a fold whose
#: corner particles lay on a flat layer and against a sloping one.
CORNER_OF_A_FOLD = dict(nx=5, ny=7, absorption_rate=0.3756255906808212, absorption_capacity=7.365530998446047,
                        areal_density=0.48989970264956356, thickness=0.002070942471921444,
                        initial_tilt=40.39055386092514, drag_normal=1.541422474384308)


def test_a_towel_sunk_onto_the_floor_comes_to_rest_with_no_layer_crossing():
    """Run as the batch runner does (samples every 0.1 s), the towel takes fewer than 50 steps and redone steps
    a second from 30 to 40 s, and no edge crosses a triangle in any sample.  (This run once folded so that a
    particle touched a flat layer and a sloping one; held on the sloping one it was let go before every step:
    243 tries a second without hold_within_friction, self_contact/resting.cpp, and 4.4 with it.  Since each
    corner takes its share of the drag at its own velocity, docs/model.md 4.3, it lands without that fold, and
    no sampled towel needs the rule: docs/open_problems.md.)"""
    sim = wetcloth.Simulation(wetcloth.load_scene(**CORNER_OF_A_FOLD))
    crossed = 0
    for _ in range(300):
        sim.advance(0.1)
        crossed += crossings(sim.positions, sim.triangles)
    tries = sim.steps + sim.rejected_steps
    for _ in range(100):
        sim.advance(0.1)
        crossed += crossings(sim.positions, sim.triangles)
    assert (sim.steps + sim.rejected_steps - tries) / 10.0 < 50
    assert crossed == 0


def particle_and_triangle():
    """A 5 x 5 sheet (0.1 m spacing) laid out to test one pair on its own: every particle far away (x = its
    column - 30 m, 50 m up), but triangle A of the far rows lying flat about (100, 100, 0) m (corners 5 cm out).
    Returns the simulation, its contact and thickness (m), each particle's column and row, the corner particle p
    (column 0, row 0, for the caller to place), A's index and the positions (3, n)."""
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=5, ny=5, width=0.4, length=0.4, self_collision="on"))
    contact, thickness = sim._contact, sim.scene.thickness
    ix = np.round((contact.rest[0] - contact.rest[0].min()) / 0.1).astype(int)
    iy = np.round((contact.rest[1] - contact.rest[1].min()) / 0.1).astype(int)
    p = int(np.flatnonzero((ix == 0) & (iy == 0))[0])
    a = next(t for t, c in enumerate(sim.triangles) if np.all(ix[c] >= 2) and np.all(iy[c] >= 3))
    pos = np.stack([ix - 30.0, 0.1 * iy, np.full(ix.size, 50.0)])
    pos[:, sim.triangles[a]] = (np.array([100.0, 100.0, 0.0]) + [[-0.05, -0.05, 0.0], [0.05, -0.05, 0.0],
                                                                 [0.0, 0.05, 0.0]]).T
    return sim, contact, thickness, ix, iy, p, a, pos


def test_a_particle_in_the_corner_of_a_fold_is_held_by_the_flat_layer_within_friction():
    """The rule behind the run above, on its own (self_contact/resting.cpp): particle p lies 0.8 thickness from a
    still vertical triangle B and a thickness above a still horizontal triangle A (the corner of a fold: a flat
    layer and a steep one), every other particle still and far away.  hold_on_layers holds it on its first support, B (the
    list's pairs ascend, and B's index is the lower); a force straight down (0, 0, -1) N does not press it onto B,
    so release_sliding lets it go; hold_within_friction then holds it on A, its normal straight up.  A force
    along A beyond friction (0.4) times the force into it, (0.5, 0, -1) N, is refused by both."""
    sim, contact, thickness, ix, iy, p, a, pos = particle_and_triangle()
    corners = sim.triangles
    b = next(t for t, c in enumerate(corners) if np.all(ix[c] >= 2) and np.all(iy[c] <= 1))
    assert b < a
    n = contact.rest.shape[1]
    centre = np.array([100.0, 100.0, 0.0])
    pos[:, p] = centre + [0.0, 0.0, thickness]
    wall = centre[0] + 0.8 * thickness
    pos[:, corners[b]] = np.array([[wall, 100.0 - 0.05, 0.5 * thickness], [wall, 100.0 + 0.05, 0.5 * thickness],
                                   [wall, 100.0, thickness + 0.05]]).T
    contact.reference[...] = pos
    vel = np.zeros((3, n))
    lists = _core.ContactState()
    _core.build(contact, thickness, contact.least_margin, lists=lists)

    def run(force_on_p):
        free, held = np.zeros(n), np.zeros(n)
        free[p] = 1.0  # the others still (held by the floor, say): supports must be
        force = np.zeros((3, n))
        force[:, p] = force_on_p
        steps = [_core.hold_on_layers(contact, thickness, pos, vel, free, held, lists=lists)]
        support = np.array(lists.resting).reshape(n, 3)[p].copy()
        steps.append(_core.release_sliding(contact, force, free, held, lists=lists))
        steps.append(_core.hold_within_friction(contact, thickness, pos, vel, force, free, held, lists=lists))
        return steps, support, free[p], np.array(lists.resting).reshape(n, 3)[p], np.array(lists.resting_normal).reshape(n, 3)[p]

    steps, first, free_p, support, normal = run([0.0, 0.0, -1.0])
    assert steps == [1, 1, 1] and sorted(first) == sorted(corners[b]), (steps, first)
    assert free_p == 0.0 and sorted(support) == sorted(corners[a]) and np.allclose(normal, [0.0, 0.0, 1.0]), (support, normal)
    steps, _, free_p, _, _ = run([0.5, 0.0, -1.0])
    assert steps == [1, 1, 0] and free_p == 1.0, steps


@pytest.mark.parametrize("solved, start, end, kept", [
    (False, 1.5, 0.8, 1.0), (False, 0.95, 0.8, 0.95), (False, 0.95, 0.945, 0.95), (False, 0.5, 0.4, 0.9),
    (False, 0.95, 0.96, 0.96), (False, 1.5, 0.995, 0.995), (False, 1.5, 0.95, 1.0),
    (True, 1.5, 0.95, 0.95), (True, 0.95, 0.91, 0.91), (True, 1.5, 0.8, 1.0), (True, 0.95, 0.85, 0.95),
    (True, 0.5, 0.4, 0.9)])
def test_a_push_sets_layers_back_to_where_they_started_not_beyond(solved, start, end, kept):
    """The push of self_contact/response.cpp (docs/model.md 6.2), on its own: particle p falls straight onto a flat
    triangle A, from `start` to `end` thicknesses above it, every other particle far away.  A pair that started
    the step at least a thickness apart is pushed to the thickness; one that started closer only back to where
    it started (at least 0.9 of the thickness), since lifting it further is work no force did (before: to the
    thickness, and a crumpled pile's pushes gained energy at nearly every fixed frame step); one that moved
    apart, or that ends within 1 % of the thickness, is left.  After a solve that held the pairs (`solved`: a
    fixed step's supports) a pair it left at least 0.9 of the thickness apart is left too, wherever it started
    (before: pushed back, and the pile's pushes still gained energy in a third to half of its steps).  The
    approaching velocity is removed, and the push conserves momentum."""
    sim, contact, thickness, _, _, p, a, x0 = particle_and_triangle()
    n = contact.rest.shape[1]
    x0[:, p] = [100.0, 100.0 - 0.05 / 3.0, start * thickness]  # over A's centroid: A moves as one
    contact.reference[...] = x0
    lists = _core.ContactState()
    _core.build(contact, thickness, contact.least_margin, lists=lists)
    h = 0.01
    x1, v1 = x0.copy(), np.zeros((3, n))
    x1[2, p] = end * thickness
    v1[2, p] = (end - start) * thickness / h
    mass, free = np.full(n, 0.01), np.ones(n)
    momentum = (mass * v1).sum(axis=1)
    _core.resolve(contact, thickness, -10.0, 1e3, mass, free, x0, x1, v1, h, lists=lists, layers_solved=solved)
    separation = x1[2, p] - x1[2, sim.triangles[a]].mean()
    assert separation == pytest.approx(kept * thickness, rel=1e-9), (separation / thickness, kept)
    assert np.allclose((mass * v1).sum(axis=1), momentum, rtol=0.0, atol=1e-15)
    approach = v1[2, p] - v1[2, sim.triangles[a]].mean()
    assert approach == (pytest.approx(0.0, abs=1e-12) if kept != end else (end - start) * thickness / h)


def test_a_fold_carries_the_pushed_particles_history(current_over_pin):
    """Self-collision's pushes carry the pushed particles' BDF2 history through their pushed state
    (docs/model.md section 6.2, "Time integration") instead of restarting it for the whole cloth.  The
    towel folded by the current (thousands of pushes in 2 s) stays within the defaults' 1 mm accuracy
    aim for the centroid (docs/benchmarks.md, `bench/work_precision.py`; here the particles' mean
    position) of the same scene at tolerance 5e-8 (100 times tighter, computed here) in every frame.
    Measured: 0.26 mm (0.19 while pushes took layers to the thickness from wherever they started);
    restarting at every push gave 0.84 mm with a third more steps."""
    sim, frames = current_over_pin
    assert sim.contact_counts["responses"] > 1000, "folds for real: the stage pushes"
    _, reference = run_frames(dict(CURRENT_OVER_PIN, tolerance=5e-8), 2.0)
    means = np.array([f.mean(axis=0) for f in frames])
    reference_means = np.array([f.mean(axis=0) for f in reference])
    assert np.linalg.norm(means - reference_means, axis=1).max() < 1e-3


def test_towel_dropped_edge_on_into_a_pool_never_crosses_itself(edge_on_pool):
    sim, frames = edge_on_pool
    assert [crossings(pos, sim.triangles) for pos in frames] == [0] * len(frames)
    assert sim.contact_counts["responses"] > 0  # the layers met: the stage had work
    assert sim.contact_counts["freezes"] == 0  # and never had to undo a step


def test_towel_dropped_at_45_degrees_in_air_never_crosses_itself():
    """The towel lands on its lower edge and lies down; with this fabric (bend_stiffness 20 N/m) its
    layers do not meet (this guards the stage's interplay with the floor, not the folds)."""
    sim, frames = run_frames(TILTED_IN_AIR, 1.5)
    assert [crossings(pos, sim.triangles) for pos in frames] == [0] * len(frames)


def test_towel_folded_by_a_current_never_crosses_itself(current_over_pin):
    sim, frames = current_over_pin
    assert [crossings(pos, sim.triangles) for pos in frames] == [0] * len(frames)
    assert sim.contact_counts["responses"] > 0 and sim.contact_counts["freezes"] == 0


def test_the_current_scene_crosses_itself_without_the_stage():
    """The check above can fail: without the stage the same towel passes through itself."""
    sim, frames = run_frames(CURRENT_OVER_PIN | {"self_collision": "off"}, 2.0)
    assert max(crossings(pos, sim.triangles) for pos in frames) > 20
    assert set(sim.contact_counts.values()) == {0}  # and the stage did nothing at all


def test_folded_layers_stay_a_thickness_apart(edge_on_pool):
    """Layer separation >= 0.9 thickness once the edge-on towel lies folded on the floor (every frame
    from 4.5 s; its layers meet from 3.5 s): between every particle and every triangle not holding it
    (hence also between particles not joined by an edge), by the checker's own distance.

    The stage pushes every pair (a particle and a triangle, two edges) closer than 0.99 thickness
    (``response.SLACK``) back to one thickness, or, if it started the step closer, back to where it started
    but to at least 0.9 thickness (``response.KEPT_FRACTION``); once its settling passes find nothing left to
    treat, every pair is >= 0.9 thickness apart.  Here the layers rest 0.990-0.991 thickness apart (measured).
    That the layers are in contact at all is checked too: in every frame some pair lies within 1.5
    thicknesses."""
    sim, frames = edge_on_pool
    thickness = sim.scene.thickness
    settled = frames[round(4.5 / 0.25) - 1:]
    closest = [layer_separation(pos, sim.triangles, reach=3.0 * thickness) / thickness for pos in settled]
    assert all(0.9 <= d <= 1.5 for d in closest), closest


@pytest.mark.parametrize("integrator", ["implicit_euler", "symplectic_euler", "explicit_euler"])
def test_every_integrator_keeps_a_fold_from_crossing(integrator):
    """A soft 11 x 15 towel (bend_stiffness 2 N/m) folded over its pinned edge by the current, 2 s:
    with each of the other integrators it passes through itself without the stage (48 to 88
    crossings in a frame, measured), and not with it."""
    values = CURRENT_OVER_PIN | {"nx": 11, "ny": 15, "bend_stiffness": 2.0, "integrator": integrator}
    sim, frames = run_frames(values, 2.0)
    assert [crossings(pos, sim.triangles) for pos in frames] == [0] * len(frames)
    assert sim.contact_counts["responses"] > 0 and sim.contact_counts["freezes"] == 0


def test_a_sheet_folding_onto_itself_at_frame_steps_loses_energy_in_nearly_every_frame():
    """The fixed-step mode (implicit_euler, tolerance 0, max_step 1/30 s) on a 41 x 41 sheet, 1 m square, hung by
    one corner in still air for 3 s: its sides swing together and fold over each other.  Nothing drives it, so its
    mechanical energy should fall in every frame.  With the layers' contact in the solve (docs/model.md section
    6.2, "Layers in the solve") it rose in none of the 90 frames from seven of eight starting heights a micrometre
    apart, in one from the eighth (by 0.00031 J; bench/self_contact_energy.py), where the stage after the solve
    alone let it rise in 20-27 frames (by up to 0.12 J); with steps whose pushes gained energy taken again in
    halves, in none from all eight.  The folding is chaotic (another CPU's rounding takes another path), hence a
    count with room: at most 3 frames.  And the fold never crosses itself."""
    scene = wetcloth.load_scene(nx=41, ny=41, width=1.0, length=1.0, pinned_vertices="box:-9,0.45,-9,-0.45,9,9",
                                initial_tilt=0.0, initial_height=2.0, water_level=-10.0, floor_level=-20.0,
                                integrator="implicit_euler", tolerance=0.0, max_step=1 / 30)
    sim = wetcloth.Simulation(scene)
    energies, crossed = [mechanical_energy(sim)], 0
    for _ in range(90):
        sim.advance(1 / 30)
        energies.append(mechanical_energy(sim))
        crossed += crossings(sim.positions, sim.triangles)
    rising = int((np.diff(energies) > 1e-9).sum())  # 1e-9 J: round-off in summing the energy (test_sanity.py)
    assert sim.contact_counts["responses"] > 10_000, "its sides met"
    assert rising <= 3, np.diff(energies).max()
    assert crossed == 0


def test_a_frame_step_whose_pushes_gain_energy_is_taken_again_in_halves():
    """The fixed-step mode takes a step again in halves (down to a sixteenth of max_step) where self-collision's
    pushes after its solve leave the cloth's energy above the step's start (stepping.cpp).  A 5 x 9 sheet folded in
    half on the floor, its upper layer half a thickness into the lower one: the first step's pushes lift that layer
    by half a thickness, m g e / 2 = 2.9e-4 J gained (measured; without the halving the frame was one step taken as
    it came).  Its first step is halved down to a sixteenth of the frame: four steps taken again.  That size
    passes to the next step, and each step taken whole doubles it: the frame is 1/16, 1/16, 1/8, 1/4 and 1/2 of
    it, five steps (before, the next step was tried whole, here two steps: a folding flag's frames tried whole
    again and again took 1880 steps again in 1.5 s instead of 240, bench/violent_frames.py)."""
    scene = wetcloth.load_scene(nx=5, ny=9, width=0.2, length=0.4, initial_tilt=0.0, initial_height=0.00101,
                                floor_level=0.0, water_level=-10.0, bend_stiffness=0.0, absorption_rate=0.0,
                                integrator="implicit_euler", tolerance=0.0, max_step=1 / 30)
    sim = wetcloth.Simulation(scene)
    pos, e = sim._buffers.pos, scene.thickness  # written in place below
    rows = np.unique(pos[1])
    for j in range(5, 9):  # rows 5..8 folded back over rows 3..0, half a thickness into them
        upper = np.isclose(pos[1], rows[j])
        pos[1, upper] = rows[8 - j]
        pos[2, upper] = scene.initial_height + 0.5 * e
    before = mechanical_energy(sim)
    sim.advance(1 / 30)
    assert sim.contact_counts["responses"] > 0, "the layers were pushed apart"
    assert mechanical_energy(sim) > before, "lifting the layer gained energy"
    assert sim.rejected_steps == 4
    assert sim.steps == 5


def test_a_crumpled_pile_at_frame_steps_comes_to_rest_at_a_step_a_frame():
    """The fixed-step mode (implicit_euler, tolerance 0, max_step 1/30 s) on a soft 11 x 15 towel (bend_stiffness
    2 N/m) dropped upright from 0.4 m onto a floor in air: it crumples into a pile of layers on the floor.  Its
    solve holds the layers (docs/model.md section 6.2, "Layers in the solve"), and the stage after it leaves the
    pairs it balanced at least 0.9 thickness apart, so from 4 to 8 s the pile takes about one step a frame
    (0.25 s frames: 8 steps each, the last one short).  Measured from eight starting heights a micrometre apart:
    128-141 steps, 0-13 of them taken again (before, when the stage pushed such pairs back to where they
    started, its pushes gained energy in most steps, each taken again in halves: 438-702 steps, 225-378 taken
    again, from four).  The landing is chaotic, hence room: at most 40 taken again.  No edge crosses a triangle
    in any 0.25 s frame, and the layers are in contact."""
    scene = wetcloth.load_scene(nx=11, ny=15, bend_stiffness=2.0, initial_tilt=90.0, initial_height=0.4,
                                floor_level=0.0, water_level=-5.0, integrator="implicit_euler", tolerance=0.0,
                                max_step=1 / 30)
    sim = wetcloth.Simulation(scene)
    sim.advance(4.0)
    steps, again, crossed = sim.steps, sim.rejected_steps, 0
    for _ in range(16):
        sim.advance(0.25)
        crossed += crossings(sim.positions, sim.triangles)
    assert sim.rejected_steps - again <= 40
    assert sim.steps - steps <= 128 + 40
    assert crossed == 0
    assert np.ptp(sim.positions[:, 2]) > 5 * scene.thickness, "a pile, not a flat sheet"
    assert sim.contact_counts["point_triangle_candidates"] > 0, "with layers close enough to touch"


@settings(max_examples=4, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(tilt=st.floats(20.0, 90.0), height=st.floats(0.4, 1.5), in_water=st.booleans())
def test_random_drops_never_cross_themselves(tilt, height, in_water):
    """A soft 11 x 15 towel (bend_stiffness 2 N/m: it folds on a coarse grid too) dropped at any tilt
    from 0.4 to 1.5 m onto a floor, in air or into water 0.3 m deep; 1.5 s, a frame every 0.25 s."""
    values = dict(nx=11, ny=15, bend_stiffness=2.0, initial_tilt=tilt, initial_height=height, floor_level=0.0,
                  water_level=0.3 if in_water else -5.0)
    sim, frames = run_frames(values, 1.5)
    assert [crossings(pos, sim.triangles) for pos in frames] == [0] * len(frames)
    assert sim.contact_counts["freezes"] == 0


# --------------------------------------------------------------------------- cost, switch and rollback


def test_a_sheet_without_folds_is_not_touched():
    """The default towel (no folds) runs bit for bit as with the stage off: no candidate pair ever, and
    a candidate list rebuilt for under 5 % of the steps (its fall and drift are a common motion that
    keeps a list valid; only its flexing on landing makes new ones)."""
    values = dict(nx=11, ny=15)
    on, _ = run_frames(values, 2.0, frame=1.0)
    off, _ = run_frames(values | {"self_collision": "off"}, 2.0, frame=1.0)
    assert np.array_equal(on.state.pos, off.state.pos) and np.array_equal(on.state.vel, off.state.vel)
    assert on.steps == off.steps
    counts = on.contact_counts
    assert counts["busy_steps"] == 0 and counts["point_triangle_candidates"] + counts["edge_edge_candidates"] == 0
    assert counts["rebuilds"] < 0.05 * on.steps


def test_the_landing_towel_rebuilds_its_list_a_few_times():
    """The default towel's drop and impact (its first 0.5 s, 21 x 29) run bit for bit as with the stage
    off, never with a candidate pair, and with at most 20 candidate lists.

    The bound: the y_min edge lands first and stops while the far edge, 0.7 m x sin 10 deg = 0.12 m
    higher, falls on, so the vertical spread of the particles' displacements grows by about 0.12 m;
    the rest is flexing.  A list expires once that spread since its reference exceeds about twice its
    margin (``broad_phase.covers`` takes out the mid-range of the displacements).  A list following
    an empty one gets the widest margin that keeps it empty, up to ``_widest_margin`` (5.2 mm here:
    reach 0.7 x the rest sheet's 17.7 mm between non-adjacent elements), so it lasts at least ~10 mm
    of spread: about 12 lists, and 20 leave room for the flexing (14 measured).  With the least
    margin alone (1.25 mm) it would take at least 48 (78 measured before the wide lists)."""
    on = wetcloth.Simulation(wetcloth.load_scene())
    off = wetcloth.Simulation(wetcloth.load_scene(self_collision="off"))
    for sim in (on, off):
        sim.advance(0.5)
    assert np.array_equal(on.state.pos, off.state.pos) and np.array_equal(on.state.vel, off.state.vel)
    counts = on.contact_counts
    assert counts["busy_steps"] == 0 and counts["point_triangle_candidates"] + counts["edge_edge_candidates"] == 0
    assert 1 <= counts["rebuilds"] <= 20, counts


def test_a_list_searched_wide_is_the_list_built_for_its_margin():
    """A list built after an empty one searches up to the widest margin and narrows to the widest one
    that keeps it empty, or to the least one (``build_widest``); a restored run rebuilds it with
    ``build`` for the kept margin alone, so both must give the same pairs.  Checked on a soft towel
    crumpling on a floor, before its layers meet (0.16 s: a margin between the least and the widest,
    no pairs) and in the pile (0.8 s: the least margin, hundreds of pairs).  Such moments come and go
    as the towel folds (scanned in steps of 0.01 s, with the default air: 0.11, 0.14, 0.16 and 0.17 s;
    in vacuum, where this test took 0.3 s, 0.13, 0.16 and 0.28 to 0.31 s)."""
    values = dict(nx=11, ny=15, bend_stiffness=2.0, initial_tilt=90.0, initial_height=0.4, floor_level=0.0,
                  water_level=-5.0)
    sim = wetcloth.Simulation(wetcloth.load_scene(**values))
    contact, thickness = sim._contact, sim.scene.thickness
    least = contact.least_margin
    widest = 0.5 * (_core.WIDE_REACH * contact.rest_gap - thickness)
    kept = []
    for duration in (0.16, 0.64):
        sim.advance(duration)
        contact.reference[...] = sim.state.pos
        searched, built = _core.ContactState(), _core.ContactState()
        _core.build_widest(contact, thickness, least, widest, lists=searched)
        margin = float(contact.margin[0])
        _core.build(contact, thickness, margin, lists=built)
        assert all(np.array_equal(searched[k], built[k]) for k in (0, 1))
        kept.append((margin, searched.point_triangle_count + searched.edge_edge_count))
    (early, none), (late, pairs) = kept
    assert least < early < widest and none == 0
    assert late == least and pairs > 100


def test_a_list_that_holds_has_every_pair_that_comes_close():
    """The candidate list's promise, checked from scratch: while it holds for a motion (``_core.covers``), no
    pair outside it comes within a thickness anywhere along that motion.  A soft towel folded over its pinned
    edge by the current (2 s: layers in contact, so the list has pairs; 1.25 s until the drag took each
    corner's share at its own velocity, docs/model.md 4.3, which folds it later), its list built for the least
    margin (2.5 mm: the pairs within 7 mm).  Then straight-line motions between two states of that towel, both
    moved by 10 cm (the end 2 cm more) and half of them turned (by up to 0.5 rad, the end up to 0.02 rad more;
    four by up to 3 rad more, whose straight lines shrink the towel), each bent (a smooth displacement of up
    to 1 to 30 mm, waves 0.2 to 1 m long) or with its upper layer pressed onto the lower one (by 2 to 10 mm),
    and shaken (up to 0.1 mm along each axis).  The list must hold for some motions and not for others; along
    those it holds for (start, quarters, end), no pair outside it may come closer than the thickness, and some
    must come within two thicknesses: the check is made near the list's limit (with allowances half as large
    again it failed, 1.5 mm, and without the shrinking of turned straight lines, 0.7 mm: measured at 1.25 s)."""
    values = CURRENT_OVER_PIN | {"nx": 11, "ny": 15, "bend_stiffness": 2.0}
    sim = wetcloth.Simulation(wetcloth.load_scene(**values))
    sim.advance(2.0)
    contact, thickness = sim._contact, sim.scene.thickness
    ref = sim.state.pos.copy()  # (3, n)
    contact.reference[...] = ref
    lists = _core.ContactState()
    _core.build(contact, thickness, contact.least_margin, lists=lists)
    listed = {("point_triangle", a, b) for a, b in lists.point_triangle.T.tolist()}
    listed |= {("edge_edge", a, b) for a, b in lists.edge_edge.T.tolist()}
    assert listed  # the layers are in contact
    rest = contact.rest[:2].T  # (n, 2)
    rng = np.random.default_rng(25)

    def turned(most: float) -> np.ndarray:
        axis = rng.normal(size=3)
        return Rotation.from_rotvec(rng.uniform(0.0, most) * axis / np.linalg.norm(axis)).as_matrix()

    def moved(turn: np.ndarray, shift: np.ndarray, bend: float, press: float) -> np.ndarray:
        wave = rng.normal(size=2)
        wave *= 2.0 * np.pi / (rng.uniform(0.2, 1.0) * np.linalg.norm(wave))
        x = ref + bend * rng.normal(size=(3, 1)) / np.sqrt(3.0) * np.sin(rest @ wave + rng.uniform(0, 2 * np.pi))
        x[2] -= press * np.clip((rest[:, 1] - 0.05) / 0.1, 0.0, 1.0)  # the upper layer down onto the lower
        centre = ref.mean(axis=1, keepdims=True)
        return turn @ (x - centre) + centre + shift + rng.uniform(-0.1e-3, 0.1e-3, size=x.shape)

    held = refused = 0
    nearest = np.inf  # the nearest pair outside the list in a motion it holds for (m)
    trials = [(b, 0.0, most, 0.04 * most) for b in (0.0, 0.001, 0.002, 0.004, 0.01, 0.03) for most in (0, 0, 0.5, 0.5)]
    trials += [(0.0, p, most, 0.04 * most) for p in (0.002, 0.003, 0.004, 0.0045, 0.005, 0.006, 0.01)
               for most in (0, 0, 0.5, 0.5)]
    trials += [(0.0, 0.0, 0.5, 3.0)] * 4  # half a turn along the motion: the straight lines shrink the towel
    for bend, press, most, more in trials:
        turn, shift = turned(most), rng.uniform(-0.1, 0.1, size=(3, 1))
        x0 = moved(turn, shift, bend, press)
        x1 = moved(turned(more) @ turn, shift + rng.uniform(-0.02, 0.02, size=(3, 1)), bend, press)
        if not _core.covers(contact, x0, x1, lists=lists):
            refused += 1
            continue
        held += 1
        for f in (0.0, 0.25, 0.5, 0.75, 1.0):
            close = close_pairs(((1.0 - f) * x0 + f * x1).T, sim.triangles, contact.edges, 2.0 * thickness)
            outside = [d for pair, d in close.items() if pair not in listed]
            nearest = min([nearest] + outside)
            assert nearest >= thickness, (bend, press, f, nearest)
    assert held >= 10 and refused >= 10 and nearest < 2.0 * thickness, (held, refused, nearest)


def nearest_points(first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The closest points of two elements of a flat sheet that do not overlap, each given by its particles'
    positions (k, 3): a point, an edge or a triangle.  In the plane they are the closest points of their
    sides (a point's side is itself), and those of two sides lie at an end of one of them."""
    def sides(corners):
        return [(corners[k], corners[(k + 1) % len(corners)]) for k in range(len(corners) if len(corners) > 2 else 1)]

    def foot(x, a, b):
        along = 0.0 if np.array_equal(a, b) else np.clip(np.dot(x - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
        return a + along * (b - a)

    options = []
    for a, b in sides(first):
        for c, d in sides(second):
            options += [(x, foot(x, c, d)) for x in (a, b)] + [(foot(y, a, b), y) for y in (c, d)]
    return min(options, key=lambda pq: np.linalg.norm(pq[1] - pq[0]))


def test_a_mesh_lists_its_particles_own_allowances_and_keeps_its_promise(tmp_path):
    """A mesh whose smallest triangles would cap a single margin (an irregular disc of 2207 vertices, 1 cm
    apart: smallest altitude 3.3 mm, median 7.7 mm, thickness 2 mm) gives each particle its own allowances in
    the finest tier, from 0.64 to 2.5 mm against a margin of 0.48 mm: one for the pairs that fit a window of
    the fine tier (cells of two median edges; 9812 of the pairs below), one for the others (252, from 1.3 mm).
    The promise, checked from scratch on the flat disc: every pair the list leaves out (it is empty) lies at
    least the thickness plus the least allowances (of its kind) of its two elements' particles apart.  Then motions from the flat disc, moved by 10 cm and
    turned (by up to 0.5 rad; a window on the rim whose few particles lie on a line in the rest sheet takes the
    whole sheet's rotation: with none, pushes by 0.5 of the allowances were refused from 0.3 rad), that push the two elements of the six pairs with
    the least room left (none) towards each other by a fraction f of those allowances (shaken by up to
    0.01 mm): the list must hold for f = 0.5 and 0.8, where such a pair ends 0.2 of its room (at most 0.4
    of the largest allowance) beyond the thickness, and not for f = 1.3; along every motion it holds for, no
    pair comes closer than the thickness.  With allowances half as large again, the push by 0.8 of them
    (1.2 of the room) would end inside the thickness."""
    points, triangles = make_meshes.round_cloth(radius=0.26, rings=26)
    path = tmp_path / "disc.ply"
    make_meshes.write(path, points, triangles)
    sim = wetcloth.Simulation(wetcloth.load_scene(cloth_mesh=str(path), place_mesh="on"))
    contact, thickness = sim._contact, sim.scene.thickness
    ref = sim.state.pos.copy()
    contact.reference[...] = ref
    lists = _core.ContactState()
    _core.build_widest(contact, thickness, contact.least_margin, 0.5 * (_core.WIDE_REACH * contact.rest_gap - thickness),
                       lists=lists)
    n = len(points)
    margin, own = float(contact.margin[0]), np.array(lists.particle_allowances).reshape(2, n)
    cells = np.array(lists.fine_cells(n)).reshape(2, n)
    assert lists.point_triangle_count + lists.edge_edge_count == 0
    assert own.min() >= margin and own.max() > 2.5 * margin, (margin, own.min(), own.max())

    def members(pair):
        """The pair's two elements' particles, and their allowances: those of the pairs that fit a window of the
        fine tier (their cells span at most WINDOW along each axis) or the others'."""
        kind, a, b = pair
        first, second = ([a], sim.triangles[b]) if kind == "point_triangle" else (contact.edges[a], contact.edges[b])
        span = np.ptp(cells[:, np.concatenate([first, second])], axis=1)
        row = 0 if np.all(span < _core.WINDOW) else 1
        return first, second, row

    room, rows = {}, []  # each pair left out: how far it lies beyond the thickness and its elements' least allowances
    for pair, gap in close_pairs(ref.T, sim.triangles, contact.edges, thickness + 2.0 * own.max()).items():
        first, second, row = members(pair)
        room[pair] = gap - thickness - own[row, first].min() - own[row, second].min()
        rows.append(row)
    assert np.bincount(rows).min() > 100, np.bincount(rows)  # both rows' promises are checked
    assert min(room.values()) >= -1e-12 * thickness
    rng = np.random.default_rng(26)
    tightest = sorted(room, key=room.get)[:6]
    held, refused, nearest = 0, 0, np.inf
    for pair in tightest:
        first, second, row = members(pair)
        p, q = nearest_points(ref.T[first], ref.T[second])
        towards = (q - p) / np.linalg.norm(q - p)
        for f in (0.5, 0.8, 1.3):
            pushed = ref.copy()
            pushed[:, first] += f * own[row, first].min() * towards[:, None]
            pushed[:, second] -= f * own[row, second].min() * towards[:, None]
            axis = rng.normal(size=3)
            turn = Rotation.from_rotvec(rng.uniform(0.0, 0.5) * axis / np.linalg.norm(axis)).as_matrix()
            centre, shift = ref.mean(axis=1, keepdims=True), rng.uniform(-0.1, 0.1, size=(3, 1))
            x0 = turn @ (ref - centre) + centre + shift
            x1 = turn @ (pushed - centre) + centre + shift + rng.uniform(-1e-5, 1e-5, size=ref.shape)
            if not _core.covers(contact, x0, x1, lists=lists):
                assert f > 1.0, (pair, f)
                refused += 1
                continue
            assert f < 1.0, (pair, f)
            held += 1
            for t in (0.0, 0.25, 0.5, 0.75, 1.0):
                close = close_pairs(((1.0 - t) * x0 + t * x1).T, sim.triangles, contact.edges, 2.0 * thickness)
                nearest = min([nearest] + list(close.values()))
                assert nearest >= thickness, (pair, f, t, nearest)
    assert refused == len(tightest) and held == 2 * len(tightest), (held, refused)
    assert nearest <= thickness + 0.4 * own.max() + 1e-4 * thickness, nearest


def test_a_small_sheet_bending_as_a_whole_keeps_its_empty_list():
    """On a sheet that one window of the 12-spacing tier holds whole (11 x 15 particles, 5 cm apart), no pair
    is left for the whole sheet's tier: its windows' rigid motions bound the distance of every pair, so the
    whole sheet may bend beyond the margin (as a small cloth drapes over a ball: the 817-vertex round cloth
    of ``bench/draped_tries.py`` built 264 empty lists in 709 steps, 263 after that tier's check failed).
    The flat sheet's list (empty, the widest margin: 14.9 mm) is checked for motions that roll it about an
    axis along x by a total angle from 0.1 to 7 rad (moved by 10 cm and turned by up to 0.3 rad): it must
    hold for 0.5 rad (a sagitta of 44 mm, 3 times the margin; refused before, when that tier's allowance
    was the margin: it held to 0.2 rad) and not once the rolled sheet closes on itself (2 pi: the ends
    meet); along every motion it holds for, no pair comes closer than the thickness."""
    sim = wetcloth.Simulation(wetcloth.load_scene(nx=11, ny=15, initial_tilt=0.0))
    contact, thickness = sim._contact, sim.scene.thickness
    ref = sim.state.pos.copy()  # flat, in a horizontal plane
    contact.reference[...] = ref
    lists = _core.ContactState()
    widest = 0.5 * (_core.WIDE_REACH * contact.rest_gap - thickness)
    _core.build_widest(contact, thickness, contact.least_margin, widest, lists=lists)
    assert lists.point_triangle_count + lists.edge_edge_count == 0 and float(contact.margin[0]) == widest
    rng = np.random.default_rng(27)
    centre = ref.mean(axis=1, keepdims=True)
    y = ref[1] - centre[1, 0]
    held = {}
    for angle in (0.1, 0.2, 0.5, 1.0, 2.0, 4.0, 6.5, 7.0):
        radius = (ref[1].max() - ref[1].min()) / angle
        rolled = ref.copy()
        rolled[1] = centre[1, 0] + radius * np.sin(y / radius)
        rolled[2] = ref[2] + radius * (1.0 - np.cos(y / radius))
        axis = rng.normal(size=3)
        turn = Rotation.from_rotvec(rng.uniform(0.0, 0.3) * axis / np.linalg.norm(axis)).as_matrix()
        shift = rng.uniform(-0.1, 0.1, size=(3, 1))
        x0, x1 = ref, turn @ (rolled - centre) + centre + shift
        held[angle] = _core.covers(contact, x0, x1, lists=lists)
        if held[angle]:
            for t in (0.0, 0.25, 0.5, 0.75, 1.0):
                with np.errstate(over="ignore"):  # the grid's parallel edges: segment_distances' unused interior
                    close = close_pairs(((1.0 - t) * x0 + t * x1).T, sim.triangles, contact.edges, thickness)
                assert not close, (angle, t, min(close.values()))
    assert held[0.5] and not held[6.5] and not held[7.0], held


def test_a_swinging_sheet_keeps_an_empty_list():
    """A 41 x 41 sheet (1 m square) pinned along one edge and released horizontal in air swings down and
    whips its free edge, but never comes near itself: its first 0.5 s run bit for bit as with the stage
    off, with no candidate pair after any frame and the list rebuilt for under 10 % of the steps (18 of
    339 measured).  Before the lists were judged by the rigid motions of the rest sheet's windows, the free
    edge's speed widened them to the fabric's neighbours: 129 lists, 30 steps with candidates (12560 pairs
    at the end)."""
    values = dict(nx=41, ny=41, width=1.0, length=1.0, pinned_edge="y_max", initial_tilt=0.0,
                  initial_height=2.0, water_level=-10.0, floor_level=-20.0)
    on = wetcloth.Simulation(wetcloth.load_scene(**values))
    off = wetcloth.Simulation(wetcloth.load_scene(**values, self_collision="off"))
    most = 0
    for _ in range(15):
        for sim in (on, off):
            sim.advance(1.0 / 30.0)
        counts = on.contact_counts
        most = max(most, counts["point_triangle_candidates"] + counts["edge_edge_candidates"])
    assert np.array_equal(on.state.pos, off.state.pos) and np.array_equal(on.state.vel, off.state.vel)
    assert most == 0 and on.contact_counts["busy_steps"] == 0
    assert on.contact_counts["rebuilds"] < 0.1 * on.steps, (on.contact_counts, on.steps)


def test_a_restored_snapshot_repeats_a_run_in_contact_bit_for_bit(current_over_pin):
    """Snapshot with the layers in contact (2 s), sent through the FMU's byte format and restored twice (into
    the same simulation and into a fresh one): the next 0.5 s repeat exactly, contacts included."""
    values = CURRENT_OVER_PIN | {"nx": 11, "ny": 15, "bend_stiffness": 2.0}
    sim = wetcloth.Simulation(wetcloth.load_scene(**values))
    sim.advance(2.0)
    assert sum(sim.contact_counts[k] for k in ("point_triangle_candidates", "edge_edge_candidates")) > 0
    saved = sim.snapshot()
    data = to_bytes(Checkpoint(values={}, refused={}, initialized=True, start_time=0.0, frames=0, scene=sim.scene,
                               leaves=leaves_of(saved)))
    responses = sim.contact_counts["responses"]
    sim.advance(0.5)
    assert sim.contact_counts["responses"] > responses  # the stage was at work in the repeated interval
    first = (sim.state.pos.copy(), sim.state.vel.copy(), sim.steps)
    for target in (sim, wetcloth.Simulation(sim.scene)):
        target.restore(snapshot_from(from_bytes(data).leaves, sim.scene, target.snapshot()))
        target.advance(0.5)
        assert np.array_equal(target.state.pos, first[0]) and np.array_equal(target.state.vel, first[1])
        assert target.steps == first[2]


def test_fmu_rollback_in_contact_repeats_exactly():
    """Through the FMU itself: getFMUstate with the layers in contact, step, setFMUstate, step again."""
    from test_fmu_support import Unit

    unit = Unit(CURRENT_OVER_PIN | {"nx": 11, "ny": 15, "bend_stiffness": 2.0, "self_collision": "on"})
    try:
        for _ in range(5):
            assert unit.step(0.25) == 0
        saved, time = unit.fmu.getFMUstate(), unit.time
        runs = []
        for _ in range(2):
            unit.fmu.setFMUstate(saved)
            unit.time = time
            rows = []
            for _ in range(2):
                assert unit.step(0.25) == 0
                rows.append(tuple(unit.outputs().values()))
            runs.append(rows)
        unit.fmu.freeFMUstate(saved)
    finally:
        unit.close()
    assert runs[0] == runs[1] and runs[0][0] != runs[0][1]


# --------------------------------------------------------------------------- parameters


@pytest.mark.parametrize("name, value, message", [
    ("self_friction", -0.1, r"'self_friction': -0.1 is out of range; allowed: 0 <= self_friction <= 10"),
    ("self_friction", "high", r"'self_friction': expected a number, got 'high'"),
    ("self_collision", "yes", r"'self_collision': 'yes' is not allowed; allowed: one of 'on', 'off'"),
    ("self_collision", True, r"'self_collision': expected a string, got True"),
])
def test_bad_values_are_refused_by_name(name, value, message):
    with pytest.raises(wetcloth.ParameterError, match=message):
        wetcloth.load_scene(**{name: value})


def test_the_parameters_reach_the_fmu_and_the_listing():
    """Both appear as FMU parameters (a String with its choices, a Real with its range) and in
    ``wetcloth params``'s table, with their defaults."""
    from wetcloth.fmu.vocabulary import variable_specs

    specs = {spec.name: spec for spec in variable_specs()}
    assert (specs["self_collision"].type, specs["self_collision"].start) == ("String", "on")
    assert "one of 'on', 'off'" in specs["self_collision"].description
    friction = specs["self_friction"]
    assert (friction.type, friction.start, friction.min, friction.max) == ("Real", 0.4, 0.0, 10.0)


def test_a_grip_pushing_its_edge_down_into_the_cloth_at_frame_steps_carries_what_it_presses_on():
    """The `wicking` towel (9 x 9) hangs from its y_max edge into a basin; its grip_z input of -0.5 m, reached
    linearly over the first 0.1 s advance, pushes the edge down into the towel below at 5 m/s, at 1/24 s frame
    steps. The edge folds the cloth beneath it onto itself, and self-collision's rigid impact zones take in pinned
    particles: such a zone moves with the grip (before, it stayed where it started and left its pinned particles
    behind: after 0.3 s they lay 94 mm apart, 57 mm short of the grip on average). At the end of each advance the
    whole edge is where the grip put it, within rounding (1e-12 m; the grip's resolution is 1e-9 m), and no edge
    crosses a triangle."""
    scene = wetcloth.load_scene("wicking", nx=9, ny=9, integrator="implicit_euler", tolerance=0.0, max_step=1 / 24,
                                grip_z=-0.5)
    sim = wetcloth.Simulation(scene)
    pinned = sim.model.topology.pinned
    for _ in range(3):
        sim.advance(0.1)
        displacement = sim.state.pos[:, pinned] - sim.model.grip_origin[:, pinned]
        assert np.abs(displacement - np.array([[0.0], [0.0], [-0.5]])).max() < 1e-12, displacement
        assert crossings(sim.positions, sim.triangles) == 0
    assert sim.contact_counts["zone_rounds"] > 0  # (the case it checks)
