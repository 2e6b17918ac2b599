"""Finite-difference checks of g_n, g_s and their first variations E and I (METHOD.md s. 3)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from dda import geometry
from dda.contact.kinematics import contact_geometry, first_variation_rows


def _moved(x, blocks, centroids, d):
    """Vertices after the linear displacement T d of their blocks (no rotation correction)."""
    t = geometry.t_matrix(x, centroids[blocks])
    return x + np.einsum("vij,vj->vi", t, d[blocks])


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_gap_variations_match_finite_differences(seed):
    rng = np.random.default_rng(seed)
    # vertex of block 0 near edge of block 1; vertices: 0 = P1, 1..2 = its neighbours,
    # block 1: 3 = P3 (edge start), 4 = P2 (edge end)
    p3 = rng.uniform(-1, 1, 2)
    ang = rng.uniform(0, 2 * np.pi)
    length = rng.uniform(0.2, 2.0)
    p2 = p3 + length * np.array([np.cos(ang), np.sin(ang)])
    xi = rng.uniform(0.05, 0.95)
    tau = (p3 - p2) / length
    n = np.array([-tau[1], tau[0]])
    p1 = p2 + xi * (p3 - p2) + rng.uniform(-0.05, 0.05) * n
    x = np.array([p1, p1 + 0.3 * n + 0.1 * tau, p1 + 0.3 * n - 0.1 * tau,
                  p3, p2, p2 - 0.5 * n])
    blocks = np.array([0, 0, 0, 1, 1, 1])
    centroids = np.array([x[:3].mean(0), x[3:].mean(0)])
    vertex, edge, nxt = np.array([0]), np.array([3]), np.array([1, 2, 0, 4, 5, 3])
    xi0 = np.array([xi + rng.uniform(-0.1, 0.1)])

    def gaps(d):
        xm = _moved(x, blocks, centroids, d)
        g = contact_geometry(xm, vertex, edge, nxt)
        return g.gap[0], g.shear_gap(xi0)[0]

    g0 = contact_geometry(x, vertex, edge, nxt)
    e_row, i_row = first_variation_rows(g0, xi0, centroids[[0]], centroids[[1]])
    direction = rng.normal(size=(2, 6))
    h = 1e-6
    plus, minus = gaps(h * direction), gaps(-h * direction)
    fd_n = (plus[0] - minus[0]) / (2 * h)
    fd_s = (plus[1] - minus[1]) / (2 * h)
    dd = direction.reshape(-1)
    scale = np.abs(e_row[0]).sum() * np.abs(dd).max()
    assert abs(e_row[0] @ dd - fd_n) <= 1e-6 * scale
    assert abs(i_row[0] @ dd - fd_s) <= 1e-6 * (np.abs(i_row[0]).sum() * np.abs(dd).max())
