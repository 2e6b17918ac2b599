"""Direct shear in 20, 50 and 200 load steps: legacy DDA against the fully implicit method.

The case of H 3(1), the paper's figure 7:

- two elastic blocks (E 1 GPa, nu 0.2) with a penalty of 10 GN/m and a friction angle of
  30 degrees;
- 1 MPa normal stress on the top face, and 2 mm of shear to the right.

The strength is tan(30) x 1 MPa = 577.35 kPa. Legacy DDA pulls an overshoot back only at the
start of the next step, so its peak lies above the strength, the more so the fewer the steps.
The fully implicit method holds the strength at every step count.

Writes:

- ``OUT/direct_shear.png``: shear stress against the shear displacement imposed at the
  loading springs, one panel per solver;
- ``OUT/direct_shear.csv``: the plotted numbers;
- ``OUT/direct_shear_*.vtu`` and ``OUT/direct_shear.pvd``: the 20-step Newton run.

It prints each run's peak and its overshoot.

Run:  python examples/direct_shear.py [--out DIR] [--full]
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import numpy as np

import dda
from dda.registry import make_solver
from dda.studies.cases import shear_box, shear_stress

STRENGTH = 1e6 * np.tan(np.radians(30.0))
SHEAR = 2e-3  # imposed at the loading springs, m
SOLVERS = ("legacy", "newton")  # run in this order; classes from dda.registry


def run(n_steps: int, solver: str, writer=None) -> dict:
    """2 mm of shear in ``n_steps`` steps after one consolidation step (static analysis)."""
    scene, lower, upper = shear_box(SHEAR, consolidation=1.0 / n_steps)
    sim = dda.Simulation(scene, dt=1.0 / n_steps, solver=make_solver(solver), analysis="static")
    start = time.perf_counter()
    result = sim.run(1.0 + 1.0 / n_steps, output=writer)
    tau = shear_stress(result, lower, upper)
    imposed = SHEAR * np.maximum(np.asarray(result.time) - 1.0 / n_steps, 0.0)
    return {"steps": n_steps, "solver": solver, "tau": tau, "imposed": imposed,
            "shear": result.displacement(upper)[:, 0], "peak": tau.max(),
            "overshoot": tau.max() / STRENGTH - 1.0, "end": tau[-1],
            "wall_time": time.perf_counter() - start}


def plot(runs: list[dict], path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, sharey=True, figsize=(10, 4.2))
    for ax, solver in zip(axes, SOLVERS, strict=True):
        for k, r in enumerate(x for x in runs if x["solver"] == solver):
            ax.plot(1e3 * r["imposed"], 1e-3 * r["tau"], "-o", ms=2.5, color=f"C{k}",
                    label=f"{r['steps']} steps (peak {r['peak'] / 1e3:.1f} kPa)")
        ax.axhline(STRENGTH / 1e3, color="k", ls="--", lw=1,
                   label="tan 30 x 1 MPa = 577.4 kPa")
        ax.set_title({"legacy": "legacy DDA (explicit pull-back)",
                      "newton": "fully implicit (Newton-Raphson)"}[solver], fontsize=10)
        ax.set_xlabel("imposed shear displacement (mm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="lower right")
    axes[0].set_ylabel("shear stress (kPa)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    ap.add_argument("--out", default="out/direct_shear", help="output folder")
    ap.add_argument("--full", action="store_true", help="also 1000 load steps")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    counts = (20, 50, 200, 1000) if args.full else (20, 50, 200)
    runs = []
    for solver in SOLVERS:
        for n in counts:
            writer = (dda.io.VTUWriter(out / "direct_shear")
                      if (solver, n) == ("newton", 20) else None)
            runs.append(run(n, solver, writer))
    plot(runs, out / "direct_shear.png")
    with open(out / "direct_shear.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["solver", "steps", "imposed_shear_mm", "block_displacement_mm",
                    "shear_stress_kPa"])
        for r in runs:
            for u, s, t in zip(r["imposed"], r["shear"], r["tau"], strict=True):
                w.writerow([r["solver"], r["steps"], f"{1e3 * u:.6f}", f"{1e3 * s:.6f}",
                            f"{1e-3 * t:.4f}"])
    print(f"direct shear, 1 MPa, phi 30: strength {STRENGTH / 1e3:.2f} kPa")
    print("solver  steps  peak (kPa)  overshoot  last (kPa)  wall (s)")
    for r in runs:
        print(f"{r['solver']:6s}  {r['steps']:5d}  {r['peak'] / 1e3:10.1f}  "
              f"{100 * r['overshoot']:+8.2f}%  {r['end'] / 1e3:10.1f}  {r['wall_time']:8.2f}")
    print(f"wrote {out / 'direct_shear.png'}, {out / 'direct_shear.csv'} and "
          f"{out / 'direct_shear.pvd'}")
    return runs


if __name__ == "__main__":
    main()
