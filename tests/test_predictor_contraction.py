"""Newton from the looser predictor gives up on a stall (dda.solvers.newton's
``PREDICTOR_CONTRACTION``): two iterates in a row that do not shrink |R| to half the last
send the step to the predictor that settles stick and slip, without the rest of
``PREDICTOR_ITERATIONS``."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

import dda
from dda.solvers import NewtonRaphson, newton
from tests.stability import scenes as S


def _tower(monkeypatch, contraction, fused):
    """The 20-block tower under Newton for 0.05 s (74 steps, 3 of them cut): 4 steps whose
    Newton from the looser predictor does not converge. Without the turned contacts' stick
    branch (``REVERSED_STICK``), as measured: with it the tower takes 62 steps, 2 cut, and
    280 solves (375 before), and the rule's hand-over costs 8 solves more than it saves (3
    stalls; the predictor that settles stick and slip takes 12 passes more)."""
    monkeypatch.setattr(newton, "REVERSED_STICK", False)
    monkeypatch.setattr(newton, "PREDICTOR_CONTRACTION", contraction)
    monkeypatch.setattr(newton, "NEWTON_DENSE_STEP", fused)
    stalls = []
    original = newton.NewtonRaphson.iterate

    def iterate(self, problem, d, max_iter=None, contraction=0.0):
        sol = original(self, problem, d, max_iter, contraction)
        stalls.append(sol.reason.startswith("Newton-Raphson stalled"))
        return sol

    monkeypatch.setattr(newton.NewtonRaphson, "iterate", iterate)
    sim = dda.Simulation(S.tower()[0], dt=1e-3, solver=NewtonRaphson())
    stats = sim.run(0.05, progress=False).stats
    return sim.committed, stats, sum(stalls)


def test_a_stalled_newton_takes_the_retry_sooner_on_the_same_path(monkeypatch):
    """Measured: the four failing attempts stall and hand over sooner, 377 -> 361 linear
    solves; the retry starts from the step's start either way, so every step, pass and
    place is the same."""
    off, st_off, stalls_off = _tower(monkeypatch, 0.0, fused=False)
    on, st_on, stalls_on = _tower(monkeypatch, 0.5, fused=False)
    assert stalls_off == 0 and stalls_on >= 3
    assert st_on["solves"].sum() < st_off["solves"].sum() - 10
    for name in ("time", "open_close_passes", "iterations"):
        np.testing.assert_array_equal(st_on[name], st_off[name], err_msg=name)
    assert len(st_on.cuts) == len(st_off.cuts)
    np.testing.assert_array_equal(on.x, off.x)


def test_the_one_call_kernel_stalls_alike(monkeypatch):
    """The dense step in one call (dda.kernels.dense_newton) and the composed predictor and
    iterations give the same bits with the rule, and the same solves."""
    composed, st_c, stalls = _tower(monkeypatch, 0.5, fused=False)
    fused, st_f, _ = _tower(monkeypatch, 0.5, fused=True)
    assert stalls >= 3
    for name in ("time", "open_close_passes", "iterations", "solves"):
        np.testing.assert_array_equal(st_f[name], st_c[name], err_msg=name)
    np.testing.assert_array_equal(fused.x, composed.x)
    np.testing.assert_array_equal(fused.velocity, composed.velocity)


def test_the_sparse_iterate_stalls_on_two_weak_contractions(stack_step, monkeypatch):
    """Without the noise floor the stack's iterate goes 0.51 -> 0.019 -> 2.6e-3 -> 2.4e-3 N
    (each step shrinking |R| by 0.037 and 0.13, then converging): a contraction of 0.5 lets
    it converge as before; one of 1e-3, which neither of those steps meets, stops it at its
    third iterate."""
    problem, d, max_iter = stack_step
    monkeypatch.setattr(newton, "NOISE_FLOOR", False)
    runs = {c: NewtonRaphson().iterate(replace(problem), d, max_iter, contraction=c)
            for c in (0.0, 0.5, 1e-3)}
    assert runs[0.0].converged and runs[0.5].converged
    # (to round-off: outside a run PARDISO may solve on several threads, and a Newton
    # correction's unrefined single-precision solve then differs in its last bits)
    np.testing.assert_allclose(runs[0.5].residual_norms, runs[0.0].residual_norms, rtol=1e-6)
    np.testing.assert_allclose(runs[0.5].d, runs[0.0].d, rtol=0.0, atol=1e-12)
    stalled = runs[1e-3]
    assert not stalled.converged and stalled.d is None
    assert stalled.reason.startswith("Newton-Raphson stalled")
    np.testing.assert_allclose(stalled.residual_norms, runs[0.0].residual_norms[:3], rtol=1e-6)
