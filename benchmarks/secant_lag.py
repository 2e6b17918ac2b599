"""Legacy DDA's secant lag (``dda.solvers.open_close.LAG_SECANT_FROM``) on the shaken cut slope:
OPEN-CLOSE passes a step with it and without it.

The 311-block jointed slope of ``examples/jointed_slope.py`` (its defaults: 5e10 N/m, dt 2e-3
asked for, 30 passes) for ``--seconds`` (default 0.3) of shaking, legacy DDA, with gravity
scaled by ``1 + eps`` for each ``--eps`` (the run is chaotic at the millimetre, so each eps is
another sample of the same scene). Prints, per run: steps, steps cut, mean passes a step, mean
passes of the steps at 1.25e-4, 2.5e-4 and 5e-4 s (the step sizes the run settles at; comparing
at one step size leaves out where the step control took the run) and CPU seconds. Each run is
its own process, so the compiled kernels and the timings do not mix.

Run:  python benchmarks/secant_lag.py [--seconds S] [--eps 0 1e-12 3e-12]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
SIZES = (1.25e-4, 2.5e-4, 5e-4)

_RUN = """
import json, sys, time, warnings
import numpy as np
sys.path.insert(0, {examples!r})
from jointed_slope import build_scene
import dda
from dda.registry import make_solver
from dda.solvers import open_close
warnings.simplefilter("ignore")
open_close.LAG_SECANT_FROM = {secant}
scene, base, blocks = build_scene()
scene.gravity = 9.81 * (1.0 + {eps!r})
sim = dda.Simulation(scene, dt=2e-3, solver=make_solver("legacy"), max_open_close=30)
start = time.process_time()
result = sim.run({seconds!r}, progress=False)
cpu = time.process_time() - start
passes = np.asarray(result.stats["open_close_passes"], dtype=float)
dt = np.asarray(result.stats["dt"])
by_size = {{}}
for size in {sizes!r}:
    at = np.isclose(dt, size)
    by_size[repr(size)] = [float(passes[at].mean()) if at.any() else None, int(at.sum())]
print(json.dumps({{"steps": len(passes), "cuts": len(result.stats.cuts),
                  "passes": float(passes.mean()), "by_size": by_size, "cpu": cpu}}))
"""


def run(secant: int, eps: float, seconds: float) -> dict:
    code = _RUN.format(examples=str(HERE.parent / "examples"), secant=secant, eps=eps,
                       seconds=seconds, sizes=SIZES)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=0.3)
    parser.add_argument("--eps", type=float, nargs="+", default=[0.0, 1e-12, 3e-12])
    args = parser.parse_args(argv)
    from dda.solvers.open_close import LAG_SECANT_FROM

    header = ("| secant from pass | eps | steps | cut | passes a step | at "
              + " | at ".join(f"{s:.3g} s" for s in SIZES) + " | CPU s |")
    print(header)
    print("|" + "---|" * (6 + len(SIZES)))
    for secant in (0, LAG_SECANT_FROM):
        for eps in args.eps:
            r = run(secant, eps, args.seconds)
            sizes = " | ".join("-" if r["by_size"][repr(s)][0] is None else
                               f"{r['by_size'][repr(s)][0]:.2f} ({r['by_size'][repr(s)][1]})"
                               for s in SIZES)
            print(f"| {secant or 'off'} | {eps:g} | {r['steps']} | {r['cuts']} | "
                  f"{r['passes']:.2f} | {sizes} | {r['cpu']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
