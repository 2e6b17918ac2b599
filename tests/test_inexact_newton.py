"""Newton's corrections solved inexactly: the single-precision factors' refinement stops at a
residual of ``INEXACT_FRACTION`` of Newton's own convergence threshold
(dda.solvers.newton; dda.solvers.sparse_factor's ``atol``), and the step's answer is the one
of solves refined in full, to within that threshold."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dda.solvers import newton
from dda.solvers import sparse_factor as sf

pytestmark = pytest.mark.skipif(not sf._pardiso_available(),
                                reason="pypardiso/MKL not installed (no mixed precision)")


def _iterate(stack_step, fraction, monkeypatch):
    """Newton's iterations of the captured step, and PARDISO's calls on its tangents (the
    phases: 22 a factorization, 33 a solve with the factors)."""
    problem, d, max_iter = stack_step
    # without the noise floor the iteration goes on to the tolerance: three corrections
    monkeypatch.setattr(newton, "NOISE_FLOOR", False)
    monkeypatch.setattr(newton, "INEXACT_FRACTION", fraction)
    calls = []
    original = sf.PardisoFactor._call

    def call(self, phase, data, b):
        if not self.symmetric and phase != 11:  # not the symbolic analysis
            calls.append(phase)
        return original(self, phase, data, b)

    monkeypatch.setattr(sf.PardisoFactor, "_call", call)
    problem = replace(problem, factors=sf.FactorSet())
    sol = newton.NewtonRaphson().iterate(problem, d, max_iter)
    return sol, calls, problem.factor(False).inexact_solves


def test_newton_corrections_stop_refining_at_their_tolerance(stack_step, monkeypatch):
    """Measured: |R| 0.51, 0.019, 2.6e-3, 2.4e-3 N either way; the first correction's solve
    leaves 1.1e-7 N unrefined, under the 1.4e-4 N it needs (a tenth of Newton's 1e-9 of the
    forces), and takes one solve with the new factors instead of two."""
    full, full_calls, early_full = _iterate(stack_step, 0.0, monkeypatch)
    inexact, calls, early = _iterate(stack_step, 0.1, monkeypatch)
    assert full.converged and inexact.converged
    assert inexact.iterations == full.iterations == 3
    assert early_full == 0 and early >= 1

    def first_solves(phases):  # the solves with the first factorization
        assert phases[0] == 22
        return phases.index(22, 1) - 1

    assert (first_solves(full_calls), first_solves(calls)) == (2, 1)
    np.testing.assert_allclose(inexact.d, full.d, rtol=0.0, atol=1e-12)
    change = np.abs(inexact.contacts.t_n - full.contacts.t_n)
    assert change.max() <= 1e-8 * np.abs(full.contacts.t_n).max()
    # both end within Newton's tolerance (1e-9 of the forces, some 2e-3 N here)
    assert inexact.residual_norms[-1] <= 1.01 * full.residual_norms[-1]
