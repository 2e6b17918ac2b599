"""A small scene's whole OPEN-CLOSE iteration in one kernel call (:mod:`dda.solvers.open_close`).

On a scene whose system is solved dense (up to ``dda.solvers.linear.DENSE_LIMIT`` unknowns) a
pass of the compiled iteration is a dozen Python-level calls around three kernels: the friction
loads and springs (:func:`dda.kernels.open_close.pass_loads`), the impact dashpots, the dense
matrix and right-hand side (:func:`dda.kernels.assembly.matrix_data`, :func:`rhs_data`), numpy's
LAPACK solve, the linearized gaps ``g = g_0 + E d`` and shear increments ``I d``, and the judge
(:func:`dda.kernels.open_close.pass_judge`); on the 2-block incline of
``benchmarks/small_step.py`` their glue cost more than their arithmetic. :func:`dense_passes`
runs every pass of the iteration, with the same rules in the same order:

    K(s) d = F(s)                 (the pass's springs and loads for the states s)
    g = g_0 + E d,   dg_s = I d   (linearized at the step's start)
    s' = judge(s, g - g_rel, dg_s), settled?  else s <- s' (or one switch on a cycle)

and stops when the judge says the states have settled, or after ``max_passes``.

It takes the same decisions as the composed iteration and its numbers agree to round-off, not
to the bit: numba's LAPACK solve and the gaps' sums of 12 products are not numpy's (numpy's
``einsum`` sums them in an order a loop cannot repeat). ``tests/test_dense_passes.py`` runs
steps both ways.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from dda.kernels.assembly import matrix_data, rhs_data
from dda.kernels.dashpot import add_dashpot
from dda.kernels.kinematics import pair_increments
from dda.kernels.open_close import _np_min, legacy_end, pass_judge, pass_loads, step_start

__all__ = ["dense_passes", "first_states", "legacy_dense_step", "rows_equal", "single_switch",
           "solve_dense", "CONVERGED", "NOT_SETTLED", "SINGULAR", "NOT_FINITE"]

CONVERGED, NOT_SETTLED, SINGULAR, NOT_FINITE = 0, 1, 2, 3


@njit(cache=True)
def solve_dense(data, n, rhs, keep, reduced):
    """The free blocks' increments (n,) of the dense system ``data`` (n x n, row major),
    restricted to the unknowns ``keep`` when ``reduced``; (solution, status)."""
    k = data.reshape(n, n)
    if reduced:
        k = k[keep][:, keep]
        b = rhs[keep]
    else:
        b = rhs
    out = np.zeros(n)
    try:
        sol = np.linalg.solve(k, b)
    except Exception:  # noqa: BLE001 (numba raises LinAlgError for a singular matrix)
        return out, SINGULAR
    for i in range(sol.shape[0]):
        if not np.isfinite(sol[i]):
            return out, NOT_FINITE
    if reduced:
        for i in range(keep.shape[0]):
            out[keep[i]] = sol[i]
    else:
        out[:] = sol
    return out, CONVERGED


@njit(cache=True)
def rows_equal(a, b):
    """Whether the int8 rows ``a`` and ``b`` (one contact state each) are the same."""
    for i in range(a.shape[0]):
        if a[i] != b[i]:
            return False
    return True


@njit(cache=True)
def _seen(seen, count, state):
    """Whether ``state`` is one of the first ``count`` rows of ``seen``."""
    for r in range(count):
        if rows_equal(seen[r], state):
            return True
    return False


@njit(cache=True)
def single_switch(state, proposed, gap):
    """Break an OPEN-CLOSE cycle: change only the contact whose gap is the most violated.

    When switching every inconsistent contact at once brings back a state already tried (a
    block that bounces off a stiff contact and falls back into it), changing one contact at a
    time is an active-set step that does not cycle. The violation is the gap of an opening
    contact, minus the gap of a closing one, 0 for a stick / slip switch; of equal ones the
    first changes (``numpy.argmax``'s rule). Both OPEN-CLOSE paths use it.
    """
    pick = -1
    best = 0.0
    for i in range(state.shape[0]):
        if proposed[i] == state[i]:
            continue
        v = 0.0
        if proposed[i] == 0:  # opening
            v += gap[i]
        if state[i] == 0:  # closing
            v += -gap[i]
        if pick < 0 or v > best:
            pick, best = i, v
    out = state.copy()
    out[pick] = proposed[pick]
    return out


@njit(cache=True)
def dense_passes(max_passes, settle_friction, band, rtol, floor, cycle_tension, relax_after,
                 patience, secant_from, remember_open, cycle_measure, own_measure, shear, block_k,
                 block_f, d_known, n, block_base, block_step, free_blocks, pair_base, pair_step,
                 side_row, side_block, keep, reduced, rows, terms, bj, bk, free, e_row, i_row, gap0,
                 pn, ps, kn, length, has_dashpot, dashpot, reference, release, kind, mu_s, mu_d,
                 cohesion, face, g_se, sliding, t_stick, state, held, gap_tol, t_n_lag):
    """Every pass of one step's OPEN-CLOSE iteration on a dense system (module docstring).

    Parameters
    ----------
    max_passes : passes allowed
    settle_friction, band, rtol, floor, cycle_tension, relax_after, patience, secant_from,
    remember_open, cycle_measure, own_measure, shear :
        the iteration's rules (:func:`dda.kernels.open_close.pass_judge`; ``secant_from`` 0,
        ``remember_open`` True and ``cycle_measure`` ``CYCLE_SCENE`` for the fully implicit
        method's predictor, legacy DDA's ``LAG_SECANT_FROM``, False and its own measure, with
        the contacts it measures on their own blocks and the committed shear forces)
    block_k, block_f, d_known : the step's block matrices, forces and known increments
    n, block_base, block_step, free_blocks, pair_base, pair_step, side_row, side_block :
        the dense layout of :class:`dda.solvers.linear.SystemPattern`
    keep, reduced : the unknowns solved for (rigid blocks' strains left out) when ``reduced``
    rows, terms : legacy DDA's spring rows [E, I] (m, 2, 12) and their terms
    bj, bk, free : the contacts' blocks; the blocks with unknowns
    e_row, i_row, gap0, pn, ps, kn, length : the contacts' linearization, penalties, the
        stiffness the judge uses and the edges' lengths
    has_dashpot, dashpot, reference, release : impact dashpots (``c / dt``), the gap their rate
        is measured from, and the gap at which a contact lets go
    kind, mu_s, mu_d, cohesion, face : the built-in laws per contact
    g_se, sliding, t_stick : the pulled-back history and the stick springs' forces
    state, held, gap_tol, t_n_lag : the first pass's states, the contacts spared the friction
        check, the round-off of the gaps, the first lagged normal forces

    Returns
    -------
    status : CONVERGED, NOT_SETTLED (after ``max_passes``), SINGULAR or NOT_FINITE
    passes : the passes taken
    d : (n_blocks, 6) the last pass's increments
    new_state : (m,) int8 the states the last pass settled on
    gap, dgs : (m,) its linearized gaps and shear increments
    friction_settled : the stick and slip states settled too
    """
    m = state.shape[0]
    state = state.copy()
    held = held.copy()
    t_n_lag = t_n_lag.copy()
    dgs_prev = np.zeros(m)
    flips = np.zeros(m, dtype=np.int64)
    pinned = np.zeros(m, dtype=np.bool_)
    calm = np.zeros(1, dtype=np.int64)
    lag_error = np.zeros(m)
    lag_memory = np.zeros((m, 3))
    seen = np.empty((max_passes + 1, m), dtype=np.int8)
    seen[0] = state
    n_seen = np.int64(1)
    d = d_known.copy()
    gap = np.zeros(m)
    dgs = np.zeros(m)
    judged = np.zeros(m)
    nf = free_blocks.shape[0]
    for passes in range(1, max_passes + 1):
        t_slip, weights, force = pass_loads(state, kind, mu_s, mu_d, cohesion, face, g_se,
                                            sliding, dgs_prev, t_n_lag, ps, length, gap0, pn,
                                            t_stick, e_row, i_row)
        if has_dashpot:
            add_dashpot(weights, force, state, dashpot, gap0, reference, e_row)
        data = matrix_data(n * n, n, block_base, block_step, block_k, free_blocks, pair_base,
                           pair_step, rows, terms, weights)
        rhs = np.empty(n)
        for s in range(nf):
            for i in range(6):
                rhs[6 * s + i] = block_f[free_blocks[s], i]
        rhs = rhs_data(rhs, side_row, side_block, force, d_known, rows, terms, weights)
        sol, status = solve_dense(data, n, rhs, keep, reduced)
        if status != CONVERGED:
            return status, passes, d, state, gap, dgs, False
        d = d_known.copy()
        for s in range(nf):
            for i in range(6):
                d[free_blocks[s], i] = sol[6 * s + i]
        dd = pair_increments(d, bj, bk)
        for c in range(m):
            g = 0.0
            s_ = 0.0
            for i in range(12):
                g += e_row[c, i] * dd[c, i]
                s_ += i_row[c, i] * dd[c, i]
            gap[c] = gap0[c] + g
            dgs[c] = s_
            judged[c] = gap[c] - release[c] if has_dashpot else gap[c]
        new_state, _, done, friction_settled, next_lag, lag_error, _ = pass_judge(
            state, held, judged, dgs, t_slip, t_n_lag, lag_error, lag_memory, flips, pinned,
            calm, gap_tol, kn, ps, length, kind, mu_s, mu_d, cohesion, face, g_se, sliding, bj,
            bk, free, settle_friction, band, passes, rtol, floor, cycle_tension, relax_after,
            patience, secant_from, remember_open, cycle_measure, own_measure, shear)
        if done:
            return CONVERGED, passes, d, new_state, gap.copy(), dgs.copy(), friction_settled
        changed = False
        for i in range(m):
            if new_state[i] != state[i]:
                changed = True
                break
        if changed and _seen(seen, n_seen, new_state):
            # a cycle: legacy's explicit rule no longer spares its contacts, and only the
            # most violated contact switches (dda.solvers.open_close)
            for i in range(m):
                held[i] = held[i] and new_state[i] == state[i]
            new_state = single_switch(state, new_state, judged)
        seen[n_seen] = new_state
        n_seen += 1
        state = new_state
        dgs_prev = dgs.copy()
        t_n_lag = next_lag
    return NOT_SETTLED, max_passes, d, state, gap, dgs, False


@njit(cache=True)
def first_states(state0, over, gap0, gap_tol, explicit):
    """The first pass's states and the contacts spared the friction check
    (:func:`dda.solvers.open_close._start`): a closed contact ``over`` its strength after the
    pull-back starts sliding; legacy DDA's explicit rule spares the closed contacts that start
    sticking; an open one touching or penetrating (``gap0 <= gap_tol``) is tried closed
    first. Returns ``(state, held)``."""
    m = state0.shape[0]
    state = state0.copy()
    held = np.zeros(m, dtype=np.bool_)
    for i in range(m):
        closed0 = state0[i] != 0
        if closed0 and over[i]:
            state[i] = 2
        held[i] = explicit and closed0 and state[i] == 1
        if state[i] == 0 and gap0[i] <= gap_tol[i]:
            state[i] = 1
    return state, held


@njit(cache=True)
def legacy_dense_step(max_passes, band, rtol, floor, cycle_tension, relax_after, patience,
                      secant_from, cycle_measure, own_measure, shear, block_k, block_f, d_known, n,
                      block_base, block_step, free_blocks, pair_base, pair_step, side_row,
                      side_block, keep, reduced, rows, terms, bj, bk, free, e_row, i_row, gap0, pn,
                      ps, kn, length, has_dashpot, dashpot, reference, release, kind, mu_s, mu_d,
                      cohesion, face, state0, g_se0, slip0, sliding0, t_n0, gap_tol):
    """Legacy DDA's whole step on a dense system (:class:`dda.solvers.LegacyPullBack`): the
    pull-back and first states of :func:`dda.solvers.open_close._start`, every OPEN-CLOSE
    pass (:func:`dense_passes`) and the step's end (:func:`dda.kernels.open_close.legacy_end`
    and the contacts' spring forces), in one call.

    The arguments are :func:`dense_passes`' but for the step's start: ``state0``, the
    committed history ``g_se0, slip0, sliding0`` and normal forces ``t_n0`` instead of the
    pulled-back history, the stick forces and the first pass's states; ``pn`` is the normal
    penalty (the spring forces' stiffness), ``kn`` the judged normal force's. ``patience`` is
    not used: legacy DDA settles its friction in every step
    (:func:`dda.solvers.open_close.predictor_patience`).

    Returns
    -------
    status, passes, d : as :func:`dense_passes`
    state : (m,) int8 the settled states
    t_n, t_s : (m,) the contacts' spring and shear forces at the step's end
    g_se, slip, sliding : (m,) their history at the step's end
    """
    m = state0.shape[0]
    # the pull-back of the excess friction, and the stick springs' forces from it
    over, g_se, slip, sliding, t_stick = step_start(state0, kind, mu_s, mu_d, cohesion, face,
                                                    g_se0, slip0, sliding0, t_n0, ps, length)
    state, held = first_states(state0, over, gap0, gap_tol, np.bool_(True))
    status, passes, d, state, gap, dgs, _ = dense_passes(
        max_passes, np.bool_(True), band, rtol, floor, cycle_tension, relax_after, np.int64(0),
        secant_from, np.bool_(False), cycle_measure, own_measure, shear,
        block_k,
        block_f, d_known, n, block_base, block_step, free_blocks, pair_base, pair_step, side_row,
        side_block, keep, reduced, rows, terms, bj, bk, free, e_row, i_row, gap0, pn, ps, kn,
        length, has_dashpot, dashpot, reference, release, kind, mu_s, mu_d, cohesion, face,
        g_se, sliding, t_stick, state, held, gap_tol, t_n0)
    t_n = np.zeros(m)
    t_s = np.zeros(m)
    if status != CONVERGED:
        return status, passes, d, state, t_n, t_s, g_se, slip, sliding
    judged = gap - release if has_dashpot else gap
    t_n, t_s, g_se, slip, sliding = legacy_end(state, judged, dgs, kind, mu_s, mu_d, cohesion,
                                               face, g_se, slip, sliding, kn, ps, length)
    if has_dashpot:  # the contacts keep their spring's force, not the dashpot's
        for i in range(m):
            t_n[i] = _np_min(pn[i] * gap[i], 0.0) if state[i] != 0 else 0.0
    return status, passes, d, state, t_n, t_s, g_se, slip, sliding
