"""numpy's order of summation, compiled: sums whose bits are ``numpy.add.reduceat``'s.

numpy adds a run of float64 values by pairwise summation: fewer than 8 values one after the
other from zero, up to 128 in eight running sums combined as ``((r0 + r1) + (r2 + r3)) + ((r4 +
r5) + (r6 + r7))`` with the remainder added after, and above that the two halves (the first a
multiple of 8) summed apart. ``numpy.add.reduceat`` starts each run from its first value and
adds the pairwise sum of the others. A kernel that sums in this order gives numpy's bits, so a
compiled path and a numpy one agree to the bit (``tests/test_block_kernels.py`` checks it on
blocks of 3 to 300 vertices).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["pairwise_sum", "run_sum"]


@njit(cache=True)
def pairwise_sum(values, order, start, n):
    """numpy's pairwise summation of ``values[order[start:start + n]]`` (module docstring)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += values[order[start + i]]
        return res
    if n <= 128:
        r = np.empty(8)
        for j in range(8):
            r[j] = values[order[start + j]]
        i = 8
        while i < n - n % 8:
            for j in range(8):
                r[j] += values[order[start + i + j]]
            i += 8
        res = (r[0] + r[1]) + (r[2] + r[3]) + ((r[4] + r[5]) + (r[6] + r[7]))
        while i < n:
            res += values[order[start + i]]
            i += 1
        return res
    half = n // 2
    half -= half % 8
    return (pairwise_sum(values, order, start, half)
            + pairwise_sum(values, order, start + half, n - half))


@njit(cache=True)
def run_sum(values, order, start, end):
    """``numpy.add.reduceat``'s sum of ``values[order[start:end]]`` (``end > start``): the
    first value plus the pairwise sum of the others."""
    if end - start == 1:
        return values[order[start]]
    return values[order[start]] + pairwise_sum(values, order, start + 1, end - start - 1)
