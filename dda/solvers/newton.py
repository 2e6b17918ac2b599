"""The fully implicit DDA step: OPEN-CLOSE, then Newton-Raphson (METHOD.md section 5, H Fig 5).

After the OPEN-CLOSE iteration has found the contact states, Newton iterations solve the
nonlinear balance of the step

    R(d) = K~ d - F~ + sum_c [t_n E^T + t_s I^T](d) + sum_b [K_b d - f_b] = 0

(the last sum: the bolts between two free blocks, linear in the step, :mod:`dda.bolts`; an
anchored bolt is in ``K~`` and ``F~``) with the contact forces evaluated exactly at every
trial state (gaps from the moved geometry, shear force from the friction law's return map
built from the committed history) and the
consistent tangent of :meth:`dda.contact.ContactElement.response` (geometric terms and the
unsymmetric slip coupling included), until the out-of-balance force is below ``tol`` times the
size of the forces in play (or has reached the round-off floor of a stiff penalty system:
below 1e-6 of the forces and no longer decreasing). Converged: quadratic. Not converged in
``max_iter``: the step is reported failed and the simulation retries it with a smaller dt.

The return map has kinks (a contact that opens, a sliding contact whose trial force changes
sign), and full Newton steps can jump back and forth across one for ever. A step that brings
the contacts back to the states (and sliding directions) of two to ``CYCLE_LENGTH`` steps
before without halving the residual since then is halved, up to ``LINE_SEARCH_HALVINGS``
times, before the next step is taken. A contact that slides the other way than at the iterate
before takes the next step on its stick branch (``REVERSED_STICK``): a sliding contact's
tangent has no shear stiffness, and full steps jumped across a narrow stick band for ever.

A contact that has opened or closed ``HOLD_AFTER_FLIPS`` times in the step's iterates and
would open again is held closed (``HOLD_CYCLING``) while the pull of its spring stays within
OPEN-CLOSE's ``CYCLE_TENSION`` of the largest contact force on its own blocks,

    p_n g_n <= CYCLE_TENSION min(F_j, F_k),   F_b = max over b's contacts of |(t_n, t_s)|

(a block whose motion is known does not count), and let go once it pulls harder. Such a
contact has no consistent state: closed, the iterate opens it; open, its block falls back
in. A cohesive joint is where this happens most: its strength ``c l`` needs no normal force
and is gone once the contact opens, so a contact that carries a shear force near ``c l`` at
a normal force near zero is switched iterate after iterate (:data:`HOLD_CYCLING` has the
numbers). Held, it carries a small tension in the step's balance; the normal force it
commits is the spring's compression only (``min(p_n g_n, 0)``, as legacy DDA's held contacts
commit).

Later iterations whose contacts keep their states (but for ``NEAR_SWITCHES``) solve by GMRES
preconditioned with the last factorization of the tangent
(:meth:`dda.solvers.sparse_factor.SparseFactor.solve_near`) instead of factorizing again.
On a dense system with the built-in laws every iteration runs in one kernel call
(:mod:`dda.kernels.dense_newton`, ``DENSE_NEWTON``): the same rules, the numbers to round-off.
"""

from __future__ import annotations

import math

import numpy as np

from dda._checks import finite_number
from dda.contact.contacts import OPEN, SLIP, STICK
from dda.kernels.assembly import newton_residuals
from dda.kernels.dense_newton import CONVERGED as DENSE_CONVERGED
from dda.kernels.dense_newton import (
    DIVERGED,
    NOT_CONVERGED,
    NOT_FINITE,
    SINGULAR,
    STALLED,
    dense_newton,
    newton_dense_step,
    penalty_round_off,
    round_off_floor,
    stalled,
)
from dda.kernels.dense_passes import NOT_SETTLED
from dda.kernels.open_close import as_float64, kernel_history, kernel_history_dict
from dda.profiling import count_solve, section
from dda.solvers.base import NonlinearSolver, StepProblem, StepSolution
from dda.solvers.linear import DENSE_LIMIT, SingularSystemError, assemble_and_solve, assemble_vector
from dda.solvers.open_close import (
    CYCLE_TENSION,
    _largest_on_blocks,
    dense_arguments,
    dense_eligible,
    dense_failure,
    dense_layout,
    open_close,
    pass_rules,
    predictor_patience,
    round_off_gap,
)

__all__ = ["NewtonRaphson"]

