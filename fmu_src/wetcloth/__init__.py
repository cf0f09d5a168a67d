"""wetcloth: cloth that meets water. A mass-spring cloth with buoyancy, drag and water absorption.

    import wetcloth
    sim = wetcloth.Simulation(wetcloth.load_scene("thesis_fast", nx=17))
    sim.advance(2.0)
    sim.outputs()
"""

from wetcloth import core_build as _core_build

_core_build.load()  # the build of the compiled core this CPU runs fastest, as wetcloth._core

from wetcloth.errors import BlowUpError, ConfigError, ParameterError
from wetcloth.scene import Scene, load_scene
from wetcloth.simulation import OUTPUT_NAMES, Simulation


def study(study, **options):
    """Run a batch study on Dask and return its results as a pandas DataFrame, one row per run.

    A thin wrapper so that ``import wetcloth`` does not import dask: see
    :func:`wetcloth.batch.execution.study` for the arguments (a study file, dict or ``Study``;
    ``scheduler``, ``workers``, ``out``, ``engine`` ...) and ``docs/batch.md``.
    """
    from wetcloth.batch import study as _study

    return _study(study, **options)


__all__ = ["BlowUpError", "ConfigError", "OUTPUT_NAMES", "ParameterError", "Scene", "Simulation", "load_scene", "study"]
__version__ = "0.1.0"
