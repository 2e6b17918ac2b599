"""The cut-rate benchmark's table and one short run (``benchmarks/cut_rate.py``)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from cut_rate import _table, one_run  # noqa: E402


def _row(solver, seed, steps, cuts, tries):
    return dict(solver=solver, seed=seed, blocks=300, seconds=10.0, steps=steps, cuts=cuts,
                tries=tries, early_steps=100, early_cuts=5, passes=6.0, cpu=10.0,
                moved_mm=400.0)


def test_pooled_share_is_cuts_over_steps_not_the_mean_of_shares():
    rows = [_row("legacy", 0, 1000, 10, 4), _row("legacy", 1, 9000, 30, 10)]
    lines = _table(rows)
    assert "| 1.00% | 4 / 6 |" in lines[2]  # 10 of 1,000
    assert "| 0.33% | 10 / 20 |" in lines[3]
    pooled = lines[4]
    # 40 of 10,000 steps: 0.40%, where the mean of the two shares would be 0.67%
    assert "**0.40%** (per cut 0.33-1.00%)" in pooled and "| 14 / 26 |" in pooled
    # after the first 0.35 s: (10 - 5) of (1,000 - 100) steps
    assert "| 0.56% |" in lines[2]


def test_a_short_run_counts_its_cuts():
    row = one_run("legacy", 1, 0.01, auto=True)
    assert row["steps"] > 0 and 0 <= row["tries"] <= row["cuts"]
    assert row["early_cuts"] == row["cuts"] and row["early_steps"] == row["steps"]
    assert row["penalty"] == 2e10 and row["dt"] < 2e-3  # the rule's floor, not 5e10
