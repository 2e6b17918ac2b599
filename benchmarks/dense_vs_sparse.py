"""Where a dense solve stops beating a sparse one: the step's linear system of brick walls.

Run:  python benchmarks/dense_vs_sparse.py
Prints assembly + solve time of the same system by the number of unknowns, one BLAS thread:
dense (LAPACK), sparse with a one-off factorization (the default backend of
dda.solvers.sparse_factor: symbolic analysis and numeric factorization), and sparse with the
symbolic analysis kept from an earlier matrix of the same pattern, as a run does;
dda.solvers.linear.DENSE_LIMIT is set from this.
"""

from __future__ import annotations

import time

import numpy as np
from step_cost import wall
from threadpoolctl import threadpool_limits

import dda
from dda.solvers import linear, open_close
from dda.solvers.sparse_factor import default_backend, make_factor


def capture_system(scene):
    """The arguments of the last assemble_and_solve call of a short run."""
    captured = {}
    original = open_close.assemble_and_solve

    def spy(*args, **kwargs):
        captured["args"] = args
        return original(*args, **kwargs)

    open_close.assemble_and_solve = spy
    try:
        dda.Simulation(scene, dt=1e-3).run(duration=0.005, progress=False)
    finally:
        open_close.assemble_and_solve = original
    return captured["args"][:8]  # without the pattern: each path builds its own


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * min(times)


def main():
    limit = linear.DENSE_LIMIT
    threadpool_limits(1)
    try:
        print(f"sparse solver: {default_backend()}")
        print(f"{'unknowns':>9} {'dense ms':>9} {'sparse ms':>10} {'analysed ms':>12}")
        for rows, cols in [(2, 4), (4, 5), (5, 8), (6, 8), (8, 8), (10, 10), (20, 20)]:
            args = capture_system(wall(rows, cols))
            n = 6 * int(np.count_nonzero(args[2]))
            linear.DENSE_LIMIT = 10**9
            dense = best_of(lambda a=args: linear.assemble_and_solve(*a), 3 if n > 2000 else 10)
            linear.DENSE_LIMIT = 0
            sparse = best_of(lambda a=args: linear.assemble_and_solve(*a), 10)
            factor = make_factor(symmetric=True)
            linear.assemble_and_solve(*args, factor=factor)

            def numeric_only(a=args, f=factor):
                f.__dict__.pop("_last", None)  # forget the numeric factorization only
                if "_values" in f.__dict__:
                    f._values = None
                linear.assemble_and_solve(*a, factor=f)

            analysed = best_of(numeric_only, 10)
            print(f"{n:9d} {dense:9.3f} {sparse:10.3f} {analysed:12.3f}")
    finally:
        linear.DENSE_LIMIT = limit
    print(f"DENSE_LIMIT = {limit} unknowns")


if __name__ == "__main__":
    main()
