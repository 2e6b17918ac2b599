"""A run's process settings: one BLAS thread during the run, restored after."""

import pytest

import dda
from dda.runtime import BLAS_THREADS
from tests.conftest import shaken_block_scene

threadpoolctl = pytest.importorskip("threadpoolctl")


def _blas_threads():
    return {p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"}


def test_a_run_uses_one_blas_thread_and_gives_the_rest_back():
    scene, _, _ = shaken_block_scene(phi=20, amplitude=6.0)
    before = _blas_threads()
    seen = set()
    dda.Simulation(scene, dt=1e-3).run(0.005, callback=lambda s, r: seen.update(_blas_threads()))
    assert seen == {BLAS_THREADS}
    assert _blas_threads() == before
