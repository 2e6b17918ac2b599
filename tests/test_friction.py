"""Friction laws: return map and consistent tangent (METHOD.md section 4)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dda.contact import CoulombSingle, StaticDynamicTransition

LAWS = [CoulombSingle(phi=30.0), CoulombSingle(phi=36.4, cohesion=1e4)]
ALL_LAWS = LAWS + [StaticDynamicTransition(phi_static=30.0, phi_dynamic=20.0)]


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
