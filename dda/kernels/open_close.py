"""Compiled OPEN-CLOSE pass of the built-in Coulomb laws (:mod:`dda.solvers.open_close`).

On a small scene a pass of the numpy iteration is some hundred small array operations and three
return maps through the law interface (the 2-block incline of ``benchmarks/small_step.py``:
about 200 us a pass, the linear solve 15 of them). Where every contact's law is a built-in
:class:`dda.contact.CoulombSingle` or :class:`dda.contact.StaticDynamicTransition` (their own
class, not a subclass), a pass is instead two kernel calls around the linear solve:

- :func:`pass_loads`: the friction load of the sliding contacts from the lagged normal force,
  and legacy DDA's springs (:func:`legacy_springs`);
- :func:`pass_judge`: the states the pass's gaps ask for, the lagged-force and cycle rules, the
  settle test with the settle band, and the next pass's lagged normal force.

Both do the arithmetic of the numpy iteration contact by contact in the same order, and the
return maps are the built-in laws' own (:func:`law_trial`, which their ``return_map`` calls
too, through :mod:`dda.kernels.friction`), so the iteration takes the same decisions and gives
the same bits (``tests/test_open_close_kernel.py``
runs scenes both ways). A law written in numpy, or a subclass of a built-in one, keeps the numpy
iteration.

The laws reach the kernels as per-contact numbers: ``kind`` (``COULOMB``, ``TRANSITION`` judged
contact by contact, ``TRANSITION_FACE`` judged by faces), the static and dynamic friction
coefficients, the cohesion, and the key of the face a face-judged contact sums over (faces are
summed within one law, as :class:`dda.contact.element.LawGroups` does; -1 elsewhere).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["COULOMB", "TRANSITION", "TRANSITION_FACE", "round_off_gaps", "law_forces",
           "law_trial", "law_return_map", "law_response", "step_start", "pass_loads", "pass_judge",
           "next_lag_force",
           "legacy_end", "legacy_springs", "kernel_history", "kernel_history_dict",
           "as_float64"]

COULOMB, TRANSITION, TRANSITION_FACE = 0, 1, 2
_OPEN, _STICK, _SLIP = 0, 1, 2

#: the open <-> closed changes of a contact in the step before the lag memory takes it
REMEMBER_FROM_FLIPS = 4

#: what the cycle rule measures a held contact's pull against (``pass_judge``'s
#: ``cycle_measure``): the pass's largest normal force, the largest on the contact's own
#: blocks, or the largest in the contact's group of free blocks that touch
#: (:func:`dda.solvers.open_close.cycle_measure`)
CYCLE_SCENE, CYCLE_BLOCKS, CYCLE_GROUP = 0, 1, 2
#: a contact's ``held_ago`` (:class:`dda.contact.ContactSet`) when it never ended a step held:
#: the count stops there
HELD_NEVER = 2**31 - 1


def kernel_history(history, m):
    """The history arrays the kernels take: ``g_se``, ``slip``, ``sliding`` (zeros where
    no law keeps it), float64 and contiguous."""
    sliding = history.get("sliding")
    return tuple(np.ascontiguousarray(a, dtype=np.float64) for a in (
        history["g_se"], history["slip"], np.zeros(m) if sliding is None else sliding))


def kernel_history_dict(history, g_se, slip, sliding) -> dict:
    """The history dict of the kernels' arrays, with the fields ``history`` has."""
    out = {"g_se": g_se, "slip": slip}
    if "sliding" in history:
        out["sliding"] = sliding
    return out


def as_float64(a):
    """``a`` as the kernels take it: float64, contiguous (a view when it already is)."""
    return np.ascontiguousarray(a, dtype=np.float64)


@njit(cache=True, inline="always")
def _np_min(a, b):
    """``numpy.minimum`` of two floats (which keeps the second on a tie: -0.0 against 0.0)."""
    return a if (a < b or a != a) else b


@njit(cache=True, inline="always")
def _np_max(a, b):
    """``numpy.maximum`` of two floats."""
    return a if (a > b or a != a) else b


