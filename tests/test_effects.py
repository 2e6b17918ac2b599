"""Shaking, prescribed motion and point loads."""

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.effects import AccelerationHistory
from dda.materials import LinearElastic
from tests.conftest import box, shaken_block_scene

ROCK = LinearElastic(young=1e9, poisson=0.2, density=2000.0)


def test_callable_shake_integrates_a_sine_exactly():
    w = 4 * np.pi
    hist = AccelerationHistory(lambda t: (9.81 * np.sin(w * t), 0.0))
    for t in np.arange(0.01, 1.0, 0.01):
        u, v = hist.state(t)
    # from rest: v = a/w (1 - cos wt), u = a/w (t - sin(wt)/w)
    assert v[0] == pytest.approx(9.81 / w * (1 - np.cos(w * t)), rel=1e-10, abs=1e-12)
    assert u[0] == pytest.approx(9.81 / w * (t - np.sin(w * t) / w), rel=1e-10)


def test_recorded_shake_is_exact_for_piecewise_linear():
    times = np.array([0.0, 1.0, 2.0])
    hist = AccelerationHistory(np.array([0.0, 2.0, 2.0]), times)
    u, v = hist.state(2.0)
    # a = 2t on [0, 1] then 2: v(1) = 1, u(1) = 1/3; v(2) = 3, u(2) = 1/3 + 1 + 1 = 7/3
    assert v[0] == pytest.approx(3.0, rel=1e-14)
    assert u[0] == pytest.approx(7.0 / 3.0, rel=1e-14)
    assert hist.state(0.5)[0][0] == pytest.approx(0.5**3 / 3, rel=1e-14)


def test_a_record_whose_first_sample_is_at_its_step_ramps_from_rest():
    """Up to its first spacing late, a record ramps from zero at t = 0: a = 2 t here."""
    hist = AccelerationHistory(np.array([0.2, 0.4, 0.4]), np.array([0.1, 0.2, 0.3]))
    u, v = hist.state(0.2)
    assert v[0] == pytest.approx(0.2**2, rel=1e-14)
    assert u[0] == pytest.approx(0.2**3 / 3, rel=1e-14)


@pytest.mark.parametrize("start", [0.2, 10.0])
def test_a_record_that_starts_late_is_refused(start):
    """A record in absolute times (10 s in) was accepted and ramped over its whole offset:
    a base under a constant 3 m/s^2 from t = 0.2 s moved 2.5 mm by t = 0.1 s."""
    times = start + np.arange(0.0, 2.0, 0.01)
    with pytest.raises(ValueError, match=rf"starts at t = {start:g} s.*shift its times"):
        AccelerationHistory(np.full(len(times), 3.0), times, name="shake of block 'base'")
    scene = dda.Scene(gravity=9.81)
    base = scene.add_block(box(0, -0.2, 1, 0.2), ROCK, fixed=True, name="base")
    with pytest.raises(ValueError, match="shake.*starts at"):
        scene.shake(base, acceleration=np.full(len(times), 3.0), times=times)


def _kinked(t):
    """A wave with a kink and a jump at its breakpoints, and a quadratic y."""
    level = 1.0 if t < 0.0105 else 2.0
    return (level * np.cos(7.0 * t) + max(0.0, t - 0.031), 0.3 * t * t)


_kinked.breakpoints = [0.0105, 0.031, 0.04]


@pytest.mark.parametrize("history", [
    AccelerationHistory(_kinked),
    AccelerationHistory(np.array([0.0, 0.3, -0.2, 0.5]), np.array([0.0, 0.013, 0.02, 0.05])),
], ids=["callable with breakpoints", "record"])
def test_a_batch_of_steps_integrates_as_its_steps_one_by_one(history):
    # (dda.compiled_run works the shaking out for a batch of steps at once: the same bits as
    # dda.step.step's advance, step by step, also across breakpoints and a break that falls
    # on a step's end)
    dt = 1e-3
    times = []
    t, state, u1, v1, states1 = 0.0, history.initial(), [], [], []
    for _ in range(45):
        t = t + dt
        times.append(t)
        u, v, state = history.advance(state, t)
        u1.append(u)
        v1.append(v)
        states1.append(state)
    for first in (0, 10, 31):  # from rest, and from a state inside the run
        start = history.initial() if first == 0 else states1[first - 1]
        u, v, states = history.advance_many(start, np.array(times[first:]))
        assert np.array_equal(u, np.array(u1[first:]))
        assert np.array_equal(v, np.array(v1[first:]))
        for k in (0, 12, len(times) - first - 1):
            if states1[first + k] is None:
                assert states[k] is None
            else:
                assert all(np.array_equal(a, b) for a, b in zip(states[k], states1[first + k],
                                                                 strict=True))


