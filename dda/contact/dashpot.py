"""The impact dashpot of a joint: a normal viscosity beside each closed contact's spring.

Without it a penalty impact loses energy only through Newmark's gamma = 1, so how much depends
on dt and on the penalty (``benchmarks/impact_restitution.py``), and a rocking block's decay with
it. A joint's ``restitution`` sets a dashpot ``c`` per closed contact, in parallel with its
normal spring ``p_n``, that gives a mass striking the spring that coefficient of restitution:

    c = 2 zeta sqrt(p_n m),   1 / m = sum over the contact's two blocks of (1/m_b + a_b^2 / I_b)

with zeta from :func:`damping_ratio` and ``m`` the contact mass (:func:`contact_mass`): the
mass a rigid block shows at the contact along its normal, its translation and its rotation
about its centroid (``a_b`` the normal's lever arm, ``I_b`` the polar moment), the two blocks
in series; a block whose motion is known counts as infinitely heavy. (A DDA block's strain
modes would make it lighter still, 0.14 of the mass at the corner of a 15 x 45 cm block against
0.77 rigid, but they answer a penalty spring a hundred times softer than the block as a rigid
body does.) The
dashpot acts on the step's change of the normal gap, its mean velocity over the step,

    t_d = (c / dt) (g_n - g_n0)

so it adds ``c / dt`` to the normal spring's stiffness ``E^T E`` and nothing to its force at the
step's start: exact for legacy DDA's gaps linearized at the step's start (``g_n - g_n0 = E d``)
and, with the exact gap, for the fully implicit method, whose tangent takes ``c / dt`` and
``t_d``'s geometric term. The normal force a friction law sees, the one OPEN-CLOSE judges and
the one a step records stay the spring's, ``p_n g_n``: a dashpot resists the rate of closing,
not the load a face carries, and a contact still opens when its gap does. A static analysis
(no velocity carried) takes no dashpot.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["damping_ratio", "contact_mass", "dashpot_stiffness"]


def damping_ratio(restitution: float) -> float:
    """The damping ratio zeta of a linear spring-dashpot whose impact rebounds with the
    coefficient of restitution ``e`` (a mass striking the spring leaves when the spring is
    back at its length):

        e = exp(-pi zeta / sqrt(1 - zeta^2)),   zeta = -ln e / sqrt(pi^2 + ln^2 e)

    ``e = 1`` gives 0 (no dashpot), ``e = 0`` gives 1 (critical damping: no rebound).

    Examples
    --------
    >>> round(damping_ratio(0.5), 4), damping_ratio(1.0), damping_ratio(0.0)
    (0.2155, 0.0, 1.0)
    """
    if restitution >= 1.0:
        return 0.0
    if restitution <= 0.0:
        return 1.0
    log_e = math.log(restitution)
    return -log_e / math.sqrt(math.pi**2 + log_e**2)


def contact_mass(point, normal, centroid_j, centroid_k, mass_j, mass_k, inertia_j,
                 inertia_k) -> np.ndarray:
    """(m,) the mass each contact's normal sees: ``1 / sum_b (1/m_b + a_b^2 / I_b)`` over its
    two blocks, ``a_b = (x - x_b) x n`` the lever arm of the normal about block b's centroid.

    Parameters
    ----------
    point, normal : (m, 2) the contact point (the vertex) and the unit normal
    centroid_j, centroid_k : (m, 2) the two blocks' centroids
    mass_j, mass_k, inertia_j, inertia_k : (m,) their masses and polar moments about their
        centroids (``inf`` for a block whose motion is known)
    """
    inverse = np.zeros(len(point))
    for centroid, mass, inertia in ((centroid_j, mass_j, inertia_j),
                                    (centroid_k, mass_k, inertia_k)):
        r = point - centroid
        arm = r[:, 0] * normal[:, 1] - r[:, 1] * normal[:, 0]
        inverse += 1.0 / mass + arm * arm / inertia  # 1/inf = 0
    return 1.0 / inverse


def dashpot_stiffness(zeta, normal_penalty, mass, dt) -> np.ndarray:
    """(m,) each contact's dashpot as a stiffness on the step's gap change, ``c / dt`` with
    ``c = 2 zeta sqrt(p_n m)`` (the module docstring).

    Parameters
    ----------
    zeta, normal_penalty : (m,) damping ratio and normal penalty of each contact's joint
    mass : (m,) its contact mass (:func:`contact_mass`)
    dt : the step (s)
    """
    return 2.0 * zeta * np.sqrt(normal_penalty * mass) / dt
