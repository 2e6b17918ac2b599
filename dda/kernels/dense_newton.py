"""A small scene's Newton-Raphson iterations in one kernel call (:mod:`dda.solvers.newton`).

On a scene whose system is solved dense (up to ``dda.solvers.linear.DENSE_LIMIT`` unknowns)
an iterate of :meth:`dda.solvers.newton.NewtonRaphson.iterate` is some forty Python-level
calls around a few kernels: the trial points ``x + A d``, their first variations
(:func:`dda.kernels.kinematics.first_variations`), the return map and residual rows
(:func:`dda.kernels.open_close.contact_response`), the out-of-balance vectors
(:func:`dda.kernels.assembly.newton_residuals`), the consistent tangent's rows
(:func:`dda.kernels.tangent.tangent_rows`), the dense matrix and LAPACK's solve; on the
2-block incline of ``benchmarks/small_step.py`` the glue cost three times the arithmetic.
:func:`dense_newton` runs every iterate with the same rules in the same order:

    R(d) = K~ d - F~ + sum_c r_c(d),   converged when |R| <= tol max(|F~|, |K~ d|, sum |r_c|)
    (or at the round-off floor), else
    K_T(d) s = -R(d),   d <- d + s    (halved when the contacts' pattern cycles)

It takes the same decisions as the composed iterate and its numbers agree to round-off, not
to the bit (numba's LAPACK solve and the trial points' sums are not numpy's).
``tests/test_dense_newton.py`` runs steps both ways.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from dda.kernels.assembly import matrix_data, newton_residuals, rhs_data
from dda.kernels.dense_passes import CONVERGED as SOLVED
from dda.kernels.dense_passes import (
    NOT_SETTLED,
    dense_passes,
    first_states,
    rows_equal,
    solve_dense,
)
from dda.kernels.dense_passes import SINGULAR as SINGULAR_SOLVE
from dda.kernels.kinematics import first_variations, pair_increments
from dda.kernels.open_close import contact_response, step_start
from dda.kernels.tangent import tangent_rows

__all__ = ["dense_newton", "newton_dense_step", "penalty_round_off", "round_off_floor",
           "TANGENT_TERMS", "CONVERGED", "NOT_CONVERGED", "DIVERGED", "SINGULAR", "NOT_FINITE",
           "STALLED"]

CONVERGED, NOT_CONVERGED, DIVERGED, SINGULAR, NOT_FINITE, STALLED = 0, 1, 2, 3, 4, 5

#: the most of the forces' scale that :func:`penalty_round_off` may raise Newton's round-off
#: floor to: far from the origin (a scene in map coordinates) with a stiff penalty the bound
#: grew to 9% of the forces at 1e6 m (E) and beyond them at 1e5 m (1.5e13 N/m), and Newton
#: stopped far from balance; the lip impact's stall (2.6e-6 of the forces) stays under it
PENALTY_FLOOR_CAP = 1e-4

#: the consistent tangent's terms on the rows E, I, S, H, B: p_n E^T E + I^T S + B^T H + H^T B
#: (:func:`dda.contact.tangent.consistent_tangent`)
TANGENT_TERMS = np.array([[0, 0], [1, 2], [4, 3], [3, 4]], dtype=np.int64)


@njit(cache=True)
def _norm(a):
    """The 2-norm of all entries of ``a``."""
    s = 0.0
    for v in a.ravel():
        s += v * v
    return math.sqrt(s)


@njit(cache=True)
def _moved(p, a, dd):
    """(m, 2) the points ``p + A dd``."""
    out = np.empty_like(p)
    for c in range(p.shape[0]):
        for k in range(2):
            s = 0.0
            for j in range(12):
                s += a[c, k, j] * dd[c, j]
            out[c, k] = p[c, k] + s
    return out


@njit(cache=True)
def penalty_round_off(p1, p2, p3, a1, a2, a3, kn, ps):
    """The |R| that the round-off of the contacts' coordinates leaves, whatever the iterate.

    A contact's gaps are differences of its points' coordinates, ``g_n = (x_1 - x_2) . n``
    and ``g_s`` from ``x_3 - x_2``, each known to about ``eps`` times the coordinates'
    size; its forces to its stiffnesses times that, and its residual rows
    ``r_c = t_n E + t_s I`` (12 entries) to those times the rows' size. With
    ``|E|, |I| <= |A_1 - A_2| + |A_3 - A_2|`` (Frobenius norms of the points' maps) and the
    contacts' round-off independent of each other,

        R_floor = sqrt( sum_c [ (k_n + k_s) (|A_1 - A_2| + |A_3 - A_2|)
                                eps (|x_1| + |x_2| + |x_3|)_max ]^2 ).

    With a penalty of 1e13 N/m (1,000 E) the floor of a 0.3 m block resting on two
    contacts is some 1e-2 N against forces of 200 N: 5e-5 of them, where ``ROUND_OFF``
    (1e-6 of the forces) expects the round-off of the system's condition number only. A
    bound, loose by 20-250 times (the points' sizes added, open contacts counted): Newton
    takes it only up to ``PENALTY_FLOOR_CAP`` of the forces.

    Parameters
    ----------
    p1, p2, p3 : (m, 2) the contacts' vertex and edge ends
    a1, a2, a3 : (m, 2, 12) their maps
    kn, ps : (m,) the normal force's stiffness and the shear penalty
    """
    eps = np.finfo(np.float64).eps
    total = 0.0
    for c in range(p1.shape[0]):
        size = 0.0
        for p in (p1, p2, p3):
            size += max(abs(p[c, 0]), abs(p[c, 1]))
        da = 0.0
        db = 0.0
        for k in range(2):
            for j in range(12):
                u = a1[c, k, j] - a2[c, k, j]
                w = a3[c, k, j] - a2[c, k, j]
                da += u * u
                db += w * w
        term = (abs(kn[c]) + abs(ps[c])) * (math.sqrt(da) + math.sqrt(db)) * eps * size
        total += term * term
    return math.sqrt(total)


@njit(cache=True)
def round_off_floor(scale, round_off, penalty_floor):
    """Newton's round-off floor of |R|: ``round_off`` of the forces' ``scale``, or the
    contacts' :func:`penalty_round_off` where larger, up to ``PENALTY_FLOOR_CAP`` of them."""
    return max(round_off * scale, min(penalty_floor, PENALTY_FLOOR_CAP * scale))


@njit(cache=True)
def _at_round_off(norm, norms, count, floor):
    """|R| is as small as round-off allows: below ``floor``, with two earlier iterates, and
    no longer decreasing (more than half the smallest before it;
    :func:`dda.solvers.newton._at_round_off`)."""
    if count < 2 or norm > floor:
        return False
    smallest = norms[0]
    for k in range(1, count):
        smallest = min(smallest, norms[k])
    return norm > 0.5 * smallest


@njit(cache=True)
def _noise_floor(free, rigid, bj, bk, residual, closed, t_n, t_s, kn, gap_tol):
    """The norm over the free unknowns of the summed residual rows of the closed contacts
    whose forces are below their stiffness times their gap's round-off
    (:func:`dda.solvers.newton._at_noise_floor`; the rows summed in its order), or -1 when
    there are none."""
    acc = np.zeros((free.shape[0], 6))
    found = False
    noise = np.zeros(bj.shape[0], dtype=np.bool_)
    for c in range(bj.shape[0]):
        limit = kn[c] * gap_tol[c]
        if closed[c] and abs(t_n[c]) <= limit and abs(t_s[c]) <= limit:
            noise[c] = True
            found = True
    if not found:
        return -1.0
    for c in range(bj.shape[0]):
        if noise[c]:
            for i in range(6):
                acc[bj[c], i] += residual[c, i]
    for c in range(bk.shape[0]):
        if noise[c]:
            for i in range(6):
                acc[bk[c], i] += residual[c, 6 + i]
    total = 0.0
    for b in range(free.shape[0]):
        if free[b]:
            for i in range(3 if rigid[b] else 6):
                total += acc[b, i] * acc[b, i]
    return math.sqrt(total)


@njit(cache=True)
def _cycle_back(pattern, patterns, count, cycle_length):
    """How many accepted iterates back (2 to ``cycle_length``) ``pattern`` was, or 0."""
    for back in range(2, min(cycle_length, count) + 1):
        if rows_equal(patterns[count - back], pattern):
            return back
    return 0


@njit(cache=True)
def stalled(norm, last, before, contraction):
    """Newton's stall rule (:meth:`dda.solvers.NewtonRaphson.iterate`): with ``contraction``
    > 0, an iterate of |R| ``norm`` after accepted ones of ``last`` and ``before`` (the one
    before it) has stalled when neither it nor the last brought |R| below ``contraction`` of
    the one before."""
    return contraction > 0.0 and norm > contraction * last and last > contraction * before


@njit(cache=True)
def _holding(closed, last_closed, flips, t_n, t_s, bj, bk, free, hold_tension, hold_after,
             kind, mu_s, mu_d, cohesion, face, g_se, slip, sliding, gap, shear, shear0,
             release, has_dashpot, kn, pn, ps, length, e_row, i_row, held):
    """(m,) the contacts :func:`dense_newton` holds closed from this iterate on, and whether
    that differs from ``held`` (:func:`dda.solvers.newton._hold_cycling`): those held that
    pull by at most ``hold_tension`` of the largest contact force on their blocks, and those
    closed at the iterate before, open at this one, with ``hold_after`` opens or closes
    behind them, that pull by at most that much when held with the others. The largest force
    is each contact's own: of ``hypot(t_n, t_s)`` on either of its blocks, the smaller."""
    m = closed.shape[0]
    opening = np.zeros(m, dtype=np.bool_)
    for c in range(m):
        opening[c] = last_closed[c] and not closed[c] and flips[c] >= hold_after
    if not (opening.any() or held.any()):  # the common iterate: nothing to measure
        return held, False
    largest = np.zeros(free.shape[0])
    for c in range(m):
        size = math.hypot(t_n[c], t_s[c])
        largest[bj[c]] = max(largest[bj[c]], size)
        largest[bk[c]] = max(largest[bk[c]], size)
    for b in range(free.shape[0]):
        if not free[b]:
            largest[b] = np.inf
    limit = np.empty(m)
    for c in range(m):
        limit[c] = hold_tension * min(largest[bj[c]], largest[bk[c]])
    kept = np.zeros(m, dtype=np.bool_)
    changed = False
    for c in range(m):
        kept[c] = held[c] and t_n[c] <= limit[c]
        changed = changed or kept[c] != held[c]
    if not opening.any():
        return kept, changed
    trial = contact_response(kind, mu_s, mu_d, cohesion, face, g_se, slip, sliding, gap, shear,
                             shear0, release, has_dashpot, kn, pn, ps, length, e_row, i_row,
                             kept | opening)[9]
    for c in range(m):
        if opening[c] and trial[c] <= limit[c]:
            kept[c] = True
            changed = True
    return kept, changed


@njit(cache=True)
def dense_newton(d, max_iter, tol, round_off, halvings_allowed, cycle_length, reversed_stick,
                 contraction, hold_tension, hold_after,
                 block_k, block_f, free, rigid, n, block_base, block_step, free_blocks,
                 pair_base, pair_step, side_row, side_block, keep, reduced, bj, bk, p1, p2, p3,
                 a1, a2, a3, xi0, shear0, release, has_dashpot, kn, pn, ps, length, kind, mu_s,
                 mu_d, cohesion,
                 face, g_se, slip, sliding, noise_floor, gap_tol):
    """Newton-Raphson iterations of one step on a dense system (module docstring).

    Parameters
    ----------
    d : (n_blocks, 6) the first iterate (the known blocks' rows are their increments)
    max_iter, tol, round_off, halvings_allowed, cycle_length, reversed_stick : the
        iteration's rules (:mod:`dda.solvers.newton`: ``max_iter``, ``tol``, ``ROUND_OFF``,
        ``LINE_SEARCH_HALVINGS``, ``CYCLE_LENGTH``, ``REVERSED_STICK``)
    contraction : when > 0, the iteration gives up (STALLED) at an iterate that has not
        converged when neither it nor the accepted iterate before brought |R| below this
        fraction of the one before it (:meth:`dda.solvers.NewtonRaphson.iterate`)
    hold_tension, hold_after : a contact that has opened or closed ``hold_after`` times in
        the step's iterates and would open again, pulled by at most ``hold_tension`` of the
        largest contact force on its blocks, is held closed while it pulls no harder
        (:data:`dda.solvers.newton.HOLD_CYCLING`); ``hold_tension`` negative: none is
    block_k, block_f, free, rigid : the step's block matrices and forces, the blocks with
        unknowns, the blocks without strain unknowns
    n, block_base, block_step, free_blocks, pair_base, pair_step, side_row, side_block :
        the dense layout of :class:`dda.solvers.linear.SystemPattern`
    keep, reduced : the unknowns solved for when ``reduced``
    bj, bk : the contacts' blocks
    p1, p2, p3, a1, a2, a3, xi0, shear0 : the contacts' points at the step's start, their
        maps, the shear reference and the start's shear gap
    release, has_dashpot, kn, pn, ps, length : the gap a contact lets go at, the normal
        force's stiffness (with the dashpot's), the penalties, the edges' lengths
    kind, mu_s, mu_d, cohesion, face, g_se, slip, sliding : the built-in laws per contact
        and the committed history
    noise_floor, gap_tol : whether an iterate within the out-of-balance of its round-off
        contacts has converged (:func:`dda.solvers.newton._at_noise_floor`), and the gaps'
        round-off

    Returns
    -------
    status : CONVERGED, NOT_CONVERGED (after ``max_iter``), DIVERGED (non-finite |R|),
        SINGULAR or NOT_FINITE (the tangent's solve), STALLED (``contraction``)
    it : the iterations counted as the composed iterate counts them
    d : (n_blocks, 6) the last iterate
    norms : |R| of the accepted iterates
    scale : the size of the forces the last |R| was judged against
    closed, slipping, spring, t_s, g_se, slip, sliding : the last iterate's contacts
        (:func:`dda.kernels.open_close.contact_response`)
    """
    m = bj.shape[0]
    nf = free_blocks.shape[0]
    d = d.copy()
    zero_known = np.zeros_like(d)
    norms = np.empty(max_iter + 1)
    n_norms = np.int64(0)
    # a global array is read-only inside a kernel: the copy keeps the assembly kernels to the
    # one compiled version that the Python callers' arrays use
    tangent_terms = TANGENT_TERMS.copy()
    patterns = np.empty((max_iter + 1, m), dtype=np.int8)
    force_norm = 0.0
    for b in range(free.shape[0]):
        if free[b]:
            for i in range(6):
                force_norm += block_f[b, i] * block_f[b, i]
    force_norm = math.sqrt(force_norm)
    # the round-off floor: ROUND_OFF of the forces, or what the contacts' coordinates leave
    penalty_floor = penalty_round_off(p1, p2, p3, a1, a2, a3, kn, ps)
    base = d.copy()
    step = np.zeros_like(d)
    has_base = False
    halvings = 0
    weights = np.ones((m, 4))
    it = 0
    scale = 1.0
    status = CONVERGED
    held = np.zeros(m, dtype=np.bool_)
    flips = np.zeros(m, dtype=np.int64)
    last_closed = np.zeros(m, dtype=np.bool_)
    for it in range(max_iter + 1):
        dd = pair_increments(d, bj, bk)
        q1, q2, q3 = _moved(p1, a1, dd), _moved(p2, a2, dd), _moved(p3, a3, dd)
        length_t, tau, normal, gap, xi, shear, e_row, i_row = first_variations(
            q1, q2, q3, xi0, a1, a2, a3)
        (closed, slipping, spring, t_s, g_out, slip_out, sliding_out, kss, ksn, t_n,
         residual) = contact_response(kind, mu_s, mu_d, cohesion, face, g_se, slip, sliding,
                                      gap, shear, shear0, release, has_dashpot, kn, pn, ps,
                                      length, e_row, i_row, held)
        if hold_tension >= 0.0 and it > 0:
            held, changed = _holding(closed, last_closed, flips, t_n, t_s, bj, bk, free,
                                     hold_tension, hold_after, kind, mu_s, mu_d, cohesion,
                                     face, g_se, slip, sliding, gap, shear, shear0,
                                     release, has_dashpot, kn, pn, ps, length, e_row,
                                     i_row, held)
            if changed:
                (closed, slipping, spring, t_s, g_out, slip_out, sliding_out, kss, ksn, t_n,
                 residual) = contact_response(kind, mu_s, mu_d, cohesion, face, g_se, slip,
                                              sliding, gap, shear, shear0, release,
                                              has_dashpot, kn, pn, ps, length, e_row, i_row,
                                              held)
        if hold_tension >= 0.0:
            if it > 0:
                for c in range(m):
                    if closed[c] != last_closed[c]:
                        flips[c] += 1
            last_closed = closed.copy()
        block_r, r_free, inertia_free, contact_free = newton_residuals(
            block_k, d, block_f, free, rigid, bj, bk, residual)
        norm = _norm(r_free)
        scale = max(force_norm, _norm(inertia_free), _norm(contact_free), 1e-300)
        if (norm <= tol * scale or _at_round_off(
                    norm, norms, n_norms, round_off_floor(scale, round_off, penalty_floor))
                or (noise_floor and norm <= round_off * scale and norm <= _noise_floor(
                    free, rigid, bj, bk, residual, closed, t_n, t_s, kn, gap_tol))):
            norms[n_norms] = norm
            n_norms += 1
            break
        if n_norms >= 2 and stalled(norm, norms[n_norms - 1], norms[n_norms - 2], contraction):
            norms[n_norms] = norm
            n_norms += 1
            status = STALLED
            break
        pattern = np.empty(m, dtype=np.int8)
        for c in range(m):
            if not closed[c]:
                pattern[c] = 0
            elif slipping[c]:  # the sliding direction: numpy.sign's -1, 0, 1, twice
                pattern[c] = 2 if t_s[c] > 0.0 else (-2 if t_s[c] < 0.0 else 0)
            else:
                pattern[c] = 1
        back = _cycle_back(pattern, patterns, n_norms, cycle_length)
        if (has_base and halvings < halvings_allowed and it < max_iter and back > 0
                and norm > 0.5 * norms[n_norms - back]):
            halvings += 1
            d = base + 0.5 ** halvings * step
            continue
        norms[n_norms] = norm
        patterns[n_norms] = pattern
        n_norms += 1
        if not math.isfinite(norm):
            status = DIVERGED
            break
        if it == max_iter:
            status = NOT_CONVERGED
            break
        if reversed_stick and n_norms >= 2:
            # sliding the other way than at the iterate before: the step of its stick branch
            for c in range(m):
                now = patterns[n_norms - 1, c]
                if (now == 2 or now == -2) and now == -patterns[n_norms - 2, c]:
                    kss[c] = ps[c]
                    ksn[c] = 0.0
                    change = ps[c] * (g_se[c] + (shear[c] - shear0[c])) - t_s[c]
                    for j in range(residual.shape[1]):
                        residual[c, j] = residual[c, j] + change * i_row[c, j]
        rows = tangent_rows(a1, a2, a3, normal, tau, xi, xi0, gap, shear, length_t, e_row,
                            i_row, kss, ksn, t_n, t_s, closed)
        for c in range(m):
            weights[c, 0] = kn[c] if closed[c] else 0.0
        data = matrix_data(n * n, n, block_base, block_step, block_k, free_blocks, pair_base,
                           pair_step, rows, tangent_terms, weights)
        rhs = np.empty(n)
        for s in range(nf):
            for i in range(6):
                rhs[6 * s + i] = -block_r[free_blocks[s], i]
        rhs = rhs_data(rhs, side_row, side_block, -residual, zero_known, rows, tangent_terms,
                       weights)
        sol, solved = solve_dense(data, n, rhs, keep, reduced)
        if solved != SOLVED:
            status = SINGULAR if solved == SINGULAR_SOLVE else NOT_FINITE
            break
        step = np.zeros_like(d)
        for s in range(nf):
            for i in range(6):
                step[free_blocks[s], i] = sol[6 * s + i]
        base = d
        has_base = True
        halvings = 0
        d = d + step
    return (status, it, d, norms[:n_norms], scale, closed, slipping, spring, t_s, g_out,
            slip_out, sliding_out)


@njit(cache=True)
def newton_dense_step(max_passes, rtol, floor, cycle_tension, relax_after, patience,
                      retry_patience, unsettled, max_iter, predictor_iterations,
                      predictor_contraction, tol, round_off,
                      halvings_allowed, cycle_length, reversed_stick, hold_tension, hold_after,
                      block_k, block_f, d_known, n, block_base,
                      block_step, free_blocks, pair_base, pair_step, side_row, side_block, keep,
                      reduced, rows, terms, bj, bk, free, e_row, i_row, gap0, pn, ps, kn, length,
                      has_dashpot, dashpot, reference, release, kind, mu_s, mu_d, cohesion, face,
                      state0, g_se0, slip0, sliding0, t_n0, gap_tol, rigid, p1, p2, p3, a1, a2,
                      a3, xi0, shear0, noise_floor):
    """The fully implicit method's whole step on a dense system
    (:meth:`dda.solvers.NewtonRaphson.solve_step`) in one call: the pull-back and first
    states, the predictor (OPEN-CLOSE with the open and closed states settled,
    :func:`dda.kernels.dense_passes.dense_passes`), Newton's iterations from it
    (:func:`dense_newton`, at most ``predictor_iterations``, given up once two iterates in a
    row do not shrink |R| to ``predictor_contraction`` of the last, when the predictor left
    stick and slip unsettled) and, when those do not converge, the predictor with stick and
    slip settled too (or, after ``retry_patience`` passes that open or close no contact, not)
    and Newton again with all its ``max_iter``. With ``unsettled``, an OPEN-CLOSE that does not
    settle in its passes is a predictor all the same (its last pass's increments, Newton's whole
    ``max_iter``; ``NewtonRaphson(unsettled_predictor=True)``).

    The arguments are :func:`dda.kernels.dense_passes.dense_passes`' from ``block_k`` to
    ``face`` (:func:`dda.solvers.open_close.dense_arguments`), the committed contacts
    (``state0``, history, ``t_n0``), the gaps' round-off, and :func:`dense_newton`'s own
    (``noise_floor`` last).

    Returns
    -------
    oc_status, oc_passes : the last OPEN-CLOSE's status and passes (NOT_SETTLED with
        ``unsettled``: Newton's results below are from its last pass)
    passes : every OPEN-CLOSE pass of the step
    status, it, d, norms, scale, closed, slipping, spring, t_s, g_se, slip, sliding : the last
        Newton iterations' (:func:`dense_newton`; meaningless when ``oc_status`` failed)
    solves : the linear solves of the step
    """
    m = state0.shape[0]
    over, g_pb, _, sliding_pb, t_stick = step_start(state0, kind, mu_s, mu_d, cohesion, face,
                                                    g_se0, slip0, sliding0, t_n0, ps, length)
    state, held = first_states(state0, over, gap0, gap_tol, np.bool_(False))
    passes = 0
    solves = 0
    oc_status, oc_passes = CONVERGED, 0
    status, it, d = CONVERGED, 0, d_known.copy()
    norms, scale = np.zeros(0), 1.0
    closed, slipping = np.zeros(m, dtype=np.bool_), np.zeros(m, dtype=np.bool_)
    spring, t_s = np.zeros(m), np.zeros(m)
    g_se, slip, sliding = g_se0.copy(), slip0.copy(), sliding0.copy()
    for settle_friction in (False, True):
        # (a conditional among the call's arguments is more than numba compiles)
        calm_limit = retry_patience if settle_friction else patience
        oc_status, oc_passes, d, _, _, _, friction_settled = dense_passes(
            max_passes, settle_friction, 0.0, rtol, floor, cycle_tension, relax_after,
            calm_limit, np.int64(0), np.bool_(True), np.int64(0), np.zeros(m, dtype=np.bool_),
            np.zeros(m),
            block_k, block_f, d_known, n, block_base, block_step, free_blocks, pair_base, pair_step,
            side_row, side_block, keep, reduced, rows, terms, bj, bk, free, e_row, i_row, gap0, pn,
            ps, kn, length, has_dashpot, dashpot, reference, release, kind, mu_s, mu_d, cohesion,
            face, g_pb, sliding_pb, t_stick, state, held, gap_tol, t_n0)
        passes += oc_passes
        solves += oc_passes
        if oc_status != CONVERGED and not (oc_status == NOT_SETTLED and unsettled):
            break
        # from the looser predictor Newton gets a few iterations only; from one that did not
        # settle, all (settling stick and slip would not settle either)
        looser = not (friction_settled or settle_friction or oc_status == NOT_SETTLED)
        limit = min(max_iter, predictor_iterations) if looser else max_iter
        contraction = predictor_contraction if looser else 0.0
        (status, it, d, norms, scale, closed, slipping, spring, t_s, g_se, slip,
         sliding) = dense_newton(d, limit, tol, round_off, halvings_allowed, cycle_length,
                                 reversed_stick, contraction, hold_tension, hold_after,
                                 block_k, block_f, free, rigid, n, block_base, block_step,
                                 free_blocks, pair_base, pair_step, side_row, side_block, keep,
                                 reduced, bj, bk, p1, p2, p3, a1, a2, a3, xi0, shear0, release,
                                 has_dashpot, kn, pn, ps, length, kind, mu_s, mu_d, cohesion,
                                 face, g_se0, slip0, sliding0, noise_floor, gap_tol)
        # a solve for every accepted iterate but the last, and for the last when it failed
        solves += norms.shape[0] - 1 + (1 if status == SINGULAR or status == NOT_FINITE else 0)
        if status == CONVERGED or friction_settled or oc_status != CONVERGED:
            break  # settling again would change nothing
    return (oc_status, oc_passes, passes, status, it, d, norms, scale, closed, slipping,
            spring, t_s, g_se, slip, sliding, solves)
