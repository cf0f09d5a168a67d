"""What a WetCloth unit does, whatever its FMI version: a thin adapter over ``wetcloth.Simulation``.

``WetClothUnit`` is mixed into the FMI 2.0 and 3.0 slave classes (``fmi2.py``, ``fmi3.py``), which
only translate between FMI calls and these methods.  The rules it applies live elsewhere: single
values are checked by ``vocabulary.check_variable`` (the scene's ranges), whole scenes by
``scene.from_dict``, input changes during a run by ``Simulation.set_inputs``, the output folder by
the exporter (``check_directory``, ``open_sequence``, ``resume_sequence``), and FMU states are
``Simulation.snapshot()``/``restore`` through ``checkpoint.py``.

Errors: a refused value is logged (FMI log and Python logging, so it shows with FMI logging off
too) and stays pending; a pending refusal or an invalid scene makes ``start`` raise (the master
then gets an error status from initialization); during a run a pending refusal discards every step
until a valid value arrives.  Every message names the variable and its allowed range.
"""

from __future__ import annotations

import functools
import inspect
import logging
import sys
from pathlib import Path

from wetcloth import run_settings
from wetcloth._core import MAX_TIME
from wetcloth.errors import ParameterError
from wetcloth.fmu import bootstrap, checkpoint, guard, packed_scene
from wetcloth.fmu.checkpoint import Checkpoint, StateError
from wetcloth.fmu.vocabulary import check_variable, variable_specs
from wetcloth.scene import collider_name, from_dict, read_scene_file
from wetcloth.simulation import Simulation

#: Errors also go to Python's logging (stderr unless the host configures logging): pythonfmu
#: forwards FMI log messages only while the master has logging switched on.
LOG = logging.getLogger("wetcloth.fmu")
#: Relative tolerance when matching the master's communication time with the unit's time.
TIME_TOLERANCE = 1e-9
#: Outcomes of a step the unit takes or declines, mapped to FMI statuses by the slaves (a call the
#: master must not make raises UnitError).
OK, DISCARD = "ok", "discard"


class UnitError(RuntimeError):
    """The master asked for something the unit refuses (the message says what and why)."""


def _checkpoint_of(handle) -> Checkpoint:
    """The checkpoint behind an FMU state pointer; StateError for a freed, stray or foreign one (``guard``, 4.)."""
    found = guard.handed_out(handle)
    if found is None:
        raise StateError("not a WetCloth FMU state: a pointer this unit did not hand out, or one already freed "
                         "(fmiFreeFMUstate); allowed: a live state from GetFMUstate or DeSerializeFMUstate")
    return found


def check_references_before(cls, base, prefix: str, kinds: tuple) -> None:
    """Replace ``cls``'s getters and setters (pythonfmu's ``get_real``..., ``base``'s) by ones that check their value
    references first (``WetClothUnit.check_references``), named as FMI names them (``prefix``: 'fmi2', 'fmi3')."""
    def checked(name: str, function: str, kind: type):
        inherited = getattr(base, name)

        def method(self, vrs, *values):
            self.check_references(function, vrs, kind, kind.__name__)
            return inherited(self, vrs, *values)

        method.__name__ = method.__qualname__ = name
        return method

    for kind in kinds:
        for verb in ("get", "set"):
            name = f"{verb}_{kind.__name__.lower()}"
            setattr(cls, name, checked(name, f"{prefix}{verb.title()}{kind.__name__}", kind))


def default_run() -> tuple[float, float]:
    """Stop time (s) and communication step (s) of the default experiment: the towel preset's [run]."""
    run = run_settings.resolve(read_scene_file(None).get("run"))
    return run.duration, 1.0 / run.fps


