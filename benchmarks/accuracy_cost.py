"""What accuracy costs: error against CPU time of both solvers on two paper cases.

The block on a moving base (1 s of 1 g, 2 Hz shaking; error: the largest gap of the slip
history to the analytical stick-slip solution, over its 20.43 mm peak) and the direct shear
(1 MPa, phi 30; error: the peak's overshoot or the end's shortfall against the strength), over

    dt       {1e-2, 3e-3, 1e-3, 3e-4, 1e-4} s (direct shear: 1 / dt load steps)
    penalty  {2e7, 2e8, 2e9, 2e10} N/m (normal and shear)
    solver   {legacy, newton}

Writes into ``benchmarks/results/`` (or ``--out``):

- ``accuracy_cost.csv``: one row per run (settings, errors, CPU time, steps, iterations,
  seconds per part of the step);
- ``accuracy_cost.md``: the same as tables, and the cheapest settings for 1% error;
- ``accuracy_cost.png``: error against CPU time, each solver's Pareto front drawn as a line.

Prints, per case, the cheapest setting of each solver within 1% error and the ratio of their
CPU times.

Run:  python benchmarks/accuracy_cost.py [--quick] [--workers N] [--scheduler ADDRESS]

``--scheduler`` sends the runs to a running Dask scheduler (``tcp://host:8786``) instead of
local processes. ``--quick`` runs dt {1e-2, 1e-3} and penalties {2e8, 2e9} only.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from dda.studies.studies import DirectShear, MovingBase
from dda.studies.sweep import cheapest, grid, markdown_table, pareto_front, sweep, write_csv

STEPS = (1e-2, 3e-3, 1e-3, 3e-4, 1e-4)
PENALTIES = (2e7, 2e8, 2e9, 2e10)
SOLVERS = ("legacy", "newton")
TOLERANCE = 0.01
HERE = Path(__file__).resolve().parent


def cases(quick: bool):
    steps = (1e-2, 1e-3) if quick else STEPS
    penalties = (2e8, 2e9) if quick else PENALTIES
    out = []
    for study in (MovingBase(), DirectShear()):
        out += grid(study, solver=SOLVERS, dt=steps, penalty=penalties)
    # the longest runs first, so the pool is not left waiting on one at the end
    out.sort(key=lambda c: c.settings["dt"])
    return out


def plot(rows, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    studies = list(dict.fromkeys(r["study"] for r in rows))
    fig, axes = plt.subplots(1, len(studies), figsize=(6 * len(studies), 4.6))
    axes = np.atleast_1d(axes)
    floor = 1e-6
    for ax, study in zip(axes, studies, strict=True):
        for k, solver in enumerate(SOLVERS):
            mine = [r for r in rows if r["study"] == study and r["solver"] == solver
                    and np.isfinite(r["error"])]
            x = [r["cpu_time"] for r in mine]
            y = [max(abs(r["error"]), floor) for r in mine]
            ax.scatter(x, y, s=18, color=f"C{k}", alpha=0.6, label=f"{solver} runs")
            front = pareto_front(mine)
            ax.plot([r["cpu_time"] for r in front], [max(abs(r["error"]), floor) for r in front],
                    "-", color=f"C{k}", lw=1.5, drawstyle="steps-post",
                    label=f"{solver} Pareto front")
            failed = [r for r in rows if r["study"] == study and r["solver"] == solver
                      and not np.isfinite(r["error"])]
            if failed:
                ax.scatter([r["cpu_time"] for r in failed], [1.0] * len(failed), marker="x",
                           color=f"C{k}", label=f"{solver} failed (drawn at 100%)")
        ax.axhline(TOLERANCE, color="k", ls="--", lw=0.8, label="1% error")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU time of the run (s)")
        ax.set_ylabel(f"relative error (clipped at {floor:g})")
        ax.set_title(study.replace("_", " "), fontsize=10)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def best_settings(rows):
    """Per study: the cheapest run of each solver within TOLERANCE, and the CPU-time ratio."""
    lines = []
    for study in dict.fromkeys(r["study"] for r in rows):
        best = {s: cheapest([r for r in rows if r["study"] == study and r["solver"] == s],
                            TOLERANCE) for s in SOLVERS}
        lines.append(f"{study}, error <= {100 * TOLERANCE:g}%:")
        for s, r in best.items():
            if r is None:
                lines.append(f"  {s:7s} no setting reaches it")
            else:
                lines.append(f"  {s:7s} dt {r['dt']:g} s, penalty {r['penalty']:.0e} N/m: "
                             f"error {100 * r['error']:.3f}%, {r['cpu_time']:.3f} s CPU, "
                             f"{r['steps']} steps, {r['solves']} solves")
        if all(best.values()):
            ratio = best["legacy"]["cpu_time"] / best["newton"]["cpu_time"]
            lines.append(f"  legacy / newton CPU time: {ratio:.2f}")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a 2 x 2 grid per solver and case")
    ap.add_argument("--workers", type=int, default=os.cpu_count(), help="local processes")
    ap.add_argument("--scheduler", help="address of a Dask scheduler to run on instead")
    ap.add_argument("--out", default=str(HERE / "results"), help="output folder")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    todo = cases(args.quick)
    start = time.perf_counter()
    if args.scheduler:
        from distributed import Client

        with Client(args.scheduler) as client:
            rows = sweep(todo, executor=client.get_executor())
    else:
        with ProcessPoolExecutor(max_workers=args.workers) as pool:
            rows = sweep(todo, executor=pool)
    elapsed = time.perf_counter() - start
    rows.sort(key=lambda r: (r["study"], r["solver"], -r["dt"], r["penalty"]))
    write_csv(rows, out / "accuracy_cost.csv")
    plot(rows, out / "accuracy_cost.png")
    summary = best_settings(rows)
    columns = ["solver", "dt", "penalty", "error", "cpu_time", "steps", "iterations", "solves",
               "dt_cuts", "status"]
    fmt = {"dt": "g", "penalty": ".0e", "error": ".3%", "cpu_time": ".3f"}
    md = [f"# Accuracy against cost\n\n{len(rows)} runs in {elapsed:.0f} s on "
          f"{platform.processor() or platform.machine()} ({os.cpu_count()} cores), "
          f"`python benchmarks/accuracy_cost.py{' --quick' if args.quick else ''}`.\n",
          "```\n" + summary + "\n```\n"]
    for study in dict.fromkeys(r["study"] for r in rows):
        md.append(f"## {study}\n")
        md.append(markdown_table([r for r in rows if r["study"] == study], columns, fmt))
    (out / "accuracy_cost.md").write_text("\n".join(md))
    print(summary)
    print(f"{len(rows)} runs in {elapsed:.0f} s; wrote {out / 'accuracy_cost.csv'}, "
          f"{out / 'accuracy_cost.md'} and {out / 'accuracy_cost.png'}")
    return rows


if __name__ == "__main__":
    main()
