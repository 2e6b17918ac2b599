"""Compiled parts of the polygon integrals of every block (:func:`dda.geometry.polygon_integrals`).

A step computes its blocks' areas, centroids and second moments once; for a few blocks the
numpy version's two dozen array operations cost more than the arithmetic (41 us on two blocks,
against 8 us with these kernels). The kernels do the same arithmetic in the same order, and
sum each block's edge terms in ``numpy.add.reduceat``'s order (:mod:`dda.kernels.sums`), so
the results have the same bits.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from dda.kernels.sums import run_sum

__all__ = ["edge_sums", "edge_terms", "moments_about_centroid", "vertex_turns"]


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
def edge_sums(vertices, offsets, nxt):
    """(n_blocks, 6) each block's :func:`edge_terms` summed over its edges, in
    ``numpy.add.reduceat(edge_terms(...), offsets[:-1], axis=0)``'s order (its bits)."""
    terms = edge_terms(vertices, offsets, nxt)
    n = terms.shape[0]
    columns = np.empty((6, n))
    for i in range(n):
        for k in range(6):
            columns[k, i] = terms[i, k]
    order = np.arange(n)
    nb = offsets.shape[0] - 1
    s = np.empty((nb, 6))
    for b in range(nb):
        for k in range(6):
            s[b, k] = run_sum(columns[k], order, offsets[b], offsets[b + 1])
    return s


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


@njit(cache=True)
def self_intersections(v, tol_cross, tol_touch):
    """(k, 2) the pairs (i < j) of non-adjacent edges of one polygon (edge i runs from vertex
    i to i + 1) that cross (orientation products below ``-tol_cross``) or where a start
    vertex lies within ``tol_touch`` of the other edge, sorted; :func:`dda.geometry.
    self_intersections`' arithmetic pair by pair, after a sweep over the edges' boxes grown
    by ``tol_touch`` (O(n log n) plus the pairs whose boxes meet, in place of all n^2)."""
    n = v.shape[0]
    xmin = np.empty(n)
    xmax = np.empty(n)
    ymin = np.empty(n)
    ymax = np.empty(n)
    for e in range(n):
        f = (e + 1) % n
        xmin[e] = min(v[e, 0], v[f, 0]) - tol_touch
        xmax[e] = max(v[e, 0], v[f, 0]) + tol_touch
        ymin[e] = min(v[e, 1], v[f, 1]) - tol_touch
        ymax[e] = max(v[e, 1], v[f, 1]) + tol_touch
    order = np.argsort(xmin, kind="mergesort")
    found_i = []
    found_j = []
    for a in range(n):
        e = order[a]
        for b in range(a + 1, n):
            g = order[b]
            if xmin[g] > xmax[e]:
                break
            if ymin[g] > ymax[e] or ymin[e] > ymax[g]:
                continue
            i, j = min(e, g), max(e, g)
            if j - i < 2 or (i == 0 and j == n - 1):
                continue  # adjacent edges share a vertex
            if _edges_meet(v, i, j, n, tol_cross, tol_touch):
                found_i.append(i)
                found_j.append(j)
    k = len(found_i)
    out = np.empty((k, 2), dtype=np.int64)
    for r in range(k):
        out[r, 0] = found_i[r]
        out[r, 1] = found_j[r]
    if k:
        key = out[:, 0] * n + out[:, 1]
        out = out[np.argsort(key)]
    return out


@njit(cache=True, inline="always")
def _orient(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@njit(cache=True, inline="always")
def _on_segment(px, py, ax, ay, bx, by, tol):
    abx = bx - ax
    aby = by - ay
    t = (0.0 + (px - ax) * abx + (py - ay) * aby) / (0.0 + abx * abx + aby * aby)
    t = min(max(t, 0.0), 1.0)
    dx = px - (ax + t * abx)
    dy = py - (ay + t * aby)
    return np.sqrt(dx * dx + dy * dy) <= tol


@njit(cache=True)
def _edges_meet(v, i, j, n, tol_cross, tol_touch):
    p1x, p1y = v[i, 0], v[i, 1]
    p2x, p2y = v[(i + 1) % n, 0], v[(i + 1) % n, 1]
    q1x, q1y = v[j, 0], v[j, 1]
    q2x, q2y = v[(j + 1) % n, 0], v[(j + 1) % n, 1]
    d1 = _orient(q1x, q1y, q2x, q2y, p1x, p1y)
    d2 = _orient(q1x, q1y, q2x, q2y, p2x, p2y)
    d3 = _orient(p1x, p1y, p2x, p2y, q1x, q1y)
    d4 = _orient(p1x, p1y, p2x, p2y, q2x, q2y)
    if d1 * d2 < -tol_cross and d3 * d4 < -tol_cross:
        return True
    return (_on_segment(p1x, p1y, q1x, q1y, q2x, q2y, tol_touch)
            or _on_segment(q1x, q1y, p1x, p1y, p2x, p2y, tol_touch))
