"""Candidate pairs from a spatial hash, kept while the cloth's motion allows.

A candidate list holds every point-triangle and edge-edge pair whose elements were closer than
``reach = thickness + 2 margin`` at the *reference* positions it was built from.  While every
particle stays within ``margin`` of its reference position, up to a translation common to all
(the distances between elements do not see a common translation), no pair left out can come
within ``thickness``: the list stays valid, and a cloth that only falls or drifts never rebuilds
it.  Pairs of elements that share a particle, or that lie closer than ``thickness`` in the flat
rest sheet (they touch by construction), are never candidates.  A sheet without folds has no
candidates at all, and the step then costs one pass over the positions (``covers``).

The list depends on the reference positions and the margin alone, so a run restored from a
snapshot of those two rebuilds exactly the same list.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth.kernels import kernel
from wetcloth.kernels.self_contact.geometry import EDGE_EDGE, POINT_TRIANGLE, distance

#: Slots of ``Contact.counters`` (int64): candidate lists built; steps that had candidates; passes
#: over them; pairs pushed apart; rounds of impact zones; steps undone as a last resort.
REBUILDS, BUSY_STEPS, PASSES, RESPONSES, ZONE_ROUNDS, FREEZES = range(6)
COUNTERS = 6

#: A list whose margin is more than this many times what the current step needs is rebuilt (``too_loose``).
LOOSE = 4.0

_FIRST_CAPACITY = 256
_HASH_X, _HASH_Y, _HASH_Z = 73856093, 19349663, 83492791  # Teschner et al. 2003


@kernel(inline="always")
def point(x, i):
    return (x[0, i], x[1, i], x[2, i])


@kernel
def covers(contact, x):
    """Whether the candidate list is valid for positions ``x`` (3, n): each within the margin of its
    reference position, once the mid-range of all displacements is taken out."""
    margin = contact.margin[0]
    return margin > 0.0 and _largest_motion_squared(contact.reference, x) <= margin * margin


@kernel
def _largest_motion_squared(x0, x1):
    """The largest squared displacement (m^2) of a particle from ``x0`` to ``x1``, once the mid-range of
    all displacements (a common translation) is taken out; NaN if a displacement is not finite."""
    n = x0.shape[1]
    shift = np.empty(3)
    for c in range(3):
        lo, hi = math.inf, -math.inf
        for i in range(n):
            d = x1[c, i] - x0[c, i]
            if not math.isfinite(d):
                return math.nan
            lo = min(lo, d)
            hi = max(hi, d)
        shift[c] = 0.5 * (lo + hi)
    largest = 0.0
    for i in range(n):
        dx = x1[0, i] - x0[0, i] - shift[0]
        dy = x1[1, i] - x0[1, i] - shift[1]
        dz = x1[2, i] - x0[2, i] - shift[2]
        largest = max(largest, dx * dx + dy * dy + dz * dz)
    return largest


@kernel(inline="always")
def _step_motion(x0, x1):
    """The largest displacement (m) of a particle over the step from ``x0`` to ``x1`` (common translation
    taken out; ``_largest_motion_squared``); NaN if the step is not finite."""
    return math.sqrt(_largest_motion_squared(x0, x1))


@kernel(inline="always")
def _margin_for(contact, motion):
    """The margin of a list built for a step of ``motion`` (m): twice that, at least ``least_margin``."""
    return max(contact.least_margin, 2.0 * motion)


@kernel
def too_loose(contact, x0, x1):
    """Whether the list's margin is over LOOSE times what a list built for this step would get: a
    list built for one violent step (a landing) would otherwise hold far-apart pairs for the rest
    of the run.  Costs nothing while the margin is the least one (a cloth that never moved fast)."""
    margin = contact.margin[0]
    if margin <= LOOSE * contact.least_margin:
        return False
    motion = _step_motion(x0, x1)
    return math.isfinite(motion) and margin > LOOSE * _margin_for(contact, motion)


@kernel
def rebuild_for_step(contact, thickness, x0, x1):
    """A new list valid for the whole step from ``x0`` to ``x1``: the reference is the midpoint, the
    margin the larger of ``Contact.least_margin`` and twice the step's largest motion (common
    translation taken out), which leaves room for the next steps.  Returns False (and builds nothing)
    if the step is not finite."""
    motion = _step_motion(x0, x1)
    if not math.isfinite(motion):
        return False  # a blown-up step: the guard after this stage refuses it
    for c in range(3):
        for i in range(x0.shape[1]):
            contact.reference[c, i] = 0.5 * (x0[c, i] + x1[c, i])
    build(contact, thickness, _margin_for(contact, motion))
    return True


@kernel
def _boxes(x, elements, lo, hi):
    for e in range(elements.shape[0]):
        for c in range(3):
            a = math.inf
            b = -math.inf
            for k in range(elements.shape[1]):
                v = x[c, elements[e, k]]
                a = min(a, v)
                b = max(b, v)
            lo[c, e] = a
            hi[c, e] = b


@kernel(inline="always")
def _cell(v, cell):
    return np.int64(math.floor(v / cell))


@kernel(inline="always")
def _box_cells(lo, hi, e, pad, cell):
    """The hash cells that box ``[lo - pad, hi + pad]`` of element ``e`` overlaps: its first cell
    (ix, iy, iz) and how many cells it spans along x, y, z (each at least 1)."""
    ix, iy, iz = _cell(lo[0, e] - pad, cell), _cell(lo[1, e] - pad, cell), _cell(lo[2, e] - pad, cell)
    return (ix, iy, iz, _cell(hi[0, e] + pad, cell) - ix + 1, _cell(hi[1, e] + pad, cell) - iy + 1,
            _cell(hi[2, e] + pad, cell) - iz + 1)


@kernel(inline="always")
def _cell_count(cells):
    """How many hash cells a box's ``cells`` (``_box_cells``) holds."""
    return cells[3] * cells[4] * cells[5]


