"""dda: 2D Discontinuous Deformation Analysis of jointed rock and masonry.

>>> import dda
>>> scene = dda.Scene(gravity=9.81)
"""

from dda import io
from dda.result import Result
from dda.scene import Block, Scene
from dda.simulation import Simulation, SimulationError

__all__ = ["Block", "Result", "Scene", "Simulation", "SimulationError", "io"]
__version__ = "0.1.0"
