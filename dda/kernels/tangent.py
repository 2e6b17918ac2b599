"""The rows of the consistent tangent's rank-one terms, one contact at a time.

The fully implicit method's contact stiffness is ``p_n E^T E + I^T S + B^T H + H^T B``
(:func:`dda.contact.tangent.consistent_tangent`); this kernel builds the rows E, I, S, H, B of
every contact in one pass, without the (m, 2, 12) temporaries numpy would need.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["tangent_rows"]


@njit(cache=True)
def tangent_rows(a1, a2, a3, normal, tau, xi, xi0, gap, shear, length, e_row, i_row, kss,
                 ksn, t_n, t_s, closed):
    """(m, 5, 12) rows E, I, S, H, B of each contact (METHOD.md sections 3-4).

    With ``da = A1 - A2`` and ``db = A3 - A2`` (the maps of the vertex and the edge's ends):

        H = n . db,   J = tau . db,   G = tau . (da - xi db),   E' = n . (da - xi0 db)
        S = k_ss I + k_sn E  (closed contacts; zero on open ones)
        B = (t_s E' - t_n G) / l - (t_s g_n / l^2) J - ((t_n g_n + t_s g_s) / (2 l^2)) H
    """
    m = e_row.shape[0]
    rows = np.empty((m, 5, 12))
    for c in range(m):
        n0, n1, t0, t1 = normal[c, 0], normal[c, 1], tau[c, 0], tau[c, 1]
        inv_l = 1.0 / length[c]
        w_e0 = inv_l * t_s[c]
        w_g = inv_l * t_n[c]
        w_j = inv_l * inv_l * t_s[c] * gap[c]
        w_h = 0.5 * inv_l * inv_l * (t_n[c] * gap[c] + t_s[c] * shear[c])
        for q in range(12):
            db0 = a3[c, 0, q] - a2[c, 0, q]
            db1 = a3[c, 1, q] - a2[c, 1, q]
            da0 = a1[c, 0, q] - a2[c, 0, q]
            da1 = a1[c, 1, q] - a2[c, 1, q]
            h = n0 * db0 + n1 * db1
            j = t0 * db0 + t1 * db1
            g = t0 * (da0 - xi[c] * db0) + t1 * (da1 - xi[c] * db1)
            e0 = n0 * (da0 - xi0[c] * db0) + n1 * (da1 - xi0[c] * db1)
            e, i = e_row[c, q], i_row[c, q]
            rows[c, 0, q] = e
            rows[c, 1, q] = i
            rows[c, 2, q] = kss[c] * i + ksn[c] * e if closed[c] else 0.0
            rows[c, 3, q] = h
            rows[c, 4, q] = w_e0 * e0 - w_g * g - w_j * j - w_h * h
    return rows
