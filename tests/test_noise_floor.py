"""Newton-Raphson ends where |R| is within the out-of-balance of the contacts whose state is
round-off (dda.solvers.newton._at_noise_floor), without factorizing again to find out."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dda.kernels.dense_newton import _noise_floor
from dda.solvers import newton
from dda.solvers.open_close import round_off_gap


def _iterate(stack_step, floor, monkeypatch):
    problem, d, max_iter = stack_step
    monkeypatch.setattr(newton, "NOISE_FLOOR", floor)
    return newton.NewtonRaphson().iterate(replace(problem), d, max_iter)


def test_newton_stops_at_the_noise_floor_of_round_off_contacts(stack_step, monkeypatch):
    """The stack's joints between columns close at gaps of 1e-12 m: their state is noise,
    and |R| cannot fall below their summed forces. Measured: strictly, 0.51 -> 0.019 ->
    0.0025 -> 0.0024 N (three factorizations, the last one to see |R| stop falling); the
    first iterate is already within the noise (1.9e-2 N), and the answers differ by 1e-12 m."""
    strict = _iterate(stack_step, False, monkeypatch)
    floor = _iterate(stack_step, True, monkeypatch)
    assert strict.converged and floor.converged
    assert floor.iterations == 1 and strict.iterations >= floor.iterations + 2
    # the same iterate, which the tolerance and the stagnation rule did not end (the strict
    # iteration went on from it): only the noise floor ended it
    # (to round-off: outside a run PARDISO may solve on several threads, and a Newton
    # correction's unrefined single-precision solve then differs in its last bits)
    np.testing.assert_allclose(floor.residual_norms, strict.residual_norms[:2], rtol=1e-6)
    np.testing.assert_allclose(floor.d, strict.d, rtol=0.0, atol=1e-11)
    change = np.abs(floor.contacts.t_n - strict.contacts.t_n)
    assert change.max() <= 1e-6 * np.abs(strict.contacts.t_n).max()


def test_the_kernel_sums_the_same_noise_floor(stack_step):
    """The dense kernel's floor (dda.kernels.dense_newton._noise_floor) is the composed one's:
    the same contacts, the same rows summed in the same order; contacts made noisy by hand
    add their rows, one with a large shear force does not count."""
    problem, d, _ = stack_step
    el = problem.element
    resp = el.response(d)
    gap_tol = np.asarray(round_off_gap(el), dtype=float)
    kn = np.ascontiguousarray(np.broadcast_to(np.asarray(el.judge_stiffness, dtype=float),
                                              (len(el),)))
    rigid = np.zeros(len(problem.free), dtype=bool)

    def both(r):
        composed = newton.noise_floor(problem, r)
        kernel = _noise_floor(problem.free, rigid, np.asarray(el.bj, dtype=np.int64),
                              np.asarray(el.bk, dtype=np.int64), r.residual, r.closed,
                              r.force, r.t_s, kn, gap_tol)
        return composed, kernel

    composed, kernel = both(resp)
    assert composed > 0.0
    assert kernel == pytest.approx(composed, rel=1e-12)
    # three loaded contacts made noise: their rows join the sum
    loaded = np.flatnonzero(resp.closed & (np.abs(resp.force) > 1e3 * kn * gap_tol))[:4]
    force, t_s = resp.force.copy(), resp.t_s.copy()
    force[loaded[:3]] = 0.5 * kn[loaded[:3]] * gap_tol[loaded[:3]]
    t_s[loaded[:3]] = 0.0
    composed3, kernel3 = both(replace(resp, force=force, t_s=t_s))
    assert kernel3 == pytest.approx(composed3, rel=1e-12)
    assert composed3 != pytest.approx(composed, rel=1e-6)
    # a fourth whose normal force is at round-off but whose shear force is not: no change
    force[loaded[3]] = 0.5 * kn[loaded[3]] * gap_tol[loaded[3]]
    t_s[loaded[3]] = 10.0 * kn[loaded[3]] * gap_tol[loaded[3]]
    composed4, kernel4 = both(replace(resp, force=force, t_s=t_s))
    assert composed4 == composed3 and kernel4 == kernel3
