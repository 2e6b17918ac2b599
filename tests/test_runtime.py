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


def test_a_run_limits_mkl_too_when_pardiso_solves():
    """MKL comes with the sparse solver PARDISO and is loaded lazily: it must still be among
    the limited pools (found after the pools were listed, PARDISO ran on every core)."""
    from dda.solvers.sparse_factor import default_backend

    if default_backend() != "pardiso":
        pytest.skip("PARDISO is not the sparse solver here")
    from threadpoolctl import threadpool_info

    scene, _, _ = shaken_block_scene(phi=20, amplitude=6.0)
    seen = set()

    def mkl_threads(state, report):
        seen.update(p["num_threads"] for p in threadpool_info() if p["internal_api"] == "mkl")

    dda.Simulation(scene, dt=1e-3).run(0.003, callback=mkl_threads)
    assert seen == {BLAS_THREADS}
