"""Compiled (numba) kernels of the step's per-contact hot path.

- :mod:`dda.kernels.pair_stiffness`: the contacts' stiffness as sums of rank-one terms
  (:class:`PairStiffness`), so no (m, 12, 12) array is built;
- :mod:`dda.kernels.assembly`: those terms summed straight into the step's matrix and
  right-hand side (:class:`dda.solvers.linear.SystemPattern` says where);
- :mod:`dda.kernels.tangent`: the rows of the fully implicit method's consistent tangent;
- :mod:`dda.kernels.kinematics`: the contact frame, gaps and first variations, the maps of
  the blocks' unknowns to the contact points, the tributary lengths;
- :mod:`dda.kernels.friction`: the return maps of the built-in Coulomb laws (a law written in
  numpy, or a subclass of a built-in one, goes through the numpy path);
- :mod:`dda.kernels.open_close`: with the built-in laws, OPEN-CLOSE's passes (two calls
  around the linear solve), the step's pull-back, legacy DDA's step end and the fully
  implicit method's contact response and tangent, the same decisions and bits as the numpy
  iteration (``dda.contact.element.KERNEL_LAWS`` switches them off);
- :mod:`dda.kernels.faces`: contacts grouped into faces;
- :mod:`dda.kernels.geometry`: polygon integrals, the turn and bisector of every vertex;
- :mod:`dda.kernels.forces`: the recorder's force sums per block pair;
- :mod:`dda.kernels.blocks`: a step's start (the blocks' integrals, matrices, Newmark
  effective system, predicted vertex speed) and end (vertex moves, their checks, the Newmark
  update), for blocks without damping, loads or constraint springs
  (``dda.step.BLOCK_KERNELS`` switches them off);
- :mod:`dda.kernels.dashpot`: each contact's impact dashpot, and its terms in legacy DDA's
  springs;
- :mod:`dda.kernels.joints`: each contact's joint row and the deepest committed spring;
- :mod:`dda.kernels.bolts`: a step's bolt terms and the bolts' moved ends (:mod:`dda.bolts`);
- :func:`dda.kernels.assembly.newton_residuals`: a Newton iterate's out-of-balance vectors;
- :mod:`dda.kernels.dense_passes` and :mod:`dda.kernels.dense_newton`: on a system solved
  dense, every OPEN-CLOSE pass (with legacy DDA's pull-back and step end) and every Newton
  iteration in one call each, built from the kernels above (their numbers agree with the
  composed path's to round-off, not to the bit: numba's LAPACK is not numpy's);
- :mod:`dda.kernels.element`: a step's contact element, every law-independent array and
  both dashpots, in one call;
- :mod:`dda.kernels.small_step`: a small scene's common step (the same contacts as the last
  step) from its detection to its guard in one call: the kernels above in the composed
  step's order, to the bit.

Two passes live beside the numpy code they replace, in :mod:`dda.contact`: the narrow phase
after the broad phase (``detection._narrow_phase_kernel``) and the penetration guard
(``penetration._guard_kernel``); ``NARROW_KERNEL`` and ``GUARD_KERNEL`` switch them off.

The kinematics, friction, OPEN-CLOSE, faces, geometry, forces, blocks, dashpot, joints,
residual, narrow-phase and guard kernels give the numbers of the numpy code they replaced, to
the bit (the tests compare them): on the few contacts of a small scene numpy's per-call
overhead, not the arithmetic, was the cost.

The kernels compile on their first call (``cache=True``: once per machine, then loaded from
``__pycache__``). numba checks a cached kernel against its own file only, not against the
files of the helpers it calls; ``import dda`` therefore drops every cached kernel of the
package once any file with a compiled function is newer than the cache
(:mod:`dda.kernels.cache`).

Each kernel compiles one version, whichever solver calls it: a kernel calls another with typed
values (``np.bool_(True)``, ``np.int64(0)``), not literals, which numba would type as
``Literal[bool]`` or ``Literal[int]`` and compile the callee again for; with a copy of a module's
constant array (read-only inside a kernel, writable from Python); and with the array layout
the other callers use. ``tests/test_kernel_cache.py`` checks it (a second version of a kernel
compiles everything it calls again: a fresh install's first run was 18% longer).
"""

from dda.kernels.pair_stiffness import PairStiffness

__all__ = ["PairStiffness"]
