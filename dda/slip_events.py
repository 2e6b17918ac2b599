"""Slip reversals located within the step.

A contact that slides one way at the start of a step and the other way at its end reversed
inside it, and there its friction force flipped by ``2 mu N``. The step finds the flip only
at its end: the solver applies one direction's friction to the whole step (Newton's return map
the end's, legacy DDA's pull-back the start's), so the block's velocity errs by up to ``2 mu
g dt`` until the next reversal, by the share of the step that lay on the wrong side. Where a
block slides back and forth without sticking between (a table shaken at more than about 1.8
times the friction), that error decides the slide: a block on a table at 1.5 g erred
0.5-2.2% under Newton at 300 steps a period and 0.4-1.9% under legacy DDA at 700, with dt
within 5% (``benchmarks/README.md``).

The step is taken again, ended where the reversing contact's slip velocity crosses zero. The
slip velocity ``w`` of a contact is the relative velocity of its vertex and its edge along the
edge, from the blocks' velocities (the first-order displacement function ``T(x)`` of each);
Newmark's ``gamma = 1`` makes the velocity linear in the step's acceleration, so the crossing
lies at

.. math::

    \\phi = \\frac{w_0}{w_0 - w_1}

of the step, ``w_0`` at its start and ``w_1`` at its end. A shorter step that still shows a
reversal puts the crossing earlier again (at most :data:`ITERATIONS` tries). The shortened
step is committed; the step control's size is unchanged, so the next step is as long as
before. With it the table at 1.5 g erred 0.18-0.20% (Newton) and 0.10-0.27% (legacy DDA, at
its 700 steps a period then) over the same dt.

A contact whose pair of blocks' normal force (summed over the pair's closed contacts)
changes more than :data:`NORMAL_RATIO` times in the step turned in an impact, not by its
friction, and is left alone; after a located reversal the
next :data:`WAIT` steps are not shortened (a vertex rattling in a corner reverses in step
after step). A step in which a contact stops and sticks counts too: Newmark's end velocity
``2 d / dt - v0`` turns its slip velocity to about ``-w0`` whatever the step's length, so
such a step is shortened to near its middle, up to three times (measured on the
``benchmarks/accuracy_cost.py`` grid: 16 of 80 cells more accurate, legacy DDA at 150 steps
a period 18.8% -> 0.30%; 4 less, Newton at 50 steps a period 0.64-1.03% -> 1.92-3.89%,
where the error jumps with dt: over dt within 10% of those cells its median fell from
5.4-6.9% to 1.4-2.6%, ``benchmarks/reversal_spread.py``; ``benchmarks/README.md``).

Every step with a sliding contact is checked (a compiled loop, about 1 us for a few
contacts), and every reversal costs up to :data:`ITERATIONS` more solves of its step. In a
jointed mass many contacts reverse by micrometres in most steps (the cut slope of
``examples/jointed_slope.py``: 11 contacts a step at the median, 1,556 retakes in 500 steps,
3.2 times the CPU), so :class:`dda.Simulation` locates reversals by default only in scenes of
at most :data:`AUTO_BLOCKS` free blocks (``locate_reversals``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from dda.contact.contacts import OPEN, SLIP

__all__ = ["AUTO_BLOCKS", "ITERATIONS", "MIN_FRACTION", "NORMAL_RATIO", "WAIT",
           "reversal_fraction"]

#: free blocks up to which ``Simulation(locate_reversals=None)`` locates reversals
AUTO_BLOCKS = 10
#: tries of a shorter step for one reversal
ITERATIONS = 3
#: a crossing within this share of either end of the step is left where the step put it,
#: and no step is shortened below this share of the step size
MIN_FRACTION = 0.02
#: accepted steps, the shortened one included, before the next reversal is located:
#: contacts that chatter (a vertex rattling in a corner) reverse in step after step. Over the
#: 84 impacts of ``tests/stability`` at dt 1e-3, without the wait 977 reversals were located
#: and the runs took 20,917 steps (an L-shaped block landing on a step at 1,000 E under
#: legacy DDA: 658 in 1,139 steps, against 690 steps when none is located); with it 150 and
#: 19,992
WAIT = 8
#: a contact whose pair of blocks carries, summed over the pair's closed contacts, a normal force at
#: one end of the step more than this many times the one at the other is left where the step put it:
#: its slip turned in an impact, where the normal force, not the friction, decides the motion. When
#: the guard came (judging each contact's own force), over 84 impact runs of ``tests/stability`` at
#: dt 1e-3 (both solvers, E/1e4 to 1,000 E) locating every reversal took the steps from 21,172 to
#: 20,719 and the cut ones from 267 to 328, a block striking a stopper at 1,000 E under
#: Newton-Raphson from 309 steps to 599, and 1,115 for a block on a lip (339); with the guard 19,992
#: and 283 in all, 309 and 340 for those two. The pair's sum, not each contact's force: when the
#: friction under a block turns, its moment moves the weight from one vertex to the other, by some
#: 30% at a soft penalty but by up to the rigid block's whole swap (749 / 113 N to 318 / 545 N a
#: step on the table at 1.5 g with ten times the inertia as penalty) where the springs are stiff,
#: and a guard on each contact missed one reversal in three there (at 2e8 N/m and dt 3e-3 s, 2e9 and
#: 2e10 at dt 1/600 s; its turn then fell 0.27-1.0% of the peak slip velocity inside a step; now
#: all, within 0.17%). The pair's sum barely moves when the friction turns. Over 56 impact runs (the
#: 7 scenes of ``tests/stability.scenes.IMPACTS`` at E/1e4, E/100, E and 1,000 E, both solvers, dt
#: 1e-3; the code of the time, which moved the counts above a little) it took 21,207 steps, 266 cut
#: and 141 reversals located, against 19,936, 283 and 150 with the guard on each contact: 1,262 of
#: the 1,271 steps more are the lip at 1,000 E under legacy DDA, whose path takes 631-2,863 steps
#: with dt within 3% and no reversal located (2,863 at 1e-3 s, as with the pair's sum; 1,601 with
#: the guard on each contact)
NORMAL_RATIO = 2.0


@njit(cache=True)
def _slip_velocity(x, nxt, centroid, velocity, v, e, bj, bk):
    """Relative velocity of vertex ``v`` (block ``bj``) and edge ``e`` (block ``bk``) along
    the edge: ``t . (T_j(x_v) v_j - T_k(x_v) v_k)``."""
    px, py = x[v, 0], x[v, 1]
    tx = x[nxt[e], 0] - x[e, 0]
    ty = x[nxt[e], 1] - x[e, 1]
    length = np.sqrt(tx * tx + ty * ty)
    if length == 0.0:
        return 0.0
    tx /= length
    ty /= length
    ux = uy = 0.0
    for side in range(2):
        b = bj if side == 0 else bk
        sign = 1.0 if side == 0 else -1.0
        dx = px - centroid[b, 0]
        dy = py - centroid[b, 1]
        d = velocity[b]
        # T(x) d of METHOD.md section 1
        ux += sign * (d[0] - dy * d[2] + dx * d[3] + 0.5 * dy * d[5])
        uy += sign * (d[1] + dx * d[2] + dy * d[4] + 0.5 * dx * d[5])
    return ux * tx + uy * ty


@njit(cache=True)
def _pair_normal_forces(bj, bk, state, t_n, open_state):
    """The closed contacts' normal forces summed over each pair of blocks: the pairs' keys
    ``min(bj, bk) * n + max(bj, bk)`` (``n`` one more than the largest block index), sorted,
    and their sums of ``|t_n|``."""
    n = 1
    for i in range(bj.shape[0]):
        n = max(n, bj[i] + 1, bk[i] + 1)
    keys = np.empty(bj.shape[0], dtype=np.int64)
    for i in range(bj.shape[0]):
        keys[i] = min(bj[i], bk[i]) * n + max(bj[i], bk[i])
    order = np.argsort(keys)
    unique = np.empty(bj.shape[0], dtype=np.int64)
    sums = np.zeros(bj.shape[0])
    m = -1
    for c in order:
        if m < 0 or unique[m] != keys[c]:
            m += 1
            unique[m] = keys[c]
        if state[c] != open_state:
            sums[m] += abs(t_n[c])
    return unique[:m + 1], sums[:m + 1], n


@njit(cache=True)
def _pair_force(keys, sums, n, bj, bk):
    """The summed normal force of the pair ``bj``, ``bk`` (0 when it has no contact)."""
    key = min(bj, bk) * n + max(bj, bk)
    at = np.searchsorted(keys, key)
    if at < keys.shape[0] and keys[at] == key:
        return sums[at]
    return 0.0


@njit(cache=True)
def _earliest_crossing(v0, e0, s0, tn0, bj0, bk0, x0, c0, vel0, v1, e1, s1, tn1, bj1, bk1,
                       x1, c1, vel1, nxt, slip, open_state, normal_ratio, carry):
    """The smallest ``w0 / (w0 - w1)`` over the contacts sliding at the start and closed at
    the end, the normal forces of their pair of blocks (summed over its closed contacts)
    within ``normal_ratio`` of each other, whose slip velocity changed sign; 2.0 when none
    did.

    A start's contact is matched to the first closed trial contact (in the trial's order) of
    the same vertex and edge: the trial's contacts sorted by vertex, each start's vertex
    found by bisection and its few trial contacts scanned."""
    best = 2.0
    order = np.argsort(v1)
    by_vertex = v1[order]
    keys0, sums0, n0 = _pair_normal_forces(bj0, bk0, s0, tn0, open_state)
    keys1, sums1, n1 = _pair_normal_forces(bj1, bk1, s1, tn1, open_state)
    for i in range(v0.shape[0]):
        if s0[i] != slip:
            continue
        t = -1
        for m in range(np.searchsorted(by_vertex, v0[i]), order.shape[0]):
            c = order[m]
            if v1[c] != v0[i]:
                break
            if e1[c] == e0[i] and s1[c] != open_state and (t < 0 or c < t):
                t = c
        if t < 0:
            continue
        a = _pair_force(keys0, sums0, n0, bj0[i], bk0[i])
        b = _pair_force(keys1, sums1, n1, bj1[t], bk1[t])
        if a > normal_ratio * b or b > normal_ratio * a:  # an impact's turn
            continue
        w0 = carry * _slip_velocity(x0, nxt, c0, vel0, v0[i], e0[i], bj0[i], bk0[i])
        w1 = _slip_velocity(x1, nxt, c1, vel1, v1[t], e1[t], bj1[t], bk1[t])
        if w0 * w1 < 0.0:
            phi = w0 / (w0 - w1)
            if phi < best:
                best = phi
    return best


def reversal_fraction(nxt: np.ndarray, before, after, carry: float = 1.0,
                      free: np.ndarray | None = None) -> float | None:
    """Where in the step from ``before`` to ``after`` (:class:`dda.step.StepState`) the first
    contact that was sliding at its start reversed its slip velocity, as a share of the
    step; None when none did.

    Parameters
    ----------
    nxt : (n_vertices,) the next vertex of each vertex on its block
        (:func:`dda.geometry.next_vertex_index`)
    before, after : the committed state and the step's trial
    carry : the share of the committed velocities the free blocks started the step from
        (``Simulation(velocity_carry=...)``)
    free : (n_blocks,) bool, optional
        The blocks whose velocity ``carry`` scales; the others (a table whose motion is
        given) start the step at their committed velocity. Default: every block.

    Committed and trial contacts are matched by vertex and edge (the trial's sorted by
    vertex: ``m log m`` for ``m`` contacts).
    """
    a, b = before.contacts, after.contacts
    start = before.velocity
    if carry != 1.0:  # the free blocks' share; a block whose motion is given keeps its own
        scale = np.full(len(start), carry) if free is None else np.where(free, carry, 1.0)
        start = start * scale[:, None]
    phi = _earliest_crossing(a.vertex, a.edge, a.state, a.t_n, a.bj, a.bk, before.x,
                             before.centroid, start, b.vertex, b.edge, b.state, b.t_n, b.bj,
                             b.bk, after.x, after.centroid, after.velocity, nxt, SLIP, OPEN,
                             NORMAL_RATIO, 1.0)
    return None if phi > 1.0 else float(phi)
