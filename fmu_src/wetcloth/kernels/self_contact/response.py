"""The self-collision stage of a step (docs/model.md section 6.2): after the integrator and the floor
have moved the cloth from ``x0`` to ``x1`` (velocities ``v1``), make the motion free of
self-intersection and push layers apart to ``thickness``.

Each candidate pair is examined along the step's straight-line motion.  A pair whose motion may
bring it closer than a safe minimum distance (``time_of_contact``) is treated in the configuration
just before that contact, where its normal says which side each element is on; a pair that ends
the step closer than ``thickness`` without such a contact is treated in its end configuration.
Treating it moves the end positions apart along that normal to ``thickness`` (in proportion to the
inverse masses and the closest points' weights; a particle on the floor is not pushed into it),
removes the pair's approaching velocity (an inelastic impulse) and reduces its sliding velocity by
``friction`` times the normal velocity removed (Coulomb).  A few passes settle stacked layers.
Pairs whose motion is still not shown safe then form rigid *impact zones* (Bridson, Fedkiw and
Anderson 2002): each zone moves with its own linear and angular momentum, zones that still meet
merge, and a zone holding a pinned particle, or that would enter the floor, stays where it was.
The end state then has no pair closer than the safe minimum along any part of the step, so the
cloth never passes through itself.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth.kernels import counted_kernel as kernel  # allocates arrays, reads the typed candidate lists
from wetcloth.kernels.integration import symmetric_adjugate
from wetcloth.kernels.self_contact.broad_phase import (BUSY_STEPS, FREEZES, PASSES, RESPONSES, ZONE_ROUNDS,
                                                       candidate_count, covers, point, rebuild_for_step, too_loose)
from wetcloth.kernels.self_contact.geometry import (CLEAR, EDGE_EDGE, POINT_TRIANGLE, along, closest, combine, distance,
                                                    motion_bound, time_of_contact)

#: Settling passes over the candidates per step (each pass treats every pair that needs it).
PASSES_MAX = 8
#: A pair whose end distance is within this fraction below ``thickness`` is left alone.
SLACK = 0.01
#: The safe minimum distance of a pair along the step: this fraction of the thickness, or half the
#: pair's distance at the start of the step if that is less.
SAFE_FRACTION = 0.1
#: A particle within this fraction of the thickness above the floor is on it (see ``_push_apart``).
ON_FLOOR = 0.01
#: Candidate lists rebuilt (when the treatment moved particles beyond the list's margin) at most this
#: many times per step; after that the step's motion is undone (never seen; counted).
ATTEMPTS = 6


@kernel(inline="always")
def _candidate(contact, point_triangle, edge_edge, j):
    """Kind and four particles of candidate ``j`` of the whole list: the point-triangle pairs
    (``contact.pairs[POINT_TRIANGLE]``, passed as ``point_triangle``) first, then the edge-edge ones."""
    if j < point_triangle.shape[1]:
        t = point_triangle[1, j]
        return POINT_TRIANGLE, (point_triangle[0, j], contact.triangles[t, 0], contact.triangles[t, 1],
                                contact.triangles[t, 2])
    a, b = edge_edge[0, j - point_triangle.shape[1]], edge_edge[1, j - point_triangle.shape[1]]
    return EDGE_EDGE, (contact.edges[a, 0], contact.edges[a, 1], contact.edges[b, 0], contact.edges[b, 1])


@kernel(inline="always")
def _inverse_masses(idx, mass, free):
    return (free[idx[0]] / mass[idx[0]], free[idx[1]] / mass[idx[1]], free[idx[2]] / mass[idx[2]],
            free[idx[3]] / mass[idx[3]])


@kernel(inline="always")
def _motion(x0, x1, i):
    return (x1[0, i] - x0[0, i], x1[1, i] - x0[1, i], x1[2, i] - x0[2, i])


@kernel
def _start_distances(contact, x0, out):
    """Each candidate's distance (m) at the start of the step (in the order of ``_candidate``)."""
    point_triangle, edge_edge = contact.pairs[POINT_TRIANGLE], contact.pairs[EDGE_EDGE]
    for j in range(out.shape[0]):
        kind, idx = _candidate(contact, point_triangle, edge_edge, j)
        out[j] = distance(kind, point(x0, idx[0]), point(x0, idx[1]), point(x0, idx[2]), point(x0, idx[3]))


