"""Output: VTU/PVD series for ParaView and pyvista."""

from dda.io.vtu import VTUWriter

__all__ = ["VTUWriter"]
