"""Time integrators: each advances the mechanics of a state by one step ``h`` into another state.

An integrator is built for one model (it keeps its scratch arrays) and called as
``step(state, out, h)``; it returns ``max |v+ - v|`` (m/s), from which the step controller
estimates the local error.  Absorption and the floor are applied afterwards by the simulation.
"""

from __future__ import annotations

import math

import numpy as np

from wetcloth.kernels.integration import euler_update, invert_blocks, solve_pcg
from wetcloth.model import GRAVITY, Model
from wetcloth.state import State

#: Fraction of the linear-stability limit that explicit schemes may use.
STABILITY_SAFETY = 0.9


class Integrator:
    """Base: stability limits shared by the schemes, from Gershgorin bounds on the model."""

    name = ""
    implicit = False

    def __init__(self, model: Model):
        self.model = model
        topo = model.topology
        n = topo.n
        stiffness_sum = np.zeros(n)
        damping_sum = np.zeros(n)
        for f, off in enumerate(topo.spring_offset):
            for target, per_spring in ((stiffness_sum, topo.spring_stiffness[f]), (damping_sum, topo.spring_damping[f])):
                target[: n - off] += per_spring[: n - off]
                target[off:] += per_spring[: n - off]
        dry = model.dry_mass
        stiffest = 1.0 + max(model.scene.wet_stiffness_factor, 0.0)  # a saturated, stiffened cloth
        # Gershgorin: the eigenvalues of M^-1 K are at most 2 * sum_j k_ij / m_i.
        self.omega_squared = 2.0 * stiffest * float(np.max(stiffness_sum / dry))
        self.damping_rate = 2.0 * float(np.max(damping_sum / dry))

    def _drag_rate(self, speed: float) -> float:
        """Upper bound on the water drag's damping rate (1/s) for particle speeds up to ``speed`` (m/s)."""
        sc = self.model.scene
        if sc.drag_model == "stokes":
            return float(np.max(self.model.stokes_coefficient / self.model.dry_mass))
        relative = speed + math.hypot(sc.current_x, sc.current_y)  # the water's speed past the cloth, at most
        return (sc.water_density * (sc.drag_normal + sc.drag_tangential) * relative + sc.drag_linear) / sc.areal_density

    def stable_step(self, speed: float) -> float:
        """Largest step (s) for which the scheme is linearly stable with particles up to ``speed`` (m/s)."""
        raise NotImplementedError

    def __call__(self, state: State, out: State, h: float) -> float:
        raise NotImplementedError


class ExplicitEuler(Integrator):
    """The thesis scheme (eq. 3.8-3.9): ``v+ = v + h F/m``, ``x+ = x + h v`` with the old ``v``."""

    name = "explicit_euler"

    def __init__(self, model: Model):
        super().__init__(model)
        # Forward Euler on a damped spring is stable only for h < c/k (the disc |1 + h lambda| < 1),
        # and on pure damping for h < 2 m / c.  Undamped springs it can never hold.
        topo = model.topology
        springs = topo.spring_stiffness > 0
        stiffest = 1.0 + max(model.scene.wet_stiffness_factor, 0.0)
        with np.errstate(over="ignore"):  # a vanishing stiffness (say 1e-320 N/m) limits nothing: inf
            limit = (float((topo.spring_damping[springs] / topo.spring_stiffness[springs]).min()) / stiffest
                     if springs.any() else math.inf)
        if self.omega_squared > 0:
            # Below 0.1/omega an unstable mode grows by at most 0.5% a step: the damping is then too
            # weak to matter, and a smaller limit would only stall (damping -> 0 gives h -> 0).
            limit = max(limit, 0.1 / math.sqrt(self.omega_squared))
        self._spring_limit = limit

    def stable_step(self, speed: float) -> float:
        limit = self._spring_limit
        gamma = self.damping_rate + self._drag_rate(speed)
        if gamma > 0:
            limit = min(limit, 2.0 / gamma)
        return STABILITY_SAFETY * limit

    def __call__(self, state: State, out: State, h: float) -> float:
        m = self.model
        force = m.forces(state.pos, state.vel, state.water)
        return euler_update(state.pos, state.vel, force, m.dry_mass, state.water, m.free, h, False, out.pos, out.vel)