@kernel
def _contact_time(kind, idx, start_distance, thickness, x0, x1):
    """(fraction of the step at which the pair must be treated, or CLEAR; whether it can come within
    ``thickness`` at all)."""
    a0, b0, c0, d0 = point(x0, idx[0]), point(x0, idx[1]), point(x0, idx[2]), point(x0, idx[3])
    pa, pb, pc, pd = _motion(x0, x1, idx[0]), _motion(x0, x1, idx[1]), _motion(x0, x1, idx[2]), _motion(x0, x1, idx[3])
    if start_distance - motion_bound(kind, pa, pb, pc, pd) >= thickness:
        return CLEAR, False
    minimum = min(SAFE_FRACTION * thickness, 0.5 * start_distance)
    return time_of_contact(kind, a0, b0, c0, d0, pa, pb, pc, pd, start_distance, minimum), True


@kernel(inline="always")
def _share(inverse, held, k):
    """Particle k's inverse mass in a push, 0 if it is held (bit k of ``held``)."""
    return 0.0 if (held >> k) & 1 else inverse[k]


@kernel
def _push_apart(idx, w, normal, target, inverse, friction, floor_z, x1, v1):
    """Move the end positions so that the pair's separation along ``normal`` (closest-point weights
    ``w`` kept) is ``target``; then remove its approaching velocity and apply Coulomb friction.
    A particle on the floor (or that the push would take below ``floor_z``) takes no share of a push
    downwards."""
    nx, ny, nz = normal
    held = 0  # bit k: particle k is on the floor and the push would take it down
    for k in range(4):
        if w[k] * nz < 0.0 and x1[2, idx[k]] <= floor_z + ON_FLOOR * target:
            held |= 1 << k
    separation = 0.0
    for k in range(4):
        i = idx[k]
        separation += w[k] * (x1[0, i] * nx + x1[1, i] * ny + x1[2, i] * nz)
    if separation < target:
        for _ in range(4):
            weight = 0.0
            for k in range(4):
                weight += w[k] * w[k] * _share(inverse, held, k)
            if weight <= 0.0:
                break
            lam = (target - separation) / weight
            floored = held
            for k in range(4):
                dz = lam * w[k] * _share(inverse, held, k) * nz
                if dz < 0.0 and x1[2, idx[k]] + dz < floor_z:
                    floored |= 1 << k
            if floored == held:
                for k in range(4):
                    i = idx[k]
                    s = lam * w[k] * _share(inverse, held, k)
                    x1[0, i] += s * nx
                    x1[1, i] += s * ny
                    x1[2, i] += s * nz
                break
            held = floored
    weight = 0.0
    rx, ry, rz = 0.0, 0.0, 0.0
    for k in range(4):
        weight += w[k] * w[k] * _share(inverse, held, k)
        i = idx[k]
        rx += w[k] * v1[0, i]
        ry += w[k] * v1[1, i]
        rz += w[k] * v1[2, i]
    approach = rx * nx + ry * ny + rz * nz
    if approach >= 0.0 or weight <= 0.0:
        return
    # Inelastic: the relative normal velocity becomes zero; friction takes up to ``friction`` times that
    # change off the relative sliding velocity, never reversing it.
    tx, ty, tz = rx - approach * nx, ry - approach * ny, rz - approach * nz
    slide = math.sqrt(tx * tx + ty * ty + tz * tz)
    keep = min(1.0, friction * -approach / slide) if slide > 0.0 else 0.0
    for k in range(4):
        i = idx[k]
        s = w[k] * _share(inverse, held, k) / weight
        v1[0, i] -= s * (approach * nx + keep * tx)
        v1[1, i] -= s * (approach * ny + keep * ty)
        v1[2, i] -= s * (approach * nz + keep * tz)


