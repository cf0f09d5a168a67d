"""The outputs (docs/model.md section 8) and a step loop that records them at a list of times.

Sampling a run from Python costs a compiled call and the outputs' NumPy work at every sample, about
20 us: on a coarse study (a 9 x 9 cloth sampled at 10 Hz, one step per sample once it sinks) that
was 8 % of the run directly, and 10-24 % with the garbage collection and cache misses that came
with it (docs/benchmarks.md, Large steps).  ``advance_sampling`` goes through many sample times in
one call.
"""

from __future__ import annotations

from wetcloth.kernels import counted_kernel, kernel
from wetcloth.kernels.stepping import DONE, PAUSED, STEPS, advance

#: Number of outputs, in the order of ``simulation.OUTPUT_NAMES``.
OUTPUT_COUNT = 6


@kernel
def record_outputs(dry_mass, water_level, pos, water, row):
    """Write the outputs into ``row`` (OUTPUT_COUNT,): the centroid (x, y, z, m; particles weighted by
    their wet mass), depth (m: ``water_level`` (m) minus the centroid's z), wet mass and absorbed
    water (kg); ``dry_mass`` and ``water`` (n) kg, ``pos`` (3, n) m."""
    wet_mass = 0.0
    water_mass = 0.0
    moment_x = 0.0
    moment_y = 0.0
    moment_z = 0.0
    for i in range(water.shape[0]):
        mass = dry_mass[i] + water[i]
        wet_mass += mass
        water_mass += water[i]
        moment_x += mass * pos[0, i]
        moment_y += mass * pos[1, i]
        moment_z += mass * pos[2, i]
    row[0] = moment_x / wet_mass
    row[1] = moment_y / wet_mass
    row[2] = moment_z / wet_mass
    row[3] = water_level - row[2]
    row[4] = wet_mass
    row[5] = water_mass


@counted_kernel  # passes self-collision's typed lists on
def advance_sampling(cloth, phys, control, work, solver, plane, contact, buf, clock, times, outputs, first, max_steps):
    """Advance to ``times[k]`` (s, ascending) for k = first, first + 1, ... and record the outputs
    there in ``outputs[k]`` (``record_outputs``).  Returns (``stepping.advance``'s status, the next k
    to record): DONE with every time recorded; BLOWN_UP with the last good state kept; PAUSED after
    about ``max_steps`` steps (call again from the k returned)."""
    budget_end = clock[STEPS] + max_steps
    for k in range(first, times.shape[0]):
        budget = int(budget_end - clock[STEPS])
        if budget <= 0:
            return PAUSED, k
        status = advance(cloth, phys, control, work, solver, plane, contact, buf, clock, times[k], budget)
        if status != DONE:
            return status, k
        record_outputs(cloth.dry_mass, phys.water_level, buf.pos, buf.water, outputs[k])
    return DONE, times.shape[0]
