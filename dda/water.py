"""Water in the joints: a water table and the hydrostatic pressure it puts on block edges.

Below a water table of head :math:`h(x)` (a level, or a polyline of increasing x, taken as
constant beyond its ends) the water pressure at a point is

.. math:: p(x, y) = \\gamma_w \\max(h(x) - y,\\ 0),

and it pushes on every block edge below the table: the traction on the block is
:math:`\\mathbf t = -p\\,\\mathbf n` with :math:`\\mathbf n` the edge's outward normal. Its
work on the block's six unknowns (METHOD.md section 1, the point load's :math:`T^T F` spread
along the edge) is

.. math:: \\mathbf f = \\int_{edge} T(x, y)^T\\, \\mathbf t\\, ds .

Along an edge split at the table's nodes and where the edge crosses the table, :math:`p` is
linear and :math:`T` is linear, so the integrand is quadratic and two Gauss points a piece
integrate it exactly. Joints carry the pressure on both faces (each block's edge gets its
own), so a joint's contact force is the effective force: uplift under a sliding block and the
push in a water-filled tension crack (Hoek and Bray's U and V) come out of the geometry. The
pressure is taken at the geometry of the step's start, each step (as the C code's loads),
and its stiffness (:func:`water_stiffness`) joins the blocks' so that the step's load is the
pressure at its end to first order. Its potential is :func:`water_energy`.

>>> import numpy as np
>>> table = WaterTable.level(2.0)
>>> x = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])  # a 1 m cube, submerged
>>> f = water_forces(table, x, np.array([1, 2, 3, 0]), np.zeros(4, int), np.array([[.5, .5]]))
>>> round(float(f[0, 1]), 6)  # buoyancy: the water's weight of the block's volume, up
9810.0
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda import geometry

__all__ = ["WaterTable", "water_forces", "water_stiffness", "water_loads", "water_energy",
           "UNIT_WEIGHT"]

#: unit weight of fresh water (N/m^3)
UNIT_WEIGHT = 9810.0

_GAUSS = 0.5 * (1.0 + np.array([-1.0, 1.0]) / np.sqrt(3.0))  # on [0, 1], weights 1/2 each


@dataclass(frozen=True, eq=False)
class WaterTable:
    """A water table: its head ``y`` (m) at the increasing ``x`` (m), constant beyond its
    ends, and the water's ``unit_weight`` (N/m^3)."""

    x: np.ndarray
    y: np.ndarray
    unit_weight: float = UNIT_WEIGHT

    @classmethod
    def level(cls, y: float, unit_weight: float = UNIT_WEIGHT) -> WaterTable:
        """A horizontal table at height ``y``."""
        return cls(np.array([0.0]), np.array([float(y)]), float(unit_weight))

    @property
    def is_level(self) -> bool:
        return len(self.x) == 1

    def head(self, x: np.ndarray) -> np.ndarray:
        """The table's height above each x (m)."""
        return np.interp(x, self.x, self.y)

    def as_data(self) -> dict:
        """The table as plain data (a scene file's ``[water]``, a checkpoint's scene)."""
        table = float(self.y[0]) if self.is_level else np.column_stack([self.x, self.y]).tolist()
        return {"table": table, "unit_weight": float(self.unit_weight)}


