"""A small scene's OPEN-CLOSE iteration in one kernel call (dda.kernels.dense_passes) against
the composed compiled passes: the same decisions, the same numbers to round-off."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial, StaticDynamicTransition
from dda.solvers import legacy, open_close
from tests.conftest import incline_scene, stack_scene
from tests.stability import scenes as S
from tests.test_open_close_kernel import CASES as KERNEL_CASES


def _without_dashpot():
    scene, dt = S.incline(CoulombSingle(phi=20.0))[:2]
    scene.set_joint(JointMaterial(1e10, 1e10, CoulombSingle(phi=20.0), restitution=1.0))
    return scene, dt, 0.2


def _rigid():
    return incline_scene(25.0, rigid=True)[0], 1e-3, 0.3


CASES = {
    "incline, impact dashpot": lambda: S.incline(CoulombSingle(phi=20.0))[:2] + (0.2,),
    "incline, no dashpot": _without_dashpot,
    "transition by contact": lambda: S.incline(
        StaticDynamicTransition(35.0, 20.0, onset="contact"))[:2] + (0.2,),
    "resting on faces": lambda: S.incline(StaticDynamicTransition(25.0, 20.0), kick=0.0,
                                          slope=24.0)[:2] + (0.2,),
    "rigid block (fewer unknowns)": _rigid,
    "two laws": KERNEL_CASES["two laws"],  # Coulomb with cohesion below, faces above
    "3 x 3 stack": lambda: (stack_scene(3), 1e-3, 0.05),
    "tower": lambda: S.tower(6)[:2] + (0.05,),
}


def _run(case, solver, dense, monkeypatch):
    monkeypatch.setattr(open_close, "DENSE_PASSES", dense)
    scene, dt, duration = CASES[case]()
    sim = dda.Simulation(scene, dt=dt, solver=solver())
    result = sim.run(duration, progress=False)
    return sim.state, result.stats, dt


@pytest.mark.parametrize("solver", [dda.solvers.LegacyPullBack, dda.solvers.NewtonRaphson])
@pytest.mark.parametrize("case", CASES)
def test_one_kernel_takes_the_composed_passes_decisions(case, solver, monkeypatch):
    (a, sa, dt), (b, sb, _) = (_run(case, solver, dense, monkeypatch)
                               for dense in (False, True))
    assert np.count_nonzero(sa["closed"]) > 0
    assert_close_runs(a, sa, b, sb, dt)


def assert_close_runs(a, sa, b, sb, dt):
    """Two runs took the same decisions (passes, contact states, sliding flags, steps) and
    their numbers agree to round-off (the steps' times too): positions and history lengths
    to 1e-11 of the scene's size, velocities to that over dt (a velocity is 2 d / dt less the
    last one), forces to 1e-8 of the largest. Newton may stop one iteration earlier or later
    where a residual is at the round-off floor of its convergence test: iterations and solves
    within 2 a run."""
    for name in ("open_close_passes", "closed", "sliding"):
        np.testing.assert_array_equal(sa[name], sb[name], err_msg=name)
    # the same steps: a step ended at a slip reversal (dda.slip_events) ends where the
    # trial's slip velocities put it, to their round-off (the 3 x 3 stack's reversals: slip
    # velocities of 1e-5 m/s, its step ends 2e-11 of them apart)
    np.testing.assert_allclose(sa["time"], sb["time"], rtol=1e-9, atol=0.0, err_msg="time")
    for name in ("iterations", "solves"):
        assert abs(int(np.sum(sa[name])) - int(np.sum(sb[name]))) <= 2, name
    size = np.ptp(a.x, axis=0).max()
    np.testing.assert_allclose(b.x, a.x, rtol=0.0, atol=1e-11 * size)
    np.testing.assert_allclose(b.velocity, a.velocity, rtol=0.0, atol=1e-9 * size / dt)
    for name in ("t_n", "t_s"):
        x, y = getattr(a.contacts, name), getattr(b.contacts, name)
        np.testing.assert_allclose(y, x, rtol=0.0, atol=1e-8 * np.abs(a.contacts.t_n).max())
    for name in a.contacts.history:  # lengths (the elastic shear gap, the slip) and flags
        x, y = a.contacts.history[name], b.contacts.history[name]
        np.testing.assert_allclose(y, x, rtol=0.0, atol=1e-11 * size, err_msg=name)


def test_the_kernel_ran_and_its_numbers_are_not_the_composed_bits(monkeypatch):
    """The comparison above is not of one path with itself: the kernel's sums differ from
    numpy's in the last bits somewhere in a run."""
    (a, _, _), (b, _, _) = (_run("two laws", dda.solvers.LegacyPullBack, dense, monkeypatch)
                      for dense in (False, True))
    assert not (np.array_equal(a.x, b.x) and np.array_equal(a.velocity, b.velocity)
                and np.array_equal(a.contacts.t_n, b.contacts.t_n))