# residuals below this fraction of the forces that stop decreasing are round-off
ROUND_OFF = 1e-6
# Newton iterations from the predictor that settled open and closed only, before the stick and
# slip states are settled too (it converges in 1-3 where it converges: 60 x 60 stack of
# benchmarks/stacks.py; one step in four there ran all 25 and failed before the retry)
PREDICTOR_ITERATIONS = 6
# ... and gives up on them (for the predictor that settles stick and slip too) once two iterates
# in a row have not shrunk |R| below this fraction of the one before (iterate's contraction):
# on the 60 x 60 stack the iterations that converge from the looser predictor shrink |R| 30 to
# 700 times in their first step (31.7 -> 0.043 N, 9.29 -> 0.31 N), those that do not hardly
# (197 -> 75 -> 85 -> 91 ... N, 1,150 -> 1,140 -> ... N: six iterations, each a factorization
# of the tangent, before the retry); one iterate whose |R| grows is how Newton crosses a change
# of the contacts' states (a block striking a stopper: 1,800 -> 4,510 -> 6e-8 N). Four runs of
# 30 steps: the mean step 455 / 511 / 520 / 543 -> 429 / 483 / 461 / 517 ms, the median step
# within the runs' spread (benchmarks/README.md, issue 19's nineteenth part)
PREDICTOR_CONTRACTION = 0.5
# a Newton step that cycles (see iterate) is halved up to this many times (each halving is one
# iteration of the budget): on the 30 x 30 stack of benchmarks/stacks.py two sliding contacts
# whose trial force changed sign at every full step held |R| at 30 N for the predictor's
# iterations and at 450 / 560 N (sliding, open, sliding, ...) for all 25 of the next ones: a
# cut step
LINE_SEARCH_HALVINGS = 4
# a Newton iteration whose contacts' states differ from those of the tangent factorized last
# in this many or fewer is solved by GMRES with that factorization (SparseFactor.solve_near):
# on the 30 x 30 stack of benchmarks/stacks.py GMRES needed 2 iterations with no state
# changed and about one more per changed contact (29 with 53 changed)
NEAR_SWITCHES = 4
# ... and a step that brings back the pattern of up to this many accepted iterates before is
# a cycle: with the impact dashpot (a resting contact lets go close to its own gap, and its
# friction sees the dashpot's force) Newton also cycled through 3 and 4 patterns (|R| 293,
# 220, 270, 135 N, 293, ... on a pile of 1,000 blocks); on three such piles (0.2 s) the
# longer cycles took the cut steps from 67 / 65 / 58 to 30 / 32 / 40
CYCLE_LENGTH = 8
# whether the predictor's passes may solve by a low-rank update of the last factorization
# (dda.solvers.sparse_factor.LOW_RANK_TERMS). On the 60 x 60 stack of benchmarks/stacks.py it
# first took 4 of 7 runs (gravity changed by 0 to 6e-12) to a cut step, none without it (a
# friction-settled predictor in which one contact switched between stick and slip in every
# pass until the limit); with the retry's patience (open_close.RETRY_PATIENCE) none cut. Over
# 13 such runs of 30 steps, each with and without it (benchmarks/README.md, issue 19's
# eighteenth and nineteenth parts), the median step took 18 ms (4%) less on average, shorter
# in 10 of the 13, with 0.4-0.7 factorizations a step fewer and no cut
PREDICTOR_LOW_RANK = True
# a Newton correction's linear solve may leave a residual of this fraction of the convergence
# threshold (tol times the forces' scale; an inexact Newton step): the single-precision
# factors' refinement stops there (dda.solvers.sparse_factor) instead of at 1e-12 of the
# solution. 0 (or None): every solve refined in full
INEXACT_FRACTION = 0.1
# a contact that slides at an iterate in the direction opposite to the iterate before's takes
# the next Newton step on its stick branch: its law's elastic force p_s (g_se + dg_s) and
# tangent (k_ss = p_s, k_sn = 0) in place of the return map's. Sliding, its tangent has no
# shear stiffness, so a full step moves its shear gap as if nothing held it; where the step's
# answer sticks with a shear force near zero, inside a band 2 mu t_n / p_s wide (2e-8 m for
# 700 N at 5e10 N/m), the steps jumped across the band from one direction to the other for
# the whole budget (the cut slope of examples/jointed_slope.py at 5e10 N/m: |R| 28, 33, 28,
# ... N, 2e-6 of the forces, and a cut step). The branch's step lands on the answer when it
# sticks, and one iterate further when the contact does slide the other way. Over 10 s of the
# cut slope's shaking the steps cut for Newton fell from 45 to 5 (all cuts 98 -> 89); on the
# 60 x 60 stack of benchmarks/stacks.py 5.80 -> 5.00 passes and 6.63 -> 5.90 factorizations
# a step. Waiting for a second turn: 27 cuts for Newton and 5.43 passes
# (benchmarks/README.md, issue 19's twenty-third part)
REVERSED_STICK = True


