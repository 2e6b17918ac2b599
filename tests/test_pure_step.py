"""The pure step: step(model, state, dt, solver) changes none of its inputs, so a refused step
costs nothing to undo; the shaking integrator is part of the state; StepControl's rules."""

import copy
import dataclasses

import numpy as np
import pytest

import dda
from dda.model import Model
from dda.solvers import LegacyPullBack, NewtonRaphson
from dda.step import StepSettings, StepState, step
from dda.step_control import StepControl
from tests.conftest import shaken_block_scene


def _snapshot(obj):
    """Every array reachable from a dataclass or plain object, copied (for comparison)."""
    return copy.deepcopy({k: v for k, v in vars(obj).items() if k != "scene"})


def _same(a, b, path="") -> None:
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            _same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _same(x, y, f"{path}[{i}]")
    elif isinstance(a, np.ndarray):
        np.testing.assert_array_equal(a, b, err_msg=path)
    elif dataclasses.is_dataclass(a):
        _same(vars(a), vars(b), path)
    elif isinstance(a, float | int | bool | str | type(None)):
        assert a == b, path


def _shaken_state(solver, steps=30):
    """The shaken block after ``steps`` steps: sliding, contacts closed, integrator advanced."""
    scene, table, top = shaken_block_scene(phi=20, amplitude=6.0)
    sim = dda.Simulation(scene, dt=1e-3, solver=solver)
    sim.run(steps * 1e-3)
    return sim


@pytest.mark.parametrize("solver", [NewtonRaphson(), LegacyPullBack()], ids=repr)
def test_a_step_changes_none_of_its_inputs(solver):
    sim = _shaken_state(solver)
    model, state = sim.model, sim.committed
    assert len(state.contacts) and state.shaking[0][0] > 0.0  # a state with history
    before_model, before_state = _snapshot(model), copy.deepcopy(state)
    trial, report = step(model, state, 1e-3, solver)
    assert report.converged and trial.time == pytest.approx(state.time + 1e-3)
    _same(_snapshot(model), before_model)
    _same(vars(state), vars(before_state))
    # the same step again gives the same trial, to the bit: nothing carried over
    again, _ = step(model, state, 1e-3, solver)
    _same(vars(again), vars(trial))
    # a refused step (the guard set so tight that it refuses) changes nothing either
    tight = StepSettings(max_displacement_ratio=1e-12)
    refused, report = step(model, state, 1e-3, solver, tight)
    assert refused is None and not report.converged and "max_displacement_ratio" in report.reason
    _same(vars(state), vars(before_state))


def test_the_shaking_integrator_lives_in_the_state():
    """A callable shaking is integrated from the state's integrator: stepping from the same
    state twice, or after a refused step, gives the same known motion."""
    scene, table, top = shaken_block_scene(phi=20, amplitude=6.0)
    model = Model(scene)
    state = StepState.initial(model)
    assert state.shaking == ((0.0, pytest.approx(np.zeros(2)), pytest.approx(np.zeros(2))),)
    first, _ = step(model, state, 1e-3, NewtonRaphson())
    assert first.shaking[0][0] == pytest.approx(1e-3)
    # u = -A/(2 pi f)^2 sin + A t/(2 pi f) for a = A sin(2 pi f t) from rest
    w = 2 * np.pi * 2.0
    t = 1e-3
    assert first.known_u[table.index, 0] == pytest.approx(6.0 * (t / w - np.sin(w * t) / w**2),
                                                           rel=1e-9)
    second, _ = step(model, state, 1e-3, NewtonRaphson())
    np.testing.assert_array_equal(second.known_u, first.known_u)


