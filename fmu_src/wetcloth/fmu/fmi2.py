"""The FMI 2.0 face of a WetCloth unit (pythonfmu): the vocabulary's variables, FMI calls mapped onto ``WetClothUnit``.

pythonfmu's binary reports a Python exception as fmi2Fatal, the only error status it lets a slave
give; a refused initialization, FMU state or doStep therefore raises (logged first), and
``guard`` keeps the instance usable afterwards.  A step the unit cannot take (a blow-up, a refused
input) returns False: fmi2Discard, and the unit stays at its last good state.
"""

from __future__ import annotations

from pythonfmu import DefaultExperiment, Fmi2Slave
from pythonfmu.enums import Fmi2Status
from pythonfmu.variables import Boolean, Integer, Real, String

import wetcloth
import wetcloth.fmu as fmu_package
from wetcloth.fmu import MODEL_NAME, guard
from wetcloth.fmu.description import extend_model_description, make_variable
from wetcloth.fmu.unit import OK, WetClothUnit, check_references_before, default_run

#: pythonfmu's methods that the binary calls on an instance, and on the class.
ENTRY_POINTS = ("setup_experiment", "enter_initialization_mode", "exit_initialization_mode", "do_step", "terminate",
                "get_integer", "get_real", "get_boolean", "get_string", "set_integer", "set_real", "set_boolean",
                "set_string", "_get_fmu_state", "_set_fmu_state")
CLASS_ENTRY_POINTS = ("_fmu_state_to_bytes", "_fmu_state_from_bytes")


class Fmi2Unit(WetClothUnit, Fmi2Slave):
    """WetCloth as an FMI 2.0 co-simulation slave."""

    FMI_VERSION = 2
    LOG_STATUS = {"error": Fmi2Status.error, "warning": Fmi2Status.warning}
    author = "wetcloth"
    description = ("Mass-spring cloth on water with buoyancy, drag and Buras-law absorption "
                   "(wetcloth, FMI 2.0 co-simulation via pythonfmu; needs CPython with numpy)")
    version = wetcloth.__version__
    license = "MIT"
    default_experiment = DefaultExperiment(0.0, *default_run())

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.modelName = MODEL_NAME
        self._start_unit()
        guard.register(self)
        for name, spec in self.specs.items():
            self.register_variable(make_variable(spec, *self.accessors(name)))

    def to_xml(self, model_options=dict()):
        self.guid = fmu_package.BUILD_TOKEN or self.guid  # from the unit's contents (builder.content_token)
        return extend_model_description(super().to_xml(model_options), list(self.specs.values()))

    def do_step(self, current_time: float, step_size: float) -> bool:
        return self.step(current_time, step_size) == OK


check_references_before(Fmi2Unit, Fmi2Slave, "fmi2", (Real, Integer, Boolean, String))
guard.guard(Fmi2Unit, ENTRY_POINTS, CLASS_ENTRY_POINTS)
