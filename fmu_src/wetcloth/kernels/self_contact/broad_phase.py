"""Candidate pairs from a spatial hash, kept while the cloth's motion allows.

A candidate list holds every point-triangle and edge-edge pair whose elements were closer than
``reach = thickness + 2 margin`` at the *reference* positions it was built from.  While every
particle stays within ``margin`` of its reference position, up to a translation common to all
(the distances between elements do not see a common translation), no pair left out can come
within ``thickness``: the list stays valid, and a cloth that only falls or drifts never rebuilds
it.  Pairs of elements that share a particle, or that lie closer than ``thickness`` in the flat
rest sheet (they touch by construction), are never candidates.  A sheet without folds has no
candidates at all, and the step then costs one pass over the positions (``covers``).

A list's margin is at least twice the largest motion of the step it was built for (and at least
``Contact.least_margin``).  A list that follows an empty one is as wide as keeps it empty too, up
to a reach of WIDE_REACH of the rest sheet's nearest non-adjacent elements' distance: it is searched
at that reach and narrowed (``build_widest``), so a sheet that moves fast without folds (a landing)
rebuilds its list a few times, not every few steps, while a folded one keeps lists of few candidates.

The list depends on the reference positions and the margin alone (its pairs ascend, whatever the
hash), so a run restored from a snapshot of those two rebuilds exactly the same list.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth.kernels import counted_kernel as kernel  # builds the candidate lists (typed lists of arrays)
from wetcloth.kernels import kernel as uncounted_kernel
from wetcloth.kernels.self_contact.geometry import EDGE_EDGE, POINT_TRIANGLE, distance

#: Slots of ``Contact.counters`` (int64): candidate lists built; steps that had candidates; passes
#: over them; pairs pushed apart; rounds of impact zones; steps undone as a last resort.
REBUILDS, BUSY_STEPS, PASSES, RESPONSES, ZONE_ROUNDS, FREEZES = range(6)
COUNTERS = 6

#: A list whose margin is more than this many times what the current step needs is rebuilt (``too_loose``).
LOOSE = 4.0
#: The reach of a list tried after an empty one, as a fraction of the rest sheet's nearest
#: non-adjacent elements' distance (``_widest_margin``): room for the sheet to be compressed by a
#: tenth without candidates (more, and the list is narrowed to the widest empty margin there is).
#: 0.9 rather than 0.7: the 81 x 81 sheet's landing rebuilt its (empty) list 59 times instead of
#: 115, the default towel 10 times instead of 14, the folding scenes took the same steps
#: (docs/benchmarks.md, Self-collision).
WIDE_REACH = 0.9

_FIRST_CAPACITY = 256
#: The most hash cells a box spans (``build``'s cells: at most 9 along each axis, 10 if rounding
#: puts both ends on a cell's boundary).
_MOST_CELLS = 10 * 10 * 10
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


@kernel(inline="always")
def _widest_margin(contact, thickness):
    """The widest margin (m) of a list built where the last one was empty: its reach (``thickness`` + 2
    margins) is WIDE_REACH of the rest sheet's nearest non-adjacent elements' distance
    (``Contact.rest_gap``), so a sheet without folds still finds no candidates; at least ``least_margin``."""
    return max(contact.least_margin, 0.5 * (WIDE_REACH * contact.rest_gap - thickness))


@kernel(inline="always")
def candidate_count(contact):
    """How many candidate pairs the current list holds."""
    return contact.pairs[POINT_TRIANGLE].shape[1] + contact.pairs[EDGE_EDGE].shape[1]


@kernel
def too_loose(contact, x0, x1):
    """Whether the list's margin is over LOOSE times what a list built for this step would get: a
    list built for one violent step (a landing) would otherwise hold far-apart pairs for the rest
    of the run.  Costs nothing while the margin is the least one (a cloth that never moved fast) or
    the list is empty (an empty list costs nothing however loose)."""
    margin = contact.margin[0]
    if margin <= LOOSE * contact.least_margin or candidate_count(contact) == 0:
        return False
    motion = _step_motion(x0, x1)
    return math.isfinite(motion) and margin > LOOSE * _margin_for(contact, motion)


@kernel
def rebuild_for_step(contact, thickness, x0, x1):
    """A new list valid for the whole step from ``x0`` to ``x1``: the reference is the midpoint.  The
    margin is the larger of ``Contact.least_margin`` and twice the step's largest motion (common
    translation taken out), which leaves room for the next steps; where the expiring list was empty,
    as wide as keeps the new list empty too, up to ``_widest_margin``.  Returns False (and builds
    nothing) if the step is not finite."""
    motion = _step_motion(x0, x1)
    if not math.isfinite(motion):
        return False  # a blown-up step: the guard after this stage refuses it
    for c in range(3):
        for i in range(x0.shape[1]):
            contact.reference[c, i] = 0.5 * (x0[c, i] + x1[c, i])
    margin = _margin_for(contact, motion)
    if candidate_count(contact) == 0:
        build_widest(contact, thickness, margin, max(margin, _widest_margin(contact, thickness)))
    else:
        build(contact, thickness, margin)
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
def _cell(v, origin, cell):
    return np.int64(math.floor((v - origin) / cell))


@kernel(inline="always")
def _box_cells(lo, hi, e, pad, origin, cell):
    """The hash cells that box ``[lo - pad, hi + pad]`` of element ``e`` overlaps: its first and last
    cells along x, y, z (cells of size ``cell`` counted from ``origin`` (3))."""
    return (_cell(lo[0, e] - pad, origin[0], cell), _cell(lo[1, e] - pad, origin[1], cell),
            _cell(lo[2, e] - pad, origin[2], cell), _cell(hi[0, e] + pad, origin[0], cell),
            _cell(hi[1, e] + pad, origin[1], cell), _cell(hi[2, e] + pad, origin[2], cell))


@kernel(inline="always")
def _cell_count(cells):
    """How many hash cells a box's ``cells`` (``_box_cells``) holds."""
    return (cells[3] - cells[0] + 1) * (cells[4] - cells[1] + 1) * (cells[5] - cells[2] + 1)


