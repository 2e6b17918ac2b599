"""Index work of the step's sparse pattern (compiled): where each block entry lies.

A block pattern stored by major index (a block column of the CSC structure, or a block row
of the upper triangle) lists the minor indices of each major one in ascending order,
``minor[ptr[j]:ptr[j + 1]]``. A step's contacts ask where each of their block entries
lies; a major index holds a few entries (a block touches its neighbours), so a binary search
within it replaces sorting and searching all the keys at once (``numpy.unique`` and
``numpy.searchsorted`` over every entry: 10 of the 60 x 60 stack's 15 ms of index work a
step).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["entry_positions"]


@njit(cache=True)
def entry_positions(ptr, minor, major_of, minor_of):
    """(e,) int64: for each entry ``e`` the position ``p`` in ``ptr[major_of[e]]`` ..
    ``ptr[major_of[e] + 1]`` with ``minor[p] == minor_of[e]``, or -1 where the pattern does
    not hold it.

    Parameters
    ----------
    ptr : (n_major + 1,) int, where each major index's entries start
    minor : (nnz,) int, their minor indices, ascending within each major index
    major_of, minor_of : (e,) int, the entries looked for
    """
    out = np.empty(major_of.shape[0], dtype=np.int64)
    for e in range(major_of.shape[0]):
        j = major_of[e]
        target = minor_of[e]
        lo, hi = ptr[j], ptr[j + 1]
        while lo < hi:  # the first position whose minor index is not below target
            mid = (lo + hi) // 2
            if minor[mid] < target:
                lo = mid + 1
            else:
                hi = mid
        out[e] = lo if lo < ptr[j + 1] and minor[lo] == target else -1
    return out
