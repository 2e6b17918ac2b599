"""The scene format's sine starts at rest and shakes about a fixed place; the plain sine drifts
at A / (2 pi f). Both are integrated exactly across their kinks (the breakpoints)."""

import math

import numpy as np
import pytest

from dda.effects import AccelerationHistory
from dda.io.scene_data import ArrayStore, SceneDataError, scene_from_data, scene_to_data
from dda.io.scene_file import SceneFileError, SineAcceleration, load_scene
from tests.test_scene_file import FULL, write

A, F, START = 6.87, 2.0, 0.1  # the demo's table: 0.7 g at 2 Hz after 0.1 s
W = 2 * math.pi * F
T = 1 / F


def exact(tau):
    """Velocity and displacement of the from-rest form (METHOD: SineAcceleration's docstring),
    ``tau`` the time since the start."""
    tau = np.asarray(tau, dtype=float)
    half = tau < T / 2
    v = np.where(half, A / (2 * W) * (1 - np.cos(W * tau)), -A / W * np.cos(W * tau))
    u = np.where(half, A / (2 * W) * (tau - np.sin(W * tau) / W),
                 math.pi * A / (2 * W**2) - A / W**2 * np.sin(W * tau))
    return np.where(tau < 0, 0.0, v), np.where(tau < 0, 0.0, u)


def history_at(f, times):
    """(n, 2) displacement and velocity of ``f`` at increasing ``times`` (one step each)."""
    hist = AccelerationHistory(f)
    out = [hist.state(t) for t in times]
    return np.array([u for u, _ in out]), np.array([v for _, v in out])


def test_it_starts_at_rest_with_continuous_acceleration():
    sine = SineAcceleration(A, F, start=START)
    assert sine(0.0) == (0.0, 0.0) and sine(START) == (0.0, 0.0)
    # continuous at the switch to the full amplitude (both sides are zero there)
    eps = 1e-9
    left, right = sine(START + T / 2 - eps)[0], sine(START + T / 2 + eps)[0]
    assert abs(left) < 1e-6 and abs(right) < 1e-6
    assert sine(START + T / 4)[0] == pytest.approx(A / 2)    # half amplitude first
    assert sine(START + 3 * T / 4)[0] == pytest.approx(-A)   # then the full one
    u, v = AccelerationHistory(sine).state(START)
    assert np.all(u == 0.0) and np.all(v == 0.0)


@pytest.mark.parametrize("dt", [1e-3, 2e-3, 3e-3])
def test_the_history_integrates_it_exactly_across_its_kinks(dt):
    """Steps that straddle start and start + T/2: exact to round-off with the breakpoints.
    Without them (the same function as a plain lambda) the kink costs a velocity error of
    order (A omega / 2) dt^2, kept for ever: 1.4e-7 m/s at dt 1e-3, 5.4e-7 at 2e-3 (small, but
    not round-off: this test fails on it)."""
    t = np.arange(1, int(round(3.0 / dt)) + 1) * dt + 0.37 * dt  # steps never on the kinks
    sine = SineAcceleration(A, F, start=START)
    u, v = history_at(sine, t)
    ve, ue = exact(t - START)
    assert np.abs(v[:, 0] - ve).max() < 1e-12
    assert np.abs(u[:, 0] - ue).max() < 1e-12
    u2, v2 = history_at(lambda s: sine(s), t)
    assert np.abs(v2[:, 0] - ve).max() > 1e-8  # the kink inside a step, not split


def test_zero_mean_velocity_and_bounded_displacement_over_100_periods():
    sine = SineAcceleration(A, F, start=START)
    after = START + T / 2
    periods = np.arange(101)
    t = np.concatenate([np.linspace(0.0, after, 7)[1:], after + T * (periods[1:, None] - 1
                        + np.linspace(0, 1, 41)[None, 1:]).ravel()])
    u, v = history_at(sine, t)
    on_period = np.isclose((t - after) / T, np.round((t - after) / T), atol=1e-12) & (t > after)
    u_p = u[on_period, 0]
    assert len(u_p) == 100
    # the mean velocity over every whole period after the half wave: (u(t+kT) - u(t)) / kT
    mean_v = (u_p[1:] - u_p[0]) / (T * np.arange(1, 100))
    assert np.abs(mean_v).max() < 1e-12
    # bounded: about pi A / (2 w^2), amplitude A / w^2, at every step of 100 periods
    centre, amp = math.pi * A / (2 * W**2), A / W**2
    assert np.abs(u[t >= after, 0] - centre).max() <= amp * (1 + 1e-9)
    assert np.abs(u[:, 0]).max() <= (centre + amp) * (1 + 1e-9)
    assert u[-1, 0] == pytest.approx(exact(t[-1] - START)[1], abs=1e-10)
    # the plain sine drifts at A / w: 100 periods, 27 m away
    plain = SineAcceleration(A, F, start=START, form="sine")
    assert plain.drift == pytest.approx(A / W) and sine.drift == 0.0
    up, _ = history_at(plain, t)
    drift = (up[on_period, 0][-1] - up[on_period, 0][0]) / (99 * T)
    assert drift == pytest.approx(A / W, rel=1e-12)
    assert up[-1, 0] > 27.0


def test_scene_file_default_is_from_rest_and_sine_is_an_option(tmp_path):
    loaded = load_scene(write(tmp_path, FULL))
    f = loaded.scene.shakes[0].history.function
    assert f == SineAcceleration(2.0, 2.0, 0.01, (1.0, 0.0), "from_rest")
    plain = FULL.replace("start = 0.01 }", 'start = 0.01, form = "sine" }')
    f = load_scene(write(tmp_path, plain, "plain.toml")).scene.shakes[0].history.function
    assert f.form == "sine"
    bad = FULL.replace("start = 0.01 }", 'start = 0.01, form = "cosine" }')
    with pytest.raises(SceneFileError, match=r"shake\[0\].sine.form: must be "
                                             r"'from_rest' or 'sine'") as info:
        load_scene(write(tmp_path, bad, "bad.toml"))
    line = int(str(info.value).split(", line ")[1].split(",")[0])
    assert 'form = "cosine"' in (tmp_path / "bad.toml").read_text().splitlines()[line - 1]
    with pytest.raises(ValueError, match="form must be"):
        SineAcceleration(1.0, 1.0, form="cos")


def test_checkpoint_data_keeps_the_form_and_old_data_reads_as_the_plain_sine(tmp_path):
    loaded = load_scene(write(tmp_path, FULL.replace("start = 0.01 }",
                                                     'start = 0.01, form = "sine" }')))
    for form in ("sine", "from_rest"):
        scene = loaded.scene
        scene._shakes[0] = type(scene._shakes[0])(
            0, AccelerationHistory(SineAcceleration(2.0, 2.0, 0.01, form=form)))
        store = ArrayStore()
        data = scene_to_data(scene, store)
        assert data["shakes"][0]["acceleration"]["sine"]["form"] == form
        back = scene_from_data(data, ArrayStore(store.arrays))
        assert back.shakes[0].history.function.form == form
    del data["shakes"][0]["acceleration"]["sine"]["form"]  # a checkpoint from before
    back = scene_from_data(data, ArrayStore(store.arrays))
    assert back.shakes[0].history.function.form == "sine"
    data["shakes"][0]["acceleration"]["sine"]["form"] = "cosine"
    with pytest.raises(SceneDataError, match="form"):
        scene_from_data(data, ArrayStore(store.arrays))