@njit(cache=True)
def round_off_gaps(p1, p2, length, relative, absolute):
    """(m,) ``max(relative l, absolute max(|p1|, |p2|))``: the round-off of a contact's
    linearized gap (:func:`dda.solvers.open_close.round_off_gap`), with ``max(|p|)`` over
    both coordinates of the vertex ``p1`` and the edge's start ``p2``."""
    m = length.shape[0]
    out = np.empty(m)
    for i in range(m):
        a = _np_max(abs(p1[i, 0]), abs(p1[i, 1]))
        b = _np_max(abs(p2[i, 0]), abs(p2[i, 1]))
        out[i] = _np_max(relative * length[i], absolute * _np_max(a, b))
    return out


@njit(cache=True)
def law_forces(kind, mu_s, mu_d, cohesion, face, g_se, sliding, dgs, t_n, ps, length, where):
    """Shear force and slipping flag of the return map of every contact in ``where`` (zero
    force and not slipping elsewhere): :func:`law_trial` without the trial force."""
    t_s, slipping, _, _ = law_trial(kind, mu_s, mu_d, cohesion, face, g_se, sliding, dgs, t_n,
                                    ps, length, where)
    return t_s, slipping


@njit(cache=True)
def law_trial(kind, mu_s, mu_d, cohesion, face, g_se, sliding, dgs, t_n, ps, length, where):
    """Shear force, slipping flag, trial force ``p_s (g_se + dg_s)`` and the strength it was
    checked against, of the return map of every contact in ``where`` (zeros elsewhere), from
    its committed ``g_se`` (and ``sliding``, the transition law's history). The built-in laws'
    one implementation: their own return maps (:mod:`dda.kernels.friction`) come here too.

    ``COULOMB``: ``S = c l_c + max(-t_n, 0) tan(phi)``, a trial ``p_s (g_se + dg_s)`` above
    it returned to it (:class:`dda.contact.CoulombSingle`). ``TRANSITION``: the
    check against ``|t_n| tan(phi_d)`` for a contact sliding at the step's start, else
    ``|t_n| tan(phi_s)``, a slip returned to ``|t_n| tan(phi_d)``; ``TRANSITION_FACE``: a
    sticking contact slips when its face's summed trial force exceeds the face's summed
    strength, over the face's contacts in ``where`` (:class:`dda.contact.StaticDynamicTransition`;
    a sliding contact's force counts at most its dynamic strength).
    """
    m = dgs.shape[0]
    t_s = np.zeros(m)
    slipping = np.zeros(m, dtype=np.bool_)
    t_trial = np.zeros(m)
    strength = np.zeros(m)
    dynamic = np.zeros(m)
    n_faces = 0
    for i in range(m):
        if not where[i]:
            continue
        t_trial[i] = ps[i] * (g_se[i] + dgs[i])
        if kind[i] == COULOMB:
            strength[i] = cohesion[i] * length[i] + max(-t_n[i], 0.0) * mu_s[i]
            dynamic[i] = strength[i]
        else:
            pressure = max(-t_n[i], 0.0)
            dynamic[i] = pressure * mu_d[i]
            strength[i] = dynamic[i] if sliding[i] > 0.5 else pressure * mu_s[i]
            if kind[i] == TRANSITION_FACE:
                n_faces = max(n_faces, face[i] + 1)
    carried = np.zeros(n_faces)
    held = np.zeros(n_faces)
    if n_faces:
        for i in range(m):
            if where[i] and kind[i] == TRANSITION_FACE:
                c = t_trial[i]
                if sliding[i] > 0.5:
                    c = min(max(c, -dynamic[i]), dynamic[i])
                carried[face[i]] += c
                held[face[i]] += strength[i]
    for i in range(m):
        if not where[i]:
            continue
        if kind[i] == TRANSITION_FACE and not sliding[i] > 0.5:
            slipping[i] = abs(carried[face[i]]) > held[face[i]]
        elif kind[i] == TRANSITION_FACE:
            slipping[i] = abs(t_trial[i]) > dynamic[i]
        else:
            slipping[i] = abs(t_trial[i]) > strength[i]
        t_s[i] = dynamic[i] * np.sign(t_trial[i]) if slipping[i] else t_trial[i]
    return t_s, slipping, t_trial, strength


