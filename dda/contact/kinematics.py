"""Vertex-edge contact kinematics: gaps and their first variations (METHOD.md section 3).

For vertex P1 (block j) against the reversed edge P2P3 of block k:

    l = |x3 - x2|,  tau = (x3 - x2) / l,  n = (1/l) [y2 - y3, x3 - x2]       (H18)
    g_n = (x1 - x2) . n                                                      (H17)
    g_s = (x1 - x0') . tau,  x0' = x2 + xi0 (x3 - x2)                         (H27)
    E = n^T [T_j(x1), -T_k(x0)]                                               (H20-H22)
    I = tau^T [T_j(x1), -T_k(x0')] + (g_n / l) n^T [0, T_k(x3) - T_k(x2)]     (H29-H31)

so that ``delta g_n = E [d_j; d_k]`` and ``delta g_s = I [d_j; d_k]`` to first order; the
second variations are in :func:`trial_kinematics`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda.kernels.kinematics import first_variations, frames, tributary_lengths
from dda.kernels.kinematics import pair_maps as _pair_maps

__all__ = [
    "ContactGeometry",
    "TrialKinematics",
    "contact_frame",
    "contact_geometry",
    "pair_maps",
    "trial_kinematics",
    "tributary_length",
]


@dataclass
class ContactGeometry:
    """Positions, edge frame, normal gap and foot parameter of every contact."""

    p1: np.ndarray
    p2: np.ndarray
    p3: np.ndarray
    length: np.ndarray
    tau: np.ndarray
    normal: np.ndarray
    gap: np.ndarray
    xi: np.ndarray

    def shear_gap(self, xi0: np.ndarray) -> np.ndarray:
        """g_s = (x1 - x0') . tau with the reference point at edge parameter xi0."""
        return (self.xi - xi0) * self.length

    def point(self, xi: np.ndarray) -> np.ndarray:
        """The point of edge P2P3 at parameter xi."""
        return self.p2 + xi[:, None] * (self.p3 - self.p2)


def contact_geometry(x: np.ndarray, vertex: np.ndarray, edge: np.ndarray, nxt: np.ndarray):
    """Contact frame of vertex ``vertex`` against the reversed CCW edge ``edge -> nxt[edge]``."""
    return contact_frame(x[vertex], x[nxt[edge]], x[edge])


def contact_frame(p1: np.ndarray, p2: np.ndarray, p3: np.ndarray) -> ContactGeometry:
    """Contact frame of points P1 (vertex) and P2 -> P3 (edge), each (m, 2) (compiled:
    :func:`dda.kernels.kinematics.frames`)."""
    length, tau, normal, gap, xi = frames(
        *(np.ascontiguousarray(a, dtype=np.float64) for a in (p1, p2, p3)))
    return ContactGeometry(p1, p2, p3, length, tau, normal, gap, xi)


@dataclass
class TrialKinematics:
    """Gaps, their first variations (rows) and second variations (12 x 12) at a trial state.

    The trial configuration is ``x = X + T(X) d``: T is taken at the step's start positions X,
    so the variations are exact derivatives of g_n(d) and g_s(d) (METHOD.md section 3).
    """

    gap: np.ndarray
    shear: np.ndarray
    xi: np.ndarray
    length: np.ndarray
    normal: np.ndarray
    tau: np.ndarray
    e_row: np.ndarray
    i_row: np.ndarray
    gn_hessian: np.ndarray | None
    gs_hessian: np.ndarray | None


def pair_maps(x_ref, vertex, edge, nxt, cj, ck):
    """Rows mapping [d_j; d_k] (12) to the motion of P1, P2 and P3: three (m, 2, 12) arrays.

    Each is :func:`dda.geometry.t_matrix` of its point, in the columns of its block (all
    three built at once, compiled: :func:`dda.kernels.kinematics.pair_maps`; they are the
    three C-contiguous parts of one (3, m, 2, 12) array).
    """
    a = _pair_maps(np.ascontiguousarray(x_ref, dtype=np.float64), _ints(vertex), _ints(edge),
                   _ints(nxt), np.ascontiguousarray(cj, dtype=np.float64),
                   np.ascontiguousarray(ck, dtype=np.float64))
    return a[0], a[1], a[2]


def trial_kinematics(p1, p2, p3, xi0, maps, second=True) -> TrialKinematics:
    """Contact kinematics of the configuration ``x`` (METHOD.md section 3, H17-H35).

    With ``a = x1 - x2``, ``b = x3 - x2``, ``l = |b|``, the rows below act on [d_j; d_k]:

        E  = n . (da - xi db)        G  = tau . (da - xi db)
        E' = n . (da - xi0 db)       G' = tau . (da - xi0 db)
        H  = n . db                  J  = tau . db
        delta g_n = E,               delta g_s = I = G' + (g_n / l) H
        Delta delta g_n = -(1/l) [G^T H + H^T G + (g_n/l) H^T H]
        Delta delta g_s =  (1/l) [E'^T H + H^T E' - (g_n/l)(H^T J + J^T H) - (g_s/l) H^T H]

    derived from g_n = (b x a) / l and g_s = a . b / l - xi0 l (the scanned paper prints the
    sign of the H^T H term of Delta delta g_n the other way; tests/test_kinematics.py checks
    every one of these against finite differences).

    Parameters
    ----------
    p1, p2, p3 : (m, 2) trial positions of the vertex and of the (reversed) edge's ends
    xi0 : (m,) shear reference parameter
    maps : the three (m, 2, 12) arrays of :func:`pair_maps` (start-of-step positions)
    second : also compute the second variations
    """
    if not second:
        return _first_only(p1, p2, p3, xi0, maps)
    geom = contact_frame(p1, p2, p3)
    a1, a2, a3 = maps
    n, tau, length, gap, xi = geom.normal, geom.tau, geom.length, geom.gap, geom.xi
    shear = geom.shear_gap(xi0)
    da = a1 - a2
    db = a3 - a2
    rel = da - xi[:, None, None] * db
    rel0 = da - xi0[:, None, None] * db
    e_row = np.einsum("mi,mij->mj", n, rel)
    h_row = np.einsum("mi,mij->mj", n, db)
    g0_row = np.einsum("mi,mij->mj", tau, rel0)
    i_row = g0_row + (gap / length)[:, None] * h_row
    gn_h = gs_h = None
    if second:
        g_row = np.einsum("mi,mij->mj", tau, rel)
        e0_row = np.einsum("mi,mij->mj", n, rel0)
        j_row = np.einsum("mi,mij->mj", tau, db)

        def sym(u, v):  # u v^T + v u^T (v u^T is the transpose of u v^T, to the bit)
            uv = u[:, :, None] * v[:, None, :]
            return uv + uv.transpose(0, 2, 1)

        hh = h_row[:, :, None] * h_row[:, None, :]
        inv_l = (1.0 / length)[:, None, None]
        gn_h = -inv_l * (sym(g_row, h_row) + (gap / length)[:, None, None] * hh)
        gs_h = inv_l * (sym(e0_row, h_row) - (gap / length)[:, None, None] * sym(h_row, j_row)
                        - (shear / length)[:, None, None] * hh)
    return TrialKinematics(gap, shear, xi, length, n, tau, e_row, i_row, gn_h, gs_h)


def _first_only(p1, p2, p3, xi0, maps) -> TrialKinematics:
    """:func:`trial_kinematics` without the second variations, compiled
    (:func:`dda.kernels.kinematics.first_variations`, the same bits)."""
    f64 = np.float64
    length, tau, normal, gap, xi, shear, e_row, i_row = first_variations(
        *(np.ascontiguousarray(a, dtype=f64) for a in (p1, p2, p3, xi0, *maps)))
    return TrialKinematics(gap, shear, xi, length, normal, tau, e_row, i_row, None, None)


def tributary_length(
    x: np.ndarray, vertex: np.ndarray, geom: ContactGeometry, prv: np.ndarray, nxt: np.ndarray
) -> np.ndarray:
    """Contact length l_c a vertex contact stands for (turns a stress into a force per metre).

    Half the shorter of the contacted edge and the vertex's own edge that runs most nearly
    along it: two vertex contacts of a face lying on an edge then share the face's length
    (compiled: :func:`dda.kernels.kinematics.tributary_lengths`).
    """
    return tributary_lengths(np.ascontiguousarray(x, dtype=np.float64), _ints(vertex),
                             _ints(prv), _ints(nxt),
                             *(np.ascontiguousarray(a, dtype=np.float64)
                               for a in (geom.p1, geom.tau, geom.length)))


def _ints(a):
    return np.asarray(a, dtype=np.int64)
