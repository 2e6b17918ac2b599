"""Block materials."""

from dda.materials.linear_elastic import LinearElastic

__all__ = ["LinearElastic"]
