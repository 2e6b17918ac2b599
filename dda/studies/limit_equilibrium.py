r"""Limit equilibrium references for the factor of safety (:mod:`dda.studies.factor_of_safety`).

- :func:`incline_factor`: a block on an inclined plane, ``F = (c A + W cos(theta) tan(phi))
  / (W sin(theta))``.
- :func:`goodman_bray` and :func:`toppling_factor`: Goodman and Bray's (1976) analysis of
  toppling columns on a stepped base (Hoek and Bray, *Rock Slope Engineering*, 3rd ed.,
  chapter 10; Wyllie and Mah, *Rock Slope Engineering*, 4th ed., section 9.4), and
  :func:`columns_scene`, the same columns as a DDA scene.

**Goodman and Bray's columns.** Axes ``u`` along the base plane (dip ``psi``, pointing up the
slope) and ``v`` normal to it. Block ``i`` (1 at the toe, ``n`` at the top) is a rectangle of
width ``dx_i`` and height ``y_i`` whose base lies at ``v = z_i`` (a stepped base: each block
on its own step). Its weight is ``W_i = gamma dx_i y_i`` (per unit thickness). The block
above pushes it with a normal force ``P_i`` on its upslope face and a shear force ``Q_i = P_i
tan(phi_s)`` (the side joints, angle ``phi_s``), the block below holds it with ``P_{i-1}``,
``Q_{i-1}``; its base carries ``R_i`` and ``S_i`` (angle ``phi_b``). The forces between two
blocks act at the top of the lower of their two tops (where a toppling block leans on its
neighbour), so with ``t_i = z_i + y_i``::

    M_i = min(t_i, t_{i+1}) - z_i         (where P_i acts on block i)
    L_i = min(t_{i-1}, t_i) - z_i         (where P_{i-1} acts on block i; L_1 = y_1 by default)

Going down from ``P_n = 0``, the force the block below must give for block ``i`` not to
topple about its toe, and not to slide on its base, is

.. math::

    P_{i-1,t} = \frac{P_i (M_i - dx_i \tan\phi_s)
                + \tfrac{W_i}{2} (y_i \sin\psi - dx_i \cos\psi)}{L_i}

    P_{i-1,s} = P_i - \frac{W_i (\tan\phi_b \cos\psi - \sin\psi)}
                           {1 - \tan\phi_b \tan\phi_s}

and ``P_{i-1}`` is the larger (the block topples when ``P_{i-1,t}`` is the larger, slides
otherwise), or zero when both are negative (the block stands alone). ``P_0 > 0`` is the force
needed at the toe: the slope fails. The factor of safety divides both ``tan(phi_b)`` and
``tan(phi_s)`` by ``F`` (strength reduction) and solves ``P_0(F) = 0``
(:func:`toppling_factor`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["incline_factor", "GoodmanBray", "goodman_bray", "toppling_factor", "columns_scene"]


def incline_factor(phi: float, theta: float, cohesion: float = 0.0, weight: float = 1.0,
                   area: float = 0.0) -> float:
    """Factor of safety of a block on a plane of dip ``theta`` (degrees), friction ``phi``.

    ``F = (cohesion area + weight cos(theta) tan(phi)) / (weight sin(theta))``; without
    cohesion ``tan(phi) / tan(theta)``.

    >>> round(incline_factor(30.0, 25.0), 4)
    1.2381
    """
    th = math.radians(theta)
    return ((cohesion * area + weight * math.cos(th) * math.tan(math.radians(phi)))
            / (weight * math.sin(th)))


@dataclass(frozen=True)
class GoodmanBray:
    """The outcome of :func:`goodman_bray`.

    Attributes
    ----------
    force : (n + 1,) array
        ``P_0 ... P_n``: ``P_i`` is the normal force between blocks ``i`` and ``i + 1``;
        ``P_0`` the force needed at the toe (positive: the slope fails), ``P_n = 0``.
    modes : tuple of str
        Per block, from the toe: "topple", "slide" or "stable".
    """

    force: np.ndarray
    modes: tuple

    @property
    def toe_force(self) -> float:
        """``P_0`` (N per m; positive: the columns need a support to stand)."""
        return float(self.force[0])


def _geometry(widths, heights, bases):
    dx, y, z = (np.asarray(a, dtype=float) for a in (widths, heights, bases))
    if not (dx.shape == y.shape == z.shape and dx.ndim == 1 and len(dx) >= 1):
        raise ValueError("goodman_bray: widths, heights and bases must be lists of one length")
    if np.any(dx <= 0) or np.any(y <= 0):
        raise ValueError("goodman_bray: widths and heights must be positive")
    return dx, y, z


def goodman_bray(widths, heights, bases, psi: float, phi_base: float, phi_side: float,
                 unit_weight: float = 1.0, support_height: float | None = None,
                 tan_base: float | None = None, tan_side: float | None = None) -> GoodmanBray:
    """Goodman and Bray's forces of a row of columns on a stepped base (module docstring).

    Parameters
    ----------
    widths, heights, bases : sequences of n floats
        ``dx_i``, ``y_i`` and ``z_i`` (m) of the blocks from the toe up, in the frame of the
        base plane.
    psi : float
        Dip of the base plane (degrees).
    phi_base, phi_side : float
        Friction angles (degrees) of the blocks' bases and of the joints between them.
    unit_weight : float
        ``gamma`` (N/m^3).
    support_height : float, optional
        Where ``P_0`` acts on the toe block above its base (default ``y_1``).
    tan_base, tan_side : float, optional
        The friction coefficients themselves (instead of the angles; for the reduced ones).

    Returns
    -------
    GoodmanBray

    Examples
    --------
    A slender column (0.5 x 3 m) leaning on a square one (1 m) on a 25 degree base with a
    0.1 m step: the column topples onto the square's corner, 0.9 m above its own base, with
    ``P_1 = (W_2 / 2)(3 sin 25 - 0.5 cos 25) / 0.9``; the square stands:

    >>> gb = goodman_bray([1.0, 0.5], [1.0, 3.0], [0.0, 0.1], psi=25.0, phi_base=50.0,
    ...                   phi_side=40.0, unit_weight=25e3)
    >>> gb.modes, [round(float(p)) for p in gb.force]
    (('stable', 'topple'), [0, 16973, 0])
    """
    dx, y, z = _geometry(widths, heights, bases)
    n = len(dx)
    p = math.radians(psi)
    tb = math.tan(math.radians(phi_base)) if tan_base is None else float(tan_base)
    ts = math.tan(math.radians(phi_side)) if tan_side is None else float(tan_side)
    if tb * ts >= 1.0:
        raise ValueError("goodman_bray: tan(phi_base) tan(phi_side) must be below 1 (the "
                         "sliding equation's denominator)")
    top = z + y
    w = unit_weight * dx * y
    force = np.zeros(n + 1)
    modes = [""] * n
    for i in range(n - 1, -1, -1):
        above = force[i + 1]
        m = (min(top[i], top[i + 1]) - z[i]) if i < n - 1 else y[i]
        if i > 0:
            arm = min(top[i - 1], top[i]) - z[i]
        else:
            arm = y[0] if support_height is None else float(support_height)
        if arm <= 0.0 or m <= 0.0:
            raise ValueError(f"goodman_bray: blocks {i} and {i + 1} (from the toe, 0-based) "
                             "do not share a face")
        topple = (above * (m - dx[i] * ts)
                  + 0.5 * w[i] * (y[i] * math.sin(p) - dx[i] * math.cos(p))) / arm
        slide = above - w[i] * (tb * math.cos(p) - math.sin(p)) / (1.0 - tb * ts)
        if max(topple, slide) <= 0.0:
            modes[i], force[i] = "stable", 0.0
        elif topple >= slide:
            modes[i], force[i] = "topple", topple
        else:
            modes[i], force[i] = "slide", slide
    return GoodmanBray(force=force, modes=tuple(modes))


def toppling_factor(widths, heights, bases, psi: float, phi_base: float, phi_side: float,
                    unit_weight: float = 1.0, support_height: float | None = None,
                    rtol: float = 1e-10) -> float:
    """The factor of safety of Goodman and Bray's columns by strength reduction.

    The ``F`` at which ``P_0 = 0`` with ``tan(phi_b) / F`` and ``tan(phi_s) / F``
    (:func:`goodman_bray`), by bisection in ``log F`` between ``sqrt(tan(phi_b)
    tan(phi_s))`` (below it the sliding equation has no meaning) and 1000. ``inf`` when the
    columns stand at 1000, ``nan`` when they fail at the lower end.

    Examples
    --------
    The two columns of :func:`goodman_bray`: the square topples too once ``tan(phi_s) / F``
    falls below ``(M_1 - R_1 / P_1) / dx_1 = 1 - 6046 / 16973 = 0.6438`` (``R_1 = (W_1 / 2)
    (cos 25 - sin 25)``, its weight's moment about its toe), so ``F = tan 40 / 0.6438``:

    >>> round(toppling_factor([1.0, 0.5], [1.0, 3.0], [0.0, 0.1], psi=25.0, phi_base=50.0,
    ...                       phi_side=40.0), 4)
    1.3034
    """
    tb, ts = math.tan(math.radians(phi_base)), math.tan(math.radians(phi_side))

    def fails(f):
        return goodman_bray(widths, heights, bases, psi, phi_base, phi_side, unit_weight,
                            support_height, tan_base=tb / f, tan_side=ts / f).toe_force > 0.0

    lo, hi = math.sqrt(tb * ts) * (1.0 + 1e-9), 1e3
    if fails(lo):
        return math.nan
    if not fails(hi):
        return math.inf
    while hi / lo - 1.0 > rtol:
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if fails(mid) else (mid, hi)
    return math.sqrt(lo * hi)


def columns_scene(widths, heights, bases, psi: float, phi_base: float, phi_side: float,
                  penalty: float = 1e10, density: float = 2500.0, young: float = 10e9,
                  toe: float = 0.5, depth: float = 0.5, gravity: float = 9.81):
    """Goodman and Bray's columns (:func:`goodman_bray`'s geometry) as a DDA scene.

    The base plane dips at ``psi`` to the left (``u`` points up it, to the right); a fixed
    block ``"base"`` carries a tread under each column (at ``v = z_i``) and a riser between
    them, reaches ``toe`` beyond the toe column and is ``depth`` thick below the lowest
    tread. The columns are ``"column1"`` (at the toe) to ``"column<n>"``; the joints between
    columns are Coulomb with ``phi_side`` (the scene's default joint), those between the
    base and each column with ``phi_base``; both penalties ``penalty``. The unit weight is
    ``density gravity``.

    Returns
    -------
    Scene
    """
    import dda
    from dda.contact import CoulombSingle, JointMaterial
    from dda.materials import LinearElastic

    dx, y, z = _geometry(widths, heights, bases)
    p = math.radians(psi)
    along = np.array([math.cos(p), math.sin(p)])
    normal = np.array([-math.sin(p), math.cos(p)])

    def world(points):
        return [tuple(u * along + v * normal) for u, v in points]

    u = np.concatenate([[0.0], np.cumsum(dx)])
    n = len(dx)
    ring = [(-toe, z[0] - depth), (u[-1] + toe, z[0] - depth), (u[-1] + toe, z[-1])]
    for i in range(n - 1, -1, -1):  # each tread from its upslope end, then down the riser
        ring += [(u[i + 1], z[i]), (u[i], z[i])]
    ring.append((-toe, z[0]))
    outline = [ring[0]]
    for q in ring[1:]:  # no repeated corner where two treads meet without a riser
        if math.hypot(q[0] - outline[-1][0], q[1] - outline[-1][1]) > 1e-12:
            outline.append(q)
    rock = LinearElastic(young=young, poisson=0.25, density=density)
    scene = dda.Scene(gravity=gravity)
    base = scene.add_block(world(outline), rock, fixed=True, name="base")
    scene.set_joint(JointMaterial(penalty, penalty, CoulombSingle(phi=phi_side)))
    for i in range(n):
        column = scene.add_block(
            world([(u[i], z[i]), (u[i + 1], z[i]), (u[i + 1], z[i] + y[i]), (u[i], z[i] + y[i])]),
            rock, name=f"column{i + 1}")
        scene.set_joint(JointMaterial(penalty, penalty, CoulombSingle(phi=phi_base)),
                        between=(base, column))
    return scene
