"""The one simulator every front end drives: ``Simulation(scene).advance(seconds)``."""

from __future__ import annotations

import math
import numbers
import os

import numpy as np

from wetcloth import _core, self_collision
from wetcloth._core import (BLOWN_UP, CALM_TIME, CG_ITERATIONS, CLOCK_SIZE, EXCHANGING, FACTORISATIONS, FAILED_STEP,
                            FIRST_GUESS, LAST_SOLVE, LAST_STEP, NEWTON_ITERATIONS, NEWTON_RATE,
                            NEXT_STEP, OUTPUT_COUNT, PAUSE_AFTER, PAUSED, RATE_CORRECTION, REJECTED, REUSE_RULE_SIZE,
                            RESTARTS, SLEEPING, SPEED, STEPS, TIME, UNCHECKED_TIME, UNCONVERGED,
                            LARGEST_ERROR, MAX_TIME)
from wetcloth.bundles import Buffers, make_solver
from wetcloth.errors import BlowUpError, ParameterError, did_you_mean, not_a_number
from wetcloth.integrators import INTEGRATORS, make_integrator
from wetcloth.model import Model
from wetcloth.preconditioner import plane_for
from wetcloth.scene import INPUT, PARAMETERS, Scene, collider_key_order, load_scene, refuse_problem
from wetcloth.state import State, initial_state
from wetcloth.topology import Topology, initial_positions, start_positions

#: The outputs (docs/model.md section 8), as the FMU publishes them: name -> (unit, meaning).
OUTPUTS = {
    "centroid_x": ("m", "mass-weighted mean particle position, x"),
    "centroid_y": ("m", "mass-weighted mean particle position, y"),
    "centroid_z": ("m", "mass-weighted mean particle position, z (z is up)"),
    "depth": ("m", "water_level - centroid_z; positive below the surface"),
    "wet_mass": ("kg", "dry mass plus absorbed water"),
    "water_mass": ("kg", "absorbed water"),
}
OUTPUT_NAMES = tuple(OUTPUTS)

#: Particle-steps (steps times particles) that one compiled call takes at most before it returns.
STEPS_PER_CALL = 2_000_000

#: What a snapshot holds besides ``state`` and ``scene``: the buffers that carry over between steps
#: (BDF2's previous step and acceleration, the sleep anchor), and the clock's slots (name, slot, type).
_SNAPSHOT_ARRAYS = ("prev_pos", "prev_vel", "prev_water", "acceleration", "anchor")
_SNAPSHOT_CLOCK = (("next_step", NEXT_STEP, float), ("last_step", LAST_STEP, float),
                   ("speed", SPEED, float), ("calm_time", CALM_TIME, float), ("unchecked_time", UNCHECKED_TIME, float),
                   ("exchanging", EXCHANGING, bool), ("sleeping", SLEEPING, bool), ("steps", STEPS, int),
                   ("rejected_steps", REJECTED, int), ("newton_rate", NEWTON_RATE, float),
                   ("rate_correction", RATE_CORRECTION, float), ("first_guess", FIRST_GUESS, float),
                   ("last_solve_iterations", LAST_SOLVE, float), ("largest_error", LARGEST_ERROR, float))



def _check_topology(scene: Scene, topology) -> None:
    """ParameterError naming ``topology`` unless it is a Topology of the scene's cloth: as many particles, at
    the same rest positions (a mesh file's points; the grid's start positions, m)."""
    if not isinstance(topology, Topology):
        raise ParameterError("topology", f"expected a wetcloth.topology.Topology, got {type(topology).__name__}")
    start, mesh = start_positions(scene)
    allowed = "allowed: a topology of the scene's cloth (as wetcloth.topology.build_topology(scene) builds)"
    if topology.n != start.shape[1]:
        raise ParameterError("topology", f"has {topology.n} particles, the scene's cloth {start.shape[1]}; {allowed}")
    if mesh is not None:
        same = np.array_equal(topology.rest_pos, mesh.points.T)
    else:
        same = topology.mesh is None and np.allclose(initial_positions(scene, topology), start, rtol=0.0,
                                                     atol=1e-12 * max(scene.width, scene.length))
    if not same:
        raise ParameterError("topology", f"has the scene's {topology.n} particles at other rest positions; {allowed}")


