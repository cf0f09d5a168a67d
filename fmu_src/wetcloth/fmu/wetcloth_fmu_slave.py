"""WetCloth: the FMI 2.0 co-simulation slave of wetcloth (pythonfmu), a thin wrapper around
``wetcloth.Simulation``: no physics of its own.

Which Python runs this: pythonfmu's binary does not link a Python library; it uses the
interpreter of the process that loads the FMU (fmpy, libcosimpy, any Python master).  That
interpreter must have wetcloth's dependencies (numpy, numba; for mesh frames also trimesh,
scipy, matplotlib and meshio).
wetcloth itself travels inside the FMU (``resources/wetcloth``): when the host's own wetcloth is
the very same source (same file digests, e.g. the project's ``.venv``), that one is imported so
numba's compiled-kernel cache is reused; otherwise the bundled copy is.

The file name is unique to this project because pythonfmu finds the slave class through
Python's module cache by script name; the class line must read ``class WetCloth(Fmi2Slave):``
(pythonfmu's binary looks for it textually).
"""

from __future__ import annotations

import copy
import hashlib
import importlib
import importlib.util
import json
import logging
import math
import pickle
import sys
from pathlib import Path

from pythonfmu import DefaultExperiment, Fmi2Slave
from pythonfmu.enums import Fmi2Status

HERE = Path(__file__).resolve().parent
#: Errors also go to Python's logging (stderr by default): pythonfmu forwards FMI log messages
#: only while the master has logging switched on.
LOG = logging.getLogger("wetcloth.fmu")
#: Written by the builder into the FMU's resources: digests of the bundled wetcloth, variable names.
MANIFEST_NAME = "wetcloth_fmu_manifest.json"


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _same_sources(package_dir: Path, files: dict[str, str]) -> bool:
    try:
        return all(_digest(package_dir / rel) == digest for rel, digest in files.items())
    except OSError:
        return False


def _import_wetcloth(manifest: dict | None):
    """Import wetcloth: the host's copy if already imported or identical to the bundle, else the bundle.

    A process holds one wetcloth: one already imported is used as it is, with a warning when its
    sources differ from the bundle's.
    """
    if "wetcloth" in sys.modules or manifest is None:
        module = importlib.import_module("wetcloth")
        if manifest is not None and not _same_sources(Path(module.__file__).parent, manifest["files"]):
            LOG.warning("this WetCloth.fmu runs the wetcloth already imported in this process (%s), whose sources "
                        "differ from the copy the FMU was built with; results may differ from that build's",
                        Path(module.__file__).parent)
        return module
    saved = list(sys.path)
    try:
        sys.path[:] = [p for p in saved if Path(p or ".").resolve() != HERE]
        spec = importlib.util.find_spec("wetcloth")
        if spec is not None and spec.submodule_search_locations:
            host_dir = Path(next(iter(spec.submodule_search_locations)))
            if host_dir.resolve() != (HERE / "wetcloth").resolve() and _same_sources(host_dir, manifest["files"]):
                return importlib.import_module("wetcloth")
    finally:
        sys.path[:] = saved
    return importlib.import_module("wetcloth")  # the copy in resources/, first on sys.path


_MANIFEST = json.loads((HERE / MANIFEST_NAME).read_text()) if (HERE / MANIFEST_NAME).exists() else None
wetcloth = _import_wetcloth(_MANIFEST)

from wetcloth.errors import BlowUpError, ParameterError  # noqa: E402
from wetcloth.fmu.description import extend_model_description, make_variable  # noqa: E402
from wetcloth.fmu.vocabulary import MESH_FORMAT_RANGE, MESH_FORMATS, MODEL_NAME, variable_specs  # noqa: E402
from wetcloth.scene import check_value, from_dict, read_scene_file  # noqa: E402
from wetcloth.simulation import Simulation  # noqa: E402

SPECS = variable_specs()
SPEC = {spec.name: spec for spec in SPECS}
if _MANIFEST is not None and _MANIFEST["variables"] != [s.name for s in SPECS]:
    raise RuntimeError(
        f"this WetCloth.fmu was built for the variables {_MANIFEST['variables']}, but the wetcloth imported "
        f"from {Path(wetcloth.__file__).parent} defines {[s.name for s in SPECS]}; rebuild it with "
        "`wetcloth build-fmu`"
    )

#: Tag of the FMU-state snapshots (dicts) and their serialized bytes.
STATE_FORMAT = "wetcloth-fmu-state/1"
#: Relative tolerance when matching the master's communication time with the unit's time.
TIME_TOLERANCE = 1e-9
#: Key of the pending error of parameters that pass one by one but not together (fixed after
#: initialization, so no setter clears it).
INVALID_SCENE = "scene"


def _default_experiment() -> DefaultExperiment:
    run = read_scene_file(None).get("run", {})
    return DefaultExperiment(start_time=0.0, stop_time=float(run.get("duration", 90.0)),
                             step_size=1.0 / float(run.get("fps", 30.0)))


