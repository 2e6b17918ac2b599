"""Time per step of both solvers on a 2-block scene and a 100-block wall.

Run:  python benchmarks/step_cost.py [--steps N]
Prints wall time per step (median of the steps after the first 20), and where it goes.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

import numpy as np

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic

ROCK = LinearElastic(young=14.9e9, poisson=0.2, density=2198.0)
JOINT = JointMaterial(normal_penalty=2e9, shear_penalty=2e9, friction=CoulombSingle(phi=36.4))


def box(x0, y0, w, h):
    return [(x0, y0), (x0 + w, y0), (x0 + w, y0 + h), (x0, y0 + h)]


def two_blocks():
    scene = dda.Scene(gravity=9.81)
    base = scene.add_block(box(0, 0, 1, 0.2), ROCK, fixed=True, name="base")
    scene.add_block(box(0.4, 0.2, 0.2, 0.2), ROCK, name="top")
    scene.set_joint(JOINT)
    scene.shake(base, acceleration=lambda t: (9.81 * np.sin(4 * np.pi * t), 0.0))
    return scene


def wall(rows=10, cols=10):
    """A running-bond wall of rows x cols bricks (rows x cols blocks) on a fixed base."""
    scene = dda.Scene(gravity=9.81)
    w, h = 0.4, 0.2
    scene.add_block(box(-0.5, -0.3, cols * w + 1.0, 0.3), ROCK, fixed=True, name="base")
    n = 1
    for r in range(rows):
        shift = 0.5 * w if r % 2 else 0.0
        for c in range(cols):
            if n > rows * cols:
                break
            scene.add_block(box(shift + c * w, r * h, w, h), ROCK)
            n += 1
    scene.set_joint(JOINT)
    return scene


def measure(scene, steps, solver, dt=1e-3):
    sim = dda.Simulation(scene, dt=dt, solver=solver)
    t0 = time.perf_counter()
    result = sim.run(duration=steps * dt, progress=False)
    total = time.perf_counter() - t0
    wall_times = result.stats["wall_time"][20:]
    return sim, result, total, float(np.median(wall_times))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--profile", action="store_true", help="print the top functions by time")
    args = ap.parse_args(argv)
    cases = (("2 blocks (1 shaken)", two_blocks), ("100-block wall", wall))
    for label, build in cases:
        for make_solver in (dda.solvers.LegacyPullBack, dda.solvers.NewtonRaphson):
            sim, result, total, median = measure(build(), args.steps, make_solver())
            contacts = int(np.median(result.stats["contacts"]))
            name = f"{label}, {sim.solver.name}"
            print(f"{name:30s} {1e3 * median:7.3f} ms/step  ({1 / median:6.0f} steps/s), "
                  f"{contacts} contacts, {args.steps} steps in {total:.2f} s; "
                  f"{result.stats.summary()}")
            if args.profile:
                prof = cProfile.Profile()
                prof.enable()
                sim.run(duration=100 * sim.dt, progress=False)
                prof.disable()
                pstats.Stats(prof).sort_stats("tottime").print_stats(12)


if __name__ == "__main__":
    main()
