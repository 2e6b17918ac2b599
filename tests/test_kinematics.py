"""Finite-difference checks of g_n, g_s and their first variations E and I (METHOD.md s. 3)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from dda import geometry
from dda.contact.kinematics import pair_maps, trial_kinematics


def _moved(x, blocks, centroids, d):
    """Vertices after the linear displacement T d of their blocks (no rotation correction)."""
    t = geometry.t_matrix(x, centroids[blocks])
    return x + np.einsum("vij,vj->vi", t, d[blocks])


def _random_contact(rng):
    """A vertex (block 0) near an edge of block 1 and a random reference parameter xi0."""
    p3 = rng.uniform(-1, 1, 2)
    ang = rng.uniform(0, 2 * np.pi)
    length = rng.uniform(0.2, 2.0)
    p2 = p3 + length * np.array([np.cos(ang), np.sin(ang)])
    tau = (p3 - p2) / length
    n = np.array([-tau[1], tau[0]])
    p1 = p2 + rng.uniform(0.05, 0.95) * (p3 - p2) + rng.uniform(-0.05, 0.05) * n
    x = np.array([p1, p1 + 0.3 * n + 0.1 * tau, p1 + 0.3 * n - 0.1 * tau,
                  p3, p2, p2 - 0.5 * n])
    blocks = np.array([0, 0, 0, 1, 1, 1])
    centroids = np.array([x[:3].mean(0), x[3:].mean(0)])
    xi0 = np.array([rng.uniform(0.0, 1.0)])
    return x, blocks, centroids, xi0


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_second_variations_match_finite_differences(seed):
    """E, I rows and the G, H, E', J bilinear forms as exact derivatives of g_n(d), g_s(d),
    checked at a random trial state d (not only at d = 0)."""
    rng = np.random.default_rng(seed)
    x, blocks, centroids, xi0 = _random_contact(rng)
    vertex, edge, nxt = np.array([0]), np.array([3]), np.array([1, 2, 0, 4, 5, 3])
    maps = pair_maps(x, vertex, edge, nxt, centroids[[0]], centroids[[1]])
    d0 = 0.02 * rng.normal(size=12)

    def kin(dd, second=True):
        xm = _moved(x, blocks, centroids, dd.reshape(2, 6))
        return trial_kinematics(xm[vertex], xm[nxt[edge]], xm[edge], xi0, maps, second=second)

    k0 = kin(d0)
    u, v = rng.normal(size=12), rng.normal(size=12)
    h = 1e-6
    kp, km = kin(d0 + h * v, False), kin(d0 - h * v, False)
    # first variations
    fd_gn = (kp.gap[0] - km.gap[0]) / (2 * h)
    fd_gs = (kp.shear[0] - km.shear[0]) / (2 * h)
    assert abs(k0.e_row[0] @ v - fd_gn) <= 1e-6 * np.abs(k0.e_row[0]).sum() * np.abs(v).max()
    assert abs(k0.i_row[0] @ v - fd_gs) <= 1e-6 * np.abs(k0.i_row[0]).sum() * np.abs(v).max()
    # second variations: derivative of the first variation rows along v, applied to u
    fd_hn = ((kp.e_row[0] - km.e_row[0]) @ u) / (2 * h)
    fd_hs = ((kp.i_row[0] - km.i_row[0]) @ u) / (2 * h)
    an_hn = u @ k0.gn_hessian[0] @ v
    an_hs = u @ k0.gs_hessian[0] @ v
    scale_n = np.abs(k0.gn_hessian[0]).max() * np.abs(u).sum() * np.abs(v).sum()
    scale_s = np.abs(k0.gs_hessian[0]).max() * np.abs(u).sum() * np.abs(v).sum()
    assert abs(an_hn - fd_hn) <= 1e-6 * scale_n
    assert abs(an_hs - fd_hs) <= 1e-6 * scale_s
    # symmetric, as second derivatives are
    np.testing.assert_allclose(k0.gn_hessian[0], k0.gn_hessian[0].T, atol=1e-14 * scale_n)