class NewtonRaphson(NonlinearSolver):
    """Fully implicit DDA: return mapping and Newton-Raphson with the consistent tangent.

    Parameters
    ----------
    tol : float
        Convergence when ``|R| <= tol * max(|F~|, |contact forces|, |K~ d|)`` over the free
        unknowns (2-norm).
    max_iter : int
        Newton iterations allowed after OPEN-CLOSE before the step is cut.
    unsettled_predictor : bool
        Iterate from an OPEN-CLOSE predictor that did not settle in ``max_open_close``
        passes (from its last pass, ``max_iter`` iterations) instead of cutting the step.
        Newton's iterations judge every contact on the moved geometry, so a step whose
        contacts chatter between passes converges where Newton can; but such a step is one in
        which a contact's period is shorter than dt (an impact inside one step, a penalty
        stiff for its dt), and the cut that resolves it in time is what DDA has always done,
        so it is off by default. Measured on the 311-block cut slope of
        ``examples/jointed_slope.py`` (0.3 s): at its own 5e10 N/m 2,182 steps, 86 cuts and
        66.8 s of CPU -> 1,028 steps, 32 cuts and 55.8 s; under ``"auto"`` penalty and dt
        1,560 steps, 17 cuts and 46.4 s -> 1,274 steps, no cut and 37.1 s; the face blocks'
        median motion 24.9 -> 23.4 mm and 24.3 -> 24.6 mm. But a 0.2 m block striking a
        stopper at 5 m/s (1e9 N/m, restitution 0, dt 1e-3) left it at 2.6 m/s instead of
        1.2 m/s (legacy DDA: 0.45 m/s): the impact was taken in whole steps, where the
        default halved them twice.

    Examples
    --------
    >>> from dda.solvers import NewtonRaphson
    >>> NewtonRaphson(tol=1e-10, max_iter=30)
    NewtonRaphson(tol=1e-10, max_iter=30)
    """

    name = "newton"
    # stiff stick springs give little (the give mu g dt^2 / (2 kappa) would be 1% of the
    # smallest slip the rule serves at 150 steps with kappa 3), so fewer steps a period serve;
    # a strength drop at onset still asks for more (dda.auto_settings, rules 1 and 2)
    auto_steps_per_period = 167
    auto_steps_per_drop = 475.0
    auto_kappa = 10.0
    # the default also for a solver pickled before the setting existed (a checkpoint)
    unsettled_predictor = False

    def __init__(self, tol: float = 1e-9, max_iter: int = 25,
                 unsettled_predictor: bool = False):
        self.tol = finite_number("tol", tol, positive=True, where="NewtonRaphson")
        if int(max_iter) != max_iter or max_iter < 1:
            raise ValueError(f"NewtonRaphson: max_iter must be a positive integer, got {max_iter}")
        self.max_iter = int(max_iter)
        if not isinstance(unsettled_predictor, bool | np.bool_):
            raise TypeError("NewtonRaphson: unsettled_predictor must be True or False, got "
                            f"{unsettled_predictor!r}")
        self.unsettled_predictor = bool(unsettled_predictor)

    def __repr__(self):
        extra = ", unsettled_predictor=True" if self.unsettled_predictor else ""
        return f"NewtonRaphson(tol={self.tol:g}, max_iter={self.max_iter}{extra})"

    def solve_step(self, problem: StepProblem) -> StepSolution:
        if DENSE_NEWTON and NEWTON_DENSE_STEP and dense_eligible(problem):
            return self._dense_step(problem)
        # the predictor: OPEN-CLOSE with the open and closed states settled; only when Newton
        # does not converge from it are the stick and slip states settled too
        passes = 0
        sym = problem.factor(True)
        if sym is not None:
            sym.low_rank = PREDICTOR_LOW_RANK
        for settle_friction in (False, True):
            oc = open_close(problem, explicit=False, settle_friction=settle_friction)
            passes += oc.passes
            if not oc.converged:
                if oc.d is None or not self.unsettled_predictor:  # or a singular system
                    return StepSolution(None, None, False, passes, 0, oc.reason)
                # an OPEN-CLOSE that does not settle is still a predictor: Newton's own
                # contact states decide (settling stick and slip would not settle either)
                sol = self.iterate(problem, oc.d)
                sol.open_close_passes = passes
                if not sol.converged:
                    sol.reason = f"{oc.reason}, and from its last pass {sol.reason}"
                return sol
            if len(problem.element) == 0:  # no contacts: the step is linear, its solve exact
                return StepSolution(oc.d, problem.element.contacts, True, passes, 0)
            # from the looser predictor Newton gets a few iterations only: when it has not
            # converged by then, settling stick and slip first is the cheaper way on
            limit = (None if oc.friction_settled or settle_friction
                     else min(self.max_iter, PREDICTOR_ITERATIONS))
            sol = self.iterate(problem, oc.d, limit, contraction=(
                PREDICTOR_CONTRACTION if limit is not None else 0.0))
            sol.open_close_passes = passes
            if sol.converged or oc.friction_settled:  # settling again would change nothing
                break
        return sol

    def iterate(self, problem: StepProblem, d: np.ndarray,
                max_iter: int | None = None, contraction: float = 0.0) -> StepSolution:
        """Newton-Raphson iterations of one step from the increments ``d`` (n_blocks, 6).

        The known blocks' rows of ``d`` must equal ``problem.d_known``; at most ``max_iter``
        iterations (default: the solver's). With ``contraction`` > 0 the iteration also gives
        up at an iterate that has not converged when neither it nor the iterate before
        brought |R| below that fraction of the one before it (one iterate whose |R| grows is
        how Newton crosses a change of the contacts' states; two that do not shrink it are a
        stall). Returns the converged trial, or a failed solution whose ``residual_norms``
        show what happened.
        """
        max_iter = self.max_iter if max_iter is None else max_iter
        el = problem.element
        free = problem.free
        pattern = problem.pattern
        if (DENSE_NEWTON and pattern.n <= DENSE_LIMIT and pattern.unknowns > 0
                and len(el) and el.kernel_laws is not None and problem.bolts is None):
            return self._dense(problem, d, max_iter, contraction)
        d = d.copy()
        norms: list[float] = []
        factor = problem.factor(False)
        factored = None  # the contact states of the tangent factorized last in this call
        base, step, halvings = None, None, 0  # the last Newton step, from base
        patterns: list[np.ndarray] = []  # the contacts' pattern at each accepted iterate
        force_norm = _norm(problem.block_f[free])
        penalty_floor = _penalty_floor(el)
        held = flips = last_closed = None
        for it in range(max_iter + 1):
            resp = el.response(d, held)
            if HOLD_CYCLING:
                if last_closed is not None:
                    resp, held = _hold_cycling(el, d, resp, held, flips, last_closed, free)
                    flips += resp.closed != last_closed
                else:
                    flips = np.zeros(len(el), dtype=np.int64)
                last_closed = resp.closed
            pair_r = resp.residual
            if problem.bolts is not None:  # the bolts' out-of-balance after the contacts'
                pair_r = np.concatenate([pair_r, problem.bolts.residual(d)])
            block_r, r_free, inertia_free, contact_free = _residuals(problem, d, pair_r)
            norm = _norm(r_free)
            scale = max(force_norm, _norm(inertia_free), _norm(contact_free), 1e-300)
            if (norm <= self.tol * scale
                    or _at_round_off(norms + [norm],
                                     round_off_floor(scale, ROUND_OFF, penalty_floor))
                    or _at_noise_floor(problem, resp, norm, scale)):
                norms.append(norm)
                break
            if len(norms) >= 2 and stalled(norm, norms[-1], norms[-2], contraction):
                norms.append(norm)
                return StepSolution(None, None, False, 0, it, _stalled(norms), norms)
            states = np.where(resp.closed, np.where(resp.slipping, SLIP, STICK), OPEN)
            # the contacts' states, and the direction of the sliding ones: Newton's full steps
            # can jump back and forth across the kinks of the return map (where a contact
            # opens, or a sliding one's trial force changes sign) for ever. A step that
            # brings back the pattern of two to CYCLE_LENGTH steps before without halving |R|
            # since then is halved (up to LINE_SEARCH_HALVINGS times) before the next one is
            # taken
            pattern = np.where(states == SLIP, 2 * np.sign(resp.t_s), states).astype(np.int8)
            back = _seen_at(pattern, patterns)
            if (base is not None and halvings < LINE_SEARCH_HALVINGS and it < max_iter
                    and back is not None and norm > 0.5 * norms[back]):
                halvings += 1
                d = base + 0.5 ** halvings * step
                continue
            norms.append(norm)
            patterns.append(pattern)
            if not math.isfinite(norm):
                return StepSolution(None, None, False, 0, it,
                                    "Newton-Raphson diverged (non-finite residual)", norms)
            if it == max_iter:
                return StepSolution(None, None, False, 0, it, (
                    f"Newton-Raphson did not converge in {max_iter} iterations "
                    f"(|R| = {norm:.3g}, {norm / scale:.3g} of the forces)"), norms)
            # a contact whose sliding direction turned takes this step on its stick branch
            # (REVERSED_STICK)
            turned = _reversed(patterns) if REVERSED_STICK else None
            if turned is not None:
                states = np.where(turned, STICK, states)
            # a tangent whose contacts are in the states of the one factorized last, but for
            # a few, differs from it by little (the geometric terms, the slip coupling's
            # direction, a low-rank change): GMRES with that factorization solves it in a
            # few iterations
            near = (factored is not None
                    and np.count_nonzero(states != factored) <= NEAR_SWITCHES)
            done = factor.factorizations if factor is not None else 0
            try:
                if turned is None:
                    tangent = resp.stiffness
                else:
                    tangent, pair_r = resp.stick_branch(turned)
                    if problem.bolts is not None:
                        pair_r = np.concatenate([pair_r, problem.bolts.residual(d)])
                if problem.bolts is not None:
                    tangent = problem.with_bolts(tangent, resp.residual)[0]
                step = assemble_and_solve(problem.block_k, -block_r, free,
                                          *problem.pair_blocks, tangent, -pair_r,
                                          np.zeros_like(problem.d_known),
                                          problem.pattern, factor=factor, near=near,
                                          atol=(INEXACT_FRACTION * self.tol * scale
                                                if INEXACT_FRACTION else None))
            except SingularSystemError as exc:
                return StepSolution(None, None, False, 0, it, f"singular tangent: {exc}", norms)
            if factor is not None and factor.factorizations != done:
                factored = states
            base, halvings = d, 0
            d = d + step
        state = np.where(resp.closed, np.where(resp.slipping, SLIP, STICK), OPEN).astype(np.int8)
        trial = el.trial_contacts(state, resp.t_n, resp.t_s, resp.history)
        return StepSolution(d, trial, True, 0, it, "", norms)

    def _dense(self, problem: StepProblem, d: np.ndarray, max_iter: int,
               contraction: float = 0.0) -> StepSolution:
        """:meth:`iterate` on a dense system with the built-in laws: every iteration in one
        kernel call (:func:`dda.kernels.dense_newton.dense_newton`; the same decisions, the
        numbers to round-off). Its time is the step profile's ``solve``."""
        el, pattern = problem.element, problem.pattern
        g = el.geometry
        rigid = problem.rigid if problem.rigid is not None else np.zeros(len(problem.free))
        dashpot = el.dashpot is not None
        g_se, slip, sliding = kernel_history(el.contacts.history, len(el))
        with section("solve"):
            (status, it, d, norms, scale, closed, slipping, spring, t_s, g_se, slip,
             sliding) = dense_newton(
                as_float64(d), max_iter, float(self.tol), ROUND_OFF, LINE_SEARCH_HALVINGS,
                CYCLE_LENGTH, bool(REVERSED_STICK), float(contraction), *_hold_rule(),
                as_float64(problem.block_k),
                as_float64(problem.block_f), np.asarray(problem.free, dtype=np.bool_),
                np.asarray(rigid, dtype=np.bool_),
                *dense_layout(pattern), np.asarray(el.bj, dtype=np.int64),
                np.asarray(el.bk, dtype=np.int64), *(as_float64(a) for a in (
                    g.p1, g.p2, g.p3, *el.maps, el.contacts.xi0, el.shear0, el.release)),
                dashpot, as_float64(el.judge_stiffness), as_float64(el.normal_penalty),
                as_float64(el.shear_penalty), as_float64(el.length), *el.kernel_laws, g_se,
                slip, sliding, bool(NOISE_FLOOR), as_float64(round_off_gap(el)))
        # a solve for every accepted iterate but the last, and for the last when it failed
        count_solve(len(norms) - 1 + (status in (SINGULAR, NOT_FINITE)))
        return _solution(el, status, it, d, norms, scale, closed, slipping, spring, t_s,
                         (g_se, slip, sliding))

    def _dense_step(self, problem: StepProblem) -> StepSolution:
        """:meth:`solve_step` on a dense system with the built-in laws: the predictor's start
        and passes and Newton's iterations in one kernel call
        (:func:`dda.kernels.dense_newton.newton_dense_step`; the same decisions and numbers
        as :func:`dda.solvers.open_close.open_close`'s dense kernel and :meth:`_dense` in
        turn). Its time is the step profile's ``solve``."""
        el = problem.element
        c, g = el.contacts, el.geometry
        rigid = problem.rigid if problem.rigid is not None else np.zeros(len(problem.free))
        with section("solve"):
            (oc_status, oc_passes, passes, status, it, d, norms, scale, closed, slipping,
             spring, t_s, g_se, slip, sliding, solves) = newton_dense_step(
                problem.max_open_close, *pass_rules(), predictor_patience(False, True),
                self.unsettled_predictor, self.max_iter, PREDICTOR_ITERATIONS,
                float(PREDICTOR_CONTRACTION), float(self.tol), ROUND_OFF, LINE_SEARCH_HALVINGS,
                CYCLE_LENGTH, bool(REVERSED_STICK), *_hold_rule(), *dense_arguments(problem),
                np.asarray(c.state, dtype=np.int8),
                *kernel_history(c.history, len(el)), as_float64(c.t_n), round_off_gap(el),
                np.asarray(rigid, dtype=np.bool_), *(as_float64(a) for a in (
                    g.p1, g.p2, g.p3, *el.maps, c.xi0, el.shear0)), bool(NOISE_FLOOR))
        count_solve(solves)
        unsettled = oc_status == NOT_SETTLED and self.unsettled_predictor
        if oc_status != DENSE_CONVERGED and not unsettled:
            return StepSolution(None, None, False, passes, 0,
                                dense_failure(oc_status, oc_passes))
        sol = _solution(el, status, it, d, norms, scale, closed, slipping, spring, t_s,
                        (g_se, slip, sliding))
        sol.open_close_passes = passes
        if unsettled and not sol.converged:
            sol.reason = (f"{dense_failure(oc_status, oc_passes)}, and from its last pass "
                          f"{sol.reason}")
        return sol


