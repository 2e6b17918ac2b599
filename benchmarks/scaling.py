"""How a step's cost grows with the number of blocks, against the floor of one sparse solve.

Two generated assemblies settle under gravity:

- ``wall``: a running-bond brick wall (0.4 x 0.2 m bricks) on a fixed base;
- ``slope``: a jointed rock slope, parallelogram blocks cut by horizontal bedding (0.5 m) and
  cross joints dipping 70 degrees (1 m), rows stepping back into a staircase face, on a fixed
  base;

at about 100, 1,000 and 10,000 blocks, under both solvers. Each run is a fresh process (so its
peak memory is its own) that takes ``--warm`` steps, then times ``--steps`` steps. Per run:

- time per step (median) and where it goes (:mod:`dda.profiling`);
- contacts, linear solves per step;
- the floor: one bare factorization and solve of the step's last linear system, done the way
  dda does it (SuperLU, symmetric mode; median of 3), and the step's time divided by it; and
  for comparison scipy's default ``spsolve`` on the same matrix;
- peak resident memory of the process above its size after the imports (MB).

Then it fits time per step ~ blocks^p and memory ~ blocks^q and prints p and q, and the
2-block legacy rate (steps per second of a whole run, records included) against the target of
2,000.

Writes ``benchmarks/results/scaling.csv`` and ``scaling.md``.

Run:  python benchmarks/scaling.py [--sizes 100 1000 10000] [--steps 10] [--warm 3]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SOLVERS = ("legacy", "newton")


def box(x0, y0, w, h):
    return [(x0, y0), (x0 + w, y0), (x0 + w, y0 + h), (x0, y0 + h)]


def _materials():
    from dda.contact import CoulombSingle, JointMaterial
    from dda.materials import LinearElastic

    rock = LinearElastic(young=10e9, poisson=0.25, density=2500.0)
    joint = JointMaterial(normal_penalty=1e10, shear_penalty=1e10,
                          friction=CoulombSingle(phi=35.0))
    return rock, joint


def wall(n_blocks: int):
    """A running-bond wall of about ``n_blocks`` bricks, twice as wide as high in bricks."""
    import dda

    rock, joint = _materials()
    w, h = 0.4, 0.2
    rows = max(1, round(np.sqrt(n_blocks / 2)))
    cols = int(np.ceil(n_blocks / rows))
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(-0.5, -0.3, cols * w + 1.5, 0.3), rock, fixed=True, name="base")
    placed = 0
    for r in range(rows):
        shift = 0.5 * w if r % 2 else 0.0
        for c in range(cols):
            if placed == n_blocks:
                break
            scene.add_block(box(shift + c * w, r * h, w, h), rock)
            placed += 1
    scene.set_joint(joint)
    return scene


def slope(n_blocks: int, dip: float = 70.0):
    """A staircase slope of about ``n_blocks`` parallelogram blocks (two joint sets)."""
    import dda

    rock, joint = _materials()
    w, h = 1.0, 0.5
    dx = h / np.tan(np.radians(dip))
    # row r holds cols - r blocks; rows = cols / 2 gives about 3 cols^2 / 8 blocks
    cols = max(2, round(np.sqrt(8 * n_blocks / 3)))
    rows = cols // 2
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(-1.0, -0.5, cols * w + 2.0, 0.5), rock, fixed=True, name="base")
    for r in range(rows):
        y0 = r * h
        for i in range(cols - r):
            x = i * w + r * dx
            scene.add_block([(x, y0), (x + w, y0), (x + w + dx, y0 + h), (x + dx, y0 + h)],
                            rock)
    scene.set_joint(joint)
    return scene


ASSEMBLIES = {"wall": wall, "slope": slope}


def rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: kB


def one(case: str, size: int, solver: str, steps: int, warm: int, dt: float,
        max_open_close: int) -> dict:
    """One run in this process (called in a subprocess by :func:`main`)."""
    import scipy.sparse.linalg as spla

    import dda
    from dda.solvers import linear
    from dda.solvers.sparse_factor import UpperTriangle, make_factor

    base_rss = rss_mb()
    t0 = time.perf_counter()
    scene = ASSEMBLIES[case](size)
    sim = dda.Simulation(scene, dt=dt,
                         solver={"legacy": dda.solvers.LegacyPullBack,
                                 "newton": dda.solvers.NewtonRaphson}[solver](),
                         max_open_close=max_open_close)
    setup = time.perf_counter() - t0
    last = {}
    solve = linear._solve

    def keep(k, rhs, factor=None, near=False):
        last["k"], last["rhs"] = k, rhs
        last["symmetric"] = bool(factor is not None and factor.symmetric)
        return solve(k, rhs, factor, near)

    linear._solve = keep
    sim.run(warm * dt, progress=False)
    result = sim.run(steps * dt, progress=False)
    linear._solve = solve
    st = result.stats
    floors, defaults = [], []
    k = last["k"]
    factor = None
    if not isinstance(k, np.ndarray):  # its symbolic analysis first, as a run keeps it
        factor = make_factor(symmetric=last["symmetric"])
        solve(k, last["rhs"], factor)
    for i in range(3):
        # the same pattern, other values: the numeric factorization and solve dda does
        k_i = k if factor is None else _scaled(k, 1.0 + 1e-12 * (i + 1))
        start = time.perf_counter()
        solve(k_i, last["rhs"], factor)
        floors.append(time.perf_counter() - start)
        start = time.perf_counter()
        if isinstance(k, np.ndarray):
            np.linalg.solve(k, last["rhs"])
        else:  # scipy's default ordering, for comparison
            spla.spsolve(k.full() if isinstance(k, UpperTriangle) else k, last["rhs"])
        defaults.append(time.perf_counter() - start)
    floor = float(np.median(floors))
    step = float(np.median(st["wall_time"]))
    prof = result.profile()
    return {
        "case": case, "blocks": sim.model.n_blocks - 1, "solver": solver, "steps": len(st),
        "unknowns": int(last["rhs"].size), "contacts": int(np.median(st["contacts"])),
        "closed": int(np.median(st["closed"])), "step_ms": 1e3 * step,
        "floor_ms": 1e3 * floor, "spsolve_ms": 1e3 * float(np.median(defaults)),
        "step_over_floor": step / floor,
        "solves_per_step": float(st["solves"].mean()),
        "dt_cuts": len(st.cuts), "setup_s": setup,
        "peak_mb": rss_mb() - base_rss,
        **{f"{k}_ms": 1e3 * v / max(len(st), 1) for k, v in prof.seconds.items()},
    }


def _scaled(k, factor: float):
    """A copy of the step's sparse matrix (or upper triangle) with its values scaled."""
    from dda.solvers.sparse_factor import UpperTriangle

    if isinstance(k, UpperTriangle):
        return UpperTriangle(k.csr * factor)
    return (k * factor).tocsc()


