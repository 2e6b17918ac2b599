"""Block geometry as pure functions on arrays (METHOD.md section 1).

All blocks live in one structure of arrays: the vertices of every block stacked in one
``(n_vertices, 2)`` array, counter-clockwise within a block, and CSR-style ``offsets`` of length
``n_blocks + 1`` so that block ``b`` owns ``vertices[offsets[b]:offsets[b + 1]]``.

Examples
--------
>>> import numpy as np
>>> from dda.geometry import polygon_integrals
>>> square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
>>> ints = polygon_integrals(square, np.array([0, 4]))
>>> float(ints.area[0]), ints.centroid[0].tolist(), round(float(ints.sxx[0]), 12)
(4.0, [1.0, 1.0], 1.333333333333)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda.kernels.geometry import edge_sums as _edge_sums
from dda.kernels.geometry import moments_about_centroid
from dda.kernels.geometry import self_intersections as _self_intersections

__all__ = [
    "SITE_DISTANCE",
    "site_origin",
    "PolygonIntegrals",
    "polygon_integrals",
    "next_vertex_index",
    "block_of_vertex",
    "t_matrix",
    "mass_matrices",
    "stiffness_matrices",
    "vertex_displacements",
    "signed_areas",
    "self_intersections",
    "cut_blocks",
    "JointSet",
]


@dataclass(frozen=True)
class PolygonIntegrals:
    """Area, centroid and second moments of every block about its own centroid.

    ``sxx = integral (x - x0)^2 dA``, ``syy = integral (y - y0)^2 dA`` and
    ``sxy = integral (x - x0)(y - y0) dA``, each of shape ``(n_blocks,)``.
    """

    area: np.ndarray
    centroid: np.ndarray
    sxx: np.ndarray
    syy: np.ndarray
    sxy: np.ndarray


#: a scene whose centre lies farther from the origin than this many times its extent is
#: computed about its own centre (:func:`site_origin`)
SITE_DISTANCE = 100.0


def site_origin(vertices: np.ndarray) -> np.ndarray:
    """Where a model's coordinates start: (0, 0), or for a scene far from the origin (its
    bounding box's centre more than :data:`SITE_DISTANCE` times the box's larger side away)
    that centre rounded to a power of ten below the side.

    A double carries 16 digits: at a site's northing, y = 4e6 m, a coordinate is known to
    5e-10 m, a penalty of 5e9 N/m turns that into newtons of contact force, and OPEN-CLOSE's
    round-off band (1e-12 of an edge) is below it. Three blocks placed at (5e5, 4e6) failed
    under Newton-Raphson at t = 0.109 s where at (0, 0) they ran through; about their own
    centre they run as there. Scenes near the origin are left as they are, to the bit.
    """
    x = np.asarray(vertices, dtype=np.float64).reshape(-1, 2)
    if not len(x):
        return np.zeros(2)
    lo, hi = x.min(axis=0), x.max(axis=0)
    side = float(np.max(hi - lo))
    centre = 0.5 * (lo + hi)
    if not (side > 0.0 and np.isfinite(side)) or np.abs(centre).max() <= SITE_DISTANCE * side:
        return np.zeros(2)
    step = 10.0 ** np.floor(np.log10(side))
    return np.round(centre / step) * step


def block_of_vertex(offsets: np.ndarray) -> np.ndarray:
    """Block index of every vertex, from CSR offsets."""
    counts = np.diff(offsets)
    return np.repeat(np.arange(len(counts)), counts)


def next_vertex_index(offsets: np.ndarray) -> np.ndarray:
    """Index of the next vertex counter-clockwise within the same block (wraps per block)."""
    n = int(offsets[-1])
    nxt = np.arange(1, n + 1)
    nxt[offsets[1:] - 1] = offsets[:-1]
    return nxt


def signed_areas(vertices: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Signed area of every polygon (shoelace formula); positive when counter-clockwise."""
    nxt = next_vertex_index(offsets)
    ref = np.repeat(vertices[offsets[:-1]], np.diff(offsets), axis=0)
    p = vertices - ref
    q = vertices[nxt] - ref
    cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    return 0.5 * np.add.reduceat(cross, offsets[:-1])