def _solution(el, status, it, d, norms, scale, closed, slipping, spring, t_s,
              history) -> StepSolution:
    """The StepSolution of a dense kernel's Newton iterations (:func:`dense_newton`'s
    results): the trial contacts when converged, else why not."""
    norms = norms.tolist()
    if status == DENSE_CONVERGED:
        state = np.where(closed, np.where(slipping, SLIP, STICK), OPEN).astype(np.int8)
        history = kernel_history_dict(el.contacts.history, *history)
        trial = el.trial_contacts(state, spring, t_s, history)
        return StepSolution(d, trial, True, 0, it, "", norms)
    if status == DIVERGED:
        reason = "Newton-Raphson diverged (non-finite residual)"
    elif status == STALLED:
        reason = _stalled(norms)
    elif status == NOT_CONVERGED:
        reason = (f"Newton-Raphson did not converge in {it} iterations "
                  f"(|R| = {norms[-1]:.3g}, {norms[-1] / scale:.3g} of the forces)")
    else:
        reason = "singular tangent: " + ("Singular matrix" if status == SINGULAR
                                         else "the step's system has no finite solution")
    return StepSolution(None, None, False, 0, it, reason, norms)

DENSE_NEWTON = True
"""Whether a dense system's iterations (up to ``DENSE_LIMIT`` unknowns, the built-in laws)
run in one kernel call (:func:`dda.kernels.dense_newton.dense_newton`); False: the composed
iterate, every scene."""