def _read_only(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.flags.writeable = False
    return view


class Simulation:
    """A cloth on water, advanced in internal steps chosen by stability and ``tolerance``.

    The step size is not the caller's: ``advance(duration)`` takes as many internal steps as
    the integrator needs, in one compiled call, so any communication step (FMU, frame rate) gives
    accurate results.  With ``tolerance > 0`` (the default) steps adapt to a local error bound and
    never exceed the explicit schemes' stability limit or ``max_step``; with ``tolerance = 0``
    every step is ``max_step``, and only the blow-up guard watches.
    """

    def __init__(self, scene: Scene | None = None, skip_idle_work: bool = True, topology: Topology | None = None):
        """``skip_idle_work=False`` computes every kernel at every step (for benchmarks of the skips);
        ``topology`` replaces the one built from the scene (same particles at the same start positions)."""
        scene = load_scene() if scene is None else scene
        if not isinstance(scene, Scene):
            named = isinstance(scene, (str, os.PathLike))
            load = f"wetcloth.load_scene({str(scene)!r})" if named else "wetcloth.load_scene()"
            raise TypeError(f"scene: expected a wetcloth.Scene, got {type(scene).__name__} {scene!r}; load one with "
                            f"{load} (a preset's name or a scene file) or build one with wetcloth.Scene(...)")
        if topology is not None:
            _check_topology(scene, topology)
        self.model = model = Model(scene, topology=topology, skip_idle_work=skip_idle_work)
        topo = model.topology
        start = initial_state(scene, topo)
        self._buffers = Buffers(
            pos=start.pos, vel=start.vel, water=start.water, trial_pos=start.pos.copy(),
            trial_vel=start.vel.copy(), trial_water=start.water.copy(), prev_pos=start.pos.copy(),
            prev_vel=start.vel.copy(), prev_water=start.water.copy(), acceleration=np.zeros_like(start.vel),
            anchor=start.pos.copy(),
            held=np.zeros(topo.n),
        )
        self._clock = np.zeros(CLOCK_SIZE)
        self._clock[NEXT_STEP] = scene.max_step
        self.integrator = make_integrator(scene.integrator, model)
        self._control = self.integrator.control()
        refuse_problem(_core.stability_problem(self._control))
        self._solver = make_solver(topo.n)
        self._plane = plane_for(topo, fixed_steps=scene.tolerance == 0.0)
        self._contact = self_collision.make_contact(topo, scene.self_collision == "on", scene.self_friction)
        self.skip_idle_work = skip_idle_work
        #: The compiled step loop over these arrays (it keeps them alive and views them in place).
        self._stepper = _core.Stepper(model.cloth, model.physics, self._control, model.work, self._solver,
                                      self._plane, self._contact, self._buffers, self._clock)
        self._output_row = np.zeros(OUTPUT_COUNT)
        #: Per time of the last ``sample``: the largest local position error (m) any step since the time
        #: before estimated for itself (with fixed steps, what the step size costs, frame by frame).
        self.sample_errors = np.zeros(0)

    # ----------------------------------------------------------------- snapshots
    def snapshot(self) -> dict:
        """Everything that evolves, as a flat dict of arrays and numbers plus ``"scene"``: the state,
        the BDF2 history, the step control, sleep, what the implicit solver's preconditioner was
        last factored for (and its reused Jacobian systems built from, ``preconditioner_reused_*``:
        empty on grids without multigrid) and what self-collision's candidate list was built from (so
        that a restored run factors the same matrices, finds the same candidates and repeats bit for bit)."""
        buf = self._buffers
        plane = self._plane
        values = {"scene": self.scene, "state": self.state.copy()}
        for key in _SNAPSHOT_ARRAYS:
            values[key] = getattr(buf, key).copy()
        values["preconditioner_mass"] = plane.reference_mass.copy()
        values["preconditioner_scale"] = float(plane.reference[0])
        values["preconditioner_factored"] = bool(plane.reference[1])
        values["preconditioner_from_jacobian"] = bool(plane.reference[2])
        values["preconditioner_jacobian_along"] = plane.jacobian_along.copy()
        values["preconditioner_jacobian_mass"] = plane.jacobian_mass.copy()
        reused_source, reused_rule = np.zeros(self._stepper.reused_size()), np.zeros(REUSE_RULE_SIZE)
        self._stepper.save_reused(reused_source, reused_rule)
        values["preconditioner_reused_source"] = reused_source
        values["preconditioner_reused_rule"] = reused_rule
        for key, slot, kind in _SNAPSHOT_CLOCK:
            values[key] = kind(self._clock[slot])
        values.update(self_collision.snapshot(self._contact))
        return values

    def restore(self, snapshot: dict) -> None:
        """Return to a ``snapshot`` of this simulation; the run continues exactly as it did from there.

        The snapshot is checked whole before anything changes (``check_snapshot``); a ValueError
        names what does not fit, and nothing changes."""
        self.check_snapshot(snapshot)
        buf = self._buffers
        state = snapshot["state"]
        buf.pos[...] = state.pos
        buf.vel[...] = state.vel
        buf.water[...] = state.water
        self._clock[TIME] = state.time
        for key in _SNAPSHOT_ARRAYS:
            getattr(buf, key)[...] = snapshot[key]
        for key, slot, _ in _SNAPSHOT_CLOCK:
            self._clock[slot] = float(snapshot[key])
        plane = self._plane
        plane.reference[1] = 0.0
        if snapshot["preconditioner_factored"]:
            cloth = self.model.cloth
            _core.refresh(plane, cloth, snapshot["preconditioner_mass"], snapshot["preconditioner_scale"])
            if snapshot["preconditioner_from_jacobian"]:
                _core.refresh_from_jacobian(plane, cloth, snapshot["preconditioner_jacobian_mass"],
                                            snapshot["preconditioner_jacobian_along"])
        self._stepper.restore_reused(snapshot["preconditioner_reused_source"], snapshot["preconditioner_reused_rule"])
        # Self-collision's list: the same reference and margin, and the list rebuilt from them.
        self._contact.reference[...] = snapshot["contact_reference"]
        margin = float(snapshot["contact_margin"])
        if margin > 0.0:
            self._stepper.build_contact(self.scene.thickness, margin)
        else:
            self._stepper.invalidate_contact()
        self._set_scene(snapshot["scene"])

    def check_snapshot(self, snapshot: dict) -> None:
        """ValueError, naming what does not fit, unless ``restore`` would take ``snapshot``: its keys,
        array shapes and types, a scene that differs from this one in inputs only, and contents the
        cloth can be in (the core's ``state_problem``: every value finite; time 0 to MAX_TIME s;
        positions within MAX_COORDINATE m and above the floor; speeds below the blow-up speed,
        pinned particles still; water from 0 to MAX_WATER_RATIO times the dry mass; a positive next
        step, whole counts; asleep only at rest)."""
        self._check_layout(snapshot)
        state = snapshot["state"]
        clock = np.zeros(CLOCK_SIZE)
        try:
            clock[TIME] = state.time
            for key, slot, _ in _SNAPSHOT_CLOCK:
                clock[slot] = snapshot[key]
        except OverflowError:
            raise ValueError("snapshot of a state the cloth cannot be in: a number of its clock is too large") from None
        others = np.concatenate([snapshot["preconditioner_mass"], snapshot["preconditioner_jacobian_along"].ravel(),
                                 snapshot["preconditioner_jacobian_mass"], [float(snapshot["preconditioner_scale"])],
                                 snapshot["preconditioner_reused_source"], snapshot["preconditioner_reused_rule"]])
        self._refuse_contents(state, snapshot, clock, float(snapshot["contact_margin"]), others)

    def _refuse_contents(self, state: State, arrays, clock: np.ndarray, margin: float, others: np.ndarray) -> None:
        """ValueError if ``state`` with the history ``arrays`` (``_SNAPSHOT_ARRAYS`` and
        ``contact_reference``), ``clock`` and self-collision's ``margin`` is not one the cloth can be in."""
        model = self.model
        flat = [np.ascontiguousarray(a, dtype=float) for a in (
            state.pos, state.vel, state.water, arrays["prev_pos"], arrays["prev_vel"], arrays["prev_water"],
            arrays["acceleration"], arrays["anchor"], arrays["contact_reference"])]
        problem = _core.state_problem(model.cloth, model.physics, self._control, *flat, margin, clock,
                                      np.ascontiguousarray(others, dtype=float))
        if problem:
            raise ValueError(f"snapshot of a state the cloth cannot be in: {problem}")

    def _check_layout(self, snapshot: dict) -> None:
        live = self.snapshot()
        if not isinstance(snapshot, dict) or set(snapshot) != set(live):
            keys = set(snapshot) if isinstance(snapshot, dict) else set()
            raise ValueError(f"not a snapshot of this simulation: keys missing {sorted(set(live) - keys)}, "
                             f"unknown {sorted(keys - set(live))}")
        for key, value in live.items():
            given = snapshot[key]
            if key == "state":
                if not isinstance(given, State):
                    raise ValueError(f"snapshot 'state': expected a State, got {type(given).__name__}")
                if not isinstance(given.time, (int, float, np.integer, np.floating)) or isinstance(given.time, bool):
                    raise ValueError(f"snapshot 'state.time': expected a number, got {type(given.time).__name__}")
                for name in ("pos", "vel", "water"):
                    want, got = getattr(value, name), getattr(given, name)
                    if not isinstance(got, np.ndarray) or got.shape != want.shape or got.dtype != want.dtype:
                        raise ValueError(f"snapshot 'state.{name}': expected a {want.dtype} array of shape "
                                         f"{want.shape}")
            elif isinstance(value, np.ndarray):
                if not isinstance(given, np.ndarray) or given.shape != value.shape or given.dtype != value.dtype:
                    got = f"{given.dtype} {given.shape}" if isinstance(given, np.ndarray) else type(given).__name__
                    raise ValueError(f"snapshot {key!r}: expected a {value.dtype} array of shape {value.shape}, "
                                     f"got {got}")
            elif key == "scene":
                if not isinstance(given, Scene):
                    raise ValueError(f"snapshot 'scene': expected a Scene, got {type(given).__name__}")
                fixed = [name for name, f in PARAMETERS.items() if f.metadata["fmu"] != INPUT
                         and getattr(given, name) != getattr(value, name)]
                if fixed:
                    raise ValueError(f"snapshot of another scene: {', '.join(fixed)} differ (only inputs may)")
            elif not isinstance(given, type(value)) or (isinstance(given, bool) and not isinstance(value, bool)):
                raise ValueError(f"snapshot {key!r}: expected {type(value).__name__}, got {type(given).__name__}")

    # ----------------------------------------------------------------- parameters
    @property
    def scene(self) -> Scene:
        return self.model.scene

    def _set_scene(self, scene: Scene) -> None:
        """Take ``scene`` (of the same cloth) from now on; a ParameterError, and nothing changed, for a scene the
        explicit scheme cannot step (``_core.stability_problem``)."""
        model = self.model
        previous, model.scene = model.scene, scene
        control = self.integrator.control()
        problem = _core.stability_problem(control)
        if problem:
            model.scene = previous
            refuse_problem(problem)
        self._control = control
        self._stepper.set_cloth(model.cloth)
        self._stepper.set_physics(model.physics)
        self._stepper.set_control(self._control)

    def set_inputs(self, **values) -> None:
        """Change inputs (water level, density, absorption; see ``scene.INPUT``) from now on."""
        for name in values:
            if name not in PARAMETERS:
                inputs = [n for n, f in PARAMETERS.items() if f.metadata["fmu"] == INPUT]
                raise ParameterError(name, did_you_mean(name, inputs, what="input"))
            if PARAMETERS[name].metadata["fmu"] != INPUT:
                raise ParameterError(name, "is fixed once the simulation starts; only inputs may change")
        scene = self.scene.replace(**values)
        if scene != self.scene:
            self._set_scene(scene)
            self._wake()

    def _wake(self) -> None:
        self._clock[SLEEPING] = 0.0
        self._clock[CALM_TIME] = 0.0
        self._buffers.anchor[...] = self._buffers.pos

    # ----------------------------------------------------------------- stepping
    @property
    def time(self) -> float:
        """Simulated time (s)."""
        return float(self._clock[TIME])

    @property
    def state(self) -> State:
        """The current state, as read-only views of the simulation's own arrays (assign a State to change it)."""
        buf = self._buffers
        return State(self.time, *(_read_only(getattr(buf, name)) for name in ("pos", "vel", "water")))

    @state.setter
    def state(self, state: State) -> None:
        """Take ``state`` (float64 arrays of this cloth's shapes) as the current one, with no history; a
        ValueError, and nothing changed, unless its contents are a state the cloth can be in (as for
        ``restore``)."""
        buf = self._buffers
        for name in ("pos", "vel", "water"):
            got, want = getattr(state, name, None), getattr(buf, name)
            if not isinstance(got, np.ndarray) or got.shape != want.shape or got.dtype != want.dtype:
                kind = f"{got.dtype} {got.shape}" if isinstance(got, np.ndarray) else type(got).__name__
                raise ValueError(f"state.{name}: expected a {want.dtype} array of shape {want.shape}, got {kind}")
        if not isinstance(state.time, (int, float, np.integer, np.floating)) or isinstance(state.time, bool):
            raise ValueError(f"state.time: expected a number, got {type(state.time).__name__}")
        if isinstance(state.time, numbers.Integral) and not state.time <= MAX_TIME:  # (perhaps beyond any float)
            raise ValueError(f"state.time: a whole number above {MAX_TIME:g} s; a state's time is 0 (its start) to "
                             f"{MAX_TIME:g} s")
        clock = self._clock.copy()
        clock[TIME], clock[LAST_STEP], clock[SLEEPING] = state.time, 0.0, 0.0
        arrays = {key: getattr(buf, key) for key in _SNAPSHOT_ARRAYS} | {"contact_reference": self._contact.reference}
        contiguous = State(state.time, *(np.ascontiguousarray(getattr(state, k)) for k in ("pos", "vel", "water")))
        self._refuse_contents(contiguous, arrays, clock, 0.0, np.zeros(0))
        buf.pos[...] = state.pos
        buf.vel[...] = state.vel
        buf.water[...] = state.water
        self._clock[TIME] = state.time
        self._clock[LAST_STEP] = 0.0  # a state from elsewhere: no history
        self._stepper.invalidate_contact()  # nor a candidate list
        self._wake()  # and it may move

    @property
    def steps(self) -> int:
        """Accepted internal steps."""
        return int(self._clock[STEPS])

    @property
    def rejected_steps(self) -> int:
        """Steps redone: with a smaller size (adaptive mode), or with particles the floor no longer holds."""
        return int(self._clock[REJECTED])

    @property
    def sleeping(self) -> bool:
        return bool(self._clock[SLEEPING])

    @property
    def solver_counts(self) -> dict[str, int]:
        """Work of the implicit solves so far: Newton iterations, conjugate-gradient iterations,
        preconditioner factorisations, linear solves stopped at their iteration limit, and how often a
        fixed step in contact started its descent again (it had ended above the energy the step started with)."""
        c = self._solver.counters
        return {"newton_iterations": int(c[NEWTON_ITERATIONS]), "cg_iterations": int(c[CG_ITERATIONS]),
                "factorisations": int(c[FACTORISATIONS]), "unconverged_solves": int(c[UNCONVERGED]),
                "descent_restarts": int(c[RESTARTS])}

    @property
    def contact_counts(self) -> dict[str, int]:
        """Work of self-collision so far: candidate lists built, steps that had candidates, passes
        over them, pairs pushed apart, rounds of impact zones, and steps whose motion was undone (a
        last resort); with the current list's point-triangle and edge-edge candidates."""
        counts = dict(zip(self_collision.COUNTER_NAMES, (int(c) for c in self._contact.counters)))
        counts["point_triangle_candidates"], counts["edge_edge_candidates"] = self._stepper.candidate_counts()
        return counts

    def advance(self, duration: float) -> None:
        """Simulate ``duration`` seconds (>= 0) more, to at most MAX_TIME (1e9 s)."""
        left = MAX_TIME - self.time
        allowed = (f"allowed: 0 <= duration <= {left:g} s (a simulation's time ends at {MAX_TIME:g} s, now "
                   f"{self.time:g} s)")
        if isinstance(duration, bool) or not isinstance(duration, numbers.Real):  # Real: NumPy's scalars too
            raise TypeError(f"duration: {not_a_number(duration)}; {allowed}")
        target = self.time + float(duration) if 0.0 <= duration <= MAX_TIME else math.nan  # (no huge int to float)
        if not target <= MAX_TIME:
            big = isinstance(duration, numbers.Integral) and duration > MAX_TIME  # (perhaps beyond any float)
            raise ValueError(f"duration: {'a whole number' if big else repr(duration)} s is out of range; {allowed}")
        self._clock[LARGEST_ERROR] = 0.0
        status = PAUSED
        while status == PAUSED:
            status = self._stepper.advance(target, self._steps_per_call, self.pause_after)
        if status == BLOWN_UP:
            self._blown_up(float(self._clock[FAILED_STEP]), target)

    @property
    def error_estimate(self) -> float:
        """The largest local position error (m) any step of the last ``advance`` estimated for itself:
        the integrator's own estimate plus what an unfinished Newton solve left.  With fixed steps
        (``tolerance = 0``) nothing holds it down: it shows what the step size costs."""
        return float(self._clock[LARGEST_ERROR])

    def sample(self, times) -> np.ndarray:
        """Advance to each of ``times`` (s, ascending, none before ``time``) in turn and return the
        outputs there: one row per time, columns as OUTPUT_NAMES.  The same steps as ``advance`` to
        each time, and the same values as ``outputs`` there, with no Python work between the times.
        Whatever stops it early (BlowUpError, KeyboardInterrupt) carries the rows of the times
        reached as its ``partial_outputs``.  ``sample_errors`` then holds, for each time, the largest
        error (m) a step since the time before estimated for itself (``error_estimate``'s per time)."""
        times = np.ascontiguousarray(times, dtype=float)
        if times.ndim != 1 or not np.all(np.isfinite(times)) or np.any(np.diff(times) < 0.0) or (
                times.size and times[0] < self.time):
            raise ValueError(f"times must be a 1-D sequence of finite times (s), ascending from the current time "
                             f"{self.time:g} s; got shape {times.shape}, first {times.ravel()[:3].tolist()}")
        if times.size and times[-1] > MAX_TIME:
            raise ValueError(f"times: the last, {times[-1]:g} s, is out of range; allowed: times from the current time "
                             f"{self.time:g} s to {MAX_TIME:g} s (where a simulation's time ends)")
        outputs = np.full((times.size, OUTPUT_COUNT), np.nan)
        self.sample_errors = errors = np.zeros(times.size)
        status, done = PAUSED, 0
        try:
            while status == PAUSED:
                status, done = self._stepper.advance_sampling(times, outputs, errors, done, self._steps_per_call,
                                                              self.pause_after)
            if status == BLOWN_UP:
                end = times[min(np.searchsorted(times, self.time, side="right"), times.size - 1)]
                self._blown_up(float(self._clock[FAILED_STEP]), float(end))
        except BaseException as exc:
            # The times reached (a Ctrl-C may come before ``done`` is assigned): the loop stops on each
            # time exactly and records it there; a blow-up leaves the clock at the last good time.
            exc.partial_outputs = outputs[:np.searchsorted(times, self.time, side="right")]
            raise
        return outputs

    #: Wall-clock seconds after which a compiled call returns (and Python sees Ctrl-C), whatever the
    #: steps cost; where the calls return never changes the results.
    pause_after: float = PAUSE_AFTER

    @property
    def _steps_per_call(self) -> int:
        """Steps one compiled call takes at most: it returns every STEPS_PER_CALL particle-steps (and
        every ``pause_after`` s of wall-clock time), so that Python sees Ctrl-C (and other signals)
        within a fraction of a second even when steps are tiny."""
        return max(1, STEPS_PER_CALL // self.model.topology.n)

    def _blown_up(self, h: float, end: float) -> None:
        """Refuse a non-finite or exploded state, or one the step control accepts no step from, in a call that
        steps to ``end`` s; the last good state stays current."""
        buf = self._buffers
        speed, finite = _core.speed_and_finiteness(buf.trial_pos, buf.trial_vel, buf.trial_water)
        scene = self.scene
        free = self.model.cloth.free
        places = np.array(collider_key_order(scene.collider_keys), dtype=np.int64) + 1  # in the core's rows' order
        cause = (_core.fast_move_cause(self.model.physics, places, buf.pos, free, buf.held, self.time, h, end,
                                       self._control.blow_up_speed)
                 or _core.pinned_cause(self.model.physics, free, buf.trial_pos))
        raise BlowUpError(
            _core.blow_up_text(INTEGRATORS[scene.integrator], scene.tolerance, scene.max_step, scene.stretch_stiffness,
                               self._control, finite, speed, self.time, h, cause),
            last_good_time=self.time,
        )

    # ----------------------------------------------------------------- results
    def outputs(self) -> dict[str, float]:
        """The FMU outputs (docs/model.md section 8): centroid (m), depth (m), wet and water mass (kg)."""
        buf, model = self._buffers, self.model
        _core.record_outputs(model.cloth.dry_mass, model.physics.water_level, buf.pos, buf.water, self._output_row)
        return dict(zip(OUTPUT_NAMES, self._output_row.tolist()))

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