@njit(cache=True)
def _trial_history(i, t_s, slipping, t_trial, kind, ps, slip, g_out, slip_out, sliding_out):
    """Contact ``i``'s history after its return map (:meth:`CoulombLike._numpy_return_map`):
    ``g_se = t_s / p_s``, ``slip += |t_tr - t_s| / p_s``, and the transition law's
    ``sliding`` flag."""
    g_out[i] = t_s[i] / ps[i]
    slip_out[i] = slip[i] + abs(t_trial[i] - t_s[i]) / ps[i]
    if kind[i] != COULOMB:
        sliding_out[i] = 1.0 if slipping[i] else 0.0


@njit(cache=True)
def law_return_map(kind, mu_s, mu_d, cohesion, face, g_se, slip, sliding, dgs, t_n, ps,
                   length):
    """The return map of every contact with its trial history: ``(t_s, slipping, strength,
    g_se, slip)`` (:meth:`CoulombLike._numpy_return_map`'s, to the bit)."""
    m = dgs.shape[0]
    where = np.ones(m, dtype=np.bool_)
    t_s, slipping, t_trial, strength = law_trial(kind, mu_s, mu_d, cohesion, face, g_se,
                                                 sliding, dgs, t_n, ps, length, where)
    g_out, slip_out, sliding_out = np.empty(m), np.empty(m), np.empty(m)
    for i in range(m):
        _trial_history(i, t_s, slipping, t_trial, kind, ps, slip, g_out, slip_out,
                       sliding_out)
    return t_s, slipping, strength, g_out, slip_out


@njit(cache=True)
def law_response(kind, mu_s, mu_d, cohesion, face, g_se, slip, sliding, dgs, t_n, ps, pn,
                 length, where):
    """The return map of the contacts in ``where`` with the trial history and the consistent
    tangent (:meth:`dda.contact.element.LawGroups.return_map` with ``normal_penalty``):
    ``(t_s, slipping, g_se, slip, sliding, dt_s/dg_s, dt_s/dg_n)``; the others keep their
    history, with zero force and tangent. The tangent is :meth:`CoulombLike.tangent`'s:
    ``p_s`` sticking; ``-p_n mu_d sign(t_s)`` against the normal gap sliding (``mu_d`` the
    sliding strength's slope, Coulomb's one angle)."""
    m = dgs.shape[0]
    t_s, slipping, t_trial, _ = law_trial(kind, mu_s, mu_d, cohesion, face, g_se, sliding,
                                          dgs, t_n, ps, length, where)
    g_out, slip_out, sliding_out = g_se.copy(), slip.copy(), sliding.copy()
    kss = np.zeros(m)
    ksn = np.zeros(m)
    for i in range(m):
        if not where[i]:
            continue
        _trial_history(i, t_s, slipping, t_trial, kind, ps, slip, g_out, slip_out,
                       sliding_out)
        if slipping[i]:
            slope = mu_s[i] if kind[i] == COULOMB else mu_d[i]
            ksn[i] = -pn[i] * slope * np.sign(t_s[i])
        else:
            kss[i] = ps[i]
    return t_s, slipping, g_out, slip_out, sliding_out, kss, ksn


@njit(cache=True)
def contact_response(kind, mu_s, mu_d, cohesion, face, g_se, slip, sliding, gap, shear, shear0,
                     release, has_dashpot, kn, pn, ps, length, e_row, i_row, held):
    """The fully implicit method's contact response around the return map
    (:meth:`dda.contact.ContactElement.response`), element by element as its numpy
    expressions: the judged gap ``g_n - release`` (``g_n`` without a dashpot), closed where
    negative, its normal force ``k_n`` times it, the shear increment ``g_s - g_s0``,
    :func:`law_response` on the closed contacts, the residual rows ``t_n E + t_s I`` and the
    spring's own force ``min(p_n g_n, 0)``. The contacts of ``held`` are closed whatever the
    gap (a pull ``k_n g > 0`` where it is open, and no normal-shear coupling there).

    Returns ``(closed, slipping and closed, spring force, t_s, g_se, slip, sliding,
    dt_s/dg_s, dt_s/dg_n, t_n, residual)``."""
    m = gap.shape[0]
    closed = np.empty(m, dtype=np.bool_)
    t_n = np.empty(m)
    dgs = np.empty(m)
    for i in range(m):
        judged = gap[i] - release[i] if has_dashpot else gap[i]
        closed[i] = judged < 0.0 or held[i]
        t_n[i] = kn[i] * judged if closed[i] else 0.0
        dgs[i] = shear[i] - shear0[i]
    t_s, slipping, g_out, slip_out, sliding_out, kss, ksn = law_response(
        kind, mu_s, mu_d, cohesion, face, g_se, slip, sliding, dgs, t_n, ps, kn, length, closed)
    for i in range(m):
        if t_n[i] > 0.0:  # a held contact in tension: its strength does not change with g_n
            ksn[i] = 0.0
    residual = np.empty((m, e_row.shape[1]))
    spring = np.empty(m)
    slipping_closed = np.empty(m, dtype=np.bool_)
    for i in range(m):
        for j in range(e_row.shape[1]):
            residual[i, j] = t_n[i] * e_row[i, j] + t_s[i] * i_row[i, j]
        if has_dashpot:
            spring[i] = _np_min(pn[i] * gap[i], 0.0) if closed[i] else 0.0
        else:
            spring[i] = _np_min(t_n[i], 0.0)
        slipping_closed[i] = slipping[i] and closed[i]
    return (closed, slipping_closed, spring, t_s, g_out, slip_out, sliding_out, kss, ksn, t_n,
            residual)


