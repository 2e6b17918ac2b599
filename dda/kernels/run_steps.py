"""A run of small steps in one kernel call: the steps of :meth:`dda.Simulation.run` that
:func:`dda.kernels.small_step.contact_step` takes, one after another, without returning to
Python between them (:mod:`dda.compiled_run` decides when, and feeds the records back).

On the 2-block incline of ``benchmarks/small_step.py`` a step's arithmetic in the kernels is
about 30 us; the Python around it (the step's start, the arguments and outputs of the kernel
call, the trial and committed state objects, the report, the stats row, the recorder, the
reversal check, the step control) 120-150 us more. :func:`run_steps` does, step after step,
what those do for a step that needs nothing else:

1. the blocks' start (:func:`dda.kernels.blocks.step_start_at`) and the search distance
   (:func:`dda.step.search_distance`), with the known increments of a shaken or moved block
   (worked out by the caller);
2. :func:`contact_step`; a step with any status other than ``OK`` is not taken;
3. where the run locates slip reversals (:mod:`dda.slip_events`), the reversal check of
   :meth:`dda.Simulation._reversal_located`; a step that would be taken again shorter is not
   taken;
4. the commit (:func:`dda.step._advanced` for plain blocks), the stats row, the record of
   every ``every``-th step (the pair forces of :func:`dda.recorder.pair_forces`), and the
   penalty advisor's quick test for soft springs, after which it stops (Python runs the full
   check).

It stops before a step it does not take, after a step whose record a thinned VTU series
takes as a frame (the caller writes it), and after ``max_steps`` (none of them the run's
last: the caller counts them); the caller takes the next step the usual way. Each step uses
the same kernels with the same arguments as :func:`dda.step.step`, so the run is the same to
the bit
(``tests/test_compiled_run.py`` runs scenes both ways).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from dda.kernels.blocks import step_start_at
from dda.kernels.forces import pair_force_sums
from dda.kernels.small_step import OK, contact_step
from dda.slip_events import _earliest_crossing

__all__ = ["run_steps", "STEPS_DONE", "NOT_OK", "REVERSAL", "SOFT", "NORMS", "FRAME",
           "ROW_FIELDS"]

#: why :func:`run_steps` stopped: ``max_steps`` taken; a step's status was not OK; a step
#: whose slip reversal is to be located; the soft-spring test failed after the last step; a
#: step's residual norms did not fit; the writer's frame is due at the last step's record
STEPS_DONE, NOT_OK, REVERSAL, SOFT, NORMS, FRAME = 0, 1, 2, 3, 4, 5

# (typed constants: a literal True or 2 passed to a kernel compiles a second version of it,
# on Literal[bool] or Literal[int], beside the one Python's calls use)
_TRUE = np.bool_(True)
_SLIP, _OPEN = np.int64(2), np.int64(0)

#: the columns of the stats rows :func:`run_steps` returns
ROW_FIELDS = ("time", "iterations", "open_close_passes", "contacts", "closed", "sliding",
              "solves", "pairs", "penetration", "spring_penetration")


@njit(cache=True)
def run_steps(max_steps, velocity, s_centroid, last_move, untracked, time,
              gravity, carry, k_factor, v_factor, fall, floor, search_factor, locate, wait,
              least, normal_ratio, start_scale, soft_check, soft_threshold, every, since,
              centroid0, has_rigid, has_sliding, max_norms, has_known, d_knowns, known_vs,
              known_max, full_blocks, writer_mode, frames_to_due, due_after,
              newton, x, offsets, nxt, prv, block, free, thickness, size, density,
              elasticity, stress, rotation, centroid, area, sxx, syy, v_eff, dt, d0,
              penetration, min_size, tolerance, min_thickness, max_ratio, pair_keys,
              pair_joint, default, pn_table, ps_table, zeta_table, zeta_s_table, c_vertex,
              c_edge, c_bj, c_bk, c_state, c_xi0, c_t_n, c_t_s, c_g_se, c_slip, c_sliding,
              c_held_ago, law, init, block_k, block_f, d_known, n, block_base, block_step,
              free_blocks, pair_base, pair_step, side_row, side_block, keep, reduced, terms,
              gap_rel, gap_abs, max_passes, band, rules, unsettled, max_iter,
              predictor_iterations, predictor_contraction, tol, round_off, halvings, cycle_length,
              reversed_stick, hold_tension, hold_after, rigid, faces, face_cos, noise_floor):
    """Up to ``max_steps`` steps of ``dt`` from the committed state (module docstring).

    The arguments from ``newton`` on are :func:`contact_step`'s for the first step (those
    of the state, ``x`` to ``penetration``, ``c_state`` to ``c_held_ago``, ``block_k`` and
    ``block_f``, are made again for every step here); before them:

    max_steps : the steps to take at most: each a whole step of ``dt`` and none the run's
        last (:meth:`dda.step_control.StepControl.step_size`, counted by the caller)
    velocity, s_centroid, last_move, untracked, time : the rest of the committed state
        (:class:`dda.step.StepState`'s ``velocity``, ``centroid``, ``last_move``,
        ``untracked``, ``time``)
    gravity, carry, k_factor, v_factor : :func:`step_start_at`'s ``g``, the velocity carry,
        ``2 / dt**2`` and ``2 / dt``
    fall, floor, search_factor : :func:`dda.step.search_distance`'s ``0.5 |g| dt dt``,
        ``1e-6 min_size`` and ``SEARCH_FACTOR``
    locate, wait, least, normal_ratio, start_scale : reversals located (and the steps before
        they are looked for again), :data:`dda.slip_events.MIN_FRACTION`, ``NORMAL_RATIO``,
        and the carry of each block's start velocity (1 for a block whose motion is known)
    soft_check, soft_threshold : the penalty advisor's quick test, ``-min t_n`` above the
        threshold (``SOFT_DEPTH`` times the thinnest block times the softest penalty)
    every, since, centroid0 : the recorder's ``every``, its steps since the last record, and
        the blocks' initial centroids
    has_rigid, has_sliding, max_norms : rigid blocks in the scene; the law keeps a
        ``sliding`` history; the most residual norms a step may hand back
    has_known, d_knowns, known_vs, known_max, full_blocks : blocks whose motion is given
        (shaken or moved): each step's known increments (its ``d_known``), known velocities
        and largest known move (:meth:`dda.model.Model.known_motion`, worked out by the caller
        for the steps it asks for), and the blocks moved in full (their velocity is their
        move over dt)
    writer_mode, frames_to_due, due_after : a writer that thins its series
        (:class:`dda.io.VTUWriter`): 0 none, 1 the record after ``frames_to_due`` others
        (``every``), 2 the first record at or after ``due_after`` (``interval``); it stops
        after a step whose record the writer takes (``FRAME``), the caller writes it
    Returns
    -------
    steps, why : the steps taken and why it stopped (``STEPS_DONE`` ...)
    time, x, velocity, stress, rotation, centroid, state, rows, last_move, untracked,
    penetration, wait, since : the state after them (``rows`` the contacts' ``xi0, t_n, t_s,
        g_se, slip, sliding``), the reversal wait and the recorder's count
    stats : (steps, len(ROW_FIELDS)) each step's row
    norms, n_norms : each step's residual norms (the first ``n_norms`` of a row)
    records, rec_time, rec_disp, rec_rot, rec_vel, rec_stress : the recorded steps (indices
        into ``stats``) and their blocks
    pair_at, pair_keys_out, pair_force, pair_normal : each record's pair forces, from
        ``pair_at[r]`` to ``pair_at[r + 1]``
    """
    nb = offsets.shape[0] - 1
    m = c_vertex.shape[0]
    stats = np.zeros((max_steps, 10))
    norms = np.zeros((max_steps, max_norms))
    n_norms = np.zeros(max_steps, dtype=np.int64)
    records = np.zeros(max_steps, dtype=np.int64)
    rec_time = np.zeros(max_steps)
    rec_disp = np.zeros((max_steps, nb, 2))
    rec_rot = np.zeros((max_steps, nb))
    rec_vel = np.zeros((max_steps, nb, 6))
    rec_stress = np.zeros((max_steps, nb, 3))
    pair_at = np.zeros(max_steps + 1, dtype=np.int64)
    pair_keys_out = np.zeros(max_steps * max(m, 1), dtype=np.int64)
    pair_force = np.zeros((max_steps * max(m, 1), 2))
    pair_normal = np.zeros((max_steps * max(m, 1), 2))
    n_rec = 0
    cur_x = x.copy()
    cur_v = velocity.copy()
    cur_stress = stress.copy()
    cur_rot = rotation.copy()
    cur_centroid = s_centroid.copy()
    cur_state = c_state.copy()
    rows = np.empty((7, m))
    rows[0, :] = c_xi0
    rows[1, :] = c_t_n
    rows[2, :] = c_t_s
    rows[3, :] = c_g_se
    rows[4, :] = c_slip
    rows[5, :] = c_sliding
    rows[6, :] = c_held_ago
    cur_pen = penetration
    no_sliding = np.zeros(m)
    steps = 0
    why = STEPS_DONE
    while steps < max_steps:
        # ---- the step's start (dda.step._plain_start, search_distance)
        (area_, centroid_, sxx_, syy_, _, k_eff, f_eff, v_eff_,
         speed) = step_start_at(cur_x, offsets, nxt, density, elasticity, gravity, cur_stress,
                                block, cur_v, carry, k_factor, v_factor, _TRUE)
        predicted = speed * dt
        predicted += fall
        step_known = d_known
        if has_known:
            step_known = d_knowns[steps]
            predicted = max(predicted, known_max[steps])
        d0_ = search_factor * max(predicted, last_move, 0.0) + floor
        sliding_in = rows[5].copy() if has_sliding else no_sliding
        (status, counts, numbers, _, step_norms, new_state, new_rows, x_new, v_new, s_new,
         r_new, c_new) = contact_step(
            newton, cur_x, offsets, nxt, prv, block, free, thickness, size, density,
            elasticity, cur_stress, cur_rot, centroid_, area_, sxx_, syy_, v_eff_, dt, d0_,
            cur_pen, min_size, tolerance, min_thickness, max_ratio, pair_keys, pair_joint,
            default, pn_table, ps_table, zeta_table, zeta_s_table, c_vertex, c_edge, c_bj,
            c_bk, cur_state, rows[0].copy(), rows[1].copy(), rows[2].copy(), rows[3].copy(),
            rows[4].copy(), sliding_in, rows[6].astype(np.int64), law, init, k_eff, f_eff,
            step_known, n, block_base,
            block_step, free_blocks, pair_base, pair_step, side_row, side_block, keep,
            reduced, terms, gap_rel, gap_abs, max_passes, band, rules, unsettled, max_iter,
            predictor_iterations, predictor_contraction, tol, round_off, halvings,
            cycle_length, reversed_stick, hold_tension, hold_after, rigid, faces, face_cos,
            noise_floor)
        if status != OK:
            why = NOT_OK
            break
        if step_norms.shape[0] > max_norms:
            why = NORMS
            break
        if has_rigid:
            for b in range(nb):
                if rigid[b]:
                    for j in range(3, 6):
                        v_new[b, j] = 0.0
        if has_known:  # (dda.step._advanced)
            for b in range(nb):
                if not free[b]:
                    v_new[b, 0] = known_vs[steps, b, 0]
                    v_new[b, 1] = known_vs[steps, b, 1]
            for b in full_blocks:
                v_new[b, 0] = step_known[b, 0] / dt
                v_new[b, 1] = step_known[b, 1] / dt
        # ---- the reversal check (Simulation._reversal_located, slip_events.reversal_fraction)
        if locate and wait == 0:
            start = cur_v.copy()
            if carry != 1.0:
                for b in range(nb):
                    for j in range(6):
                        start[b, j] = cur_v[b, j] * start_scale[b]
            phi = _earliest_crossing(c_vertex, c_edge, cur_state, rows[1], c_bj, c_bk, cur_x,
                                     cur_centroid, start, c_vertex, c_edge, new_state,
                                     new_rows[1], c_bj, c_bk, x_new, c_new, v_new, nxt, _SLIP,
                                     _OPEN, normal_ratio, 1.0)
            if phi <= 1.0 and least < phi < 1.0 - least and not phi * dt < least * dt:
                why = REVERSAL
                break
        # ---- the commit (dda.step._advanced, Simulation._advance, StepControl.accepted)
        time = time + dt
        cur_x = x_new
        cur_v = v_new
        cur_stress = s_new
        cur_rot = r_new
        cur_centroid = c_new
        cur_state = new_state
        rows = new_rows
        last_move = numbers[0]
        cur_pen = numbers[3]
        untracked = numbers[5]
        if wait > 0:
            wait -= 1
        closed = 0
        sliding = 0
        for c in range(m):
            if cur_state[c] != 0:
                closed += 1
            if cur_state[c] == 2:
                sliding += 1
        row = stats[steps]
        row[0] = time
        row[1] = counts[4] if newton else counts[3]
        row[2] = counts[3]
        row[3] = m
        row[4] = closed
        row[5] = sliding
        row[6] = counts[5]
        row[7] = counts[6]
        row[8] = numbers[3]
        row[9] = numbers[4]
        n_norms[steps] = step_norms.shape[0]
        for i in range(step_norms.shape[0]):
            norms[steps, i] = step_norms[i]
        # ---- the record (Recorder.committed, dda.recorder.pair_forces)
        since += 1
        if since >= every:
            since = 0
            records[n_rec] = steps
            rec_time[n_rec] = time
            for b in range(nb):
                rec_disp[n_rec, b, 0] = cur_centroid[b, 0] - centroid0[b, 0]
                rec_disp[n_rec, b, 1] = cur_centroid[b, 1] - centroid0[b, 1]
                rec_rot[n_rec, b] = cur_rot[b]
                for j in range(6):
                    rec_vel[n_rec, b, j] = cur_v[b, j]
                for j in range(3):
                    rec_stress[n_rec, b, j] = cur_stress[b, j]
            keys, f, nrm = pair_force_sums(cur_x, nxt, cur_state, c_edge, c_bj, c_bk,
                                           rows[1], rows[2], nb)
            at = pair_at[n_rec]
            for i in range(keys.shape[0]):
                pair_keys_out[at + i] = keys[i]
                pair_force[at + i, 0] = f[i, 0]
                pair_force[at + i, 1] = f[i, 1]
                pair_normal[at + i, 0] = nrm[i, 0]
                pair_normal[at + i, 1] = nrm[i, 1]
            pair_at[n_rec + 1] = at + keys.shape[0]
            n_rec += 1
            if (writer_mode == 1 and n_rec - 1 == frames_to_due
                    or writer_mode == 2 and time >= due_after):
                steps += 1
                why = FRAME
                break
        steps += 1
        # ---- the penalty advisor's quick test (PenaltyAdvisor._check_soft)
        if soft_check and m:
            least_t_n = rows[1, 0]
            for c in range(1, m):
                v = rows[1, c]
                if v != v or v < least_t_n:
                    least_t_n = v
                    if v != v:
                        break
            if not -least_t_n <= soft_threshold:
                why = SOFT
                break
    return (steps, why, time, cur_x, cur_v, cur_stress, cur_rot, cur_centroid, cur_state, rows,
            last_move, untracked, cur_pen, wait, since, stats[:steps], norms[:steps],
            n_norms[:steps], records[:n_rec], rec_time[:n_rec], rec_disp[:n_rec],
            rec_rot[:n_rec], rec_vel[:n_rec], rec_stress[:n_rec], pair_at[:n_rec + 1],
            pair_keys_out, pair_force, pair_normal)
