"""Compiled return maps of the built-in Coulomb laws (:class:`dda.contact.CoulombSingle`,
:class:`dda.contact.StaticDynamicTransition`).

The numpy return map of :class:`dda.contact.CoulombLike` costs two to three dozen array
operations a call, which on the few contacts of a small scene is most of its time (11 us for
two contacts of ``CoulombSingle``, 21 us with the face onset, several calls a step). These
kernels do the same arithmetic contact by contact in the same order (the numpy path stays the
reference, and any law that overrides a part of it takes that path), so the results have the
same bits.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["coulomb_return_map", "transition_return_map"]


@njit(cache=True)
def coulomb_return_map(g_se, slip, delta_g_s, t_n, shear_penalty, length, mu, cohesion):
    """Coulomb's return map: ``S = c l_c + max(-t_n, 0) tan(phi)``, a trial above it
    returned to it. Returns ``(t_s, slipping, strength, g_se, slip)`` of the trial."""
    m = delta_g_s.shape[0]
    t_s = np.empty(m)
    slipping = np.empty(m, dtype=np.bool_)
    strength = np.empty(m)
    g_out = np.empty(m)
    slip_out = np.empty(m)
    for i in range(m):
        t_trial = shear_penalty[i] * (g_se[i] + delta_g_s[i])
        s = cohesion * length[i] + max(-t_n[i], 0.0) * mu
        strength[i] = s
        slipping[i] = abs(t_trial) > s
        t = s * np.sign(t_trial) if slipping[i] else t_trial
        t_s[i] = t
        g_out[i] = t / shear_penalty[i]
        slip_out[i] = slip[i] + abs(t_trial - t) / shear_penalty[i]
    return t_s, slipping, strength, g_out, slip_out


@njit(cache=True)
def transition_return_map(g_se, slip, sliding, delta_g_s, t_n, shear_penalty, mu_static,
                          mu_dynamic, face):
    """The static-to-dynamic transition's return map. A contact sliding at the step's start
    (``sliding > 0.5``) is checked against ``|t_n| tan(phi_d)``, one sticking against
    ``|t_n| tan(phi_s)``; a trial that slips is returned to ``|t_n| tan(phi_d)``. With a face
    index (``face``, length m; empty: each contact on its own) a sticking contact slips when
    its face does: ``|sum t_c| > sum S`` over the face, the sliding contacts' force ``t_c``
    capped at their dynamic strength. Returns ``(t_s, slipping, strength, g_se, slip)``."""
    m = delta_g_s.shape[0]
    t_trial = np.empty(m)
    strength = np.empty(m)
    dynamic = np.empty(m)
    for i in range(m):
        t_trial[i] = shear_penalty[i] * (g_se[i] + delta_g_s[i])
        pressure = max(-t_n[i], 0.0)
        dynamic[i] = pressure * mu_dynamic
        strength[i] = dynamic[i] if sliding[i] > 0.5 else pressure * mu_static
    slipping = np.empty(m, dtype=np.bool_)
    if face.shape[0] == 0:
        for i in range(m):
            slipping[i] = abs(t_trial[i]) > strength[i]
    else:
        n_faces = 0
        for i in range(m):
            n_faces = max(n_faces, face[i] + 1)
        carried = np.zeros(n_faces)
        held = np.zeros(n_faces)
        for i in range(m):
            c = t_trial[i]
            if sliding[i] > 0.5:
                c = min(max(c, -dynamic[i]), dynamic[i])
            carried[face[i]] += c
            held[face[i]] += strength[i]
        for i in range(m):
            if sliding[i] > 0.5:
                slipping[i] = abs(t_trial[i]) > dynamic[i]
            else:
                slipping[i] = abs(carried[face[i]]) > held[face[i]]
    t_s = np.empty(m)
    g_out = np.empty(m)
    slip_out = np.empty(m)
    for i in range(m):
        t = dynamic[i] * np.sign(t_trial[i]) if slipping[i] else t_trial[i]
        t_s[i] = t
        g_out[i] = t / shear_penalty[i]
        slip_out[i] = slip[i] + abs(t_trial[i] - t) / shear_penalty[i]
    return t_s, slipping, strength, g_out, slip_out