@njit(cache=True)
def step_start(state, kind, mu_s, mu_d, cohesion, face, g_se, slip, sliding, t_n, ps,
               length):
    """The pull-back at a step's start: the return map, with no increment, of every contact
    closed at the last step's end. Returns which of those exceed their strength and the
    pulled-back history ``(g_se, slip, sliding)`` (the others' copied), and every contact's
    stick spring force ``p_s g_se`` from it (:func:`dda.solvers.open_close._start`)."""
    m = state.shape[0]
    closed = np.empty(m, dtype=np.bool_)
    for i in range(m):
        closed[i] = state[i] != _OPEN
    zero = np.zeros(m)
    t_s, over, t_trial, _ = law_trial(kind, mu_s, mu_d, cohesion, face, g_se, sliding, zero,
                                      t_n, ps, length, closed)
    g_out, slip_out, sliding_out = g_se.copy(), slip.copy(), sliding.copy()
    t_stick = np.empty(m)
    for i in range(m):
        if closed[i]:
            _trial_history(i, t_s, over, t_trial, kind, ps, slip, g_out, slip_out,
                           sliding_out)
        t_stick[i] = ps[i] * (g_out[i] + zero[i])
    return over, g_out, slip_out, sliding_out, t_stick


@njit(cache=True)
def legacy_end(state, gap, dgs, kind, mu_s, mu_d, cohesion, face, g_se, slip, sliding, pn,
               ps, length):
    """Legacy DDA's end of a step (:meth:`dda.contact.ContactElement.legacy_trial` and
    ``trial_contacts``): normal forces ``min(p_n g_n, 0)`` of the closed contacts; a sticking
    contact keeps its spring, ``t_s = p_s (g_se + dg_s)``; a sliding one is returned to its
    strength (the return map judged over every closed contact); an open one gets the initial
    history (zeros). Returns ``(t_n, t_s, g_se, slip, sliding)``; the ``sliding`` of a
    Coulomb contact, which has none, is passed through."""
    m = state.shape[0]
    closed = np.empty(m, dtype=np.bool_)
    t_n = np.zeros(m)
    for i in range(m):
        closed[i] = state[i] != _OPEN
        if closed[i]:
            t_n[i] = _np_min(pn[i] * gap[i], 0.0)
    t_map, slipping, t_trial, _ = law_trial(kind, mu_s, mu_d, cohesion, face, g_se, sliding,
                                            dgs, t_n, ps, length, closed)
    g_out, slip_out, sliding_out = g_se.copy(), slip.copy(), sliding.copy()
    t_s = np.empty(m)
    for i in range(m):
        t_stick = 0.0
        t_slip = 0.0
        if state[i] == _STICK:
            g_out[i] = g_se[i] + dgs[i]
            t_stick = ps[i] * g_out[i]
            if kind[i] != COULOMB:
                sliding_out[i] = 0.0
        elif state[i] == _SLIP:
            _trial_history(i, t_map, slipping, t_trial, kind, ps, slip, g_out, slip_out,
                           sliding_out)
            t_slip = t_map[i]
        else:
            g_out[i] = 0.0
            slip_out[i] = 0.0
            if kind[i] != COULOMB:
                sliding_out[i] = 0.0
        t_s[i] = t_stick + t_slip
    return t_n, t_s, g_out, slip_out, sliding_out


