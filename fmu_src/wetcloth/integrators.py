"""Time integrators: their names, what their steps cost in stability, and their control settings.

The steps themselves are compiled (the core's step loop, ``fmu_src/core/src/stepping.cpp``):

* ``explicit_euler``: the thesis scheme (eq. 3.8-3.9), ``v+ = v + h F/m``, ``x+ = x + h v``;
* ``symplectic_euler``: ``v+ = v + h F/m``, then ``x+ = x + h v+``;
* ``implicit_euler``: backward Euler, Newton iterations that descend the step's incremental potential
  (a line search along each correction) and stop after a few: its steps never fail, so it is the
  fixed-step mode for frame-long steps (``tolerance = 0``, ``max_step = 1/fps``);
* ``bdf2``: the second-order backward differentiation formula with variable steps, Newton
  iterations to a stated tolerance, and an embedded error estimate (``fmu_src/core/src/implicit.cpp``).

With ``tolerance > 0`` the step adapts to a local position error of at most ``tolerance`` times the
cloth's size per step, estimated as each scheme's first omitted term: ``h |v+ - v| / 2`` for the
Euler schemes, the predictor-corrector difference for BDF2 (third order, so a tenfold tighter
tolerance shrinks its steps about 2.2 times where the Euler schemes' shrink 3.2 times).  The
explicit schemes' steps are also capped at their linear-stability limit, which on stiff cloth is
far below what the tolerance allows: their runs then do not change with the tolerance.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth import _core
from wetcloth._core import BDF2, CG_TOLERANCE, EXPLICIT_EULER, FIXED_STEP_CG_TOLERANCE, GRAVITY, IMPLICIT_EULER, SYMPLECTIC_EULER
from wetcloth.bundles import Control
from wetcloth.model import Model

#: Name -> code of the compiled step loop.
INTEGRATORS = {"explicit_euler": EXPLICIT_EULER, "symplectic_euler": SYMPLECTIC_EULER,
               "implicit_euler": IMPLICIT_EULER, "bdf2": BDF2}
#: Steps the controller will not go below (s); an error above tolerance is then accepted.
SMALLEST_STEP = 1e-9
#: Largest growth and shrink factors of the step between two steps.
STEP_GROWTH, STEP_SHRINK = 2.0, 0.2
#: Speed (m/s) beyond which the state counts as exploded: far above any fall in a tank.
BLOW_UP_SPEED = 1.0e3
#: BDF2's Newton iterations stop when the position correction is below this fraction of the
#: local error allowed per step (or, with fixed steps, of 1e-5 times the cloth's size).
NEWTON_FRACTION = 0.1
FIXED_STEP_NEWTON_TOLERANCE = 1e-6
#: A cloth whose particles all stay within SLEEP_DISTANCE (m) of where they were for SLEEP_AFTER
#: seconds of simulated time, with no water going in or out, is asleep: time passes, nothing is
#: computed.  Half a millimetre tolerates the slight jitter of a floating cloth (its heave mode is
#: barely damped) and keeps a frozen cloth within the 1 mm accuracy the defaults aim for.
SLEEP_DISTANCE, SLEEP_AFTER = 5e-4, 1.0


class Integrator:
    """One scheme for one model: its stability data (Gershgorin bounds) and control settings."""

    def __init__(self, name: str, model: Model):
        self.name = name
        self.code = INTEGRATORS[name]
        self.model = model
        topo = model.topology
        dry = model.dry_mass
        stiffest = 1.0 + max(model.scene.wet_stiffness_factor, 0.0)  # a saturated, stiffened cloth
        # Gershgorin: the eigenvalues of M^-1 K are at most 2 * sum_j k_ij / m_i.
        stiffness = topo.per_particle_sum(topo.spring_stiffness) + topo.per_particle_pair_sum(topo.pair_stiffness)
        damping = topo.per_particle_sum(topo.spring_damping) + topo.per_particle_pair_sum(topo.pair_damping)
        self.omega_squared = 2.0 * stiffest * float(np.max(stiffness / dry))
        self.damping_rate = 2.0 * float(np.max(damping / dry))
        # Forward Euler on a damped spring is stable only for h < c/k (the disc |1 + h lambda| < 1),
        # and on pure damping for h < 2 m / c.  Undamped springs it can never hold.
        k = np.concatenate([topo.spring_stiffness.ravel(), topo.pair_stiffness])
        c = np.concatenate([topo.spring_damping.ravel(), topo.pair_damping])
        springs = k > 0
        with np.errstate(over="ignore"):  # a vanishing stiffness (say 1e-320 N/m) limits nothing: inf
            limit = float((c[springs] / k[springs]).min()) / stiffest if springs.any() else math.inf
        if self.omega_squared > 0:
            # Below 0.1/omega an unstable mode grows by at most 0.5% a step: the damping is then too
            # weak to matter, and a smaller limit would only stall (damping -> 0 gives h -> 0).
            limit = max(limit, 0.1 / math.sqrt(self.omega_squared))
        self.spring_limit = limit

    @property
    def implicit(self) -> bool:
        return self.code in (IMPLICIT_EULER, BDF2)

    def control(self) -> Control:
        """The loop's settings for the model's current scene."""
        sc = self.model.scene
        size = max(sc.width, sc.length)
        if sc.drag_model == "stokes":
            drag_offset, drag_slope = float(np.max(self.model.stokes_coefficient / self.model.dry_mass)), 0.0
        else:  # the water's speed past the cloth is at most a particle's speed plus the current's
            drag_slope = sc.water_density * (sc.drag_normal + sc.drag_tangential) / sc.areal_density
            drag_offset = drag_slope * math.hypot(sc.current_x, sc.current_y) + sc.drag_linear / sc.areal_density
        if sc.air_density > 0:  # the air's share of a triangle is what the water leaves: the larger rate bounds both
            air_slope = sc.air_density * (sc.drag_normal + sc.drag_tangential) / sc.areal_density
            drag_slope = max(drag_slope, air_slope)
            wind = math.sqrt(sc.wind_x * sc.wind_x + sc.wind_y * sc.wind_y + sc.wind_z * sc.wind_z)  # as model.cpp
            drag_offset += air_slope * wind
        allowed = sc.tolerance * size  # m of local position error per step
        newton = NEWTON_FRACTION * allowed if allowed > 0 else FIXED_STEP_NEWTON_TOLERANCE * size
        return Control(
            integrator=self.code, tolerance=sc.tolerance, allowed=allowed, max_step=sc.max_step, newton_tolerance=newton,
            cg_tolerance=CG_TOLERANCE if allowed > 0 else FIXED_STEP_CG_TOLERANCE,
            omega_squared=self.omega_squared, buoyancy_omega_squared=sc.water_density * GRAVITY / sc.areal_density,
            damping_rate=self.damping_rate, spring_limit=self.spring_limit, drag_rate_offset=drag_offset,
            drag_rate_slope=drag_slope, smallest_step=SMALLEST_STEP, growth=STEP_GROWTH, shrink=STEP_SHRINK,
            blow_up_speed=BLOW_UP_SPEED, sleep_distance=SLEEP_DISTANCE, sleep_after=SLEEP_AFTER,
        )

    def stable_step(self, speed: float) -> float:
        """Largest step (s) for which the scheme is linearly stable with particles up to ``speed`` (m/s)."""
        return _core.stable_step(self.control(), speed)


def make_integrator(name: str, model: Model) -> Integrator:
    return Integrator(name, model)