class WetClothUnit:
    """One unit's values, simulation and frames.  Mixed into a pythonfmu slave class, which sets
    ``FMI_VERSION`` and ``LOG_STATUS`` (FMI status of 'error' and 'warning' log messages)."""

    FMI_VERSION: int
    LOG_STATUS: dict

    def _start_unit(self) -> None:
        """Set up the unit's own state (called from the slave's ``__init__``)."""
        # Every instance, not only the first script run: pythonfmu3 does not run the slave script
        # again for a second unit, and pythonfmu runs it with the first unit's ``__file__``.  So
        # each unit's binary is made to exit safely, and its own manifest checked, here too.
        if self.resources:  # through the bootstrap the script ran, if any: it knows the units checked
            sys.modules.get(bootstrap.MODULE_NAME, bootstrap).load_wetcloth(Path(self.resources))
        self._tolerance_noted = False
        self.packed = packed_scene.load(self.resources)  # a scene built in (build-fmu --scene), or None
        self.specs = {spec.name: spec for spec in variable_specs(fmi_version=self.FMI_VERSION, packed=self.packed)}
        self.values = {name: spec.start for name, spec in self.specs.items() if spec.causality in ("parameter", "input")}
        self.refused: dict[str, str] = {}  # variable -> why its value was refused (pending)
        self.entered = False  # fmiEnterInitializationMode called
        self.initialized = False
        self.terminated = False
        self.start_time = 0.0  # s, the master's time at the simulation's t = 0
        self._clock_set = False  # by fmi2SetupExperiment, else (FMI 3.0) by the first doStep
        self.stop_time: float | None = None  # s, fmi2SetupExperiment's stop time if defined: no step ends beyond it
        self.sim: Simulation | None = None  # from initialization on
        self._preview: Simulation | None = None  # the initial state of the current values, before that
        self.frames = 0  # mesh frames written
        self.sequence = None  # the exporter's frame sequence, opened at the first step
        self._read: dict = {}  # outputs read since the state last changed (a master reads each one by one)

    # ------------------------------------------------------------------ logging
    def _report(self, level: str, message: str) -> None:
        """Log through FMI (shown while the master's logging is on: pythonfmu's binary filters) and
        Python's logging."""
        self.log(message, self.LOG_STATUS[level])
        getattr(LOG, level)("%s: %s", self.instance_name, message)

    # ------------------------------------------------------------------ variables
    def accessors(self, name: str) -> tuple:
        """The getter and setter (a refusal for outputs) through which pythonfmu reads and writes variable ``name``."""
        if name in self.values:
            return functools.partial(self.value, name), functools.partial(self.set_value, name)
        return functools.partial(self.output, name), functools.partial(self.refuse_output, name)

    def check_references(self, function: str, vrs, kind: type, kind_name: str) -> None:
        """UnitError (logged) unless every value reference in ``vrs`` is a variable of type ``kind`` (pythonfmu's
        own checks raise KeyError or TypeError, which reach only the binary's stderr)."""
        for vr in vrs:
            var = self.vars.get(vr)
            if var is None:
                known = sorted(self.vars)
                self._refuse_call(f"{function}: no variable has the value reference {vr} "
                                  f"({known[0]} to {known[-1]})" if known else f"{function}: no variables")
            if not isinstance(var, kind):
                found = next((c.__name__ for c in type(var).__mro__ if c.__module__.startswith("pythonfmu")
                              and c.__name__ not in ("ScalarVariable", "ModelVariable", "Arrayable")), "another type")
                self._refuse_call(f"{function}: variable {var.name!r} is a {found}, not a {kind_name}")

    def refuse_output(self, name: str, value) -> None:
        """UnitError (logged): the master set an output."""
        self._refuse_call(f"fmiSet: variable {name!r} is an output: the master cannot set it "
                          f"(allowed: parameters and inputs; value {value!r} refused)")

    def __init_subclass__(cls, **kwargs):
        """Give every unit class ``set_string`` in its own dict (guard.py 7.): the binaries call it with a failed
        decoding pending, when a lookup that reaches a class lacking the name fails."""
        super().__init_subclass__(**kwargs)
        setter = inspect.getattr_static(cls, "set_string", None)
        if setter is not None:
            cls.set_string = setter

    def _refuse_undecodable_text(self, vrs) -> None:
        """UnitError (logged, pending like any refused value): a text the binary could not decode as UTF-8."""
        names = [self.vars[vr].name for vr in vrs if vr in self.vars]
        message = (f"fmiSetString: the text for variable {' or '.join(map(repr, names)) or 'unknown'} is not "
                   "UTF-8; allowed: UTF-8 text (value refused)")
        self.refused |= {name: message for name in names if name in self.values}
        self._refuse_call(message)

    def value(self, name: str):
        return self.values[name]

    def set_value(self, name: str, value) -> None:
        """Take a parameter or input value, or refuse it: logged, the old value kept, the refusal pending."""
        try:
            if not self.initialized:
                check_variable(name, value)
                self._preview = None
            elif value != self.values[name]:  # an unchanged value changes nothing (and clears a refusal)
                if not self.specs[name].scene:
                    raise ParameterError(name, "is fixed once the unit is initialized")
                if self.specs[name].collider:
                    raise ParameterError(name, "is fixed once the simulation starts; only inputs may change")
                self.sim.set_inputs(**{name: value})  # the simulation owns which parameters may change
        except ParameterError as exc:
            reason = str(exc)
            if self.specs[name].causality == "input":  # the scene's rule calls every value a parameter
                reason = reason.replace(f"parameter {name!r}", f"input {name!r}", 1)
            self.refused[name] = reason
            self._report("error", f"{reason} (value refused: {name} stays {self.values[name]!r})")
            return
        self.values[name] = value
        self.refused.pop(name, None)
        self._read.clear()

    def _simulation(self) -> Simulation:
        """The running simulation, or before initialization the initial state of the current values
        (the defaults while they do not form a valid scene)."""
        if self.sim is not None:
            return self.sim
        if self._preview is None:
            try:
                self._preview = Simulation(from_dict(self._scene_values()))
            except ParameterError:
                self._preview = Simulation(from_dict(self._scene_values({n: s.start for n, s in self.specs.items()})))
        return self._preview

    def output(self, name: str):
        """An output: a scalar of ``Simulation.outputs()``, ``step_error`` (``Simulation.error_estimate``),
        an array output as a flat list (a constant one, a mesh cloth's faces and UVs, as built), or the time (s)."""
        spec = self.specs[name]
        if spec.variability == "constant":
            return spec.values
        if not self._read:
            sim = self._simulation()
            self._read.update(sim.outputs(), step_error=sim.error_estimate, time=self.start_time + sim.time)
        if name not in self._read:  # an array output
            self._read[name] = getattr(self._simulation(), name).ravel().tolist()
        return self._read[name]

    def _scene_values(self, values: dict | None = None) -> dict:
        """The scene's parameters as the variables hold them (or as ``values`` holds them), with the colliders
        and keys built in (--scene): the collider parameters (collider1_radius) change the listed colliders."""
        values = {name: value for name, value in (self.values if values is None else values).items()
                  if self.specs[name].scene}
        if self.packed is not None:
            values.update(self.packed.fixtures())
        return values

    # ------------------------------------------------------------------ life cycle
    def phase(self) -> str:
        """The unit's FMI state, as named in messages."""
        if self.terminated:
            return "terminated"
        if self.initialized:
            return "initialized (stepping)"
        return "initialization mode" if self.entered else "instantiated"

    def _check_phase(self, function: str, allowed: str) -> None:
        """UnitError (logged) unless the unit is in the ``allowed`` phase."""
        if self.phase() != allowed:
            self._refuse_call(f"{function} is not allowed in the {self.phase()} state; allowed only in the "
                              f"{allowed} state")

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):  # pythonfmu's call
        self._check_phase("fmiSetupExperiment", "instantiated")
        if not abs(start_time) <= MAX_TIME:
            self._refuse_call(f"the start time must be a finite number of seconds within +-{MAX_TIME:g} s, "
                              f"got {start_time!r}")
        self.check_tolerance("fmi2SetupExperiment", tolerance)
        if stop_time is not None and not stop_time >= start_time:
            self._refuse_call(f"fmi2SetupExperiment: stopTime {stop_time!r} s lies before startTime {start_time!r} s; "
                              "allowed: stopTime >= startTime")
        self.start_time, self._clock_set = float(start_time), True
        self.stop_time = None if stop_time is None else float(stop_time)
        self._read.clear()

    def check_tolerance(self, function: str, tolerance) -> None:
        """The master's experiment tolerance (None: not defined): refused (UnitError, logged) unless > 0; else
        a warning, once, that the unit's own ``tolerance`` parameter sets its accuracy, not the experiment's
        (the native units' rule and words)."""
        if tolerance is None:
            return
        if not tolerance > 0.0:
            self._refuse_call(f"{function}: tolerance {tolerance!r} is not allowed; allowed: a tolerance > 0 where "
                              "toleranceDefined is true (or none). The unit's accuracy is set by its own parameter "
                              "'tolerance', not by the experiment's")
        if not self._tolerance_noted:
            self._tolerance_noted = True
            self._report("warning", f"{function}: the experiment's tolerance {tolerance!r} is not used: the unit's "
                                    f"accuracy is set by its own parameter 'tolerance' "
                                    f"(now {self.values.get('tolerance')!r})")

    def start(self) -> None:
        """Build the simulation from the parameters and start values; UnitError (logged, naming the
        parameter and its range) if any was refused, they do not form a scene, or the mesh folder is taken."""
        problems = list(self.refused.values())
        try:
            scene = from_dict(self._scene_values())
        except ParameterError as exc:
            scene = None
            problems.append(str(exc))
        directory = self.values["mesh_output_dir"]
        if directory:
            from wetcloth.exporter import ExportError, check_directory

            try:
                check_directory(directory, overwrite=True, exclusive=True)
            except ExportError as exc:
                problems.append(f"parameter 'mesh_output_dir': {exc}")
        if scene is not None and self.FMI_VERSION == 3:
            problems += self._array_problems(scene)
        if problems:
            message = "initialization refused: " + "; ".join(dict.fromkeys(problems))
            self._report("error", message)
            raise UnitError(message)
        self.sim = Simulation(scene)
        self._preview = None
        self._read.clear()
        self.initialized = True

    def _array_problems(self, scene) -> list[str]:
        """Why the FMI 3.0 arrays, sized when the unit was built, cannot hold ``scene``'s cloth (or none)."""
        vertices = None if self.packed is None else self.packed.vertices
        if vertices is None and scene.cloth_mesh:
            return ["parameter 'cloth_mesh': this unit's array outputs are ny x nx (the rectangle); for a cloth "
                    "from a mesh file build the unit with 'wetcloth build-fmu --fmi 3 --scene SCENE'"]
        if vertices is not None:
            from wetcloth.topology import build_topology

            n = build_topology(scene).n
            if n != vertices:
                return [f"parameter 'cloth_mesh': this unit's array outputs hold the {vertices} vertices of the "
                        f"mesh it was built with, {scene.cloth_mesh!r} has {n}; allowed: a mesh of {vertices} "
                        "vertices (or build the unit with the scene of this mesh)"]
        return []

    def step(self, current_time: float, step_size: float) -> str:
        """Advance from ``current_time`` by ``step_size`` s: OK, or DISCARD (the unit stays at
        ``current_time``, message logged); UnitError (logged) for a call the master must not make."""
        if not (abs(current_time) <= MAX_TIME and step_size >= 0.0 and current_time + step_size <= MAX_TIME):
            self._refuse_call(f"doStep needs a finite communication point within +-{MAX_TIME:g} s and a finite step "
                              f"size >= 0 s that ends there too (t + step <= {MAX_TIME:g} s), "
                              f"got t = {current_time!r} s, step {step_size!r} s")
        stop = self.stop_time
        if stop is not None and current_time + step_size > stop + TIME_TOLERANCE * max(1.0, abs(stop)):
            self._refuse_call(f"doStep from t = {current_time!r} s by {step_size!r} s ends past the experiment's "
                              f"stopTime {stop!r} s; allowed: t + step <= stopTime")
        if self.terminated:
            self._refuse_call(f"doStep at t = {current_time:g} s after fmiTerminate: the run is over")
        if not self.initialized:
            self._refuse_call("doStep before the unit was initialized")
        if self.refused:
            for message in self.refused.values():
                self._report("error", f"step refused at t = {current_time:g} s: {message}")
            return DISCARD
        sim = self.sim
        if not self._clock_set:  # pythonfmu3 does not pass fmi3EnterInitializationMode's start time on
            self.start_time, self._clock_set = current_time - sim.time, True
            self._read.clear()
        now = self.start_time + sim.time
        if abs(current_time - now) > TIME_TOLERANCE * max(1.0, abs(now)):
            self._report("error", f"doStep from t = {current_time!r} s, but the unit is at t = {now!r} s; "
                                  "restore an FMU state to go back in time")
            return DISCARD
        if self.values["mesh_output_dir"] and not self._frames_ready(step_size):
            return DISCARD
        before = sim.snapshot()
        self._read.clear()
        try:
            sim.advance(max(0.0, current_time + step_size - self.start_time - sim.time))
            if self.sequence is not None:
                self.sequence.on_frame(self.frames, sim)
                self.frames += 1
        except Exception as exc:  # a blow-up, a full disk...: never let it reach the master as a crash
            sim.restore(before)
            self._report("error", f"step from t = {current_time:g} s by {step_size:g} s failed: "
                                  f"{type(exc).__name__}: {exc} The unit stays at t = {current_time:g} s "
                                  "with its last good outputs.")
            return DISCARD
        return OK

    def _refuse_call(self, message: str) -> None:
        self._report("error", message)
        raise UnitError(message)

    def _frames_ready(self, step_size: float) -> bool:
        """Open the frame sequence at the first step (or continue it after a restored state) and
        write the frame of the current state if none is written; False (logged, pending) if the
        folder cannot be used."""
        from wetcloth.exporter import ExportError, open_sequence, resume_sequence

        directory, fmt = self.values["mesh_output_dir"], self.values["mesh_format"]
        try:
            if self.sequence is None:
                fps = 1.0 / (step_size if step_size > 0 else default_run()[1])
                options = dict(fmt=fmt, writer="trimesh", fps=fps, scene=self.sim.scene)
                if self.frames == 0:
                    self.sequence = open_sequence(directory, overwrite=True, exclusive=True, **options)
                    if self.sequence.replaced:
                        self._report("warning", f"mesh_output_dir: replaced the earlier frame sequence in {directory} "
                                                f"({len(self.sequence.replaced)} files: "
                                                f"{', '.join(self.sequence.replaced)})")
                else:
                    self.sequence = resume_sequence(directory, self.frames, **options)
            if self.frames == 0:
                self.sequence.on_frame(0, self.sim)
                self.frames = 1
        except (ExportError, OSError, ImportError) as exc:
            self.refused["mesh_output_dir"] = f"parameter 'mesh_output_dir': cannot write {fmt} frames into {directory!r}: {exc}"
            self._report("error", f"{self.refused['mesh_output_dir']} (no step taken)")
            return False
        return True

    def finish(self) -> None:
        """End the run: the frame sequence is closed (frames.json complete); a second call does nothing."""
        if self.terminated:
            self._report("warning", "fmiTerminate called again: the run had already ended; nothing done")
            return
        self.terminated = True
        if self.sequence is not None:
            self.sequence.close()
            self.sequence = None

    def release(self) -> None:
        """Drop the simulation and whatever else holds the compiled core's objects (at Python's exit, ``guard``, 5.)."""
        self.sim = self._preview = None
        self._read = {}

    # ------------------------------------------------------------------ pythonfmu's and pythonfmu3's calls
    def enter_initialization_mode(self):
        self._check_phase("fmiEnterInitializationMode", "instantiated")
        self.entered = True

    def exit_initialization_mode(self):
        self._check_phase("fmiExitInitializationMode", "initialization mode")
        self.start()

    def terminate(self):
        if not self.terminated:
            self._check_phase("fmiTerminate", "initialized (stepping)")
        self.finish()

    def _get_fmu_state(self) -> guard.StateHandle:
        return guard.StateHandle(self.capture())

    def _set_fmu_state(self, handle) -> None:
        try:
            self.restore(_checkpoint_of(handle))
        except Exception as exc:  # whatever it is, the reason is logged (wetcloth.fmu too) and the unit unchanged
            reason = str(exc) if isinstance(exc, StateError) else f"{type(exc).__name__}: {exc}"
            self._report("error", f"FMU state refused, the unit is unchanged: {reason}")
            raise StateError(reason) from None

    @staticmethod
    def _fmu_state_to_bytes(handle) -> bytes:
        try:
            return checkpoint.to_bytes(_checkpoint_of(handle))
        except StateError as exc:
            LOG.error("FMU state not serialized: %s", exc)
            raise

    @classmethod
    def _fmu_state_from_bytes(cls, data: bytes) -> guard.StateHandle:
        """A state read from bytes, refused at once (StateError, logged) unless this unit wrote it
        and it fits a simulation of its scene.  (The class cannot know the instance's colliders: their
        parameters in the state are checked here one by one, and against the unit's at SetFMUstate.)"""
        try:
            state = checkpoint.from_bytes(data)
            names = {s.name for s in variable_specs(fmi_version=cls.FMI_VERSION) if s.causality in ("parameter", "input")}
            values = state.values if isinstance(state, Checkpoint) and isinstance(state.values, dict) else {}
            checkpoint.fitting_simulation(state, names | {name for name in values if collider_name(name)})
            return guard.StateHandle(state)
        except Exception as exc:  # whatever it is, the reason is logged on wetcloth.fmu
            reason = str(exc) if isinstance(exc, StateError) else f"{type(exc).__name__}: {exc}"
            LOG.error("serialized FMU state refused: %s", reason)
            raise StateError(reason) from None

    # ------------------------------------------------------------------ FMU state
    def capture(self) -> Checkpoint:
        """The whole unit's state: values, refusals, clock, frame count and the simulation's snapshot."""
        sim = self.sim
        return Checkpoint(values=dict(self.values), refused=dict(self.refused), initialized=self.initialized,
                          start_time=self.start_time, frames=self.frames, scene=sim.scene if sim else None,
                          leaves=checkpoint.leaves_of(sim.snapshot()) if sim else {})

    def restore(self, state) -> None:
        """Return to a checkpoint (of this or another instance of this unit); StateError, nothing
        changed, if it is not one or does not fit: everything is checked before anything changes."""
        sim = checkpoint.fitting_simulation(state, set(self.values), self.sim if self.initialized else None)
        if sim is None and self.sim is not None and self.initialized:
            pass  # an uninitialized state: the unit goes back to before its initialization
        if sim is not None:
            sim.restore(checkpoint.snapshot_from(state.leaves, state.scene, sim.snapshot()))
        self._rewind_frames(state)
        self.values, self.refused = dict(state.values), dict(state.refused)
        self.entered = self.entered and not self.initialized and not state.initialized  # else: instantiated
        self.initialized, self.start_time, self.frames = state.initialized, state.start_time, state.frames
        self._clock_set = self._clock_set or state.initialized
        self.sim, self._preview = sim, None
        self._read.clear()

    def _rewind_frames(self, state: Checkpoint) -> None:
        """After a rollback the open sequence continues after the state's frames (later ones were the
        abandoned branch); a sequence of another folder or format is closed (the next step resumes)."""
        if self.sequence is None:  # no mesh output: nothing of the exporter (meshio, trimesh) is needed
            return
        mesh = ("mesh_output_dir", "mesh_format")
        try:
            if all(state.values[k] == self.values[k] for k in mesh):
                return self.sequence.resume_after(state.frames)
        except Exception as exc:  # ExportError, OSError: the frames' trouble; the state is restored all the same
            self._report("warning", f"mesh_output_dir: {exc}")
        try:
            self.sequence.close(complete=False)
        except Exception as exc:
            self._report("warning", f"mesh_output_dir: {exc}")
        self.sequence = None
