"""Reference solutions: the rigid sliding block against closed forms (METHOD.md section 9)."""

import numpy as np
import pytest

from dda.studies.references import sliding_block

G = 9.81


def test_block_on_a_sinusoidal_table_matches_the_closed_form_slip():
    """a_1 = A sin(w t) with A > mu g: the first slip, from t_1 = asin(mu g / A) / w, has
    s'' = -A sin(w t) + mu g, integrated by hand; the motion then repeats each half cycle."""
    mu, amp, w = np.tan(np.radians(36.4)), G, 4 * np.pi
    t = np.linspace(0.0, 1.0, 4001)
    ref = sliding_block(lambda tt: (amp * np.sin(w * tt), 0.0), t, mu)
    t1 = np.arcsin(mu * G / amp) / w
    (start, what), (stop, _) = ref.events[:2]
    assert what == "slide -" and start == pytest.approx(t1, abs=1e-12)
    tt = t[(t > t1) & (t < stop)]
    closed = ((amp / w**2) * (np.sin(w * tt) - np.sin(w * t1))
              - (amp / w) * np.cos(w * t1) * (tt - t1) + 0.5 * mu * G * (tt - t1) ** 2)
    sel = (t > t1) & (t < stop)
    np.testing.assert_allclose(ref.slip[sel], closed, rtol=0, atol=1e-12)
    # it sticks when the relative velocity returns to zero ...
    rel_velocity = (amp / w) * (np.cos(w * stop) - np.cos(w * t1)) + mu * G * (stop - t1)
    assert rel_velocity == pytest.approx(0.0, abs=1e-10)
    # ... and each half period mirrors the previous one: back and forth between 0 and the
    # deepest slip
    starts = [e for e, what in ref.events if what.startswith("slide")]
    np.testing.assert_allclose(np.diff(starts), 0.25, atol=1e-10)
    ts = stop - t1
    deepest = ((amp / w**2) * (np.sin(w * stop) - np.sin(w * t1))
               - (amp / w) * np.cos(w * t1) * ts + 0.5 * mu * G * ts**2)
    # sampled every 0.25 ms, the extremes (where s' = 0) are within 0.5 s'' dt^2 of it
    assert ref.slip.min() == pytest.approx(deepest, abs=1e-6)
    assert ref.slip.max() == pytest.approx(0.0, abs=1e-9)
    assert ref.slip[-1] == pytest.approx(0.0, abs=1e-9)


def test_block_stays_when_the_table_is_gentle():
    ref = sliding_block(lambda t: (0.7 * G * np.sin(6 * t), 0.0), np.linspace(0, 3, 31),
                        mu_static=0.75)
    np.testing.assert_array_equal(ref.slip, 0.0)
    assert not ref.sliding.any() and ref.events == []


@pytest.mark.parametrize("mu, slides", [(0.3, True), (0.6, False)])
def test_block_on_a_still_incline(mu, slides):
    t = np.linspace(0, 2, 21)
    ref = sliding_block(lambda tt: (0.0, 0.0), t, mu, dip=30.0)
    b = np.radians(30.0)
    expect = 0.5 * G * (np.sin(b) - mu * np.cos(b)) * t**2 if slides else 0.0 * t
    np.testing.assert_allclose(ref.slip, expect, rtol=1e-10, atol=1e-14)


def test_static_to_dynamic_on_a_shaken_incline():
    """The table accelerates towards the slope's back at a_x = -k t: the block holds until
    -a_x = g tan(phi_s - dip), then slides with phi_d; the slide is a cubic in t."""
    phi_s, phi_d, dip, k = 40.5, 31.6, 15.0, 2.0
    b, mu_d = np.radians(dip), np.tan(np.radians(phi_d))
    t = np.linspace(0, 4, 401)
    ref = sliding_block(lambda tt: (-k * tt, 0.0), t, np.tan(np.radians(phi_s)), mu_d, dip=dip)
    t_star = G * np.tan(np.radians(phi_s - dip)) / k
    assert ref.start_time() == pytest.approx(t_star, abs=1e-10)
    c0 = G * (np.sin(b) - mu_d * np.cos(b))
    c1 = k * (np.cos(b) + mu_d * np.sin(b))
    after = t > t_star
    ta = t[after]
    expect = (0.5 * c0 * (ta - t_star) ** 2
              + 0.5 * c1 * ((ta**3 - t_star**3) / 3 - t_star**2 * (ta - t_star)))
    np.testing.assert_allclose(ref.slip[after], expect, rtol=1e-9, atol=1e-14)
    np.testing.assert_array_equal(ref.slip[~after], 0.0)


def test_jumps_in_the_table_acceleration_are_honoured():
    """A step in a_x at t = 0.5 s given as a breakpoint: the slip is piecewise quadratic."""
    def accel(t):
        return (0.2 * G if t < 0.5 else 0.6 * G, 0.0)

    t = np.linspace(0, 1, 11)
    ref = sliding_block(accel, t, 0.3, breakpoints=[0.5])
    late = t >= 0.5
    np.testing.assert_array_equal(ref.slip[~late], 0.0)
    np.testing.assert_allclose(ref.slip[late], -0.5 * 0.3 * G * (t[late] - 0.5) ** 2,
                               rtol=1e-10, atol=1e-15)


