"""WetCloth3.fmu's slave script (FMI 3.0, pythonfmu3): find wetcloth, then define the unit.

pythonfmu3's binary imports this file by its name and instantiates the first class whose line
names ``Fmi3Slave`` (it reads the class line as text).  The unit itself is
``wetcloth.fmu.fmi3.Fmi3Unit``; ``wetcloth_fmu_bootstrap`` (``wetcloth/fmu/bootstrap.py``) picks
the wetcloth it runs.
"""

from pathlib import Path

from pythonfmu3 import Fmi3Slave
from wetcloth_fmu_bootstrap import load_wetcloth

load_wetcloth(Path(__file__).parent)

from wetcloth.fmu.fmi3 import Fmi3Unit  # noqa: E402


class WetCloth(Fmi3Unit, Fmi3Slave):
    """A cloth dropped onto water (wetcloth): floats, absorbs water where it touches it, sinks; its mesh every step."""
