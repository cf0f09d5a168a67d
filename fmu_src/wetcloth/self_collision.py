"""The arrays of self-collision (the compiled core's ``self_contact/``; docs/model.md section 6.2):
the cloth never passes through itself and keeps its layers 0.9 to 1 ``thickness`` apart.

One stage per accepted step, after the floor: a spatial hash finds the candidate pairs (point and
triangle, edge and edge) and the list is kept while the motion allows; close pairs are pushed apart
with friction, and rigid impact zones are the fallback.  The candidate lists live in the core (a
``_core.Stepper`` owns them); what carries over between steps is the list's reference positions and
margin (``snapshot``), from which a restored run rebuilds the very same list.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from wetcloth._core import CONTACT_COUNTERS, ZONE_ROWS

#: ``enabled`` (bool); ``friction`` (-) between layers; ``least_margin`` (m) of a candidate list;
#: ``rest_gap`` (m) between the rest sheet's nearest elements that share no particle (``rest_gap``);
#: ``typical_gap`` (m): a mesh's median triangle altitude (a grid's rest gap), what caps the particles' own
#: allowances in the finest tier (docs/model.md 6.2);
#: the cloth's ``triangles`` (m, 3) and ``edges`` (k, 2) (particle indices) and ``rest`` positions
#: (3, n) in the flat sheet (m); the list's ``reference`` positions (3, n) and ``margin`` (1,) (m; 0
#: when there is none); scratch of the impact zones ``zone`` (n) and ``zone_sums`` (ZONE_ROWS, n);
#: ``counters``: lists built, steps that had candidates, passes over them, pairs pushed apart, rounds
#: of impact zones, steps undone as a last resort.
Contact = namedtuple("Contact", "enabled friction least_margin rest_gap typical_gap triangles edges rest reference margin zone "
                                "zone_sums counters")
COUNTER_NAMES = ("rebuilds", "busy_steps", "passes", "responses", "zone_rounds", "freezes")

#: A candidate list's least margin, as a fraction of the grid's smaller spacing: the margin of a
#: list that has candidates (or follows one that had).  Smaller margins mean more rebuilds of the
#: list and fewer candidates in it: from 0.2 to 0.05 a crumpled 11 x 15 towel's candidates fell
#: from 9000 to 2000 and its run from 15 s to 4.5 s.  A list that follows an empty one is as wide as
#: keeps it empty (the core's WIDE_REACH): with 0.05 everywhere, the default towel's landing (first
#: 0.5 s, no candidates) rebuilt its list 78 times, now 10 (docs/benchmarks.md).
MARGIN_FRACTION = 0.05


def rest_gap(dx: float, dy: float) -> float:
    """The distance (m) of the rest sheet's nearest elements that share no particle, on a grid of
    spacings ``dx``, ``dy`` (m) whose cells are cut by one diagonal: a cell's corner off that
    diagonal and the diagonal."""
    return dx * dy / math.hypot(dx, dy)


def grid_edges(triangles: np.ndarray) -> np.ndarray:
    """The distinct edges (k, 2) int64 of a triangle mesh, each as (lower index, higher index), in ascending order."""
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]).astype(np.int64)
    edges.sort(axis=1)
    # One number per edge that sorts as its row does (a third of the time of np.unique over the rows).
    span = int(edges.max()) + 1 if len(edges) else 1
    keys = np.unique(edges[:, 0] * span + edges[:, 1])
    return np.stack([keys // span, keys % span], axis=1)


def altitudes(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The smallest altitude (m) of each of the triangles (m, 3) of points (3, n) m: a corner's distance from
    the opposite edge's line (on a grid, ``rest_gap``)."""
    p = points.T[triangles]
    double_area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    longest = np.max([np.linalg.norm(p[:, (k + 1) % 3] - p[:, k], axis=1) for k in range(3)], axis=0)
    return double_area / longest


def make_contact(topology, enabled: bool, friction: float) -> Contact:
    """The stage's arrays for a cloth ``topology`` (``wetcloth.topology.Topology``).  A mesh's rest gap is
    the smallest altitude of its triangles in the flat rest sheet, its least margin MARGIN_FRACTION of that,
    its typical gap their median altitude."""
    n = topology.n
    rest = np.zeros((3, n))
    rest[:2] = topology.rest_xy
    if topology.pairs.shape[1] == 0:  # the grid's families (also of a file that forms the grid)
        gap, least = rest_gap(topology.dx, topology.dy), MARGIN_FRACTION * min(topology.dx, topology.dy)
        typical = gap
    else:
        heights = altitudes(rest, topology.triangles)
        gap, typical = float(np.min(heights)), float(np.median(heights))
        least = MARGIN_FRACTION * gap
    return Contact(
        enabled=bool(enabled), friction=float(friction), least_margin=least, rest_gap=gap, typical_gap=typical,
        triangles=np.ascontiguousarray(topology.triangles, dtype=np.int64), edges=grid_edges(topology.triangles),
        rest=rest, reference=np.zeros((3, n)), margin=np.zeros(1), zone=np.arange(n, dtype=np.int64),
        zone_sums=np.zeros((ZONE_ROWS, n)), counters=np.zeros(CONTACT_COUNTERS, dtype=np.int64),
    )


def snapshot(contact: Contact) -> dict:
    """What the stage carries over between steps: the candidate list's reference (3, n) m and margin m."""
    return {"contact_reference": contact.reference.copy(), "contact_margin": float(contact.margin[0])}
