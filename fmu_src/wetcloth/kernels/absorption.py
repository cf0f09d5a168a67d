"""Water uptake (docs/model.md section 5): the Buras law, integrated exactly over a step."""

from __future__ import annotations

import math

from wetcloth.kernels import kernel

#: A particle whose remaining uptake is below this fraction of its capacity counts as saturated.
SATURATED = 1e-12


@kernel(inline="always")
def contact_fraction(z_start, z_end, vz_start, vz_end, h, surface):
    """Fraction of a step of ``h`` s (0..1) that a particle spends touching water, i.e. below
    ``surface`` (m).  Its height over the step is the cubic Hermite curve through its start and end
    heights (m) and vertical speeds (m/s): the crossing time is then accurate to the fourth order
    in h, where a straight line between the ends would misplace it by a fraction of the step
    whenever the particle brakes on the water."""
    below_start = z_start < surface
    below_end = z_end < surface
    if below_start and below_end:
        return 1.0
    if not (below_start or below_end):
        return 0.0
    a, b = z_start - surface, z_end - surface
    p0, p1 = h * vz_start, h * vz_end
    crossing = a / (a - b)  # the straight line's crossing: the first guess
    for _ in range(3):  # Newton on the Hermite cubic, kept inside the step
        t = crossing
        t2 = t * t
        t3 = t2 * t
        value = (2 * t3 - 3 * t2 + 1) * a + (t3 - 2 * t2 + t) * p0 + (3 * t2 - 2 * t3) * b + (t3 - t2) * p1
        slope = (6 * t2 - 6 * t) * a + (3 * t2 - 4 * t + 1) * p0 + (6 * t - 6 * t2) * b + (3 * t2 - 2 * t) * p1
        if slope == 0.0:
            break
        crossing = min(1.0, max(0.0, t - value / slope))
    return 1.0 - crossing if below_end else crossing


@kernel(inline="always")
def _room(capacity, dry_mass, water):
    """(the water a particle holds when full, what it can still take) in kg; 0 for the second once
    it counts as saturated (SATURATED)."""
    full = capacity * dry_mass
    missing = full - water
    return full, (0.0 if missing <= SATURATED * full else missing)


@kernel
def uptake(z_start, z_end, vz_start, vz_end, surface, dry_mass, capacity, rate, h, water, out):
    """Absorbed water (kg) after a step of ``h`` s, into ``out`` (may be ``water``).

    A particle touches water while its centre is below ``surface`` (m; where its submerged fraction
    becomes positive); over the step it moved from ``z_start`` to ``z_end`` with vertical speeds
    ``vz_start`` to ``vz_end``, and it absorbs for the part of the step it spent below
    (``contact_fraction``), so the moment of contact is not rounded to a whole step.  ``dq/dt = I (1 - q/Q)`` over a contact time t is exactly
    ``q+ = Q - (Q - q) exp(-I t / Q)``, ``Q = capacity * dry_mass``, ``I / Q = rate / capacity``.
    Returns the number of particles still absorbing.
    """
    active = 0
    full_decay = math.exp(-rate * h / capacity)
    for i in range(water.shape[0]):
        out[i] = water[i]
        touching = contact_fraction(z_start[i], z_end[i], vz_start[i], vz_end[i], h, surface)
        if touching <= 0.0:
            continue
        full, missing = _room(capacity, dry_mass[i], water[i])
        if missing == 0.0:
            continue
        active += 1
        decay = full_decay if touching == 1.0 else math.exp(-rate * touching * h / capacity)
        out[i] = full - missing * decay
    return active


