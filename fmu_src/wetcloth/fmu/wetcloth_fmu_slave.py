"""WetCloth.fmu's slave script (FMI 2.0, pythonfmu): find wetcloth, then define the unit.

pythonfmu's binary imports this file by its name (unique to this project, as modules are cached
by name) and instantiates the deepest ``Fmi2Slave`` subclass defined here.  The unit itself is
``wetcloth.fmu.fmi2.Fmi2Unit``; ``wetcloth_fmu_bootstrap`` (``wetcloth/fmu/bootstrap.py``) picks
the wetcloth it runs.
"""

from pathlib import Path

from wetcloth_fmu_bootstrap import load_wetcloth

load_wetcloth(Path(__file__).parent)

from wetcloth.fmu import guard  # noqa: E402
from wetcloth.fmu.fmi2 import Fmi2Unit  # noqa: E402

guard.hold_script_namespace(globals())  # runs at every instantiation, see wetcloth.fmu.guard


class WetCloth(Fmi2Unit):
    """A cloth dropped onto water (wetcloth): floats, absorbs water where it touches it, sinks."""
