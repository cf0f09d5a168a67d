"""Water uptake (MODEL.md section 5): the Buras law, integrated exactly over a step."""

from __future__ import annotations

from numba import njit

from wetcloth.kernels import FASTMATH

#: A particle whose remaining uptake is below this fraction of its capacity counts as saturated.
SATURATED = 1e-12


@njit(cache=True, nogil=True, fastmath=FASTMATH)
def absorb(s, dry_mass, capacity, decay, water, vel):
    """Advance absorbed water (kg) of particles touching water (``s > 0``) by one step.

    ``dq/dt = I (1 - q/Q)`` over a step of length h is exactly
    ``q+ = Q - (Q - q) * decay`` with ``decay = exp(-I h / Q) = exp(-rate h / capacity)``.
    ``Q = capacity * dry_mass``.  Water arrives at rest: momentum is kept, so the particle
    slows by ``m / m+``.  Returns the number of particles still absorbing.
    """
    active = 0
    for i in range(s.shape[0]):
        if s[i] <= 0.0:
            continue
        full = capacity * dry_mass[i]
        missing = full - water[i]
        if missing <= SATURATED * full:
            continue
        active += 1
        new_water = full - missing * decay
        scale = (dry_mass[i] + water[i]) / (dry_mass[i] + new_water)
        water[i] = new_water
        vel[0, i] *= scale
        vel[1, i] *= scale
        vel[2, i] *= scale
    return active


@njit(cache=True, nogil=True, fastmath=FASTMATH)
def dry(s, keep, water):
    """Particles in air (``s == 0``) keep the fraction ``keep = exp(-drying_rate h)`` of their water.

    The water leaves with the particle's velocity, which therefore does not change.  Returns the
    number of particles that lost water."""
    drying = 0
    for i in range(s.shape[0]):
        if s[i] == 0.0 and water[i] > 0.0:
            water[i] *= keep
            drying += 1
    return drying


@njit(cache=True, nogil=True, fastmath=FASTMATH, error_model="numpy")
def _saturation_flux(off, conductance, saturation, dt, flux):
    """flux[k] (kg): water moving over dt from spring k's second end into its first."""
    m = saturation.shape[0] - off
    si, sj = saturation[:m], saturation[off:]
    g = conductance[:m]
    for k in range(m):
        flux[k] = dt * g[k] * (sj[k] - si[k])


@njit(cache=True, nogil=True, fastmath=FASTMATH)
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