@kernel
def uptake_timing_error(z_start, z_end, vz_start, vz_end, surface, dry_mass, capacity, rate, h, water):
    """An estimate (kg, summed over particles) of the error in a step's uptake from where on its
    path a particle met the surface: the difference between the uptake with the crossing timed on
    the Hermite curve (``contact_fraction``) and on the straight line between the step's ends.  Only
    particles that cross the surface during the step contribute."""
    total = 0.0
    for i in range(water.shape[0]):
        if (z_start[i] < surface) == (z_end[i] < surface):
            continue
        missing = _room(capacity, dry_mass[i], water[i])[1]
        if missing == 0.0:
            continue
        curved = contact_fraction(z_start[i], z_end[i], vz_start[i], vz_end[i], h, surface)
        straight = contact_fraction(z_start[i], z_end[i], 0.0, 0.0, 0.0, surface)
        total += missing * abs(math.exp(-rate * straight * h / capacity) - math.exp(-rate * curved * h / capacity))
    return total


@kernel
def keep_momentum(mass_before, dry_mass, water, vel):
    """Water arrives at rest: a particle whose mass went from ``mass_before`` to ``dry_mass + water``
    (kg) keeps its momentum, so it slows by their ratio."""
    for i in range(water.shape[0]):
        scale = mass_before[i] / (dry_mass[i] + water[i])
        vel[0, i] *= scale
        vel[1, i] *= scale
        vel[2, i] *= scale


@kernel
def dry(z_start, z_end, vz_start, vz_end, surface, rate, h, water):
    """Particles keep ``exp(-rate t)`` of their water after t s in air (above ``surface``, m) during
    the step (its path as in ``uptake``).  The water leaves with the particle's velocity, which therefore does not change.
    Returns the number of particles that lost water."""
    drying = 0
    for i in range(water.shape[0]):
        in_air = 1.0 - contact_fraction(z_start[i], z_end[i], vz_start[i], vz_end[i], h, surface)
        if in_air > 0.0 and water[i] > 0.0:
            water[i] *= math.exp(-rate * in_air * h)
            drying += 1
    return drying


@kernel
def _saturation_flux(off, conductance, saturation, dt, flux):
    """flux[k] (kg): water moving over dt from spring k's second end into its first."""
    m = saturation.shape[0] - off
    si, sj = saturation[:m], saturation[off:]
    g = conductance[:m]
    for k in range(m):
        flux[k] = dt * g[k] * (sj[k] - si[k])


@kernel
def wick(offsets, conductance, capacity, dry_mass, substeps, h, water, vel, buf):
    """Diffuse water between axis neighbours over ``h`` s in ``substeps`` explicit sub-steps.

    The flux from j to i is ``conductance * (sat_j - sat_i)`` (kg/s), ``sat = water / capacity``;
    each flux is added to one end and taken from the other, so the total is conserved to
    round-off.  Sub-steps short enough that each new saturation is a weighted mean of old ones
    keep every saturation within the range it had.  Moving water carries its donor's velocity,
    so momentum is conserved (``vel`` is updated).  ``buf`` is (6, n) scratch.  Returns the largest
    amount moved in one sub-step (kg).
    """
    n = water.shape[0]
    saturation, flux, scratch = buf[0], buf[1], buf[2]
    momentum = buf[3:6]
    for c in range(3):
        for i in range(n):
            momentum[c, i] = (dry_mass[i] + water[i]) * vel[c, i]
    dt = h / substeps
    largest = 0.0
    for _ in range(substeps):
        for i in range(n):
            saturation[i] = water[i] / capacity[i]
        for f in range(offsets.shape[0]):
            off = offsets[f]
            m = n - off
            _saturation_flux(off, conductance[f], saturation, dt, flux)
            for k in range(m):
                largest = max(largest, abs(flux[k]))
                water[k] += flux[k]
                water[k + off] -= flux[k]
            for c in range(3):
                for k in range(m):
                    donor = k + off if flux[k] > 0.0 else k
                    scratch[k] = flux[k] * vel[c, donor]
                for k in range(m):
                    momentum[c, k] += scratch[k]
                    momentum[c, k + off] -= scratch[k]
    for c in range(3):
        for i in range(n):
            vel[c, i] = momentum[c, i] / (dry_mass[i] + water[i])
    return largest