@njit(cache=True)
def pass_loads(state, kind, mu_s, mu_d, cohesion, face, g_se, sliding, dgs_prev, t_n_lag, ps,
               length, gap0, pn, t_stick, e_row, i_row):
    """A pass's friction loads and springs: ``t_slip`` (the return map's force of the sliding
    contacts from the last pass's shear increment and the lagged normal force, evaluated on
    every closed contact as the numpy iteration does), and legacy DDA's spring weights and
    forces (:func:`legacy_springs`)."""
    m = state.shape[0]
    closed = np.empty(m, dtype=np.bool_)
    for i in range(m):
        closed[i] = state[i] != _OPEN
    t_s, _ = law_forces(kind, mu_s, mu_d, cohesion, face, g_se, sliding, dgs_prev, t_n_lag,
                        ps, length, closed)
    t_slip = np.zeros(m)
    for i in range(m):
        if state[i] == _SLIP:
            t_slip[i] = t_s[i]
    weights, force = legacy_springs(state, gap0, pn, ps, t_stick, t_slip, e_row, i_row)
    return t_slip, weights, force


@njit(cache=True)
def pass_judge(state, held, gap, dgs, t_slip, t_n_lag, lag_error, lag_memory, flips, pinned,
               calm, gap_tol, pn, ps, length, kind, mu_s, mu_d, cohesion, face, g_se, sliding,
               bj, bk, free, settle_friction, band, passes, rtol, floor, cycle_tension,
               relax_after, patience, secant_from, remember_open, cycle_measure, own_measure,
               shear):
    """Judge one pass (:func:`dda.solvers.open_close.open_close`'s rules, in its order).

    Returns ``(new_state, t_n, done, friction_settled, next_t_n_lag, lag_error, lag_ok)``: the
    states the pass asks for (after the cycle rule), its normal forces, whether the iteration
    has settled, whether the stick and slip states settled too, the lagged normal force of the
    next pass with this pass's lag error, and which contacts' lagged force counts as settled.
    ``flips``, ``pinned``, ``calm`` (a 1-element count of the passes in a row that changed no
    contact between open and closed) and ``lag_memory`` (:func:`next_lag_force`, which takes
    ``relax_after``, ``secant_from`` and ``remember_open``) change in place. The cycle rule's
    limit is ``cycle_tension`` of the largest normal force in the contact's group of touching
    free blocks (``cycle_measure`` ``CYCLE_GROUP``, legacy DDA's default: :func:`_group_force`),
    on its own blocks (``CYCLE_BLOCKS``: :func:`_local_force`) or in the pass (``CYCLE_SCENE``:
    the fully implicit method's predictor, whose iterations judge every contact again); under
    ``CYCLE_GROUP`` a contact whose ``own_measure`` (m,) is True is measured on its own blocks
    (a contact held at the end of one of its last steps: :func:`own_measures`), each contact's
    force there ``hypot(t_n, shear)`` with ``shear`` (m,) the contacts' committed shear forces
    (a cohesive contact carries its block in shear at no normal force; under ``CYCLE_BLOCKS``
    the normal forces alone); the lagged force's floor ``floor`` is the group's under the first
    two, the pass's under the third; the iteration has settled, its friction not, once ``calm``
    reaches ``patience`` (0: never), whatever the friction and lagged forces
    (:func:`dda.solvers.open_close.predictor_patience`).
    """
    m = state.shape[0]
    new_state = np.empty(m, dtype=np.int8)
    t_n = np.empty(m)
    check = np.empty(m, dtype=np.bool_)
    # the states the pass's gaps ask for; within round-off of zero a contact keeps its state
    for i in range(m):
        noise = abs(gap[i]) <= gap_tol[i]
        closed = gap[i] < -gap_tol[i] or (noise and state[i] != _OPEN)
        if closed:
            t_n[i] = _np_min(pn[i] * gap[i], 0.0)
            new_state[i] = _STICK if state[i] == _OPEN else state[i]
        else:
            t_n[i] = 0.0
            new_state[i] = _OPEN
        check[i] = closed and not held[i] and not noise
    t_ret, slipping = law_forces(kind, mu_s, mu_d, cohesion, face, g_se, sliding, dgs, t_n,
                                 ps, length, check)
    for i in range(m):
        if check[i]:
            # a slip that reverses against the friction load of this pass sticks (a load of
            # zero, from a lagged normal force of zero, has no direction to reverse)
            reversed_ = (state[i] == _SLIP and t_slip[i] != 0.0
                         and np.sign(t_ret[i]) != np.sign(t_slip[i]))
            new_state[i] = _SLIP if slipping[i] and not reversed_ else _STICK
    # the lagged normal force, and the cycle rule
    largest = 0.0
    cycling = False  # a contact that the cycle rule may hold
    local = np.zeros(0)  # its limit per contact, measured on blocks or groups
    for i in range(m):
        largest = _np_max(largest, abs(t_n[i]))
        cycling = cycling or (flips[i] >= 2 and state[i] != _OPEN and new_state[i] == _OPEN)
    group = np.zeros(0)  # the largest normal force in each contact's group
    if cycle_measure != CYCLE_SCENE:
        group = _group_force(t_n, state, bj, bk, free, 1.0)
        if cycling:
            if cycle_measure == CYCLE_GROUP:
                local = cycle_tension * group
                if own_measure.any():
                    own = _local_force(np.hypot(t_n, shear), bj, bk, free, cycle_tension)
                    for i in range(m):
                        if own_measure[i]:
                            local[i] = own[i]
            else:
                local = _local_force(t_n, bj, bk, free, cycle_tension)
    lag_ok = np.empty(m, dtype=np.bool_)
    for i in range(m):
        lag_ok[i] = abs(t_n[i] - t_n_lag[i]) <= rtol * _np_max(
            abs(t_n[i]), abs(t_n_lag[i])) + floor * (
                largest if cycle_measure == CYCLE_SCENE else group[i])
        if (cycling and flips[i] >= 2 and state[i] != _OPEN and new_state[i] == _OPEN
                and pn[i] * gap[i] <= (cycle_tension * largest if cycle_measure == CYCLE_SCENE
                                       else local[i])):
            new_state[i] = state[i]
            pinned[i] = True
        lag_ok[i] = lag_ok[i] or (pinned[i] and gap[i] >= 0.0)
        if (state[i] != _OPEN) != (new_state[i] != _OPEN):
            flips[i] += 1
    settled = True
    friction_settled = True
    same_contact = True  # no contact changed between open and closed
    for i in range(m):
        if new_state[i] != state[i]:
            friction_settled = False
        same_contact = same_contact and (new_state[i] != _OPEN) == (state[i] != _OPEN)
        if settle_friction:
            settled = settled and new_state[i] == state[i]
    if not settle_friction:
        settled = same_contact
    calm[0] = calm[0] + 1 if same_contact else 0
    lag_settled = _lag_all(lag_ok, state)
    if band != 0.0 and not (settled and lag_settled):
        local = _local_force(t_n, bj, bk, free, band)
        for i in range(m):
            lag_ok[i] = lag_ok[i] or _np_max(abs(t_n[i]), abs(t_n_lag[i])) <= local[i]
        if not settled:
            settled = _negligible(state, new_state, gap, dgs, t_n, t_slip, pn, ps, length,
                                  kind, mu_s, mu_d, cohesion, face, g_se, sliding,
                                  settle_friction, local)
        lag_settled = _lag_all(lag_ok, state)
    done = settled and lag_settled
    if not done and patience > 0 and calm[0] >= patience:
        done = True
        friction_settled = False
    next_lag, error = next_lag_force(state, gap, pn, t_n, t_n_lag, lag_error, lag_memory,
                                     passes, relax_after, secant_from, remember_open, flips)
    return new_state, t_n, done, friction_settled, next_lag, error, lag_ok