def test_simulation_commits_only_what_step_returns():
    """Simulation.run is step after step: the same numbers as calling step by hand (the run
    takes its last step up to t_end, which round-off makes differ from 1e-3 by 1e-18 s)."""
    scene, table, top = shaken_block_scene(phi=20, amplitude=6.0)
    sim = dda.Simulation(scene, dt=1e-3)
    sim.run(0.02)
    model = Model(scene)
    state = StepState.initial(model)
    for _ in range(20):
        state, report = step(model, state, 1e-3, NewtonRaphson())
        assert report.converged
    np.testing.assert_allclose(state.x, sim.committed.x, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(state.velocity, sim.committed.velocity, rtol=1e-9, atol=1e-12)


def test_step_control_cuts_widens_and_grows_back():
    control = StepControl(dt=1e-3)
    assert control.step_size(1.0) == 1e-3
    assert control.step_size(1e-3 + 1e-10) == pytest.approx(1e-3 + 1e-10)  # no sliver left
    # a step that moved farther than predicted is searched wider, at most max_widenings times
    assert control.widen(0.01, widened=0) and control.search_hint == 0.01
    assert not control.widen(0.01, widened=0)  # no wider than before: cut instead
    assert not control.widen(0.02, widened=control.max_widenings)
    control.cut(1e-3, "OPEN-CLOSE did not settle in 12 passes")
    control.cut(5e-4, "a vertex moved 1 m")
    assert control.dt_now == 2.5e-4 and control.contact_cuts == 1
    for _ in range(control.grow_after - 1):
        control.accepted()
    assert control.dt_now == 2.5e-4 and control.search_hint == 0.0
    control.accepted()
    assert control.dt_now == 5e-4
    for _ in range(3 * control.grow_after):
        control.accepted()
    assert control.dt_now == 1e-3  # never above the size asked for


def test_run_tells_a_callback_every_committed_step():
    scene, table, top = shaken_block_scene(phi=20, amplitude=6.0)
    seen = []
    result = dda.Simulation(scene, dt=1e-3).run(
        0.01, callback=lambda state, report: seen.append((state.time, report.converged)))
    assert [t for t, _ in seen] == pytest.approx(list(result.time[1:]))
    assert all(ok for _, ok in seen)


def test_a_hard_step_below_a_failed_try_grows_back_at_once_and_keeps_the_wait():
    """The control remembers the size whose try failed: a step cut at the working size grows
    back to it after grow_after steps (not the long wait), and holding there neither resets the
    wait nor brings the next try at the failed size early."""
    control = StepControl(dt=1e-3)
    g = control.grow_after
    control.cut(1e-3, "OPEN-CLOSE did not settle in 30 passes")  # works at 5e-4
    for _ in range(3):  # tries at 1e-3 fail: the wait grows to 8 g
        while control.dt_now == 5e-4:
            control.accepted()
        control.cut(control.dt_now, "OPEN-CLOSE did not settle in 30 passes")
    assert control.ceiling == 1e-3 and control._wait() == 8 * g
    for _ in range(10):
        control.accepted()
    control.cut(5e-4, "OPEN-CLOSE did not settle in 30 passes")  # a hard step at 5e-4
    steps = 0
    while control.dt_now == 2.5e-4:
        control.accepted()
        steps += 1
    assert steps == g  # back at the working size after grow_after steps
    for _ in range(g):  # ... and it holds there
        control.accepted()
    assert not control.probing and control.ceiling == 1e-3 and control._wait() == 8 * g
    steps = 0
    while control.dt_now == 5e-4:
        control.accepted()
        steps += 1
    assert steps == 8 * g - g  # the next try at 1e-3 waits out the long wait
    # a try at the failed size that holds forgets it
    for _ in range(g):
        control.accepted()
    assert control.ceiling == 0.0 and control._wait() == g


def test_a_doubled_step_size_that_fails_at_once_waits_longer_before_the_next_try():
    """Where the contacts cannot settle at twice the working step size, every try costs a
    failed step: the wait before the next try doubles (up to max_wait) and resets once a
    doubled size holds for grow_after steps."""
    control = StepControl(dt=1e-3)
    g = control.grow_after
    control.cut(1e-3, "OPEN-CLOSE did not settle in 30 passes")
    waits = []
    for _ in range(4):  # grow back, fail at once, again and again
        steps = 0
        while control.dt_now == 5e-4:
            control.accepted()
            steps += 1
        waits.append(steps)
        control.cut(control.dt_now, "OPEN-CLOSE did not settle in 30 passes")
    assert waits == [g, 2 * g, 4 * g, 8 * g]
    # the doubled size holds for grow_after steps: the wait is back to grow_after
    for _ in range(16 * g):
        control.accepted()
    assert control.dt_now == 1e-3 and control.probing
    for _ in range(g):
        control.accepted()
    assert not control.probing and control._wait() == g
    control.cut(1e-3, "OPEN-CLOSE did not settle in 30 passes")
    for _ in range(g):
        control.accepted()
    assert control.dt_now == 1e-3
    # the wait never grows beyond max_wait
    control = StepControl(dt=1e-3, max_wait=3 * g)
    control.cut(1e-3, "OPEN-CLOSE did not settle in 30 passes")
    for _ in range(6):
        while control.dt_now == 5e-4:
            control.accepted()
        control.cut(control.dt_now, "OPEN-CLOSE did not settle in 30 passes")
    assert control._wait() == 3 * g
    # a block that moved too far does not make the wait longer: it slows down
    control = StepControl(dt=1e-3)
    control.cut(1e-3, "OPEN-CLOSE did not settle in 30 passes")
    for _ in range(3):
        while control.dt_now == 5e-4:
            control.accepted()
        control.cut(control.dt_now, "a vertex of 'shot' moved 1 m")
    assert control._wait() == g
