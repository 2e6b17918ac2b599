"""Legacy DDA's secant step on an oscillating lagged normal force, and the fully implicit
predictor's lag memory through an open pass (:func:`dda.solvers.open_close.next_lag`, compiled
as :func:`dda.kernels.open_close.next_lag_force`)."""

from __future__ import annotations

import numpy as np
import pytest

from dda.contact.contacts import OPEN, SLIP
from dda.kernels.open_close import REMEMBER_FROM_FLIPS, next_lag_force
from dda.solvers.open_close import LAG_RELAX_AFTER, LAG_SECANT_FROM, next_lag

STIFFNESS = 1e10


def _iterate(a, b, passes, secant_from, state=SLIP, rule="numpy", start=0.0):
    """Lagged forces of a sliding contact whose pass answers ``N = a - b N_lag`` (compression
    negative: ``a < 0``), through ``passes`` passes of the rule; the spring force is ``N``
    itself (a contact that stays closed)."""
    m = 1
    lag = np.array([start])
    lag_error = np.zeros(m)
    memory = np.zeros((m, 3))
    states = np.full(m, state, dtype=np.int8)
    history = [lag[0]]
    for k in range(1, passes + 1):
        spring = a - b * lag
        t_n = np.minimum(spring, 0.0)
        gap = spring / STIFFNESS
        if rule == "numpy":
            lag, lag_error = next_lag(states, gap, np.full(m, STIFFNESS), t_n, lag, lag_error,
                                      memory, k, secant_from)
        else:
            lag, lag_error = next_lag_force(states, gap, np.full(m, STIFFNESS), t_n, lag,
                                            lag_error, memory, k, LAG_RELAX_AFTER, secant_from,
                                            False, np.zeros(m, dtype=np.int64))
        history.append(lag[0])
    return np.array(history)


@pytest.mark.parametrize("b", [0.3, 1.05, 2.0, 4.0])
def test_the_secant_step_lands_on_the_fixed_point_of_a_linear_map(b):
    """``N = a - b N_lag`` with ``b > 0`` oscillates; its fixed point is ``a / (1 + b)``. The
    plain iteration contracts by ``b`` a pass and does not settle for ``b >= 1`` (the halving
    from pass LAG_RELAX_AFTER by ``|1 - b| / 2``, not for ``b >= 3``); the secant step lands on
    the fixed point at the first oscillation from pass LAG_SECANT_FROM, to round-off."""
    a = -1e5
    fixed = a / (1.0 + b)
    lags = _iterate(a, b, LAG_SECANT_FROM + 1, LAG_SECANT_FROM)
    # lags[k] is the lag of pass k + 1; the secant step is taken after pass LAG_SECANT_FROM
    assert lags[LAG_SECANT_FROM] == pytest.approx(fixed, rel=1e-12)
    assert lags[LAG_SECANT_FROM + 1] == pytest.approx(fixed, rel=1e-12)
    plain = _iterate(a, b, LAG_SECANT_FROM, 0)
    assert abs(plain[-1] - fixed) > 1e-3 * abs(fixed)  # without it, not there yet


@pytest.mark.parametrize("b", [0.3, 2.0, 4.0])
@pytest.mark.parametrize("secant_from", [0, LAG_SECANT_FROM])
def test_the_compiled_rule_gives_numpys_bits(b, secant_from):
    for start in (0.0, -3e4):
        numpy_lags = _iterate(-1e5, b, 12, secant_from, start=start)
        compiled = _iterate(-1e5, b, 12, secant_from, rule="kernel", start=start)
        np.testing.assert_array_equal(numpy_lags, compiled)


def test_without_the_secant_the_rule_is_the_plain_one_then_the_halving():
    """Before LAG_SECANT_FROM, or with it off (the fully implicit method's predictor), the
    lag is the pass's own force, and from LAG_RELAX_AFTER the mean of an oscillation."""
    a, b = -1e5, 2.0
    lags = _iterate(a, b, LAG_RELAX_AFTER, 0)
    for k in range(1, LAG_RELAX_AFTER):
        assert lags[k] == min(a - b * lags[k - 1], 0.0)
    n = min(a - b * lags[LAG_RELAX_AFTER - 1], 0.0)
    assert lags[LAG_RELAX_AFTER] == 0.5 * (n + lags[LAG_RELAX_AFTER - 1])