def test_a_stuck_phase_reads_the_table_once_a_max_step():
    """The block's rest is not integrated: over 10 s of a gentle table the static strength is
    read every max_step (10,001 readings, an ODE solver's event search read it twice a step),
    and a crossing inside the phase is still found to round-off."""
    calls = []

    def gentle(t):
        calls.append(t)
        return (0.7 * G * np.sin(6 * t), 0.0)

    ref = sliding_block(gentle, np.linspace(0, 10, 11), mu_static=0.75, max_step=1e-3)
    assert ref.events == [] and len(calls) <= 10_001 + 5
    # the crossing: a_x = 0.8 g sin(6 t) passes mu g at t = asin(0.75 / 0.8) / 6
    ref = sliding_block(lambda t: (0.8 * G * np.sin(6 * t), 0.0), np.linspace(0, 0.3, 4), 0.75)
    assert ref.events[0][0] == pytest.approx(np.arcsin(0.75 / 0.8) / 6, abs=1e-13)


@pytest.mark.parametrize("kwargs, message", [
    ({"mu_dynamic": 0.5}, "mu_dynamic"), ({"dip": 95}, "dip"), ({"mu_static": -1}, "mu_static"),
])
def test_bad_arguments_are_named(kwargs, message):
    args = {"mu_static": 0.4} | kwargs
    with pytest.raises(ValueError, match=message):
        sliding_block(lambda t: (0.0, 0.0), np.linspace(0, 1, 3), **args)


def test_lift_off_is_refused():
    with pytest.raises(ValueError, match="lifts off"):
        sliding_block(lambda t: (0.0, -2 * G), np.linspace(0, 1, 3), 0.4)


# --- a rigid block rocking on a shaken base (housner_shaken) ----------------------------

def _pulse(peak, length=0.2):
    """A half-sine pulse of the base, then stillness."""
    return lambda t: (peak * np.sin(np.pi * t / length) if t < length else 0.0, 0.0)


def _swings(history, after):
    """Each free swing after ``after`` s (between two impacts): (peak |theta|, duration)."""
    t, th = history.time, history.rotation
    keep = t > after
    t, th = t[keep], th[keep]
    land = np.flatnonzero(np.abs(th) < 1e-9)
    out = []
    for a, b in zip(land[:-1], land[1:], strict=True):
        if b > a + 2:
            out.append((np.abs(th[a:b + 1]).max(), t[b] - t[a]))
    return out


def test_a_block_stands_until_the_base_exceeds_g_tan_alpha_and_then_leans_away_from_it():
    from dda.studies.references import housner_shaken

    a = G * 0.15 / 0.45
    assert housner_shaken(0.15, 0.45, lambda t: (0.99 * a, 0.0), 1.0).peak == 0.0
    pushed = housner_shaken(0.15, 0.45, _pulse(1.2 * a), 0.4)
    # a base accelerating to +x throws the block's top back (-x): it pivots on its left
    # corner, counterclockwise, as a DDA block's rotation counts
    assert pushed.peak > 0.0 and pushed.rotation.max() == pushed.peak
    assert housner_shaken(0.15, 0.45, _pulse(-1.2 * a), 0.4).rotation.min() < 0.0


def test_free_swings_after_a_pulse_lose_housners_share_at_each_impact():
    """Between impacts no energy is lost; each impact keeps r^2 of it: the next swing's peak
    is what :func:`housner_rocking` gives from this one's."""
    from dda.studies.references import housner_rocking, housner_shaken

    h = housner_shaken(0.15, 0.45, _pulse(6.0), 3.0)
    swings = _swings(h, 0.2)
    assert len(swings) >= 5
    for (peak, _), (after, _) in zip(swings[:4], swings[1:5], strict=True):
        # the peaks are the integrator's samples (max_step 1 ms): 1e-5 of the angle below
        assert after == pytest.approx(housner_rocking(0.15, 0.45, peak, 1)[1], rel=2e-4)
    lossless = _swings(housner_shaken(0.15, 0.45, _pulse(6.0), 3.0, restitution=1.0), 0.2)
    peaks = [p for p, _ in lossless]
    assert np.ptp(peaks) < 2e-4 * peaks[0]


def test_a_slender_blocks_swing_lasts_housners_time():
    """For a slender block (alpha 1.1 degrees) the swing between two impacts with peak theta
    lasts 2 / p arccosh(1 / (1 - theta / alpha)), p^2 = 3 g / (4 R) (Housner 1963,
    linearized: exact to about alpha^2)."""
    from dda.studies.references import housner_shaken

    w, h = 0.02, 1.0
    alpha, p = np.arctan(w / h), np.sqrt(3 * G / (2 * np.hypot(w, h)))
    swings = _swings(housner_shaken(w, h, _pulse(1.5 * G * w / h, 0.1), 4.0), 0.1)
    assert len(swings) >= 3
    for peak, length in swings[:3]:
        assert length == pytest.approx(2 / p * np.arccosh(1 / (1 - peak / alpha)), rel=1e-3)


def test_a_strong_enough_shaking_topples_the_block():
    from dda.studies.cases import ramped_sine
    from dda.studies.references import housner_shaken

    assert housner_shaken(0.15, 0.45, lambda t: (2 * G, 0.0), 1.0).toppled
    assert not housner_shaken(0.15, 0.45, ramped_sine(3, 700, stop=2.0), 3.0).toppled
    assert housner_shaken(0.15, 0.45, ramped_sine(3, 1300, stop=2.0), 3.0).toppled


def test_housner_shaken_refuses_a_restitution_outside_0_to_1():
    from dda.studies.references import housner_shaken

    with pytest.raises(ValueError, match="restitution must be between 0 and 1"):
        housner_shaken(0.15, 0.45, lambda t: (0.0, 0.0), 1.0, restitution=1.5)
