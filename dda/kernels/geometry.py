"""Compiled parts of the polygon integrals of every block (:func:`dda.geometry.polygon_integrals`).

A step computes its blocks' areas, centroids and second moments once; for a few blocks the
numpy version's two dozen array operations cost more than the arithmetic (41 us on two blocks,
against 8 us with these kernels). The kernels do the same arithmetic in the same order, and
the sums over each block's edges stay with ``numpy.add.reduceat`` (whose order of summation
the kernels need not copy), so the results have the same bits.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["edge_terms", "moments_about_centroid", "vertex_turns"]


@njit(cache=True)
def edge_terms(vertices, offsets, nxt):
    """(n_vertices, 6) each edge's terms of the integrals, from the block's first vertex:
    ``c, c (x1 + x2), c (y1 + y2), c (x1^2 + x1 x2 + x2^2), c (y1^2 + y1 y2 + y2^2),
    c (2 x1 y1 + x1 y2 + x2 y1 + 2 x2 y2)`` with ``c = x1 y2 - x2 y1``."""
    out = np.empty((vertices.shape[0], 6))
    for b in range(offsets.shape[0] - 1):
        start = offsets[b]
        rx, ry = vertices[start, 0], vertices[start, 1]
        for i in range(start, offsets[b + 1]):
            x1, y1 = vertices[i, 0] - rx, vertices[i, 1] - ry
            j = nxt[i]
            x2, y2 = vertices[j, 0] - rx, vertices[j, 1] - ry
            c = x1 * y2 - x2 * y1
            out[i, 0] = c
            out[i, 1] = c * (x1 + x2)
            out[i, 2] = c * (y1 + y2)
            out[i, 3] = c * (x1 * x1 + x1 * x2 + x2 * x2)
            out[i, 4] = c * (y1 * y1 + y1 * y2 + y2 * y2)
            out[i, 5] = c * (2 * x1 * y1 + x1 * y2 + x2 * y1 + 2 * x2 * y2)
    return out


@njit(cache=True)
def moments_about_centroid(s, first):
    """(area, centroid, sxx, syy, sxy) from each block's summed edge terms ``s`` and its first
    vertex ``first``."""
    nb = s.shape[0]
    area = np.empty(nb)
    centroid = np.empty((nb, 2))
    sxx = np.empty(nb)
    syy = np.empty(nb)
    sxy = np.empty(nb)
    for b in range(nb):
        a = s[b, 0] / 2.0
        cx = s[b, 1] / 6.0 / a
        cy = s[b, 2] / 6.0 / a
        area[b] = a
        sxx[b] = s[b, 3] / 12.0 - a * cx * cx
        syy[b] = s[b, 4] / 12.0 - a * cy * cy
        sxy[b] = s[b, 5] / 24.0 - a * cx * cy
        centroid[b, 0] = first[b, 0] + cx
        centroid[b, 1] = first[b, 1] + cy
    return area, centroid, sxx, syy, sxy


@njit(cache=True)
def vertex_turns(x, prv, nxt):
    """Per vertex, with arms ``a = prev - v`` and ``b = next - v``: the cross product
    ``a x b``, its round-off scale ``|a| |b|`` (hypot), the dot product ``a . b`` (summed from
    zero, as ``numpy.einsum``) and the outward unit bisector (for a straight vertex, whose
    bisector vanishes, the outward normal of prev -> next). Its numbers are those of the
    numpy formulas in ``tests/test_contact_detection.py``, to the bit."""
    n = x.shape[0]
    cross = np.empty(n)
    scale = np.empty(n)
    dot = np.empty(n)
    bisector = np.empty((n, 2))
    for v in range(n):
        a0 = x[prv[v], 0] - x[v, 0]
        a1 = x[prv[v], 1] - x[v, 1]
        b0 = x[nxt[v], 0] - x[v, 0]
        b1 = x[nxt[v], 1] - x[v, 1]
        cross[v] = a0 * b1 - a1 * b0
        scale[v] = math.hypot(a0, a1) * math.hypot(b0, b1)
        d = 0.0
        d += a0 * b0
        d += a1 * b1
        dot[v] = d
        la = np.sqrt(a0 * a0 + a1 * a1)
        lb = np.sqrt(b0 * b0 + b1 * b1)
        ub0 = b0 / lb
        ub1 = b1 / lb
        i0 = a0 / la + ub0
        i1 = a1 / la + ub1
        norm = np.sqrt(i0 * i0 + i1 * i1)
        if norm < 1e-12:  # straight: the left normal of prev -> next, inward
            i0, i1 = -ub1, ub0
        else:
            norm = max(norm, 1e-300)
            i0, i1 = i0 / norm, i1 / norm
        bisector[v, 0] = -i0
        bisector[v, 1] = -i1
    return cross, scale, dot, bisector
