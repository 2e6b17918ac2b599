"""NewtonRaphson(unsettled_predictor=True): Newton iterates from an OPEN-CLOSE predictor that
did not settle instead of cutting the step."""

from __future__ import annotations

import pickle
from dataclasses import replace

import numpy as np
import pytest

import dda
from dda.io.scene_file import load_scene
from dda.solvers import NewtonRaphson, newton
from dda.solvers.open_close import open_close
from tests.stability import scenes as S
from tests.test_cli_and_pictures import SCENE


def _stopper():
    """A 0.2 m block striking a stopper at 5 m/s, 1e9 N/m, restitution 0: its predictor does
    not settle in the impact's steps at dt 1e-3 (a contact that closes and bounces open
    inside one step). No shear dashpot: with it, Newton from the last pass of one such step
    does not converge in 25 iterations either (|R| 0.68 of the forces), and the step is cut
    with the option too."""
    scene = S.stopper_impact()[0]
    joint = scene.default_joint
    scene.set_joint(replace(joint, normal_penalty=joint.normal_penalty / 1e4,
                            shear_penalty=joint.shear_penalty / 1e4, restitution=0.0,
                            shear_dashpot=False))
    return scene


def _run(solver, duration=0.04):
    sim = dda.Simulation(_stopper(), dt=1e-3, solver=solver)
    result = sim.run(duration, progress=False)
    return sim, result.stats


def test_by_default_an_unsettled_predictor_cuts_the_step():
    _, st = _run(NewtonRaphson())
    reasons = [r for _, _, r in st.cuts]
    assert reasons and all(r.startswith("OPEN-CLOSE did not settle in ") for r in reasons)


def test_newton_from_an_unsettled_predictor_converges_without_a_cut():
    sim, st = _run(NewtonRaphson(unsettled_predictor=True))
    assert len(st.cuts) == 0
    assert np.all(np.diff(st["time"]) == pytest.approx(1e-3))
    # the steps that the default cut took the whole OPEN-CLOSE budget and then converged
    assert np.max(st["open_close_passes"]) == 12 and np.all(st["iterations"] <= 25)
    # Newton's convergence test held on them: |R| within tol of the forces (or round-off)
    assert sim.committed.penetration < 1e-3


def test_the_one_call_kernel_iterates_from_an_unsettled_predictor_alike(monkeypatch):
    """The dense step in one call and the composed predictor and iterate give the same bits
    where the predictor did not settle."""
    runs = []
    for fused in (False, True):
        monkeypatch.setattr(newton, "NEWTON_DENSE_STEP", fused)
        sim, st = _run(NewtonRaphson(unsettled_predictor=True))
        runs.append((sim.committed, st))
    (a, sa), (b, sb) = runs
    for name in ("open_close_passes", "iterations", "solves", "time"):
        np.testing.assert_array_equal(sa[name], sb[name], err_msg=name)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.velocity, b.velocity)


def _unsettled_problem():
    """The StepProblem of the stopper's first step whose predictor does not settle."""
    problems = []
    solver = NewtonRaphson()
    original = solver.solve_step

    def capture(problem):
        problems.append(problem)
        return original(problem)

    solver.solve_step = capture
    dda.Simulation(_stopper(), dt=1e-3, solver=solver).run(0.03, progress=False)
    for problem in problems:
        if not open_close(replace(problem), explicit=False, settle_friction=False).converged:
            return problem
    raise AssertionError("no step with an unsettled predictor")


@pytest.mark.parametrize("fused", [False, True])
def test_a_failure_from_an_unsettled_predictor_says_both(fused, monkeypatch):
    """Newton that fails from an unsettled predictor reports both (the one-call kernel and
    the composed path alike); where it converges the step needs no cut."""
    problem = _unsettled_problem()
    monkeypatch.setattr(newton, "NEWTON_DENSE_STEP", fused)
    sol = NewtonRaphson(tol=1e-30, max_iter=1, unsettled_predictor=True).solve_step(
        replace(problem))
    assert not sol.converged
    assert sol.reason.startswith(f"OPEN-CLOSE did not settle in {problem.max_open_close} "
                                 "passes, and from its last pass Newton-Raphson did not "
                                 "converge in 1 iterations (|R| = "), sol.reason
    assert sol.open_close_passes == problem.max_open_close
    # from an unsettled predictor Newton has all of max_iter, not the few iterations it gets
    # from one that settled open and closed only
    monkeypatch.setattr(newton, "PREDICTOR_ITERATIONS", 0)
    sol = NewtonRaphson(unsettled_predictor=True).solve_step(replace(problem))
    assert sol.converged and sol.iterations >= 1
    assert not NewtonRaphson().solve_step(replace(problem)).converged


def test_the_setting_is_a_bool_and_shows_in_the_repr():
    assert repr(NewtonRaphson(unsettled_predictor=True)) == (
        "NewtonRaphson(tol=1e-09, max_iter=25, unsettled_predictor=True)")
    assert repr(NewtonRaphson()) == "NewtonRaphson(tol=1e-09, max_iter=25)"
    with pytest.raises(TypeError, match="unsettled_predictor must be True or False, got 1"):
        NewtonRaphson(unsettled_predictor=1)


def test_a_solver_pickled_before_the_setting_existed_has_it_off():
    """A checkpoint of the same layout written before the setting existed holds a
    NewtonRaphson without the attribute: it reads as the default."""
    old = NewtonRaphson()
    del old.__dict__["unsettled_predictor"]
    back = pickle.loads(pickle.dumps(old))
    assert back.unsettled_predictor is False
    sim, st = _run(back, 0.02)
    assert len(st) > 0


def test_a_scene_file_sets_it(tmp_path):
    text = SCENE.replace('solver = "legacy"', 'solver = "newton"\nunsettled_predictor = true')
    path = tmp_path / "scene.toml"
    path.write_text(text)
    solver = load_scene(path).solver
    assert isinstance(solver, NewtonRaphson) and solver.unsettled_predictor
