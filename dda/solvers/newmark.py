"""Newmark time integration with beta = 0.5, gamma = 1.0 (METHOD.md section 2, A1-A4).

Written for the displacement increment d of a step of ``M a + C v + K u = F``:

    K~ = K + (2 / dt^2) M + (2 / dt) C          F~ = F + (2 / dt) M v_n + C v_n
    v_{n+1} = (2 / dt) d - v_n

C is the scene's viscous damping (none unless the scene sets it). A static analysis is the
same with v_n := 0 at every step.
"""

from __future__ import annotations

import numpy as np

__all__ = ["effective_system", "updated_velocity"]


def effective_system(k, m, f, v, dt, c=None):
    """Effective block matrices and forces (n_blocks, 6, 6) and (n_blocks, 6).

    ``v`` None is a static step (v_n = 0): the inertial and damping force terms are left out,
    the mass term of K~ stays (DDA's static analysis, METHOD.md section 2). ``c`` None is a
    scene without damping: no damping term at all.

    The damping terms follow from ``C v_{n+1}`` with ``v_{n+1} = (2 / dt) d - v_n``.

    Examples
    --------
    >>> import numpy as np
    >>> m, k, c = np.eye(6)[None], np.zeros((1, 6, 6)), 0.5 * np.eye(6)[None]
    >>> v = np.ones((1, 6))
    >>> k_eff, f_eff = effective_system(k, m, np.zeros((1, 6)), v, 0.1, c)
    >>> round(float(k_eff[0, 0, 0]), 9), float(f_eff[0, 0])  # 2/dt^2 + 2 c/dt, 2/dt + c
    (210.0, 20.5)
    """
    k_eff = k + (2.0 / dt**2) * m
    if c is not None:
        k_eff += (2.0 / dt) * c
    if v is None:
        return k_eff, f
    f_eff = f + (2.0 / dt) * np.einsum("bij,bj->bi", m, v)
    if c is not None:
        f_eff += np.einsum("bij,bj->bi", c, v)
    return k_eff, f_eff


def updated_velocity(d, v, dt):
    """Velocity at the end of the step, v_{n+1} = 2 d / dt - v_n (v None: a static step)."""
    if v is None:
        return (2.0 / dt) * d
    return (2.0 / dt) * d - v