NEWTON_DENSE_STEP = True
"""Whether a step whose OPEN-CLOSE takes the dense kernel
(:func:`dda.solvers.open_close.dense_eligible`, with ``DENSE_NEWTON``) runs its predictor and
iterations in one kernel call (:func:`dda.kernels.dense_newton.newton_dense_step`); False:
the predictor's kernel and the iterations' kernel in turn."""


RESIDUAL_KERNEL = True
"""Whether an iterate's out-of-balance vectors come from one compiled pass
(:func:`dda.kernels.assembly.newton_residuals`); False: numpy (the same bits)."""


def _residuals(problem, d, pair_r):
    """``(block_r, r, inertia, contact)`` of the iterate ``d``: the blocks' own out-of-balance
    ``K_b d - f_b`` (every block), and of the free blocks only the total out-of-balance
    ``r``, the blocks' ``K_b d`` and the contacts' summed ``|r_c|`` (the last two measure the
    forces |r| is judged against)."""
    free, el = problem.free, problem.element
    # the blocks of pair_r's rows: the contacts' (and after them the bolts')
    bj, bk = (el.bj, el.bk) if getattr(problem, "bolts", None) is None else problem.pair_blocks
    if RESIDUAL_KERNEL:
        with section("assembly"):
            rigid = problem.rigid if problem.rigid is not None else np.zeros(len(free), bool)
            return newton_residuals(problem.block_k, d, problem.block_f, free, rigid,
                                    np.asarray(bj, dtype=np.int64),
                                    np.asarray(bk, dtype=np.int64),
                                    np.ascontiguousarray(pair_r, dtype=np.float64))
    inertia = np.einsum("bij,bj->bi", problem.block_k, d)
    block_r = inertia - problem.block_f
    r = assemble_vector(block_r, free, bj, bk, pair_r, problem.rigid)
    contact = assemble_vector(np.zeros_like(block_r), free, bj, bk, np.abs(pair_r),
                              problem.rigid)
    return block_r, r[free], inertia[free], contact[free]


