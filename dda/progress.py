"""A progress bar for long runs, as a callback of :meth:`dda.Simulation.run`."""

from __future__ import annotations

import sys
import time as _time

__all__ = ["ProgressBar"]


class ProgressBar:
    """A minimal progress bar on stderr (no dependency): simulated time, share, time left.

    Call it with the committed :class:`dda.step.StepState` after every step; ``close()`` ends
    the line.
    """

    def __init__(self, t_end, t_start):
        self.t_end, self.t_start = t_end, t_start
        self.start = _time.perf_counter()
        self.last = 0.0

    def __call__(self, state, report=None):
        t = state.time
        now = _time.perf_counter()
        if now - self.last < 0.2 and t < self.t_end:
            return
        self.last = now
        frac = (t - self.t_start) / (self.t_end - self.t_start)
        bar = "#" * int(30 * frac)
        eta = (now - self.start) * (1 - frac) / max(frac, 1e-9)
        sys.stderr.write(f"\r  t = {t:9.4f} s [{bar:<30}] {100 * frac:5.1f}%  eta {eta:6.1f} s")
        sys.stderr.flush()

    def close(self):
        sys.stderr.write("\n")
        sys.stderr.flush()
