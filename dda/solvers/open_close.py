"""DDA's OPEN-CLOSE iteration: find the contact states of a step (METHOD.md section 5).

Solve with the current states (open / stick / slip), re-check each contact from the new
displacements, change the springs, and solve again until no state changes. Contacts are
closed when their gap is negative at the end of the step. The linear system is the one of
the step's start (the rows E and I of :class:`dda.contact.ContactElement`); a sliding contact
carries its friction force as a load, from the previous pass's normal force.

Two flavours:
- ``explicit=True`` (legacy DDA): a contact that was sticking at the start of the step keeps
  sticking for the whole step, even when its spring force ends above the strength; the excess is
  pulled back at the start of the next step (the pull-back below). Every other closed contact
  (sliding at the start, or closing during the step, which has no committed shear force) gets
  the friction check in every pass, as in Shi's OPEN-CLOSE, so a vertex that lands while
  sliding is not locked at once.
- ``explicit=False`` (the start of the fully implicit method): every closed contact gets the
  friction check in every pass.

The iteration has settled when no state changes and every sliding contact's friction came
from the pass's own normal force. As the fully implicit method's predictor, a switch between
stick and slip alone takes no further pass: Newton's iterations judge every contact again (on
the 30 x 30 stack of ``benchmarks/stacks.py``: 4.93 passes a step before, 4.12 after); only when
they do not converge from there is the iteration run again to the full rule. Legacy
DDA keeps the full rule: without it (as in Shi's code) a contact that starts sliding in the
last pass ends the step stuck, and the README demo's block slid back up its joint.

As the fully implicit method's predictor the iteration has also settled once
``LAG_PATIENCE`` passes in a row have changed no contact between open and closed, whatever its
stick and slip states and lagged normal forces (its result then says the friction did not
settle, and Newton gets the predictor's few iterations before the full rule is tried): Newton
computes every contact's friction from its exact normal force anyway. On the 1,000-brick wall
of ``benchmarks/scaling.py`` one step's predictor had settled its open and closed states by
pass 4 and then switched one contact between stick and slip, and found 10 to 17 lagged forces
off, in every pass until the limit of 30 cut the step. The predictor run again to the full rule
(Newton did not converge from the looser one) has settled the same way after
``RETRY_PATIENCE`` such passes, and Newton then gets its whole budget of iterations: on the
60 x 60 stack one contact switched between stick and slip in every pass of it until the limit.

Three rules keep the iteration honest (each was needed; tests/test_dynamics.py shows why):
- a sliding contact whose trial shear force turns against the friction load of the pass
  sticks (Shi's rule; without it friction does positive work and a block that hits a stop
  is thrown back); a load of zero (the contact's lagged normal force was zero: a pass had
  opened it, or the cycle rule below held it closed at no force) has no direction, and the
  law decides. Read as a reversal, it stuck a contact that its own friction load opens,
  stuck it loaded up, it slid and opened again: a cycle of four passes until the pass limit
  (``examples/jointed_slope.py``'s first 0.3 s: a slip of zero load stuck in the last ten
  passes of 73 of its 86 failed steps; the 1,000-brick wall's cut step of
  ``tests/test_predictor_patience.py``);
- the pass only counts as settled when every sliding contact's lagged normal force agrees with
  the pass's own within ``NORMAL_FORCE_RTOL`` (otherwise a one-pass penetration spike sets the
  friction, and a sliding block decelerates at several times mu g), give or take
  ``NORMAL_FORCE_FLOOR`` of the largest normal force (legacy DDA: in the contact's group,
  below; the predictor: the pass's);
- when a pass brings back a set of states already tried, only the most violated contact is
  switched (an active-set step), which ends the two-pass cycles of a block bouncing off a
  stiff contact; and legacy's explicit rule no longer spares the contacts of that cycle the
  friction check (a pivot that unloads may need to slide to settle).

A joint's impact dashpot (:mod:`dda.contact.dashpot`) enters as a stiffer normal spring on the
closed contacts, and each contact is judged by its gap less the gap where the spring's and the
dashpot's force cancel (:meth:`dda.contact.ContactElement.judged_gap`): the normal force every
rule below uses is the two together.

A contact that has been opened and closed again within the step and would open once more,
pulled by less than ``CYCLE_TENSION`` of the largest normal force, stays closed for the rest of
the step: it has no consistent state (closed, its spring pulls; open, it penetrates), and it
would otherwise switch every pass until the pass limit cuts the step. While it pulls, such a
contact counts as settled whatever its lagged normal force. In the 10 x 10 stack of
``benchmarks/stacks.py`` one pulled 6.4 N closed and penetrated 1.7e-9 m open; on the faces of
the shaken cut slope of ``examples/jointed_slope.py`` they pull 1e-4 to 1e-2 of the largest
normal force closed and penetrate 1e-4 to 7e-2 of it (as a spring force) open, and were most of
its cut steps.

Which largest normal force? The pass's, the whole scene's, is a known wrong answer where blocks
of very different loads share a scene: a 0.5 x 1 m block sliding and tipping on a cohesive 30
degree incline moves 87.2 mm in 0.5 s alone and 15.1 mm when a heavy block stands 20 m away
touching nothing of it (its contact held closed pulling up to 8% of its weight;
``tests/test_open_close_cycles.py``). The held tension changes answers: held at up to 2% of its
blocks' own largest force that block moves 81.4 mm, at 10% 17.7. So legacy DDA measures it
over the contact's *group* (``CYCLE_GROUP``, the default): the free blocks joined to its own
through contacts closed in the pass (a block whose motion is known joins none). Where every
free block touches the others that is the scene's largest, and a run is the scene-wide rule's
to the bit (41 of the 42 runs of ``benchmarks/regression_set.py``; its 31-block shaken cut
slope, whose blocks part at times, took 245 steps and 9 cuts instead of 267 and 11); a block
that touches only fixed ones is measured on its own forces. The lagged normal force's floor
(``NORMAL_FORCE_FLOOR``) is measured over the group too, and the far block leaves the
incline's block as it is alone, to 1e-14 of its motion. On the shaken cut slope of
``examples/jointed_slope.py`` the 0.3 s took 910 steps and 41 cuts instead of 990 and 47.

What the group alone does not mend: a light block on a heavy one that it touches. With the
incline itself a free block of 41 t a metre on a fixed floor, the group's largest normal force
is the incline's on its floor, 40 times the block's, and the block, its cohesive contact held
closed pulling up to 1% of that step after step, moves 5.0 mm in 0.3 s where the fully
implicit method moves it 31.05 mm (``tests/test_open_close_cycles.py``). A hold that comes
back step after step is such a block's glue; one that does not is a pass's noise. So a
contact held at the end of one of its last ``CYCLE_MEMORY`` (8) steps (its
:attr:`dda.contact.ContactSet.held_ago`: it ended the step closed at zero normal force) is
measured on its own blocks, as the fully implicit method's iterations measure every contact
(:data:`dda.solvers.newton.HOLD_CYCLING`): against the largest contact force ``hypot(t_n,
t_s)`` on either block, the smaller, with the committed shear force ``t_s`` (a cohesive
contact carries its block in shear at no normal force; measured on the normal forces alone,
the example's slope at 1 MPa of cohesion below ended one face block 13.3 mm away where Newton
leaves it at 1.2 mm). The block then moves 30.44 mm (2,121 steps and 47 cuts; Newton 2,348 and
16), and 87.16 mm beside the far block as alone. Measured 2026-12-08 on legacy DDA's 0.3 s of
``examples/jointed_slope.py`` (steps, cuts, CPU; the face blocks' median / most motion in
mm; Newton's from ``dda.solvers.newton``'s docstring), the memory against the group alone
(``cycle_memory=0``, the default before):

=====================  ====================  =======================  ===================
run                    memory (default)      group alone              Newton
=====================  ====================  =======================  ===================
5e10 N/m, dt 2e-3 s    1,064, 51, 28 s;      910, 41, 21 s;           710, 32;
                       22.18 / 27.70         21.86 / 27.27            21.90 / 26.03
``--auto``             1,282, 2, 23 s        1,274, 0                 698, 0
``--dt auto``          2,078, 12, 36 s       2,078, 10                --
10 kPa cohesion        3,800, 147, 60 s;     1,216, 51, 25 s;         9,166, 303;
                       10.72 / 12.62         9.56 / 10.62             11.29 / 13.18
1 MPa cohesion         5,438, 169, 68 s;     1,712, 88, 25 s;         13,592, 495;
                       0.49 / 1.29           0.39 / 0.89              0.47 / 1.20
=====================  ====================  =======================  ===================

(1 MPa with gravity 1e-6 larger and smaller: 4,696 and 4,294 steps, the face 0.49 / 1.12 and
0.47 / 1.06 mm.) At the example's stiff settings the memory costs 1.2 times the steps, and 3
times with cohesive joints, whose faces it brings to within 7% of Newton's from 19-26% below
it; at the settings the simulation would choose it costs next to nothing over 0.3 s (over
10 s at ``--dt auto`` it cut 0.22% and 0.43% of the steps on two cuts of the rock mass
against 0.04% and 0.07%, ``benchmarks/README.md``). The memory's length, on
the normal forces alone (single runs, chaotic at a few percent): 1 step moved the incline's
block 27.1 mm, 4 steps 30.0, 8 30.5, 16 30.4, every step since the contact was first held 30.7;
the example at 10 kPa took 2,282, 3,025, 3,708, 4,162 and 10,239 steps.

With ``CYCLE_LOCAL`` (or ``LegacyPullBack(cycle_local=True)`` for one solver) every contact is
measured on its own blocks, on their largest normal forces alone: 30.88 mm on the heavy incline
(2,353 steps, 16 cuts), the far block's 87.2 mm to 1e-11, but on the example's slope 1,891
steps and 53 cuts (43 s of CPU against the group's 24) with the face at 22.91 / 29.42 mm,
11,395 steps and 420 cuts at 10 kPa, and 17,730 and 651 at 1 MPa, where one face block ends
16.4 mm away (2026-12-07, ``benchmarks/README.md``, "Legacy DDA's cycle rule on a contact's
own blocks, measured again"): on the shaken cut slope the contacts that cycle pull a median
14% of the largest normal force on their own blocks and 0.01% of the scene's, so the group's
limit holds nearly all of them and the own blocks' 9%. Measured with the shear forces too, as
the memory measures, it ended a face block 135 mm away at 1 MPa (17,129 steps, one run), and
took 2,487 steps and 67 cuts on the example: it stays on the normal forces.
``dda.settling``'s static steps keep the group's measure without the memory (on the own
blocks the cut slope's held static steps did not settle in 400). The fully implicit method's
predictor keeps the scene's measure either way: its iterations judge every contact again.

From pass ``LAG_RELAX_AFTER`` on, a lagged normal force that oscillates (its error changed sign
since the last pass) is under-relaxed, ``N_lag <- (N_lag + N) / 2``: where a sliding contact's
friction load opens it (a face block's corner), the plain iteration ``N_(k+1) = a - b N_k``
oscillates with ``b`` just above 1 (1.05 measured) and never settles; the relaxed one contracts
by ``|1 - b| / 2``. Relaxing every sliding contact slows the common case for nothing: from pass
6, the kicked block of ``tests/stability/scenes.py``'s incline, whose force converges without
oscillating, no longer settled its first step within 12 passes at dt 5e-4; from pass 2 the
10 x 10 stack's 3.7 passes a step became 5.7.

Legacy DDA takes, from pass ``LAG_SECANT_FROM`` on, the secant step instead (:func:`next_lag`):
where a contact closed in this pass and the last oscillates, its two passes give the slope
``-b`` of its map, and the lag moves to the map's fixed point ``a / (1 + b)``, so a sliding
block's friction that its normal force answers with ``b`` well above 1 (2 to 4 on the faces of
``examples/jointed_slope.py``, where halving contracts by 0.5 to 1.5) settles in a pass, and one
with ``b`` near 0 is barely touched. On that example (0.3 s, three runs) its steps at 1.25e-4 s
took 8.45-8.95 passes before and 6.45-6.92 with it, those at 2.5e-4 s 11.1-14.2 and 9.6-10.3
(``benchmarks/secant_lag.py``). From pass 2, where the first pass's switches still move the
other contacts' forces, it saved about as much there but cost the stacks 2-4% more passes; from
pass 3 the stacks' steps take 1-3% more passes, all among those that switch more than ten
contacts. The fully implicit method's predictor keeps the plain rule: its Newton iterations
judge the friction with the exact normal force, and with the secant from pass 2 the stacks'
Newton passes grew by 2-4% for no clear gain on the example.

The fully implicit method's predictor remembers instead, through an open pass, the lag of a
contact that has already gone from closed to open and back (``REMEMBER_FROM_FLIPS`` changes in
the step): where its last closed pass's spring pulled (that pass's loads opened it, on the
cut slope's faces its own friction load) and it penetrates again, its next lag is
``min((N_lag + p g) / 2, 0)`` of that closed pass, not the spring force of the penetration,
which loads its friction up and opens it again, a cycle of two passes through an open one that
the halving does not reach (it needs two closed passes). Only a contact that closes sliding
uses it (a sticking one's friction takes the pass's own force); restricted to contacts that
were sliding in that closed pass as well, it lost its gain below (135 cut steps).
On ``examples/jointed_slope.py`` through 10 s of shaking (5e10 N/m) Newton's steps cut for
OPEN-CLOSE went 99 -> 53 and its cut steps 144 in 6,974 -> 98 in 6,505. From the first cycle
on it cut 78 steps but took the 60 x 60 stack from 5.80 to 6.63 passes a step (its bouncing
contacts); from the second the stacks are unchanged. Legacy DDA keeps the plain rule: the
memory lets its steps settle into the moving base's see-saw, where a held stick spring rings at
two steps a period (``benchmarks/README.md``, issue 19's twenty-first and twenty-second parts),
and its errors there went 12.8% -> 22.3% (2e9 N/m) and 15.9% -> 17.9% (2e10) at dt 1e-2.

Legacy DDA also ends the iteration on changes too small to matter (``SETTLE_BAND``): a pass
counts as settled when every contact whose state it changed moves less than 1% of the force
that measures it (the largest normal force on its lighter loaded block; blocks whose motion is
known do not count), whether the tension a closed spring carried, the spring force an open
contact lacked, or the gap between the stick spring's shear force and the return map's; its
new states are committed. And a sliding contact whose normal force is below that 1% does not
wait for its lagged force. The side joints of a stack carry almost no normal force and switch
in pass after pass as it settles (on the 30 x 30 stack of ``benchmarks/stacks.py``, 98% of the
switches are on vertical joints, pulling 1e-5 to 6e-3 of the largest normal force): 4.13 ->
3.54 passes a step on the 10 x 10 stack, 4.33 -> 3.50 on the 30 x 30, with centroids 5.6e-7 m
and stresses 336 Pa from the answer without the band after 0.1 s, where halving dt moves them
4.4e-5 m and 45 kPa. A band on every lagged force (not only the small ones) took the stacks to
2.7 passes but let the friction of a sliding block lag by 1% of its own load in every step:
the moving base of ``benchmarks/accuracy_cost.py`` went from 4.9% to 7.4% error (dt 3e-3, 2e10
N/m). A block whose only loaded contact is the changing one (a block landing) gets no band.
The fully implicit method's predictor takes none: its Newton iterations judge every contact
again, and on the 30 x 30 stack the band saved it 0.23 passes a step and no time (116 against
109 ms of CPU a step).

And a contact whose linearized gap is within round-off of zero (:func:`round_off_gap`) keeps
its state: blocks that move alike leave their joint's gap at noise level, and the noise's sign
would open and close such contacts by the thousand every pass (a 10,000-brick wall did not
settle in 60 passes; it takes 4).

Where every contact's law is a built-in one (:class:`dda.contact.CoulombSingle`,
:class:`dda.contact.StaticDynamicTransition`), a pass is two compiled calls around the linear
solve (:mod:`dda.kernels.open_close`) that apply these rules in this order, with the same
results to the bit; any other law takes the numpy iteration below, which stays the reference
(``dda.contact.element.KERNEL_LAWS = False`` sends every law there).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda.contact.contacts import OPEN, SLIP, STICK
from dda.contact.tangent import SPRING_TERMS
from dda.kernels.dense_passes import CONVERGED, NOT_SETTLED, SINGULAR, dense_passes
from dda.kernels.dense_passes import single_switch as _single_switch
from dda.kernels.open_close import CYCLE_BLOCKS as _CYCLE_BLOCKS
from dda.kernels.open_close import CYCLE_GROUP as _CYCLE_GROUP
from dda.kernels.open_close import CYCLE_SCENE as _CYCLE_SCENE
from dda.kernels.open_close import (
    REMEMBER_FROM_FLIPS,
    _group_force,
    as_float64,
    kernel_history,
    kernel_history_dict,
    pass_judge,
    pass_loads,
    round_off_gaps,
    step_start,
)
from dda.kernels.pair_stiffness import PairStiffness
from dda.profiling import count_solve, section
from dda.solvers.base import StepProblem
from dda.solvers.linear import DENSE_LIMIT, SingularSystemError, assemble_and_solve

__all__ = ["OpenCloseResult", "open_close", "NORMAL_FORCE_RTOL", "NORMAL_FORCE_FLOOR",
           "GAP_ROUND_OFF", "CYCLE_TENSION", "CYCLE_LOCAL", "CYCLE_GROUP", "CYCLE_MEMORY",
           "LAG_RELAX_AFTER",
           "LAG_SECANT_FROM", "LAG_PATIENCE", "RETRY_PATIENCE", "SETTLE_BAND",
           "predictor_patience", "round_off_gap", "next_lag", "local_cycle_limit",
           "cycle_measure", "cycle_memory", "own_cycle_measures"]

# relative change of a sliding contact's normal force between passes that ends OPEN-CLOSE
NORMAL_FORCE_RTOL = 0.01
# ... and the absolute part of that test, as a fraction of the largest normal force (legacy
# DDA: in the contact's group of touching free blocks; the predictor, and with CYCLE_GROUP
# off: the pass's)
NORMAL_FORCE_FLOOR = 1e-4
# a linearized gap within this fraction of the edge's length of zero keeps the contact's state
GAP_ROUND_OFF = 1e-12
# a contact that cycles open / closed stays closed when it pulls less than this fraction of the
# largest normal force in its group (legacy DDA), on its own blocks (CYCLE_LOCAL), or in the pass
CYCLE_TENSION = 1e-2
# legacy DDA: the cycle rule's limit measured on the contact's own blocks (module docstring:
# right where a heavy block, far away or under it, would hold a light block's contact; off
# by default for what it costs elsewhere, cohesive joints most)
CYCLE_LOCAL = False
# legacy DDA, without CYCLE_LOCAL: the limit measured over the contact's group of free blocks
# that touch through closed contacts (the scene's largest where they all touch; a block far
# away that touches only fixed ones is a group of its own); False: over the whole pass (the
# lagged force's floor is the group's with CYCLE_LOCAL whatever this says)
CYCLE_GROUP = True
# legacy DDA, over the group: the steps for which a contact held at a step's end is measured
# on its own blocks (a hold that repeats is a light block's glue; one that does not is a
# pass's noise; 0: never)
CYCLE_MEMORY = 8
# the pass from which a sliding contact's lagged normal force is under-relaxed
LAG_RELAX_AFTER = 6
# legacy DDA: the pass from which an oscillating lagged normal force takes the secant step
# (module docstring; 0: never)
LAG_SECANT_FROM = 3
# the fully implicit method's predictor: settled once this many passes in a row have changed no
# contact between open and closed, whatever its friction (module docstring)
LAG_PATIENCE = 5
# ... and once the predictor settles stick and slip too (Newton did not converge from the
# looser one), after this many (module docstring); legacy DDA has no such rule
RETRY_PATIENCE = 10
# legacy DDA: a pass whose state changes each move less force than this fraction of the largest
# normal force on the lighter loaded of the contact's blocks counts as settled (module docstring)
SETTLE_BAND = 1e-2
#: None, or a list that gets, per pass, (closing, opening, stick-slip switches, lagging sliding
#: contacts): what kept the iteration going (benchmarks/stacks.py reads it)
PASS_LOG = None
#: a dense system's passes in one kernel call (:mod:`dda.kernels.dense_passes`); False: the
#: composed passes
DENSE_PASSES = True


@dataclass
class OpenCloseResult:
    """Outcome of the OPEN-CLOSE iteration.

    ``history`` is the committed history after the pull-back; ``gap`` and ``dgs`` are the
    normal gap and the shear increment of the last pass, linearized at the step's start.
    An iteration that did not settle in its passes keeps the last pass's increments in ``d``
    (the fully implicit method iterates from them); a singular one has none.
    """

    converged: bool
    passes: int
    reason: str = ""
    d: np.ndarray | None = None
    state: np.ndarray | None = None
    gap: np.ndarray | None = None
    dgs: np.ndarray | None = None
    history: dict | None = None
    friction_settled: bool = True  # the stick and slip states settled too


def open_close(problem: StepProblem, explicit: bool,
               settle_friction: bool | None = None,
               band: float | None = None,
               cycle_local: bool | None = None,
               cycle_memory: int | None = None) -> OpenCloseResult:
    """Run the OPEN-CLOSE iteration of one step (see the module docstring).

    ``settle_friction`` (default: ``explicit``) asks for the stick and slip states to settle
    too; without it only the open and closed ones must. ``band`` (default: ``SETTLE_BAND``
    for legacy DDA, ``explicit``, and 0 for the fully implicit method's predictor): state
    changes that move less force than this fraction of the largest normal force on the
    lighter loaded of the contact's blocks do not take another pass. ``cycle_local`` (default:
    ``CYCLE_LOCAL`` for legacy DDA, False for the predictor) measures the cycle rule's
    limit on each contact's own blocks (and the lagged force's floor over its group of
    touching free blocks); without it legacy DDA measures both over the group
    (``CYCLE_GROUP``), but the limit of a contact held at the end of one of its last
    ``cycle_memory`` steps (default ``CYCLE_MEMORY``; 0: none) on its own blocks, and the
    predictor over the pass.
    """
    if settle_friction is None:
        settle_friction = explicit
    if band is None:
        band = SETTLE_BAND if explicit else 0.0
    measure = _cycle_measure(explicit, cycle_local)
    patience = predictor_patience(explicit, settle_friction)
    el = problem.element
    if len(el) == 0:  # no contacts: one linear solve settles the step
        return _without_contacts(problem)
    own = own_cycle_measures(el.contacts, measure, cycle_memory)
    gap_tol = round_off_gap(el)
    compiled = el.kernel_laws is not None
    history, t_stick, state, held = _start(el, explicit, gap_tol, compiled)
    secant_from = LAG_SECANT_FROM if explicit else 0  # legacy DDA's secant lag only
    remember_open = not explicit  # the predictor's lag memory only
    if compiled:
        return _compiled_passes(problem, el, history, t_stick, state, held, gap_tol,
                                settle_friction, band, patience, secant_from, remember_open,
                                measure, own)
    t_n_lag = el.contacts.t_n.copy()
    dgs_prev = np.zeros(len(el))
    passes = 0
    seen = {state.tobytes()}
    flips = np.zeros(len(el), dtype=np.int64)  # open <-> closed changes of each contact so far
    pinned = np.zeros(len(el), dtype=bool)  # held closed by the cycle rule
    lag_error = np.zeros(len(el))  # the last pass's normal force less its lagged one
    lag_memory = np.zeros((len(el), 3))  # the last pass's lagged and spring forces, closed
    calm = 0  # passes in a row that changed no contact between open and closed
    for passes in range(1, problem.max_open_close + 1):
        # evaluated on every closed contact (used on the sliding ones): a law that judges
        # faces needs a face's sticking contacts too
        t_slip, _, _ = el.friction(history, dgs_prev, t_n_lag, where=state != OPEN)
        t_slip = np.where(state == SLIP, t_slip, 0.0)
        k, f = el.legacy_contributions(state, t_stick, t_slip)
        try:
            d, gap, dgs, judged = _solve_pass(problem, k, f)
        except SingularSystemError as exc:
            return OpenCloseResult(False, passes, f"singular system: {exc}")
        new_state, t_n = _next_states(el, state, history, judged, dgs, t_slip, held, gap_tol)
        lag_ok = _lag_settled(el, state, new_state, judged, t_n, t_n_lag, flips, pinned,
                              problem.free, measure, own)
        flips += (state != OPEN) != (new_state != OPEN)
        # settled when no state changes and every sliding contact's friction came from this
        # pass's normal force; for the fully implicit method's predictor a switch between
        # stick and slip alone takes no further pass (its iterations judge every contact
        # again)
        settled = (np.array_equal(new_state, state) if settle_friction
                   else np.array_equal(new_state != OPEN, state != OPEN))
        if band and not (settled and np.all(lag_ok | (state != SLIP))):
            local = band * _largest_on_blocks(el, t_n, problem.free)
            # a sliding contact that carries less than that of its blocks' largest normal
            # force does not hold the iteration by its lagged force (its friction is noise
            # to them)
            lag_ok |= np.maximum(np.abs(t_n), np.abs(t_n_lag)) <= local
            settled = settled or _negligible_changes(el, state, new_state, judged, dgs,
                                                     history, t_n, t_slip, settle_friction,
                                                     local)
        if PASS_LOG is not None:
            PASS_LOG.append(_why(state, new_state, lag_ok))
        calm = calm + 1 if np.array_equal(new_state != OPEN, state != OPEN) else 0
        if settled and np.all(lag_ok | (state != SLIP)):
            return OpenCloseResult(True, passes, "", d, new_state, gap, dgs, history,
                                   bool(np.array_equal(new_state, state)))
        if patience and calm >= patience:
            return OpenCloseResult(True, passes, "", d, new_state, gap, dgs, history, False)
        if new_state.tobytes() in seen and not np.array_equal(new_state, state):
            held = _unhold_cycling(held, state, new_state)
            new_state = _single_switch(state, new_state, judged)
        seen.add(new_state.tobytes())
        t_n_lag, lag_error = next_lag(state, judged, el.judge_stiffness, t_n, t_n_lag,
                                      lag_error, lag_memory, passes, secant_from,
                                      remember_open, flips)
        state, dgs_prev = new_state, dgs
    return OpenCloseResult(False, passes, f"OPEN-CLOSE did not settle in {passes} passes", d)


def _solve_pass(problem, k, f):
    """A pass's increments with the contacts' springs ``k`` and forces ``f``, and the gaps
    they give: ``(d, gap, dgs, judged)``, the normal gaps and shear increments linearized at
    the step's start and the gaps the pass judges (:meth:`dda.contact.ContactElement.
    judged_gap`)."""
    el = problem.element
    k, f = problem.with_bolts(k, f)
    d = assemble_and_solve(problem.block_k, problem.block_f, problem.free,
                           *problem.pair_blocks, k, f, problem.d_known, problem.pattern,
                           factor=problem.factor(symmetric=True))
    gap, dgs = el.linear_gaps(d)
    return d, gap, dgs, el.judged_gap(gap)


def _compiled_passes(problem, el, history, t_stick, state, held, gap_tol, settle_friction,
                     band, patience, secant_from, remember_open, measure,
                     own) -> OpenCloseResult:
    """The iteration of :func:`open_close` with the built-in laws' compiled passes
    (:mod:`dda.kernels.open_close`): the same rules in the same order, the same results."""
    m = len(el)
    f64 = np.float64
    laws = el.kernel_laws
    g_se, _, sliding = kernel_history(history, m)
    if dense_eligible(problem):
        return _dense(problem, el, history, state, held, gap_tol, settle_friction, band,
                      patience, secant_from, remember_open, measure, own,
                      (g_se, sliding, as_float64(t_stick)))
    pn, kn, ps, length, gap0, e_row, i_row, t_stick = (
        np.ascontiguousarray(a, dtype=f64) for a in (
            el.normal_penalty, el.judge_stiffness, el.shear_penalty, el.length, el.gap0,
            el.e_row, el.i_row, t_stick))
    bj, bk = (np.asarray(b, dtype=np.int64) for b in (el.bj, el.bk))
    free = np.asarray(problem.free, dtype=np.bool_)
    state = np.asarray(state, dtype=np.int8)
    rules = pass_rules(patience)
    shear = as_float64(np.abs(el.contacts.t_s))
    t_n_lag = np.array(el.contacts.t_n, dtype=f64)
    dgs_prev = np.zeros(m)
    seen = {state.tobytes()}
    flips = np.zeros(m, dtype=np.int64)
    pinned = np.zeros(m, dtype=bool)
    calm = np.zeros(1, dtype=np.int64)
    lag_error = np.zeros(m)
    lag_memory = np.zeros((m, 3))
    for passes in range(1, problem.max_open_close + 1):
        with section("return_map"):
            t_slip, weights, f = pass_loads(state, *laws, g_se, sliding, dgs_prev, t_n_lag,
                                            ps, length, gap0, pn, t_stick, e_row, i_row)
        el.with_dashpot(weights, f, state)
        k = PairStiffness.checked_by_caller(el._spring_rows, SPRING_TERMS, weights)
        try:
            d, gap, dgs, judged = _solve_pass(problem, k, f)
        except SingularSystemError as exc:
            return OpenCloseResult(False, passes, f"singular system: {exc}")
        with section("return_map"):
            new_state, t_n, done, friction_settled, next_lag, lag_error, lag_ok = pass_judge(
                state, held, judged, dgs, t_slip, t_n_lag, lag_error, lag_memory, flips,
                pinned, calm, gap_tol, kn, ps, length, *laws, g_se, sliding, bj, bk, free,
                settle_friction, float(band), passes, *rules, secant_from, remember_open,
                measure, own, shear)
        if PASS_LOG is not None:
            PASS_LOG.append(_why(state, new_state, lag_ok))
        if done:
            return OpenCloseResult(True, passes, "", d, new_state, gap, dgs, history,
                                   friction_settled)
        if new_state.tobytes() in seen and not np.array_equal(new_state, state):
            held = _unhold_cycling(held, state, new_state)
            new_state = _single_switch(state, new_state, judged)
        seen.add(new_state.tobytes())
        state, dgs_prev, t_n_lag = new_state, dgs, next_lag
    return OpenCloseResult(False, passes, f"OPEN-CLOSE did not settle in {passes} passes", d)


def dense_eligible(problem: StepProblem) -> bool:
    """Whether the step's OPEN-CLOSE takes the dense kernel (:func:`_dense`): a dense system
    with unknowns and contacts, the built-in laws, no pass log, no bolts."""
    el, pattern = problem.element, problem.pattern
    return (DENSE_PASSES and PASS_LOG is None and pattern.n <= DENSE_LIMIT
            and pattern.unknowns > 0 and len(el) > 0 and el.kernel_laws is not None
            and problem.bolts is None)


def dense_arguments(problem: StepProblem) -> tuple:
    """The arguments of :func:`dda.kernels.dense_passes.dense_passes` from ``block_k`` to
    ``face``: the step's blocks, the dense layout, legacy DDA's spring rows, the contacts'
    linearization, penalties, impact dashpots and built-in laws."""
    el, pattern = problem.element, problem.pattern
    m = len(el)
    f64 = np.float64
    if el.dashpot is None:
        zero = np.zeros(m)
        dashpot = (False, zero, zero, zero)
    else:
        dashpot = (True, as_float64(el.dashpot), as_float64(el.dashpot_reference),
                   as_float64(el.release))
    return (np.ascontiguousarray(problem.block_k, dtype=f64),
            np.ascontiguousarray(problem.block_f, dtype=f64),
            np.ascontiguousarray(problem.d_known, dtype=f64), *dense_layout(pattern),
            el._spring_rows, SPRING_TERMS, np.asarray(el.bj, dtype=np.int64),
            np.asarray(el.bk, dtype=np.int64), np.asarray(problem.free, dtype=np.bool_),
            *(as_float64(a) for a in (el.e_row, el.i_row, el.gap0, el.normal_penalty,
                                      el.shear_penalty, el.judge_stiffness, el.length)),
            *dashpot, *el.kernel_laws)


def dense_layout(pattern) -> tuple:
    """The dense kernels' layout arguments of a :class:`dda.solvers.linear.SystemPattern`:
    ``n``, where the blocks' and the contacts' 6 x 6 blocks go, the contacts' right-hand side
    rows, and the unknowns solved for (``keep``, ``reduced``)."""
    layout = pattern.__dict__.get("_dense_layout")  # (kept with the pattern, across steps)
    if layout is None:
        keep = pattern.keep
        layout = pattern.__dict__["_dense_layout"] = (
            pattern.n, pattern.block_base, pattern.block_step, pattern.free_blocks,
            pattern.pair_base, pattern.pair_step, pattern.side_row, pattern.side_block,
            _NO_KEEP if keep is None else np.asarray(keep, dtype=np.int64), keep is not None)
    return layout


def local_cycle_limit(solver) -> bool:
    """Whether ``solver``'s OPEN-CLOSE measures the cycle rule's limit on a contact's own
    blocks: legacy DDA's ``cycle_local``, or ``CYCLE_LOCAL`` where that is None (a solver
    without the setting: ``CYCLE_LOCAL``, which only legacy DDA's passes read)."""
    flag = getattr(solver, "cycle_local", None)
    return bool(CYCLE_LOCAL if flag is None else flag)


def cycle_memory(solver) -> int:
    """The steps for which legacy DDA's ``solver`` measures the cycle limit of a contact
    held at a step's end on its own blocks: its ``cycle_memory``, or ``CYCLE_MEMORY`` where
    that is None (read at each step)."""
    memory = getattr(solver, "cycle_memory", None)
    return int(CYCLE_MEMORY if memory is None else memory)


def own_cycle_measures(contacts, measure: int, memory: int | None) -> np.ndarray:
    """(m,) the contacts whose cycle limit is measured on their own blocks under the group's
    measure: held at the end of one of their last ``memory`` steps (None:
    ``CYCLE_MEMORY``) by :attr:`dda.contact.ContactSet.held_ago`; none under the other
    measures."""
    if memory is None:
        memory = CYCLE_MEMORY
    if measure != _CYCLE_GROUP or memory <= 0:
        return np.zeros(len(contacts), dtype=np.bool_)
    return np.asarray(contacts.held_ago) <= memory


def cycle_measure(solver) -> int:
    """What legacy DDA's ``solver`` measures the cycle rule's limit against, as the kernels
    take it (:data:`dda.kernels.open_close.CYCLE_BLOCKS` with :func:`local_cycle_limit`, else
    ``CYCLE_GROUP``, or ``CYCLE_SCENE`` with the module's ``CYCLE_GROUP`` off)."""
    return _cycle_measure(True, local_cycle_limit(solver))


def _cycle_measure(explicit: bool, cycle_local: bool | None) -> int:
    if cycle_local is None:
        cycle_local = explicit and CYCLE_LOCAL
    if cycle_local:
        return _CYCLE_BLOCKS
    return _CYCLE_GROUP if explicit and CYCLE_GROUP else _CYCLE_SCENE


def pass_rules(patience: int | None = None) -> tuple:
    """The passes' rules as the kernels take them: ``NORMAL_FORCE_RTOL``,
    ``NORMAL_FORCE_FLOOR``, ``CYCLE_TENSION``, ``LAG_RELAX_AFTER`` and the patience
    (``LAG_PATIENCE`` unless given; read at each call)."""
    return (NORMAL_FORCE_RTOL, NORMAL_FORCE_FLOOR, CYCLE_TENSION, LAG_RELAX_AFTER,
            LAG_PATIENCE if patience is None else int(patience))


def predictor_patience(explicit: bool, settle_friction: bool) -> int:
    """The passes in a row that open or close no contact after which the iteration counts as
    settled with its friction unsettled (the kernels' ``patience``; 0: never): legacy DDA
    never, the fully implicit method's predictor after ``LAG_PATIENCE``, and after
    ``RETRY_PATIENCE`` when it settles stick and slip too (module docstring)."""
    if explicit:
        return 0
    return RETRY_PATIENCE if settle_friction else LAG_PATIENCE


def dense_failure(status: int, passes: int) -> str:
    """Why the dense kernel's OPEN-CLOSE stopped (``status`` other than CONVERGED)."""
    if status == NOT_SETTLED:
        return f"OPEN-CLOSE did not settle in {passes} passes"
    return "singular system: " + ("Singular matrix" if status == SINGULAR
                                  else "the step's system has no finite solution")


def _dense(problem, el, history, state, held, gap_tol, settle_friction, band, patience,
           secant_from, remember_open, measure, own, start) -> OpenCloseResult:
    """:func:`_compiled_passes` on a dense system: every pass in one kernel call
    (:func:`dda.kernels.dense_passes.dense_passes`; the same decisions, the numbers to
    round-off). ``start`` is the step's pulled-back ``g_se``, ``sliding`` and stick forces.
    Its time is the step profile's ``solve``."""
    with section("solve"):
        status, passes, d, new_state, gap, dgs, friction_settled = dense_passes(
            problem.max_open_close, bool(settle_friction), float(band), *pass_rules(patience),
            secant_from, remember_open, measure, own, as_float64(np.abs(el.contacts.t_s)),
            *dense_arguments(problem), *start,
            np.asarray(state, dtype=np.int8),
            np.asarray(held, dtype=np.bool_), gap_tol, as_float64(el.contacts.t_n))
    count_solve(passes)
    if status == CONVERGED:
        return OpenCloseResult(True, passes, "", d, new_state, gap, dgs, history,
                               friction_settled)
    # the last pass's increments when it did not settle (the fully implicit method iterates
    # from them)
    return OpenCloseResult(False, passes, dense_failure(status, passes),
                           d if status == NOT_SETTLED else None)


_NO_KEEP = np.zeros(0, dtype=np.int64)


def _lag_settled(el, state, new_state, gap, t_n, t_n_lag, flips, pinned, free, measure, own):
    """(m,) the contacts whose lagged normal force is settled; applies the cycle rule
    (``new_state`` and ``pinned`` change in place) with its limit measured as ``measure``
    says (:func:`_cycle_measure`): on each contact's own blocks or over its group of touching
    free blocks (``free``: the blocks with unknowns; the floor over the group under either;
    the contacts ``own`` on their own blocks under the group's measure), or on the pass's
    largest normal force (the fully implicit method's predictor)."""
    # a sliding contact's friction came from the last pass's normal force: the pass only
    # counts when that force is the one this pass ended with (forces below NORMAL_FORCE_FLOOR
    # of the largest, in the group or the pass, matter to no block: a barely touching contact
    # would otherwise hold the iteration for many passes)
    largest = float(np.max(np.abs(t_n), initial=0.0))
    if measure != _CYCLE_SCENE:  # the largest in each contact's group: the floor's
        largest = _group_force(np.asarray(t_n, dtype=np.float64), np.asarray(state),
                               np.asarray(el.bj, dtype=np.int64),
                               np.asarray(el.bk, dtype=np.int64),
                               np.asarray(free, dtype=np.bool_), 1.0)
    lag_ok = np.abs(t_n - t_n_lag) <= NORMAL_FORCE_RTOL * np.maximum(
        np.abs(t_n), np.abs(t_n_lag)) + NORMAL_FORCE_FLOOR * largest
    # a contact that has been opened and closed again in this step's passes and would open
    # once more, pulled by less than CYCLE_TENSION of the largest normal force (in its group,
    # on its own blocks, or in the pass), stays closed (open it penetrates, closed it pulls:
    # alone it would cycle until the pass limit), and while it pulls its lagged normal force
    # does not hold the iteration
    cycling = (flips >= 2) & (state != OPEN) & (new_state == OPEN)
    if cycling.any():
        # remembered, on its own blocks each contact's force is hypot(t_n, t_s), the shear
        # force the committed one (a cohesive contact carries its block in shear at no
        # normal force); with CYCLE_LOCAL the normal force alone (module docstring)
        if measure == _CYCLE_BLOCKS:
            limit = CYCLE_TENSION * _largest_on_blocks(el, t_n, free)
        elif measure == _CYCLE_GROUP and own.any():
            limit = CYCLE_TENSION * np.where(
                own, _largest_on_blocks(el, np.hypot(t_n, el.contacts.t_s), free), largest)
        else:
            limit = CYCLE_TENSION * largest
        cycling &= el.judge_stiffness * gap <= limit
        new_state[cycling] = state[cycling]
        pinned |= cycling
    return lag_ok | (pinned & (gap >= 0.0))


def _largest_on_blocks(el, t_n, free) -> np.ndarray:
    """(m,) the force that measures what a change of each contact does: the largest normal
    force magnitude on either of its blocks, the smaller of the two (a change that is noise
    to a heavily loaded block may not be to a light one beside it); a block whose motion is
    known does not count (its largest force would be that of the whole scene's heaviest
    block)."""
    largest = np.zeros(len(free))
    np.maximum.at(largest, el.bj, np.abs(t_n))
    np.maximum.at(largest, el.bk, np.abs(t_n))
    largest[~free] = np.inf
    return np.minimum(largest[el.bj], largest[el.bk])


def _negligible_changes(el, state, new_state, gap, dgs, history, t_n, t_slip,
                        settle_friction, limit) -> bool:
    """True when every contact whose state the pass changed carried a force within
    ``limit`` of the one its new state gives.

    The force error of a change: ``p_n |g_n|`` when a contact opens (the tension its spring
    carried) or closes (the spring force it lacked); ``|t_used - t_s|`` when it switches
    between stick and slip, with ``t_used`` the stick spring's force or the friction load the
    pass solved with and ``t_s`` the return map's from the pass's own gaps.
    """
    if settle_friction:
        idx = np.flatnonzero(new_state != state)
    else:
        idx = np.flatnonzero((new_state != OPEN) != (state != OPEN))
    was, now = state[idx] != OPEN, new_state[idx] != OPEN
    error = el.judge_stiffness[idx] * np.abs(gap[idx])
    switched = was & now
    if np.any(switched):
        where = np.zeros(len(state), dtype=bool)
        where[idx[switched]] = True
        t_spring, _ = el.stick(history, dgs, where=where)
        t_s, _, _ = el.friction(history, dgs, t_n, where=where)
        used = np.where(state == STICK, t_spring, t_slip)
        error[switched] = np.abs(used - t_s)[idx[switched]]
    return bool(np.all(error <= limit[idx]))


def next_lag(state, gap, stiffness, t_n, t_n_lag, lag_error, lag_memory, passes,
             secant_from=0, remember_open=False, flips=None):
    """The lagged normal force of the next pass, and this pass's lag error ``N - N_lag``.

    The pass's own force ``N``; where the error changed sign since the last pass (an
    oscillation of ``N_(k+1) = a - b N_k`` with ``b > 0``), from pass ``secant_from`` on (0:
    never), on a contact closed in this pass and the last, the secant step to the fixed point

        N_lag <- min(N_lag + w (p g - N_lag), 0),   w = -(N_lag - N_lag') / (e - e')

    with ``e = p g - N_lag`` the spring force (``stiffness * gap``, a tension not cut off)
    less the lagged force and primes for the last pass, used when ``0.05 < w < 1`` (for the
    linear map ``w = 1 / (1 + b)``, and the step lands on its fixed point ``a / (1 + b)``);
    from pass ``LAG_RELAX_AFTER`` on, otherwise, the mean ``(N + N_lag) / 2``. ``lag_memory``
    (m, 3) holds each contact's lagged force, spring force and closed flag (1.0) of the last
    pass and is updated in place; with ``remember_open`` (the fully implicit predictor) an
    open pass leaves it, and a contact that closes again after ``REMEMBER_FROM_FLIPS`` changes
    between open and closed (``flips``), its last closed pass's spring pulling, takes
    ``min((N_lag + p g) / 2, 0)`` of that pass (the module docstring). The compiled passes'
    rule is
    :func:`dda.kernels.open_close.next_lag_force`, the same arithmetic.
    """
    error = t_n - t_n_lag
    spring = stiffness * gap
    closed = state != OPEN
    oscillates = error * lag_error < 0.0
    out = t_n.copy()
    secant = np.zeros(len(t_n), dtype=bool)
    if secant_from and passes >= secant_from:
        change = (spring - t_n_lag) - (lag_memory[:, 1] - lag_memory[:, 0])
        candidate = oscillates & closed & (lag_memory[:, 2] != 0.0) & (change != 0.0)
        w = np.full(len(t_n), np.nan)
        w[candidate] = -(t_n_lag - lag_memory[:, 0])[candidate] / change[candidate]
        secant = candidate & (w > 0.05) & (w < 1.0)
        out[secant] = np.minimum(t_n_lag + w * (spring - t_n_lag), 0.0)[secant]
    if passes >= LAG_RELAX_AFTER:
        relax = oscillates & ~secant
        out[relax] = (0.5 * (t_n + t_n_lag))[relax]
    write = closed | (not remember_open)
    if remember_open:
        # open in this pass: the memory keeps the contact's last closed pass; one that its
        # own tension opened there and that closes again takes half of its lag back
        back = (~closed & (t_n < 0.0) & (lag_memory[:, 2] != 0.0) & (lag_memory[:, 1] > 0.0)
                & (flips >= REMEMBER_FROM_FLIPS))
        out[back] = np.minimum(0.5 * (lag_memory[:, 0] + lag_memory[:, 1]), 0.0)[back]
    lag_memory[write] = np.column_stack((t_n_lag, spring, closed.astype(float)))[write]
    return out, error


def _why(state, new_state, lag_ok) -> tuple[int, int, int, int]:
    """What a pass found (for :data:`PASS_LOG`): contacts that close, that open, that switch
    between stick and slip, and sliding contacts whose lagged normal force is off."""
    was, now = state != OPEN, new_state != OPEN
    return (int(np.count_nonzero(~was & now)), int(np.count_nonzero(was & ~now)),
            int(np.count_nonzero(was & now & (state != new_state))),
            int(np.count_nonzero(~lag_ok & (state == SLIP))))


def _without_contacts(problem) -> OpenCloseResult:
    el = problem.element
    try:
        k, f = problem.with_bolts(np.zeros((0, 12, 12)), np.zeros((0, 12)))
        d = assemble_and_solve(problem.block_k, problem.block_f, problem.free,
                               *problem.pair_blocks, k, f, problem.d_known, problem.pattern,
                               factor=problem.factor(symmetric=True))
    except SingularSystemError as exc:
        return OpenCloseResult(False, 1, f"singular system: {exc}")
    z = np.zeros(0)
    return OpenCloseResult(True, 1, "", d, np.zeros(0, dtype=np.int8), z, z,
                           {k: v.copy() for k, v in el.contacts.history.items()})


def _start(el, explicit, gap_tol, compiled=False):
    """The step's start: the pulled-back history, the stick springs' forces, the first
    states, and the contacts spared the friction check (legacy's explicit rule).
    ``compiled``: the built-in laws' kernel (:func:`dda.kernels.open_close.step_start`)."""
    c = el.contacts
    m = len(el)
    closed0 = c.state != OPEN
    if compiled:
        with section("return_map"):
            over, history, t_stick = _compiled_start(el)
    else:
        zero = np.zeros(m)
        # pull-back: last step's shear force above the strength is cut back to it here
        _, over, history = el.friction(c.history, zero, c.t_n, where=closed0)
        # the stick springs' force at the step's start, from the pulled-back history (every
        # contact: one that closes during the step starts from its law's initial history)
        t_stick, _ = el.stick(history, zero, where=np.ones(m, dtype=bool))
    state = c.state.copy()
    state[closed0 & over] = SLIP
    # legacy's explicit rule spares only the contacts that start the step sticking
    spared = (state == STICK) if explicit else np.zeros(m, dtype=bool)
    # a contact that starts the step touching or penetrating is first tried closed: started
    # open, a stack of n touching blocks would need n passes to close from the bottom up
    state[(state == OPEN) & (el.gap0 <= gap_tol)] = STICK
    return history, t_stick, state, spared & closed0


def _compiled_start(el):
    """:func:`_start`'s pull-back and stick forces by the kernel: (over, history, t_stick)."""
    c = el.contacts
    hist = kernel_history(c.history, len(el))
    over, g_se, slip, sliding, t_stick = step_start(
        np.asarray(c.state, dtype=np.int8), *el.kernel_laws, *hist,
        as_float64(c.t_n), as_float64(el.shear_penalty), as_float64(el.length))
    return over, kernel_history_dict(c.history, g_se, slip, sliding), t_stick


def _next_states(el, state, history, gap, dgs, t_slip, held, gap_tol):
    """The contact states a pass's solution asks for, and its normal forces."""
    # within round-off of zero a contact keeps its state (open, stick or slip): the gap
    # of two blocks that move alike (a row of bricks) is zero up to noise, and so are its
    # normal force and strength, whose signs would flip the state every pass
    noise = np.abs(gap) <= gap_tol
    closed = (gap < -gap_tol) | (noise & (state != OPEN))
    t_n = np.where(closed, np.minimum(el.judge_stiffness * gap, 0.0), 0.0)
    # a closing contact starts sticking (the return map below may make it slip); one that
    # legacy spares the friction check must not stay open when it closes again after a
    # pass opened it (a slab bounced into its floor by a brick stayed open 1.4 mm deep)
    new_state = np.where(closed, np.where(state == OPEN, STICK, state), OPEN).astype(np.int8)
    check = closed & ~held & ~noise
    t_trial, slipping, _ = el.friction(history, dgs, t_n, where=check)
    # a slip that reverses against the friction load of this pass sticks; a load of zero
    # (its lagged normal force was zero: the contact had opened) has no direction to reverse
    reversed_ = (state == SLIP) & (t_slip != 0.0) & (np.sign(t_trial) != np.sign(t_slip))
    new_state[check] = np.where(slipping[check] & ~reversed_[check], SLIP, STICK)
    return new_state, t_n


_COORDINATE_ROUND_OFF = 64.0 * float(np.finfo(float).eps)


def round_off_gap(element) -> np.ndarray:
    """(m,) the size below which a contact's linearized gap is round-off, not a gap.

    ``GAP_ROUND_OFF`` of the contacted edge's length, or the round-off of the coordinates
    the gap is computed from when those are larger (a scene far from the origin).
    """
    kept = getattr(element, "gap_round_off", None)  # (ContactElement.compiled)
    if kept is not None:
        return kept
    g = element.geometry
    return round_off_gaps(as_float64(g.p1), as_float64(g.p2), as_float64(g.length),
                          GAP_ROUND_OFF, _COORDINATE_ROUND_OFF)


def gap_round_off() -> tuple[float, float]:
    """The relative and absolute round-off of a linearized gap (:func:`round_off_gap`), as
    :meth:`dda.contact.ContactElement.compiled` takes them (read at each call)."""
    return GAP_ROUND_OFF, _COORDINATE_ROUND_OFF


def _unhold_cycling(held, state, proposed):
    """Legacy's explicit rule no longer spares the contacts of a cycle the friction check
    (``held`` is returned, changed or not).

    A contact that unloads in the step (a rocking block's pivot before its other corner
    lands) can open in one pass, where it is free to slide, and close in the next, where its
    stick spring holds it and the block turns up off it: no state is consistent until its
    friction, of a normal force near zero, lets it slide. With an impact dashpot, which lets
    a contact go at zero force, the rocking block of ``tests/validation/test_rocking_block.py``
    cut 8 of 15,000 steps at dt 1e-4 for it; the 13 scenes of the regression baseline never
    reach this rule (their results are the same to the bit with it).
    """
    return held & (proposed == state)
