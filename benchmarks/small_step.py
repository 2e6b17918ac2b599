"""The fixed cost of one step on a 2-block scene (issue 19): a block sliding down an incline.

Run:  python benchmarks/small_step.py [--steps N] [--warmup N] [--record-every N] [--calls]
                                      [--profile K] [--step-by-step]

For both solvers it prints, after a warm-up run:

- ``step``: the median of ``result.stats['wall_time']`` (the step itself: detection, element,
  solver, guard, the Newmark update, and the commit's bookkeeping around it; a step of a
  batch taken in one kernel call, :mod:`dda.compiled_run`, its share of the batch);
- ``loop``: the run's wall time divided by its steps (everything a user pays: the step, the
  recording of every step into the Result, the stats row, the penalty advice);
- ``cpu``: the run's process time divided by its steps;
- with ``--calls``: the Python function calls per step (cProfile, recording included);
- with ``--profile K``: the top K functions by own time, in microseconds per step.

A run takes its steps in batches in one kernel call where it can (:mod:`dda.compiled_run`);
``--step-by-step`` turns that off (``dda.compiled_run.COMPILED_RUN = False``), for the steps
one :func:`dda.step.step` call at a time.

The seed rock slope of the paper runs 160,000 steps (dt 1e-4, 16 s): ``loop`` times 160,000
is what a 2-block scene of it would take.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from pathlib import Path

import numpy as np

import dda
from dda.contact import CoulombSingle

SEED_STEPS = 160_000


def incline():
    """A 0.3 m block kicked down a fixed 30 degree incline at 1 m/s with phi 30 degrees (it
    slides on at about that speed), joint penalty 1e10: ``tests/stability/scenes.py``'s."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from tests.stability.scenes import incline as scene

    return scene(CoulombSingle(phi=30.0))[0]


def measure(solver, steps, warmup, dt=1e-4, record_every=1):
    """(step median, loop per step, cpu per step) in seconds, and the simulation."""
    sim = dda.Simulation(incline(), dt=dt, solver=solver, record_every=record_every)
    sim.run(duration=warmup * dt, progress=False)
    t0, c0 = time.perf_counter(), time.process_time()
    result = sim.run(duration=steps * dt, progress=False)
    t1, c1 = time.perf_counter(), time.process_time()
    n = len(result.stats)
    return float(np.median(result.stats["wall_time"])), (t1 - t0) / n, (c1 - c0) / n, sim


def profile(sim, steps, top):
    """Calls per step, and the ``top`` functions by own time (us per step)."""
    prof = cProfile.Profile()
    prof.enable()
    result = sim.run(duration=steps * sim.dt, progress=False)
    prof.disable()
    n = len(result.stats)
    st = pstats.Stats(prof)
    rows = []
    for (file, line, func), (_, ncalls, tottime, cumtime, _) in st.stats.items():
        rows.append((tottime, cumtime, ncalls, f"{file.split('/')[-1]}:{line}({func})"))
    rows.sort(reverse=True)
    return st.total_calls / n, [(1e6 * t / n, 1e6 * c / n, k / n, name)
                                for t, c, k, name in rows[:top]]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--warmup", type=int, default=200)
    ap.add_argument("--record-every", type=int, default=1,
                    help="record every this many steps (default: every step, as a run does)")
    ap.add_argument("--calls", action="store_true", help="count the Python calls per step")
    ap.add_argument("--profile", type=int, default=0, metavar="K",
                    help="print the K functions with the most own time")
    ap.add_argument("--step-by-step", action="store_true",
                    help="every step through dda.step.step (no batches in one kernel call)")
    args = ap.parse_args(argv)
    if args.step_by_step:
        from dda import compiled_run

        compiled_run.COMPILED_RUN = False
    print(f"2-block incline, dt 1e-4, {args.steps} steps after {args.warmup} of warm-up, "
          f"recording every {args.record_every}"
          + (", step by step" if args.step_by_step else ""))
    for make in (dda.solvers.LegacyPullBack, dda.solvers.NewtonRaphson):
        step, loop, cpu, sim = measure(make(), args.steps, args.warmup,
                                       record_every=args.record_every)
        line = (f"{sim.solver.name:7s} step {1e6 * step:7.1f} us  loop {1e6 * loop:7.1f} us  "
                f"cpu {1e6 * cpu:7.1f} us  (x {SEED_STEPS:,}: {loop * SEED_STEPS:5.0f} s)")
        if args.calls or args.profile:
            calls, top = profile(sim, min(args.steps, 1000), args.profile)
            line += f"  {calls:6.0f} calls/step"
        print(line)
        for own, cum, ncalls, name in top if args.profile else ():
            print(f"    {own:7.1f} us own {cum:8.1f} us cum {ncalls:6.1f}x  {name}")


if __name__ == "__main__":
    main()