@kernel
def _settle_pair(kind, idx, start_distance, contact, thickness, floor_z, mass, free, x0, x1, v1):
    """Treat one pair if it needs it (see the module's docstring); returns whether it did."""
    inverse = _inverse_masses(idx, mass, free)
    if inverse[0] + inverse[1] + inverse[2] + inverse[3] == 0.0:
        return False
    when, near = _contact_time(kind, idx, start_distance, thickness, x0, x1)
    if not near:
        return False
    if when == CLEAR:
        a, b, c, d = point(x1, idx[0]), point(x1, idx[1]), point(x1, idx[2]), point(x1, idx[3])
    else:
        a0, b0, c0, d0 = point(x0, idx[0]), point(x0, idx[1]), point(x0, idx[2]), point(x0, idx[3])
        a = along(a0, when, _motion(x0, x1, idx[0]))
        b = along(b0, when, _motion(x0, x1, idx[1]))
        c = along(c0, when, _motion(x0, x1, idx[2]))
        d = along(d0, when, _motion(x0, x1, idx[3]))
    w = closest(kind, a, b, c, d)
    gap = combine(w, a, b, c, d)
    length = math.sqrt(gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2])
    if when == CLEAR and length >= (1.0 - SLACK) * thickness:
        return False
    if not length > 0.0:
        return False  # no side to push to: left to the impact zones
    normal = (gap[0] / length, gap[1] / length, gap[2] / length)
    _push_apart(idx, w, normal, thickness, inverse, contact.friction, floor_z, x1, v1)
    return True


@kernel
def _settle(contact, thickness, floor_z, mass, free, x0, x1, v1, start):
    """Passes over the candidates until none needs treatment (at most PASSES_MAX); ``start`` holds
    their distances at the start of the step (``_start_distances``)."""
    point_triangle, edge_edge = contact.pairs[POINT_TRIANGLE], contact.pairs[EDGE_EDGE]
    for _ in range(PASSES_MAX):
        contact.counters[PASSES] += 1
        treated = 0
        for j in range(start.shape[0]):
            kind, idx = _candidate(contact, point_triangle, edge_edge, j)
            treated += _settle_pair(kind, idx, start[j], contact, thickness, floor_z, mass, free, x0, x1, v1)
        contact.counters[RESPONSES] += treated
        if treated == 0:
            return


