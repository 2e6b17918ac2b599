"""Compiled block-level parts of a step: its start (the blocks' matrices and forces, the
Newmark effective system, the predicted vertex speed) and its end (the vertex moves, their
checks and the Newmark update).

On a few blocks the numpy version of these formulas is some forty small array operations a
step, each costing more than its arithmetic (about 60 us at the start and 30 us at the end of
a 2-block step, against a few with these kernels). The kernels do the numpy version's
arithmetic in its order: ``numpy.einsum``'s sums over a 6 x 6 (or 3 x 3) matrix times a vector
add the even and the odd terms apart and then the two, ``(p0 + p2 + p4) + (p1 + p3 + p5)``,
and so do the kernels, so a step gives the same bits either way
(``tests/test_block_kernels.py`` compares them). The sums over a block's edges are
``numpy.add.reduceat``'s, in its order (:func:`dda.kernels.geometry.edge_sums`).

Only a scene whose blocks have no damping, point loads or constraint springs takes these
kernels (:attr:`dda.model.Model.plain_blocks`); the others keep the numpy path, which adds
those terms in its own order.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from dda.kernels.geometry import edge_sums, moments_about_centroid

__all__ = ["step_start", "step_start_at", "step_end"]


@njit(cache=True)
def _dot6(m, b, i, v, r):
    """``numpy.einsum('bij,bj->bi')``'s row ``i`` of block ``b``: ``m[b, i] . v[r]``."""
    even = m[b, i, 0] * v[r, 0] + m[b, i, 2] * v[r, 2] + m[b, i, 4] * v[r, 4]
    odd = m[b, i, 1] * v[r, 1] + m[b, i, 3] * v[r, 3] + m[b, i, 5] * v[r, 5]
    return even + odd


@njit(cache=True)
def step_start(s, first, density, elasticity, gravity, stress, x, block, velocity, carry,
               c_mass, c_vel, dynamic):
    """The blocks' integrals, Newmark effective system and largest predicted vertex speed.

    Parameters
    ----------
    s : (nb, 6) each block's summed edge terms (:func:`dda.kernels.geometry.edge_terms`)
    first : (nb, 2) each block's first vertex
    density, elasticity, gravity, stress : the blocks' (:class:`dda.model.Model`)
    x, block : (n, 2) the vertices and (n,) their blocks
    velocity, carry : (nb, 6) committed velocities and the velocity carry
    c_mass, c_vel : ``2 / dt^2`` and ``2 / dt``
    dynamic : whether the step carries velocity (a static step takes no inertial force)

    Returns
    -------
    area, centroid, sxx, syy, sxy : the integrals (:func:`dda.geometry.polygon_integrals`)
    k_eff, f_eff : ``K + (2 / dt^2) M`` and ``F + (2 / dt) M v`` with ``K = S D`` on the
        strain unknowns, ``M = rho int T^T T dA`` and ``F`` gravity less the stress's
        ``S sigma`` (:func:`dda.solvers.newmark.effective_system`)
    v_eff : (nb, 6) ``carry v``
    speed : the largest ``|T(x) carry v|`` over the vertices
    """
    nb = s.shape[0]
    area, centroid, sxx, syy, sxy = moments_about_centroid(s, first)
    m = np.zeros((nb, 6, 6))
    k_eff = np.empty((nb, 6, 6))
    f_eff = np.zeros((nb, 6))
    v_eff = np.empty((nb, 6))
    for b in range(nb):
        a, xx, yy, xy = area[b], sxx[b], syy[b], sxy[b]
        rho = density[b]
        m[b, 0, 0] = a * rho
        m[b, 1, 1] = a * rho
        m[b, 2, 2] = (xx + yy) * rho
        m[b, 3, 3] = xx * rho
        m[b, 4, 4] = yy * rho
        m[b, 5, 5] = 0.25 * (xx + yy) * rho
        m[b, 2, 3] = m[b, 3, 2] = -xy * rho
        m[b, 2, 4] = m[b, 4, 2] = xy * rho
        m[b, 2, 5] = m[b, 5, 2] = 0.5 * (xx - yy) * rho
        m[b, 3, 5] = m[b, 5, 3] = 0.5 * xy * rho
        m[b, 4, 5] = m[b, 5, 4] = 0.5 * xy * rho
        for i in range(6):
            for j in range(6):
                kij = a * elasticity[b, i - 3, j - 3] if i >= 3 and j >= 3 else 0.0
                k_eff[b, i, j] = kij + c_mass * m[b, i, j]
            v_eff[b, i] = velocity[b, i] * carry
        if gravity != 0.0:
            f_eff[b, 1] = 0.0 - gravity * rho * a
        for i in range(3):
            f_eff[b, 3 + i] = 0.0 - a * stress[b, i]
        if dynamic:
            for i in range(6):
                f_eff[b, i] = f_eff[b, i] + c_vel * _dot6(m, b, i, v_eff, b)
    speed = 0.0
    for p in range(x.shape[0]):
        b = block[p]
        dx = x[p, 0] - centroid[b, 0]
        dy = x[p, 1] - centroid[b, 1]
        v0, v1, v2, v3, v4, v5 = (v_eff[b, 0], v_eff[b, 1], v_eff[b, 2], v_eff[b, 3],
                                  v_eff[b, 4], v_eff[b, 5])
        # T(x) v in numpy.einsum's order, the zero terms of T included
        u = (1.0 * v0 + -dy * v2 + 0.0 * v4) + (0.0 * v1 + dx * v3 + 0.5 * dy * v5)
        w = (0.0 * v0 + dx * v2 + dy * v4) + (1.0 * v1 + 0.0 * v3 + 0.5 * dx * v5)
        h = math.hypot(u, w)
        if h > speed or p == 0:
            speed = h
    return area, centroid, sxx, syy, sxy, k_eff, f_eff, v_eff, speed