def test_a_batch_of_steps_reaches_the_exact_integrals_of_a_polynomial():
    # 5-point Gauss-Legendre is exact to degree 9: a = t^3 gives v = t^4 / 4, u = t^5 / 20
    history = AccelerationHistory(lambda t: (t**3, 1.0))
    u, v, _ = history.advance_many(history.initial(), np.linspace(0.1, 1.0, 10))
    assert v[:, 0] == pytest.approx(np.linspace(0.1, 1.0, 10) ** 4 / 4, rel=1e-14, abs=1e-16)
    assert u[:, 0] == pytest.approx(np.linspace(0.1, 1.0, 10) ** 5 / 20, rel=1e-14, abs=1e-17)
    assert u[-1, 1] == pytest.approx(0.5, rel=1e-15)
    with pytest.raises(ValueError, match="advance_many needs times after"):
        history.advance_many((0.5, np.zeros(2), np.zeros(2)), np.array([0.4, 0.6]))


def test_shaken_block_follows_its_history_and_carries_a_stuck_block():
    amp, f = 1.0, 2.0  # 0.1 g: far below tan(45) g, so the top block sticks
    scene, table, top = shaken_block_scene(phi=45, amplitude=amp, freq=f)
    result = dda.Simulation(scene, dt=1e-3).run(duration=1.0)
    w = 2 * np.pi * f
    t = result.time
    expected = amp / w * (t - np.sin(w * t) / w)
    np.testing.assert_allclose(result.displacement(table)[:, 0], expected, atol=1e-12)
    np.testing.assert_allclose(result.displacement(top)[:, 0], expected, atol=2e-5)


def test_full_prescribed_motion_moves_every_vertex():
    scene = dda.Scene()
    b = scene.add_block(box(0, 0, 1, 1), ROCK)
    scene.prescribe_motion(b, displacement=lambda t: (0.1 * t, -0.05 * t * t))
    result = dda.Simulation(scene, dt=0.01).run(duration=1.0)
    np.testing.assert_allclose(result.displacement(b)[-1], [0.1, -0.05], rtol=1e-12)


def test_partial_prescribed_motion_leaves_the_other_direction_free():
    scene = dda.Scene(gravity=9.81)
    b = scene.add_block(box(0, 0, 1, 1), ROCK)
    scene.prescribe_motion(b, displacement=lambda t: (0.2 * t, None))
    result = dda.Simulation(scene, dt=1e-3).run(duration=0.5)
    d = result.displacement(b)[-1]
    assert d[0] == pytest.approx(0.1, rel=1e-4)  # held by penalty springs
    assert d[1] == pytest.approx(-9.81 * 0.5**2 / 2, rel=1e-4)  # falls freely


@pytest.mark.parametrize("constant", [True, False])
def test_point_load_accelerates_a_free_block(constant):
    scene = dda.Scene()
    b = scene.add_block(box(0, 0, 1, 0.5), ROCK)
    fx = 1e3
    force = (fx, 0.0) if constant else (lambda t: (fx, 0.0))
    scene.add_point_load(b, point=(0.5, 0.25), force=force)  # at the centroid: no spin
    result = dda.Simulation(scene, dt=1e-3).run(duration=0.5)
    mass = ROCK.density * 0.5
    assert result.displacement(b)[-1, 0] == pytest.approx(fx / mass * 0.5**2 / 2, rel=1e-9)
    assert abs(result.rotation(b)[-1]) < 1e-12


def _spin_under_ramp_couple(dt):
    scene = dda.Scene()
    b = scene.add_block(box(-0.5, -0.5, 1, 1), ROCK)
    # two opposite forces at the top and bottom faces: a couple of 100 t N m per m
    scene.add_point_load(b, point=(0.0, 0.5), force=lambda t: (-100.0 * t, 0.0))
    scene.add_point_load(b, point=(0.0, -0.5), force=lambda t: (100.0 * t, 0.0))
    return dda.Simulation(scene, dt=dt).run(duration=0.2).rotation(b)[-1]


