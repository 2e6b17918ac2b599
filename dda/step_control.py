"""StepControl: the size of the next step, cut on a refused step and grown back after.

A refused step (:func:`dda.step.step`) is tried again: first with a wider contact search when
it moved farther than predicted (at most ``max_widenings`` times), then with half the step
size. After ``grow_after`` accepted steps in a row a cut step size doubles again, up to the
size asked for. A step cut more than ``max_cuts`` times in a row ends the run, or, when it takes
more, more than the cuts that bring the step asked down to ``BELOW_NATURAL`` halvings below
the scene's natural step (``natural_dt``, :func:`dda.penalty_advice.natural_step`; there the
lightest block's inertia is 4**8 times the stiffest spring, and contacts that do not settle
will not settle at any dt). A try that fails below that many halvings of the step asked
for, reached through accepted steps in between, ends the run too. A static analysis at 1 s
a step whose light bar a bolt of 40 kN pretension pulls against a post from a 0.1 mm gap
(``tests/test_step_control.py``) has a natural step of 3.3e-5 s: its first step settles at
2.4e-4 s, after 12 cuts, and the run then grows its steps back to 1 s; a limit of 12 counted
from 1 s stopped it there.

A doubled step size that is cut again for its contacts (OPEN-CLOSE or Newton did not settle)
before it has made ``grow_after`` steps doubles the wait before the next try (up to
``max_wait`` steps); one that holds for ``grow_after`` steps resets it. Cuts for a block that
moved too far do not: those end when the block slows down. Without this back-off a run whose
contacts cannot settle at twice its step size spends a cut every ``grow_after + 1`` steps
trying (the 311-block cut slope of ``examples/jointed_slope.py``: 10% of its steps, each a
failed step of up to ``max_open_close`` passes).

The control remembers the size whose try failed (``ceiling``): the long wait holds only the
tries at that size or above. A step cut at the working size (a hard step, not a try) grows back
to it after ``grow_after`` steps, and holding there says nothing about the size above, so it
neither resets the wait nor lets the next try come early. With one wait for every size, the
cut slope, its steps at 1.25e-4 s and its tries at 2.5e-4 s failing, dropped to 6.25e-5 s on a
hard step, waited the long wait to get back, held, reset the wait, and tried 2.5e-4 s again
``grow_after`` steps later: 44 of its 86 cuts in 0.3 s were such tries (legacy).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dda.errors import SimulationError
from dda.penalty_advice import contact_cut

__all__ = ["StepControl"]

#: the halvings below the natural step a step may be cut to (see :meth:`StepControl.cut_limit`)
BELOW_NATURAL = 8
#: a cut try whose untracked penetration is still above this share of the try before's has
#: not been helped by the smaller step (see :meth:`StepControl.check_can_go_on`)
STALLED = 0.9


@dataclass
class StepControl:
    """Adaptive step size of a run (see the module docstring).

    Parameters
    ----------
    dt : the step size asked for (s)
    max_cuts : cuts of one step in a row before the run stops
    grow_after : accepted steps in a row after which a cut step size doubles
    max_widenings : retries of one step with a wider search before dt is cut instead
    max_wait : the longest wait (accepted steps) before a cut step size is tried doubled again
    natural_dt : the scene's natural step (s; :func:`dda.penalty_advice.natural_step`, 0:
        none): a step may be cut down to ``BELOW_NATURAL`` halvings below it
    """

    dt: float
    max_cuts: int = 12
    grow_after: int = 8
    max_widenings: int = 2
    max_wait: int = 256
    natural_dt: float = 0.0
    # what the control has seen so far
    dt_now: float | None = None
    good_steps: int = 0
    search_hint: float = 0.0
    steps: int = 0  # accepted steps
    contact_cuts: int = 0  # steps cut because the contacts would not settle
    wait: int = 0  # accepted steps before the next doubling (0: grow_after)
    probing: bool = False  # the step size was just doubled and has not held yet
    # the smallest step size whose try failed for its contacts since a try there last held
    # (0: none); the wait holds the tries at it and above
    ceiling: float = 0.0
    # the untracked penetration (tolerances) of this step's last refused try (-1: none yet)
    tried_untracked: float = -1.0
    # accepted steps before a slip reversal is located again (dda.slip_events)
    reversal_wait: int = 0

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
        if self.probing and contact_cut(reason):
            # the contacts did not settle at the doubled size: wait longer before the next try
            self.wait = min(self.max_wait, 2 * self._wait())
            self.ceiling = dt if self.ceiling == 0.0 else min(self.ceiling, dt)
        self.probing = False
        self.dt_now = dt / 2.0
        self.good_steps = 0

    def accepted(self) -> None:
        """After an accepted step: forget the hint, grow a cut step size back when due."""
        self.search_hint = 0.0
        self.tried_untracked = -1.0
        self.steps += 1
        self.good_steps += 1
        if self.reversal_wait > 0:
            self.reversal_wait -= 1
        if self.probing and self.good_steps >= self.grow_after:  # the doubled size held
            self.probing = False
            if not self._below_ceiling(self.dt_now):
                self.wait = self.grow_after
                self.ceiling = 0.0
        if self.dt_now < self.dt and self.good_steps >= self._wait(2.0 * self.dt_now):
            self.dt_now = min(self.dt, 2.0 * self.dt_now)
            self.good_steps = 0
            self.probing = True

    def _wait(self, size: float | None = None) -> int:
        """Accepted steps before a try at ``size`` (default: at or above the ceiling)."""
        if size is not None and self._below_ceiling(size):
            return self.grow_after  # below the size that failed: back to the working size
        return max(self.wait, self.grow_after)

    def _below_ceiling(self, size: float) -> bool:
        """Whether ``size`` is below the remembered failed size (False when there is none)."""
        return self.ceiling > 0.0 and size < self.ceiling * (1.0 - 1e-9)

    def cut_limit(self) -> int:
        """Cuts of one step in a row before the run stops: ``max_cuts``, or those that halve
        ``dt`` to ``BELOW_NATURAL`` halvings below the natural step if that takes more (a
        step asked far above it is cut that far before its contacts' failing to settle says
        anything)."""
        if self.natural_dt <= 0.0 or self.dt <= self.natural_dt:
            return self.max_cuts
        return max(self.max_cuts,
                   math.ceil(math.log2(self.dt / self.natural_dt)) + BELOW_NATURAL)

    def check_can_go_on(self, report, tries: int, dt: float, committed,
                        soft_advice=None, short_step: bool = False) -> None:
        """After a cut: raise :class:`dda.SimulationError` when cutting dt further cannot
        help (``tries`` cuts of this step, the last at ``dt``, from the ``committed``
        state). ``soft_advice`` (optional, a callable) says whether the committed state's
        contact springs sink too deep (:meth:`dda.penalty_advice.PenaltyAdvisor.soft_advice`):
        an untracked penetration beside springs that sink by a large share of a block is the
        penalty's doing, not detection's. ``short_step``: the step's first try was shorter
        than the working size (the run's end was near), and the floor below the size asked
        for does not apply to it (its cuts count as ever)."""
        time = committed.time
        before = getattr(self, "tried_untracked", -1.0)  # (a checkpoint from before it)
        self.tried_untracked = report.untracked
        held = getattr(report, "untracked_held", False)
        stalled = before > 0.0 and report.untracked > STALLED * before
        if report.untracked > 1.0 and committed.untracked > 0.5 and (stalled or not held):
            # the vertex is already half the tolerance in, untracked, at the start of the
            # step: with no closed contact holding it, any step that moves it on is refused
            # and smaller ones only creep. One that a contact holds takes up the start's
            # depth in its spring, and leaves untracked only what its linear gap misses of
            # the step's own turning and sliding, which a smaller step shrinks (columns
            # toppling in a static analysis at 0.2 s a step): it is cut until a smaller step
            # leaves it as deep
            halved = (f", and halving dt left it {report.untracked:.2g} deep ({before:.2g} "
                      "before)" if held else "")
            soft = soft_advice() if soft_advice is not None else None
            why = ("contact detection missed it: please report the scene" if soft is None
                   else f"the penalty is the cause: {soft}")
            raise SimulationError(
                f"the run cannot go on at t = {time:.6g} s: {report.reason}; it was already "
                f"{committed.untracked:.2g} tolerances deep, untracked, at the start of "
                f"the step{halved}, so a smaller dt cannot help ({why})"
            )
        floor = self.dt * 2.0 ** -self.cut_limit()
        # a try below the floor, reached through steps taken in between, fails at any dt (a
        # friction law whose slip branch is wrong let Newton-Raphson take steps of 7e-15 s,
        # where nothing slips, and fail every try above)
        below = dt < floor * (1.0 - 1e-9) and not short_step
        if tries > self.cut_limit() or below:
            soft = (soft_advice() if soft_advice is not None
                    and report.reason.startswith("untracked penetration") else None)
            how = (f"step cut {tries} times down to dt = {dt:.3g} s" if tries > self.cut_limit()
                   else f"a step of {dt:.3g} s failed, below the smallest a step is cut to, "
                        f"{floor:.3g} s: dt / 2^{self.cut_limit()}")
            raise SimulationError(
                f"the run cannot go on at t = {time:.6g} s: {report.reason} ({how}"
                + ("" if soft is None else f"; the penalty is the likely cause: {soft}") + ")"
            )