class SymplecticEuler(ExplicitEuler):
    """Semi-implicit Euler: ``v+ = v + h F/m``, then ``x+ = x + h v+``."""

    name = "symplectic_euler"

    def stable_step(self, speed: float) -> float:
        # For x'' = -w^2 x - g x' the scheme is stable iff h < 4 / (g + sqrt(g^2 + 4 w^2)).
        sc = self.model.scene
        omega2 = self.omega_squared + sc.water_density * GRAVITY / sc.areal_density
        gamma = self.damping_rate + self._drag_rate(speed)
        return STABILITY_SAFETY * 4.0 / (gamma + math.sqrt(gamma * gamma + 4.0 * omega2))

    def __call__(self, state: State, out: State, h: float) -> float:
        m = self.model
        force = m.forces(state.pos, state.vel, state.water)
        return euler_update(state.pos, state.vel, force, m.dry_mass, state.water, m.free, h, True, out.pos, out.vel)


class ImplicitEuler(Integrator):
    """Backward Euler, one Newton step, solved by conjugate gradients (Baraff and Witkin 1998).

    Solves ``(M - h C - h^2 K) dv = h F + h^2 K v`` for the velocity change, then
    ``x+ = x + h (v + dv)``.  Stable for any step; its accuracy is left to the step controller.
    """

    name = "implicit_euler"
    implicit = True
    #: Conjugate gradients stop at this residual relative to the right-hand side: on the towel
    #: this moves the centroid by 0.02 mm against a 1e-8 solve (docs/benchmarks.md, Simulator step).
    CG_TOLERANCE = 1e-4
    CG_MAX_ITERATIONS = 500

    def __init__(self, model: Model):
        super().__init__(model)
        shape = (3, model.topology.n)
        self._rhs = np.zeros(shape)
        self._dv = np.zeros(shape)
        self._scratch = [np.zeros(shape) for _ in range(5)]
        self._blocks = np.zeros((6, model.topology.n))  # the system's 3x3 diagonal blocks
        self._inverse = np.zeros((6, model.topology.n))  # their inverses: the preconditioner
        self.last_iterations = 0

    def stable_step(self, speed: float) -> float:
        return math.inf

    def __call__(self, state: State, out: State, h: float) -> float:
        m = self.model
        force = m.forces_and_blocks(state.pos, state.vel, state.water, h)
        mass = m.mass(state.water)
        np.multiply(force, h, out=self._rhs)
        self._rhs += m.rhs
        blocks = self._blocks
        np.add(m.diagonal_blocks, m.blocks, out=blocks)
        blocks[:3] += mass
        invert_blocks(blocks, self._inverse)
        dv = self._dv
        np.divide(self._rhs, mass, out=dv)  # first guess: the explicit step (solve_pcg improves on it)
        dv *= m.free
        topo = m.topology
        self.last_iterations, _ = solve_pcg(
            topo.spring_offset, m.direction, m.along, m.across, mass, m.blocks, self._inverse, m.free,
            self._rhs, dv, *self._scratch, self.CG_TOLERANCE, self.CG_MAX_ITERATIONS,
        )
        np.add(state.vel, dv, out=out.vel)
        np.multiply(out.vel, h, out=out.pos)
        out.pos += state.pos
        return float(np.abs(dv).max())


INTEGRATORS = {cls.name: cls for cls in (ExplicitEuler, SymplecticEuler, ImplicitEuler)}


def make_integrator(name: str, model: Model) -> Integrator:
    return INTEGRATORS[name](model)