def _captured_problem(monkeypatch):
    """The StepProblem of the 3 x 3 stack's first step (without the shear dashpot, whose
    stiffness leaves the broken systems below nearly singular instead of singular, a case the
    two paths' solvers tell apart at different passes)."""
    problems = []
    solver = dda.solvers.LegacyPullBack()
    original = solver.solve_step

    def capture(problem):
        problems.append(problem)
        return original(problem)

    monkeypatch.setattr(solver, "solve_step", capture)
    dda.Simulation(stack_scene(3, shear_dashpot=False), dt=1e-3,
                   solver=solver).run(1e-3, progress=False)
    return problems[0]


@pytest.mark.parametrize("broken, reason", [
    (lambda p: replace(p, block_k=np.zeros_like(p.block_k)), "singular system: "),
    # numpy's solve calls NaN loads a singular matrix, numba's finds no finite solution
    (lambda p: replace(p, block_f=np.full_like(p.block_f, np.nan)), "singular system: ")])
def test_a_singular_pass_is_reported_alike(broken, reason, monkeypatch):
    """A system without the blocks' inertia and stiffness (the open contacts hold nothing)
    is singular, one with non-finite loads has no finite solution: both paths say so after
    the same pass."""
    problem = broken(_captured_problem(monkeypatch))
    out = []
    for dense in (False, True):
        monkeypatch.setattr(open_close, "DENSE_PASSES", dense)
        out.append(open_close.open_close(replace(problem), explicit=True))
    for oc in out:
        assert not oc.converged and oc.reason.startswith(reason), oc.reason
    assert out[0].passes == out[1].passes


def _run_legacy(case, fused, monkeypatch):
    monkeypatch.setattr(legacy, "LEGACY_DENSE_STEP", fused)
    scene, dt, duration = CASES[case]()
    sim = dda.Simulation(scene, dt=dt, solver=dda.solvers.LegacyPullBack())
    result = sim.run(duration, progress=False)
    return sim.state, result.stats


@pytest.mark.parametrize("case", CASES)
def test_legacy_step_in_one_call_gives_the_passes_kernels_bits(case, monkeypatch):
    """Legacy DDA's pull-back, passes and step end in one kernel call
    (dda.kernels.dense_passes.legacy_dense_step) are the start's, the passes' and the end's
    kernels called in turn: the same results to the bit."""
    (a, sa), (b, sb) = (_run_legacy(case, fused, monkeypatch) for fused in (False, True))
    assert np.count_nonzero(sa["closed"]) > 0
    assert_same_run(a, sa, b, sb)


def assert_same_run(a, sa, b, sb):
    """Two runs' final states ``a``, ``b`` and step stats ``sa``, ``sb`` are the same bits."""
    for name in ("open_close_passes", "iterations", "solves", "closed", "sliding", "time"):
        np.testing.assert_array_equal(sa[name], sb[name], err_msg=name)
    for name in ("x", "velocity", "stress"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for name in ("state", "t_n", "t_s"):
        np.testing.assert_array_equal(getattr(a.contacts, name), getattr(b.contacts, name))
    assert a.contacts.history.keys() == b.contacts.history.keys()
    for key, value in a.contacts.history.items():
        np.testing.assert_array_equal(value, b.contacts.history[key], err_msg=key)


def test_a_failed_legacy_step_in_one_call_says_why(monkeypatch):
    """A singular system stops the one-call step on the pass the passes' kernel stops on,
    with its reason."""
    problem = _captured_problem(monkeypatch)
    problem = replace(problem, block_k=np.zeros_like(problem.block_k))
    out = []
    for fused in (False, True):
        monkeypatch.setattr(legacy, "LEGACY_DENSE_STEP", fused)
        out.append(dda.solvers.LegacyPullBack().solve_step(replace(problem)))
    for sol in out:
        assert not sol.converged and sol.reason.startswith("singular system: "), sol.reason
    assert out[0].open_close_passes == out[1].open_close_passes
    assert out[0].iterations == out[1].iterations
