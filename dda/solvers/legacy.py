"""Original DDA's way to finish a step: OPEN-CLOSE, then explicit pull-back (METHOD.md s. 5).

The step ends when the OPEN-CLOSE iteration (:mod:`dda.solvers.open_close`, explicit flavour)
has settled: a contact that sticks keeps its spring for the whole step even when the spring's
force ends above the strength. That overshoot is what original DDA does; the next step starts
by pulling it back to the strength, and the cut is an unbalanced force that that step's solve
redistributes. Sliding contacts carry the friction of the previous pass's normal force as a
load: the material stick terms of the linearization only, no slip tangent, no geometric terms.
"""

from __future__ import annotations

import numpy as np

from dda.contact.contacts import OPEN, ContactSet
from dda.kernels.dense_passes import CONVERGED, legacy_dense_step
from dda.kernels.open_close import as_float64, kernel_history, kernel_history_dict, legacy_end
from dda.profiling import count_solve, section
from dda.solvers import open_close as oc_rules
from dda.solvers.base import NonlinearSolver, StepProblem, StepSolution
from dda.solvers.open_close import (
    cycle_measure,
    cycle_memory,
    dense_arguments,
    dense_eligible,
    dense_failure,
    local_cycle_limit,
    open_close,
    own_cycle_measures,
    pass_rules,
    round_off_gap,
)

__all__ = ["LegacyPullBack"]

LEGACY_DENSE_STEP = True
"""Whether a step whose OPEN-CLOSE takes the dense kernel
(:func:`dda.solvers.open_close.dense_eligible`) runs its pull-back, passes and end in one
kernel call (:func:`dda.kernels.dense_passes.legacy_dense_step`); False: the passes' kernel
between the start's and the end's."""


class LegacyPullBack(NonlinearSolver):
    """Legacy DDA: OPEN-CLOSE iteration and explicit pull-back of the excess friction.

    Parameters
    ----------
    cycle_local : bool or None
        Measure OPEN-CLOSE's cycle rule on every contact's own blocks: a contact that cycles
        between open and closed is held closed while it pulls by at most ``CYCLE_TENSION``
        of the largest normal force on either of its blocks (the smaller), as the fully
        implicit method's iterations do (they take the shear forces too), instead of the
        largest
        normal force in its group of free blocks that touch each other through closed
        contacts (False; where all touch, the scene's largest) for the contacts that the
        memory below does not measure on their own blocks. On the shaken cut slope it costs
        2 to 3 times the steps of the default, most with cohesive joints
        (:mod:`dda.solvers.open_close` has the numbers). None (the default):
        :data:`dda.solvers.open_close.CYCLE_LOCAL` (False), read at each step.
    cycle_memory : int or None
        Under the group's measure, the steps for which a contact that ended a step held by
        the cycle rule is measured on its own blocks all the same: a hold that comes back
        step after step is what hangs a light block on a heavy one it touches (on a heavy
        free incline the block moves 30.4 mm in 0.3 s with the default 8, 5.0 mm with 0;
        Newton 31.1), a hold that does not is a pass's noise. 0: never. None (the
        default): :data:`dda.solvers.open_close.CYCLE_MEMORY` (8), read at each step.

    Examples
    --------
    >>> from dda.solvers import LegacyPullBack
    >>> LegacyPullBack()
    LegacyPullBack()
    >>> LegacyPullBack(cycle_local=True)
    LegacyPullBack(cycle_local=True)
    >>> LegacyPullBack(cycle_memory=0)
    LegacyPullBack(cycle_memory=0)
    """

    name = "legacy"
    # explicit friction: the error is first order in dt (dda.auto_settings has the numbers)
    auto_steps_per_period = 400
    # its onset of slip lags by up to a step: where the strength drops at onset, the slide
    # lost grows with the drop (dda.auto_settings, rule 1)
    auto_steps_per_drop = 4100.0
    # stiffer stick springs gain it nothing: its explicit friction's error stays (rule 2)
    auto_kappa = 3.0
    # (a subclass's own __init__ need not set it)
    cycle_local = None
    cycle_memory = None

    def __init__(self, cycle_local: bool | None = None, cycle_memory: int | None = None):
        if cycle_local is not None and not isinstance(cycle_local, bool | np.bool_):
            raise TypeError("LegacyPullBack: cycle_local must be True, False or None, got "
                            f"{cycle_local!r}")
        if cycle_memory is not None and (isinstance(cycle_memory, bool | np.bool_)
                                         or not isinstance(cycle_memory, int | np.integer)):
            raise TypeError("LegacyPullBack: cycle_memory must be a whole number of steps or "
                            f"None, got {cycle_memory!r}")
        if cycle_memory is not None and cycle_memory < 0:
            raise ValueError(f"LegacyPullBack: cycle_memory must be 0 or more steps, got "
                             f"{cycle_memory}")
        self.cycle_local = None if cycle_local is None else bool(cycle_local)
        self.cycle_memory = None if cycle_memory is None else int(cycle_memory)

    def __repr__(self):
        extra = []
        if self.cycle_local is not None:
            extra.append(f"cycle_local={self.cycle_local}")
        if self.cycle_memory is not None:
            extra.append(f"cycle_memory={self.cycle_memory}")
        return f"LegacyPullBack({', '.join(extra)})"

    def solve_step(self, problem: StepProblem) -> StepSolution:
        el = problem.element
        if LEGACY_DENSE_STEP and dense_eligible(problem):
            return _dense_step(problem, cycle_measure(self), cycle_memory(self))
        oc = open_close(problem, explicit=True, cycle_local=local_cycle_limit(self),
                        cycle_memory=cycle_memory(self))
        if not oc.converged:
            return StepSolution(None, None, False, oc.passes, oc.passes, oc.reason)
        if len(el) == 0:
            return StepSolution(oc.d, el.contacts, True, oc.passes, oc.passes)
        state, gap, dgs, history, d = oc.state, oc.gap, oc.dgs, oc.history, oc.d
        if el.kernel_laws is not None:
            return StepSolution(d, _compiled_trial(el, state, gap, dgs, history), True,
                                oc.passes, oc.passes)
        # the friction sees the spring's and an impact dashpot's normal force; the contacts
        # keep the spring's
        t_n = np.where(state != OPEN, np.minimum(el.judge_stiffness * el.judged_gap(gap),
                                                 0.0), 0.0)
        t_s, new_history = el.legacy_trial(history, dgs, t_n, state)
        trial = el.trial_contacts(state, el.spring_force(state != OPEN, gap, t_n), t_s,
                                 new_history)
        return StepSolution(d, trial, True, oc.passes, oc.passes)



