"""Vertex-edge contact kinematics: gaps and their first variations (METHOD.md section 3).

For vertex P1 (block j) against the reversed edge P2P3 of block k:

    l = |x3 - x2|,  tau = (x3 - x2) / l,  n = (1/l) [y2 - y3, x3 - x2]       (H18)
    g_n = (x1 - x2) . n                                                      (H17)
    g_s = (x1 - x0') . tau,  x0' = x2 + xi0 (x3 - x2)                         (H27)
    E = n^T [T_j(x1), -T_k(x0)]                                               (H20-H22)
    I = tau^T [T_j(x1), -T_k(x0')] + (g_n / l) n^T [0, T_k(x3) - T_k(x2)]     (H29-H31)

so that ``delta g_n = E [d_j; d_k]`` and ``delta g_s = I [d_j; d_k]`` to first order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda.geometry import t_matrix

__all__ = ["ContactGeometry", "contact_geometry", "first_variation_rows", "tributary_length"]


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
    p1 = x[vertex]
    p2 = x[nxt[edge]]
    p3 = x[edge]
    d = p3 - p2
    length = np.hypot(d[:, 0], d[:, 1])
    tau = d / length[:, None]
    normal = np.stack([-tau[:, 1], tau[:, 0]], axis=1)
    rel = p1 - p2
    gap = np.einsum("ij,ij->i", rel, normal)
    xi = np.einsum("ij,ij->i", rel, tau) / length
    return ContactGeometry(p1, p2, p3, length, tau, normal, gap, xi)


def first_variation_rows(
    geom: ContactGeometry, xi0: np.ndarray, cj: np.ndarray, ck: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The E and I rows (m, 12) of every contact: d g_n = E [d_j; d_k], d g_s = I [d_j; d_k].

    Parameters
    ----------
    geom : ContactGeometry
    xi0 : (m,) edge parameter of the shear reference point x0'
    cj, ck : (m, 2) centroids of the vertex's block j and of the edge's block k
    """
    tj1 = t_matrix(geom.p1, cj)
    tk0 = t_matrix(geom.point(geom.xi), ck)
    tk0r = t_matrix(geom.point(xi0), ck)
    dtk = t_matrix(geom.p3, ck) - t_matrix(geom.p2, ck)
    n, tau = geom.normal, geom.tau
    e_row = np.concatenate(
        [np.einsum("mi,mij->mj", n, tj1), -np.einsum("mi,mij->mj", n, tk0)], axis=1
    )
    geo = (geom.gap / geom.length)[:, None] * np.einsum("mi,mij->mj", n, dtk)
    i_row = np.concatenate(
        [np.einsum("mi,mij->mj", tau, tj1), geo - np.einsum("mi,mij->mj", tau, tk0r)], axis=1
    )
    return e_row, i_row


def tributary_length(
    x: np.ndarray, vertex: np.ndarray, geom: ContactGeometry, prv: np.ndarray, nxt: np.ndarray
) -> np.ndarray:
    """Contact length l_c a vertex contact stands for (turns a stress into a force per metre).

    Half the shorter of the contacted edge and the vertex's own edge that runs most nearly
    along it: two vertex contacts of a face lying on an edge then share the face's length.
    """
    arms = []
    for nb in (prv[vertex], nxt[vertex]):
        a = x[nb] - geom.p1
        la = np.hypot(a[:, 0], a[:, 1])
        cos = np.abs(np.einsum("ij,ij->i", a, geom.tau)) / la
        arms.append((la, cos))
    (la, ca), (lb, cb) = arms
    parallel = np.where(ca >= cb, la, lb)
    return 0.5 * np.minimum(geom.length, parallel)