@kernel(inline="always")
def _buckets(cells, mask, out):
    """Write the hash buckets of a box's ``cells`` (``_box_cells``) to ``out``; returns how many.
    (Nested loops: the integer divisions of one flat loop over the cells cost most of a rebuild.)"""
    count = 0
    for ix in range(cells[0], cells[3] + 1):
        hx = ix * _HASH_X
        for iy in range(cells[1], cells[4] + 1):
            hxy = hx ^ (iy * _HASH_Y)
            for iz in range(cells[2], cells[5] + 1):
                out[count] = (hxy ^ (iz * _HASH_Z)) & mask
                count += 1
    return count


@kernel
def _hash(lo, hi, pad, origin, cell, out):
    """Spatial hash of boxes ``[lo - pad, hi + pad]`` (3, m): each box is listed in the bucket of every
    cell it overlaps (``out``: scratch for one box's buckets).  Returns (start (buckets + 1), items,
    mask): bucket b (a cell's hash ``& mask``) holds items[start[b]:start[b+1]], in ascending order."""
    entries = 0
    for e in range(lo.shape[1]):
        entries += _cell_count(_box_cells(lo, hi, e, pad, origin, cell))
    mask = _table_mask(entries)
    count = np.zeros(mask + 2, dtype=np.int64)
    for e in range(lo.shape[1]):
        for k in range(_buckets(_box_cells(lo, hi, e, pad, origin, cell), mask, out)):
            count[out[k] + 1] += 1
    for b in range(mask + 1):
        count[b + 1] += count[b]
    start = count.copy()
    items = np.empty(entries, dtype=np.int64)
    for e in range(lo.shape[1]):
        for k in range(_buckets(_box_cells(lo, hi, e, pad, origin, cell), mask, out)):
            items[count[out[k]]] = e
            count[out[k]] += 1
    return start, items, mask


@kernel
def _table_mask(entries):
    """Hash mask: a power of two at least the entries (and at least 2), minus one."""
    size = 2
    while size < entries:
        size *= 2
    return size - 1


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
def _candidate_distance(kind, x, rest, a, b, c, d, reach, thickness):
    """The distance (m) at ``x`` of elements of particles (a | b, c, d) for POINT_TRIANGLE or
    (a, b | c, d) for EDGE_EDGE if they are a candidate pair: within ``reach`` (m), and not already
    closer than ``thickness`` (m) in the flat rest sheet (such neighbours are the fabric itself, not
    two layers); infinity if they are not."""
    gap = distance(kind, point(x, a), point(x, b), point(x, c), point(x, d))
    if gap >= reach or distance(kind, point(rest, a), point(rest, b), point(rest, c), point(rest, d)) < thickness:
        return math.inf
    return gap


