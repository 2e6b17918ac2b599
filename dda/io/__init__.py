"""Input and output: VTU/PVD series for ParaView and pyvista, TOML scene files, recorded
accelerograms (PEER NGA .AT2, K-NET / KiK-net)."""

from dda.io.records import Record, RecordError, read_at2, read_knet, read_record
from dda.io.scene_file import LoadedScene, SceneFileError, load_scene
from dda.io.vtu import VTUWriter

__all__ = ["LoadedScene", "Record", "RecordError", "SceneFileError", "VTUWriter", "load_scene",
           "read_at2", "read_knet", "read_record"]