def _compiled_trial(el, state, gap, dgs, history) -> ContactSet:
    """The step's trial contacts from the built-in laws' kernel
    (:func:`dda.kernels.open_close.legacy_end`: the same as ``legacy_trial`` and
    ``trial_contacts``)."""
    with section("return_map"):
        t_n, t_s, g_se, slip, sliding = legacy_end(
            state, as_float64(el.judged_gap(gap)), as_float64(dgs), *el.kernel_laws,
            *kernel_history(history, len(el)), as_float64(el.judge_stiffness),
            as_float64(el.shear_penalty), as_float64(el.length))
    c = el.contacts
    return ContactSet(c.vertex, c.edge, c.bj, c.bk, state, c.xi0.copy(),
                      el.spring_force(state != OPEN, gap, t_n), t_s,
                      kernel_history_dict(history, g_se, slip, sliding), c.held_ago)


def _dense_step(problem: StepProblem, measure: int, memory: int) -> StepSolution:
    """:meth:`LegacyPullBack.solve_step` on a dense system with the built-in laws: the
    pull-back, every OPEN-CLOSE pass and the step's end in one kernel call (the same
    decisions and numbers as the passes' kernel between the start's and the end's). Its time
    is the step profile's ``solve``."""
    el = problem.element
    c = el.contacts
    with section("solve"):
        status, passes, d, state, t_n, t_s, g_se, slip, sliding = legacy_dense_step(
            problem.max_open_close, float(oc_rules.SETTLE_BAND), *pass_rules(),
            oc_rules.LAG_SECANT_FROM, int(measure),
            own_cycle_measures(c, measure, memory), as_float64(np.abs(c.t_s)),
            *dense_arguments(problem), np.asarray(c.state, dtype=np.int8),
            *kernel_history(c.history, len(el)), as_float64(c.t_n), round_off_gap(el))
    count_solve(passes)
    if status != CONVERGED:
        return StepSolution(None, None, False, passes, passes, dense_failure(status, passes))
    trial = ContactSet(c.vertex, c.edge, c.bj, c.bk, state, c.xi0.copy(), t_n, t_s,
                       kernel_history_dict(c.history, g_se, slip, sliding), c.held_ago)
    return StepSolution(d, trial, True, passes, passes)