class WetCloth(Fmi2Slave):
    """A cloth dropped onto water (wetcloth): floats, absorbs water where it touches it, sinks."""

    author = "wetcloth"
    description = ("Mass-spring cloth on water with buoyancy, drag and Buras-law absorption "
                   "(wetcloth, FMI 2.0 co-simulation via pythonfmu; needs Python with numpy and numba)")
    version = wetcloth.__version__
    license = "MIT"
    default_experiment = _default_experiment()

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.modelName = MODEL_NAME
        self._values = {spec.name: spec.start for spec in SPECS if spec.causality != "output"}
        self._rejected: dict[str, str] = {}  # variable -> why its value was refused (pending error)
        self._initialized = False
        self._start_time = 0.0
        self.sim: Simulation | None = None  # the running simulation, from exit_initialization_mode on
        self._preview: Simulation | None = None  # initial state of the current values, before that
        self._outputs: dict[str, float] | None = None
        self._frame = 0  # index of the next mesh frame
        self._sequence = None  # the mesh exporter's sequence, opened at the first step
        for spec in SPECS:
            if spec.causality == "output":
                self.register_variable(make_variable(spec, self._output_getter(spec.name), None))
            else:
                self.register_variable(make_variable(spec, self._value_getter(spec.name), self._setter(spec.name)))

    # ------------------------------------------------------------------ model description
    def to_xml(self, model_options=dict()):
        return extend_model_description(super().to_xml(model_options), SPECS)

    # ------------------------------------------------------------------ variables
    def _value_getter(self, name):
        return lambda: self._values[name]

    def _output_getter(self, name):
        return lambda: self._current_outputs()[name]

    def _setter(self, name):
        return lambda value: self._set(name, value)

    def _reject(self, name: str, message: str, consequence: str | None = None) -> None:
        """Log an error naming the variable and its range; the unit refuses to step while it is pending."""
        if consequence is None:
            consequence = f"value refused, {name} stays {self._values.get(name)!r}"
        self._rejected[name] = message
        self._error(f"{message} ({consequence})")

    def _error(self, message: str) -> None:
        """Log an error through FMI (shown when the master enables logging) and Python's logging."""
        self.log(message, Fmi2Status.error)
        LOG.error("%s: %s", self.instance_name, message)

    def _set(self, name: str, value) -> None:
        """Set a variable: checked against its allowed range; a refused value is logged and pending."""
        spec = SPEC[name]
        if spec.scene:
            try:
                check_value(name, value)
            except ParameterError as exc:
                return self._reject(name, str(exc))
        elif name == "mesh_format" and value not in MESH_FORMATS:
            return self._reject(name, f"parameter 'mesh_format': {value!r} is not allowed; "
                                      f"allowed: {MESH_FORMAT_RANGE}")
        if self._initialized:
            if spec.causality != "input":
                if value != self._values[name]:  # its own value is accepted (and clears a refused change)
                    return self._reject(name, f"parameter '{name}' is fixed once the unit is initialized; only the "
                                              "inputs " + ", ".join(s.name for s in SPECS if s.causality == "input")
                                              + " may change")
            elif value != self._values[name]:
                try:
                    self.sim.set_inputs(**{name: value})
                except ParameterError as exc:
                    return self._reject(name, str(exc))
        else:
            self._preview = None
        self._values[name] = value
        self._rejected.pop(name, None)
        self._outputs = None

    def _scene_values(self) -> dict:
        return {name: value for name, value in self._values.items() if SPEC[name].scene}

    def _current_outputs(self) -> dict[str, float]:
        if self._outputs is None:
            sim = self.sim if self.sim is not None else self._preview_simulation()
            self._outputs = sim.outputs()
        return self._outputs

    def _preview_simulation(self) -> Simulation:
        """The initial state of the current values (or, if they do not form a valid scene, the defaults)."""
        if self._preview is None:
            try:
                self._preview = Simulation(from_dict(self._scene_values()))
            except ParameterError:
                self._preview = Simulation(from_dict({s.name: s.start for s in SPECS if s.scene}))
        return self._preview

    # ------------------------------------------------------------------ life cycle
    def setup_experiment(self, start_time=0.0, stop_time=None, tolerance=None):
        self._start_time = float(start_time)

    def exit_initialization_mode(self):
        """Build the simulation from the parameters and start values of the inputs."""
        self._initialized = True
        self._outputs = None
        try:
            self.sim = Simulation(from_dict(self._scene_values()))
        except ParameterError as exc:
            self._reject(INVALID_SCENE, str(exc), "the parameters do not form a valid scene; the unit will not step")
            self.sim = self._preview_simulation()  # last accepted configuration: outputs stay defined

    def do_step(self, current_time: float, step_size: float) -> bool:
        """Advance by ``step_size`` s; False (fmi2Discard, message logged) leaves the unit at ``current_time``."""
        if self._rejected:
            for message in self._rejected.values():
                self._error(f"step refused at t = {current_time:g} s: {message}")
            return False
        sim = self.sim
        if sim is None:
            self._error("do_step called before the unit was initialized")
            return False
        now = self._start_time + sim.time
        if abs(current_time - now) > TIME_TOLERANCE * max(1.0, abs(now)):
            self._error(f"do_step from t = {current_time!r} s, but the unit is at t = {now!r} s; "
                        "restore an FMU state to go back in time")
            return False
        if not (step_size >= 0.0 and math.isfinite(step_size)):
            self._error(f"communication step size must be a finite number >= 0 s, got {step_size!r}")
            return False
        if self._values["mesh_output_dir"] and not self._open_sequence(step_size):
            return False
        checkpoint = sim.snapshot()
        try:
            sim.advance(max(0.0, current_time + step_size - self._start_time - sim.time))
            if self._sequence is not None:
                self._sequence.on_frame(self._frame, sim)
        except Exception as exc:  # a blow-up, or anything else: never let it reach the master as a crash
            sim.restore(checkpoint)
            self._outputs = None
            kind = "" if isinstance(exc, BlowUpError) else f"{type(exc).__name__}: "
            self._error(f"step from t = {current_time:g} s by {step_size:g} s failed: {kind}{exc} "
                        f"The unit stays at t = {current_time:g} s with its last good outputs.")
            return False
        self._frame += self._sequence is not None
        self._outputs = None
        return True

    def _open_sequence(self, step_size: float) -> bool:
        """Open the mesh exporter at the first step and write the frame of the current state.

        A new run replaces the frames of an earlier run in the folder; a run resumed from a
        restored FMU state continues its frames (``cloth_<frame + 1>`` next).
        """
        if self._sequence is not None:
            return True
        directory, fmt = self._values["mesh_output_dir"], self._values["mesh_format"]
        fps = 1.0 / (step_size if step_size > 0 else self.default_experiment.step_size)
        try:
            from wetcloth.exporter import FrameSequence, open_sequence

            if self._frame == 0:
                sequence = open_sequence(directory, fmt=fmt, writer="trimesh", fps=fps, scene=self.sim.scene,
                                         overwrite=True)
                sequence.on_frame(0, self.sim)
            else:
                Path(directory).mkdir(parents=True, exist_ok=True)
                sequence = FrameSequence(Path(directory), fmt, "trimesh", fps, scene=self.sim.scene)
                sequence.resume_after(self._frame)
        except Exception as exc:
            self._reject("mesh_output_dir", f"parameter 'mesh_output_dir': cannot write {fmt} frames into "
                                            f"{directory!r}: {exc}", "no step is taken")
            return False
        self._sequence = sequence
        self._frame = sequence.frame_count
        return True

    def terminate(self):
        if self._sequence is not None:
            self._sequence.close()
            self._sequence = None

    # ------------------------------------------------------------------ FMU state
    def _get_fmu_state(self) -> dict:
        """A snapshot of the whole unit: the simulation object with all its arrays, values and counters."""
        return {
            "format": STATE_FORMAT,
            "values": dict(self._values),
            "rejected": dict(self._rejected),
            "initialized": self._initialized,
            "start_time": self._start_time,
            "frame": self._frame,
            "sim": copy.deepcopy(self.sim),
        }

    def _set_fmu_state(self, state: dict) -> None:
        if not isinstance(state, dict) or state.get("format") != STATE_FORMAT:
            raise ValueError(f"not a WetCloth FMU state (expected format {STATE_FORMAT!r})")
        if self._sequence is not None and (state["values"]["mesh_output_dir"], state["values"]["mesh_format"]) != (
                self._values["mesh_output_dir"], self._values["mesh_format"]):
            self.terminate()
        self._values = dict(state["values"])
        self._rejected = dict(state["rejected"])
        self._initialized = state["initialized"]
        self._start_time = state["start_time"]
        self._frame = state["frame"]
        self.sim = copy.deepcopy(state["sim"])  # the snapshot stays reusable
        if self._sequence is not None:
            self._sequence.resume_after(self._frame)  # rolled back: the next frames overwrite later ones
        self._preview = None
        self._outputs = None

    @staticmethod
    def _fmu_state_to_bytes(state: dict) -> bytes:
        return pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL)

    @staticmethod
    def _fmu_state_from_bytes(data: bytes) -> dict:
        try:
            state = pickle.loads(data)  # bytes come from this unit's own fmi2SerializeFMUstate
        except Exception as exc:
            raise ValueError(f"not a serialized WetCloth FMU state ({type(exc).__name__}: {exc})") from None
        if not isinstance(state, dict) or state.get("format") != STATE_FORMAT:
            raise ValueError(f"not a serialized WetCloth FMU state (expected format {STATE_FORMAT!r})")
        return state