def _splits(table: WaterTable, p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(n_edges, m) sorted edge parameters in [0, 1]: the ends, the table's nodes and the
    places the edge may cross the table (every segment's line and the two constant ends: a
    root outside its segment only adds a harmless split)."""
    dx = q[:, 0] - p[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        nodes = (table.x[None, :] - p[:, 0, None]) / dx[:, None]
        # head above the edge's points, along each segment's line: g(s) = g0 + s (g1 - g0)
        if len(table.x) > 1:
            slope = np.diff(table.y) / np.diff(table.x)
            g0 = table.y[:-1] + slope * (p[:, 0, None] - table.x[:-1]) - p[:, 1, None]
            g1 = table.y[:-1] + slope * (q[:, 0, None] - table.x[:-1]) - q[:, 1, None]
        else:
            g0 = g1 = np.zeros((len(p), 0))
        ends = np.array([table.y[0], table.y[-1]])
        e0, e1 = ends - p[:, 1, None], ends - q[:, 1, None]
        roots = np.concatenate([g0 / (g0 - g1), e0 / (e0 - e1)], axis=1)
    s = np.concatenate([np.zeros((len(p), 1)), np.ones((len(p), 1)), nodes, roots], axis=1)
    s = np.where(np.isfinite(s), np.clip(s, 0.0, 1.0), 0.0)
    return np.sort(s, axis=1)


def water_forces(table: WaterTable, x: np.ndarray, nxt: np.ndarray, vertex_block: np.ndarray,
                 centroid: np.ndarray, edges: np.ndarray | None = None) -> np.ndarray:
    """The water pressure's forces on the blocks' unknowns, (n_blocks, 6).

    Parameters
    ----------
    table : WaterTable
    x : (n_vertices, 2) vertex positions (counter-clockwise blocks)
    nxt : (n_vertices,) the next vertex of each vertex's block (an edge per vertex)
    vertex_block : (n_vertices,) the block of each vertex
    centroid : (n_blocks, 2) block centroids (T's origin)
    edges : (k,) int, optional
        The edges (by first vertex) to load; default all (a step passes the free blocks').
    """
    f = np.zeros((len(centroid), 6))
    v = np.arange(len(x)) if edges is None else edges
    p, q = x[v], x[nxt[v]]
    # edges wholly above the table's highest point carry nothing: drop them first
    wet = np.minimum(p[:, 1], q[:, 1]) < table.y.max()
    v, p, q = v[wet], p[wet], q[wet]
    if not len(v):
        return f
    s = _splits(table, p, q)                                   # (e, m)
    a, b = s[:, :-1], s[:, 1:]                                 # pieces (e, m - 1)
    sg = a[..., None] + (b - a)[..., None] * _GAUSS            # (e, m - 1, 2)
    d = q - p
    length = np.hypot(d[:, 0], d[:, 1])
    points = p[:, None, None, :] + sg[..., None] * d[:, None, None, :]
    pressure = table.unit_weight * np.maximum(
        table.head(points[..., 0]) - points[..., 1], 0.0)      # (e, m - 1, 2)
    weight = 0.5 * (b - a)[..., None] * length[:, None, None]  # ds of each Gauss point
    normal = np.column_stack([d[:, 1], -d[:, 0]]) / length[:, None]  # outward (CCW blocks)
    blk = vertex_block[v]
    n_g = sg.shape[1] * 2
    t = geometry.t_matrix(points.reshape(-1, 2), np.repeat(centroid[blk], n_g, axis=0))
    traction = -(pressure * weight).reshape(-1, 1) * np.repeat(normal, n_g, axis=0)
    np.add.at(f, np.repeat(blk, n_g), np.einsum("gij,gi->gj", t, traction))
    return f


def water_energy(table: WaterTable, x: np.ndarray, nxt: np.ndarray,
                 edges: np.ndarray | None = None) -> float:
    r"""The potential of the water pressure on the blocks whose ``edges`` are given (J/m).

    The pressure is a fixed field ``p(x, y)``, so its work on a block that moves (or
    deforms) from ``A`` to ``A'`` is ``U(A) - U(A')`` with

    .. math:: U = \int_A p\, dA = \frac{\gamma_w}{2} \oint \max(h(x) - y,\ 0)^2\, dx,

    (Reynolds' transport theorem on the traction :math:`-p\mathbf n`; the line integral by
    Green's theorem, counter-clockwise): the buoyancy's potential beside gravity's.
    Along each piece of an edge (:func:`water_forces`' splits) the integrand is quadratic,
    so two Gauss points a piece integrate it exactly.

    >>> table = WaterTable.level(2.0)
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])  # depth 1.5 at its centre
    >>> round(water_energy(table, x, np.array([1, 2, 3, 0])), 6)
    14715.0
    """
    v = np.arange(len(x)) if edges is None else edges
    p, q = x[v], x[nxt[v]]
    wet = np.minimum(p[:, 1], q[:, 1]) < table.y.max()
    p, q = p[wet], q[wet]
    if not len(p):
        return 0.0
    s = _splits(table, p, q)
    a, b = s[:, :-1], s[:, 1:]
    sg = a[..., None] + (b - a)[..., None] * _GAUSS            # (e, m - 1, 2)
    d = q - p
    points = p[:, None, None, :] + sg[..., None] * d[:, None, None, :]
    depth = np.maximum(table.head(points[..., 0]) - points[..., 1], 0.0)
    dx = 0.5 * (b - a)[..., None] * d[:, 0, None, None]        # dx of each Gauss point
    return 0.5 * table.unit_weight * float(np.sum(depth * depth * dx))


def water_stiffness(table: WaterTable, x: np.ndarray, nxt: np.ndarray,
                    vertex_block: np.ndarray, centroid: np.ndarray,
                    edges: np.ndarray | None = None) -> np.ndarray:
    r"""The water pressure's stiffness on the blocks' unknowns, (n_blocks, 6, 6).

    .. math:: K_w = -\frac{\partial \mathbf f_w}{\partial \mathbf d}
              = \frac{\partial^2 U}{\partial \mathbf d^2}

    (:func:`water_energy`'s ``U``: symmetric). An edge ``p q`` (``e = q - p``, ``n L = (e_y,
    -e_x)``) carries at its ends the forces

    .. math:: \mathbf g_a = -\gamma_w \int_0^1 D(s)\, N_a(s)\, \mathbf n L\, ds,
              \qquad D = \max(h(x) - y, 0),\quad N_p = 1 - s,\quad N_q = s,

    so that :math:`\partial \mathbf g_a / \partial \mathbf b = -\gamma_w \int N_a
    (\mathbf n L \otimes \partial D / \partial \mathbf b + D\, \partial (\mathbf n L) /
    \partial \mathbf b)\, ds` with :math:`\partial D / \partial \mathbf b = N_b (h'(x),
    -1)` below the table (0 above); each piece's integrand is quadratic, two Gauss points
    integrate it exactly. The ends move by ``T d`` (affine), so
    :math:`K_w = \sum J^T K_e J` with :math:`J = [T(p); T(q)]`. A step adds it to the
    blocks' stiffness, so that its load is ``f_w(x_n) - K_w d``: the pressure at the step's
    end to first order. Taken at the step's start alone, the pressure lagged the motion and
    fed it: a floating cube bobbing with 142 steps a period gained 16% of amplitude in 7
    periods.
    """
    return water_loads(table, x, nxt, vertex_block, centroid, edges)[1]


def water_loads(table: WaterTable, x: np.ndarray, nxt: np.ndarray, vertex_block: np.ndarray,
                centroid: np.ndarray, edges: np.ndarray | None = None):
    r"""The water pressure's forces and stiffness on the blocks' unknowns, (n_blocks, 6) and
    (n_blocks, 6, 6), on the same pieces of the edges (:func:`water_stiffness`): each edge's
    end forces :math:`\mathbf g_p, \mathbf g_q` taken to the unknowns by :math:`J^T` (``T``
    is affine, so this is :func:`water_forces`' integral of :math:`T^T \mathbf t`)."""
    nb = len(centroid)
    f, k = np.zeros((nb, 6)), np.zeros((nb, 6, 6))
    v = np.arange(len(x)) if edges is None else edges
    p, q = x[v], x[nxt[v]]
    wet = np.minimum(p[:, 1], q[:, 1]) < table.y.max()
    v, p, q = v[wet], p[wet], q[wet]
    if not len(v):
        return f, k
    s = _splits(table, p, q)
    a, b = s[:, :-1], s[:, 1:]
    sg = (a[..., None] + (b - a)[..., None] * _GAUSS).reshape(len(v), -1)   # (e, g)
    w = np.repeat(0.5 * (b - a), 2, axis=1)                                 # (e, g)
    e = q - p
    points = p[:, None, :] + sg[..., None] * e[:, None, :]
    depth = table.head(points[..., 0]) - points[..., 1]
    below = depth > 0.0
    depth = np.where(below, depth, 0.0)
    if len(table.x) > 1:  # h'(x) on the piece (0 beyond the ends)
        seg = np.clip(np.searchsorted(table.x, points[..., 0]) - 1, -1, len(table.x) - 1)
        slopes = np.concatenate([[0.0], np.diff(table.y) / np.diff(table.x), [0.0]])
        dh = slopes[seg + 1]
    else:
        dh = np.zeros_like(depth)
    shape = np.stack([1.0 - sg, sg], axis=-1)                               # (e, g, 2)
    nl = np.column_stack([e[:, 1], -e[:, 0]])                               # (e, 2)
    grad = np.stack([dh, -np.ones_like(dh)], axis=-1) * below[..., None]    # (e, g, 2)
    # d(nL)/d(end): p -> [[0, -1], [1, 0]], q -> its negative
    rot = np.array([[0.0, -1.0], [1.0, 0.0]])
    sgn = np.array([1.0, -1.0])
    gamma = table.unit_weight
    # dg[e, a, i, b, j] = d g_a,i / d b_j
    wn = w[..., None] * shape                                               # (e, g, 2)
    first = nl[:, None, :, None, None] * np.einsum("ega,egb,egj->eabj", wn, shape,
                                                   grad)[:, :, None]
    load = np.einsum("ega,eg->ea", wn, depth)                               # int N_a D
    second = load[:, :, None, None, None] * (sgn[:, None, None] * rot[None, :, :]
                                             ).transpose(1, 0, 2)[None, None]
    ke = gamma * (first + second).reshape(len(v), 4, 4)    # -dg: the edge's stiffness
    t = geometry.t_matrix(np.concatenate([p, q]), np.tile(centroid[vertex_block[v]], (2, 1)))
    jac = np.concatenate([t[: len(v)], t[len(v):]], axis=1)                 # (e, 4, 6)
    ends = -gamma * (load[:, :, None] * nl[:, None, :]).reshape(len(v), 4)  # g_p, g_q
    blk = vertex_block[v]
    np.add.at(f, blk, np.einsum("eai,ea->ei", jac, ends))
    np.add.at(k, blk, np.einsum("eai,eab,ebj->eij", jac, ke, jac))
    return f, 0.5 * (k + k.transpose(0, 2, 1))
