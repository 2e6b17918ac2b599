"""BartonBandis: peak strength, limits, mobilization, return map and its consistent tangent."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import dda
from dda.contact import BartonBandis
from dda.contact.barton import MOBILIZATION_JRC, MOBILIZATION_SLIP
from dda.contact.contacts import SLIP
from dda.studies.cases import shear_box
from tests.conftest import capture_step_problem
from tests.test_contact_element import resting_problem, sliding_problem, tangent_mismatch
from tests.test_newton import convergence_order

LENGTH = 0.05  # tributary length of the unit tests, m
PEAK_SLIP = 1e-3


def stress_angle(trial, t_n):
    """Friction angle (degrees) the returned shear force stands for."""
    return np.degrees(np.arctan(np.abs(trial.t_s) / np.abs(t_n)))


def drive(law, increments, sigma_n=1e6, penalty=1e13):
    """Slide one contact by ``increments`` under a constant normal stress, committing each.

    Returns the accumulated slip and the friction angle after every increment.
    """
    t_n = np.array([-sigma_n * LENGTH])
    state = law.initial_state(1)
    slips, angles = [], []
    for dg in increments:
        trial = law.return_map(state, np.array([dg]), t_n, np.array([penalty]),
                               np.array([LENGTH]))
        state = law.commit(trial)
        slips.append(state["slip"][0])
        angles.append(stress_angle(trial, t_n)[0])
    return np.array(slips), np.array(angles)


# --- peak strength and its limits -------------------------------------------------------------

@settings(max_examples=200, deadline=None)
@given(jrc=st.floats(0.5, 20), jcs=st.floats(5e6, 300e6), phi_r=st.floats(15, 40),
       ratio=st.floats(1e-3, 0.9))
def test_peak_strength_is_barton_formula(jrc, jcs, phi_r, ratio):
    sigma = ratio * jcs
    law = BartonBandis(jrc, jcs, phi_r, mobilized=False)
    t_n = np.array([-sigma * LENGTH])
    trial = law.return_map(law.initial_state(1), np.array([1.0]), t_n, np.array([1e9]),
                           np.array([LENGTH]))
    angle = min(phi_r + jrc * np.log10(jcs / sigma), 70.0)
    assert trial.slipping[0]
    assert trial.t_s[0] == pytest.approx(sigma * LENGTH * np.tan(np.radians(angle)), rel=1e-12)


def test_limits_where_the_logarithm_misbehaves():
    law = BartonBandis(jrc=15, jcs=50e6, phi_r=28, mobilized=False)
    sigma = np.array([0.0, 1e-6, 1.0, 50e6, 80e6, 1e9])
    angle = law.peak_angle(sigma)
    # capped at 70 degrees as sigma_n -> 0, and no roughness at or above JCS
    np.testing.assert_allclose(angle, [70, 70, 70, 28, 28, 28])
    # the cap is continuous: it starts where phi_r + i reaches 70
    at_cap = 50e6 * 10 ** (-(70 - 28) / 15)
    np.testing.assert_allclose(law.peak_angle(at_cap * np.array([1 - 1e-9, 1 + 1e-9])), 70,
                               atol=1e-6)
    # strength: zero at zero normal force, finite everywhere
    s, ds_dp, ds_dk, _ = law.shear_strength(sigma * LENGTH, np.full(6, LENGTH), np.zeros(6))
    assert s[0] == 0.0 and np.all(np.isfinite(s)) and np.all(np.isfinite(ds_dp))
    np.testing.assert_allclose(ds_dp[:3], np.tan(np.radians(70)))  # cap: d i/d sigma = 0
    np.testing.assert_allclose(ds_dp[3:], np.tan(np.radians(28)))
    np.testing.assert_array_equal(ds_dk, 0.0)


def test_open_contact_carries_no_shear():
    law = BartonBandis(jrc=10, jcs=50e6, phi_r=30, slip_at_peak=PEAK_SLIP)
    trial = law.return_map(law.initial_state(2), np.array([1e-4, -1e-4]), np.zeros(2),
                           np.full(2, 1e9), np.full(2, LENGTH))
    np.testing.assert_array_equal(trial.t_s, 0.0)
    np.testing.assert_allclose(trial.state["slip"], 1e-4, rtol=1e-12)


@pytest.mark.parametrize("kwargs, message", [
    ({"jrc": 21}, "jrc"), ({"jrc": -1}, "jrc"), ({"jcs": 0}, "jcs"), ({"phi_r": 75}, "phi_r"),
    ({"phi_r": float("nan")}, "phi_r"), ({"max_angle": 90}, "max_angle"),
    ({"slip_at_peak": 0}, "slip_at_peak"), ({"block_size": -1}, "block_size"),
])
def test_bad_parameters_are_named(kwargs, message):
    args = {"jrc": 10, "jcs": 50e6, "phi_r": 30} | kwargs
    with pytest.raises(ValueError, match=f"BartonBandis: {message}"):
        BartonBandis(**args)


# --- mobilization -----------------------------------------------------------------------------

def test_mobilized_angle_follows_barton_table():
    """Slid in 1 um increments, the angle follows the table, linearly between its entries."""
    jrc, jcs, phi_r, sigma = 12.0, 60e6, 28.0, 2e6
    law = BartonBandis(jrc, jcs, phi_r, slip_at_peak=PEAK_SLIP)
    i = jrc * np.log10(jcs / sigma)
    slips, angles = drive(law, np.full(12_000, 1e-6), sigma_n=sigma)
    at_knots = np.where(MOBILIZATION_SLIP == 0, 0.0,
                        phi_r + np.nan_to_num(MOBILIZATION_JRC) * i)
    # nearly rigid-plastic: the elastic part t_s / p_s is about 1e-8 m
    np.testing.assert_allclose(slips, 1e-6 * np.arange(1, 12_001), rtol=0, atol=2e-8)
    np.testing.assert_allclose(angles, np.interp(slips / PEAK_SLIP, MOBILIZATION_SLIP, at_knots),
                               atol=1e-9)
    # rises to the peak at slip_at_peak, then softens
    k = np.argmax(angles)
    assert slips[k] == pytest.approx(PEAK_SLIP, abs=2e-8)
    assert angles[k] == pytest.approx(phi_r + i, abs=5e-4)  # 1e-8 m short of the peak
    assert np.all(np.diff(angles[: k + 1]) > 0) and np.all(np.diff(angles[k:]) < 0)


def test_residual_angle_beyond_the_table():
    law = BartonBandis(jrc=12, jcs=60e6, phi_r=28, slip_at_peak=1e-5)
    _, angles = drive(law, [0.5e-3, 1e-3, 5e-3])  # 50, 150 and 650 slips at peak
    assert angles[0] > 28.0
    np.testing.assert_allclose(angles[1:], 28.0, atol=1e-9)


def test_one_large_increment_lands_on_the_backward_euler_solution():
    """An increment that crosses several table segments still satisfies the return map."""
    law = BartonBandis(jrc=12, jcs=60e6, phi_r=28, slip_at_peak=PEAK_SLIP)
    ps = np.full(4, 2e6)  # a soft penalty: the elastic part is visible
    t_n = np.full(4, -1e6 * LENGTH)
    length = np.full(4, LENGTH)
    dg = np.array([0.4e-3, 1.5e-3, 3e-3, -6e-3])
    trial = law.return_map(law.initial_state(4), dg, t_n, ps, length)
    lam = trial.state["slip"]
    s, _, _, _ = law.shear_strength(-t_n, length, lam)
    np.testing.assert_allclose(np.abs(ps * dg) - ps * lam, s, rtol=1e-12)
    np.testing.assert_allclose(trial.t_s, np.sign(dg) * s, rtol=1e-12)
    assert np.all(lam > 0) and np.all(lam < np.abs(dg))


def test_size_rule_for_the_slip_at_peak():
    length = np.array([0.05, 0.5])
    by_contact = BartonBandis(jrc=10, jcs=50e6, phi_r=30)
    np.testing.assert_allclose(by_contact.peak_slip(length),
                               2 * length / 500 * (10 / (2 * length)) ** 0.33)
    by_block = BartonBandis(jrc=10, jcs=50e6, phi_r=30, block_size=1.0)
    np.testing.assert_allclose(by_block.peak_slip(length), 1.0 / 500 * 10**0.33)
    given_slip = BartonBandis(jrc=10, jcs=50e6, phi_r=30, slip_at_peak=2e-3, block_size=1.0)
    np.testing.assert_allclose(given_slip.peak_slip(length), 2e-3)


def test_smooth_joint_has_nothing_to_mobilize():
    law = BartonBandis(jrc=0, jcs=50e6, phi_r=30)
    _, angles = drive(law, [1e-6, 1e-3])
    np.testing.assert_allclose(angles, 30.0, rtol=1e-12)


def test_dilation_is_kept_only_when_asked():
    assert "dilation" not in BartonBandis(10, 50e6, 30).initial_state(1)
    jrc, jcs, phi_r, sigma = 10.0, 50e6, 30.0, 1e6
    law = BartonBandis(jrc, jcs, phi_r, mobilized=False, dilation=True)
    t_n = np.array([-sigma * LENGTH])
    state = law.initial_state(1)
    for _ in range(3):
        state = law.commit(law.return_map(state, np.array([1e-3]), t_n, np.array([1e12]),
                                          np.array([LENGTH])))
    i = jrc * np.log10(jcs / sigma)
    assert state["dilation"][0] == pytest.approx(np.tan(np.radians(i / 2)) * state["slip"][0],
                                                 rel=1e-12)


def on_surface(law, slip, sigma, penalty, fraction=1.0, sign=1.0):
    """Committed history of one contact with ``slip`` accumulated, its elastic shear force at
    ``fraction`` of the strength."""
    s, _, _, _ = law.shear_strength(np.array([sigma * LENGTH]), np.array([LENGTH]),
                                    np.array([slip]))
    state = law.initial_state(1)
    state["slip"][:] = slip
    state["g_se"][:] = sign * fraction * s / penalty
    return state


def test_snap_back_warns_once():
    law = BartonBandis(jrc=20, jcs=100e6, phi_r=30, slip_at_peak=1e-6)
    ps, pn = np.array([1e6]), np.array([1e6])
    state = on_surface(law, 1.5e-6, 5e6, ps[0])  # on the softening branch
    def step():
        return law.return_map(state, np.array([1e-9]), np.array([-5e6 * LENGTH]), ps,
                              np.array([LENGTH]))

    with pytest.warns(RuntimeWarning, match="softens faster than the shear penalty"):
        trial = step()
    assert trial.slipping[0]
    assert np.all(np.isfinite(law.tangent(trial, pn, ps)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        step()


# --- consistent tangent -----------------------------------------------------------------------

def tangent_cases():
    """(law, committed slip, elastic force / strength, shear increment, normal stress)."""
    mob = BartonBandis(jrc=12, jcs=60e6, phi_r=28, slip_at_peak=PEAK_SLIP)
    peak = BartonBandis(jrc=12, jcs=60e6, phi_r=28, mobilized=False)
    sized = BartonBandis(jrc=8, jcs=60e6, phi_r=28, dilation=True)
    return {
        "stick": (mob, 0.8e-3, 0.5, 1e-6, 2e6),
        "stick-unloading": (mob, 0.8e-3, 1.0, -1e-6, 2e6),
        "rising": (mob, 0.1e-3, 1.0, 2e-6, 2e6),
        "hardening": (mob, 0.7e-3, 1.0, 2e-6, 2e6),
        "softening": (mob, 1.5e-3, 1.0, 5e-6, 2e6),
        "softening-negative": (mob, 2.5e-3, -1.0, -5e-6, 2e6),
        "tail": (mob, 20e-3, 1.0, 5e-5, 2e6),
        "across-knots": (mob, 0.2e-3, 1.0, 1.5e-3, 2e6),
        "capped": (mob, 1.5e-3, 1.0, 5e-6, 100.0),
        "above-jcs": (mob, 1.5e-3, 1.0, 5e-6, 90e6),
        "peak": (peak, 0.0, 1.0, 2e-6, 2e6),
        "size-rule": (sized, 0.5e-3, 1.0, 2e-6, 2e6),
    }


@pytest.mark.parametrize("case", sorted(tangent_cases()))
def test_tangent_matches_finite_differences(case):
    law, slip, fraction, dg, sigma = tangent_cases()[case]
    pn, ps = np.array([3e9]), np.array([2e9])
    length = np.array([LENGTH])
    committed = on_surface(law, slip, sigma, ps[0], abs(fraction), np.sign(fraction))
    t_n0 = -sigma * LENGTH
    g_n0 = t_n0 / pn[0]

    def t_s(delta_g_s, g_n):
        return law.return_map(committed, np.array([delta_g_s]), np.array([pn[0] * g_n]), ps,
                              length).t_s[0]

    trial = law.return_map(committed, np.array([dg]), np.array([t_n0]), ps, length)
    assert trial.slipping[0] == (not case.startswith("stick"))
    dts_dgs, dts_dgn = law.tangent(trial, pn, ps)
    hs, hn = 1e-4 * abs(dg), 1e-6 * abs(g_n0)
    fd_s = (t_s(dg + hs, g_n0) - t_s(dg - hs, g_n0)) / (2 * hs)
    fd_n = (t_s(dg, g_n0 + hn) - t_s(dg, g_n0 - hn)) / (2 * hn)
    scale = ps[0] + pn[0]
    assert abs(dts_dgs[0] - fd_s) < 1e-6 * scale, (dts_dgs[0], fd_s)
    assert abs(dts_dgn[0] - fd_n) < 1e-6 * scale, (dts_dgn[0], fd_n)
    if not case.startswith("stick"):  # the normal-shear coupling is there in slip
        assert abs(dts_dgn[0]) > 1e-3 * pn[0]


# --- inside the contact element and Newton-Raphson ----------------------------------------------

SCENE_LAWS = {
    "peak": lambda: BartonBandis(jrc=2, jcs=1e5, phi_r=20, mobilized=False),
    "mobilized": lambda: BartonBandis(jrc=2, jcs=1e5, phi_r=20, slip_at_peak=1e-3),
    "size-rule": lambda: BartonBandis(jrc=5, jcs=1e6, phi_r=20),
}


@pytest.mark.parametrize("law_name", sorted(SCENE_LAWS))
@pytest.mark.parametrize("case, expect_slip", [(sliding_problem, True),
                                               (resting_problem, False)],
                         ids=["slip", "stick"])
def test_contact_tangent_matches_finite_differences(case, expect_slip, law_name):
    """The element's tangent with this law against FD of its residual (geometric terms in)."""
    problem = case(SCENE_LAWS[law_name]())
    resp, mismatch = tangent_mismatch(problem, np.random.default_rng(1))
    on_law = resp.closed & (problem.element.contacts.history["slip"] > 0)  # not the wedge's
    if expect_slip:
        assert resp.slipping[on_law].sum() >= 2
    else:
        assert (resp.closed & ~resp.slipping).sum() >= 2
    assert mismatch < 1e-6


