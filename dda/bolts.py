"""Rock bolts: axial springs between material points of two blocks (issue 23, item 1).

A bolt ``i`` joins the material point ``x_a`` of block ``a`` to the material point ``x_b`` of
block ``b`` (either block may be one whose motion is known: fixed, shaken or moved). Its
axial force, tension positive, is

    N = P + k (L - L0),     L = |x_b - x_a|,

with ``k`` its stiffness, ``P`` its pretension (applied at the start: ``N = P`` at t = 0) and
``L0`` its length at the start. It is the force of the energy

    W(d) = 1/2 k (L(d) - L0)^2 + P L(d).

Within a step the two points move by ``T_a d_a`` and ``T_b d_b`` (``T`` the DDA displacement
matrix at the point, METHOD.md section 1), so with ``u = R d``, ``R = [-T_a, T_b]`` (2 x 12)
on ``d = [d_a; d_b]``, the unit direction ``n = (x_b - x_a) / L`` and its normal
``t = (-n_y, n_x)`` at the step's start,

    dL/dd = R^T n = r,         d2L/dd2 = R^T (I - n n^T) R / L = s s^T / L,   s = R^T t,

and a step takes the bolt's energy to second order about the step's start (the exact
derivatives there; ``tests/test_bolts.py`` checks them against finite differences of W):

    K_bolt = k r r^T + (N0 / L) s s^T,       f_bolt = -N0 r,

``N0`` the force at the step's start. Legacy DDA and Newton-Raphson both solve with these
terms (the term is linear in ``d``: Newton's residual is ``K_bolt d - f_bolt``), and every
step starts again from the bolts' exact geometry: the points are tracked as material points
(:func:`dda.geometry.vertex_displacements`, as the vertices are) and ``N0`` is recomputed from
them, so nothing is lost to the linearization over many steps. ``f_bolt`` pulls ``a`` towards
``b`` under tension: ``f_a = N0 T_a^T n``, ``f_b = -N0 T_b^T n``.

A bolt between two free blocks couples them: its block pair joins the contacts' in the
step's system (:attr:`dda.solvers.StepProblem.pair_blocks`), its 12 x 12 matrix and 12-vector
the contacts' (:meth:`BoltTerm.joined`). A bolt anchored in a block whose motion is known
(fixed, shaken, moved) acts on its free block alone: its 6 x 6 part goes into that block's
matrix and its forces, less the known end's increment times the coupling, into the block's
forces (:meth:`BoltTable.system`), so the step keeps its layout and a small scene the
compiled step of :mod:`dda.kernels.small_step` and the dense solvers' one-call kernels.

Breaking: a bolt breaks when its force at the end of a step, from the moved points, exceeds
its strength in tension (``N > strength``; compression is carried without limit). The step
is then solved again from its start without the most overloaded bolt (``N / strength``
largest), and again while any bolt is overloaded: one bolt at a time, so that a bolt that
would be unloaded by another's failure (two bolts in series) does not break with it. No
committed state holds a bolt above its strength; a broken bolt stays broken and carries
nothing. The broken flags are part of the step's trial state (:class:`dda.step.StepState`),
so a refused step undoes a break as it undoes everything else.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda import geometry
from dda.kernels.bolts import bolt_rows, fold_anchored, moved_bolt_points
from dda.kernels.pair_stiffness import PairStiffness

__all__ = ["BoltTable", "BoltTerm", "bolt_energy", "bolt_label", "moved_points",
           "outside_distance", "released_peak", "shortest_period"]

# the two rank-one terms of a bolt on its rows [r, s]
_BOLT_TERMS = np.array([[0, 0], [1, 1]], dtype=np.int64)


@dataclass(frozen=True)
class BoltTable:
    """A scene's bolts as arrays (:attr:`dda.model.Model.bolts`).

    Attributes
    ----------
    blocks : (n, 2) int, blocks ``a`` and ``b`` of each bolt
    points : (n, 2, 2) its two material points at the start (``[:, 0]`` on a, ``[:, 1]`` on b)
    stiffness, pretension : (n,) ``k`` (N/m per m) and ``P`` (N per m)
    strength : (n,) tensile strength (N per m), inf for a bolt that does not break
    length : (n,) ``L0``, the length at the start (m)
    labels : how messages name each bolt
    """

    blocks: np.ndarray
    points: np.ndarray
    stiffness: np.ndarray
    pretension: np.ndarray
    strength: np.ndarray
    length: np.ndarray
    labels: tuple

    @classmethod
    def from_scene(cls, scene, free, origin=(0.0, 0.0)) -> BoltTable | None:
        """The scene's bolts, or None without any; ``free`` (n_blocks,) are the blocks with
        unknowns. ValueError for a bolt between two blocks whose motion is known."""
        bolts = scene.bolts
        if not bolts:
            return None
        blocks = np.array([(b.block_a, b.block_b) for b in bolts], dtype=np.int64)
        handles = scene.blocks
        labels = tuple(bolt_label(i, handles[b.block_a], handles[b.block_b])
                       for i, b in enumerate(bolts))
        known = ~np.asarray(free)[blocks].any(axis=1)
        if known.any():
            i = int(np.flatnonzero(known)[0])
            raise ValueError(f"{labels[i]}: both its blocks have a known motion (fixed, shaken "
                             "or moved); a bolt needs a block that can move")
        points = np.array([(b.point_a, b.point_b) for b in bolts], dtype=float)
        points = points - np.asarray(origin, dtype=float)  # the model's frame
        delta = points[:, 1] - points[:, 0]
        return cls(blocks, points, np.array([b.stiffness for b in bolts], dtype=float),
                   np.array([b.pretension for b in bolts], dtype=float),
                   np.array([np.inf if b.strength is None else b.strength for b in bolts],
                            dtype=float),
                   np.hypot(delta[:, 0], delta[:, 1]), labels)

    def __len__(self):
        return len(self.blocks)

    def forces(self, points: np.ndarray, broken: np.ndarray) -> np.ndarray:
        """(n,) axial force ``N = P + k (L - L0)`` of each bolt at ``points`` (n, 2, 2),
        tension positive; 0 where ``broken``."""
        n = self.pretension + self.stiffness * (_lengths(points) - self.length)
        return np.where(broken, 0.0, n)

    def to_break(self, force: np.ndarray, broken: np.ndarray) -> int:
        """The bolt that breaks under ``force``: the most overloaded (largest
        ``N / strength`` above 1) of those not ``broken``, or -1 when none is."""
        over = (force > self.strength) & ~broken  # (an unbreakable bolt's strength: inf)
        if not over.any():
            return -1
        idx = np.flatnonzero(over)
        return int(idx[np.argmax(force[idx] / self.strength[idx])])

    def term(self, points: np.ndarray, broken: np.ndarray,
             centroid: np.ndarray) -> BoltTerm | None:
        """The step's :class:`BoltTerm` of the bolts not ``broken`` at ``points`` (the step's
        start), on blocks whose centroids are ``centroid`` (n_blocks, 2); None when every
        bolt is broken."""
        if broken.any():
            idx = np.flatnonzero(~broken)
            if not len(idx):
                return None
            blocks, pts, k = self.blocks[idx], points[idx], self.stiffness[idx]
            force = self.pretension[idx] + k * (_lengths(pts) - self.length[idx])
        else:  # (the common case: every bolt, no copies)
            idx, blocks, pts, k = self._all, self.blocks, points, self.stiffness
            force = self.pretension + k * (_lengths(pts) - self.length)
        a, b = blocks[:, 0], blocks[:, 1]
        rows, weights, f = bolt_rows(np.ascontiguousarray(pts, dtype=np.float64), a, b,
                                     np.ascontiguousarray(centroid, dtype=np.float64),
                                     k, force)
        return BoltTerm(a, b, rows, weights, f, idx)

    def system(self, points, broken, centroid, free, block_k, block_f, d_known):
        """The step's bolts as the solvers take them: ``(block_k, block_f, coupled)``.

        A bolt with one end on a block whose motion is known (an anchor) acts on one block's
        unknowns only: its term is folded into that block's matrix and forces (new arrays;
        the known end's increment ``d_known`` moved to the right-hand side),

            K_ff += K_bolt,ff,     f_f += f_bolt,f - K_bolt,fk d_known,k,

        so the step's system keeps its blocks' layout (and a small scene its compiled
        step). The bolts between two free blocks couple them: ``coupled`` is their
        :class:`BoltTerm` (None when there is none) for :attr:`dda.solvers.StepProblem.
        bolts`. ``block_k`` and ``block_f`` are returned as given when no bolt is anchored.
        """
        term = self.term(points, broken, centroid)
        if term is None:
            return block_k, block_f, None
        free = np.asarray(free, dtype=np.bool_)
        if free[term.bj].all() and free[term.bk].all():
            return block_k, block_f, term
        k, f, coupled = fold_anchored(term.rows, term.weights, term.force, term.bj, term.bk,
                                      free, np.ascontiguousarray(block_k, dtype=np.float64),
                                      np.ascontiguousarray(block_f, dtype=np.float64),
                                      np.ascontiguousarray(d_known, dtype=np.float64))
        return k, f, term.subset(coupled)

    @property
    def _all(self) -> np.ndarray:
        return np.arange(len(self.blocks))

    def moved(self, points: np.ndarray, centroid: np.ndarray, d: np.ndarray) -> np.ndarray:
        """The bolts' ends ``points`` (n, 2, 2) moved by the blocks' increments ``d`` from a
        step's start whose centroids are ``centroid`` (:func:`moved_points`, compiled)."""
        return moved_bolt_points(np.ascontiguousarray(points, dtype=np.float64), self.blocks,
                                 np.ascontiguousarray(centroid, dtype=np.float64),
                                 np.ascontiguousarray(d, dtype=np.float64))


