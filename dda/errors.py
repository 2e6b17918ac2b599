"""The errors a run raises."""

__all__ = ["SimulationError"]


class SimulationError(RuntimeError):
    """A run that cannot go on; ``result`` holds the steps done before."""

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result
