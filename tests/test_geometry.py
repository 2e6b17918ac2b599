"""Polygon integrals, T matrix, mass and stiffness against closed forms (METHOD.md s. 1)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dda import geometry
from dda.materials import LinearElastic

RECT = np.array([[1.0, 2.0], [4.0, 2.0], [4.0, 4.0], [1.0, 4.0]])  # 3 x 2
TRI = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 2.0]])  # right triangle b=3, h=2
# L-shape: a 3 x 1 foot plus a 1 x 2 upright on its left end
L_SHAPE = np.array([[0, 0], [3, 0], [3, 1], [1, 1], [1, 3], [0, 3]], dtype=float)


def integrals(v):
    return geometry.polygon_integrals(np.asarray(v, float), np.array([0, len(v)]))


def rect_moments(x0, y0, w, h):
    """Area, centroid and moments about the origin of a rectangle (closed form)."""
    a = w * h
    cx, cy = x0 + w / 2, y0 + h / 2
    return a, cx, cy, w**3 * h / 12 + a * cx * cx, w * h**3 / 12 + a * cy * cy, a * cx * cy


def test_rectangle_integrals():
    ints = integrals(RECT)
    assert ints.area[0] == pytest.approx(6.0, rel=1e-14)
    np.testing.assert_allclose(ints.centroid[0], [2.5, 3.0], rtol=1e-14)
    assert ints.sxx[0] == pytest.approx(3**3 * 2 / 12, rel=1e-13)
    assert ints.syy[0] == pytest.approx(3 * 2**3 / 12, rel=1e-13)
    assert abs(ints.sxy[0]) < 1e-13


def test_triangle_integrals():
    b, h = 3.0, 2.0
    ints = integrals(TRI)
    assert ints.area[0] == pytest.approx(b * h / 2, rel=1e-14)
    np.testing.assert_allclose(ints.centroid[0], [b / 3, h / 3], rtol=1e-14)
    assert ints.sxx[0] == pytest.approx(b**3 * h / 36, rel=1e-13)
    assert ints.syy[0] == pytest.approx(b * h**3 / 36, rel=1e-13)
    assert ints.sxy[0] == pytest.approx(-(b**2) * h**2 / 72, rel=1e-13)


def test_l_shape_integrals_by_composition():
    parts = [rect_moments(0, 0, 3, 1), rect_moments(0, 1, 1, 2)]
    a = sum(p[0] for p in parts)
    cx = sum(p[0] * p[1] for p in parts) / a
    cy = sum(p[0] * p[2] for p in parts) / a
    sxx = sum(p[3] for p in parts) - a * cx * cx
    syy = sum(p[4] for p in parts) - a * cy * cy
    sxy = sum(p[5] for p in parts) - a * cx * cy
    ints = integrals(L_SHAPE)
    assert ints.area[0] == pytest.approx(a, rel=1e-14)
    np.testing.assert_allclose(ints.centroid[0], [cx, cy], rtol=1e-14)
    assert ints.sxx[0] == pytest.approx(sxx, rel=1e-13)
    assert ints.syy[0] == pytest.approx(syy, rel=1e-13)
    assert ints.sxy[0] == pytest.approx(sxy, rel=1e-13)


def test_integrals_far_from_origin_keep_precision():
    shifted = RECT + 1e6
    ints = integrals(shifted)
    assert ints.sxx[0] == pytest.approx(3**3 * 2 / 12, rel=1e-9)


def _triangles(v):
    """A fan triangulation valid for the star-shaped test polygons (from a kernel point)."""
    if len(v) == 6:  # L-shape: split into 4 triangles by hand
        return [v[[0, 1, 2]], v[[0, 2, 3]], v[[0, 3, 5]], v[[3, 4, 5]]]
    return [v[[0, i, i + 1]] for i in range(1, len(v) - 1)]


def _quadrature_mass(v, rho):
    """rho * integral T^T T dA by the edge-midpoint rule (exact for quadratics) on triangles."""
    c = integrals(v).centroid[0]
    m = np.zeros((6, 6))
    for tri in _triangles(np.asarray(v, float)):
        e1, e2 = tri[1] - tri[0], tri[2] - tri[0]
        area = 0.5 * abs(e1[0] * e2[1] - e1[1] * e2[0])
        mids = 0.5 * (tri + np.roll(tri, -1, axis=0))
        t = geometry.t_matrix(mids, np.repeat(c[None], 3, axis=0))
        m += area / 3 * np.einsum("qij,qik->jk", t, t)
    return rho * m


@pytest.mark.parametrize("poly", [RECT, TRI, L_SHAPE], ids=["rectangle", "triangle", "L"])
def test_mass_matrix_matches_quadrature(poly):
    ints = integrals(poly)
    m = geometry.mass_matrices(ints, np.array([2500.0]))[0]
    np.testing.assert_allclose(m, _quadrature_mass(poly, 2500.0), rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(m, m.T)
    assert np.all(np.linalg.eigvalsh(m) > 0)


@pytest.mark.parametrize("plane", ["stress", "strain"])
@pytest.mark.parametrize("poly", [RECT, TRI, L_SHAPE], ids=["rectangle", "triangle", "L"])
def test_stiffness_is_area_times_d(poly, plane):
    e, nu = 2.0e9, 0.25
    mat = LinearElastic(young=e, poisson=nu, density=1.0, plane=plane)
    ints = integrals(poly)
    k = geometry.stiffness_matrices(ints.area, mat.elasticity()[None])[0]
    if plane == "stress":
        d = e / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    else:
        f = e / ((1 + nu) * (1 - 2 * nu))
        d = f * np.array([[1 - nu, nu, 0], [nu, 1 - nu, 0], [0, 0, (1 - 2 * nu) / 2]])
    np.testing.assert_allclose(k[3:, 3:], ints.area[0] * d, rtol=1e-14)
    assert np.all(k[:3] == 0) and np.all(k[:, :3] == 0)


def test_t_matrix_gives_rigid_motion_and_strain():
    pts = np.array([[2.0, 1.0], [0.0, 0.0]])
    c = np.array([[1.0, 1.0], [1.0, 1.0]])
    t = geometry.t_matrix(pts, c)
    # rotation r0 moves (x - x0, y - y0) = (1, 0) by (0, r0)
    np.testing.assert_allclose(t[0] @ [0, 0, 1, 0, 0, 0], [0, 1])
    # uniform strain: u = ex (x - x0), v = ey (y - y0); shear: u = g/2 (y-y0), v = g/2 (x-x0)
    np.testing.assert_allclose(t[1] @ [0, 0, 0, 0.1, 0.2, 0.0], [-0.1, -0.2])
    np.testing.assert_allclose(t[1] @ [0, 0, 0, 0, 0, 0.2], [-0.1, -0.1])


@settings(max_examples=50, deadline=None)
@given(st.floats(-3.0, 3.0), st.floats(-1, 1), st.floats(-1, 1))
def test_finite_rotation_keeps_area(r, u, v):
    d = np.array([[u, v, r, 0, 0, 0]] * 6)
    ints = integrals(L_SHAPE)
    moved = L_SHAPE + geometry.vertex_displacements(
        L_SHAPE, np.repeat(ints.centroid, 6, axis=0), d)
    assert integrals(moved).area[0] == pytest.approx(ints.area[0], rel=1e-12)


def test_self_intersection_found():
    bowtie = np.array([[0, 0], [1, 1], [1, 0], [0, 1]], float)
    assert geometry.self_intersections(bowtie)
    assert not geometry.self_intersections(L_SHAPE)


def test_signed_area_sign():
    assert geometry.signed_areas(RECT, np.array([0, 4]))[0] > 0
    assert geometry.signed_areas(RECT[::-1], np.array([0, 4]))[0] < 0


def _numpy_integrals(vertices, offsets, nxt):
    """The numpy form of :func:`dda.geometry.polygon_integrals` (before its kernels)."""
    counts, starts = np.diff(offsets), offsets[:-1]
    ref = np.repeat(vertices[starts], counts, axis=0)
    p, q = vertices - ref, vertices[nxt] - ref
    x1, y1, x2, y2 = p[:, 0], p[:, 1], q[:, 0], q[:, 1]
    c = x1 * y2 - x2 * y1
    per_edge = np.stack([c, c * (x1 + x2), c * (y1 + y2), c * (x1 * x1 + x1 * x2 + x2 * x2),
                         c * (y1 * y1 + y1 * y2 + y2 * y2),
                         c * (2 * x1 * y1 + x1 * y2 + x2 * y1 + 2 * x2 * y2)], axis=1)
    s = np.add.reduceat(per_edge, starts, axis=0)
    area = s[:, 0] / 2.0
    cx, cy = s[:, 1] / 6.0 / area, s[:, 2] / 6.0 / area
    return (area, vertices[starts] + np.stack([cx, cy], axis=1),
            s[:, 3] / 12.0 - area * cx * cx, s[:, 4] / 12.0 - area * cy * cy,
            s[:, 5] / 24.0 - area * cx * cy)


def test_compiled_polygon_integrals_have_numpys_bits():
    """The compiled terms and moments give the numpy form's results to the bit, on polygons
    of 3 to 80 vertices far from the origin (the sums are numpy's in both)."""
    from dda.geometry import next_vertex_index, polygon_integrals

    rng = np.random.default_rng(0)
    for _ in range(50):
        counts = rng.integers(3, 80, rng.integers(1, 20))
        offsets = np.concatenate([[0], np.cumsum(counts)])
        parts = []
        for n in counts:
            angle = np.sort(rng.uniform(0.0, 2.0 * np.pi, n))
            radius = rng.uniform(0.5, 2.0, n)
            centre = rng.uniform(-1e3, 1e3, 2)
            parts.append(centre + np.stack([radius * np.cos(angle), radius * np.sin(angle)], 1))
        x = np.concatenate(parts)
        nxt = next_vertex_index(offsets)
        got = polygon_integrals(x, offsets, nxt)
        want = _numpy_integrals(x, offsets, nxt)
        for a, b in zip((got.area, got.centroid, got.sxx, got.syy, got.sxy), want, strict=True):
            np.testing.assert_array_equal(a, b)