@kernel(inline="always")
def _bucket(cells, c, mask):
    """The hash bucket of cell ``c`` (0 to ``_cell_count(cells) - 1``; x slowest, z fastest) of a box's
    ``cells`` (``_box_cells``)."""
    ix, iy, iz, _, ny, nz = cells
    return (((ix + c // (ny * nz)) * _HASH_X) ^ ((iy + c // nz % ny) * _HASH_Y) ^ ((iz + c % nz) * _HASH_Z)) & mask


@kernel
def _hash(lo, hi, pad, cell, mask):
    """Spatial hash of boxes ``[lo - pad, hi + pad]`` (3, m): each box is listed in the bucket of every
    cell it overlaps.  Returns (start (buckets + 1), items): bucket b holds items[start[b]:start[b+1]]."""
    count = np.zeros(mask + 2, dtype=np.int64)
    for e in range(lo.shape[1]):
        cells = _box_cells(lo, hi, e, pad, cell)
        for c in range(_cell_count(cells)):
            count[_bucket(cells, c, mask) + 1] += 1
    for b in range(mask + 1):
        count[b + 1] += count[b]
    start = count.copy()
    items = np.empty(count[mask + 1], dtype=np.int64)
    for e in range(lo.shape[1]):
        cells = _box_cells(lo, hi, e, pad, cell)
        for c in range(_cell_count(cells)):
            b = _bucket(cells, c, mask)
            items[count[b]] = e
            count[b] += 1
    return start, items


@kernel
def _buckets_for(entries):
    """Hash mask: a power of two at least twice the entries, minus one."""
    size = 1
    while size < 2 * entries:
        size *= 2
    return size - 1


@kernel
def _append(pairs, count, a, b):
    """Append (a, b) to a (2, capacity) array, doubling it when full; returns the array."""
    if count == pairs.shape[1]:
        grown = np.empty((2, 2 * pairs.shape[1]), dtype=np.int64)
        for k in range(count):  # element by element: a slice assignment's shape checks cost seconds of compiling
            grown[0, k] = pairs[0, k]
            grown[1, k] = pairs[1, k]
        pairs = grown
    pairs[0, count] = a
    pairs[1, count] = b
    return pairs


@kernel(inline="always")
def _boxes_overlap(lo, hi, a, lo2, hi2, b, pad):
    return (lo[0, a] <= hi2[0, b] + pad and lo2[0, b] - pad <= hi[0, a] and lo[1, a] <= hi2[1, b] + pad
            and lo2[1, b] - pad <= hi[1, a] and lo[2, a] <= hi2[2, b] + pad and lo2[2, b] - pad <= hi[2, a])


@kernel(inline="always")
def _particle(first, second, a, b, slot):
    """Particle ``slot`` (0 to 3) of the pair of element ``a`` (a row of ``first``) and ``b`` (of ``second``)."""
    return first[a, slot] if slot < first.shape[1] else second[b, slot - first.shape[1]]


@kernel(inline="always")
def _share_a_particle(first, second, a, b):
    """Whether element ``a`` of ``first`` and ``b`` of ``second`` have a particle in common."""
    for i in range(first.shape[1]):
        for j in range(second.shape[1]):
            if first[a, i] == second[b, j]:
                return True
    return False


@kernel(inline="always")
def _candidate(kind, x, rest, a, b, c, d, reach, thickness):
    """Whether elements of particles (a | b, c, d) for POINT_TRIANGLE or (a, b | c, d) for EDGE_EDGE
    are a candidate pair: within ``reach`` (m) now, and not already closer than ``thickness`` (m)
    in the flat rest sheet (such neighbours are the fabric itself, not two layers)."""
    if distance(kind, point(x, a), point(x, b), point(x, c), point(x, d)) >= reach:
        return False
    return distance(kind, point(rest, a), point(rest, b), point(rest, c), point(rest, d)) >= thickness


@kernel
def _pairs(kind, x, rest, first, first_lo, first_hi, second, lo, hi, reach, thickness, cell):
    """The candidate pairs (2, count) of one ``kind``: (a, b) for element ``a`` of ``first`` (particles
    (count, 1) for POINT_TRIANGLE, edges for EDGE_EDGE; boxes ``first_lo``, ``first_hi``) and element
    ``b`` of ``second`` (triangles, or the same edges: then each pair once, a < b; boxes ``lo``, ``hi``),
    found through a spatial hash of the second elements' boxes grown by ``reach``."""
    mask = _buckets_for(8 * second.shape[0])
    start, items = _hash(lo, hi, reach, cell, mask)
    seen = np.full(second.shape[0], -1, dtype=np.int64)
    pairs = np.empty((2, _FIRST_CAPACITY), dtype=np.int64)
    count = 0
    for a in range(first.shape[0]):
        cells = _box_cells(first_lo, first_hi, a, 0.0, cell)
        for c in range(_cell_count(cells)):
            b = _bucket(cells, c, mask)
            for k in range(start[b], start[b + 1]):
                e = items[k]
                if (kind == EDGE_EDGE and e <= a) or seen[e] == a:
                    continue
                seen[e] = a
                if _share_a_particle(first, second, a, e) or not _boxes_overlap(first_lo, first_hi, a, lo, hi, e, reach):
                    continue
                if not _candidate(kind, x, rest, _particle(first, second, a, e, 0), _particle(first, second, a, e, 1),
                                  _particle(first, second, a, e, 2), _particle(first, second, a, e, 3), reach, thickness):
                    continue
                pairs = _append(pairs, count, a, e)
                count += 1
    return pairs[:, :count].copy()


@kernel
def build(contact, thickness, margin):
    """Build the candidate lists from ``contact.reference`` for ``margin`` (m) and keep the margin."""
    x = contact.reference
    reach = thickness + 2.0 * margin
    triangles, edges = contact.triangles, contact.edges
    tri_lo = np.empty((3, triangles.shape[0]))
    tri_hi = np.empty((3, triangles.shape[0]))
    edge_lo = np.empty((3, edges.shape[0]))
    edge_hi = np.empty((3, edges.shape[0]))
    _boxes(x, triangles, tri_lo, tri_hi)
    _boxes(x, edges, edge_lo, edge_hi)
    # Cells as large as a typical triangle's box grown by the reach: a box then spans a few cells.
    # (Cells of at least an eighth of the largest box: no box spans more than a few thousand cells.)
    total = 0.0
    largest = 0.0
    for t in range(triangles.shape[0]):
        extent = max(tri_hi[0, t] - tri_lo[0, t], tri_hi[1, t] - tri_lo[1, t], tri_hi[2, t] - tri_lo[2, t])
        total += extent
        largest = max(largest, extent)
    cell = max(total / max(1, triangles.shape[0]), 0.125 * largest) + 2.0 * reach
    particles = np.arange(x.shape[1]).reshape((x.shape[1], 1))
    contact.pairs[POINT_TRIANGLE] = _pairs(POINT_TRIANGLE, x, contact.rest, particles, x, x, triangles, tri_lo, tri_hi,
                                           reach, thickness, cell)
    contact.pairs[EDGE_EDGE] = _pairs(EDGE_EDGE, x, contact.rest, edges, edge_lo, edge_hi, edges, edge_lo, edge_hi, reach,
                                      thickness, cell)
    contact.margin[0] = margin
    contact.counters[REBUILDS] += 1