def _norm(a: np.ndarray) -> float:
    """``numpy.linalg.norm`` of a float array as numpy computes it (the square root of the
    flattened array's dot product with itself), without its dispatch (4 calls an iterate)."""
    v = a.ravel(order="K")
    return math.sqrt(v.dot(v))


HOLD_CYCLING = True
"""Whether Newton's iterations hold a cycling contact closed (module docstring); False: every
iterate judges every contact by its gap alone.

Measured on the 311-block cut slope of ``examples/jointed_slope.py`` (0.3 s at its defaults,
5e10 N/m and dt 2e-3) with cohesive joints (``--cohesion``), runs two at a time on two
cores, CPU seconds. Without the hold, Newton stopped ("cannot go on") at t = 0.025 s with
1 MPa (113 s) and at 0.020 s with 0.1 MPa, and took 14,903 steps for 0.1 s with 10 kPa: in
the failing steps one contact, at a normal force of 0.1 to 1 N/m and a shear force of 2.4e5
to 2.6e5 N/m (of its 5e5), opened and closed 10 to 14 times in 25 iterations. With it: 1
MPa 13,592 steps, 495 cut, 260 s, the face blocks 0.47 / 1.20 mm (median / most); 0.1 MPa
15,125, 501, 314 s, 0.89 / 20.16 mm (legacy DDA: 2,087, 86, 31 s, 0.44 / 0.80 mm and 1,588,
60, 28 s, 0.35 / 0.58 mm, its OPEN-CLOSE measuring a held contact's pull against the scene's
largest normal force, as it did then; over the contact's group of touching blocks,
``open_close.CYCLE_GROUP``, 1,712, 88, 27 s and 2,239, 94, 41 s; with its memory of held
contacts, ``open_close.CYCLE_MEMORY``, 5,438, 169, 68 s and 0.49 / 1.29 mm at 1 MPa). Measured
against the
scene's largest normal force, as OPEN-CLOSE did, Newton took 2,206 steps, 98 cut, 70 s at 1
MPa, but a light block could hang by a held contact: a block sliding and tipping on a
cohesive incline moved 8.6 mm instead of 87.3 mm when a heavy block stood 20 m away,
touching nothing
(``tests/test_cohesive_newton.py``), and on the slope 16 held contacts pulled more than
their block's weight (a review). Against the contact's own blocks' largest normal force
alone (without the shear): 20,348 steps, 717 cut, 335 s at 1 MPa. Without cohesion the
example took 710 steps, 32 cut, 21.90 / 26.03 mm, against 702, 27, 21.77 / 26.13 without
the hold (the shaken slope is chaotic at the millimetre); the N x N stacks of
``benchmarks/stacks.py`` (10 and 30 a side) take the same passes, iterations and
factorizations either way.
"""

