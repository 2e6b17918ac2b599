"""Where a dense solve stops beating a sparse one: the step's linear system of brick walls.

Run:  python benchmarks/dense_vs_sparse.py
Prints assembly + solve time of the same system, dense (LAPACK) and sparse (SuperLU), by the
number of unknowns; dda.solvers.linear.DENSE_LIMIT is set from this.
"""

from __future__ import annotations

import time

import numpy as np
from step_cost import wall

import dda
from dda.solvers import legacy, linear


def capture_system(scene):
    """The arguments of the last assemble_and_solve call of a short run."""
    captured = {}
    original = legacy.assemble_and_solve

    def spy(*args):
        captured["args"] = args
        return original(*args)

    legacy.assemble_and_solve = spy
    try:
        dda.Simulation(scene, dt=1e-3).run(duration=0.005, progress=False)
    finally:
        legacy.assemble_and_solve = original
    return captured["args"]


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * min(times)


def main():
    limit = linear.DENSE_LIMIT
    try:
        print(f"{'unknowns':>9} {'dense ms':>9} {'sparse ms':>10}")
        for rows, cols in [(2, 4), (4, 5), (5, 8), (8, 8), (10, 10), (20, 20)]:
            args = capture_system(wall(rows, cols))
            n = 6 * int(np.count_nonzero(args[2]))
            linear.DENSE_LIMIT = 10**9
            dense = best_of(lambda a=args: linear.assemble_and_solve(*a), 3 if n > 2000 else 10)
            linear.DENSE_LIMIT = 0
            sparse = best_of(lambda a=args: linear.assemble_and_solve(*a), 10)
            print(f"{n:9d} {dense:9.3f} {sparse:10.3f}")
    finally:
        linear.DENSE_LIMIT = limit
    print(f"DENSE_LIMIT = {limit} unknowns")


if __name__ == "__main__":
    main()
