"""The tank floor: a rigid plane with Coulomb friction (docs/model.md section 6.1).

Two parts of one rule.  A particle that reaches the floor during a step is put back on it and
loses its downward velocity, and its sliding speed drops by ``friction`` times that loss
(``floor_contact``, after the step).  A particle that lies still on the floor (static friction)
is held there during the step, as a constraint of the step's own solve (``hold_resting``), as long
as the force on it presses it onto the floor within the friction cone (``release_slipping``).
Holding it, rather than letting the step push it into the floor and projecting it back, keeps
the multistep history and the error estimate of an implicit step free of the floor: a cloth
resting on the floor then takes steps set by the rest of its motion.  Where the floor did change
a particle's motion, its history is made to agree with its new velocity (``agree_history``).
"""

from __future__ import annotations

import math

from wetcloth.kernels import kernel


@kernel
def floor_contact(z_min, friction, pos, vel):
    """Keep particle centres at or above ``z_min`` (m); stop their fall and apply friction.

    The normal velocity change ``dv_n`` removed by the floor reduces the sliding speed by
    ``friction * dv_n`` (an inelastic Coulomb impulse), never reversing it.  Returns the
    number of particles in contact.
    """
    touching = 0
    for i in range(pos.shape[1]):
        if pos[2, i] >= z_min:
            continue
        touching += 1
        pos[2, i] = z_min
        dvn = -vel[2, i] if vel[2, i] < 0.0 else 0.0
        vel[2, i] = max(vel[2, i], 0.0)
        slide = math.sqrt(vel[0, i] ** 2 + vel[1, i] ** 2)
        if slide > 0.0:
            keep = max(0.0, 1.0 - friction * dvn / slide)
            vel[0, i] *= keep
            vel[1, i] *= keep
    return touching


@kernel
def hold_resting(z_min, pos, vel, free, held):
    """Hold the particles at rest on the floor for the coming step: those on it (centre at ``z_min``,
    m, where ``floor_contact`` left it) with zero velocity (friction stopped them) get ``free`` 0
    and ``held`` 1 (all others ``held`` 0).  Pinned particles are left alone.  Returns how many."""
    count = 0
    for i in range(free.shape[0]):
        resting = (free[i] != 0.0 and pos[2, i] <= z_min and vel[0, i] == 0.0 and vel[1, i] == 0.0
                   and vel[2, i] == 0.0)
        held[i] = 1.0 if resting else 0.0
        if resting:
            free[i] = 0.0
            count += 1
    return count


@kernel
def release_slipping(friction, force, free, held):
    """Release the held particles that the step's ``force`` (N, (3, n)) does not keep on the floor:
    it lifts them (upward normal force) or overcomes static friction (force along the floor above
    ``friction`` times the force into it): the floor's impulse (``floor_contact``) would not have
    kept them still either.  Returns how many were released (the step is then to be redone)."""
    released = 0
    for i in range(free.shape[0]):
        if held[i] == 0.0:
            continue
        pressing = -force[2, i]
        along = math.sqrt(force[0, i] ** 2 + force[1, i] ** 2)
        if pressing <= 0.0 or along > friction * pressing:
            held[i] = 0.0
            free[i] = 1.0
            released += 1
    return released


@kernel
def release_all(free, held):
    """Give the held particles back their ``free`` flag (1) after the step."""
    for i in range(free.shape[0]):
        if held[i] != 0.0:
            free[i] = 1.0
            held[i] = 0.0


@kernel
def agree_history(z_min, pos, vel, prev_pos, prev_vel, h):
    """After a step of ``h`` s: the particles on the floor (centre at ``z_min``, m) get the history of
    a straight motion at their present velocity (``prev_pos = pos - h vel``, ``prev_vel = vel``).
    The floor stops a particle (or slows its sliding) at once; a multistep scheme extrapolating the
    positions before that would carry on the old fall (BDF2 from ``pos`` and ``prev_pos``) and its
    error estimate would see the floor's stop as a large error at the next step.  Particles held
    at rest keep the history they have (at rest: the same).  Returns how many were on the floor."""
    count = 0
    for i in range(pos.shape[1]):
        if pos[2, i] > z_min:
            continue
        count += 1
        for c in range(3):
            prev_pos[c, i] = pos[c, i] - h * vel[c, i]
            prev_vel[c, i] = vel[c, i]
    return count
