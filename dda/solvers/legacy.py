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

from dda.contact.contacts import OPEN
from dda.solvers.base import NonlinearSolver, StepProblem, StepSolution
from dda.solvers.open_close import open_close

__all__ = ["LegacyPullBack"]


class LegacyPullBack(NonlinearSolver):
    """Legacy DDA: OPEN-CLOSE iteration and explicit pull-back of the excess friction.

    Examples
    --------
    >>> from dda.solvers import LegacyPullBack
    >>> LegacyPullBack()
    LegacyPullBack()
    """

    name = "legacy"
    # explicit friction: the error is first order in dt (dda.auto_settings has the numbers)
    auto_steps_per_period = 700

    def solve_step(self, problem: StepProblem) -> StepSolution:
        el = problem.element
        oc = open_close(problem, explicit=True)
        if not oc.converged:
            return StepSolution(None, None, False, oc.passes, oc.passes, oc.reason)
        if len(el) == 0:
            return StepSolution(oc.d, el.contacts, True, oc.passes, oc.passes)
        state, gap, dgs, history, d = oc.state, oc.gap, oc.dgs, oc.history, oc.d
        t_n = np.where(state != OPEN, np.minimum(el.normal_penalty * gap, 0.0), 0.0)
        t_s, new_history = el.legacy_trial(history, dgs, t_n, state)
        trial = el.trial_contacts(state, t_n, t_s, new_history)
        return StepSolution(d, trial, True, oc.passes, oc.passes)