@njit(cache=True)
def step_start_at(x, offsets, nxt, density, elasticity, gravity, stress, block, velocity, carry,
                  c_mass, c_vel, dynamic):
    """:func:`step_start` from the vertices ``x`` (the blocks' ``offsets`` and next-vertex
    table ``nxt``): their edge sums (:func:`dda.kernels.geometry.edge_sums`) and first
    vertices taken here, in the same call."""
    first = np.empty((offsets.shape[0] - 1, 2))
    for b in range(first.shape[0]):
        first[b, 0] = x[offsets[b], 0]
        first[b, 1] = x[offsets[b], 1]
    return step_start(edge_sums(x, offsets, nxt), first, density, elasticity, gravity, stress,
                      x, block, velocity, carry, c_mass, c_vel, dynamic)


@njit(cache=True)
def step_end(x, block, offsets, centroid, d, free, size, v_eff, dynamic, c_vel, elasticity,
             stress, rotation):
    """The vertex moves of the increments ``d`` and the Newmark update of an accepted step.

    Each vertex moves by ``T d`` with the rotation made finite (:func:`dda.geometry.
    vertex_displacements`); the velocity is ``2 d / dt - v`` (``2 d / dt`` in a static step)
    and the stress grows by ``D eps`` on free blocks (:func:`dda.step._advanced`).

    Returns
    -------
    move, x_new : (n, 2)
    largest : the largest vertex move
    worst, worst_move : the free block whose largest move is the largest share of its size
        (the first of them), and that move
    velocity, stress, rotation, centroid : (nb, ...) the blocks' at the step's end (the
        velocity of blocks whose motion is known is left 0 here)
    """
    n = x.shape[0]
    nb = d.shape[0]
    move = np.empty((n, 2))
    x_new = np.empty((n, 2))
    distance = np.empty(n)
    largest = 0.0
    for p in range(n):
        b = block[p]
        dx = x[p, 0] - centroid[b, 0]
        dy = x[p, 1] - centroid[b, 1]
        r = d[b, 2]
        c = math.cos(r) - 1.0
        sn = math.sin(r)
        g = d[b, 5]
        u = d[b, 0] + c * dx - sn * dy + d[b, 3] * dx + 0.5 * g * dy
        v = d[b, 1] + sn * dx + c * dy + 0.5 * g * dx + d[b, 4] * dy
        move[p, 0] = u
        move[p, 1] = v
        x_new[p, 0] = x[p, 0] + u
        x_new[p, 1] = x[p, 1] + v
        h = math.hypot(u, v)
        distance[p] = h
        if h > largest or p == 0:
            largest = h
    worst = 0
    worst_ratio = -1.0
    worst_move = 0.0
    velocity = np.zeros((nb, 6))
    new_stress = np.empty((nb, 3))
    new_rotation = np.empty(nb)
    new_centroid = np.empty((nb, 2))
    for b in range(nb):
        per_block = distance[offsets[b]]
        for p in range(offsets[b] + 1, offsets[b + 1]):
            if distance[p] > per_block:
                per_block = distance[p]
        ratio = per_block / size[b] if free[b] else 0.0
        if ratio > worst_ratio:
            worst, worst_ratio, worst_move = b, ratio, per_block
        for i in range(3):
            grow = 0.0
            if free[b]:
                grow = (elasticity[b, i, 0] * d[b, 3] + elasticity[b, i, 2] * d[b, 5]) \
                    + elasticity[b, i, 1] * d[b, 4]
            new_stress[b, i] = stress[b, i] + grow
        if free[b]:
            for i in range(6):
                if dynamic:
                    velocity[b, i] = c_vel * d[b, i] - v_eff[b, i]
                else:
                    velocity[b, i] = c_vel * d[b, i]
        new_rotation[b] = rotation[b] + d[b, 2]
        new_centroid[b, 0] = centroid[b, 0] + d[b, 0]
        new_centroid[b, 1] = centroid[b, 1] + d[b, 1]
    return (move, x_new, largest, worst, worst_move, velocity, new_stress, new_rotation,
            new_centroid)
