"""Compiled return maps of the built-in Coulomb laws (:class:`dda.contact.CoulombSingle`,
:class:`dda.contact.StaticDynamicTransition`).

The numpy return map of :class:`dda.contact.CoulombLike` costs two to three dozen array
operations a call, which on the few contacts of a small scene is most of its time (11 us for
two contacts of ``CoulombSingle``, 21 us with the face onset, several calls a step). These
functions give the laws' parameters to :func:`dda.kernels.open_close.law_return_map`, the
one implementation of the built-in laws' arithmetic, which the compiled OPEN-CLOSE passes use
too; it does the numpy return map's arithmetic contact by contact in the same order (the numpy
path stays the reference, and any law that overrides a part of it takes that path), so the
results have the same bits. (Plain functions: numba renews a cached kernel when its own file
changes, not when a kernel it calls in another file does.)
"""

from __future__ import annotations

import numpy as np

from dda.kernels.open_close import COULOMB, TRANSITION, TRANSITION_FACE, law_return_map

__all__ = ["coulomb_return_map", "transition_return_map"]


def coulomb_return_map(g_se, slip, delta_g_s, t_n, shear_penalty, length, mu, cohesion):
    """Coulomb's return map: ``S = c l_c + max(-t_n, 0) tan(phi)``, a trial above it
    returned to it. Returns ``(t_s, slipping, strength, g_se, slip)`` of the trial."""
    m = len(delta_g_s)
    return law_return_map(np.full(m, COULOMB, dtype=np.int64), np.full(m, float(mu)),
                          np.full(m, float(mu)), np.full(m, float(cohesion)),
                          np.full(m, -1, dtype=np.int64), g_se, slip, np.zeros(m), delta_g_s,
                          t_n, shear_penalty, length)


def transition_return_map(g_se, slip, sliding, delta_g_s, t_n, shear_penalty, mu_static,
                          mu_dynamic, face):
    """The static-to-dynamic transition's return map. A contact sliding at the step's start
    (``sliding > 0.5``) is checked against ``|t_n| tan(phi_d)``, one sticking against
    ``|t_n| tan(phi_s)``; a trial that slips is returned to ``|t_n| tan(phi_d)``. With a face
    index (``face``, length m; empty: each contact on its own) a sticking contact slips when
    its face does: ``|sum t_c| > sum S`` over the face, the sliding contacts' force ``t_c``
    capped at their dynamic strength. Returns ``(t_s, slipping, strength, g_se, slip)``."""
    m = len(delta_g_s)
    by_face = len(face) > 0
    kind = np.full(m, TRANSITION_FACE if by_face else TRANSITION, dtype=np.int64)
    faces = np.asarray(face, dtype=np.int64) if by_face else np.full(m, -1, dtype=np.int64)
    return law_return_map(kind, np.full(m, float(mu_static)), np.full(m, float(mu_dynamic)),
                          np.zeros(m), faces, g_se, slip, sliding, delta_g_s, t_n,
                          shear_penalty, np.ones(m))
