"""dda: 2D Discontinuous Deformation Analysis of jointed rock and masonry.

>>> import dda
>>> scene = dda.Scene(gravity=9.81)
"""

from dda.kernels import cache as _kernel_cache

_kernel_cache.drop_stale_kernel_caches()  # before any kernel loads its compiled code
_kernel_cache.COLD = _kernel_cache.cold_kernel_cache()  # this process will compile them

from dda import io  # noqa: E402
from dda.errors import FrictionLawError, OverlapError  # noqa: E402
from dda.io.scene_file import load_scene  # noqa: E402
from dda.result import Result  # noqa: E402
from dda.scene import Block, Scene  # noqa: E402
from dda.simulation import (  # noqa: E402
    PenaltyWarning,
    PlausibilityWarning,
    Simulation,
    SimulationError,
)

__all__ = ["Block", "FrictionLawError", "OverlapError", "PenaltyWarning", "PlausibilityWarning",
           "Result", "Scene", "Simulation", "SimulationError", "io", "load_scene"]
__version__ = "0.1.0"


def __getattr__(name):
    # dda.studies (sweeps, the factor of safety: dda.studies.strength_reduction) and dda.plot
    # (matplotlib, pyvista) are imported on first use, so that ``import dda`` loads neither
    # the sweep runner nor the plotting libraries
    if name in ("studies", "plot"):
        import importlib

        return importlib.import_module(f"dda.{name}")
    raise AttributeError(f"module 'dda' has no attribute {name!r}")
