"""What a run needs from its process: Ctrl-C and SIGTERM acted on between steps, and one BLAS
thread.

- Ctrl-C (SIGINT) and SIGTERM during a run are noted and raise ``KeyboardInterrupt`` at the
  end of the step under way, so a killed job (a cluster's time limit) writes its checkpoint
  and its last frames. Raised where the signal lands, the interrupt could come inside a
  compiled kernel's call back into Python (numba unpickling a constant), which turns it into
  a ``SystemError`` and a traceback. A second signal before the step ends stops at once.
- BLAS runs on ``BLAS_THREADS`` (1) threads: a step's dense work is small, and more threads
  only wait for each other, or for other processes (a sweep's workers). Legacy steps of the
  stacks of ``benchmarks/stacks.py`` on two cores, one thread against two: 2 x 2, 1.9 against
  3.0 ms; 10 x 10, 16.7-20.3 against 17.8-23.4 ms; 30 x 30, 329 against 335 ms.
"""

from __future__ import annotations

import functools
import os
import signal
import threading
from contextlib import contextmanager

__all__ = ["BLAS_THREADS", "Interrupts", "blas_threads", "deferred_interrupts", "run_environment",
           "sigterm_as_interrupt", "usable_cores"]

BLAS_THREADS = 1


def usable_cores() -> int:
    """The cores this process may run on: its CPU affinity (a batch job's allocation, a
    ``taskset``), not the machine's count, which ``os.cpu_count()`` gives (a sweep on one core
    of two started two workers, each then at half speed)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # not on Linux
        return os.cpu_count() or 1


@contextmanager
def run_environment():
    """Ctrl-C and SIGTERM deferred to the end of a step (:func:`deferred_interrupts`; the
    block gets its :class:`Interrupts`) and ``BLAS_THREADS`` BLAS threads within the block."""
    with deferred_interrupts() as interrupts, _blas().limit(limits=BLAS_THREADS,
                                                            user_api="blas"):
        yield interrupts


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


class Interrupts:
    """The signal noted during a run (None: none yet); :meth:`check` raises it."""

    def __init__(self):
        self.signal = None

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if a signal came (call it between steps)."""
        if self.signal is not None:
            raise KeyboardInterrupt(f"signal {self.signal}")


@contextmanager
def deferred_interrupts():
    """Within the block, Ctrl-C and SIGTERM only note themselves in the :class:`Interrupts`
    the block gets (the run checks it after each step); a second one raises
    ``KeyboardInterrupt`` at once. Main thread only: elsewhere signals cannot be handled and
    nothing changes. The old handlers are restored after."""
    interrupts = Interrupts()
    if threading.current_thread() is not threading.main_thread():
        yield interrupts
        return

    def note(signum, frame):
        if interrupts.signal is not None:
            raise KeyboardInterrupt(f"signal {signum}")
        interrupts.signal = signum

    previous = {s: signal.signal(s, note) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield interrupts
    finally:
        for s, handler in previous.items():
            if handler is not None:  # (None: a handler not set from Python; left as is)
                signal.signal(s, handler)
