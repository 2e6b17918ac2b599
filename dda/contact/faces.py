"""Faces: the vertex-edge contacts that together stand for one face-to-face contact.

DDA models two blocks lying face to face by vertex-edge contacts at the ends of the shared part
of the faces (METHOD.md section 3). Most friction laws judge each contact alone. A law may
instead judge a face as a whole (``FrictionLaw.uses_faces``), as a rigid-block analysis does
with its one joint; this module says which contacts form a face and how their shear forces add
up to the face's.

A contact of vertex V against edge e belongs to the face ``{e, f}`` when one of V's own two
edges, f, runs against e within ``FACE_ANGLE`` (blocks are numbered counter-clockwise, so two
faces in contact run in opposite directions). Every contact whose vertex's edges make a wider
angle with e is a corner contact and is a face of its own.

The shear forces of a face's contacts simply add up to the face's shear force, whichever block
holds the vertex: with the roles swapped, both the edge direction and the side the force acts on
turn, so ``t_s`` keeps its sign (``tests/test_faces.py`` checks it against the push on a block
that overhangs its base).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda.kernels.faces import face_index

__all__ = ["FACE_ANGLE", "Faces", "contact_faces"]

#: largest angle (degrees) between a vertex's edge and the edge it touches for a face contact
FACE_ANGLE = 5.0


@dataclass(frozen=True)
class Faces:
    """The face of each contact: contacts with the same ``index`` (an (m,) array of
    non-negative ints) form one.

    Examples
    --------
    >>> import numpy as np
    >>> faces = Faces(np.array([0, 0, 1]))
    >>> faces.total(np.array([2.0, 3.0, 5.0]))
    array([5., 5., 5.])
    """

    index: np.ndarray

    @classmethod
    def separate(cls, m: int) -> Faces:
        """``m`` contacts, each a face of its own."""
        return cls(np.arange(m))

    def subset(self, idx: np.ndarray) -> Faces:
        """The faces of the contacts ``idx`` only (the others no longer count in the sums)."""
        return Faces(self.index[idx])

    def total(self, values: np.ndarray) -> np.ndarray:
        """Sum of ``values`` over each contact's face, returned per contact."""
        if len(values) == 0:
            return np.zeros(0)
        # the indices need not be consecutive (a subset's are not): faces that are not
        # there sum to zero and are never read
        return np.bincount(self.index, weights=values)[self.index]


def contact_faces(x: np.ndarray, vertex: np.ndarray, edge: np.ndarray, nxt: np.ndarray,
                  prv: np.ndarray, angle: float = FACE_ANGLE) -> Faces:
    """Group vertex-edge contacts into faces (see the module docstring).

    Parameters
    ----------
    x : (n_vertices, 2) vertex positions
    vertex, edge : (m,) each contact's vertex and the start of the CCW edge it touches
    nxt, prv : vertex neighbours in each block's CCW order
    angle : float
        Largest angle in degrees between a face's two edges.
    """
    if len(vertex) == 0:
        return Faces(np.zeros(0, dtype=np.int64))
    return Faces(face_index(np.ascontiguousarray(x, dtype=np.float64),
                            np.asarray(vertex, dtype=np.int64), np.asarray(edge, dtype=np.int64),
                            np.asarray(nxt, dtype=np.int64), np.asarray(prv, dtype=np.int64),
                            float(np.cos(np.radians(angle)))))
