"""The strategy interface that solves one time step, and what goes in and out of it.

The simulation owns the loop over steps, commit and revert; a solver only turns one
:class:`StepProblem` (built from the committed state) into a :class:`StepSolution` (a trial the
simulation commits when it has converged).
"""

from __future__ import annotations

import threading
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from dda.contact.contacts import ContactSet
from dda.contact.element import ContactElement
from dda.profiling import section
from dda.solvers.linear import SystemPattern
from dda.solvers.sparse_factor import FactorSet, SparseFactor

__all__ = ["NonlinearSolver", "StepProblem", "StepSolution"]


@dataclass
class StepProblem:
    """Everything a solver needs for one step, all built from the committed state.

    Attributes
    ----------
    dt : step size
    block_k, block_f : (n_blocks, 6, 6) and (n_blocks, 6) effective block matrices and forces
        (stiffness, Newmark inertia, constraints, loads), contacts excluded
    free : (n_blocks,) bool, the blocks that carry unknowns
    d_known : (n_blocks, 6) known increments of the other blocks
    element : ContactElement of the step's contacts
    max_open_close : limit of OPEN-CLOSE passes before the step is declared failed
    rigid : (n_blocks,) bool or None, blocks with 3 unknowns (no strain)
    factors : FactorSet or None, the solver's factorizations kept from step to step
        (:meth:`NonlinearSolver.factors`); one-off ones when None
    bolts : :class:`dda.bolts.BoltTerm` of the step's intact bolts, or None (a scene without
        bolts, or with every bolt broken): axial springs that couple their two blocks like a
        contact, linear in the step's increments. Their block pairs follow the contacts' in
        :attr:`pair_blocks` and in the :attr:`pattern`; :meth:`with_bolts` appends their
        stiffness and forces to the contacts'.
    """

    dt: float
    block_k: np.ndarray
    block_f: np.ndarray
    free: np.ndarray
    d_known: np.ndarray
    element: ContactElement
    max_open_close: int = 12
    rigid: np.ndarray | None = None
    factors: FactorSet | None = None
    bolts: object | None = None

    def factor(self, symmetric: bool) -> SparseFactor | None:
        """Who factorizes this step's sparse systems, symmetric (the OPEN-CLOSE passes) or
        not (Newton's tangent); None: a one-off holder per solve."""
        return None if self.factors is None else self.factors.get(symmetric)

    @cached_property
    def pattern(self) -> SystemPattern:
        """The assembly's index work for this step's blocks and contacts (built once, and
        kept for the next step when its blocks and contacts are the same)."""
        with section("assembly"):
            el = self.element
            args = ((self.free, el.bj, el.bk, self.rigid) if self.bolts is None
                    else (self.free, *self.pair_blocks, self.rigid))
            if self.factors is None:
                return SystemPattern(*args)
            return self.factors.kept("pattern", args,
                                     lambda: SystemPattern(*args, cache=self.factors))


    @property
    def pair_blocks(self) -> tuple[np.ndarray, np.ndarray]:
        """``(bj, bk)``: the two blocks of every coupling term of the system, the contacts'
        and then the bolts'."""
        el = self.element
        if self.bolts is None:
            return el.bj, el.bk
        kept = self.__dict__.get("_pair_blocks")
        if kept is None:
            kept = self.__dict__["_pair_blocks"] = (
                np.concatenate([np.asarray(el.bj, dtype=np.int64), self.bolts.bj]),
                np.concatenate([np.asarray(el.bk, dtype=np.int64), self.bolts.bk]))
        return kept

    def with_bolts(self, pair_k, pair_f):
        """The contacts' stiffness and forces on ``[d_j; d_k]`` with the bolts' appended
        (:meth:`dda.bolts.BoltTerm.joined`), the pairs of :attr:`pair_blocks`; as given
        without bolts."""
        if self.bolts is None:
            return pair_k, pair_f
        return self.bolts.joined(pair_k, pair_f)


@dataclass
class StepSolution:
    """A solver's trial for one step.

    ``converged`` False means the step must be reverted and retried (``reason`` says why).
    """

    d: np.ndarray | None
    contacts: ContactSet | None
    converged: bool
    open_close_passes: int = 0
    iterations: int = 0
    reason: str = ""
    residual_norms: list[float] = field(default_factory=list)
    search_hint: float = 0.0
    unknowns: int = 0
    pairs: int = 0
    penetration: float = 0.0
    spring_penetration: float = 0.0
    untracked: float = 0.0  # the deepest untracked penetration, in penetration tolerances


class NonlinearSolver(ABC):
    """A strategy that solves one time step (DESIGN.md: LegacyPullBack, NewtonRaphson)."""

    name = "solver"
    #: steps per period of the shaking that ``dt="auto"`` takes (:mod:`dda.auto_settings`,
    #: rule 1)
    auto_steps_per_period = 300
    #: the steps added per unit of the largest strength drop at the onset of slip of the
    #: scene's friction laws (:meth:`dda.contact.FrictionLaw.onset_drop`; 0: none added)
    auto_steps_per_drop = 0.0
    #: the "auto" penalty as a multiple of Newmark's inertia ``2 m / dt^2`` of the lightest free
    #: block (:mod:`dda.auto_settings`, rule 2)
    auto_kappa = 3.0

    def factors(self) -> FactorSet:
        """The sparse factorizations this solver keeps from step to step (their symbolic
        analysis stands while the system's pattern does), one set per thread: a solver
        shared by runs in threads never shares a factorization."""
        per_thread = self.__dict__.setdefault("_factors", {})
        key = threading.get_ident()
        if key not in per_thread:
            per_thread[key] = FactorSet()
        return per_thread[key]

    def __getstate__(self):
        # factorizations are caches (and hold library handles): never pickled
        state = self.__dict__.copy()
        state.pop("_factors", None)
        return state

    @abstractmethod
    def solve_step(self, problem: StepProblem) -> StepSolution:
        """Solve one step from the committed state; never modify the problem's arrays."""

    def __repr__(self):
        return f"{type(self).__name__}()"
