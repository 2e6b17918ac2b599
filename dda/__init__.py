"""dda: 2D Discontinuous Deformation Analysis of jointed rock and masonry.

>>> import dda
>>> scene = dda.Scene(gravity=9.81)
"""

from dda import io
from dda.io.scene_file import load_scene
from dda.result import Result
from dda.scene import Block, Scene
from dda.simulation import PenaltyWarning, Simulation, SimulationError

__all__ = ["Block", "PenaltyWarning", "Result", "Scene", "Simulation", "SimulationError", "io",
           "load_scene"]
__version__ = "0.1.0"
