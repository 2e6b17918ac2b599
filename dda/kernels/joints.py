"""Compiled joint lookups of a step's contacts (:meth:`dda.model.Model.joint_index`).

The joint of a contact is the row of its block pair's key in the joint table, found by a
binary search of the sorted keys (numpy's ``searchsorted``, clipped, as
:meth:`dda.model.JointTable.index` does), or the default joint. Two lookups a step (the
contact element's and the deepest committed spring's) cost 4 us each in numpy on a few
contacts, against under 1 here; the rows are the same integers.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["deepest_spring", "joint_rows"]


@njit(cache=True, inline="always")
def _row(a, b, n_blocks, pair_keys, pair_joint, default):
    """The joint table row of blocks a and b (``default`` where the pair has none)."""
    n = pair_keys.shape[0]
    if n == 0:
        return default
    key = min(a, b) * n_blocks + max(a, b)
    lo, hi = 0, n  # numpy.searchsorted(pair_keys, key) (side "left")
    while lo < hi:
        mid = (lo + hi) // 2
        if pair_keys[mid] < key:
            lo = mid + 1
        else:
            hi = mid
    pos = min(lo, n - 1)
    return pair_joint[pos] if pair_keys[pos] == key else default


@njit(cache=True)
def joint_rows(bj, bk, n_blocks, pair_keys, pair_joint, default):
    """(m,) the joint table row of each contact's block pair (-1: no joint, no default)."""
    m = bj.shape[0]
    out = np.empty(m, dtype=np.int64)
    for c in range(m):
        out[c] = _row(bj[c], bk[c], n_blocks, pair_keys, pair_joint, default)
    return out


@njit(cache=True)
def deepest_spring(state, t_n, bj, bk, n_blocks, pair_keys, pair_joint, default,
                   normal_penalty):
    """The deepest spring penetration ``-t_n / p_n`` of the closed contacts (state not 0),
    0 when none is deeper: ``numpy.maximum.reduce`` from 0 of :meth:`dda.model.Model.
    spring_depths`' depths (a row of -1 taken from the table's end, as numpy indexes)."""
    deepest = 0.0
    rows = normal_penalty.shape[0]
    for c in range(state.shape[0]):
        if state[c] == 0:
            continue
        r = _row(bj[c], bk[c], n_blocks, pair_keys, pair_joint, default)
        depth = -t_n[c] / normal_penalty[r + rows if r < 0 else r]
        deepest = deepest if deepest > depth else depth
    return deepest