@kernel(inline="always")
def _kept(first_lo, first_hi, a, lo, hi, b, gap, reach):
    """Whether a pair (element ``a`` of the first boxes, ``b`` of the second) at distance ``gap`` (m;
    ``_candidate_distance``) is a candidate at ``reach`` (m): the one test of ``_pairs`` and ``_within``."""
    return _boxes_overlap(first_lo, first_hi, a, lo, hi, b, reach) and gap < reach


@kernel
def _pairs(kind, x, rest, first, first_lo, first_hi, second, lo, hi, reach, thickness, origin, cell, out):
    """The candidate pairs (2, count) of one ``kind``: (a, b) for element ``a`` of ``first`` (particles
    (count, 1) for POINT_TRIANGLE, edges for EDGE_EDGE; boxes ``first_lo``, ``first_hi``) and element
    ``b`` of ``second`` (triangles, or the same edges: then each pair once, a < b; boxes ``lo``, ``hi``),
    found through a spatial hash of the second elements' boxes grown by ``reach`` (cells of ``cell``
    from ``origin``; ``out``: scratch for one box's buckets), and their distances (1, count) m.  The
    pairs come in ascending order of (a, b), whatever the hash: the order the stage treats them in
    depends on the list alone.  The search (``_search``) fills arrays allocated here, and is run
    again with twice the room if they were too small."""
    start, items, mask = _hash(lo, hi, reach, origin, cell, out)
    seen = np.empty(second.shape[0], dtype=np.int64)
    capacity = _FIRST_CAPACITY
    while True:
        pairs = np.empty((2, capacity), dtype=np.int64)
        gaps = np.empty((1, capacity))
        count = _search(kind, x, rest, first, first_lo, first_hi, second, lo, hi, reach, thickness, origin, cell,
                        out, start, items, mask, seen, pairs, gaps)
        if count >= 0:
            return pairs[:, :count].copy(), gaps[:, :count].copy()
        capacity *= 2


@uncounted_kernel
def _search(kind, x, rest, first, first_lo, first_hi, second, lo, hi, reach, thickness, origin, cell, out, start,
            items, mask, seen, pairs, gaps):
    """``_pairs``' search through the hash (``start``, ``items``, ``mask`` from ``_hash``) into ``pairs``
    and ``gaps``; ``seen`` (one slot per second element) is scratch.  Returns how many pairs it found,
    or -1 if they did not fit.  It allocates nothing, so it is compiled without reference counting:
    counted, the arrays handed to the helpers it inlines for every pair it tests were each taken and
    released (atomic instructions: a quarter of a rebuild's time on an 81 x 81 sheet, perf)."""
    for e in range(seen.shape[0]):
        seen[e] = -1
    count = 0
    for a in range(first.shape[0]):
        found = count
        for q in range(_buckets(_box_cells(first_lo, first_hi, a, 0.0, origin, cell), mask, out)):
            b = out[q]
            for k in range(start[b + 1] - 1, start[b] - 1, -1):  # a bucket's items ascend (``_hash``)
                e = items[k]
                if kind == EDGE_EDGE and e <= a:
                    break  # each edge-edge pair once, from its lower edge
                if seen[e] == a:
                    continue
                seen[e] = a
                if _share_a_particle(first, second, a, e) or not _boxes_overlap(first_lo, first_hi, a, lo, hi, e, reach):
                    continue
                gap = _candidate_distance(kind, x, rest, _particle(first, second, a, e, 0),
                                          _particle(first, second, a, e, 1), _particle(first, second, a, e, 2),
                                          _particle(first, second, a, e, 3), reach, thickness)
                if not _kept(first_lo, first_hi, a, lo, hi, e, gap, reach):
                    continue
                if count == pairs.shape[1]:
                    return -1
                pairs[0, count], pairs[1, count], gaps[0, count] = a, e, gap
                count += 1
        _sort_partners(pairs, gaps, found, count)
    return count


@kernel(inline="always")
def _sort_partners(pairs, gaps, begin, end):
    """Sort columns ``begin:end`` of ``pairs`` (one element's few partners) and ``gaps`` by the
    partner ``pairs[1]``, in place, by insertion."""
    for i in range(begin + 1, end):
        b, gap = pairs[1, i], gaps[0, i]
        j = i
        while j > begin and pairs[1, j - 1] > b:
            pairs[1, j], gaps[0, j] = pairs[1, j - 1], gaps[0, j - 1]
            j -= 1
        pairs[1, j], gaps[0, j] = b, gap


