"""The errors a run raises."""

__all__ = ["SimulationError", "FrictionLawError", "OverlapError"]


class SimulationError(RuntimeError):
    """A run that cannot go on; ``result`` holds the steps done before."""

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


class FrictionLawError(SimulationError):
    """A friction law that returned a non-finite shear force or tangent from finite inputs:
    a defect of the law, which no smaller dt mends."""


class OverlapError(ValueError):
    """Blocks that overlap at the start: ``blocks`` are the two handles, ``depth`` (m) how far
    the deeper one's deepest point lies inside the other."""

    def __init__(self, message, blocks=None, depth=None):
        super().__init__(message)
        self.blocks = blocks
        self.depth = depth
