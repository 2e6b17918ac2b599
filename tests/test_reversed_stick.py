"""Newton's step on the stick branch of a contact whose sliding direction turned
(dda.solvers.newton.REVERSED_STICK), in the composed iterate and in the dense kernel."""

import numpy as np
import pytest

import dda
import dda.solvers.newton as newton
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic
from dda.solvers import NewtonRaphson
from tests.conftest import box, capture_step_problem

PENALTY = 5e10  # the cut slope's: 540 times its lightest block's inertia at dt 2e-3


@pytest.fixture(scope="module")
def resting_step():
    """A 1 m block resting on a fixed base at a stiff penalty: the step problem and its
    solution (both contacts sticking)."""
    rock = LinearElastic(young=1e10, poisson=0.25, density=2600.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 3, 0.5), rock, fixed=True, name="base")
    scene.add_block(box(1, 0.5, 1, 1), rock, name="top")
    scene.set_joint(JointMaterial(normal_penalty=PENALTY, shear_penalty=PENALTY,
                                  friction=CoulombSingle(phi=35.0)))
    sim = dda.Simulation(scene, dt=1e-3, solver=NewtonRaphson())
    sim.run(0.01, progress=False)
    problem = capture_step_problem(sim, 1e-3)
    solution = NewtonRaphson().solve_step(problem)
    assert solution.converged and (solution.contacts.state == 1).all()
    return problem, solution


@pytest.fixture(params=[True, False], ids=["dense kernel", "composed"])
def dense(request, monkeypatch):
    monkeypatch.setattr(newton, "DENSE_NEWTON", request.param)
    return request.param


def iterate_from_slid(problem, solution, slid):
    """Newton's iterations from the solution with the block moved ``slid`` metres along
    the base (both contacts sliding at the first iterate)."""
    d = solution.d.copy()
    d[1, 0] += slid
    return NewtonRaphson().iterate(problem, d)


@pytest.mark.parametrize("slid", [1e-4, 1e-3])
def test_a_contact_that_turns_takes_its_stick_branch(resting_step, dense, slid, monkeypatch):
    """Sliding, the contacts' tangent has no shear stiffness: from a start moved along the
    base the full Newton step throws the block back by mu N over its inertia (3.4e-6 m),
    far across the stick band (|t_s| < mu t_n: 1.8e-7 m at 5e10 N/m), and the contacts
    slide the other way. From there the step is taken on their stick branch (their stick
    force and shear penalty), which lands on the answer: 2 Newton steps. Without the rule
    the full step throws the block back again, and the line search's halving finds the
    band three steps later."""
    problem, solution = resting_step
    sol = iterate_from_slid(problem, solution, slid)
    assert sol.converged, sol.reason
    np.testing.assert_allclose(sol.d, solution.d, rtol=0, atol=1e-12)
    assert (sol.contacts.state == 1).all()
    assert sol.iterations == 2
    monkeypatch.setattr(newton, "REVERSED_STICK", False)
    without = iterate_from_slid(problem, solution, slid)
    assert without.converged
    np.testing.assert_allclose(without.d, solution.d, rtol=0, atol=1e-12)
    assert without.iterations == 5


def test_a_contact_that_does_slide_the_other_way_costs_one_iterate(dense, monkeypatch):
    """A start that slides the wrong way turns on its way to an answer that slides: the
    stick branch's step lands inside the band, its force is above the strength there, and
    the next step slides. The block slipping down the wedge of tests/test_newton.py, started
    0.01 rad off: 4 Newton steps instead of 3, to the same answer."""
    from tests.conftest import wedge_scene

    scene, _, _ = wedge_scene(penalty=1e7)
    sim = dda.Simulation(scene, dt=1e-3, solver=NewtonRaphson())
    sim.run(0.05, progress=False)
    problem = capture_step_problem(sim, 1e-3)
    reference = NewtonRaphson(tol=1e-14).solve_step(problem)
    assert (reference.contacts.state == 2).any()
    d = reference.d.copy()
    d[problem.free, 2] += 0.01 * np.array([1.0, -1.0])
    runs = {}
    for rule in (True, False):
        monkeypatch.setattr(newton, "REVERSED_STICK", rule)
        runs[rule] = NewtonRaphson(tol=1e-14).iterate(problem, d)
        assert runs[rule].converged
        np.testing.assert_allclose(runs[rule].d, reference.d, rtol=0, atol=1e-12)
    assert (runs[True].iterations, runs[False].iterations) == (4, 3)


def test_the_dense_kernel_takes_the_same_steps(resting_step, monkeypatch):
    """The compiled iterations and the composed ones: the same decisions (iterations) and
    residuals to round-off."""
    problem, solution = resting_step
    runs = {}
    for dense in (True, False):
        monkeypatch.setattr(newton, "DENSE_NEWTON", dense)
        runs[dense] = iterate_from_slid(problem, solution, 1e-4)
    assert runs[True].iterations == runs[False].iterations
    np.testing.assert_allclose(runs[True].residual_norms[:-1], runs[False].residual_norms[:-1],
                               rtol=1e-8)
    np.testing.assert_allclose(runs[True].d, runs[False].d, rtol=0, atol=1e-14)


def test_reversed_marks_the_contacts_that_turned_at_the_last_iterate():
    from dda.solvers.newton import _reversed

    p = [np.array(k, dtype=np.int8) for k in ([2, 2, 1, 2], [-2, 2, 1, -2], [2, -2, 1, 2])]
    np.testing.assert_array_equal(_reversed(p), [True, True, False, True])
    np.testing.assert_array_equal(_reversed(p[:2]), [True, False, False, True])
    assert _reversed(p[:1]) is None
    assert _reversed([p[0], p[0]]) is None
    # open or sticking between the slides is not a turn
    q = [np.array([2], dtype=np.int8), np.array([0], dtype=np.int8),
         np.array([2], dtype=np.int8)]
    assert _reversed(q) is None
