"""The contacts' stiffness on [d_j; d_k] as sums of rank-one terms (:class:`PairStiffness`).

Legacy DDA's springs and the consistent tangent of the fully implicit method are built from
a few 12-rows per contact (METHOD.md sections 3-4) instead of (m, 12, 12) arrays; the
assembly sums their outer products where they go (:mod:`dda.kernels.assembly`).
"""

from __future__ import annotations

import numpy as np

from dda.kernels.pair_stiffness import PairStiffness
from dda.kernels.tangent import tangent_rows

__all__ = ["spring_stiffness", "consistent_tangent", "SPRING_TERMS"]

#: the terms (E, E) and (I, I) of legacy DDA's springs on the rows [E, I]
SPRING_TERMS = np.array([[0, 0], [1, 1]], dtype=np.int64)
# rows E, I, S, H, B: p_n E^T E + I^T S + B^T H + H^T B
_TANGENT_TERMS = np.array([[0, 0], [1, 2], [4, 3], [3, 4]], dtype=np.int64)


def spring_stiffness(e_row, i_row, kn, ks) -> PairStiffness:
    """Legacy DDA's normal and shear springs: ``K = k_n E^T E + k_s I^T I``.

    Parameters
    ----------
    e_row, i_row : (m, 12) the rows E and I of the step's start
    kn, ks : (m,) the springs' stiffness (zero where a spring is off)
    """
    return PairStiffness(np.stack([e_row, i_row], axis=1), SPRING_TERMS,
                         np.stack([kn, ks], axis=1))


def consistent_tangent(kin, maps, xi0, kn, kss, ksn, t_n, t_s, closed) -> PairStiffness:
    """The consistent tangent of the contact forces ``t_n E^T + t_s I^T`` (METHOD.md s. 4).

        K = k_n E^T E + I^T S + t_n Delta delta g_n + t_s Delta delta g_s
          = k_n E^T E + I^T S + B^T H + H^T B

    with ``S = k_ss I + k_sn E`` on a closed contact (zero on an open one) and, from the
    second variations of :func:`dda.contact.kinematics.trial_kinematics`,

        B = (t_s E' - t_n G) / l - (t_s g_n / l^2) J - ((t_n g_n + t_s g_s) / (2 l^2)) H

    Parameters
    ----------
    kin : TrialKinematics at the trial state (its first variations suffice)
    maps : the three (m, 2, 12) maps of :func:`dda.contact.kinematics.pair_maps`
    xi0 : (m,) shear reference parameter
    kn : (m,) normal penalty of the closed contacts (zero on the open ones)
    kss, ksn : (m,) the friction law's tangent d t_s / d g_s and d t_s / d g_n
    t_n, t_s : (m,) the normal and shear forces
    closed : (m,) bool
    """
    rows = tangent_rows(*maps, kin.normal, kin.tau, kin.xi, xi0, kin.gap, kin.shear,
                        kin.length, kin.e_row, kin.i_row, kss, ksn, t_n, t_s, closed)
    one = np.ones(len(kn))
    weights = np.stack([kn, one, one, one], axis=1).astype(np.float64, copy=False)
    return PairStiffness.checked_by_caller(rows, _TANGENT_TERMS, weights)
