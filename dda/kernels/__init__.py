"""Compiled (numba) kernels of the step's per-contact hot path.

- :mod:`dda.kernels.pair_stiffness`: the contacts' stiffness as sums of rank-one terms
  (:class:`PairStiffness`), so no (m, 12, 12) array is built;
- :mod:`dda.kernels.assembly`: those terms summed straight into the step's matrix and
  right-hand side (:class:`dda.solvers.linear.SystemPattern` says where);
- :mod:`dda.kernels.tangent`: the rows of the fully implicit method's consistent tangent.

The kernels compile on their first call (``cache=True``: once per machine, then loaded from
``__pycache__``).
"""

from dda.kernels.pair_stiffness import PairStiffness

__all__ = ["PairStiffness"]