HOLD_AFTER_FLIPS = 2
"""The opens and closes of a contact in the step's iterates (line-search iterates included)
before it may be held: OPEN-CLOSE's count for its own cycle rule. With the scene-wide limit
(:data:`HOLD_CYCLING`), after 4 the cohesive slope above took 2,943 steps, 131 cut, 113 s
(1 MPa) and 3,991, 107, 173 s (0.1 MPa), against 2,206, 98, 70 s and 2,830, 96, 89 s after
2. Held for good (not let go when it pulls harder), held contacts pulled more than the limit
(``tests/test_cohesive_newton.py``)."""


def _hold_rule() -> tuple[float, int]:
    """The dense kernels' ``(hold_tension, hold_after)``: ``CYCLE_TENSION`` (-1 without
    ``HOLD_CYCLING``) and ``HOLD_AFTER_FLIPS``."""
    return (float(CYCLE_TENSION) if HOLD_CYCLING else -1.0), int(HOLD_AFTER_FLIPS)


def _hold_cycling(el, d, resp, held, flips, last_closed, free):
    """``(response, held)`` of an iterate with the hold rule applied (module docstring).

    ``resp`` is the iterate's response with the contacts of ``held`` (None: none) closed;
    ``flips`` (m,) counts each contact's opens and closes over the step's earlier iterates,
    whose last one left ``last_closed``. With ``t_n`` the normal force of ``resp`` (a held
    contact's ``p_n g_n``, positive where it pulls) and the limit ``CYCLE_TENSION`` times the
    largest ``hypot(t_n, t_s)`` on either of the contact's blocks, the smaller
    (:func:`dda.solvers.open_close._largest_on_blocks`): a held contact that pulls by more
    than the limit is let go; one closed at the iterate before, open at this one and with
    ``HOLD_AFTER_FLIPS`` flips behind it is held when, held with the others, its pull is
    within the limit. The response is evaluated again only when the held contacts change."""
    opening = last_closed & ~resp.closed & (flips >= HOLD_AFTER_FLIPS)
    if held is None and not opening.any():  # the common iterate: nothing to measure
        return resp, held
    force = resp.force if resp.force is not None else resp.t_n
    limit = CYCLE_TENSION * _largest_on_blocks(el, np.hypot(force, resp.t_s), free)
    kept = None if held is None else held & (force <= limit)
    if not opening.any():
        if np.array_equal(kept, held):
            return resp, held
        return el.response(d, kept), kept
    trial_held = opening if kept is None else kept | opening
    trial = el.response(d, trial_held)
    tforce = trial.force if trial.force is not None else trial.t_n
    ok = opening & (tforce <= limit)
    if np.array_equal(ok, opening):
        return trial, trial_held
    new = ok if kept is None else kept | ok
    return el.response(d, new), new


