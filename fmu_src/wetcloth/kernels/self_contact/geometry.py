"""Closest points of the two kinds of contact pair, and a conservative continuous collision test.

A *pair* is four particles: a point and a triangle (``POINT_TRIANGLE``: p, a, b, c) or two edges
(``EDGE_EDGE``: p1, q1, p2, q2).  Its closest points are given by four *weights* ``w`` (the point
side positive, the other side negative, each side summing to 1), so that ``sum_k w_k x_k`` is the
vector from the closest point of the second element to that of the first, whose length is the
pair's distance and whose direction is the contact normal.  Positions are 3-tuples of floats (m).
"""

from __future__ import annotations

import math

from wetcloth.kernels import kernel

POINT_TRIANGLE, EDGE_EDGE = 0, 1

#: Squared lengths (relative to the elements' size squared) below which an edge counts as a point
#: and two edges as parallel.
_DEGENERATE = 1e-14
#: Additive CCD (Li, Kaufman and Jiang 2021, "Codimensional Incremental Potential Contact", section
#: 4): the pair is cleared once its gap can be shown to stay above zero; a contact is reported when
#: the gap falls below CCD_REPORT of its value at the start.  At most CCD_ITERATIONS advances
#: (then a contact is reported: the answer stays conservative).
CCD_REPORT = 0.1
CCD_ADVANCE = 0.9
CCD_ITERATIONS = 200
#: What ``time_of_contact`` returns for a motion that stays clear.
CLEAR = 2.0


@kernel(inline="always")
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@kernel(inline="always")
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@kernel(inline="always")
def _clamp01(v):
    return min(1.0, max(0.0, v))


@kernel(inline="always")
def along(x, t, p):
    """The point ``x + t p`` (a 3-tuple): where ``x`` is after a fraction ``t`` of its motion ``p``."""
    return (x[0] + t * p[0], x[1] + t * p[1], x[2] + t * p[2])


@kernel
def _segment_segment(p1, q1, p2, q2):
    """Parameters (s, t) in [0, 1] of the closest points ``p1 + s (q1 - p1)``, ``p2 + t (q2 - p2)``
    (Ericson, "Real-Time Collision Detection", 5.1.9; parallel segments get one of their closest pairs)."""
    d1 = _sub(q1, p1)
    d2 = _sub(q2, p2)
    r = _sub(p1, p2)
    a = _dot(d1, d1)
    e = _dot(d2, d2)
    f = _dot(d2, r)
    tiny = _DEGENERATE * max(a, e, 1e-300)
    if a <= tiny and e <= tiny:
        return 0.0, 0.0
    if a <= tiny:
        return 0.0, _clamp01(f / e)
    c = _dot(d1, r)
    if e <= tiny:
        return _clamp01(-c / a), 0.0
    b = _dot(d1, d2)
    denom = a * e - b * b
    s = _clamp01((b * f - c * e) / denom) if denom > _DEGENERATE * a * e else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        return _clamp01(-c / a), 0.0
    if t > 1.0:
        return _clamp01((b - c) / a), 1.0
    return s, t


@kernel
def _point_segment(p, a, b):
    """Parameter in [0, 1] of the point of segment ab closest to p."""
    ab = _sub(b, a)
    length2 = _dot(ab, ab)
    if length2 <= 0.0:
        return 0.0
    return _clamp01(_dot(_sub(p, a), ab) / length2)


