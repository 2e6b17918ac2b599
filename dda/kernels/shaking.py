"""A shaken block's motion integrated over steps (:class:`dda.effects.AccelerationHistory`).

One kernel serves a single step (:meth:`~dda.effects.AccelerationHistory.advance`) and a batch
of steps (:meth:`~dda.effects.AccelerationHistory.advance_many`, for
:mod:`dda.compiled_run`), so that the two give the same bits.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["gauss_legendre_steps"]


@njit(cache=True)
def gauss_legendre_steps(u0, v0, start, end, last, acc, weights, nodes):
    r"""Displacement and velocity after each of a run of steps of a callable acceleration,
    integrated segment by segment with the Gauss-Legendre rule ``(weights, nodes)`` on
    [0, 1]: over a segment from ``t0`` to ``t0 + h``, with ``s_j = h x_j``,

    .. math::

        u_1 = u_0 + v_0 h + h \sum_j w_j (h - s_j)\, a(t_0 + s_j), \qquad
        v_1 = v_0 + h \sum_j w_j\, a(t_0 + s_j)

    (the exact integrals of a polynomial acceleration of degree up to 2J - 1).

    Parameters
    ----------
    u0, v0 : (2,) displacement and velocity at the first segment's start
    start, end : (S,) the segments' start and end times, in order, each starting where the
        one before ended
    last : (S,) bool, whether a segment ends a step
    acc : (S, J, 2) the accelerations at ``start + (end - start) * nodes``
    weights, nodes : (J,) the rule on [0, 1]

    Returns
    -------
    u, v : (K, 2) at the end of each step (K the segments that end one)
    """
    steps = 0
    for i in range(last.shape[0]):
        if last[i]:
            steps += 1
    u = np.empty((steps, 2))
    v = np.empty((steps, 2))
    ux, uy, vx, vy = u0[0], u0[1], v0[0], v0[1]
    k = 0
    for i in range(start.shape[0]):
        h = end[i] - start[i]
        dux = duy = dvx = dvy = 0.0
        for j in range(nodes.shape[0]):
            c = weights[j] * (h - h * nodes[j])
            dux += c * acc[i, j, 0]
            duy += c * acc[i, j, 1]
            dvx += weights[j] * acc[i, j, 0]
            dvy += weights[j] * acc[i, j, 1]
        ux = ux + vx * h + h * dux
        uy = uy + vy * h + h * duy
        vx = vx + h * dvx
        vy = vy + h * dvy
        if last[i]:
            u[k, 0], u[k, 1], v[k, 0], v[k, 1] = ux, uy, vx, vy
            k += 1
    return u, v
