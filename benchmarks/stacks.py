"""N x N stacks of 1 m squares settling on a fixed base: the cost of a step against the C code.

The Berkeley DDA code's own kind of test (issue 19): N x N unit squares (E 10 GPa, nu 0.25,
2500 kg/m^3) stacked on a fixed base, joints p_n = p_s = 1e10 N/m and phi 35 degrees,
gravity, dt 1e-3, ``max_open_close`` 30. Each (N, solver) runs in a fresh process (its peak
memory is its own) for ``--steps`` steps and prints:

- ms per step: the median of the steps' wall time, and CPU seconds per step (process time,
  all threads);
- OPEN-CLOSE passes, Newton iterations and linear solves per step, and how many of those
  solves factorized the matrix (numeric factorizations) and analysed its pattern (symbolic
  analyses; the sparse solver, ``DDA_SPARSE_SOLVER``, is in the table); dt cuts;
- why OPEN-CLOSE needed another pass, summed over the run: passes that closed contacts,
  opened contacts, switched contacts between stick and slip only, or found only a sliding
  contact whose lagged normal force was off by more than ``NORMAL_FORCE_RTOL``
  (:data:`dda.solvers.open_close.PASS_LOG`);
- passes a step by how many contacts the step's first pass switched (0, 1-3, 4-10, 11 or
  more): the settling steps in which few contacts change against those in which many do;
- peak resident memory above the process's size after the imports and a 2 x 2 warm-up run
  (which loads the compiled kernels and MKL) (MB).

The C code's numbers on the same scenes (issue 19, same machine class, dt 1e-3): 1.17 ms (101
blocks), 55.7 ms (901), 795 ms (3,601) per step, one OPEN-CLOSE pass.

Writes ``benchmarks/results/stacks.md``.

With ``--case wall`` the scenes are instead ``benchmarks/scaling.py``'s running-bond walls of
``--sizes`` bricks (``results/walls.md``).

Run:  python benchmarks/stacks.py [--sizes 10 30 60] [--steps N] [--solvers legacy newton]
                                  [--case stack|wall] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
C_CODE_MS = {10: 1.17, 30: 55.7, 60: 795.0}


def stack(n: int):
    """The N x N stack on its base (a scene)."""
    import dda
    from dda.contact import CoulombSingle, JointMaterial
    from dda.materials import LinearElastic

    rock = LinearElastic(young=10e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(-1.0, -1.0), (n + 1.0, -1.0), (n + 1.0, 0.0), (-1.0, 0.0)], rock,
                    fixed=True, name="base")
    for i in range(n):
        for j in range(n):
            x, y = float(j), float(i)
            scene.add_block([(x, y), (x + 1, y), (x + 1, y + 1), (x, y + 1)], rock)
    # restitution 1: no impact dashpot, as Berkeley's C code (the same scene as its)
    scene.set_joint(JointMaterial(normal_penalty=1e10, shear_penalty=1e10,
                                  friction=CoulombSingle(phi=35.0), restitution=1.0))
    return scene


def scene_of(case: str, n: int):
    """The N x N stack, or (``case`` "wall") the running-bond wall of N bricks of
    ``benchmarks/scaling.py`` (0.4 x 0.2 m, the stack's rock and joint, with the joint's
    default impact dashpot)."""
    if case == "wall":
        sys.path.insert(0, str(HERE))
        from scaling import wall  # noqa: PLC0415

        return wall(n)
    return stack(n)


def measure(n: int, solver: str, steps: int, case: str = "stack") -> dict:
    """One run in this process (see the module docstring)."""
    import dda
    import dda.solvers.open_close as oc
    from dda.registry import make_solver

    # a 2 x 2 stack first: the libraries a run loads (numba's kernels, MKL) are not the
    # stack's memory, and their first call is not its time
    dda.Simulation(stack(2), dt=1e-3, solver=make_solver(solver)).run(3e-3, progress=False)
    scene = scene_of(case, n)
    base_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    nonlinear = make_solver(solver)
    sim = dda.Simulation(scene, dt=1e-3, solver=nonlinear, max_open_close=30)
    oc.PASS_LOG = []
    cpu = time.process_time()
    result = sim.run(steps * 1e-3, progress=False)
    cpu = time.process_time() - cpu
    log = np.array(oc.PASS_LOG, dtype=int).reshape(-1, 4)
    oc.PASS_LOG = None
    st = result.stats
    blocked = log[:-1] if len(log) else log  # the last pass of a run ends it
    step_passes = np.asarray(st["open_close_passes"], dtype=int)
    return {
        "n": n, "blocks": n * n + 1 if case == "stack" else n + 1, "case": case,
        "solver": solver, "steps": len(st),
        "contacts": float(np.mean(st["contacts"])),
        "ms_median": 1e3 * float(np.median(st["wall_time"])),
        "cpu_ms": 1e3 * cpu / len(st),
        "passes": float(np.mean(st["open_close_passes"])),
        "iterations": float(np.mean(st["iterations"])),
        "solves": float(np.mean(st["solves"])), "cuts": len(st.cuts),
        # numeric factorizations and symbolic analyses of the sparse system per step
        "factorizations": nonlinear.factors().counts[0] / max(len(st), 1),
        "analyses": nonlinear.factors().counts[1] / max(len(st), 1),
        "backend": nonlinear.factors().backend + (
            " (single precision, refined)" if nonlinear.factors().refinements else ""),
        "why_close": int(np.count_nonzero(blocked[:, 0])),
        "why_open": int(np.count_nonzero(blocked[:, 1])),
        "why_stick_slip_only": int(np.count_nonzero(
            (blocked[:, 0] == 0) & (blocked[:, 1] == 0) & (blocked[:, 2] > 0))),
        "why_lag_only": int(np.count_nonzero((blocked[:, :3] == 0).all(axis=1)
                                             & (blocked[:, 3] > 0))),
        "peak_mb": (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - base_rss) / 1024.0,
        "by_changes": passes_by_changes(log, step_passes),
    }


#: the bins of :func:`passes_by_changes`: contacts the step's first pass switched
CHANGE_BINS = ((0, 0), (1, 3), (4, 10), (11, None))


def passes_by_changes(log: np.ndarray, step_passes: np.ndarray) -> list | None:
    """Passes a step by how many contacts its first pass switched (closed, opened, or moved
    between stick and slip), per bin of :data:`CHANGE_BINS`: ``[steps, mean passes]`` each
    (mean None for an empty bin); None when the log's passes are not the committed steps'
    (a cut step's passes are logged too, and are not told apart)."""
    if int(step_passes.sum()) != len(log):
        return None
    first = log[np.concatenate([[0], np.cumsum(step_passes)[:-1]]), :3].sum(axis=1)
    out = []
    for lo, hi in CHANGE_BINS:
        pick = (first >= lo) & ((first <= hi) if hi is not None else True)
        n = int(np.count_nonzero(pick))
        out.append([n, float(step_passes[pick].mean()) if n else None])
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 30, 60])
    ap.add_argument("--steps", type=int, default=None,
                    help="steps per run (default: 100 up to 30 x 30, 30 beyond)")
    ap.add_argument("--solvers", nargs="+", default=["legacy", "newton"])
    ap.add_argument("--case", choices=["stack", "wall"], default="stack",
                    help="N x N stacks (default), or running-bond walls of N bricks")
    ap.add_argument("--one", nargs=3, metavar=("N", "SOLVER", "STEPS"), help=argparse.SUPPRESS)
    ap.add_argument("--out", default=None,
                    help="the table (default: results/stacks.md, results/walls.md)")
    args = ap.parse_args(argv)
    if args.one:  # the child process
        print(json.dumps(measure(int(args.one[0]), args.one[1], int(args.one[2]),
                                 args.case)))
        return None
    rows = []
    for n in args.sizes:
        for solver in args.solvers:
            steps = args.steps or (100 if n <= 30 else 30)
            out = subprocess.run([sys.executable, __file__, "--case", args.case, "--one",
                                  str(n), solver, str(steps)],
                                 capture_output=True, text=True, check=True)
            row = json.loads(out.stdout.strip().splitlines()[-1])
            rows.append(row)
            print(_line(row), flush=True)
    table = _table(rows)
    args.out = args.out or str(HERE / "results" / f"{args.case}s.md")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(table)
    print(f"wrote {args.out}")
    return rows


