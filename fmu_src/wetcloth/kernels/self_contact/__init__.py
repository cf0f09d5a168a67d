"""Self-collision (docs/model.md section 6.2): the cloth never passes through itself and keeps its
layers ``thickness`` apart.

One stage per accepted step, after the floor (``resolve``, called by ``kernels.stepping``):
``broad_phase`` finds the candidate pairs from a spatial hash and keeps them while the motion
allows, ``geometry`` gives their closest points and a conservative continuous collision test,
``response`` pushes layers apart with friction and falls back on rigid impact zones.

``Contact`` holds everything the stage keeps.  What carries over between steps is the candidate
list's reference positions and margin (``snapshot`` / ``restore`` here); the list itself is
rebuilt from them, so a restored run repeats bit for bit.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import typed

from wetcloth.kernels.self_contact.broad_phase import COUNTERS, build
from wetcloth.kernels.self_contact.response import ZONE_ROWS, resolve

__all__ = ["Contact", "make_contact", "resolve", "snapshot", "restore", "invalidate", "candidate_counts", "grid_edges"]

#: ``enabled`` (bool); ``friction`` (-) between layers; ``least_margin`` (m) of a candidate list;
#: ``rest_gap`` (m) between the rest sheet's nearest elements that share no particle (``rest_gap``);
#: the cloth's ``triangles`` (m, 3) and ``edges`` (k, 2) (particle indices) and ``rest`` positions
#: (3, n) in the flat sheet (m); the list's ``reference`` positions (3, n) and ``margin`` (1,) (m; 0
#: when there is none); ``pairs``, a typed list of the point-triangle (particle, triangle) and
#: edge-edge (edge, edge) candidates, each (2, count) int64; scratch of the impact zones ``zone``
#: (n) and ``zone_sums`` (ZONE_ROWS, n); ``counters`` (see ``broad_phase.COUNTERS``).
Contact = namedtuple("Contact", "enabled friction least_margin rest_gap triangles edges rest reference margin pairs zone "
                                "zone_sums counters")

#: A candidate list's least margin, as a fraction of the grid's smaller spacing: the margin of a
#: list that has candidates (or follows one that had).  Smaller margins mean more rebuilds of the
#: list and fewer candidates in it: from 0.2 to 0.05 a crumpled 11 x 15 towel's candidates fell
#: from 9000 to 2000 and its run from 15 s to 4.5 s.  A list that follows an empty one is as wide as
#: keeps it empty, up to ``broad_phase.WIDE_REACH``: with 0.05 everywhere, the default towel's
#: landing (first 0.5 s, no candidates) rebuilt its list 78 times, now 14 (docs/benchmarks.md).
MARGIN_FRACTION = 0.05


def rest_gap(dx: float, dy: float) -> float:
    """The distance (m) of the rest sheet's nearest elements that share no particle, on a grid of
    spacings ``dx``, ``dy`` (m) whose cells are cut by one diagonal: a cell's corner off that
    diagonal and the diagonal."""
    return dx * dy / math.hypot(dx, dy)


def grid_edges(triangles: np.ndarray) -> np.ndarray:
    """The distinct edges (k, 2) of a triangle mesh, each as (lower index, higher index)."""
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    edges.sort(axis=1)
    return np.unique(edges, axis=0).astype(np.int64)


def make_contact(topology, enabled: bool, friction: float) -> Contact:
    """The stage's arrays for a cloth ``topology`` (``wetcloth.topology.Topology``)."""
    n = topology.n
    rest = np.zeros((3, n))
    rest[:2] = topology.rest_xy
    empty = np.zeros((2, 0), dtype=np.int64)
    return Contact(
        enabled=bool(enabled), friction=float(friction), least_margin=MARGIN_FRACTION * min(topology.dx, topology.dy),
        rest_gap=rest_gap(topology.dx, topology.dy),
        triangles=np.ascontiguousarray(topology.triangles, dtype=np.int64), edges=grid_edges(topology.triangles),
        rest=rest, reference=np.zeros((3, n)), margin=np.zeros(1), pairs=typed.List([empty, empty.copy()]),
        zone=np.arange(n, dtype=np.int64), zone_sums=np.zeros((ZONE_ROWS, n)), counters=np.zeros(COUNTERS, dtype=np.int64),
    )


def snapshot(contact: Contact) -> dict:
    """What the stage carries over between steps: the candidate list's reference (3, n) m and margin m."""
    return {"contact_reference": contact.reference.copy(), "contact_margin": float(contact.margin[0])}


def restore(contact: Contact, values: dict, thickness: float) -> None:
    """Return to a ``snapshot``: the same reference and margin, and the list rebuilt from them."""
    contact.reference[...] = values["contact_reference"]
    margin = float(values["contact_margin"])
    if margin > 0.0:
        build(contact, thickness, margin)
    else:
        invalidate(contact)


def invalidate(contact: Contact) -> None:
    """Forget the candidate list (positions were set from outside): the next step builds one."""
    contact.margin[0] = 0.0
    contact.pairs[0] = np.zeros((2, 0), dtype=np.int64)
    contact.pairs[1] = np.zeros((2, 0), dtype=np.int64)


def candidate_counts(contact: Contact) -> tuple[int, int]:
    """(point-triangle, edge-edge) candidates in the current list."""
    return int(contact.pairs[0].shape[1]), int(contact.pairs[1].shape[1])