def test_a_contact_open_in_the_pass_takes_no_secant_step():
    """The secant needs two passes of one closed contact: an open contact's force is the
    spring force it lacks, not a point of the closed contact's map."""
    lags = _iterate(-1e5, 2.0, LAG_SECANT_FROM + 1, LAG_SECANT_FROM, state=OPEN)
    plain = _iterate(-1e5, 2.0, LAG_SECANT_FROM + 1, 0, state=OPEN)
    np.testing.assert_array_equal(lags, plain)


def test_a_monotone_convergence_is_left_alone():
    """``b < 0``: the error keeps its sign, there is no oscillation to damp and the plain
    iteration stands."""
    lags = _iterate(-1e5, -0.5, 8, LAG_SECANT_FROM)
    plain = _iterate(-1e5, -0.5, 8, 0)
    np.testing.assert_array_equal(lags, plain)


def _through_an_open_pass(rule, remember, flips=REMEMBER_FROM_FLIPS, lag0=-1e5, tension=2e4,
                          closing=-3e5):
    """A sliding contact whose pass-1 spring pulls (``tension``: its friction load opened it),
    open in pass 2 where it penetrates again (``closing``), having changed between open and
    closed ``flips`` times in the step: the lag of pass 3."""
    stiffness = np.full(1, STIFFNESS)
    memory = np.zeros((1, 3))
    lag, lag_error = np.array([lag0]), np.zeros(1)
    changes = np.array([flips], dtype=np.int64)
    for k, (state, spring) in enumerate(((SLIP, tension), (OPEN, closing)), start=1):
        states = np.array([state], dtype=np.int8)
        gap = np.array([spring / STIFFNESS])
        t_n = np.minimum(gap * STIFFNESS, 0.0)
        if rule == "numpy":
            lag, lag_error = next_lag(states, gap, stiffness, t_n, lag, lag_error, memory, k,
                                      0, remember, changes)
        else:
            lag, lag_error = next_lag_force(states, gap, stiffness, t_n, lag, lag_error, memory,
                                            k, LAG_RELAX_AFTER, 0, remember, changes)
    return lag[0]


@pytest.mark.parametrize("rule", ["numpy", "kernel"])
def test_a_contact_its_own_tension_opened_closes_again_on_half_its_lag(rule):
    """The fully implicit predictor's lag memory: a contact that has cycled between open and
    closed (``REMEMBER_FROM_FLIPS`` changes) takes ``(N_lag + p g) / 2`` of its last closed
    pass when it closes again (here (-1e5 + 2e4) / 2), not the spring force of the open
    pass's penetration (-3e5, which loads its friction up and opens it again)."""
    assert _through_an_open_pass(rule, True) == pytest.approx(-4e4, rel=1e-15)
    # a tension above the lagged force leaves no compression to take back
    assert _through_an_open_pass(rule, True, tension=3e5) == 0.0
    # its first cycle keeps the plain rule (the 60 x 60 stack's bouncing contacts)
    assert _through_an_open_pass(rule, True, flips=REMEMBER_FROM_FLIPS - 2) == -3e5
    # legacy DDA keeps the plain rule (its see-saw, benchmarks/README.md)
    assert _through_an_open_pass(rule, False) == -3e5


@pytest.mark.parametrize("remember", [False, True])
def test_the_lag_memory_keeps_the_last_closed_pass(remember):
    """With the memory an open pass does not overwrite what the last closed pass left;
    without it (legacy DDA) it does, as before (numpy and compiled alike)."""
    for rule in ("numpy", "kernel"):
        memory = np.zeros((1, 3))
        args = (np.array([OPEN], dtype=np.int8), np.array([-1e-6]), np.full(1, STIFFNESS),
                np.array([-1e4]), np.zeros(1), np.zeros(1), memory)
        memory[0] = (-7.0, 5.0, 1.0)
        flips = np.array([REMEMBER_FROM_FLIPS], dtype=np.int64)
        if rule == "numpy":
            next_lag(*args, 4, LAG_SECANT_FROM, remember, flips)
        else:
            next_lag_force(*args, 4, LAG_RELAX_AFTER, LAG_SECANT_FROM, remember, flips)
        expected = (-7.0, 5.0, 1.0) if remember else (0.0, -1e4, 0.0)
        np.testing.assert_array_equal(memory[0], expected)