def _c_code(r) -> float:
    """The C code's ms/step on the row's scene (measured on the stacks only)."""
    if r.get("case", "stack") != "stack":
        return float("nan")
    return C_CODE_MS.get(r["n"], float("nan"))


def _line(r) -> str:
    return (f"{r['blocks']:5d} blocks {r['solver']:6s} {r['ms_median']:8.1f} ms/step "
            f"(C code {_c_code(r):.4g}), {r['passes']:.2f} passes, "
            f"{r['solves']:.2f} solves, {r['factorizations']:.2f} factorizations, "
            f"{r['analyses']:.2f} analyses ({r['backend']}), {r['cuts']} cuts, "
            f"{r['peak_mb']:.0f} MB")


def _table(rows) -> str:
    head = ("| blocks | contacts | solver | ms/step (median wall) | CPU ms/step | C code ms/step "
            "| passes | iterations | solves | factorizations (analyses) | sparse solver | cuts "
            "| passes for: close / open / stick-slip only / lag only | peak MB |\n|"
            + "---|" * 14 + "\n")
    body = "".join(
        f"| {r['blocks']:,} | {r['contacts']:,.0f} | {r['solver']} | {r['ms_median']:.1f} | "
        f"{r['cpu_ms']:.1f} | {_c_code(r):.4g} | {r['passes']:.2f} | "
        f"{r['iterations']:.2f} | {r['solves']:.2f} | {r['factorizations']:.2f} "
        f"({r['analyses']:.2f}) | {r['backend']} | {r['cuts']} | {r['why_close']} / "
        f"{r['why_open']} / {r['why_stick_slip_only']} / {r['why_lag_only']} | "
        f"{r['peak_mb']:.0f} |\n" for r in rows)
    bins = [f"{lo}" if hi == lo else (f"{lo}+" if hi is None else f"{lo}-{hi}")
            for lo, hi in CHANGE_BINS]
    head2 = ("| blocks | solver | steps | " + " | ".join(bins) + " |\n|"
             + "---|" * (3 + len(bins)) + "\n")
    body2 = "".join(
        f"| {r['blocks']:,} | {r['solver']} | {r['steps']} | "
        + " | ".join(_bin_cell(b) for b in (r["by_changes"] or [[0, None]] * len(bins)))
        + " |\n" for r in rows)
    title = ("Running-bond walls settling under gravity (`python benchmarks/stacks.py --case "
             "wall`)" if rows and rows[0].get("case") == "wall" else
             "N x N stacks settling under gravity (`python benchmarks/stacks.py`)")
    return (f"# {title}\n\n"
            "Steps of dt 1e-3 from the start (`--steps`; by default 100 up to 30 x 30, 30 "
            "beyond; each run's count is in the second table).\n\n" + head + body
            + "\nPasses a step by the contacts its first pass switched (closed, opened, or "
            "between stick and slip): mean passes (steps); n/a where a cut step's passes "
            "cannot be told apart.\n\n" + head2 + body2)


def _bin_cell(b) -> str:
    n, mean = b
    return "n/a" if n and mean is None else ("-" if not n else f"{mean:.2f} ({n})")


if __name__ == "__main__":
    main()
