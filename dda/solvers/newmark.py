"""Newmark time integration with beta = 0.5, gamma = 1.0 (METHOD.md section 2, A1-A4).

Written for the displacement increment d of a step:

    K~ = K + (2 / dt^2) M          F~ = F + (2 / dt) M v_n
    v_{n+1} = (2 / dt) d - v_n

A static analysis is the same with v_n := 0 at every step.
"""

from __future__ import annotations

import numpy as np

__all__ = ["effective_system", "updated_velocity"]


def effective_system(k, m, f, v, dt):
    """Effective block matrices and forces (n_blocks, 6, 6) and (n_blocks, 6).

    ``v`` None is a static step (v_n = 0): the inertial force term is left out, the mass term
    of K~ stays (DDA's static analysis, METHOD.md section 2).
    """
    k_eff = k + (2.0 / dt**2) * m
    if v is None:
        return k_eff, f
    f_eff = f + (2.0 / dt) * np.einsum("bij,bj->bi", m, v)
    return k_eff, f_eff


def updated_velocity(d, v, dt):
    """Velocity at the end of the step, v_{n+1} = 2 d / dt - v_n (v None: a static step)."""
    if v is None:
        return (2.0 / dt) * d
    return (2.0 / dt) * d - v
