"""The one simulator every front end drives: ``Simulation(scene).advance(seconds)``."""

from __future__ import annotations

import math

import numpy as np

from wetcloth.advice import blow_up_advice
from wetcloth.errors import BlowUpError, ParameterError
from wetcloth.integrators import make_integrator
from wetcloth.kernels.absorption import absorb, dry, wick
from wetcloth.kernels.floor import floor_contact
from wetcloth.kernels.integration import largest_deviation, speed_and_finiteness
from wetcloth.model import Model
from wetcloth.scene import INPUT, PARAMETERS, Scene, load_scene
from wetcloth.state import State, initial_state

#: The outputs (MODEL.md section 7), as the FMU publishes them: name -> (unit, meaning).
OUTPUTS = {
    "centroid_x": ("m", "mass-weighted mean particle position, x"),
    "centroid_y": ("m", "mass-weighted mean particle position, y"),
    "centroid_z": ("m", "mass-weighted mean particle position, z (z is up)"),
    "depth": ("m", "water_level - centroid_z; positive below the surface"),
    "wet_mass": ("kg", "dry mass plus absorbed water"),
    "water_mass": ("kg", "absorbed water"),
}
OUTPUT_NAMES = tuple(OUTPUTS)

#: Speed (m/s) beyond which the state counts as exploded: far above any fall in a tank.
BLOW_UP_SPEED = 1.0e3
#: Steps the controller will not go below (s); an error above tolerance is then accepted.
SMALLEST_STEP = 1e-9
#: Largest growth and shrink factors of the step between two steps.
STEP_GROWTH, STEP_SHRINK = 2.0, 0.2
#: A cloth whose particles all stay within SLEEP_DISTANCE (m) of where they were for SLEEP_AFTER
#: seconds of simulated time, with no water going in or out, is asleep: time passes, nothing is
#: computed.  Half a millimetre tolerates the slight jitter of a floating cloth (its heave mode is
#: barely damped) and keeps a frozen cloth within the 1 mm accuracy the defaults aim for.
SLEEP_DISTANCE, SLEEP_AFTER = 5e-4, 1.0