@kernel
def _point_triangle(p, a, b, c):
    """Barycentric weights (u, v, w) of the point of triangle abc closest to p (Ericson 5.1.5; a
    degenerate triangle is treated through its edges)."""
    ab = _sub(b, a)
    ac = _sub(c, a)
    ap = _sub(p, a)
    d1 = _dot(ab, ap)
    d2 = _dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0
    bp = _sub(p, b)
    d3 = _dot(ab, bp)
    d4 = _dot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return 1.0 - v, v, 0.0
    cp = _sub(p, c)
    d5 = _dot(ab, cp)
    d6 = _dot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return 1.0 - w, 0.0, w
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 0.0, 1.0 - w, w
    total = va + vb + vc
    if total > 0.0:
        v = vb / total
        w = vc / total
        return 1.0 - v - w, v, w
    # A triangle of (nearly) no area: the closest of its three edges.
    corners = (a, b, c)
    best = math.inf
    weights = (1.0, 0.0, 0.0)
    for k in range(3):
        start, end = corners[k], corners[(k + 1) % 3]
        t = _point_segment(p, start, end)
        d = _sub(p, along(start, t, _sub(end, start)))
        if _dot(d, d) < best:
            best = _dot(d, d)
            if k == 0:
                weights = (1.0 - t, t, 0.0)
            elif k == 1:
                weights = (0.0, 1.0 - t, t)
            else:
                weights = (t, 0.0, 1.0 - t)
    return weights


@kernel
def closest(kind, x0, x1, x2, x3):
    """Weights (w0, w1, w2, w3) of the pair's closest points (see the module's docstring)."""
    if kind == POINT_TRIANGLE:
        u, v, w = _point_triangle(x0, x1, x2, x3)
        return 1.0, -u, -v, -w
    s, t = _segment_segment(x0, x1, x2, x3)
    return 1.0 - s, s, t - 1.0, -t


@kernel(inline="always")
def combine(w, x0, x1, x2, x3):
    """``sum_k w_k x_k`` (a 3-tuple)."""
    return (w[0] * x0[0] + w[1] * x1[0] + w[2] * x2[0] + w[3] * x3[0],
            w[0] * x0[1] + w[1] * x1[1] + w[2] * x2[1] + w[3] * x3[1],
            w[0] * x0[2] + w[1] * x1[2] + w[2] * x2[2] + w[3] * x3[2])


@kernel
def distance(kind, x0, x1, x2, x3):
    """Distance (m) between the pair's elements."""
    d = combine(closest(kind, x0, x1, x2, x3), x0, x1, x2, x3)
    return math.sqrt(_dot(d, d))


@kernel(inline="always")
def _norm(a):
    return math.sqrt(_dot(a, a))


@kernel
def motion_bound(kind, p0, p1, p2, p3):
    """Largest change (m) of the pair's distance over straight-line displacements p0..p3: after the
    mean displacement is taken out, the largest on one side plus the largest on the other."""
    mx = 0.25 * (p0[0] + p1[0] + p2[0] + p3[0])
    my = 0.25 * (p0[1] + p1[1] + p2[1] + p3[1])
    mz = 0.25 * (p0[2] + p1[2] + p2[2] + p3[2])
    mean = (mx, my, mz)
    n0, n1, n2, n3 = _norm(_sub(p0, mean)), _norm(_sub(p1, mean)), _norm(_sub(p2, mean)), _norm(_sub(p3, mean))
    if kind == POINT_TRIANGLE:
        return n0 + max(n1, n2, n3)
    return max(n0, n1) + max(n2, n3)


@kernel
def time_of_contact(kind, x0, x1, x2, x3, p0, p1, p2, p3, start_distance, minimum):
    """Additive CCD: the pair moves from x0..x3 by p0..p3 over the step (fraction 0 to 1).  Returns
    CLEAR if its distance provably stays above ``minimum`` (m) throughout, else a fraction at which
    it is still above ``minimum`` but has lost at least 1 - CCD_REPORT of its starting gap
    (``start_distance - minimum``, which must be positive): the moment to treat the contact."""
    bound = motion_bound(kind, p0, p1, p2, p3)
    gap = start_distance - minimum
    if bound <= 0.0 or gap >= bound:
        return CLEAR
    if gap <= 0.0:
        return 0.0
    report = CCD_REPORT * gap
    t = 0.0
    advance = (1.0 - CCD_REPORT) * gap / bound
    for _ in range(CCD_ITERATIONS):
        trial = t + advance
        d = distance(kind, along(x0, trial, p0), along(x1, trial, p1), along(x2, trial, p2), along(x3, trial, p3))
        gap = d - minimum
        if gap < report:
            return t
        t = trial
        if t >= 1.0:
            return CLEAR
        advance = CCD_ADVANCE * gap / bound
    return t
