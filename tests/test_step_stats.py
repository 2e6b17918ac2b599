"""Per-step statistics in bounded memory (dda.result.StepStats; issue 21, item 4): compact
columns, timings summed per recorded interval, the same numbers read back."""

import tracemalloc

import numpy as np
import pytest

import dda
from dda.profiling import SECTIONS
from dda.result import StepStats
from tests import checkpoint_scene as cs


def _row(i, contacts=120, **extra):
    row = dict(time=i * 1e-3, dt=1e-3, iterations=2, open_close_passes=3, contacts=contacts,
               closed=80, sliding=5, retries=0, wall_time=1e-4 + 1e-7 * (i % 7), solves=4,
               unknowns=600, pairs=50, penetration=1e-5, spring_penetration=2e-5,
               **{f"{name}_time": 1e-5 * (1 + k) for k, name in enumerate(SECTIONS)})
    row.update(extra)
    return row


def test_thirty_thousand_steps_recorded_every_thousandth_hold_under_2_mb():
    """The issue's measure: a 30,000-step run with record_every=1000 (Newton's two residual
    norms a step) holds under 2 MB of statistics (the lists of dicts held 0.55 MiB a 1,000
    steps: 16 MB)."""
    stats = StepStats(timing_every=1000)
    rows = [tuple(_row(i, contacts=30_000)[k] for k in StepStats.FIELDS)
            for i in range(256)]
    tracemalloc.start()
    for i in range(30_000):
        stats.append_row(rows[i % 256], (1.0, 1e-3))
    assert len(stats) == 30_000
    current, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert stats.nbytes < 2e6, stats.nbytes
    assert current < 2e6, current


def test_the_rows_read_back_as_they_were_appended():
    stats = StepStats()
    big = [7, 300, 70_000, 5_000_000_000]  # counts that need wider integers as they come
    for i in range(600):
        stats.append(residual_norms=[1.0 / (i + 1)] * (i % 3), **_row(
            i, contacts=big[min(i // 150, 3)]))
    assert len(stats) == 600
    np.testing.assert_array_equal(stats["time"], np.arange(600) * 1e-3)
    assert stats["contacts"].dtype == np.int64
    np.testing.assert_array_equal(stats["contacts"], np.repeat(big, 150))
    np.testing.assert_array_equal(stats.iterations, 2)
    # float32 columns to their precision, the timings per step when each step is recorded
    np.testing.assert_allclose(stats["penetration"], 1e-5, rtol=1e-7)
    np.testing.assert_allclose(stats["wall_time"], 1e-4 + 1e-7 * (np.arange(600) % 7),
                               rtol=1e-7)
    norms = stats.residual_norms
    assert [len(n) for n in norms[:4]] == [0, 1, 2, 0]
    np.testing.assert_allclose(norms[5], [1.0 / 6] * 2, rtol=1e-7)
    with pytest.raises(KeyError, match="no statistic 'nope'"):
        stats["nope"]
    with pytest.raises(ValueError, match="must not be negative"):
        stats.append(**_row(0, contacts=-1))
        len(stats.contacts)


@pytest.mark.parametrize("every, steps", [(10, 95), (256, 600), (1000, 300)])
def test_timings_of_an_interval_are_its_mean_per_step_and_exact_in_sum(every, steps):
    stats = StepStats(timing_every=every)
    for i in range(steps):
        stats.append(**_row(i))
    wall = 1e-4 + 1e-7 * (np.arange(steps) % 7)
    got = stats["wall_time"]
    assert len(got) == steps
    assert got.sum() == pytest.approx(wall.sum(), rel=1e-7)
    closed = steps // every * every
    means = wall[:closed].reshape(-1, every).mean(axis=1)
    np.testing.assert_allclose(got[:closed], np.repeat(means, every), rtol=1e-7)
    np.testing.assert_allclose(got[closed:], wall[closed:].mean(), rtol=1e-7)


def test_a_run_recording_every_tenth_step_keeps_a_row_a_step(tmp_path):
    sim = cs.simulation()
    sim.record_every = 10
    result = sim.run(0.1)
    st = result.stats
    assert len(st) == 50 and len(result.time) == 6  # the start and every 10th step
    np.testing.assert_allclose(st["time"], (np.arange(50) + 1) * cs.DT, rtol=1e-12)
    profile = result.profile()
    assert profile.wall == pytest.approx(float(st["wall_time"].sum()))
    assert profile.solves == int(st["solves"].sum()) >= 50
    assert isinstance(dda.Result, type)