@pytest.fixture(scope="module")
def softening_shear_step():
    """A direct-shear step on the softening branch (slip about 2 slip_at_peak), solved."""
    law = BartonBandis(jrc=10, jcs=50e6, phi_r=30, slip_at_peak=0.5e-3)
    n = 50
    scene, _, _ = shear_box(4e-3, friction=law, consolidation=1.0 / n)
    sim = dda.Simulation(scene, dt=1.0 / n, analysis="static")
    sim.run(0.6)
    problem = capture_step_problem(sim, 1.0 / n)
    return problem, dda.solvers.NewtonRaphson(tol=1e-14).solve_step(problem)


@pytest.mark.parametrize("shift", [1e-4, 3e-4, 1e-3])
def test_newton_converges_quadratically_through_the_law(softening_shear_step, shift):
    """g_n is linear in the unknowns here, so the law alone makes the step nonlinear; a
    1 mm shift crosses the table entry at 4 slips at peak."""
    problem, reference = softening_shear_step
    assert (reference.contacts.state == SLIP).all()
    d = reference.d.copy()
    d[problem.free, 0] += shift
    sol = dda.solvers.NewtonRaphson(tol=1e-14).iterate(problem, d)
    assert sol.converged
    np.testing.assert_allclose(sol.d, reference.d, rtol=0, atol=1e-12)
    assert convergence_order(sol.residual_norms, floor=1e-6) >= 1.8


