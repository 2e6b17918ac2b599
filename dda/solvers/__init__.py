"""Strategies that solve one time step, the Newmark integrator and the linear solve."""

from dda.solvers.base import NonlinearSolver, StepProblem, StepSolution
from dda.solvers.legacy import LegacyPullBack
from dda.solvers.newton import NewtonRaphson

__all__ = ["LegacyPullBack", "NewtonRaphson", "NonlinearSolver", "StepProblem", "StepSolution"]
