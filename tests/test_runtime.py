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


@pytest.mark.parametrize("name", ["SIGINT", "SIGTERM"])
def test_a_signal_stops_the_run_after_the_step_under_way(monkeypatch, name):
    """A signal that lands inside a step (here: in the middle of dda.step.step) lets the step
    finish and stops the run after it: raised where it lands, it could come inside a compiled
    kernel's call back into Python and turn into a SystemError (seen under load)."""
    import os
    import signal

    import dda.simulation

    scene, _, _ = shaken_block_scene(phi=20, amplitude=6.0)
    sim = dda.Simulation(scene, dt=1e-3)
    real_step = dda.simulation.step
    finished = []

    def step_with_a_signal(*args, **kwargs):
        if len(finished) == 3:
            os.kill(os.getpid(), getattr(signal, name))
        out = real_step(*args, **kwargs)
        finished.append(out[0] is not None)
        return out

    monkeypatch.setattr(dda.simulation, "step", step_with_a_signal)
    # (the handler the process had: Python's default, or SIG_IGN when it was started as a
    # background job of a shell without job control)
    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt, match=f"signal {int(getattr(signal, name))}"):
        sim.run(0.05)
    assert len(finished) == 4 and all(finished)
    assert sim.committed.time == pytest.approx(4e-3, rel=1e-12)
    assert signal.getsignal(signal.SIGINT) is before


def test_a_second_signal_stops_at_once(monkeypatch):
    import os
    import signal

    import dda.simulation

    scene, _, _ = shaken_block_scene(phi=20, amplitude=6.0)
    sim = dda.Simulation(scene, dt=1e-3)
    real_step = dda.simulation.step
    finished = []

    def step_with_two_signals(*args, **kwargs):
        if len(finished) == 3:
            os.kill(os.getpid(), signal.SIGTERM)
            os.kill(os.getpid(), signal.SIGTERM)
        out = real_step(*args, **kwargs)
        finished.append(True)
        return out

    monkeypatch.setattr(dda.simulation, "step", step_with_two_signals)
    with pytest.raises(KeyboardInterrupt):
        sim.run(0.05)
    assert len(finished) == 3 and sim.committed.time == pytest.approx(3e-3, rel=1e-12)