@pytest.mark.parametrize("rotation", [0.003, 0.01])
def test_newton_converges_quadratically_on_a_moving_edge(rotation):
    """The block slipping down the free wedge: geometric terms and the law together."""
    problem = sliding_problem(SCENE_LAWS["mobilized"]())
    reference = dda.solvers.NewtonRaphson(tol=1e-14).solve_step(problem)
    d = reference.d.copy()
    d[problem.free, 2] += rotation * np.array([1.0, -1.0])
    sol = dda.solvers.NewtonRaphson(tol=1e-14).iterate(problem, d)
    assert sol.converged
    np.testing.assert_allclose(sol.d, reference.d, rtol=0, atol=1e-12)
    assert convergence_order(sol.residual_norms, floor=1e-7) >= 1.8


# --- the compiled return map ------------------------------------------------------------------

#: the relative round-off the compiled and numpy return maps may differ by (a few ulp of the
#: transcendental functions, 31 ulp = 3.4e-15 in a derivative measured)
ROUND_OFF = 1e-13


@pytest.mark.parametrize("options", [
    {}, {"mobilized": False}, {"slip_at_peak": 2e-4}, {"block_size": 0.5},
    {"dilation": True}, {"jrc": 0.0}, {"jrc": 18.0, "max_angle": 60.0},
])
def test_compiled_return_map_is_the_numpy_one(options):
    """dda.kernels.barton against the numpy return map, over contacts that stick, slip on
    every segment of Barton's table and beyond it, stand above JCS, carry no load or are open,
    with a push either way and softening faster than the penalty: the same decisions, and
    the numbers to round-off. They were the same bits on machines without AVX-512; on one
    with it numpy's vectorized ``log10``, ``tan`` and the like differ from the C library's,
    which the kernel calls, in the last bits (3 ulp in the forces, 31 in ``ds_dk``)."""
    import dda.contact.barton as barton

    args = {"jrc": 10.0, "jcs": 50e6, "phi_r": 30.0} | options
    law = BartonBandis(**args)
    rng = np.random.default_rng(len(repr(options)))
    m = 400
    length = rng.uniform(0.01, 0.5, m)
    sigma = 10.0 ** rng.uniform(2, 8.5, m)  # up to beyond JCS
    sigma[:20] = 0.0
    t_n = -sigma * length
    t_n[20:30] = 1e3  # open
    peak = law.peak_slip(length) if law.mobilized else np.full(m, 1e-3)
    committed = law.initial_state(m)
    committed["slip"] = peak * 10.0 ** rng.uniform(-3, 2.3, m)  # 0.001 to 200 peaks
    committed["slip"][30:40] = 0.0
    penalty = 10.0 ** rng.uniform(5, 11, m)
    committed["g_se"] = rng.normal(0.0, 1.0, m) * sigma * length / penalty
    if law.dilation:
        committed["dilation"] = rng.uniform(0.0, 1e-4, m)
    dgs = rng.normal(0.0, 1.0, m) * 10.0 ** rng.uniform(-7, -3, m)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the softest penalties snap back
        compiled = law.return_map(committed, dgs, t_n, penalty, length)
        barton.COMPILED = False
        try:
            numpy = law.return_map(committed, dgs, t_n, penalty, length)
        finally:
            barton.COMPILED = True
    assert 0.2 * m < numpy.slipping.sum() < m - 40
    np.testing.assert_array_equal(compiled.slipping, numpy.slipping)
    for name in ("t_s", "strength"):
        np.testing.assert_allclose(getattr(compiled, name), getattr(numpy, name), rtol=ROUND_OFF,
                                   atol=0.0, err_msg=name)
    assert compiled.state.keys() == numpy.state.keys()
    for name in numpy.state:
        np.testing.assert_allclose(compiled.state[name], numpy.state[name], rtol=ROUND_OFF,
                                   atol=0.0, err_msg=name)
    for name in ("ds_dp", "ds_dk"):
        np.testing.assert_allclose(compiled.extra[name], numpy.extra[name], rtol=ROUND_OFF,
                                   atol=0.0, err_msg=name)
