"""A step's contact element in one compiled call (:class:`dda.contact.ContactElement`).

What the element computes at the step's start from the contacts' geometry, independent of
the friction laws: the tributary lengths, the maps of the blocks' unknowns to the contact
points, the rows E and I and the shear gap (METHOD.md section 3), legacy DDA's spring rows,
the round-off of each linearized gap, and with dashpots (:mod:`dda.contact.dashpot`) the
impact dashpot's ``c / dt``, its reference gap, release gap and the judged normal stiffness,
and the shear dashpot's ``c_s / dt``, effective shear penalty and scaled committed ``g_se``.

Each is the arithmetic of the kernel or numpy expression it stands for, in its order (the
same bits, compared by ``tests/test_element_kernel.py``): on a small scene the dozen calls and
lazily computed properties they replace cost more than the arithmetic (about 50 us of a
2-block step).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from dda.kernels.dashpot import dashpot_stiffnesses
from dda.kernels.kinematics import first_variations, pair_maps, tributary_lengths
from dda.kernels.open_close import _np_min, round_off_gaps

__all__ = ["element_arrays"]


@njit(cache=True)
def element_arrays(x, centroid, nxt, prv, vertex, edge, bj, bk, xi0, p1, p2, p3, edge_length,
                   tau, normal, gap, pn, ps, g_se, zeta, zeta_s, free, density, area, sxx, syy,
                   dt, gap_relative, gap_absolute):
    """Every law-independent array of a step's contact element.

    Parameters
    ----------
    x : (n_vertices, 2) vertex positions at the step's start
    centroid : (n_blocks, 2) block centroids at the step's start
    nxt, prv : vertex neighbours
    vertex, edge, bj, bk, xi0 : the contacts (:class:`dda.contact.ContactSet`)
    p1, p2, p3, edge_length, tau, normal, gap : their geometry at ``x``
        (:class:`dda.contact.kinematics.ContactGeometry`)
    pn, ps : (m,) the joints' normal and shear penalties
    g_se : (m,) the committed elastic shear displacements
    zeta, zeta_s : (m,) the impact and shear dashpots' damping ratios; empty arrays: no
        dashpot of that kind
    free, density, area, sxx, syy : the blocks' (the contact masses of the dashpots)
    dt : the step (s)
    gap_relative, gap_absolute : the round-off of a linearized gap
        (:func:`dda.kernels.open_close.round_off_gaps`)

    Returns
    -------
    length : (m,) tributary lengths
    maps : (3, m, 2, 12) the maps of [d_j; d_k] to P1, P2, P3
    shear0 : (m,) the shear gap at the step's start, ``(xi - xi0) l``
    e_row, i_row : (m, 12)
    rows : (m, 2, 12) E and I stacked (legacy DDA's springs)
    gap_tol : (m,) the round-off of each linearized gap
    dashpot, reference, release, judge : (m,) ``c / dt``, ``min(g_n0, 0)``,
        ``c g_ref / (p_n + c)`` and ``p_n + c`` (``dashpot`` empty without impact dashpots,
        ``judge`` then ``pn`` itself)
    shear_dashpot, ps_eff, g_se_scaled : (m,) ``c_s / dt``, ``p_s + c_s / dt`` and
        ``g_se p_s / p_eff`` (empty without shear dashpots)
    """
    m = vertex.shape[0]
    cj = np.empty((m, 2))
    ck = np.empty((m, 2))
    for c in range(m):
        cj[c, 0], cj[c, 1] = centroid[bj[c], 0], centroid[bj[c], 1]
        ck[c, 0], ck[c, 1] = centroid[bk[c], 0], centroid[bk[c], 1]
    length = tributary_lengths(x, vertex, prv, nxt, p1, tau, edge_length)
    maps = pair_maps(x, vertex, edge, nxt, cj, ck)
    _, _, _, _, _, shear0, e_row, i_row = first_variations(p1, p2, p3, xi0, maps[0], maps[1],
                                                           maps[2])
    rows = np.empty((m, 2, 12))
    for c in range(m):
        for j in range(12):
            rows[c, 0, j] = e_row[c, j]
            rows[c, 1, j] = i_row[c, j]
    gap_tol = round_off_gaps(p1, p2, edge_length, gap_relative, gap_absolute)
    reference = np.empty(m)
    for c in range(m):
        reference[c] = _np_min(gap[c], 0.0)
    if zeta.shape[0]:
        dashpot = dashpot_stiffnesses(zeta, pn, p1, normal, bj, bk, centroid, free, density,
                                      area, sxx, syy, dt)
        release = np.empty(m)
        judge = np.empty(m)
        for c in range(m):
            release[c] = dashpot[c] * reference[c] / (pn[c] + dashpot[c])
            judge[c] = pn[c] + dashpot[c]
    else:
        dashpot = np.zeros(0)
        release = np.zeros(m)
        judge = pn
    if zeta_s.shape[0]:
        tangent = np.empty((m, 2))
        for c in range(m):
            tangent[c, 0] = normal[c, 1]
            tangent[c, 1] = -normal[c, 0]
        shear_dashpot = dashpot_stiffnesses(zeta_s, ps, p1, tangent, bj, bk, centroid, free,
                                            density, area, sxx, syy, dt)
        ps_eff = np.empty(m)
        g_se_scaled = np.empty(m)
        for c in range(m):
            ps_eff[c] = ps[c] + shear_dashpot[c]
            g_se_scaled[c] = g_se[c] * (ps[c] / ps_eff[c])
    else:
        shear_dashpot = ps_eff = g_se_scaled = np.zeros(0)
    return (length, maps, shear0, e_row, i_row, rows, gap_tol, dashpot, reference, release,
            judge, shear_dashpot, ps_eff, g_se_scaled)
