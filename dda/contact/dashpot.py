"""The impact dashpot of a joint: a normal viscosity beside each closed contact's spring.

Without it a penalty impact loses energy only through Newmark's gamma = 1, so how much depends
on dt and on the penalty (``benchmarks/impact_restitution.py``), and a rocking block's decay with
it. A joint's ``restitution`` e (0 by default, 1 for none) sets a dashpot ``c`` per closed
contact, in parallel with its normal spring ``p_n``:

    c = 2 zeta sqrt(p_n m),   1 / m = sum over the contact's two blocks of (1/m_b + a_b^2 / I_b)

with zeta from :func:`damping_ratio` (the spring-dashpot's standard relation to e: 0 at e = 1,
critical damping at e = 0) and ``m`` the contact mass (:func:`contact_mass`): the mass a rigid
block shows at the contact along its normal, its translation and its rotation about its
centroid (``a_b`` the normal's lever arm, ``I_b`` the polar moment), the two blocks in series;
a block whose motion is known counts as infinitely heavy. (A DDA block's strain modes would
make it lighter still, 0.14 of the mass at the corner of a 15 x 45 cm block against 0.77
rigid, but they answer a penalty spring a hundred times softer than the block as a rigid body
does.)

The dashpot acts on the step's change of the penetration, its mean rate over the step,

    t_d = (c / dt) (g_n - g_ref),   g_ref = min(g_n0, 0)

(a contact that starts the step open is damped from where it touches, never across a gap), so
it adds ``c / dt`` to the normal spring's stiffness ``E^T E``: exact for legacy DDA's gaps
linearized at the step's start and, with the exact gap, for the fully implicit method, whose
tangent takes ``c / dt`` and the geometric term of the whole normal force.

A contact is closed while the spring's and the dashpot's force ``p_n g_n + t_d`` pushes, that
is while ``g_n`` is below the gap where the two cancel
(:attr:`dda.contact.ContactElement.release`): a contact that unloads lets go at zero force,
without the pull of a dashpot resisting its opening (that pull took 3-6% of a rocking block's
energy at each impact), and the force stays continuous, which Newton's iterations need. The
friction law sees that force too: with the spring's alone, a contact let go carried a
friction strength it had no normal force for, and Newton's iterations cycled on it (26 cut
steps of 15,000 on the rocking block). The force a step records (and the guard's spring depth,
the contact energy) is the spring's. A static analysis (no velocity carried) takes no dashpot.

Let go at zero force, a free impact rebounds somewhat more than ``e`` (which is measured where
the spring is back at its length): 0.135 for a single contact at e = 0, exp(-2). Housner's
rocking block, whose striking corner carries the block on, loses what Housner says at e = 0
(``tests/validation/test_rocking_block.py``).

With ``JointMaterial(shear_dashpot=True)`` (the default) the joint's closed contacts also get
a shear dashpot of the same damping ratio, ``c_s = 2 zeta sqrt(p_s m_s)`` with ``m_s`` the
contact mass along the edge (the lever arm of the tangent), in parallel with the shear spring
and acting on the step's shear increment; the pair is a Kelvin-Voigt element in series with
the friction law's slider. A sticking contact carries

    t_s = p_s g_se0 + (p_s + c_s / dt) dg_s

(``g_se0`` its committed elastic shear displacement), the trial the law caps: a sliding
contact's friction force is the spring's and the dashpot's together, and its spring takes
that force over the pair's relaxation time ``c_s / p_s``, not at once. Without it a block at
rest on its shear springs vibrates (period ``2 pi sqrt(m_s / p_s)``, 12 ms for the rock
slope's upper block on the paper's 10 MN/m) with no loss but Newmark's gamma = 1 damping,
strong at dt 1e-3 and weak at 1e-4: the 16 s rock slope of ``examples/rock_slope.py`` with its
face-onset joint followed the rigid block within 0.69% at dt 1e-3 and 10.95% at dt 1e-4
(Newton), where each slide event ends in a shear vibration that moves the next event; with
the shear dashpot 0.70% and 0.30%. Legacy DDA at dt 1e-4: 61.7% -> 5.2%.

It enters every solver path the same way, as a stiffer shear spring for the step
(:func:`shear_dashpot_start`: ``p_s + c_s / dt``, with the committed ``g_se`` scaled so that
the spring force at the step's start is unchanged), and leaves at the step's end
(:func:`shear_dashpot_end`: the committed history and force are the spring's alone, as the
normal force a step records is). Any law whose shear force is ``p_s g_se`` (every built-in
one) takes it unchanged.
"""

