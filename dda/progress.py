"""A progress bar for long runs (tqdm), as a callback of :meth:`dda.Simulation.run`.

It shows the simulated time against the run's end, the time left, and what says whether a run
is slow or stalled: the step size ``dt`` now, the steps cut so far, and the OPEN-CLOSE passes
and solves a step (over the last update).
"""

from __future__ import annotations

import sys
import time

from tqdm import tqdm

__all__ = ["ProgressBar"]

#: seconds between two steps below which a note on the first steps' slowness is dropped
NOTE_UNTIL = 1.0


class ProgressBar:
    """Simulated time from ``t_start`` to ``t_end`` on stderr; ``stats`` (the run's
    :class:`dda.result.StepStats`, optional) gives the cuts.

    Call it with the committed :class:`dda.step.StepState` and its report after every step;
    ``close()`` ends the line. ``note`` is shown beside the bar until two steps come within
    ``NOTE_UNTIL`` s of each other (the first run of an install, which compiles the kernels
    as its first steps call them, says so: the README demo's first two steps took 47 and
    22 s on a fresh clone).
    """

    def __init__(self, t_end, t_start, stats=None, file=None, note: str = ""):
        self.t_end, self.t_start, self.stats = t_end, t_start, stats
        self.last_time = t_start
        self.passes = self.steps = 0
        self.note = note
        self.last_call = time.perf_counter()
        self.bar = tqdm(total=t_end - t_start, initial=0.0, unit="s", unit_scale=False,
                        file=file or sys.stderr, desc=f"t ({note})" if note else "t",
                        mininterval=0.2, leave=True,
                        bar_format="{desc} {n:.4f}/{total:.4f} s |{bar}| {percentage:3.0f}% "
                                   "[{elapsed}<{remaining}{postfix}]")

    def __call__(self, state, report=None, steps: int = 1):
        """After ``steps`` committed steps (one, or a batch of :mod:`dda.compiled_run`;
        ``report.open_close_passes`` their passes). The ``dt`` shown is a step's: the time
        advanced over ``steps`` (a batch's steps are all of one size)."""
        advanced = state.time - self.last_time
        dt = advanced / max(steps, 1)
        self.last_time = state.time
        self.steps += steps
        if self.note:
            now = time.perf_counter()
            if now - self.last_call < NOTE_UNTIL:
                self.note = ""
                self.bar.set_description_str("t", refresh=False)
            self.last_call = now
        if report is not None:
            self.passes += report.open_close_passes
        self.bar.set_postfix_str(
            f"dt {dt:.3g} s, {len(self.stats.cuts) if self.stats is not None else 0} cut, "
            f"{self.passes / self.steps:.1f} passes/step", refresh=False)
        self.bar.update(advanced)

    def close(self):
        self.bar.close()
