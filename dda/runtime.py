"""What a run needs from its process: SIGTERM as Ctrl-C, and one BLAS thread.

- SIGTERM raises ``KeyboardInterrupt`` during a run, so a killed job (a cluster's time limit)
  writes its checkpoint and its last frames.
- BLAS runs on ``BLAS_THREADS`` (1) threads: a step's dense work is small, and more threads
  only wait for each other, or for other processes (a sweep's workers). Legacy steps of the
  stacks of ``benchmarks/stacks.py`` on two cores, one thread against two: 2 x 2, 1.9 against
  3.0 ms; 10 x 10, 16.7-20.3 against 17.8-23.4 ms; 30 x 30, 329 against 335 ms.
"""

from __future__ import annotations

import functools
import signal
import threading
from contextlib import contextmanager

__all__ = ["BLAS_THREADS", "blas_threads", "run_environment", "sigterm_as_interrupt"]

BLAS_THREADS = 1


@contextmanager
def run_environment():
    """SIGTERM as Ctrl-C and ``BLAS_THREADS`` BLAS threads within the block."""
    with sigterm_as_interrupt(), _blas().limit(limits=BLAS_THREADS, user_api="blas"):
        yield


def blas_threads():
    """Context manager: ``BLAS_THREADS`` BLAS threads within the block (threadpoolctl; a
    sweep's case, :func:`dda.studies.sweep.run_case`)."""
    return _blas().limit(limits=BLAS_THREADS, user_api="blas")


@functools.cache
def _blas():
    """The process's thread pools (found once: about 1 ms; limiting them then costs 5 us).

    MKL, which the sparse solver PARDISO brings, is loaded first so that it is among them:
    found after it, PARDISO ran on every core, and on a loaded two-core machine a
    factorization of the 30 x 30 stack took 34 ms instead of 3-7 ms."""
    from threadpoolctl import ThreadpoolController

    from dda.solvers.sparse_factor import default_backend

    default_backend()  # loads MKL when PARDISO is the backend
    return ThreadpoolController()


@contextmanager
def sigterm_as_interrupt():
    """Within the block, SIGTERM raises ``KeyboardInterrupt`` (main thread only; elsewhere
    signals cannot be handled and nothing changes). The old handler is restored after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt(f"signal {signum}")

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