def polygon_integrals(vertices: np.ndarray, offsets: np.ndarray,
                      nxt: np.ndarray | None = None) -> PolygonIntegrals:
    """Polygon integrals of every block by Green's theorem over its edges (METHOD.md section 1).

    With ``c_i = x_i y_{i+1} - x_{i+1} y_i`` summed over the edges of a counter-clockwise polygon:
    ``A = sum c_i / 2``, ``Sx = sum c_i (x_i + x_{i+1}) / 6``,
    ``Sxx = sum c_i (x_i^2 + x_i x_{i+1} + x_{i+1}^2) / 12`` and
    ``Sxy = sum c_i (2 x_i y_i + x_i y_{i+1} + x_{i+1} y_i + 2 x_{i+1} y_{i+1}) / 24``.
    Coordinates are taken relative to each block's first vertex to keep the sums well
    conditioned far from the origin, then the moments are moved to the centroid.
    ``nxt`` (:func:`next_vertex_index` of ``offsets``) may be passed when it is at hand.
    """
    if nxt is None:
        nxt = next_vertex_index(offsets)
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    offsets = np.asarray(offsets, dtype=np.int64)
    s = edge_sums(vertices, offsets, nxt)
    area, centroid, sxx, syy, sxy = moments_about_centroid(s, vertices[offsets[:-1]])
    return PolygonIntegrals(area=area, centroid=centroid, sxx=sxx, syy=syy, sxy=sxy)


def edge_sums(vertices: np.ndarray, offsets: np.ndarray, nxt: np.ndarray) -> np.ndarray:
    """(n_blocks, 6) each block's edge terms of :func:`polygon_integrals`, summed: ``sum c``,
    ``sum c (x1 + x2)``, ... from the block's first vertex (float64 contiguous ``vertices``,
    int64 ``offsets``)."""
    # compiled: the same arithmetic and sums in the same order as numpy's, to the bit
    return _edge_sums(vertices, offsets, np.asarray(nxt, dtype=np.int64))


def t_matrix(points: np.ndarray, centroids: np.ndarray) -> np.ndarray:
    """First-order displacement matrix T(x, y) of METHOD.md section 1 (H14-H16).

    Parameters
    ----------
    points : (n, 2) array
        Points at which T is evaluated.
    centroids : (n, 2) array
        Centroid of the block each point belongs to.

    Returns
    -------
    (n, 2, 6) array with ``u(x, y) = T(x, y) d`` for ``d = [u0, v0, r0, ex, ey, gxy]``.
    """
    dx = points[:, 0] - centroids[:, 0]
    dy = points[:, 1] - centroids[:, 1]
    n = len(dx)
    t = np.zeros((n, 2, 6))
    t[:, 0, 0] = 1.0
    t[:, 1, 1] = 1.0
    t[:, 0, 2] = -dy
    t[:, 1, 2] = dx
    t[:, 0, 3] = dx
    t[:, 1, 4] = dy
    t[:, 0, 5] = 0.5 * dy
    t[:, 1, 5] = 0.5 * dx
    return t


def mass_matrices(ints: PolygonIntegrals, density: np.ndarray) -> np.ndarray:
    """Consistent mass ``M = rho * integral(T^T T dA)`` of every block, shape (n_blocks, 6, 6).

    The first moments vanish about the centroid, so only S, Sxx, Syy and Sxy appear.
    """
    a, sxx, syy, sxy = ints.area, ints.sxx, ints.syy, ints.sxy
    m = np.zeros((len(a), 6, 6))
    m[:, 0, 0] = a
    m[:, 1, 1] = a
    m[:, 2, 2] = sxx + syy
    m[:, 3, 3] = sxx
    m[:, 4, 4] = syy
    m[:, 5, 5] = 0.25 * (sxx + syy)
    m[:, 2, 3] = m[:, 3, 2] = -sxy
    m[:, 2, 4] = m[:, 4, 2] = sxy
    m[:, 2, 5] = m[:, 5, 2] = 0.5 * (sxx - syy)
    m[:, 3, 5] = m[:, 5, 3] = 0.5 * sxy
    m[:, 4, 5] = m[:, 5, 4] = 0.5 * sxy
    return m * density[:, None, None]


