"""wetcloth: cloth that meets water. A mass-spring cloth with buoyancy, drag and water absorption.

    import wetcloth
    sim = wetcloth.Simulation(wetcloth.load_scene("thesis_fast", nx=17))
    sim.advance(2.0)
    sim.outputs()
"""

from wetcloth.errors import BlowUpError, ParameterError
from wetcloth.scene import Scene, load_scene
from wetcloth.simulation import OUTPUT_NAMES, Simulation

__all__ = ["BlowUpError", "OUTPUT_NAMES", "ParameterError", "Scene", "Simulation", "load_scene"]
__version__ = "0.1.0"
