"""The step's contact stiffness as sums of rank-one terms.

Every contact's 12 x 12 stiffness on ``[d_j; d_k]`` is a few outer products of 12-rows:

    K_c = sum_t w_ct r_c,u(t) r_c,v(t)^T

with the rows ``r_c`` and weights ``w_c`` of the contact and the pairs ``(u(t), v(t))`` shared
by every contact. Legacy DDA's springs are two terms, ``p_n E^T E + p_s I^T I``, and the
consistent tangent of the fully implicit method four (:mod:`dda.contact.tangent`). The
assembly (:mod:`dda.kernels.assembly`) evaluates the entries where they are summed, so the
(m, 12, 12) array is only built when asked for (:meth:`PairStiffness.dense`).
"""

from __future__ import annotations

import numpy as np

# defined with the OPEN-CLOSE kernels that call it (numba renews a cached kernel when its own
# file changes, not a helper's in another file)
from dda.kernels.open_close import legacy_springs

__all__ = ["PairStiffness", "legacy_springs"]


class PairStiffness:
    """Per-contact 12 x 12 matrices ``K_c = sum_t w_ct r_c,u(t) r_c,v(t)^T``.

    It stands for the (m, 12, 12) array wherever one is taken (``np.asarray`` builds it).

    Parameters
    ----------
    rows : (m, p, 12) the rows of each contact
    terms : (T, 2) int, the rows ``(u, v)`` of each term
    weights : (m, T) the weight of each term for each contact
    """

    def __init__(self, rows, terms, weights):
        self.rows = np.ascontiguousarray(rows, dtype=np.float64)
        self.terms = np.ascontiguousarray(terms, dtype=np.int64).reshape(-1, 2)
        self.weights = np.ascontiguousarray(weights, dtype=np.float64)
        m, p, width = self.rows.shape
        if width != 12 or self.weights.shape != (m, len(self.terms)):
            raise ValueError(f"PairStiffness: rows {self.rows.shape}, terms "
                             f"{self.terms.shape} and weights {self.weights.shape} do not fit")
        if len(self.terms) and not (0 <= self.terms.min() and self.terms.max() < p):
            raise ValueError(f"PairStiffness: terms name rows outside 0..{p - 1}")

    @classmethod
    def checked_by_caller(cls, rows, terms, weights) -> PairStiffness:
        """The same, from arrays the caller guarantees fit (C-contiguous float64 rows and
        weights, int64 terms within the rows): no copies, no checks (the step's own
        springs, built every OPEN-CLOSE pass)."""
        k = cls.__new__(cls)
        k.rows, k.terms, k.weights = rows, terms, weights
        return k

    def __len__(self):
        return len(self.rows)

    @property
    def shape(self) -> tuple[int, int, int]:
        return (len(self.rows), 12, 12)

    def dense(self) -> np.ndarray:
        """The (m, 12, 12) matrices (the compiled assembly sums the same values)."""
        k = np.zeros(self.shape)
        for t, (u, v) in enumerate(self.terms):
            k += self.weights[:, t, None, None] * (
                self.rows[:, u, :, None] * self.rows[:, v, None, :])
        return k

    def __array__(self, dtype=None, copy=None):
        if copy is False:
            raise ValueError("PairStiffness: the (m, 12, 12) array is built on request")
        k = self.dense()
        return k if dtype is None else k.astype(dtype)