@kernel
def _within(pairs, gaps, first_lo, first_hi, lo, hi, reach):
    """The pairs (2, count) of a list (with their distances ``gaps`` (1, count) m, ``_pairs``) that are
    candidates at the smaller ``reach`` (m): those a list built for it holds, in the same order."""
    kept = 0
    for k in range(pairs.shape[1]):
        kept += _kept(first_lo, first_hi, pairs[0, k], lo, hi, pairs[1, k], gaps[0, k], reach)
    narrow = np.empty((2, kept), dtype=np.int64)
    kept = 0
    for k in range(pairs.shape[1]):
        if _kept(first_lo, first_hi, pairs[0, k], lo, hi, pairs[1, k], gaps[0, k], reach):
            narrow[0, kept], narrow[1, kept] = pairs[0, k], pairs[1, k]
            kept += 1
    return narrow


@kernel(inline="always")
def _nearest(gaps):
    """The smallest of a list's distances ``gaps`` (1, count) m; infinity if it is empty."""
    nearest = math.inf
    for k in range(gaps.shape[1]):
        nearest = min(nearest, gaps[0, k])
    return nearest


@kernel
def build(contact, thickness, margin):
    """Build the candidate lists from ``contact.reference`` for ``margin`` (m) and keep the margin."""
    build_widest(contact, thickness, margin, margin)


@kernel
def build_widest(contact, thickness, least, widest):
    """Build the candidate lists from ``contact.reference`` for the widest margin from ``least`` to
    ``widest`` (m) whose lists are empty, or for ``least`` if none is (the lists searched at
    ``widest`` and narrowed: the same lists as ``build`` for that margin, so a restored run repeats
    them); keep that margin."""
    x = contact.reference
    reach = thickness + 2.0 * widest
    triangles, edges = contact.triangles, contact.edges
    tri_lo = np.empty((3, triangles.shape[0]))
    tri_hi = np.empty((3, triangles.shape[0]))
    edge_lo = np.empty((3, edges.shape[0]))
    edge_hi = np.empty((3, edges.shape[0]))
    _boxes(x, triangles, tri_lo, tri_hi)
    _boxes(x, edges, edge_lo, edge_hi)
    # Cells as large as a typical triangle's box grown by the reach: a box then spans a few cells.
    # (Cells of at least an eighth of the largest box: no box spans more than 9 cells along an axis.)
    # The cells start at the lowest grown box, so that a flat sheet's boxes lie in one layer of cells.
    total = 0.0
    largest = 0.0
    origin = np.full(3, math.inf)
    for t in range(triangles.shape[0]):
        extent = max(tri_hi[0, t] - tri_lo[0, t], tri_hi[1, t] - tri_lo[1, t], tri_hi[2, t] - tri_lo[2, t])
        total += extent
        largest = max(largest, extent)
        for c in range(3):
            origin[c] = min(origin[c], tri_lo[c, t] - reach)
    cell = max(total / max(1, triangles.shape[0]), 0.125 * largest) + 2.0 * reach
    out = np.empty(_MOST_CELLS, dtype=np.int64)
    particles = np.arange(x.shape[1]).reshape((x.shape[1], 1))
    point_triangle, point_gaps = _pairs(POINT_TRIANGLE, x, contact.rest, particles, x, x, triangles, tri_lo, tri_hi,
                                        reach, thickness, origin, cell, out)
    edge_edge, edge_gaps = _pairs(EDGE_EDGE, x, contact.rest, edges, edge_lo, edge_hi, edges, edge_lo, edge_hi, reach,
                                  thickness, origin, cell, out)
    # The widest margin whose lists are empty: the nearest pair just out of reach.
    margin = max(least, min(widest, 0.5 * (min(_nearest(point_gaps), _nearest(edge_gaps)) - thickness)))
    if margin < widest:
        reach = thickness + 2.0 * margin
        point_triangle = _within(point_triangle, point_gaps, x, x, tri_lo, tri_hi, reach)
        edge_edge = _within(edge_edge, edge_gaps, edge_lo, edge_hi, edge_lo, edge_hi, reach)
    contact.pairs[POINT_TRIANGLE] = point_triangle
    contact.pairs[EDGE_EDGE] = edge_edge
    contact.margin[0] = margin
    contact.counters[REBUILDS] += 1
