"""Fully implicit DDA: quadratic convergence, and the same scene under both solvers."""

import numpy as np
import pytest

import dda
from tests.conftest import capture_step_problem, wedge_scene


def convergence_order(norms, floor):
    """Order of convergence from the last three residual norms above ``floor``."""
    r = np.asarray([n for n in norms if n > floor])
    assert len(r) >= 3, f"too few iterations above the floor: {norms}"
    return np.log(r[-1] / r[-2]) / np.log(r[-2] / r[-3])


@pytest.fixture(scope="module")
def wedge_step():
    """The step problem of a block slipping down a free wedge, and its solution."""
    scene, _, _ = wedge_scene(penalty=1e7)
    sim = dda.Simulation(scene, dt=1e-3, solver=dda.solvers.NewtonRaphson())
    sim.run(0.05)
    problem = capture_step_problem(sim, 1e-3)
    return problem, dda.solvers.NewtonRaphson(tol=1e-14).solve_step(problem)


@pytest.mark.parametrize("rotation", [0.01, 0.03])
def test_newton_converges_quadratically_on_a_slipping_step(wedge_step, rotation):
    problem, reference = wedge_step
    assert (reference.contacts.state == 2).any()  # the block slips on the wedge
    d = reference.d.copy()
    d[problem.free, 2] += rotation * np.array([1.0, -1.0])  # start far from the solution
    solver = dda.solvers.NewtonRaphson(tol=1e-14)
    sol = solver.iterate(problem, d)
    assert sol.converged
    np.testing.assert_allclose(sol.d, reference.d, rtol=0, atol=1e-12)
    assert convergence_order(sol.residual_norms, floor=1e-7) >= 1.8


def test_newton_records_residual_norms_in_the_stats():
    scene, _, top = wedge_scene(penalty=1e7)
    result = dda.Simulation(scene, dt=1e-3, solver=dda.solvers.NewtonRaphson()).run(0.02)
    assert len(result.stats.residual_norms) == len(result.stats)
    assert all(len(n) >= 1 for n in result.stats.residual_norms)
    final = np.array([n[-1] for n in result.stats.residual_norms])
    first = np.array([n[0] for n in result.stats.residual_norms])
    assert np.all(final <= np.maximum(first, 1e-6))


def test_same_scene_object_runs_under_both_solvers():
    """Only ``solver=`` changes; the scene is not modified by a run."""
    scene, wedge, top = wedge_scene(penalty=1e8)
    results = {}
    for solver in (dda.solvers.LegacyPullBack(), dda.solvers.NewtonRaphson()):
        results[solver.name] = dda.Simulation(scene, dt=1e-3, solver=solver).run(0.3)
    legacy, implicit = results["legacy"], results["newton"]
    np.testing.assert_array_equal(legacy.time, implicit.time)
    # both slide the block down the wedge by about the same amount here
    s_legacy = np.linalg.norm(legacy.displacement(top)[-1])
    s_newton = np.linalg.norm(implicit.displacement(top)[-1])
    assert s_newton > 0.01
    assert s_legacy == pytest.approx(s_newton, rel=0.05)
    assert implicit.stats["iterations"].sum() < legacy.stats["iterations"].sum()


def test_newton_rejects_bad_settings():
    with pytest.raises(ValueError, match="tol"):
        dda.solvers.NewtonRaphson(tol=-1.0)
    with pytest.raises(ValueError, match="max_iter"):
        dda.solvers.NewtonRaphson(max_iter=0)


def test_newton_halves_a_step_that_cycles_across_a_kink():
    """On the 30 x 30 stack of benchmarks/stacks.py the step after t = 0.075 s had two
    sliding contacts whose trial force changed sign at every full Newton step: |R| stayed at
    30 N through the predictor's iterations and cycled between 450 and 560 N (sliding, open,
    sliding) through all 25 of the next, and the step was cut. Halving a step that brings
    back the contact pattern of two steps before converges it; so does the step on a turned
    contact's stick branch (REVERSED_STICK) without halving. (Without the impact dashpot,
    as measured: with it the stack takes another path and that step has no such cycle.)"""
    import dda.solvers.newton as newton
    from dda.solvers import NewtonRaphson
    from tests.conftest import stack_scene

    rule = newton.REVERSED_STICK
    newton.REVERSED_STICK = False  # the run to the step as measured
    try:
        sim = dda.Simulation(stack_scene(30, restitution=1.0), dt=1e-3,
                             solver=NewtonRaphson(), max_open_close=30)
        sim.run(0.075, progress=False)
        problem = capture_step_problem(sim, 1e-3)
        sol = NewtonRaphson().solve_step(problem)
        assert sol.converged, sol.reason
        old = newton.LINE_SEARCH_HALVINGS
        newton.LINE_SEARCH_HALVINGS = 0
        try:
            without = NewtonRaphson().solve_step(problem)
            newton.REVERSED_STICK = True
            branch = NewtonRaphson().solve_step(problem)
        finally:
            newton.LINE_SEARCH_HALVINGS = old
    finally:
        newton.REVERSED_STICK = rule
    assert not without.converged and "did not converge in 25" in without.reason
    assert branch.converged, branch.reason


def test_a_cycle_is_a_pattern_of_two_to_cycle_length_iterates_back():
    """Newton's cycle test (dda.solvers.newton._seen_at): the same contact pattern two, three or
    CYCLE_LENGTH accepted iterates back is a cycle (the pile of
    tests/stability/test_newton_cycles.py cycled through 3 and 4); the last iterate's own
    pattern (a step that changed no state) and one further back are not."""
    from dda.solvers import newton
    from dda.solvers.newton import _seen_at

    a, b, c, d = (np.array([k], dtype=np.int8) for k in range(4))
    assert _seen_at(a, [a, b]) == -2
    assert _seen_at(a, [a, b, c]) == -3
    assert _seen_at(a, [a, b, c, d]) == -4
    assert _seen_at(b, [a, b]) is None
    assert _seen_at(d, [a, b, c]) is None
    longer = [a] + [np.array([k], dtype=np.int8) for k in range(10, 10 + newton.CYCLE_LENGTH)]
    assert _seen_at(a, longer) is None
