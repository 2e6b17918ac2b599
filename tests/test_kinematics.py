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


def test_compiled_first_variations_are_the_numpy_ones():
    """Without second variations the kinematics come from a compiled kernel; its frame, gaps
    and rows are the numpy path's (the one that also builds the second variations) to the
    bit."""
    from dda.contact.kinematics import trial_kinematics

    rng = np.random.default_rng(0)
    m = 500
    p1, p2, p3 = (rng.normal(size=(m, 2)) for _ in range(3))
    xi0 = rng.uniform(-0.2, 1.2, m)
    maps = tuple(rng.normal(size=(m, 2, 12)) for _ in range(3))
    fast = trial_kinematics(p1, p2, p3, xi0, maps, second=False)
    full = trial_kinematics(p1, p2, p3, xi0, maps, second=True)
    assert fast.gn_hessian is None and full.gn_hessian is not None
    for name in ("gap", "shear", "xi", "length", "normal", "tau", "e_row", "i_row"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(full, name), err_msg=name)


def test_compiled_contact_frame_is_the_numpy_one():
    """The compiled contact frame gives numpy's frame to the bit (hypot, then the dot
    products as einsum sums them)."""
    from dda.contact.kinematics import contact_frame

    rng = np.random.default_rng(1)
    p1, p2, p3 = (rng.normal(scale=50.0, size=(400, 2)) for _ in range(3))
    got = contact_frame(p1, p2, p3)
    d = p3 - p2
    length = np.hypot(d[:, 0], d[:, 1])
    tau = d / length[:, None]
    normal = np.stack([-tau[:, 1], tau[:, 0]], axis=1)
    rel = p1 - p2
    for name, want in (("length", length), ("tau", tau), ("normal", normal),
                       ("gap", np.einsum("ij,ij->i", rel, normal)),
                       ("xi", np.einsum("ij,ij->i", rel, tau) / length)):
        np.testing.assert_array_equal(getattr(got, name), want, err_msg=name)


def test_compiled_pair_maps_and_tributary_lengths_are_the_numpy_ones():
    """The element's maps of [d_j; d_k] to its three points and the contacts' tributary
    lengths come from compiled kernels: the numpy formulas' numbers to the bit, on the
    contacts of a shaken jointed slope."""
    import dda
    from dda.contact.kinematics import contact_geometry, pair_maps, tributary_length
    from dda.geometry import polygon_integrals, t_matrix
    from tests.stability import scenes

    sim = dda.Simulation(scenes.shaken_cut_slope()[0], dt=2e-3)
    sim.run(0.02, progress=False)
    x, c, topo = sim.state.x, sim.state.contacts, sim.model.topo
    centroid = polygon_integrals(x, sim.model.offsets, topo.nxt).centroid
    cj, ck = centroid[c.bj], centroid[c.bk]
    m = len(c)
    t = t_matrix(np.concatenate([x[c.vertex], x[topo.nxt[c.edge]], x[c.edge]]),
                 np.concatenate([cj, ck, ck]))
    want = np.zeros((3, m, 2, 12))
    want[0, :, :, :6] = t[:m]
    want[1:, :, :, 6:] = t[m:].reshape(2, m, 2, 6)
    for got, expected in zip(pair_maps(x, c.vertex, c.edge, topo.nxt, cj, ck), want,
                             strict=True):
        np.testing.assert_array_equal(got, expected)
    geom = contact_geometry(x, c.vertex, c.edge, topo.nxt)
    arms = []
    for nb in (topo.prv[c.vertex], topo.nxt[c.vertex]):
        a = x[nb] - geom.p1
        la = np.hypot(a[:, 0], a[:, 1])
        arms.append((la, np.abs(np.einsum("ij,ij->i", a, geom.tau)) / la))
    (la, ca), (lb, cb) = arms
    expected = 0.5 * np.minimum(geom.length, np.where(ca >= cb, la, lb))
    np.testing.assert_array_equal(
        tributary_length(x, c.vertex, geom, topo.prv, topo.nxt), expected)
