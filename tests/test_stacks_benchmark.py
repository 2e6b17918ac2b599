"""The stacks benchmark's passes-by-changes table (``benchmarks/stacks.py``)."""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from stacks import passes_by_changes  # noqa: E402


def test_passes_binned_by_the_first_pass_changes():
    # three steps: 1 pass (nothing switched), 2 passes (2 closed, then settled), 3 passes
    # (5 opened + 7 stick-slip switches first)
    log = np.array([[0, 0, 0, 0],
                    [2, 0, 0, 0], [0, 0, 0, 0],
                    [0, 5, 7, 1], [1, 0, 0, 0], [0, 0, 0, 0]])
    bins = passes_by_changes(log, np.array([1, 2, 3]))
    assert bins == [[1, 1.0], [1, 2.0], [0, None], [1, 3.0]]


def test_a_log_that_is_not_the_steps_is_not_binned():
    # a cut step's passes are logged but not counted in the committed steps
    log = np.zeros((4, 4), dtype=int)
    assert passes_by_changes(log, np.array([1, 2])) is None