def two_block_rate(duration: float = 2.0) -> dict:
    """Steps per second of a whole 2-block legacy run (recording every step included)."""
    sys.path.insert(0, str(HERE))
    from step_cost import two_blocks

    import dda

    sim = dda.Simulation(two_blocks(), dt=1e-3, solver=dda.solvers.LegacyPullBack())
    sim.run(0.05, progress=False)
    start = time.perf_counter()
    result = sim.run(duration, progress=False)
    elapsed = time.perf_counter() - start
    return {"steps": len(result.stats), "seconds": elapsed,
            "steps_per_s": len(result.stats) / elapsed,
            "step_only_per_s": len(result.stats) / result.stats["wall_time"].sum()}


def fit_exponent(x, y) -> float:
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = (x > 0) & (y > 0)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[100, 1000, 10000])
    ap.add_argument("--cases", nargs="+", default=list(ASSEMBLIES), choices=list(ASSEMBLIES))
    ap.add_argument("--solvers", nargs="+", default=list(SOLVERS), choices=list(SOLVERS))
    ap.add_argument("--steps", type=int, default=8, help="timed steps per run")
    ap.add_argument("--warm", type=int, default=2, help="untimed steps first")
    ap.add_argument("--max-open-close", type=int, default=30,
                    help="OPEN-CLOSE passes before a cut (the Simulation default, 12, does not "
                         "settle the first step of a 1000-block slope)")
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--one", nargs=3, metavar=("CASE", "SIZE", "SOLVER"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        case, size, solver = args.one
        print(json.dumps(one(case, int(size), solver, args.steps, args.warm, args.dt,
                             args.max_open_close)))
        return None
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    header = (f"{'case':6s} {'blocks':>6s} {'solver':7s} {'contacts':>8s} {'ms/step':>9s} "
              f"{'floor ms':>9s} {'ratio':>6s} {'solves':>6s} {'MB':>7s}  biggest part")
    print(header)
    for case in args.cases:
        for size in args.sizes:
            for solver in args.solvers:
                cmd = [sys.executable, __file__, "--one", case, str(size), solver,
                       "--steps", str(args.steps), "--warm", str(args.warm), "--dt",
                       str(args.dt), "--max-open-close", str(args.max_open_close)]
                done = subprocess.run(cmd, capture_output=True, text=True, check=False)
                if done.returncode != 0:
                    print(f"{case} {size} {solver} failed:\n{done.stderr[-2000:]}")
                    continue
                r = json.loads(done.stdout.strip().splitlines()[-1])
                rows.append(r)
                parts = {k[:-3]: v for k, v in r.items() if k.endswith("_ms") and k not in
                         ("step_ms", "floor_ms", "spsolve_ms")}
                big = max(parts, key=parts.get)
                print(f"{case:6s} {r['blocks']:6d} {solver:7s} {r['contacts']:8d} "
                      f"{r['step_ms']:9.2f} {r['floor_ms']:9.2f} {r['step_over_floor']:6.2f} "
                      f"{r['solves_per_step']:6.2f} {r['peak_mb']:7.1f}  {big} "
                      f"{parts[big]:.2f} ms", flush=True)
    lines = []
    for case in args.cases:
        for solver in args.solvers:
            mine = [r for r in rows if r["case"] == case and r["solver"] == solver]
            if len(mine) < 2:
                continue
            p = fit_exponent([r["blocks"] for r in mine], [r["step_ms"] for r in mine])
            q = fit_exponent([r["blocks"] for r in mine], [r["peak_mb"] for r in mine])
            lines.append(f"{case} {solver}: time per step ~ blocks^{p:.2f}, "
                         f"peak memory ~ blocks^{q:.2f}")
    rate = two_block_rate()
    lines.append(f"2-block legacy run: {rate['steps_per_s']:.0f} steps/s with recording "
                 f"({rate['step_only_per_s']:.0f} steps/s in the steps alone); target 2000")
    print("\n".join(lines))
    from dda.studies.sweep import markdown_table, write_csv

    if rows:
        write_csv(rows, out / "scaling.csv")
    columns = ["case", "blocks", "solver", "unknowns", "contacts", "step_ms", "floor_ms",
               "spsolve_ms",
               "step_over_floor", "solves_per_step", "peak_mb", "detection_ms",
               "contact_element_ms", "return_map_ms", "assembly_ms", "solve_ms", "other_ms"]
    fmt = {c: ".2f" for c in columns if c.endswith(("_ms", "_floor", "_step", "_mb"))}
    md = (f"# Scaling\n\n{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}; `python benchmarks/scaling.py "
          f"{' '.join(argv or sys.argv[1:])}`\n\n" + markdown_table(rows, columns, fmt)
          + "\n```\n" + "\n".join(lines) + "\n```\n")
    (out / "scaling.md").write_text(md)
    print(f"wrote {out / 'scaling.csv'} and {out / 'scaling.md'}")
    return rows


if __name__ == "__main__":
    main()
