"""A small scene's contact step in one kernel call: detection, the element, the solver, the
moves and the penetration guard (:func:`dda.step.step`'s middle, its common case).

On a scene of a few blocks a step was some thirty Python functions around a dozen kernels, and
their glue cost twice the kernels' arithmetic (the 2-block incline of
``benchmarks/small_step.py``: 165 us a step, about 60 of them in the kernels). :func:`contact_step`
calls the same kernels, with the same arguments, in the same order as the composed step:

1. the penetration limit, the boxes, the broad phase and its known-known pairs dropped, the
   narrow phase (:mod:`dda.contact.detection`'s kernels);
2. the closed contacts :func:`dda.contact.detection.keep_closed` would put back (none, or it
   stops: ``FALLBACK``), and the committed contacts carried over whole (the same vertex and
   edge pairs in the same order, or ``FALLBACK``), the open ones with their foot as their
   shear reference and no force;
3. each contact's joint row, a fresh contact's law history, its penalties and dashpots, and
   the element's arrays (:func:`dda.kernels.element.element_arrays`);
4. the solver's whole step on the dense system (:func:`dda.kernels.dense_passes.
   legacy_dense_step` or :func:`dda.kernels.dense_newton.newton_dense_step`), the open
   contacts' history reset (the fully implicit method), the shear dashpot taken out of the
   springs;
5. the moves (:func:`dda.kernels.blocks.step_end`), the two checks on them, and the guard.

Where the composed step would take any other branch (a closed contact to put back, contacts
that changed, a pair without a joint, no contact at all), it returns ``FALLBACK`` before it has
changed anything and :func:`dda.step.step` takes the composed path; every other outcome (a
converged step, a solver that did not converge, moves too far, an untracked penetration) is
the composed step's, to the bit (``tests/test_small_step.py`` runs both).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from dda.contact.detection import (
    _boxes,
    _broad_phase,
    _narrow_phase_kernel,
    _pairs_with_free_block,
    _stale_closed,
)
from dda.contact.penetration import _guard_kernel
from dda.kernels.blocks import step_end
from dda.kernels.dense_newton import newton_dense_step
from dda.kernels.dense_passes import legacy_dense_step
from dda.kernels.element import element_arrays
from dda.kernels.faces import face_index
from dda.kernels.joints import deepest_spring, joint_rows
from dda.kernels.open_close import CYCLE_GROUP, own_measures

__all__ = ["contact_step", "OK", "FALLBACK", "NOT_SOLVED", "MOVED", "TOO_FAR", "UNTRACKED"]

OK, FALLBACK, NOT_SOLVED, MOVED, TOO_FAR, UNTRACKED = 0, 1, 2, 3, 4, 5


@njit(cache=True)
def contact_step(newton, x, offsets, nxt, prv, block, free, thickness, size, density,
                 elasticity, stress, rotation, centroid, area, sxx, syy, v_eff, dt, d0,
                 penetration, min_size, tolerance, min_thickness, max_ratio, pair_keys,
                 pair_joint, default, pn_table, ps_table, zeta_table, zeta_s_table, c_vertex,
                 c_edge, c_bj, c_bk, c_state, c_xi0, c_t_n, c_t_s, c_g_se, c_slip, c_sliding,
                 c_held_ago, law, init, block_k, block_f, d_known, n, block_base, block_step,
                 free_blocks, pair_base, pair_step, side_row, side_block, keep, reduced, terms,
                 gap_rel, gap_abs, max_passes, band, rules, unsettled, max_iter,
                 predictor_iterations, predictor_contraction, tol, round_off, halvings,
                 cycle_length, reversed_stick, hold_tension, hold_after, rigid, faces, face_cos,
                 noise_floor):
    """One step's contacts, solve, moves and guard (module docstring).

    ``law`` is ``(kind, mu_static, mu_dynamic, cohesion)`` of the scene's one law, ``init``
    its initial ``(g_se, slip, sliding)``, ``faces`` whether it judges faces (grouped with
    :func:`dda.kernels.faces.face_index` and ``face_cos``); ``rules`` the passes' ``(rtol, floor,
    cycle_tension, relax_after, patience, retry_patience, secant_from, cycle_measure,
    cycle_memory)`` (the fully implicit method's patience of its predictor and of its retry,
    :func:`dda.solvers.open_close.predictor_patience`, and legacy DDA's secant lag,
    ``LAG_SECANT_FROM``, and cycle limit's measure and memory,
    :func:`dda.solvers.open_close.cycle_measure` and ``cycle_memory``); ``c_held_ago`` the
    committed contacts' :attr:`dda.contact.ContactSet.held_ago`; the rest are the arguments of
    the kernels named in the module docstring, under their names there.

    Returns
    -------
    status : OK, FALLBACK, NOT_SOLVED (the solver's own status and counts tell why), MOVED
        (a vertex moved more than half the search distance), TOO_FAR (a free block moved
        more than ``max_ratio`` of its size) or UNTRACKED (the guard's)
    ints : (solver status, OPEN-CLOSE status, OPEN-CLOSE passes, all passes, iterations,
        solves, pairs, the worst block, the guard's vertex, its block, on an edge)
    floats : (the largest move, the worst block's move, the residual scale, the guard's
        deepest, spring and untracked depths, its depth and tolerance)
    d, norms : the increments, Newton's residual norms
    state : the trial contacts' states
    rows : (7, m) the trial contacts' ``xi0, t_n, t_s, g_se, slip, sliding, held_ago``
        (:func:`_contact_rows`)
    x_new, velocity, new_stress, new_rotation, new_centroid : the blocks at the step's end
    """
    nb = offsets.shape[0] - 1
    m0 = c_vertex.shape[0]
    ints = np.zeros(11, dtype=np.int64)
    floats = np.zeros(8)
    e0 = np.zeros(0)
    e1 = np.zeros((0, 2))
    # ---- detection (dda.step._detect)
    spring = deepest_spring(c_state, c_t_n, c_bj, c_bk, nb, pair_keys, pair_joint, default,
                            pn_table)
    pen_limit = max(2.0 * d0, 1e-3 * min_size, 2.0 * max(spring, penetration) + d0)
    sunk = 0.25 * tolerance * thickness
    boxes = _boxes(x, offsets)
    margin = max(d0, pen_limit)
    pairs = _pairs_with_free_block(_broad_phase(boxes, margin), free)
    ints[6] = pairs.shape[0]
    if pairs.shape[0] == 0:
        return (FALLBACK,) + _nothing(nb)
    (vertex, edge, bj, bk, p1, p2, p3, edge_length, tau, normal, gap,
     xi) = _narrow_phase_kernel(x, offsets, nxt, prv, block, pairs, boxes,
                                max(d0, pen_limit), d0, pen_limit, sunk, 0.0)
    # (no touching tolerance: it is a run's first step's, and a first step, with no
    # committed contacts, falls back to dda.step below)
    m = vertex.shape[0]
    if m == 0 or m != m0:
        return (FALLBACK,) + _nothing(nb)
    for c in range(m):
        if vertex[c] != c_vertex[c] or edge[c] != c_edge[c]:
            return (FALLBACK,) + _nothing(nb)
    n_closed = 0
    for c in range(m):
        if c_state[c] != 0:
            n_closed += 1
    if n_closed:
        closed_vertex = np.empty(n_closed, dtype=np.int64)
        closed_edge = np.empty(n_closed, dtype=np.int64)
        k = 0
        for c in range(m):
            if c_state[c] != 0:
                closed_vertex[k], closed_edge[k] = c_vertex[c], c_edge[c]
                k += 1
        lost, turned, _ = _stale_closed(vertex, edge, bk, closed_vertex, closed_edge, block,
                                        nxt, prv, nb, x)
        if lost.shape[0] or turned.shape[0]:
            return (FALLBACK,) + _nothing(nb)
    # the contacts carried over whole (dda.contact.contacts._carried_whole)
    state0 = c_state.copy()
    xi0 = c_xi0.copy()
    t_n0 = c_t_n.copy()
    t_s0 = c_t_s.copy()
    g_se = c_g_se.copy()
    slip = c_slip.copy()
    sliding = c_sliding.copy()
    for c in range(m):
        if state0[c] == 0:
            xi0[c] = xi[c]
            t_n0[c] = 0.0
            t_s0[c] = 0.0
    # ---- the element (dda.step._element, ContactElement.compiled)
    joint = joint_rows(bj, bk, nb, pair_keys, pair_joint, default)
    for c in range(m):
        if joint[c] < 0:
            return (FALLBACK,) + _nothing(nb)  # no joint: the composed step says which pair
    for c in range(m):
        if state0[c] == 0:  # a fresh contact: its law's initial history
            g_se[c], slip[c], sliding[c] = init[0], init[1], init[2]
    pn = np.empty(m)
    ps = np.empty(m)
    for c in range(m):
        pn[c] = pn_table[joint[c]]
        ps[c] = ps_table[joint[c]]
    has_dashpot = zeta_table.shape[0] > 0
    has_shear = zeta_s_table.shape[0] > 0
    zeta = np.empty(m if has_dashpot else 0)
    zeta_s = np.empty(m if has_shear else 0)
    for c in range(zeta.shape[0]):
        zeta[c] = zeta_table[joint[c]]
    for c in range(zeta_s.shape[0]):
        zeta_s[c] = zeta_s_table[joint[c]]
    (length, maps, shear0, e_row, i_row, rows, gap_tol, dashpot, reference, release, judge,
     shear_dashpot, ps_eff, g_se_scaled) = element_arrays(
        x, centroid, nxt, prv, vertex, edge, bj, bk, xi0, p1, p2, p3, edge_length, tau, normal,
        gap, pn, ps, g_se if has_shear else e0, zeta, zeta_s, free, density, area, sxx, syy, dt,
        gap_rel, gap_abs)
    g_se0 = g_se.copy()
    ps_step = ps
    if has_shear:
        ps_step = ps_eff
        g_se = g_se_scaled
    if not has_dashpot:
        dashpot = np.zeros(m)
        reference = np.zeros(m)
        release = np.zeros(m)
    kind = np.full(m, law[0], dtype=np.int64)
    mu_s = np.full(m, law[1])
    mu_d = np.full(m, law[2])
    cohesion = np.full(m, law[3])
    if faces:  # (ContactElement.compiled: the law's contacts grouped into faces)
        face = face_index(x, vertex, edge, nxt, prv, face_cos)
    else:
        face = np.full(m, -1, dtype=np.int64)
    # ---- the solver's step (dda.solvers.legacy._dense_step, dda.solvers.newton._dense_step)
    (rtol, floor, cycle_tension, relax_after, patience, retry_patience, secant_from,
     cycle_measure, cycle_memory) = rules
    own, ago = own_measures(c_state, c_t_n, c_held_ago,
                            cycle_memory if cycle_measure == CYCLE_GROUP else np.int64(0))
    norms = e0
    if newton:
        (oc_status, oc_passes, passes, status, it, d, norms, scale, closed, slipping, t_n, t_s,
         g_se_out, slip_out, sliding_out, solves) = newton_dense_step(
            max_passes, rtol, floor, cycle_tension, relax_after, patience, retry_patience,
            unsettled, max_iter, predictor_iterations, predictor_contraction, tol, round_off,
            halvings, cycle_length, reversed_stick, hold_tension, hold_after, block_k, block_f,
            d_known, n, block_base, block_step, free_blocks, pair_base, pair_step, side_row,
            side_block, keep, reduced, rows, terms,
            bj, bk, free, e_row, i_row, gap, pn, ps_step, judge, length, has_dashpot, dashpot,
            reference, release, kind, mu_s, mu_d, cohesion, face, state0, g_se, slip, sliding,
            t_n0, gap_tol, rigid, p1, p2, p3, maps[0], maps[1], maps[2], xi0, shear0,
            noise_floor)
        ints[0], ints[1], ints[2], ints[3], ints[4], ints[5] = (status, oc_status, oc_passes,
                                                                passes, it, solves)
        floats[2] = scale
        solved = status == 0 and (oc_status == 0 or (oc_status == 1 and unsettled))
        state = np.zeros(m, dtype=np.int8)
        for c in range(m):
            if closed[c]:
                state[c] = 2 if slipping[c] else 1
            else:  # an open contact: its law's initial history (trial_contacts)
                g_se_out[c], slip_out[c], sliding_out[c] = init[0], init[1], init[2]
    else:
        (status, passes, d, state, t_n, t_s, g_se_out, slip_out,
         sliding_out) = legacy_dense_step(max_passes, band, rtol, floor, cycle_tension,
                                          relax_after, np.int64(0), secant_from, cycle_measure,
                                          own, np.abs(t_s0), block_k, block_f, d_known, n,
                                          block_base, block_step, free_blocks, pair_base,
                                          pair_step, side_row, side_block, keep, reduced, rows,
                                          terms, bj, bk, free, e_row, i_row, gap, pn, ps_step,
                                          judge, length, has_dashpot, dashpot, reference,
                                          release, kind, mu_s, mu_d, cohesion, face, state0,
                                          g_se, slip, sliding, t_n0, gap_tol)
        ints[0], ints[3], ints[4], ints[5] = status, passes, passes, passes
        solved = status == 0
    if not solved:
        return (NOT_SOLVED, ints, floats, d, norms, state,
                _contact_rows(xi0, t_n, t_s, g_se_out, slip_out, sliding_out, ago),
                e1, np.zeros((nb, 6)), np.zeros((nb, 3)), np.zeros(nb), e1)
    if has_shear:  # dda.contact.dashpot.shear_dashpot_end
        for c in range(m):
            if state[c] != 0:
                scaled0 = g_se0[c] * (ps[c] / (ps[c] + shear_dashpot[c]))
                g_se_out[c] = g_se0[c] + (g_se_out[c] - scaled0)
                t_s[c] = ps[c] * g_se_out[c]
    # ---- the moves, their checks and the guard (dda.step.step)
    (_, x_new, largest, worst, worst_move, velocity, new_stress, new_rotation,
     new_centroid) = step_end(x, block, offsets, centroid, d, free, size, v_eff, np.bool_(True),
                              2.0 / dt, elasticity, stress, rotation)
    floats[0], floats[1] = largest, worst_move
    ints[7] = worst
    result = OK
    if 2.0 * largest > d0:
        result = MOVED
    elif free[worst] and worst_move / size[worst] > max_ratio:
        result = TOO_FAR
    else:
        (deepest, spring_deep, untracked, on_edge, gv, gk, gdepth,
         gtol) = _guard_kernel(x_new, offsets, nxt, prv, block, thickness, tolerance,
                               min_thickness, state, t_n, pn, dashpot, has_dashpot, vertex,
                               edge, bj, bk, pairs)
        floats[3], floats[4], floats[5], floats[6], floats[7] = (deepest, spring_deep,
                                                                 untracked, gdepth, gtol)
        ints[8], ints[9], ints[10] = gv, gk, 1 if on_edge else 0
        if untracked > 1.0:
            result = UNTRACKED
    return (result, ints, floats, d, norms, state,
            _contact_rows(xi0, t_n, t_s, g_se_out, slip_out, sliding_out, ago),
            x_new, velocity, new_stress, new_rotation, new_centroid)


@njit(cache=True)
def _contact_rows(xi0, t_n, t_s, g_se, slip, sliding, held_ago):
    """(7, m) the trial contacts' ``xi0, t_n, t_s, g_se, slip, sliding, held_ago`` as rows: one
    array to hand back, where seven cost seven conversions to numpy arrays (half a us
    each)."""
    rows = np.empty((7, xi0.shape[0]))
    rows[0, :] = xi0
    rows[1, :] = t_n
    rows[2, :] = t_s
    rows[3, :] = g_se
    rows[4, :] = slip
    rows[5, :] = sliding
    rows[6, :] = held_ago
    return rows


@njit(cache=True)
def _nothing(nb):
    """The outputs after the status of a step that returns before it has solved anything."""
    e0 = np.zeros(0)
    e1 = np.zeros((0, 2))
    return (np.zeros(11, dtype=np.int64), np.zeros(8), np.zeros((nb, 6)), e0,
            np.zeros(0, dtype=np.int8), np.zeros((7, 0)), e1, np.zeros((nb, 6)),
            np.zeros((nb, 3)), np.zeros(nb), e1)
