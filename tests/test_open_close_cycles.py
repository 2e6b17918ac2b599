"""OPEN-CLOSE ends where a contact would only cycle between open and closed."""

from __future__ import annotations

import numpy as np

import dda
from dda.solvers import LegacyPullBack
from tests.conftest import stack_scene


def test_a_touching_contact_does_not_cycle_until_the_pass_limit():
    """The 10 x 10 stack of benchmarks/stacks.py, legacy, dt 1e-3: at t = 10 ms one vertex
    of a side joint pulled 6.4e-10 m (6.4 N) closed and penetrated 1.7e-9 m (17 N) open, and
    OPEN-CLOSE switched it 30 times, then cut the step. It now stays closed: no cut, and no
    step needs more than a few passes."""
    sim = dda.Simulation(stack_scene(10), dt=1e-3, solver=LegacyPullBack(), max_open_close=30)
    r = sim.run(0.012, progress=False)
    assert r.stats.cuts == []
    assert np.max(r.stats["open_close_passes"]) <= 8