@dataclass(frozen=True)
class BoltTerm:
    """One step's bolts, linearized at the step's start (module docstring).

    Attributes
    ----------
    bj, bk : (m,) blocks ``a`` and ``b`` of each bolt in the term
    rows : (m, 2, 12) the rows ``r = R^T n`` and ``s = R^T t`` on ``[d_a; d_b]``
    weights : (m, 2) ``k`` and ``N0 / L``
    force : (m, 12) ``f_bolt = -N0 r``
    index : (m,) the bolts' indices in the scene
    """

    bj: np.ndarray
    bk: np.ndarray
    rows: np.ndarray
    weights: np.ndarray
    force: np.ndarray
    index: np.ndarray

    @classmethod
    def build(cls, a, b, points, centroid, k, n0, index=None) -> BoltTerm:
        """The term of bolts from block ``a`` at ``points[:, 0]`` to ``b`` at
        ``points[:, 1]`` (the step's start), stiffness ``k`` and force ``n0`` there.

        Examples
        --------
        >>> import numpy as np
        >>> pts = np.array([[[0.0, 0.0], [2.0, 0.0]]])      # a bolt along x, 2 m long
        >>> term = BoltTerm.build(np.array([0]), np.array([1]), pts,
        ...                       np.array([[0.0, 0.0], [2.0, 0.0]]), np.array([10.0]),
        ...                       np.array([4.0]))
        >>> term.force[0, [0, 6]].tolist()     # tension 4 pulls a to +x and b to -x
        [4.0, -4.0]
        >>> k = term.stiffness()[0]
        >>> float(k[0, 0]), float(k[1, 1])      # k along the bolt, N0 / L across it
        (10.0, 2.0)
        """
        pa, pb = points[:, 0], points[:, 1]
        ta = geometry.t_matrix(pa, centroid[a])
        tb = geometry.t_matrix(pb, centroid[b])
        delta = pb - pa
        length = np.hypot(delta[:, 0], delta[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            n = np.where(length[:, None] > 0.0, delta / length[:, None], 0.0)
            across = np.where(length > 0.0, n0 / length, 0.0)
        t = np.stack([-n[:, 1], n[:, 0]], axis=1)
        rows = np.empty((len(a), 2, 12))
        for j, e in enumerate((n, t)):
            rows[:, j, :6] = -np.einsum("mij,mi->mj", ta, e)
            rows[:, j, 6:] = np.einsum("mij,mi->mj", tb, e)
        weights = np.stack([np.asarray(k, dtype=float), across], axis=1)
        index = np.arange(len(a)) if index is None else index
        return cls(np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64), rows,
                   weights, -n0[:, None] * rows[:, 0], index)

    def __len__(self):
        return len(self.bj)

    def subset(self, keep: np.ndarray) -> BoltTerm | None:
        """The term of the bolts where ``keep`` (None when none is kept)."""
        if not keep.any():
            return None
        if keep.all():
            return self
        return BoltTerm(self.bj[keep], self.bk[keep], self.rows[keep], self.weights[keep],
                        self.force[keep], self.index[keep])

    def stiffness(self) -> np.ndarray:
        """(m, 12, 12) ``K_bolt = k r r^T + (N0 / L) s s^T``."""
        r, s = self.rows[:, 0], self.rows[:, 1]
        return (self.weights[:, 0, None, None] * r[:, :, None] * r[:, None, :]
                + self.weights[:, 1, None, None] * s[:, :, None] * s[:, None, :])

    def residual(self, d: np.ndarray) -> np.ndarray:
        """(m, 12) the bolts' out-of-balance ``K_bolt [d_a; d_b] - f_bolt`` at the increments
        ``d`` (n_blocks, 6)."""
        pair = np.concatenate([d[self.bj], d[self.bk]], axis=1)
        proj = np.einsum("mpj,mj->mp", self.rows, pair) * self.weights
        return np.einsum("mp,mpj->mj", proj, self.rows) - self.force

    def joined(self, pair_k, pair_f):
        """The contacts' stiffness ``pair_k`` and forces ``pair_f`` (m_c, 12) with the bolts'
        after them (the order of :attr:`dda.solvers.StepProblem.pair_blocks`).

        A :class:`dda.kernels.PairStiffness` stays one (the compiled assembly): the bolts'
        two rows take two of its diagonal terms ``(u, u)``, and where it has fewer than two
        (Newton's tangent has one) the rows and terms it lacks are added, zero for the
        contacts. An array (m_c, 12, 12) gets the bolts' matrices appended.
        """
        f = np.concatenate([np.asarray(pair_f, dtype=float).reshape(-1, 12), self.force])
        if not isinstance(pair_k, PairStiffness):
            k = np.asarray(pair_k, dtype=float).reshape(-1, 12, 12)
            return np.concatenate([k, self.stiffness()]), f
        rows, terms, weights = pair_k.rows, pair_k.terms, pair_k.weights
        m, p = len(rows), rows.shape[1]
        diagonal = {}
        for t, (u, v) in enumerate(terms.tolist()):
            if u == v and u not in diagonal:
                diagonal[u] = t
        slots = list(diagonal.items())[:2]
        extra = 2 - len(slots)
        if extra:
            rows = np.concatenate([rows, np.zeros((m, extra, 12))], axis=1)
            new_terms = np.array([[p + j, p + j] for j in range(extra)], dtype=np.int64)
            slots += [(p + j, len(terms) + j) for j in range(extra)]
            terms = np.concatenate([terms, new_terms])
            weights = np.concatenate([weights, np.zeros((m, extra))], axis=1)
        nb = len(self)
        bolt_rows = np.zeros((nb, rows.shape[1], 12))
        bolt_weights = np.zeros((nb, len(terms)))
        for j, (row, term) in enumerate(slots):
            bolt_rows[:, row] = self.rows[:, j]
            bolt_weights[:, term] = self.weights[:, j]
        return PairStiffness(np.concatenate([rows, bolt_rows]), terms,
                             np.concatenate([weights, bolt_weights])), f


def moved_points(points: np.ndarray, blocks: np.ndarray, centroid: np.ndarray,
                 d: np.ndarray) -> np.ndarray:
    """The bolts' material points (n, 2, 2) moved by the blocks' increments ``d``
    (n_blocks, 6) from a step's start (centroids ``centroid``), as the vertices move
    (:func:`dda.geometry.vertex_displacements`)."""
    flat = points.reshape(-1, 2)
    owner = blocks.reshape(-1)
    move = geometry.vertex_displacements(flat, centroid[owner], d[owner])
    return (flat + move).reshape(points.shape)


def bolt_energy(table: BoltTable | None, points: np.ndarray, broken: np.ndarray) -> float:
    """Elastic energy ``N^2 / (2 k)`` of the bolts not broken (J per m): ``W`` of the module
    docstring up to a constant, zero for a slack bolt (``N = 0``); a break releases it."""
    if table is None:
        return 0.0
    n = table.forces(points, broken)
    return float(0.5 * np.sum(n * n / table.stiffness))


def outside_distance(vertices: np.ndarray, point: np.ndarray) -> float:
    """How far ``point`` lies outside the polygon ``vertices`` (m): 0 inside or on its
    boundary, else its distance to the nearest edge."""
    a = vertices
    b = np.roll(vertices, -1, axis=0)
    ab = b - a
    lengths2 = np.einsum("ij,ij->i", ab, ab)
    s = np.clip(np.einsum("ij,ij->i", point - a, ab) / lengths2, 0.0, 1.0)
    foot = a + s[:, None] * ab
    distance = float(np.min(np.hypot(*(point - foot).T)))
    # crossing number: a ray from the point in +x
    y0, y1 = a[:, 1], b[:, 1]
    straddle = (y0 > point[1]) != (y1 > point[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[:, 0] + (point[1] - y0) * ab[:, 0] / ab[:, 1]
    inside = np.count_nonzero(straddle & (x_cross > point[0])) % 2 == 1
    return 0.0 if inside else distance


def released_peak(steps: float) -> float:
    r"""The peak force of a spring-held mass let go from rest, as a share of the undamped
    ``2 W``, under DDA's Newmark step (beta 1/2, gamma 1) at ``steps`` steps a period.

    The one-mass system ``m u'' + k u = W`` from ``u = u' = 0``, stepped as the blocks are
    (:mod:`dda.solvers.newmark`): ``(2 m / dt^2 + k) d = W - k u_n + 2 m v_n / dt``,
    ``v_(n+1) = 2 d / dt - v_n``, over the first one and a half periods. gamma = 1 damps
    the vibration by about ``exp(-pi omega dt / 4)`` a half period, so the share is about
    ``1 - pi^2 / (4 N)`` for many steps ``N`` (used from 10^4 on).

    Examples
    --------
    >>> [round(released_peak(n), 3) for n in (20, 82, 250)]
    [0.892, 0.971, 0.99]
    """
    n = float(steps)
    if not n > 0.0:
        raise ValueError(f"released_peak: steps must be positive, got {steps}")
    if n > 1e4:  # the recursion's answer there, to 1e-7
        return 1.0 - np.pi**2 / (4.0 * n)
    dt = 2.0 * np.pi / n  # in units m = k = W = 1 (omega 1, the static deflection 1)
    u = v = peak = 0.0
    for _ in range(int(np.ceil(1.5 * n)) + 1):
        d = (1.0 - u + 2.0 * v / dt) / (2.0 / dt**2 + 1.0)
        u += d
        v = 2.0 * d / dt - v
        peak = max(peak, u)
    return peak / 2.0


def shortest_period(model) -> tuple[float, str]:
    r"""The shortest period of the bolts' axial vibration at the start (s), and whose it is.

    A bolt of stiffness ``k`` pulls the block at its point ``p`` along its axis ``n``. The
    point's rigid motion along ``n`` is ``g^T [u0, v0, r0]`` with ``g = [n_x, n_y,
    (p - c) x n]`` (``c`` the block's centroid), so against the block's rigid mass ``M =
    diag(m, m, I)`` (``I = rho (S_xx + S_yy)``, the polar moment about the centroid) the
    bolt is a spring on the inverse mass

    .. math::

        g^T M^{-1} g = 1 / m + ((p - c) \times n)^2 / I.

    One bolt vibrates at ``omega^2 = k sum_(free ends) g^T M^{-1} g``; the bolts on one free
    block together at the largest eigenvalue of ``M^{-1} sum k (1 + w_o / w) g g^T``, ``w``
    and ``w_o`` the bolt's inverse masses ``g^T M^{-1} g`` at this end and the other (0 for
    a block whose motion is known): exact for bolts anchored in known blocks, for one bolt
    or parallel bolts between two free blocks, and above the highest mode of a chain (4 k /
    m for three equal blocks, whose highest is 3 k / m: a shorter period, more steps). The
    period is ``2 pi / omega`` for the largest ``omega`` of either kind. The blocks' strain
    unknowns are left out: their own elastic modes are the rock's, far stiffer than a bolt.
    A bolt of zero length has no axis and is taken along the direction that gives it the
    largest inverse mass.

    Parameters
    ----------
    model : dda.model.Model

    Returns
    -------
    period : float
        ``inf`` without bolts.
    what : str
        The bolt, or the block whose bolts, vibrate fastest ("" without bolts).
    """
    table = model.bolts
    if table is None or len(table) == 0:
        return float("inf"), ""
    ints = geometry.polygon_integrals(model.x_initial, model.offsets, model.topo.nxt)
    mass = model.density * ints.area
    polar = model.density * (ints.sxx + ints.syy)
    points = table.points
    delta = points[:, 1] - points[:, 0]
    length = np.hypot(delta[:, 0], delta[:, 1])
    axis = length > 0.0
    n = np.where(axis[:, None], delta / np.where(axis, length, 1.0)[:, None], [1.0, 0.0])
    ends = np.zeros((len(table), 2))  # each end's inverse mass along the bolt
    rows = []
    for end in (0, 1):  # the bolts' two ends, each over all bolts at once
        blk = table.blocks[:, end]
        arm = points[:, end] - ints.centroid[blk]
        cross = np.where(axis, arm[:, 0] * n[:, 1] - arm[:, 1] * n[:, 0],
                         np.hypot(arm[:, 0], arm[:, 1]))
        rows.append(np.column_stack([n, cross]))
        ends[:, end] = np.where(model.free[blk], 1.0 / mass[blk] + cross**2 / polar[blk], 0.0)
    per_bolt = table.stiffness * ends.sum(axis=1)
    spring = np.zeros((model.n_blocks, 3, 3))
    for end in (0, 1):
        own, other = ends[:, end], ends[:, 1 - end]
        scale = np.where(own > 0.0, 1.0 + other / np.where(own > 0.0, own, 1.0), 0.0)
        g = rows[end]
        np.add.at(spring, table.blocks[:, end],
                  (table.stiffness * scale)[:, None, None] * g[:, :, None] * g[:, None, :])
    fastest = int(np.argmax(per_bolt))
    omega2, what = float(per_bolt[fastest]), table.labels[fastest]
    held = np.flatnonzero(model.free & (np.abs(spring).sum(axis=(1, 2)) > 0.0))
    if len(held):
        root = 1.0 / np.sqrt(np.column_stack([mass, mass, polar])[held])  # M^(-1/2)
        lam = np.linalg.eigvalsh(spring[held] * root[:, :, None] * root[:, None, :])[:, -1]
        if float(lam.max()) > omega2 * (1.0 + 1e-9):  # one bolt alone: its own name
            b = int(held[np.argmax(lam)])
            omega2, what = float(lam.max()), f"the bolts on {model.block_label(b)}"
    if omega2 <= 0.0:
        return float("inf"), ""
    return 2.0 * np.pi / np.sqrt(omega2), what


def bolt_label(i: int, block_a, block_b) -> str:
    """How messages name bolt ``i`` from ``block_a`` to ``block_b`` (their handles)."""
    return f"bolt {int(i)} ({block_a} to {block_b})"


def _lengths(points: np.ndarray) -> np.ndarray:
    delta = points[:, 1] - points[:, 0]
    return np.hypot(delta[:, 0], delta[:, 1])
