"""Friction laws: return map and consistent tangent (METHOD.md section 4)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dda.contact import CoulombSingle, StaticDynamicTransition

LAWS = [CoulombSingle(phi=30.0), CoulombSingle(phi=36.4, cohesion=1e4)]
ALL_LAWS = LAWS + [StaticDynamicTransition(phi_static=30.0, phi_dynamic=20.0),
                   StaticDynamicTransition(phi_static=30.0, phi_dynamic=20.0, onset="contact")]


@pytest.mark.parametrize("law", LAWS, ids=repr)
def test_stick_inside_and_slip_on_the_surface(law):
    n = 5
    ps = np.full(n, 1e8)
    t_n = np.full(n, -1e5)
    length = np.full(n, 0.1)
    strength = law.cohesion * 0.1 + 1e5 * law.mu
    dg = np.array([-3, -0.5, 0.0, 0.5, 3]) * strength / 1e8
    trial = law.return_map(law.initial_state(n), dg, t_n, ps, length)
    np.testing.assert_array_equal(trial.slipping, [True, False, False, False, True])
    np.testing.assert_allclose(trial.t_s, [-strength, -0.5 * strength, 0, 0.5 * strength,
                                           strength], rtol=1e-12)
    # the slip goes into the history, the elastic part stays at the strength
    np.testing.assert_allclose(trial.state["slip"], [2 * strength / 1e8, 0, 0, 0,
                                                     2 * strength / 1e8], rtol=1e-12)
    np.testing.assert_allclose(trial.state["g_se"] * ps, trial.t_s, rtol=1e-12)


@pytest.mark.parametrize("law", ALL_LAWS, ids=repr)
def test_return_map_never_changes_the_committed_state(law):
    committed = law.initial_state(3)
    before = {k: v.copy() for k, v in committed.items()}
    law.return_map(committed, np.ones(3), -np.ones(3), np.ones(3), np.ones(3))
    for k in before:
        np.testing.assert_array_equal(committed[k], before[k])


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(ALL_LAWS), st.floats(-5, 5), st.floats(-5, 5), st.floats(0.1, 3.0),
       st.booleans())
def test_tangent_matches_finite_differences(law, g_se0, dg, gn_scale, sliding):
    """d t_s / d g_s and d t_s / d g_n of the return map against central differences."""
    pn, ps, lc = 1e9, 2e8, 0.1
    gn = -1e-4 * gn_scale
    committed = law.initial_state(1)
    committed["sliding"] = np.array([float(sliding)])
    if isinstance(law, StaticDynamicTransition):
        mu = law.mu_dynamic if sliding else law.mu_static
        strength = pn * abs(gn) * mu
    else:
        strength = law.cohesion * lc + pn * abs(gn) * law.mu
    committed["g_se"] = np.array([g_se0 * strength / ps])
    dgs = np.array([dg * strength / ps])
    # stay away from the kink of the yield surface, where no derivative exists
    trial_t = ps * (committed["g_se"] + dgs)
    if abs(abs(trial_t[0]) - strength) < 1e-3 * strength:
        return

    def ts(dgs_, gn_):
        return law.return_map(committed, dgs_, np.array([pn * gn_]), np.array([ps]),
                              np.array([lc])).t_s[0]

    trial = law.return_map(committed, dgs, np.array([pn * gn]), np.array([ps]), np.array([lc]))
    dts_dgs, dts_dgn = law.tangent(trial, np.array([pn]), np.array([ps]))
    h = 1e-7 * strength / ps
    fd_s = (ts(dgs + h, gn) - ts(dgs - h, gn)) / (2 * h)
    hn = 1e-7 * abs(gn)
    fd_n = (ts(dgs, gn + hn) - ts(dgs, gn - hn)) / (2 * hn)
    assert dts_dgs[0] == pytest.approx(fd_s, rel=1e-6, abs=1e-6 * ps)
    assert dts_dgn[0] == pytest.approx(fd_n, rel=1e-6, abs=1e-6 * pn)


def test_static_dynamic_transition_follows_method_section_6():
    law = StaticDynamicTransition(phi_static=30.0, phi_dynamic=20.0)
    ps, t_n, lc = np.array([1.0]), np.array([-1.0]), np.ones(1)
    mu_s, mu_d = np.tan(np.radians(30)), np.tan(np.radians(20))
    state = law.initial_state(1)
    # sticking: holds up to the static strength
    trial = law.return_map(state, np.array([0.99 * mu_s]), t_n, ps, lc)
    assert not trial.slipping[0] and trial.t_s[0] == pytest.approx(0.99 * mu_s)
    # yields above it and drops at once to the dynamic strength
    trial = law.return_map(state, np.array([1.01 * mu_s]), t_n, ps, lc)
    assert trial.slipping[0] and trial.t_s[0] == pytest.approx(mu_d)
    sliding = law.commit(trial)
    assert sliding["sliding"][0] == 1.0
    # while sliding, the yield check uses the dynamic angle
    trial = law.return_map(sliding, np.array([0.01]), t_n, ps, lc)
    assert trial.slipping[0] and trial.t_s[0] == pytest.approx(mu_d)
    # unloading back into the cone sticks again ...
    trial = law.return_map(sliding, np.array([-0.05]), t_n, ps, lc)
    assert not trial.slipping[0] and trial.t_s[0] == pytest.approx(mu_d - 0.05)
    stuck = law.commit(trial)
    assert stuck["sliding"][0] == 0.0
    # ... and the next slip must exceed the static strength again
    trial = law.return_map(stuck, np.array([mu_s - (mu_d - 0.05) - 0.01]), t_n, ps, lc)
    assert not trial.slipping[0] and trial.t_s[0] == pytest.approx(mu_s - 0.01)
    # a legacy (elastic) update clears the sliding flag too
    assert law.elastic_update(sliding, np.zeros(1))["sliding"][0] == 0.0


def test_static_dynamic_transition_checks_its_angles():
    with pytest.raises(ValueError, match="phi_dynamic"):
        StaticDynamicTransition(phi_static=20.0, phi_dynamic=30.0)
    with pytest.raises(ValueError, match="phi_static"):
        StaticDynamicTransition(phi_static=95.0, phi_dynamic=30.0)


@pytest.mark.parametrize("law", [
    CoulombSingle(phi=30.0), CoulombSingle(phi=25.0, cohesion=2e4),
    StaticDynamicTransition(35.0, 20.0, onset="contact"), StaticDynamicTransition(35.0, 20.0)])
def test_compiled_return_map_is_the_numpy_one(law):
    """The built-in laws' compiled return map gives the numpy path's trial to the bit:
    sticking and slipping contacts, open ones (t_n >= 0), zero trials, faces of one to four
    contacts with sliding and sticking members."""
    from dda.contact.faces import Faces

    rng = np.random.default_rng(3)
    m = 400
    history = law.initial_state(m)
    history["g_se"] = rng.normal(scale=1e-6, size=m)
    history["slip"] = rng.uniform(0, 1e-3, size=m)
    if "sliding" in history:
        history["sliding"] = (rng.uniform(size=m) < 0.4).astype(float)
    dgs = rng.normal(scale=2e-6, size=m)
    dgs[:5] = -history["g_se"][:5]  # zero trial force
    t_n = -rng.uniform(0, 2e3, size=m)
    t_n[5:15] = rng.uniform(0, 1e2, size=10)  # open or just touching
    t_n[15:20] = 0.0
    p_s = rng.uniform(1e8, 1e10, size=m)
    length = rng.uniform(0.1, 2.0, size=m)
    faces = Faces(np.sort(rng.integers(0, m // 2, size=m))) if law.uses_faces else None
    got = law.return_map(history, dgs, t_n, p_s, length, faces=faces)
    want = law._numpy_return_map(history, dgs, t_n, p_s, length, faces=faces)
    assert got.slipping.any() and not got.slipping.all()
    for a, b in ((got.t_s, want.t_s), (got.slipping, want.slipping),
                 (got.strength, want.strength)):
        np.testing.assert_array_equal(a, b)
    assert got.state.keys() == want.state.keys()
    for key in got.state:
        np.testing.assert_array_equal(got.state[key], want.state[key])
    np.testing.assert_array_equal(law.tangent(got, 1e10, p_s), law.tangent(want, 1e10, p_s))


def test_a_subclass_of_a_built_in_law_takes_the_numpy_path():
    """A law that overrides a part of a built-in one (here the strength) is not given the
    built-in law's compiled return map."""
    class Weaker(CoulombSingle):
        def strength(self, t_n, length, history=None):
            return 0.5 * super().strength(t_n, length, history)

    law = Weaker(phi=45.0)
    trial = law.return_map(law.initial_state(1), np.array([1.0]), np.array([-100.0]),
                           np.array([80.0]), np.ones(1))
    assert trial.slipping[0] and trial.t_s[0] == pytest.approx(50.0)
