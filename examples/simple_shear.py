"""Simple shear with static-to-dynamic friction: the stress drops from phi_s to phi_d at once.

The case of S 3(1):

- two elastic blocks (E 1 GPa, nu 0): an upper block of 100 x 100 mm centred on a lower block
  of 150 x 100 mm;
- a penalty of 100 GN/m, phi_s 30 and phi_d 20 degrees;
- 1 MPa normal stress, and 0.3 mm of shear in 150 steps.

The shear stress rises to the static strength tan(30) x 1 MPa = 577.35 kPa. When the joint
yields it drops at once to the dynamic strength tan(20) x 1 MPa = 363.97 kPa, and it stays
there while the joint slides. Both solvers are run.

Writes:

- ``OUT/simple_shear.png``: shear stress against imposed displacement;
- ``OUT/simple_shear.csv``: the plotted numbers;
- ``OUT/simple_shear_*.vtu`` and ``OUT/simple_shear.pvd``: the Newton run.

It prints the peak and the stress after the drop.

Run:  python examples/simple_shear.py [--out DIR] [--full]
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import numpy as np

import dda
from dda.contact import StaticDynamicTransition
from dda.registry import make_solver
from dda.studies.cases import shear_box, shear_stress

STATIC = 1e6 * np.tan(np.radians(30.0))
DYNAMIC = 1e6 * np.tan(np.radians(20.0))
SHEAR = 0.3e-3
SOLVERS = ("newton", "legacy")  # run in this order; classes from dda.registry


def run(n_steps: int, solver: str, writer=None) -> dict:
    scene, lower, upper = shear_box(SHEAR, friction=StaticDynamicTransition(30.0, 20.0),
                                    poisson=0.0, penalty=100e9, consolidation=1.0 / n_steps)
    sim = dda.Simulation(scene, dt=1.0 / n_steps, solver=make_solver(solver), analysis="static")
    start = time.perf_counter()
    result = sim.run(1.0 + 1.0 / n_steps, output=writer)
    tau = shear_stress(result, lower, upper)
    k = int(np.argmax(tau))
    return {"solver": solver, "steps": n_steps, "tau": tau,
            "imposed": SHEAR * np.maximum(np.asarray(result.time) - 1.0 / n_steps, 0.0),
            "peak": tau[k], "after_drop": tau[k + 1] if k + 1 < len(tau) else np.nan,
            "end": tau[-1], "wall_time": time.perf_counter() - start}


def plot(runs: list[dict], path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for k, r in enumerate(runs):
        ax.plot(1e3 * r["imposed"], 1e-3 * r["tau"], "-o" if k == 0 else "--", ms=2.5,
                color=f"C{k}", label=f"{r['solver']} ({r['steps']} steps)")
    ax.axhline(STATIC / 1e3, color="k", ls=":", lw=1,
               label=f"tan 30 x 1 MPa = {STATIC / 1e3:.1f} kPa")
    ax.axhline(DYNAMIC / 1e3, color="0.4", ls="-.", lw=1,
               label=f"tan 20 x 1 MPa = {DYNAMIC / 1e3:.1f} kPa")
    ax.set_xlabel("imposed shear displacement (mm)")
    ax.set_ylabel("shear stress (kPa)")
    ax.set_title("Simple shear, phi_s 30 / phi_d 20", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    ap.add_argument("--out", default="out/simple_shear", help="output folder")
    ap.add_argument("--full", action="store_true", help="600 steps instead of 150")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    n = 600 if args.full else 150
    runs = [run(n, "newton", dda.io.VTUWriter(out / "simple_shear")), run(n, "legacy")]
    plot(runs, out / "simple_shear.png")
    with open(out / "simple_shear.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["solver", "steps", "imposed_shear_mm", "shear_stress_kPa"])
        for r in runs:
            for u, t in zip(r["imposed"], r["tau"], strict=True):
                w.writerow([r["solver"], r["steps"], f"{1e3 * u:.6f}", f"{1e-3 * t:.4f}"])
    print(f"simple shear: static strength {STATIC / 1e3:.2f} kPa, dynamic {DYNAMIC / 1e3:.2f} kPa")
    print("solver  steps  peak (kPa)  after the drop (kPa)  last (kPa)  wall (s)")
    for r in runs:
        print(f"{r['solver']:6s}  {r['steps']:5d}  {r['peak'] / 1e3:10.1f}  "
              f"{r['after_drop'] / 1e3:20.1f}  {r['end'] / 1e3:10.1f}  {r['wall_time']:8.2f}")
    print(f"wrote {out / 'simple_shear.png'}, {out / 'simple_shear.csv'} and "
          f"{out / 'simple_shear.pvd'}")
    return runs


if __name__ == "__main__":
    main()
