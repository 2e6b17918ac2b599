"""Direct shear of a rough joint with BartonBandis (METHOD.md section 7) in the papers' box."""

import numpy as np
import pytest

import dda
from dda.contact import BartonBandis
from dda.studies.cases import SHEAR_BOX_LENGTH, shear_box, shear_stress

JRC, JCS, PHI_R = 10.0, 50e6, 30.0

#: Barton and Bandis' mobilization table, written out again here so the test does not lean on
#: the module's copy: slip / slip at peak, and JRC_mob / JRC_peak (first entry: angle zero)
TABLE_SLIP = [0.0, 0.3, 0.6, 1.0, 2.0, 4.0, 10.0, 100.0]
TABLE_JRC = [None, 0.0, 0.75, 1.0, 0.85, 0.70, 0.50, 0.0]


def barton_peak(sigma_n):
    """tau = sigma_n tan(phi_r + JRC log10(JCS / sigma_n))."""
    return sigma_n * np.tan(np.radians(PHI_R + JRC * np.log10(JCS / sigma_n)))


@np.vectorize
def barton_mobilized(sigma_n, ratio):
    """Shear stress at slip ratio ``slip / slip_at_peak`` (table, linear between entries)."""
    i = JRC * np.log10(JCS / sigma_n)
    knots = [0.0 if m is None else PHI_R + m * i for m in TABLE_JRC]
    return sigma_n * np.tan(np.radians(np.interp(ratio, TABLE_SLIP, knots)))


@pytest.mark.parametrize("sigma_n", [0.5e6, 1e6, 2e6, 5e6])
def test_direct_shear_reaches_the_peak_strength(sigma_n):
    """6 mm in 50 steps with the peak law: the plateau is Barton's strength within 1%."""
    n = 50
    scene, lower, upper = shear_box(6e-3, friction=BartonBandis(JRC, JCS, PHI_R, mobilized=False),
                                    normal_stress=sigma_n, consolidation=1.0 / n)
    result = dda.Simulation(scene, dt=1.0 / n, analysis="static").run(1.0 + 1.0 / n)
    tau = shear_stress(result, lower, upper)
    normal = result.joint_force(lower, upper)[:, 0] / SHEAR_BOX_LENGTH
    np.testing.assert_allclose(normal[1:], sigma_n, rtol=1e-4)
    assert tau.max() == pytest.approx(barton_peak(sigma_n), rel=0.01)
    # a plateau, closer than 1%: the contacts see the deformed face, which Poisson's effect
    # widens by 0.2 sigma_n / E (0.1% at 5 MPa), so their normal stress is that much lower
    # and the measured strength 0.0015% (0.5 MPa) to 0.015% (5 MPa) above the formula
    np.testing.assert_allclose(tau[-10:], barton_peak(sigma_n), rtol=1e-3)


@pytest.fixture(scope="module")
def mobilized_direct_shear():
    """10 mm in 200 steps at 1 MPa with the mobilized law and Barton's size rule.

    Returns per step the shear stress, the normal stress and the contacts' mean accumulated
    slip, and the slip at peak of the size rule (face length 2 l_c = 0.1 m: 0.914 mm).
    """
    law = BartonBandis(JRC, JCS, PHI_R)
    n = 200
    scene, lower, upper = shear_box(10e-3, friction=law, consolidation=1.0 / n)
    sim = dda.Simulation(scene, dt=1.0 / n, analysis="static")
    sim.run(1.0 / n)  # consolidation
    tau, sigma, slip = [], [], []
    for _ in range(n):
        step = sim.run(1.0 / n)
        tau.append(shear_stress(step, lower, upper)[-1])
        sigma.append(step.joint_force(lower, upper)[-1, 0] / SHEAR_BOX_LENGTH)
        slip.append(sim.state.contacts.history["slip"].mean())
    peak_slip = SHEAR_BOX_LENGTH / 500 * (JRC / SHEAR_BOX_LENGTH) ** 0.33
    return np.array(tau), np.array(sigma), np.array(slip), peak_slip


def test_mobilized_curve_follows_barton_table(mobilized_direct_shear):
    tau, sigma, slip, peak_slip = mobilized_direct_shear
    assert slip[-1] / peak_slip > 10  # the run reaches the table's 10-slip entry
    np.testing.assert_allclose(tau, barton_mobilized(sigma, slip / peak_slip), rtol=0.01)


def test_mobilized_curve_peaks_at_the_slip_at_peak_and_softens(mobilized_direct_shear):
    tau, sigma, slip, peak_slip = mobilized_direct_shear
    k = int(np.argmax(tau))
    step_slip = np.diff(slip).max()
    assert abs(slip[k] - peak_slip) <= step_slip
    assert tau[k] == pytest.approx(barton_peak(sigma[k]), rel=0.01)
    assert np.all(np.diff(tau[: k + 1]) > 0)  # rises ...
    assert np.all(np.diff(tau[k:]) < 0)  # ... and softens along the table
    at_two = np.argmin(np.abs(slip / peak_slip - 2.0))
    assert tau[at_two] == pytest.approx(barton_mobilized(sigma[at_two], 2.0), rel=0.01)
