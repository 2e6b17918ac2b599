"""StepControl: the size of the next step, cut on a refused step and grown back after.

A refused step (:func:`dda.step.step`) is tried again: first with a wider contact search when
it moved farther than predicted (at most ``max_widenings`` times), then with half the step
size. After ``grow_after`` accepted steps in a row a cut step size doubles again, up to the
size asked for. A step cut more than ``max_cuts`` times in a row ends the run.
"""

from __future__ import annotations

from dataclasses import dataclass

from dda.errors import SimulationError
from dda.penalty_advice import contact_cut

__all__ = ["StepControl"]


@dataclass
class StepControl:
    """Adaptive step size of a run (see the module docstring).

    Parameters
    ----------
    dt : the step size asked for (s)
    max_cuts : cuts of one step in a row before the run stops
    grow_after : accepted steps in a row after which a cut step size doubles
    max_widenings : retries of one step with a wider search before dt is cut instead
    """

    dt: float
    max_cuts: int = 12
    grow_after: int = 8
    max_widenings: int = 2
    # what the control has seen so far
    dt_now: float | None = None
    good_steps: int = 0
    search_hint: float = 0.0
    steps: int = 0  # accepted steps
    contact_cuts: int = 0  # steps cut because the contacts would not settle

    def __post_init__(self):
        if self.dt_now is None:
            self.dt_now = self.dt

    def step_size(self, remaining: float) -> float:
        """The size of the next try, leaving no sliver of a step before ``remaining``."""
        dt = min(self.dt_now, remaining)
        if remaining - dt < 1e-6 * dt:
            dt = remaining
        return dt

    def widen(self, hint: float, widened: int) -> bool:
        """After a refused try: search wider (True) when the step asks for it and may."""
        if hint > self.search_hint and widened < self.max_widenings:
            self.search_hint = hint
            return True
        return False

    def cut(self, dt: float, reason: str) -> None:
        """After a refused try that is not widened: halve the step size."""
        if contact_cut(reason):
            self.contact_cuts += 1
        self.dt_now = dt / 2.0
        self.good_steps = 0

    def accepted(self) -> None:
        """After an accepted step: forget the hint, grow a cut step size back when due."""
        self.search_hint = 0.0
        self.steps += 1
        self.good_steps += 1
        if self.dt_now < self.dt and self.good_steps >= self.grow_after:
            self.dt_now = min(self.dt, 2.0 * self.dt_now)
            self.good_steps = 0

    def check_can_go_on(self, report, tries: int, dt: float, committed) -> None:
        """After a cut: raise :class:`dda.SimulationError` when cutting dt further cannot
        help (``tries`` cuts of this step, the last at ``dt``, from the ``committed``
        state)."""
        time = committed.time
        if report.untracked > 1.0 and committed.untracked > 0.5:
            # the vertex is already half the tolerance in, untracked, at the start of the
            # step: any step that moves it on is refused, and smaller ones only creep
            raise SimulationError(
                f"the run cannot go on at t = {time:.6g} s: {report.reason}; it was already "
                f"{committed.untracked:.2g} tolerances deep, untracked, at the start of "
                "the step, so a smaller dt cannot help (contact detection missed it: please "
                "report the scene)"
            )
        if tries > self.max_cuts:
            raise SimulationError(
                f"the run cannot go on at t = {time:.6g} s: {report.reason} "
                f"(step cut {tries} times down to dt = {dt:.3g} s)"
            )
