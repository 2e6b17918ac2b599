"""The moving base's error near each cell of accuracy_cost.py, slip reversals located or not.

One run of the block on a moving base (``dda.studies.MovingBase``: 1 s of 1 g, 2 Hz
shaking, error the largest gap of the slip history to the analytical stick-slip solution
over its peak) is one sample of a function of dt that jumps from step size to step size:
where the block's onset of slip and its stops fall inside a step decides the error, and a
change of dt by 3% moves them. So a cell of ``benchmarks/accuracy_cost.py`` that got worse
or better may have moved within that spread. This runs each moving-base cell at

    dt x {0.9, 0.95, 0.97, 1, 1.03, 1.05, 1.1}

with ``Simulation(locate_reversals=False)`` and ``True`` (:mod:`dda.slip_events`) and
prints, per solver, dt and penalty, the error at the cell's own dt and the median and
largest error over the seven.

Run:  python benchmarks/reversal_spread.py [--workers N] [--steps 1e-2,3e-3,...]
(about 2 minutes on 2 cores; the 1e-4 cells are most of it). Writes
``benchmarks/results/reversal_spread.md`` (or ``--out``).
"""

from __future__ import annotations

import argparse
import itertools
import os
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from dda.studies.studies import MovingBase

STEPS = (1e-2, 3e-3, 1e-3, 3e-4, 1e-4)
PENALTIES = (2e7, 2e8, 2e9, 2e10)
SOLVERS = ("legacy", "newton")
FACTORS = (0.9, 0.95, 0.97, 1.0, 1.03, 1.05, 1.1)
HERE = Path(__file__).resolve().parent


def error(job):
    """The moving base's relative error for ``(solver, dt, penalty, locate)``."""
    solver, dt, penalty, locate = job
    sim, duration, measure = MovingBase().prepare(solver, dt, penalty)
    sim.locate_reversals = locate
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the penalty advice of the stiff cells
        return measure(sim.run(duration, progress=False))["error"]


def table(errors, steps):
    """Markdown rows: each cell's error at its dt and over the seven dts, both ways."""
    head = ("| solver | dt | penalty | at dt: not located | located | median of 7: not located "
            "| located | largest of 7: not located | located |\n|---|---|---|---|---|---|---|---"
            "|---|")
    rows = [head]
    for solver, dt, penalty in itertools.product(SOLVERS, steps, PENALTIES):
        cells = []
        for pick in (lambda e: e[FACTORS.index(1.0)], np.median, np.max):
            for locate in (False, True):
                e = [errors[(solver, dt * f, penalty, locate)] for f in FACTORS]
                cells.append(f"{100 * pick(e):.3f}%")
        rows.append(f"| {solver} | {dt:g} | {penalty:.0e} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=os.cpu_count(), help="local processes")
    ap.add_argument("--steps", default=",".join(f"{s:g}" for s in STEPS),
                    help="the cells' dt, comma-separated")
    ap.add_argument("--out", default=str(HERE / "results"), help="output folder")
    args = ap.parse_args(argv)
    steps = tuple(float(s) for s in args.steps.split(","))
    jobs = list(itertools.product(SOLVERS, [dt * f for dt in steps for f in FACTORS],
                                  PENALTIES, (False, True)))
    jobs.sort(key=lambda j: j[1])  # the longest runs first
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        errors = dict(zip(jobs, pool.map(error, jobs), strict=True))
    elapsed = time.perf_counter() - start
    text = table(errors, steps)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "reversal_spread.md").write_text(
        f"# The moving base's error near each accuracy_cost cell\n\n{len(jobs)} runs in "
        f"{elapsed:.0f} s, dt x {FACTORS}, `python benchmarks/reversal_spread.py`.\n\n"
        + text + "\n")
    print(text)
    print(f"{len(jobs)} runs in {elapsed:.0f} s; wrote {out / 'reversal_spread.md'}")
    return errors


if __name__ == "__main__":
    main()
