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
pressure is taken at the geometry of the step's start, each step (as the C code's loads).

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

__all__ = ["WaterTable", "water_forces", "UNIT_WEIGHT"]

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
