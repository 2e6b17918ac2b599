"""Original DDA's way to finish a step: OPEN-CLOSE, then explicit pull-back (METHOD.md s. 5).

1. Pull-back: at the start of the step every closed contact goes through its friction law's
   return map with no new displacement, at the committed normal force. A shear force that the
   last step left above the strength is cut back to it here, and the contact slides in this
   step; the cut is an unbalanced force that this step's solve redistributes.
2. OPEN-CLOSE: solve with the current contact states, re-check each contact (open when its
   gap is positive at the end of the step, stick or slip from the trial shear force of a sliding
   contact), change the springs and solve again until no state changes. A contact that sticks
   keeps its spring for the whole step even when the spring's force ends above the strength:
   that overshoot is what original DDA does and what step 1 of the next step corrects.
   A contact that closes during the step has no committed shear force to carry over: it gets
   the friction check in every pass (as in Shi's OPEN-CLOSE), so a vertex that lands while
   sliding is not locked at once.
   When a pass brings back a state already tried (a block bouncing off a stiff contact and
   falling back into it), only the most violated contact is switched in that pass.

Sliding contacts carry the friction force of the previous pass's normal force as a load (no
slip tangent, no geometric stiffness): the material stick terms of the linearization only. The
passes go on until that lagged normal force agrees with the pass's own within 1%, so the
friction of a converged step never exceeds mu |t_n| by more than that.
"""

from __future__ import annotations

import numpy as np

from dda.contact.contacts import OPEN, SLIP, STICK, ContactSet
from dda.solvers.base import NonlinearSolver, StepProblem, StepSolution
from dda.solvers.linear import SingularSystemError, assemble_and_solve

__all__ = ["LegacyPullBack"]

# relative change of a sliding contact's normal force between passes that ends OPEN-CLOSE
NORMAL_FORCE_RTOL = 0.01


class LegacyPullBack(NonlinearSolver):
    """Legacy DDA: OPEN-CLOSE iteration and explicit pull-back of the excess friction.

    Examples
    --------
    >>> from dda.solvers import LegacyPullBack
    >>> LegacyPullBack()
    LegacyPullBack()
    """

    name = "legacy"

    def solve_step(self, problem: StepProblem) -> StepSolution:
        el = problem.element
        c = el.contacts
        m = len(el)
        pn, ps, lc = el.normal_penalty, el.shear_penalty, el.length
        laws = el.laws
        closed0 = c.state != OPEN
        zero = np.zeros(m)
        # 1. pull-back of last step's overshoot
        _, over, history = laws.return_map(c.history, zero, c.t_n, ps, lc, where=closed0)
        state = c.state.copy()
        state[closed0 & over] = SLIP
        t_n_lag = c.t_n.copy()
        dgs_prev = zero
        passes = 0
        d = gap = dgs = None
        seen = {state.tobytes()}
        for passes in range(1, problem.max_open_close + 1):
            slip = state == SLIP
            t_slip, _, _ = laws.return_map(history, dgs_prev, t_n_lag, ps, lc, where=slip)
            k, f = el.legacy_contributions(state, history["g_se"], t_slip)
            try:
                d = assemble_and_solve(problem.block_k, problem.block_f, problem.free, el.bj,
                                       el.bk, k, f, problem.d_known)
            except SingularSystemError as exc:
                return StepSolution(None, None, False, passes, passes, f"singular system: {exc}")
            gap, dgs = el.linear_gaps(d)
            closed = gap < 0.0
            t_n = np.where(closed, pn * gap, 0.0)
            new_state = np.where(closed, state, OPEN).astype(np.int8)
            # friction check of sliding contacts and of contacts closing in this step
            check = closed & ((state == SLIP) | ~closed0)
            t_trial, slipping, _ = laws.return_map(history, dgs, t_n, ps, lc, where=check)
            # a slip that reverses against the friction load of this pass sticks
            reversed_ = (state == SLIP) & (np.sign(t_trial) != np.sign(t_slip))
            new_state[check] = np.where(slipping[check] & ~reversed_[check], SLIP, STICK)
            # a sliding contact's friction came from the last pass's normal force: the pass
            # only counts when that force is the one this pass ended with
            lag_ok = np.abs(t_n - t_n_lag) <= NORMAL_FORCE_RTOL * np.maximum(
                np.abs(t_n), np.abs(t_n_lag))
            if np.array_equal(new_state, state) and np.all(lag_ok | (state != SLIP)):
                break
            key = new_state.tobytes()
            if key in seen and not np.array_equal(new_state, state):
                new_state = _single_switch(state, new_state, gap)
            seen.add(new_state.tobytes())
            state, t_n_lag, dgs_prev = new_state, t_n, dgs
        else:
            return StepSolution(None, None, False, passes, passes,
                                f"OPEN-CLOSE did not settle in {passes} passes")

        closed = state != OPEN
        t_n = np.where(closed, pn * gap, 0.0)
        stick = state == STICK
        slip = state == SLIP
        new_history = laws.elastic_update(history, dgs, stick)
        t_s_slip, _, slip_history = laws.return_map(history, dgs, t_n, ps, lc, where=slip)
        for key, v in slip_history.items():
            new_history[key][slip] = v[slip]
        t_s = np.where(stick, ps * new_history["g_se"], 0.0) + np.where(slip, t_s_slip, 0.0)
        laws.initial_history(new_history, ~closed)
        trial = ContactSet(c.vertex, c.edge, c.bj, c.bk, state, c.xi0.copy(), t_n, t_s,
                           new_history)
        return StepSolution(d, trial, True, passes, passes)


def _single_switch(state, proposed, gap):
    """Break an OPEN-CLOSE cycle: change only the contact whose gap is the most violated.

    When switching every inconsistent contact at once brings back a state already tried (a
    block that bounces off a stiff contact and falls back into it), changing one contact at a
    time is an active-set step that does not cycle.
    """
    changed = np.flatnonzero(proposed != state)
    opening = proposed[changed] == OPEN
    closing = state[changed] == OPEN
    violation = np.where(opening, gap[changed], 0.0) + np.where(closing, -gap[changed], 0.0)
    violation = np.where(opening | closing, violation, 0.0)
    pick = changed[int(np.argmax(violation))]
    out = state.copy()
    out[pick] = proposed[pick]
    return out
