"""The FMI 3.0 face of a WetCloth unit (pythonfmu3): the vocabulary's variables with the mesh as array
outputs, FMI calls mapped onto ``WetClothUnit``.

pythonfmu3 lets ``do_step`` return any status: a refused call is fmi3Error, a step the unit cannot
take (a blow-up, a refused input) fmi3Discard.  Elsewhere a Python exception is its only error
status (fmi3Fatal); ``guard`` keeps the instance usable afterwards.  pythonfmu3 does not pass
``fmi3EnterInitializationMode``'s start time to Python: the first ``fmi3DoStep`` sets the clock.
"""

from __future__ import annotations

from pythonfmu3 import DefaultExperiment, Fmi3Slave, Fmi3Status, Fmi3StepResult
from pythonfmu3.variables import Boolean, Float64, Int32, Int64, String, UInt64

import wetcloth
import wetcloth.fmu as fmu_package
from wetcloth.fmu import MODEL_NAME, description3, guard
from wetcloth.fmu.unit import OK, UnitError, WetClothUnit, check_references_before, default_run

#: pythonfmu3's methods that the binary calls on an instance, and on the class.
ENTRY_POINTS = ("enter_initialization_mode", "exit_initialization_mode", "do_step", "terminate", "get_float64",
                "get_int32", "get_int64", "get_uint64", "get_boolean", "get_string", "set_float64", "set_int32",
                "set_int64", "set_uint64", "set_boolean", "set_string", "_get_fmu_state", "_set_fmu_state",
                "update_discrete_states")
CLASS_ENTRY_POINTS = ("_fmu_state_to_bytes", "_fmu_state_from_bytes")


class Fmi3Unit(WetClothUnit, Fmi3Slave):
    """WetCloth as an FMI 3.0 co-simulation slave, with the cloth mesh as array outputs."""

    FMI_VERSION = 3
    LOG_STATUS = {"error": Fmi3Status.error, "warning": Fmi3Status.warning}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.modelName = MODEL_NAME
        self.author, self.license, self.version = "wetcloth", "MIT", wetcloth.__version__
        self.description = ("Mass-spring cloth on water with buoyancy, drag and Buras-law absorption, and its mesh "
                            "at every step (wetcloth, FMI 3.0 co-simulation via pythonfmu3; needs CPython with "
                            "numpy)")
        self.default_experiment = DefaultExperiment(0.0, *default_run())
        self._start_unit()
        guard.register(self)
        specs = list(self.specs.values())
        self.register_units(description3.units(specs))
        references = {spec.name: i for i, spec in enumerate(specs)}
        structural = description3.dimension_sources(specs)
        for name, spec in self.specs.items():
            self.register_variable(description3.make_variable(spec, *self.accessors(name), references, structural))

    def to_xml(self, model_options=dict()):
        self.guid = fmu_package.BUILD_TOKEN or self.guid  # from the unit's contents (builder.content_token)
        return description3.extend_model_description(super().to_xml(model_options), list(self.specs.values()))

    def do_step(self, current_time: float, step_size: float) -> Fmi3StepResult:
        try:
            outcome = self.step(current_time, step_size)
        except UnitError:
            return Fmi3StepResult(status=Fmi3Status.error)
        return Fmi3StepResult(status=Fmi3Status.ok if outcome == OK else Fmi3Status.discard)

    def update_discrete_states(self):
        """Refused (UnitError, logged): the unit has no event mode."""
        self._refuse_call("fmi3UpdateDiscreteStates is not supported: this unit has no events and no event mode "
                          "(allowed: fmi3DoStep in step mode)")


check_references_before(Fmi3Unit, Fmi3Slave, "fmi3", (Float64, Int32, Int64, UInt64, Boolean, String))
guard.guard(Fmi3Unit, ENTRY_POINTS, CLASS_ENTRY_POINTS)
