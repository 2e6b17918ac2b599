"""Compiled impact dashpots of a step's contacts (:mod:`dda.contact.dashpot`).

:func:`dda.contact.dashpot.contact_mass` and :func:`dda.contact.dashpot.dashpot_stiffness` in
one pass over the contacts, with their arithmetic in their order (the same bits; a dozen small
array operations a step, 15 us on a 2-block scene, against 2 here).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["add_dashpot", "dashpot_stiffnesses", "shear_dashpot_ends"]


@njit(cache=True)
def dashpot_stiffnesses(zeta, normal_penalty, point, normal, bj, bk, centroid, free, density,
                        area, sxx, syy, dt):
    """(m,) each contact's dashpot ``c / dt = 2 zeta sqrt(p_n m) / dt`` with the contact mass
    ``1 / m = sum_b (1 / m_b + a_b^2 / I_b)`` over its blocks, ``a_b = (x - x_b) x n``,
    ``m_b = rho A`` and ``I_b = rho (Sxx + Syy)`` (infinite for a block whose motion is
    known)."""
    m = point.shape[0]
    out = np.empty(m)
    for c in range(m):
        inverse = 0.0
        for side in range(2):
            b = bj[c] if side == 0 else bk[c]
            if free[b]:
                mass = density[b] * area[b]
                inertia = density[b] * (sxx[b] + syy[b])
            else:
                mass = np.inf
                inertia = np.inf
            r0 = point[c, 0] - centroid[b, 0]
            r1 = point[c, 1] - centroid[b, 1]
            arm = r0 * normal[c, 1] - r1 * normal[c, 0]
            inverse = inverse + (1.0 / mass + arm * arm / inertia)
        mass_c = 1.0 / inverse
        out[c] = 2.0 * zeta[c] * math.sqrt(normal_penalty[c] * mass_c) / dt
    return out


@njit(cache=True)
def add_dashpot(weights, force, state, dashpot, gap0, reference, e_row):
    """Legacy DDA's spring weights and forces with each closed contact's impact dashpot, in
    place (:meth:`dda.contact.ContactElement.with_dashpot`): ``c / dt`` added to ``k_n`` and
    ``(c / dt)(g_n0 - g_ref) E`` taken from the force (element by element, as numpy)."""
    for c in range(state.shape[0]):
        cd = dashpot[c] if state[c] != 0 else 0.0
        weights[c, 0] += cd
        g = cd * (gap0[c] - reference[c])
        for j in range(e_row.shape[1]):
            force[c, j] -= g * e_row[c, j]


@njit(cache=True)
def shear_dashpot_ends(state, g_se, t_s, shear_penalty, shear_dashpot, g_se0):
    """:func:`dda.contact.dashpot.shear_dashpot_end`'s arithmetic: ``(g_se, t_s)`` of the
    step's contacts with the shear dashpot taken out of a closed contact's spring (new
    arrays; an open contact, and one without a dashpot, keeps what its law gave it)."""
    m = state.shape[0]
    g_out = np.empty(m)
    t_out = np.empty(m)
    for c in range(m):
        if state[c] != 0 and shear_dashpot[c] > 0.0:
            scaled0 = g_se0[c] * (shear_penalty[c] / (shear_penalty[c] + shear_dashpot[c]))
            g_out[c] = g_se0[c] + (g_se[c] - scaled0)
            t_out[c] = shear_penalty[c] * g_out[c]
        else:
            g_out[c] = g_se[c]
            t_out[c] = t_s[c]
    return g_out, t_out
