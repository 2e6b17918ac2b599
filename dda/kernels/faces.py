"""Compiled grouping of vertex-edge contacts into faces (:func:`dda.contact.faces.contact_faces`).

The numpy version took 74 us a step on the two contacts of the seed rock slope (a dozen array
operations and ``numpy.unique``); this kernel does the same arithmetic per contact and numbers
the faces as ``numpy.unique(key, return_inverse=True)`` would (by sorted key).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["face_index"]


@njit(cache=True)
def face_index(x, vertex, edge, nxt, prv, cos_limit):
    """(m,) each contact's face: contacts with the same number form one face.

    A contact of vertex V against the edge e (from ``edge`` to ``nxt[edge]``) belongs to the
    face {e, f} when f, the one of V's two edges most opposed to e, has
    ``cos(e, f) <= -cos_limit``; otherwise it is a corner, a face of its own. The key of a
    face is ``min(e, f) n + max(e, f)``, of a corner ``n^2 + i`` (n vertices, i the contact).
    """
    m = vertex.shape[0]
    n = x.shape[0]
    key = np.empty(m, dtype=np.int64)
    for i in range(m):
        e = edge[i]
        tx = x[nxt[e], 0] - x[e, 0]
        ty = x[nxt[e], 1] - x[e, 1]
        norm = np.sqrt(tx * tx + ty * ty)
        tx, ty = tx / norm, ty / norm
        best = np.inf
        other = -1
        for own in (vertex[i], prv[vertex[i]]):  # the vertex's outgoing, then incoming edge
            ux = x[nxt[own], 0] - x[own, 0]
            uy = x[nxt[own], 1] - x[own, 1]
            norm = np.sqrt(ux * ux + uy * uy)
            c = ux / norm * tx + uy / norm * ty
            if c < best:  # the first of two equal ones, as numpy.argmin
                best = c
                other = own
        if best <= -cos_limit:
            key[i] = min(e, other) * n + max(e, other)
        else:
            key[i] = n * n + i
    order = np.argsort(key)
    index = np.empty(m, dtype=np.int64)
    label = -1
    for j in range(m):
        i = order[j]
        if j == 0 or key[i] != key[order[j - 1]]:
            label += 1
        index[i] = label
    return index