def test_a_point_load_outside_its_block_is_refused():
    scene = dda.Scene(gravity=9.81)
    base = scene.add_block(box(0, -0.2, 1, 0.2), ROCK, fixed=True, name="base")
    top = scene.add_block(box(0.4, 0.0, 0.2, 0.2), ROCK, name="top")
    with pytest.raises(ValueError, match=r"point load on block 'top': point \(5, 5\) is "
                                         r"outside block 'top', 6\.\d+ m from it"):
        scene.add_point_load(top, point=(5.0, 5.0), force=(0.0, -1.0))
    scene.add_point_load(top, point=(0.6, 0.1), force=(0.0, -1.0))  # on its boundary
    with pytest.warns(dda.PlausibilityWarning, match="block 'base': the block is fixed"):
        scene.add_point_load(base, point=(0.5, -0.1), force=(0.0, -1.0))


def test_a_fixed_blocks_initial_velocity_is_ignored_with_a_warning():
    scene = dda.Scene(gravity=None)
    with pytest.warns(dda.PlausibilityWarning, match="fixed, so its initial velocity"):
        wall = scene.add_block(box(0, 0, 1, 1), ROCK, fixed=True, velocity=(1.0, 0.0))
    scene.add_block(box(3, 0, 1, 1), ROCK, velocity=(1.0, 0.0))
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=30.0)))
    result = dda.Simulation(scene, dt=1e-2).run(0.1, progress=False)
    assert np.all(result.displacement(wall) == 0.0)


def test_time_dependent_point_load_spins_a_block_at_first_order():
    """gamma = 1 Newmark is first-order for a varying load: the error halves with dt."""
    inertia = ROCK.density * (1.0 / 12 + 1.0 / 12)
    exact = 50 * 0.2**3 / (3 * inertia)  # torque 100 t: r = 50 t^3 / (3 I)
    errors = [abs(_spin_under_ramp_couple(dt) - exact) for dt in (4e-3, 2e-3, 1e-3)]
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    np.testing.assert_allclose(rates, 1.0, atol=0.1)
    assert errors[-1] / exact < 0.01


def test_progress_bar_reports_on_stderr(capsys):
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 1, 1), ROCK)
    dda.Simulation(scene, dt=1e-2).run(duration=0.5, progress=True)
    err = capsys.readouterr().err
    # the simulated time, the share, and what tells a slow run from a stalled one: dt, the
    # cuts, the passes a step (issue 22)
    assert "0.5000/0.5000 s" in err and "100%" in err, err
    assert "dt 0.01 s, 0 cut, 1.0 passes/step" in err, err


@pytest.mark.parametrize(("value", "message"), [
    ((1.0, 2.0, 3.0), "must return two numbers"), (None, "must return two numbers"),
    ("ab", "must return two numbers"), ((np.nan, 0.0), "not finite"),
    ((0.0, np.inf), "not finite")])
def test_a_shake_function_that_returns_no_acceleration_is_named(value, message):
    """A shaking function must give (x, y) numbers at every time it is asked for; anything
    else is refused with the effect's name and what it returned."""
    bad_from = 0.05

    def accel(t):
        return value if t >= bad_from else (0.0, 0.0)

    hist = AccelerationHistory(accel, name="table shake")
    with pytest.raises(ValueError, match=f"table shake: acceleration.*{message}"):
        hist.advance(hist.initial(), 0.1)


def test_a_load_that_turns_nan_mid_run_names_the_time():
    scene = dda.Scene(gravity=None)
    block = scene.add_block(box(0, 0, 1, 1), ROCK, name="block")
    scene.add_point_load(block, point=(0.5, 0.5),
                         force=lambda t: (np.nan, 0.0) if t > 0.05 else (1.0, 0.0))
    with pytest.raises(ValueError, match=r"point load on block 'block': force\(t\) at "
                                         r"t = 0\.06 s returned a value that is not finite"):
        dda.Simulation(scene, dt=1e-2).run(0.1, progress=False)
