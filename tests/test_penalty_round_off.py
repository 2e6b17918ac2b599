"""Newton-Raphson's round-off floor knows the contacts' penalties
(dda.kernels.dense_newton.penalty_round_off): a stiff penalty holding small forces leaves a
residual that no iterate and no smaller dt lowers, and the step is not cut for it."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import dda
from dda.kernels.dense_newton import penalty_round_off
from dda.registry import make_solver
from dda.solvers import newton
from tests.stability import scenes
from tests.stability.test_impacts import PENALTIES

EPS = np.finfo(float).eps


def _one_contact(shift=0.0, penalty=1e10):
    """One contact: vertex (1, 0.2) against the edge (0, 0)-(2, 0), every point moved by
    ``shift`` in x, with the maps of a rigid motion of each block about the origin."""
    p1 = np.array([[1.0 + shift, 0.2]])
    p2 = np.array([[0.0 + shift, 0.0]])
    p3 = np.array([[2.0 + shift, 0.0]])

    def rigid_map(p, side):
        a = np.zeros((1, 2, 12))
        a[0, 0, 6 * side], a[0, 1, 6 * side + 1] = 1.0, 1.0
        a[0, 0, 6 * side + 2], a[0, 1, 6 * side + 2] = -p[0, 1], p[0, 0]
        return a

    return (p1, p2, p3, rigid_map(p1, 0), rigid_map(p2, 1), rigid_map(p3, 1),
            np.array([penalty]), np.array([penalty / 2.5]))


def test_the_floor_is_the_stiffness_times_the_coordinates_round_off():
    """By hand for one contact: ``(k_n + k_s) (|A_1 - A_2| + |A_3 - A_2|) eps (|x_1| +
    |x_2| + |x_3|)_max``; it grows with the penalty and with the coordinates' size (a scene
    far from the origin), and contacts add in quadrature."""
    args = _one_contact()
    a1, a2, a3 = args[3:6]
    lever = np.linalg.norm(a1 - a2) + np.linalg.norm(a3 - a2)
    by_hand = (1e10 + 4e9) * lever * EPS * (1.0 + 0.0 + 2.0)
    assert penalty_round_off(*args) == pytest.approx(by_hand, rel=1e-12)
    assert penalty_round_off(*_one_contact(penalty=1e13)) == pytest.approx(1e3 * by_hand,
                                                                           rel=1e-12)
    far = penalty_round_off(*_one_contact(shift=1000.0))
    assert far > 300.0 * by_hand
    two = [np.concatenate([a, a]) for a in args]
    assert penalty_round_off(*two) == pytest.approx(np.sqrt(2.0) * by_hand, rel=1e-12)
    assert penalty_round_off(*(a[:0] for a in args)) == 0.0


class _LastStep:
    """The last converged step's problem and answer of a Newton run."""

    def __init__(self, monkeypatch):
        solve = newton.NewtonRaphson.solve_step

        def kept(solver, problem):
            sol = solve(solver, problem)
            if sol.converged:
                self.problem, self.d = problem, sol.d
            return sol

        monkeypatch.setattr(newton.NewtonRaphson, "solve_step", kept)


@pytest.mark.parametrize("dense", [True, False])
@pytest.mark.parametrize("penalty", ["E", "1000 E"])
def test_the_floor_bounds_the_residual_of_a_resting_block(penalty, dense, monkeypatch):
    """The lip's block at rest on its two contacts, iterated on from its converged answer
    with nothing but round-off left: |R| stays below the floor, and the floor is no more
    than 1,000 times that residual (measured: 2e-5 N against 3e-7 to 4e-7 N at E, 1.8e-2 N
    against 9e-5 to 5e-4 N at 1,000 E; forces of 2,400 N)."""
    last = _LastStep(monkeypatch)
    scene, _ = scenes.IMPACTS["lip"](PENALTIES[penalty])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dda.Simulation(scene, dt=1e-3, solver=make_solver("newton")).run(0.3, progress=False)
    floor = newton._penalty_floor(last.problem.element)
    monkeypatch.setattr(newton, "DENSE_NEWTON", dense)
    monkeypatch.setattr(newton, "NOISE_FLOOR", False)
    monkeypatch.setattr(newton, "ROUND_OFF", 0.0)
    sol = newton.NewtonRaphson(tol=1e-18, max_iter=8).iterate(replace(last.problem), last.d)
    assert sol.converged  # by the floor: tol 1e-18 of the forces is out of reach
    norms = np.asarray(sol.residual_norms)
    assert len(norms) >= 3
    assert norms.max() <= floor <= 1e3 * norms.max()


@pytest.mark.parametrize("dense", [True, False])
def test_newton_does_not_cut_a_stiff_resting_contact_for_round_off(dense, monkeypatch):
    """The lip impact at 1,000 E (1e13 N/m), dt 1e-3: before the floor knew the penalty,
    four of its nine cut steps were Newton stalling at |R| 4.5e-4 to 7.4e-4 N, 2.6e-6 of
    the forces (``ROUND_OFF`` is 1e-6 of them), and each retry at half the dt stalled at
    the same fraction. Now only OPEN-CLOSE cuts it (the impact inside a step)."""
    monkeypatch.setattr(newton, "DENSE_NEWTON", dense)
    scene, duration = scenes.IMPACTS["lip"](PENALTIES["1000 E"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = dda.Simulation(scene, dt=1e-3, solver=make_solver("newton")).run(
            duration, progress=False)
    reasons = [cut[2] for cut in result.stats.cuts]
    assert not [r for r in reasons if "Newton-Raphson" in r], reasons
    assert len(reasons) <= 6
