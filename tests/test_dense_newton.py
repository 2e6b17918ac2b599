"""A small scene's Newton-Raphson iterations in one kernel call (dda.kernels.dense_newton)
against the composed iterate: the same decisions, the same numbers to round-off."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import dda
from dda.materials import LinearElastic
from dda.profiling import StepProfile
from dda.solvers import newton, open_close
from tests.conftest import stack_scene
from tests.test_dense_passes import CASES, assert_close_runs, assert_same_run


def _run(case, dense, monkeypatch):
    monkeypatch.setattr(newton, "DENSE_NEWTON", dense)
    scene, dt, duration = CASES[case]()
    sim = dda.Simulation(scene, dt=dt, solver=dda.solvers.NewtonRaphson())
    result = sim.run(duration, progress=False)
    return sim.state, result.stats, dt


@pytest.mark.parametrize("case", CASES)
def test_one_kernel_takes_the_composed_iterations_decisions(case, monkeypatch):
    (a, sa, dt), (b, sb, _) = (_run(case, dense, monkeypatch) for dense in (False, True))
    assert np.count_nonzero(sa["closed"]) > 0 and np.sum(sa["iterations"]) > 0
    assert_close_runs(a, sa, b, sb, dt)


def _problem_and_start(monkeypatch, scene=None, step=3):
    """A StepProblem of a Newton run of the 3 x 3 stack (its ``step``-th step) and the
    predictor's increments Newton iterates from. The stack's joint has no shear dashpot: the
    perturbed and broken starts below were measured without it (with it, the dashpot's
    ``c_s / dt`` makes a 0.1 mm perturbation take more than 25 iterations, and the broken
    tangent only nearly singular)."""
    captured = []
    original = newton.NewtonRaphson.iterate

    def capture(self, problem, d, max_iter=None, contraction=0.0):
        captured.append((problem, d.copy()))
        return original(self, problem, d, max_iter, contraction)

    monkeypatch.setattr(newton.NewtonRaphson, "iterate", capture)
    monkeypatch.setattr(newton, "NEWTON_DENSE_STEP", False)  # the iterate is called apart
    sim = dda.Simulation(scene or stack_scene(3, shear_dashpot=False), dt=1e-3,
                         solver=dda.solvers.NewtonRaphson())
    sim.run(step * 1e-3, progress=False)
    monkeypatch.setattr(newton.NewtonRaphson, "iterate", original)
    monkeypatch.setattr(newton, "NEWTON_DENSE_STEP", True)
    return captured[-1]


def perturbed_start(problem, d):
    """``d`` with the free blocks moved about 0.1 mm and turned about 1e-5 rad (seeded)."""
    rng = np.random.default_rng(3)
    start = d.copy()
    free = problem.free
    start[free, :2] += 1e-4 * rng.standard_normal((np.count_nonzero(free), 2))
    start[free, 2] += 1e-5 * rng.standard_normal(np.count_nonzero(free))
    return start


def _both(problem, d, monkeypatch, **kw):
    out = []
    for dense in (False, True):
        monkeypatch.setattr(newton, "DENSE_NEWTON", dense)
        out.append(newton.NewtonRaphson(**kw).iterate(replace(problem), d))
    return out


@pytest.mark.parametrize("reversed_stick", [True, False])
def test_an_iterate_gives_the_composed_residuals_from_a_perturbed_start(monkeypatch,
                                                                         reversed_stick):
    """From a start 0.1 mm off the predictor at a penalty of 1e10 N/m (contacts that change
    state and turn their sliding direction; without the turned contacts' stick branch,
    newton.REVERSED_STICK, patterns that cycle and are halved) both paths take the same
    iterations (6; 25 without the stick branch), their |R| agree to round-off of the forces,
    and they end on the same contacts."""
    problem, d = _problem_and_start(monkeypatch)
    monkeypatch.setattr(newton, "REVERSED_STICK", reversed_stick)
    # the counts were measured without the hold of cycling contacts (with it, the variant
    # without the stick branch ends its 25 iterations at |R| 175 N, both paths alike:
    # tests/test_cohesive_newton.py)
    monkeypatch.setattr(newton, "HOLD_CYCLING", False)
    a, b = _both(problem, perturbed_start(problem, d), monkeypatch)
    assert a.converged and b.converged
    assert a.iterations == b.iterations >= (5 if reversed_stick else 10)
    assert len(a.residual_norms) == len(b.residual_norms)
    if not reversed_stick:  # an iteration that halves a cycling step records no |R|
        assert len(a.residual_norms) < a.iterations + 1
    scale = np.abs(problem.block_f[problem.free]).max()
    np.testing.assert_allclose(b.residual_norms, a.residual_norms, rtol=1e-6,
                               atol=1e-9 * scale)
    np.testing.assert_allclose(b.d, a.d, rtol=0.0, atol=1e-12)
    np.testing.assert_array_equal(b.contacts.state, a.contacts.state)
    np.testing.assert_allclose(b.contacts.t_n, a.contacts.t_n, rtol=1e-9,
                               atol=1e-9 * np.abs(a.contacts.t_n).max())


def test_an_iterate_that_runs_out_says_so_alike(monkeypatch):
    problem, d = _problem_and_start(monkeypatch)
    start = d.copy()
    start[problem.free, 1] += 1e-3
    a, b = _both(problem, start, monkeypatch, max_iter=1)
    for s in (a, b):
        assert not s.converged
        assert s.reason.startswith("Newton-Raphson did not converge in 1 iterations (|R| = ")
    assert a.iterations == b.iterations == 1
    assert a.reason.split("(")[1][:6] == b.reason.split("(")[1][:6]  # |R| to 3 digits
    np.testing.assert_allclose(b.residual_norms, a.residual_norms, rtol=1e-6)


@pytest.mark.parametrize("broken, reason", [
    (lambda p: replace(p, block_k=np.zeros_like(p.block_k)), "singular tangent: "),
    (lambda p: replace(p, block_f=np.full_like(p.block_f, np.nan)),
     "Newton-Raphson diverged (non-finite residual)")])
def test_a_failed_iterate_is_reported_alike(broken, reason, monkeypatch):
    """A tangent without the blocks' inertia is singular where no contact holds a block, and
    NaN loads give a non-finite residual: both paths say so at the same iteration. The stack
    has a block apart that touches nothing, so that the tangent is singular exactly: the
    stack's own blocks without their inertia are held by their springs in all but their
    strains, a tangent singular to round-off only, whose LU (numpy's LAPACK and numba's
    differ) meets an exact zero pivot at an iteration that depends on the machine (2 against
    3 on an AMD EPYC)."""
    scene = stack_scene(3, shear_dashpot=False)
    scene.add_block([(10.0, 5.0), (11.0, 5.0), (11.0, 6.0), (10.0, 6.0)],
                    LinearElastic(young=10e9, poisson=0.25, density=2500.0))
    problem, d = _problem_and_start(monkeypatch, scene, step=1)
    problem = broken(problem)
    a, b = _both(problem, d, monkeypatch)
    for s in (a, b):
        assert not s.converged and s.reason.startswith(reason), s.reason
    assert a.iterations == b.iterations
    assert len(a.residual_norms) == len(b.residual_norms)


def test_the_dense_iterate_ran_and_counts_its_solves(monkeypatch):
    """The comparison is not of one path with itself: the kernel's numbers differ from the
    composed iterate's in the last bits, and it counts a solve per iteration as the
    composed one does."""
    problem, d = _problem_and_start(monkeypatch)
    start = d.copy()
    start[problem.free, 0] += 1e-3
    a, b = _both(problem, start, monkeypatch)
    assert not np.array_equal(a.d, b.d)
    (_, sa, _), (_, sb, _) = (_run("3 x 3 stack", dense, monkeypatch) for dense in (False, True))
    np.testing.assert_array_equal(sa["solves"], sb["solves"])


def _run_step(case, fused, monkeypatch):
    monkeypatch.setattr(newton, "NEWTON_DENSE_STEP", fused)
    return _run(case, True, monkeypatch)


@pytest.mark.parametrize("case", CASES)
def test_newton_step_in_one_call_gives_the_two_kernels_bits(case, monkeypatch):
    """The predictor and the iterations in one kernel call
    (dda.kernels.dense_newton.newton_dense_step) are the predictor's and the iterations'
    kernels called in turn: the same results to the bit."""
    (a, sa, _), (b, sb, _) = (_run_step(case, fused, monkeypatch) for fused in (False, True))
    assert_same_run(a, sa, b, sb)


def _stack_step_problem(index):
    """The StepProblem of the 3 x 3 stack's step ``index`` (Newton, dt 1e-3)."""
    problems = []
    solver = newton.NewtonRaphson()
    original = solver.solve_step

    def capture(problem):
        problems.append(problem)
        return original(problem)

    solver.solve_step = capture
    dda.Simulation(stack_scene(3), dt=1e-3, solver=solver).run((index + 1) * 1e-3,
                                                                progress=False)
    return problems[index]