from __future__ import annotations

import math

import numpy as np

from dda.kernels.dashpot import shear_dashpot_ends

__all__ = ["damping_ratio", "contact_mass", "dashpot_stiffness", "shear_dashpot_start",
           "shear_dashpot_end"]


SHEAR_END_KERNEL = True
"""Whether :func:`shear_dashpot_end` runs compiled
(:func:`dda.kernels.dashpot.shear_dashpot_ends`, the same bits); False: numpy."""


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


def shear_dashpot_start(shear_penalty, shear_dashpot, g_se):
    """The step's effective shear penalty and scaled history of the shear dashpot (module
    docstring): ``p_eff = p_s + c_s / dt`` and ``g' = g_se p_s / p_eff``, so that a
    sticking contact's trial ``p_eff (g' + dg_s) = p_s g_se + (p_s + c_s / dt) dg_s``.

    Parameters
    ----------
    shear_penalty, shear_dashpot : (m,) ``p_s`` and ``c_s / dt`` of each contact
    g_se : (m,) the committed elastic shear displacements

    Returns
    -------
    p_eff, g_scaled : (m,) arrays
    """
    p_eff = shear_penalty + shear_dashpot
    return p_eff, g_se * (shear_penalty / p_eff)


def shear_dashpot_end(contacts, shear_penalty, shear_dashpot, g_se0) -> None:
    """Undo :func:`shear_dashpot_start` on a step's solved contacts, in place.

    The spring and the dashpot act in parallel, and the two in series with the friction
    law's slider: whether the contact stuck or slid, the law's elastic increment
    ``g' - g'_0`` is the increment of the pair, so a closed contact's spring ends at

        g_se = g_se0 + (g' - g'_0),   t_s = p_s g_se,

    the pair's force ``p_s g_se0 + p_eff (g' - g'_0)`` being the law's (the friction force of
    a sliding contact, part of it the dashpot's). The law's plastic slip needs no change (it
    is the shear increment less the same elastic one), and an open contact keeps what its
    law gave it, as does one without a dashpot (``c_s = 0``: its joint has none, or its law
    keeps no ``g_se`` and so gets none; another law's zero-filled ``g_se`` there had set its
    committed shear force to zero).

    Parameters
    ----------
    contacts : :class:`dda.contact.ContactSet` of the step's solution
    shear_penalty, shear_dashpot : (m,) ``p_s`` and ``c_s / dt``
    g_se0 : (m,) the committed elastic shear displacements at the step's start
    """
    if SHEAR_END_KERNEL:
        contacts.history["g_se"], contacts.t_s = shear_dashpot_ends(
            np.asarray(contacts.state, dtype=np.int8), *(np.ascontiguousarray(
                a, dtype=np.float64) for a in (contacts.history["g_se"], contacts.t_s,
                                               shear_penalty, shear_dashpot, g_se0)))
        return
    closed = (contacts.state != 0) & (shear_dashpot > 0.0)
    scaled0 = g_se0 * (shear_penalty / (shear_penalty + shear_dashpot))
    g_se = np.where(closed, g_se0 + (contacts.history["g_se"] - scaled0),
                    contacts.history["g_se"])
    contacts.history["g_se"] = g_se
    contacts.t_s = np.where(closed, shear_penalty * g_se, contacts.t_s)