class Simulation:
    """A cloth on water, advanced in internal steps chosen by stability and ``tolerance``.

    The step size is not the caller's: ``advance(duration)`` takes as many internal steps as
    the integrator needs, so any communication step (FMU, frame rate) gives accurate results.
    With ``tolerance > 0`` (the default) steps adapt to a local error bound and never exceed the
    explicit schemes' stability limit or ``max_step``; with ``tolerance = 0`` every step is
    ``max_step``, the thesis's fixed-step scheme, and only the blow-up guard watches.
    """

    def __init__(self, scene: Scene | None = None, skip_idle_work: bool = True):
        """``skip_idle_work=False`` computes every kernel at every step (for benchmarks of the skips)."""
        scene = load_scene() if scene is None else scene
        self.model = Model(scene, skip_idle_work=skip_idle_work)
        self.state = initial_state(scene, self.model.topology)
        self._trial = self.state.copy()
        self.integrator = make_integrator(scene.integrator, self.model)
        self.skip_idle_work = skip_idle_work
        self._next_step = scene.max_step
        self._speed = 0.0  # m/s, fastest particle of the current state
        self._calm_time = 0.0  # s of simulated time spent within SLEEP_DISTANCE of _anchor
        self._anchor = self.state.pos.copy()
        self._wick_buffer = np.zeros((6, self.model.topology.n))
        self._unchecked_time = 0.0  # s simulated since stillness was last checked
        self._exchanging = False  # whether water went in or out since then
        self.sleeping = False
        self.steps = 0  # accepted internal steps
        self.rejected_steps = 0  # steps redone with a smaller size (adaptive mode)

    _DYNAMIC = ("_next_step", "_speed", "_calm_time", "_unchecked_time", "_exchanging", "sleeping", "steps",
                "rejected_steps")

    def snapshot(self) -> dict:
        """Everything that evolves (state arrays, inputs, step control, sleep): for ``restore``."""
        return {"state": self.state.copy(), "scene": self.scene, "anchor": self._anchor.copy()} | {
            k: getattr(self, k) for k in self._DYNAMIC}

    def restore(self, snapshot: dict) -> None:
        """Return to a ``snapshot`` of this simulation; the run continues exactly as it did from there."""
        self.state.assign(snapshot["state"])
        self._anchor[...] = snapshot["anchor"]
        self.model.scene = snapshot["scene"]
        for key in self._DYNAMIC:
            setattr(self, key, snapshot[key])

    # ----------------------------------------------------------------- parameters
    @property
    def scene(self) -> Scene:
        return self.model.scene

    def set_inputs(self, **values) -> None:
        """Change inputs (water level, density, absorption; see ``scene.INPUT``) from now on."""
        for name in values:
            if name not in PARAMETERS:
                raise ParameterError(name, "unknown parameter")
            if PARAMETERS[name].metadata["fmu"] != INPUT:
                raise ParameterError(name, "is fixed once the simulation starts; only inputs may change")
        scene = self.scene.replace(**values)
        if scene != self.scene:
            self.model.scene = scene
            self._wake()

    def _wake(self) -> None:
        self.sleeping = False
        self._calm_time = 0.0
        self._anchor[...] = self.state.pos

    # ----------------------------------------------------------------- stepping
    @property
    def time(self) -> float:
        """Simulated time (s)."""
        return self.state.time

    def advance(self, duration: float) -> None:
        """Simulate ``duration`` seconds (>= 0) more."""
        if not (duration >= 0.0 and math.isfinite(duration)):
            raise ValueError(f"duration must be a finite number >= 0 s, got {duration!r}")
        target = self.state.time + duration
        while target - self.state.time > 1e-12 * max(1.0, abs(target)) and not self.sleeping:
            self._step(target - self.state.time)
        self.state.time = max(self.state.time, target)

    def _step(self, remaining: float) -> None:
        """Take one accepted internal step of at most ``remaining`` seconds."""
        scene = self.scene
        state, trial = self.state, self._trial
        adaptive = scene.tolerance > 0.0
        allowed = scene.tolerance * max(scene.width, scene.length)  # m of local position error
        while True:
            if not adaptive:  # fixed steps of max_step, as the user asked: the blow-up guard watches
                h = min(scene.max_step, remaining)
                self.integrator(state, trial, h)
                break
            limit = min(scene.max_step, self.integrator.stable_step(self._speed))
            planned = min(self._next_step, limit)
            h = min(planned, remaining)
            largest_dv = self.integrator(state, trial, h)
            error = 0.5 * h * largest_dv  # |h (v+ - v)| / 2: first- against second-order position update
            factor = 0.9 * math.sqrt(allowed / error) if error > 0.0 else STEP_GROWTH
            if error <= allowed or h <= SMALLEST_STEP or not math.isfinite(error):
                proposed = h * min(STEP_GROWTH, max(STEP_SHRINK, factor)) if math.isfinite(error) else h
                # A step cut short by the end of the interval says nothing against the planned one.
                self._next_step = max(proposed, planned) if h < planned and error <= allowed else proposed
                break
            self._next_step = max(SMALLEST_STEP, h * max(STEP_SHRINK, factor))
            self.rejected_steps += 1
        trial.time = state.time + h
        exchanging = self._finish_step(trial, h)
        self._guard(trial, h)
        self.state, self._trial = trial, state
        self.steps += 1
        self._maybe_sleep(h, exchanging)

    def _finish_step(self, trial: State, h: float) -> bool:
        """Floor contact, then the water's exchanges over the step: uptake where the cloth touches
        water (exact exponential update), drying in air, wicking between neighbours.  Each is
        skipped when its rate is zero.  Returns whether any particle's water changed."""
        scene, model = self.scene, self.model
        floor_contact(model.floor_z, scene.floor_friction, trial.pos, trial.vel)
        trial.water[...] = self.state.water
        absorbing = scene.absorption_capacity > 0.0 and scene.absorption_rate > 0.0
        if not (absorbing or scene.drying_rate > 0.0 or scene.wicking_rate > 0.0):
            return False
        model.touches_water(trial.pos[2])
        exchanged = 0
        if absorbing:
            decay = math.exp(-scene.absorption_rate * h / scene.absorption_capacity)
            exchanged += absorb(model.s, model.dry_mass, scene.absorption_capacity, decay, trial.water, trial.vel)
        if scene.drying_rate > 0.0:
            exchanged += dry(model.s, math.exp(-scene.drying_rate * h), trial.water)
        if scene.wicking_rate > 0.0 and scene.absorption_capacity > 0.0:
            substeps = max(1, math.ceil(h / model.wick_step_limit))
            moved = wick(model.wick_offsets, model.wick_conductance, model.capacity, model.dry_mass, substeps, h,
                         trial.water, trial.vel, self._wick_buffer)
            trial.vel *= model.free
            exchanged += moved > 0.0
        return exchanged > 0

    def _maybe_sleep(self, h: float, exchanging: bool) -> None:
        """Fall asleep after SLEEP_AFTER s still, with no water exchange (velocities then zero).

        Stillness is checked every SLEEP_AFTER / 20 s of simulated time, not at every step."""
        if not self.skip_idle_work:
            return
        self._exchanging = self._exchanging or exchanging
        self._unchecked_time += h
        if self._unchecked_time < SLEEP_AFTER / 20:
            return
        if self._exchanging or largest_deviation(self.state.pos, self._anchor) > SLEEP_DISTANCE:
            self._anchor[...] = self.state.pos
            self._calm_time = 0.0
        else:
            self._calm_time += self._unchecked_time
        self._unchecked_time, self._exchanging = 0.0, False
        if self._calm_time >= SLEEP_AFTER:
            self.sleeping = True
            self.state.vel[...] = 0.0
            self._speed = 0.0

    def _guard(self, trial: State, h: float) -> None:
        """Refuse a non-finite or exploded state; the last good state stays current."""
        speed, finite = speed_and_finiteness(trial.pos, trial.vel, trial.water)
        if finite and speed < BLOW_UP_SPEED:
            self._speed = speed
            return
        scene = self.scene
        what = "became non-finite" if not finite else f"exploded (speed {speed:.3g} m/s)"
        raise BlowUpError(
            f"the cloth state {what} in the step from t = {self.state.time:.6g} s to {trial.time:.6g} s "
            f"(step {h:.3g} s, integrator {scene.integrator!r}). Likely cause: the step is too large for "
            f"stretch_stiffness = {scene.stretch_stiffness:g} N/m; {blow_up_advice(scene)}. "
            f"Last good time: {self.state.time:.6g} s.",
            last_good_time=self.state.time,
        )

    # ----------------------------------------------------------------- results
    def outputs(self) -> dict[str, float]:
        """The FMU outputs (MODEL.md section 7): centroid (m), depth (m), wet and water mass (kg)."""
        mass = self.model.mass(self.state.water)
        total = float(mass.sum())
        centroid = self.state.pos @ mass / total
        return {
            "centroid_x": float(centroid[0]),
            "centroid_y": float(centroid[1]),
            "centroid_z": float(centroid[2]),
            "depth": float(self.scene.water_level - centroid[2]),
            "wet_mass": total,
            "water_mass": float(self.state.water.sum()),
        }

    @property
    def positions(self) -> np.ndarray:
        """Particle positions (n, 3), m."""
        return self.state.pos.T.copy()

    @property
    def velocities(self) -> np.ndarray:
        """Particle velocities (n, 3), m/s."""
        return self.state.vel.T.copy()

    @property
    def wetness(self) -> np.ndarray:
        """Saturation of each particle, absorbed water over capacity (0 to 1)."""
        capacity = self.scene.absorption_capacity * self.model.dry_mass
        return np.clip(np.divide(self.state.water, capacity, out=np.zeros_like(capacity), where=capacity > 0), 0.0, 1.0)

    @property
    def triangles(self) -> np.ndarray:
        """Triangle vertex indices (m, 3), counter-clockwise seen from +z in the rest sheet."""
        return self.model.topology.triangles