@njit(cache=True)
def next_lag_force(state, gap, pn, t_n, t_n_lag, lag_error, lag_memory, passes, relax_after,
                   secant_from, remember_open, flips):
    """The lagged normal force of the next pass and this pass's lag error ``N - N_lag``
    (:func:`dda.solvers.open_close.next_lag` is the same rule in numpy, the reference).

    A contact's own normal force ``N``, but where the error changed sign since the last pass
    (an oscillation): from pass ``secant_from`` on (0: never), on a contact closed in this pass
    and the last, the secant step ``N_lag + w (p_n g - N_lag)``, ``w = -(N_lag - N_lag') /
    (e - e')`` with ``e = p_n g - N_lag`` (the spring force less the lagged force, a tension
    not cut off; primes: the last pass), capped at zero, when ``0.05 < w < 1``; from pass
    ``relax_after`` on, otherwise, the mean ``(N + N_lag) / 2``. ``lag_memory`` (m, 3) holds
    each contact's lagged force, spring force and closed flag (1.0) of the last pass, and is
    updated in place. With ``remember_open`` (the fully implicit predictor) an open pass leaves
    the memory as its last closed pass left it, and a contact open in this pass that closes
    again, whose ``flips`` (open <-> closed changes in the step) reach ``REMEMBER_FROM_FLIPS``
    and whose last closed pass's spring pulled, takes ``min((N_lag + p_n g) / 2, 0)`` of that
    pass.
    """
    m = t_n.shape[0]
    next_lag = t_n.copy()
    error = np.empty(m)
    for i in range(m):
        error[i] = t_n[i] - t_n_lag[i]
        spring = pn[i] * gap[i]
        closed = state[i] != _OPEN
        oscillates = error[i] * lag_error[i] < 0.0
        secant = False
        if (oscillates and secant_from > 0 and passes >= secant_from and closed
                and lag_memory[i, 2] != 0.0):
            change = (spring - t_n_lag[i]) - (lag_memory[i, 1] - lag_memory[i, 0])
            if change != 0.0:
                w = -(t_n_lag[i] - lag_memory[i, 0]) / change
                if 0.05 < w < 1.0:
                    next_lag[i] = _np_min(t_n_lag[i] + w * (spring - t_n_lag[i]), 0.0)
                    secant = True
        if not secant and oscillates and passes >= relax_after:
            next_lag[i] = 0.5 * (t_n[i] + t_n_lag[i])
        if remember_open and not closed:
            # open in this pass: the memory keeps the contact's last closed pass; one that
            # its own tension opened there and that closes again takes half of its lag back
            if (t_n[i] < 0.0 and lag_memory[i, 2] != 0.0 and lag_memory[i, 1] > 0.0
                    and flips[i] >= REMEMBER_FROM_FLIPS):
                next_lag[i] = _np_min(0.5 * (lag_memory[i, 0] + lag_memory[i, 1]), 0.0)
            continue
        lag_memory[i, 0] = t_n_lag[i]
        lag_memory[i, 1] = spring
        lag_memory[i, 2] = 1.0 if closed else 0.0
    return next_lag, error