@kernel
def _root(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


#: Rows of ``Contact.zone_sums`` per zone root: mass; mass-weighted start position (3) and motion (3);
#: whether held; angular momentum (3); inertia (xx, yy, zz, xy, xz, yz); rotation over the step (3);
#: members.
_MASS, _POS, _MOVE, _HELD, _MOMENT, _INERTIA, _SPIN, _MEMBERS = 0, 1, 4, 7, 8, 11, 17, 20
ZONE_ROWS = 21


@kernel
def _solve_inertia(s, r):
    """The zone's rotation over the step (3; h times its angular velocity) from root ``r``'s inertia and
    the angular momentum of its members' displacements; a tiny multiple of the trace regularises zones
    that are nearly a line."""
    xx, yy, zz = s[_INERTIA, r], s[_INERTIA + 1, r], s[_INERTIA + 2, r]
    xy, xz, yz = s[_INERTIA + 3, r], s[_INERTIA + 4, r], s[_INERTIA + 5, r]
    eps = 1e-9 * (xx + yy + zz)
    xx += eps
    yy += eps
    zz += eps
    c00, c11, c22, c01, c02, c12, det = symmetric_adjugate(xx, yy, zz, xy, xz, yz)
    lx, ly, lz = s[_MOMENT, r], s[_MOMENT + 1, r], s[_MOMENT + 2, r]
    if not det > 0.0:
        return 0.0, 0.0, 0.0
    return ((c00 * lx + c01 * ly + c02 * lz) / det, (c01 * lx + c11 * ly + c12 * lz) / det,
            (c02 * lx + c12 * ly + c22 * lz) / det)


@kernel
def _move_zones(contact, floor_z, mass, free, x0, x1, v1, h):
    """Give every zone (a root with members) the rigid motion of its members' linear and angular
    momentum over the step: motion ``h (v + w x r)`` about the centre of mass, which never brings two
    points of a zone closer along the straight-line path.  A zone holding a pinned particle, or one
    whose motion would take a member below the floor, stays where it started (velocities zero)."""
    parent, s = contact.zone, contact.zone_sums
    n = x0.shape[1]
    for i in range(n):
        for row in range(ZONE_ROWS):
            s[row, i] = 0.0
    for i in range(n):
        r = _root(parent, i)
        m = mass[i]
        s[_MEMBERS, r] += 1.0
        s[_MASS, r] += m
        for c in range(3):
            s[_POS + c, r] += m * x0[c, i]
            s[_MOVE + c, r] += m * (x1[c, i] - x0[c, i])
        if free[i] == 0.0:
            s[_HELD, r] = 1.0
    for i in range(n):
        if parent[i] != i:
            continue
        for c in range(3):
            s[_POS + c, i] /= s[_MASS, i]
            s[_MOVE + c, i] /= s[_MASS, i]
    for i in range(n):
        r = _root(parent, i)
        m = mass[i]
        rx, ry, rz = x0[0, i] - s[_POS, r], x0[1, i] - s[_POS + 1, r], x0[2, i] - s[_POS + 2, r]
        ux = x1[0, i] - x0[0, i] - s[_MOVE, r]
        uy = x1[1, i] - x0[1, i] - s[_MOVE + 1, r]
        uz = x1[2, i] - x0[2, i] - s[_MOVE + 2, r]
        s[_MOMENT, r] += m * (ry * uz - rz * uy)
        s[_MOMENT + 1, r] += m * (rz * ux - rx * uz)
        s[_MOMENT + 2, r] += m * (rx * uy - ry * ux)
        s[_INERTIA, r] += m * (ry * ry + rz * rz)
        s[_INERTIA + 1, r] += m * (rx * rx + rz * rz)
        s[_INERTIA + 2, r] += m * (rx * rx + ry * ry)
        s[_INERTIA + 3, r] -= m * rx * ry
        s[_INERTIA + 4, r] -= m * rx * rz
        s[_INERTIA + 5, r] -= m * ry * rz
    for i in range(n):
        if parent[i] == i:
            wx, wy, wz = _solve_inertia(s, i)  # from displacements: h times the angular velocity
            s[_SPIN, i], s[_SPIN + 1, i], s[_SPIN + 2, i] = wx, wy, wz
    for i in range(n):
        r = _root(parent, i)
        if s[_MEMBERS, r] == 1.0:
            continue  # a particle in no zone
        rx, ry, rz = x0[0, i] - s[_POS, r], x0[1, i] - s[_POS + 1, r], x0[2, i] - s[_POS + 2, r]
        dz = s[_MOVE + 2, r] + s[_SPIN, r] * ry - s[_SPIN + 1, r] * rx
        if x0[2, i] + dz < floor_z:
            s[_HELD, r] = 1.0
    for i in range(n):
        r = _root(parent, i)
        if s[_MEMBERS, r] == 1.0:
            continue
        if s[_HELD, r] != 0.0:
            for c in range(3):
                x1[c, i] = x0[c, i]
                v1[c, i] = 0.0
            continue
        rx, ry, rz = x0[0, i] - s[_POS, r], x0[1, i] - s[_POS + 1, r], x0[2, i] - s[_POS + 2, r]
        wx, wy, wz = s[_SPIN, r], s[_SPIN + 1, r], s[_SPIN + 2, r]
        move = (s[_MOVE, r] + wy * rz - wz * ry, s[_MOVE + 1, r] + wz * rx - wx * rz, s[_MOVE + 2, r] + wx * ry - wy * rx)
        for c in range(3):
            v1[c, i] += (move[c] - (x1[c, i] - x0[c, i])) / h
            x1[c, i] = x0[c, i] + move[c]


@kernel
def _impact_zones(contact, thickness, floor_z, mass, free, x0, x1, v1, h, start):
    """Merge the particles of every pair whose motion is not shown safe into rigid zones until none
    is left (each round merges at least two zones, so this ends)."""
    parent = contact.zone
    n = x0.shape[1]
    for i in range(n):
        parent[i] = i
    point_triangle, edge_edge = contact.pairs[POINT_TRIANGLE], contact.pairs[EDGE_EDGE]
    for _ in range(n):
        unsafe = 0
        for j in range(start.shape[0]):
            kind, idx = _candidate(contact, point_triangle, edge_edge, j)
            r = _root(parent, idx[0])
            if r == _root(parent, idx[1]) and r == _root(parent, idx[2]) and r == _root(parent, idx[3]):
                continue  # inside one zone: its rigid motion keeps it apart
            inverse = _inverse_masses(idx, mass, free)
            if inverse[0] + inverse[1] + inverse[2] + inverse[3] == 0.0:
                continue
            when, _ = _contact_time(kind, idx, start[j], thickness, x0, x1)
            if when == CLEAR:
                continue
            unsafe += 1
            for other in range(1, 4):
                a, b = _root(parent, idx[0]), _root(parent, idx[other])
                if a != b:
                    parent[max(a, b)] = min(a, b)
        if unsafe == 0:
            return
        contact.counters[ZONE_ROUNDS] += 1
        _move_zones(contact, floor_z, mass, free, x0, x1, v1, h)


@kernel
def _refused(x1, v1, blow_up_speed):
    """Whether the step's blow-up guard will refuse it: a value not finite, or a particle at
    ``blow_up_speed`` (m/s) or faster.  The stage leaves such a step alone, so that neither its
    rigid zones nor its last resort hide a blow-up from the guard."""
    limit = blow_up_speed * blow_up_speed
    for i in range(x1.shape[1]):
        v2 = v1[0, i] * v1[0, i] + v1[1, i] * v1[1, i] + v1[2, i] * v1[2, i]
        if not (v2 < limit and math.isfinite(x1[0, i] + x1[1, i] + x1[2, i])):
            return True
    return False


@kernel
def resolve(contact, thickness, floor_z, blow_up_speed, mass, free, x0, x1, v1, h):
    """The self-collision stage of one step of ``h`` s from ``x0`` to ``x1`` (both (3, n), m; ``x1`` and
    the end velocities ``v1`` (m/s) are changed in place); ``mass`` (kg) per particle, ``free`` 1 for
    moving particles.  Nothing to do, and one pass over the positions, while no pair is near.  A step
    that the blow-up guard will refuse (``_refused``; checked only where there is work) is left alone.

    Returns whether it changed ``x1`` or ``v1``: the step's motion then has a kink that a multistep
    integrator must not extrapolate (the caller restarts its history, as after a wake-up)."""
    if not contact.enabled:
        return False
    treated = contact.counters[RESPONSES] + contact.counters[ZONE_ROUNDS]
    for _ in range(ATTEMPTS):
        if not covers(contact, x1) or too_loose(contact, x0, x1):
            if _refused(x1, v1, blow_up_speed) or not rebuild_for_step(contact, thickness, x0, x1):
                return False
        candidates = candidate_count(contact)
        if candidates == 0:
            return contact.counters[RESPONSES] + contact.counters[ZONE_ROUNDS] != treated
        if _refused(x1, v1, blow_up_speed):
            return False
        contact.counters[BUSY_STEPS] += 1
        start = np.empty(candidates)
        _start_distances(contact, x0, start)
        _settle(contact, thickness, floor_z, mass, free, x0, x1, v1, start)
        _impact_zones(contact, thickness, floor_z, mass, free, x0, x1, v1, h, start)
        if covers(contact, x1):
            return contact.counters[RESPONSES] + contact.counters[ZONE_ROUNDS] != treated
    # The treatment kept moving particles beyond every list built for it: undo the step's motion.
    contact.counters[FREEZES] += 1
    for c in range(3):
        for i in range(x0.shape[1]):
            x1[c, i] = x0[c, i]
            v1[c, i] = 0.0
    return True
