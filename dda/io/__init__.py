"""Input and output: VTU/PVD series for ParaView and pyvista, TOML scene files."""

from dda.io.scene_file import LoadedScene, SceneFileError, load_scene
from dda.io.vtu import VTUWriter

__all__ = ["LoadedScene", "SceneFileError", "VTUWriter", "load_scene"]