def stiffness_matrices(area: np.ndarray, elasticity: np.ndarray) -> np.ndarray:
    """Elastic stiffness of every block: ``S * D`` on the strain unknowns (METHOD.md section 1).

    Parameters
    ----------
    area : (n_blocks,) array
    elasticity : (n_blocks, 3, 3) array of D matrices (stress = D strain, engineering shear).
    """
    k = np.zeros((len(area), 6, 6))
    k[:, 3:, 3:] = area[:, None, None] * elasticity
    return k


def vertex_displacements(
    vertices: np.ndarray, centroids: np.ndarray, d: np.ndarray
) -> np.ndarray:
    """Displacement of points for the block increments ``d``, with the rotation made exact.

    ``T d`` inflates a rotating block by a factor ``1 + r0^2`` per step; as in Shi's DDA the
    rotational part is replaced by the finite rotation ``(R(r0) - I)(x - x0)`` so that a rigid
    spin keeps the area exactly.

    Parameters
    ----------
    vertices : (n, 2) array of points
    centroids : (n, 2) centroid of each point's block
    d : (n, 6) increments of each point's block
    """
    dx = vertices[:, 0] - centroids[:, 0]
    dy = vertices[:, 1] - centroids[:, 1]
    r = d[:, 2]
    c = np.cos(r) - 1.0
    s = np.sin(r)
    ex, ey, g = d[:, 3], d[:, 4], d[:, 5]
    u = d[:, 0] + c * dx - s * dy + ex * dx + 0.5 * g * dy
    v = d[:, 1] + s * dx + c * dy + 0.5 * g * dx + ey * dy
    return np.stack([u, v], axis=1)


def _segments_cross(p1, p2, q1, q2, tol):
    """Whether segments p1p2 and q1q2 cross properly (arrays of shape (n, 2))."""

    def orient(a, b, c):
        return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])

    d1 = orient(q1, q2, p1)
    d2 = orient(q1, q2, p2)
    d3 = orient(p1, p2, q1)
    d4 = orient(p1, p2, q2)
    return (d1 * d2 < -tol) & (d3 * d4 < -tol)


def self_intersections(vertices: np.ndarray) -> list[tuple[int, int]]:
    """Pairs of non-adjacent edges of one polygon that cross or touch (edge i runs i -> i+1),
    sorted; a sweep over the edges' boxes (:func:`dda.kernels.geometry.self_intersections`:
    O(n log n) time and O(n) memory where comparing every pair took O(n^2) of both, 37 GiB
    for 200,000 vertices)."""
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    scale = np.ptp(v, axis=0).max() ** 2
    pairs = _self_intersections(v, 1e-24 * scale * scale, 1e-12 * np.sqrt(scale))
    return [(int(i), int(j)) for i, j in pairs]


def _self_intersections_all_pairs(vertices: np.ndarray) -> list[tuple[int, int]]:
    """:func:`self_intersections` by testing every pair (the reference of the tests)."""
    n = len(vertices)
    i, j = np.triu_indices(n, k=2)
    keep = ~((i == 0) & (j == n - 1))
    i, j = i[keep], j[keep]
    p1, p2 = vertices[i], vertices[(i + 1) % n]
    q1, q2 = vertices[j], vertices[(j + 1) % n]
    scale = np.ptp(vertices, axis=0).max() ** 2
    crossing = _segments_cross(p1, p2, q1, q2, 1e-24 * scale * scale)
    # a vertex lying on a non-adjacent edge also makes the boundary non-simple
    touching = _point_on_segment(p1, q1, q2, 1e-12 * np.sqrt(scale)) | _point_on_segment(
        q1, p1, p2, 1e-12 * np.sqrt(scale)
    )
    bad = crossing | touching
    return list(zip(i[bad].tolist(), j[bad].tolist(), strict=True))


def _point_on_segment(p, a, b, tol):
    ab = b - a
    ap = p - a
    length2 = np.einsum("ij,ij->i", ab, ab)
    t = np.einsum("ij,ij->i", ap, ab) / length2
    foot = a + np.clip(t, 0.0, 1.0)[:, None] * ab
    return np.linalg.norm(p - foot, axis=1) <= tol


# block cutting lives in its own module (it needs shapely); it is part of dda.geometry's API
from dda.cutting import JointSet, cut_blocks  # noqa: E402
