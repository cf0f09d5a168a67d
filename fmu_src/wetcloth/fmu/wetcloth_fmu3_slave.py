"""WetCloth3.fmu's slave script (FMI 3.0, pythonfmu3): find wetcloth, then define the unit.

pythonfmu3's binary imports this file by its name and instantiates the first class whose line
names ``Fmi3Slave`` (it reads the class line as text).  The unit itself is
``wetcloth.fmu.fmi3.Fmi3Unit``; ``wetcloth_fmu_bootstrap`` (``wetcloth/fmu/bootstrap.py``) picks
the wetcloth it runs.

pythonfmu3's binary crashes its host when this script fails to import (a segmentation fault in its
error path), but not when the class fails to instantiate: a failure to start (already logged by the
bootstrap) is therefore raised by the class instead.
"""

from pathlib import Path

from pythonfmu3 import Fmi3Slave
import wetcloth_fmu_bootstrap
from wetcloth_fmu_bootstrap import load_wetcloth

try:
    load_wetcloth(Path(__file__).parent)
    from wetcloth.fmu.fmi3 import Fmi3Unit
except Exception as _failure:  # noqa: BLE001 (logged by load_wetcloth; raised at instantiation below)
    _START_FAILURE = ImportError(str(_failure))
    _failure_logged = True  # by load_wetcloth, for the instantiation that ran this script

    class Fmi3Unit:
        """Stands in for the unit when wetcloth cannot start: every instantiation fails with the reason (logged)."""

        def __init__(self, **kwargs):
            global _failure_logged
            if not _failure_logged:
                wetcloth_fmu_bootstrap.LOG.error("%s", _START_FAILURE)
            _failure_logged = False
            raise _START_FAILURE


class WetCloth(Fmi3Unit, Fmi3Slave):
    """A cloth dropped onto water (wetcloth): floats, absorbs water where it touches it, sinks; its mesh every step."""