@njit(cache=True)
def _lag_all(lag_ok, state):
    for i in range(state.shape[0]):
        if not (lag_ok[i] or state[i] != _SLIP):
            return False
    return True


@njit(cache=True)
def own_measures(state, t_n, held_ago, memory):
    """(m,) the contacts whose cycle limit legacy DDA measures on their own blocks under
    ``CYCLE_GROUP``: those held at the end of one of their last ``memory`` steps, as the
    committed ``state``, normal forces ``t_n`` and step counts ``held_ago`` (of the step
    that committed them: :attr:`dda.contact.ContactSet.held_ago`) say, and the counts
    carried to the next step (:func:`dda.contact.contacts.held_ago`): returns
    ``(own, ago)``."""
    m = state.shape[0]
    own = np.zeros(m, dtype=np.bool_)
    ago = np.empty(m, dtype=np.int64)
    for i in range(m):
        if state[i] != _OPEN and t_n[i] == 0.0:
            ago[i] = 1
        else:
            ago[i] = _np_min(held_ago[i], HELD_NEVER - 1) + 1
        own[i] = ago[i] <= memory
    return own, ago


@njit(cache=True)
def _local_force(t_n, bj, bk, free, band):
    """``band`` times the largest normal force (or other force ``t_n``) on either block of
    each contact, the smaller of the two (a block whose motion is known does not count)."""
    largest = np.zeros(free.shape[0])
    for i in range(t_n.shape[0]):
        largest[bj[i]] = _np_max(largest[bj[i]], abs(t_n[i]))
    for i in range(t_n.shape[0]):
        largest[bk[i]] = _np_max(largest[bk[i]], abs(t_n[i]))
    for b in range(free.shape[0]):
        if not free[b]:
            largest[b] = np.inf
    local = np.empty(t_n.shape[0])
    for i in range(t_n.shape[0]):
        local[i] = band * _np_min(largest[bj[i]], largest[bk[i]])
    return local


