"""Compiled bolt terms (:mod:`dda.bolts`): a step's rows, weights and forces, and the bolts'
material points moved by a step, in one call each.

On the one bolt of a 2-block scene the numpy versions (:meth:`dda.bolts.BoltTerm.build`,
:func:`dda.bolts.moved_points`) cost some 65 and 25 us a call, numpy's per-call overhead on
arrays of a few numbers; these do the same arithmetic (``tests/test_bolts.py`` compares
them).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["bolt_rows", "fold_anchored", "moved_bolt_points"]


@njit(cache=True)
def bolt_rows(points, a, b, centroid, k, n0):
    """``(rows, weights, force)`` of :meth:`dda.bolts.BoltTerm.build`: per bolt the rows
    ``r = R^T n`` and ``s = R^T t`` on ``[d_a; d_b]``, the weights ``(k, N0 / L)`` and the
    force ``-N0 r``, with ``R = [-T_a, T_b]`` at the bolt's ends ``points`` (m, 2, 2)."""
    m = points.shape[0]
    rows = np.zeros((m, 2, 12))
    weights = np.empty((m, 2))
    force = np.empty((m, 12))
    for i in range(m):
        ax, ay = points[i, 0, 0], points[i, 0, 1]
        bx, by = points[i, 1, 0], points[i, 1, 1]
        dx, dy = bx - ax, by - ay
        length = np.hypot(dx, dy)
        if length > 0.0:
            nx, ny = dx / length, dy / length
            weights[i, 1] = n0[i] / length
        else:
            nx, ny = 0.0, 0.0
            weights[i, 1] = 0.0
        weights[i, 0] = k[i]
        # T(x)^T e = [e0, e1, -y e0 + x e1, x e0, y e1, (y e0 + x e1) / 2] about the centroid
        xa, ya = ax - centroid[a[i], 0], ay - centroid[a[i], 1]
        xb, yb = bx - centroid[b[i], 0], by - centroid[b[i], 1]
        for j in range(2):
            e0, e1 = (nx, ny) if j == 0 else (-ny, nx)
            rows[i, j, 0] = -e0
            rows[i, j, 1] = -e1
            rows[i, j, 2] = -(-ya * e0 + xa * e1)
            rows[i, j, 3] = -(xa * e0)
            rows[i, j, 4] = -(ya * e1)
            rows[i, j, 5] = -(0.5 * ya * e0 + 0.5 * xa * e1)
            rows[i, j, 6] = e0
            rows[i, j, 7] = e1
            rows[i, j, 8] = -yb * e0 + xb * e1
            rows[i, j, 9] = xb * e0
            rows[i, j, 10] = yb * e1
            rows[i, j, 11] = 0.5 * yb * e0 + 0.5 * xb * e1
        for c in range(12):
            force[i, c] = -n0[i] * rows[i, 0, c]
    return rows, weights, force


@njit(cache=True)
def moved_bolt_points(points, blocks, centroid, d):
    """The bolts' ends (n, 2, 2) moved by the blocks' increments ``d`` (n_blocks, 6) from a
    step's start, as :func:`dda.geometry.vertex_displacements` moves the vertices (the
    rotation made exact)."""
    out = np.empty_like(points)
    for i in range(points.shape[0]):
        for j in range(2):
            blk = blocks[i, j]
            dx = points[i, j, 0] - centroid[blk, 0]
            dy = points[i, j, 1] - centroid[blk, 1]
            r = d[blk, 2]
            c = np.cos(r) - 1.0
            s = np.sin(r)
            ex, ey, g = d[blk, 3], d[blk, 4], d[blk, 5]
            u = d[blk, 0] + c * dx - s * dy + ex * dx + 0.5 * g * dy
            v = d[blk, 1] + s * dx + c * dy + 0.5 * g * dx + ey * dy
            out[i, j, 0] = points[i, j, 0] + u
            out[i, j, 1] = points[i, j, 1] + v
    return out


@njit(cache=True)
def fold_anchored(rows, weights, force, bj, bk, free, block_k, block_f, d_known):
    """``(block_k, block_f, coupled)``: copies of the blocks' matrices and forces with the
    bolts that have one free end folded into that end's block,

        K_ff += w0 r_f r_f^T + w1 s_f s_f^T,
        f_f += f_bolt,f - (w0 r_f (r_k . d_k) + w1 s_f (s_k . d_k)),

    (``f``: the free end's six entries of a bolt's rows, ``k``: the known end's, ``d_k`` its
    known increment), and (m,) bool, the bolts between two free blocks (the rest: both ends
    known, which a scene refuses)."""
    k = block_k.copy()
    f = block_f.copy()
    m = rows.shape[0]
    coupled = np.zeros(m, dtype=np.bool_)
    for i in range(m):
        fa, fb = free[bj[i]], free[bk[i]]
        if fa and fb:
            coupled[i] = True
            continue
        if not (fa or fb):
            continue
        own, other = (0, 6) if fa else (6, 0)
        blk = bj[i] if fa else bk[i]
        known = bk[i] if fa else bj[i]
        for j in range(2):
            w = weights[i, j]
            proj = 0.0
            for c in range(6):
                proj += rows[i, j, other + c] * d_known[known, c]
            for p in range(6):
                rp = rows[i, j, own + p]
                f[blk, p] -= w * rp * proj
                for q in range(6):
                    k[blk, p, q] += w * rp * rows[i, j, own + q]
        for p in range(6):
            f[blk, p] += force[i, own + p]
    return k, f, coupled