def _both_paths(problem, monkeypatch, **solver):
    """``NewtonRaphson(**solver).solve_step(problem)`` composed and in one kernel call:
    ``[(solution, calls, solves), ...]``, with ``calls`` the composed path's OPEN-CLOSE
    calls as ``(settle_friction, passes, friction_settled)``."""
    out = []
    for fused in (False, True):
        monkeypatch.setattr(newton, "NEWTON_DENSE_STEP", fused)
        calls = []
        original = open_close.open_close

        def counted(*args, original=original, calls=calls, **kw):
            result = original(*args, **kw)
            calls.append((kw.get("settle_friction"), result.passes, result.friction_settled))
            return result

        monkeypatch.setattr(newton, "open_close", counted)
        profile = StepProfile()
        with profile.active():
            sol = newton.NewtonRaphson(**solver).solve_step(replace(problem))
        out.append((sol, calls, profile.solves))
    return out


@pytest.mark.parametrize("max_iter, tol", [(25, 1e-9), (1, 1e-30)])
def test_a_newton_step_in_one_call_settles_friction_when_it_must(max_iter, tol, monkeypatch):
    """A step whose predictor leaves stick and slip unsettled (the 3 x 3 stack's fourth)
    and whose first iterations do not converge (none allowed) settles stick and slip and
    iterates again, in one call as in turn: the same passes, iterations, solves and outcome;
    with one iteration allowed towards a tolerance below round-off both fail alike."""
    problem = _stack_step_problem(3)
    monkeypatch.setattr(newton, "PREDICTOR_ITERATIONS", 0)
    out = _both_paths(problem, monkeypatch, tol=tol, max_iter=max_iter)
    (a, calls, solves_a), (b, fused_calls, solves_b) = out
    assert [c[0] for c in calls] == [False, True] and fused_calls == []  # friction settled
    assert a.converged == b.converged == (tol == 1e-9)
    assert (a.open_close_passes, a.iterations, a.reason) == (
        b.open_close_passes, b.iterations, b.reason)
    assert solves_a == solves_b
    assert a.residual_norms == b.residual_norms
    if a.converged:
        np.testing.assert_array_equal(a.d, b.d)


