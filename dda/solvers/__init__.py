"""Strategies that solve one time step, the Newmark integrator and the linear solve."""

from dda.solvers.base import NonlinearSolver, StepProblem, StepSolution
from dda.solvers.legacy import LegacyPullBack

__all__ = ["LegacyPullBack", "NonlinearSolver", "StepProblem", "StepSolution"]
