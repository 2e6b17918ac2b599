"""Products with a symmetric matrix stored as its upper triangle (compiled).

PARDISO reads a symmetric matrix as the upper triangle of its rows (CSR), and the step's
symmetric system is assembled in that layout (:meth:`dda.solvers.linear.SystemPattern.
upper_matrix`). The refinement of a single-precision solution needs ``K x`` in double
precision on every refinement; with scipy that is three passes over the data
(``U x + U^T x - diag(U) x``), here one.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["upper_symmetric_matvec"]


@njit(cache=True)
def upper_symmetric_matvec(indptr, indices, data, x):
    """``y = K x`` for the symmetric ``K`` whose upper triangle (diagonal included) is the CSR
    matrix ``(data, indices, indptr)``:

        y_i = sum_(j >= i) U_ij x_j + sum_(j < i) U_ji x_j

    Each stored entry is read once: ``U_ij`` adds ``U_ij x_j`` to ``y_i`` and, off the
    diagonal, ``U_ij x_i`` to ``y_j``. The indices of each row must be sorted (its diagonal
    entry, if stored, first) and no entry below the diagonal stored. On the 60 x 60 stack's
    matrix (581,112 stored entries) 0.81 ms against scipy's 1.09.
    """
    n = indptr.shape[0] - 1
    y = np.zeros(n)
    for i in range(n):
        xi = x[i]
        start, acc = indptr[i], 0.0
        if start < indptr[i + 1] and indices[start] == i:  # the diagonal (sorted: first)
            acc = data[start] * xi
            start += 1
        for p in range(start, indptr[i + 1]):
            j = indices[p]
            acc += data[p] * x[j]
            y[j] += data[p] * xi
        y[i] += acc
    return y