@njit(cache=True)
def _group_root(parent, b):
    """The root of block ``b``'s group in the union-find forest ``parent`` (paths halved on
    the way)."""
    while parent[b] != b:
        parent[b] = parent[parent[b]]
        b = parent[b]
    return b


@njit(cache=True)
def _group_force(t_n, state, bj, bk, free, band):
    """``band`` times the largest normal force in each contact's group: the free blocks
    joined through contacts closed in ``state`` between two free blocks (a block whose motion
    is known joins none; a contact between two groups takes the smaller of their forces).
    Where every free block touches the others it is the pass's largest normal force; a block
    that touches only fixed ones is measured on its own. Each block's group is found by
    union-find, in one sweep of the contacts and one of the blocks."""
    nb = free.shape[0]
    m = t_n.shape[0]
    parent = np.arange(nb)
    for i in range(m):
        if state[i] != _OPEN and free[bj[i]] and free[bk[i]]:
            a, b = _group_root(parent, bj[i]), _group_root(parent, bk[i])
            if a != b:
                parent[a] = b
    root = np.empty(nb, dtype=np.int64)
    for b in range(nb):
        root[b] = _group_root(parent, b)
    largest = np.zeros(nb)
    for i in range(m):
        if free[bj[i]]:
            largest[root[bj[i]]] = _np_max(largest[root[bj[i]]], abs(t_n[i]))
        if free[bk[i]]:
            largest[root[bk[i]]] = _np_max(largest[root[bk[i]]], abs(t_n[i]))
    local = np.empty(m)
    for i in range(m):
        fj = largest[root[bj[i]]] if free[bj[i]] else np.inf
        fk = largest[root[bk[i]]] if free[bk[i]] else np.inf
        local[i] = band * _np_min(fj, fk)
    return local


@njit(cache=True)
def _negligible(state, new_state, gap, dgs, t_n, t_slip, pn, ps, length, kind, mu_s, mu_d,
                cohesion, face, g_se, sliding, settle_friction, limit):
    """Every changed contact moved less force than ``limit`` (the numpy iteration's
    ``_negligible_changes``)."""
    m = state.shape[0]
    changed = np.zeros(m, dtype=np.bool_)
    switched = np.zeros(m, dtype=np.bool_)
    any_switched = False
    for i in range(m):
        was, now = state[i] != _OPEN, new_state[i] != _OPEN
        changed[i] = (new_state[i] != state[i]) if settle_friction else (was != now)
        switched[i] = changed[i] and was and now
        any_switched = any_switched or switched[i]
    t_map = np.zeros(m)
    if any_switched:
        t_map, _ = law_forces(kind, mu_s, mu_d, cohesion, face, g_se, sliding, dgs, t_n, ps,
                              length, switched)
    for i in range(m):
        if not changed[i]:
            continue
        if switched[i]:
            used = ps[i] * (g_se[i] + dgs[i]) if state[i] == _STICK else t_slip[i]
            error = abs(used - t_map[i])
        else:
            error = pn[i] * abs(gap[i])
        if not error <= limit[i]:
            return False
    return True


@njit(cache=True)
def legacy_springs(state, gap0, normal_penalty, shear_penalty, t_stick, t_slip, e_row, i_row):
    """Legacy DDA's springs of every contact (state 0 open, 1 stick, 2 slip): the weights
    ``(k_n, k_s)`` of ``k_n E^T E + k_s I^T I`` and the force
    ``-(k_n g_n0 E + t_s I)`` with ``t_s`` the stick spring's force or the friction load
    (:meth:`dda.contact.ContactElement.legacy_contributions`, the same arithmetic)."""
    m = state.shape[0]
    weights = np.empty((m, 2))
    force = np.empty((m, 12))
    for c in range(m):
        kn = normal_penalty[c] if state[c] != 0 else 0.0
        ks = shear_penalty[c] if state[c] == 1 else 0.0
        weights[c, 0] = kn
        weights[c, 1] = ks
        fn = kn * gap0[c]
        fs = (t_stick[c] if state[c] == 1 else 0.0) + (t_slip[c] if state[c] == 2 else 0.0)
        for j in range(12):
            force[c, j] = -(fn * e_row[c, j] + fs * i_row[c, j])
    return weights, force
