"""Compiled contact frame and first variations (:func:`dda.contact.kinematics.trial_kinematics`
without the second variations, which :mod:`dda.kernels.tangent` builds).

On the few contacts of a small scene the numpy version's two dozen array operations cost more
than the arithmetic (the element of the seed rock slope's two contacts spent about 30 us in
it each step, and the fully implicit method does it again at every iteration). This kernel
does the same arithmetic in the same order (the dot products summed from zero, as
``numpy.einsum`` sums them), so the results have the same bits.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["first_variations", "frames", "pair_increments", "pair_maps", "tributary_lengths"]


@njit(cache=True)
def first_variations(p1, p2, p3, xi0, a1, a2, a3):
    """Frame, gaps and rows of each contact of vertex P1 against the reversed edge P2P3.

    ``a1, a2, a3`` (m, 2, 12) map [d_j; d_k] to the motion of the three points. Returns
    ``(length, tau, normal, gap, xi, shear, e_row, i_row)``: ``l = |x3 - x2|``,
    ``tau = (x3 - x2) / l``, ``n = (-tau_y, tau_x)``, ``g_n = (x1 - x2) . n``,
    ``xi = (x1 - x2) . tau / l``, ``g_s = (xi - xi0) l``,
    ``E = n . (da - xi db)``, ``I = tau . (da - xi0 db) + (g_n / l) n . db`` with
    ``da = a1 - a2``, ``db = a3 - a2``.
    """
    m = p1.shape[0]
    length, tau, normal, gap, xi = frames(p1, p2, p3)
    shear = np.empty(m)
    e_row = np.empty((m, 12))
    i_row = np.empty((m, 12))
    for c in range(m):
        n0, n1 = normal[c, 0], normal[c, 1]
        t0, t1 = tau[c, 0], tau[c, 1]
        x = xi[c]
        shear[c] = (x - xi0[c]) * length[c]
        ratio = gap[c] / length[c]
        for j in range(12):
            da0 = a1[c, 0, j] - a2[c, 0, j]
            da1 = a1[c, 1, j] - a2[c, 1, j]
            db0 = a3[c, 0, j] - a2[c, 0, j]
            db1 = a3[c, 1, j] - a2[c, 1, j]
            e = 0.0
            e += n0 * (da0 - x * db0)
            e += n1 * (da1 - x * db1)
            h = 0.0
            h += n0 * db0
            h += n1 * db1
            g0 = 0.0
            g0 += t0 * (da0 - xi0[c] * db0)
            g0 += t1 * (da1 - xi0[c] * db1)
            e_row[c, j] = e
            i_row[c, j] = g0 + ratio * h
    return length, tau, normal, gap, xi, shear, e_row, i_row


@njit(cache=True)
def frames(p1, p2, p3):
    """``(length, tau, normal, gap, xi)`` of each contact (see :func:`first_variations`)."""
    m = p1.shape[0]
    length = np.empty(m)
    tau = np.empty((m, 2))
    normal = np.empty((m, 2))
    gap = np.empty(m)
    xi = np.empty(m)
    for c in range(m):
        ln, t0, t1, n0, n1, g, x = _frame(p1[c, 0], p1[c, 1], p2[c, 0], p2[c, 1], p3[c, 0],
                                          p3[c, 1])
        length[c] = ln
        tau[c, 0] = t0
        tau[c, 1] = t1
        normal[c, 0] = n0
        normal[c, 1] = n1
        gap[c] = g
        xi[c] = x
    return length, tau, normal, gap, xi


@njit(cache=True, inline="always")
def _frame(x1, y1, x2, y2, x3, y3):
    """One contact's edge length, tangent, normal, gap and foot parameter."""
    d0 = x3 - x2
    d1 = y3 - y2
    ln = math.hypot(d0, d1)
    t0 = d0 / ln
    t1 = d1 / ln
    n0 = -t1
    n1 = t0
    r0 = x1 - x2
    r1 = y1 - y2
    g = 0.0
    g += r0 * n0
    g += r1 * n1
    x = 0.0
    x += r0 * t0
    x += r1 * t1
    return ln, t0, t1, n0, n1, g, x / ln


@njit(cache=True)
def pair_maps(x, vertex, edge, nxt, cj, ck):
    """(3, m, 2, 12): the maps of [d_j; d_k] to the motion of the vertex (block j's columns),
    of the edge's end ``nxt[edge]`` and of its start ``edge`` (block k's): each point's
    ``T(x, y)`` (:func:`dda.geometry.t_matrix`) about its block's centroid ``cj`` / ``ck``."""
    m = vertex.shape[0]
    out = np.zeros((3, m, 2, 12))
    for c in range(m):
        for p in range(3):
            if p == 0:
                v, cx, cy, col = vertex[c], cj[c, 0], cj[c, 1], 0
            elif p == 1:
                v, cx, cy, col = nxt[edge[c]], ck[c, 0], ck[c, 1], 6
            else:
                v, cx, cy, col = edge[c], ck[c, 0], ck[c, 1], 6
            dx = x[v, 0] - cx
            dy = x[v, 1] - cy
            out[p, c, 0, col] = 1.0
            out[p, c, 1, col + 1] = 1.0
            out[p, c, 0, col + 2] = -dy
            out[p, c, 1, col + 2] = dx
            out[p, c, 0, col + 3] = dx
            out[p, c, 1, col + 4] = dy
            out[p, c, 0, col + 5] = 0.5 * dy
            out[p, c, 1, col + 5] = 0.5 * dx
    return out


@njit(cache=True)
def tributary_lengths(x, vertex, prv, nxt, p1, tau, length):
    """Half the shorter of the contacted edge and the vertex's own edge (to its previous
    or next vertex) that runs most nearly along it (the previous one when both do)."""
    m = vertex.shape[0]
    out = np.empty(m)
    for c in range(m):
        best_cos = 0.0
        best_len = 0.0
        for k in range(2):
            nb = prv[vertex[c]] if k == 0 else nxt[vertex[c]]
            a0 = x[nb, 0] - p1[c, 0]
            a1 = x[nb, 1] - p1[c, 1]
            la = math.hypot(a0, a1)
            dot = 0.0
            dot += a0 * tau[c, 0]
            dot += a1 * tau[c, 1]
            cos = abs(dot) / la
            if k == 0 or not (best_cos >= cos):
                best_cos, best_len = cos, la
        out[c] = 0.5 * min(length[c], best_len)
    return out


@njit(cache=True)
def pair_increments(d, bj, bk):
    """(m, 12) ``[d[bj[c]], d[bk[c]]]`` of every contact c (a copy of the rows)."""
    m = bj.shape[0]
    out = np.empty((m, 12))
    for c in range(m):
        for i in range(6):
            out[c, i] = d[bj[c], i]
            out[c, 6 + i] = d[bk[c], i]
    return out