@pytest.mark.parametrize("patience", [1, 2, 10**6])
def test_the_retry_hands_over_after_its_patience_alike(patience, monkeypatch):
    """The friction-settled retry of the predictor (the 3 x 3 stack's fourth step, Newton
    allowed no iteration from the looser predictor) counts as settled, its friction not, once
    ``RETRY_PATIENCE`` passes in a row have opened or closed no contact, and Newton then takes
    its whole budget; in one kernel call as in turn: the same passes, iterations, solves and
    answer. Off (a patience beyond the passes) the retry settles its friction, in more passes.
    Legacy DDA has no such rule."""
    problem = _stack_step_problem(3)
    monkeypatch.setattr(newton, "PREDICTOR_ITERATIONS", 0)
    monkeypatch.setattr(open_close, "RETRY_PATIENCE", patience)
    assert open_close.predictor_patience(True, True) == 0
    assert open_close.predictor_patience(False, True) == patience
    out = _both_paths(problem, monkeypatch)
    (a, calls, solves_a), (b, fused_calls, solves_b) = out
    assert a.converged and b.converged and fused_calls == []
    retry = calls[1]
    if patience < 10:  # its open and closed states stand from the first pass on
        assert retry == (True, patience + 1, False)
    else:
        assert retry[0] and retry[2] and retry[1] > 3
    assert (a.open_close_passes, a.iterations) == (b.open_close_passes, b.iterations)
    assert solves_a == solves_b
    assert a.residual_norms == b.residual_norms
    np.testing.assert_array_equal(a.d, b.d)