def _reversed(patterns):
    """(m,) the contacts sliding at the last accepted iterate in the direction opposite to
    the iterate before's, or None when there is none (``patterns``: :meth:`iterate`'s)."""
    if len(patterns) < 2:
        return None
    now = patterns[-1]
    turned = (np.abs(now) == 2) & (now == -patterns[-2])
    return turned if turned.any() else None


def _seen_at(pattern, patterns):
    """Index into ``patterns`` of the same pattern two to ``CYCLE_LENGTH`` accepted iterates
    back, or None."""
    for back in range(2, min(CYCLE_LENGTH, len(patterns)) + 1):
        if np.array_equal(pattern, patterns[-back]):
            return -back
    return None


def _penalty_floor(el) -> float:
    """The |R| that the round-off of the contacts' coordinates leaves
    (:func:`dda.kernels.dense_newton.penalty_round_off`), 0 without contacts.

    A stiff penalty holding small forces has its floor there: the lip impact of
    ``tests/stability`` at 1,000 E (1e13 N/m) stalled at |R| 4.5e-4 to 7.4e-4 N, 2.6e-6 of
    its 171 N, in four of its nine cut steps at dt 1e-3 (the retries stall at the same
    fraction of the forces: a smaller dt does not lower it).
    """
    if len(el) == 0:
        return 0.0
    g = el.geometry
    a1, a2, a3 = el.maps
    return float(penalty_round_off(
        as_float64(g.p1), as_float64(g.p2), as_float64(g.p3), as_float64(a1),
        as_float64(a2), as_float64(a3), as_float64(el.judge_stiffness),
        as_float64(el.shear_penalty)))


NOISE_FLOOR = True
"""Whether an iterate whose |R| is within the forces of its round-off contacts has converged
(:func:`_at_noise_floor`); False: only ``tol`` and :func:`_at_round_off` end the iterations."""


def _at_noise_floor(problem, resp, norm: float, scale: float) -> bool:
    """|R| is no larger than the out-of-balance of the contacts whose state is round-off.

    A closed contact whose normal force (and shear force) is below its stiffness times the
    round-off of its gap (:func:`dda.solvers.open_close.round_off_gap`) has no state: the
    sign of a gap of 1e-12 of its edge is noise, it opens or closes from one iterate to the
    next, and |R| cannot fall below what such contacts contribute. Below ``ROUND_OFF`` of the
    forces, an iterate whose |R| is at most the norm of their summed residual rows,

        |R| <= | sum_(c noise) r_c |    (the free unknowns),

    has converged. On the 60 x 60 stack of ``benchmarks/stacks.py`` 3,000 to 3,800 of its
    21,000 contacts are such (the vertical joints, gaps at 1e-12 m), their rows sum to
    0.3-0.4 N (forces of 1e7 N), and Newton's second `L U` of a step only showed that |R|
    stayed there (6.1e-2 -> 4.9e-2 N).
    """
    if not NOISE_FLOOR or norm > ROUND_OFF * scale:
        return False
    return norm <= noise_floor(problem, resp)


def noise_floor(problem, resp) -> float:
    """``| sum_(c noise) r_c |`` over the free unknowns (:func:`_at_noise_floor`), -1 when
    no contact's forces are at round-off."""
    el = problem.element
    if len(el) == 0:
        return -1.0
    force = resp.force if resp.force is not None else resp.t_n
    limit = np.asarray(el.judge_stiffness, dtype=float) * round_off_gap(el)
    noise = resp.closed & (np.abs(force) <= limit) & (np.abs(resp.t_s) <= limit)
    if not noise.any():
        return -1.0
    rows = np.where(noise[:, None], resp.residual, 0.0)
    summed = assemble_vector(np.zeros((len(problem.free), 6)), problem.free, el.bj, el.bk,
                             rows, problem.rigid)
    return _norm(summed[problem.free])


def _stalled(norms) -> str:
    """Why Newton gave up on a contraction rule (``norms``: |R| of the accepted iterates and
    of the one that did not shrink it enough)."""
    return f"Newton-Raphson stalled (|R| {norms[-2]:.3g} -> {norms[-1]:.3g})"


def _at_round_off(norms, floor) -> bool:
    """The residual is as small as round-off allows: below ``floor``, and no longer
    decreasing.

    With penalties of 1e10 and more the system's condition number puts the floor of |R| near
    1e-12 of the forces; a ``tol`` below that would otherwise cut the step for nothing. The
    floor is ``ROUND_OFF`` of the forces, or the round-off of the contacts' coordinates
    times their stiffnesses where that is larger (:func:`_penalty_floor`).
    """
    if len(norms) < 3 or norms[-1] > floor:
        return False
    return norms[-1] > 0.5 * min(norms[:-1])
