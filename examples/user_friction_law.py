"""A friction law of your own, in one file: check it, run it under both solvers, from Python and
from a scene file.

The law is ``examples/my_laws.py``: Coulomb friction whose cohesion breaks at the first slip
(``BrittleCohesion``, 23 lines of class). The scene: a 1 m x 0.5 m block on a 35-degree
incline (phi 30 degrees, cohesion 5 kPa), kicked down the incline at 0.5 m/s.

- With ``CoulombSingle(phi=30, cohesion=5e3)`` the cohesion stays: friction and cohesion
  decelerate the block at ``(c L + W cos 35 tan 30 - W sin 35) / m = 3.01 m/s^2`` and it stops
  after ``v0^2 / 2a = 4.2 cm``.
- With ``BrittleCohesion`` the kick breaks the cohesion at the first step; the block then slides
  on friction alone at ``a = g (sin 35 - cos 35 tan 30) = 0.99 m/s^2``, so after 1 s it has
  slid ``v0 t + a t^2 / 2 = 0.99 m``.

The script checks the law with :func:`dda.contact.check_friction_law`, runs both laws under
both solvers, runs ``examples/brittle_block.toml`` (which names the law by import path,
``law = "my_laws:BrittleCohesion"``), and prints each slide against the formula above.
The guide is ``docs/friction_laws.md``.

Run:  python examples/user_friction_law.py
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import dda
from dda import registry
from dda.contact import CoulombSingle, JointMaterial, check_friction_law
from dda.materials import LinearElastic
from dda.solvers import LegacyPullBack, NewtonRaphson

HERE = Path(__file__).resolve().parent
# my_laws.py sits next to this script: the same lookup a scene file's import path makes
BrittleCohesion = registry.law_class("my_laws:BrittleCohesion", folder=HERE)

G, DIP, PHI, COHESION, V0 = 9.81, np.radians(35.0), np.radians(30.0), 5e3, 0.5
ROCK = LinearElastic(young=10e9, poisson=0.25, density=2500.0)
MASS = 2500.0 * 1.0 * 0.5  # kg per m


def slide_formula(law_name: str, t: np.ndarray) -> np.ndarray:
    """The rigid-block slide along the incline (m) at times t (see the module docstring)."""
    friction = G * (np.sin(DIP) - np.cos(DIP) * np.tan(PHI))  # down the incline, m/s^2
    if law_name == "brittle":
        return V0 * t + 0.5 * friction * t**2
    a = friction - COHESION * 1.0 / MASS  # negative: the block slows down
    t_stop = V0 / -a
    tc = np.minimum(t, t_stop)
    return V0 * tc + 0.5 * a * tc**2


def build_scene(law) -> dda.Scene:
    """The incline and the kicked block, as ``brittle_block.toml`` has them."""
    scene = dda.Scene(gravity=G)
    scene.add_block([(0.0, 0.0), (4.0, 0.0), (4.0, 2.8008)], ROCK, fixed=True, name="slope")
    top = np.array([4.0, 2.8008])
    t = top / np.linalg.norm(top)
    n = np.array([-t[1], t[0]])
    foot = 1.5 * t + 1e-6 * n
    corners = [foot, foot + t, foot + t + 0.5 * n, foot + 0.5 * n]
    scene.add_block([tuple(p) for p in corners], ROCK, velocity=tuple(-V0 * t), name="block")
    scene.set_joint(JointMaterial(normal_penalty=1e10, shear_penalty=1e10, friction=law))
    return scene


def slide(result, scene) -> np.ndarray:
    """How far the block has slid down the incline (m), per recorded step."""
    top = np.array([4.0, 2.8008])
    return -result.displacement(scene.block("block")) @ (top / np.linalg.norm(top))


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--duration", type=float, default=1.0,
                        help="simulated time of each run, s (default 1)")
    parser.add_argument("--out", default=None,
                        help="a folder to write slides.csv in: each run's slide against time "
                             "(default: none; dda run SCRIPT.py --out DIR gives one)")
    args = parser.parse_args(argv)
    brittle = BrittleCohesion(phi=30.0, cohesion=COHESION)
    check_friction_law(brittle)
    print(f"check_friction_law({brittle!r}): passed")
    runs = {}
    for law in (brittle, CoulombSingle(phi=30.0, cohesion=COHESION)):
        for solver in (NewtonRaphson(), LegacyPullBack()):
            scene = build_scene(law)
            result = dda.Simulation(scene, dt=1e-3, solver=solver).run(args.duration)
            runs[(law.name, solver.name)] = (result.time, slide(result, scene))
    loaded = dda.load_scene(HERE / "brittle_block.toml")
    result = loaded.simulation().run(args.duration)
    runs[("brittle", "scene file")] = (result.time, slide(result, loaded.scene))
    print(f"slide after {args.duration:g} s (formula: rigid block; see the docstring)")
    for (name, how), (t, s) in runs.items():
        expected = slide_formula(name, np.asarray(t))[-1]
        print(f"  {name:8s} {how:10s} {1e3 * s[-1]:8.2f} mm   formula {1e3 * expected:8.2f} mm"
              f"   {100 * (s[-1] / expected - 1):+6.2f} %")
    if args.out is not None:
        _write_slides(Path(args.out) / "slides.csv", runs)
    return runs


def _write_slides(path: Path, runs: dict) -> None:
    """Each run's slide (m) against time (s), one column pair per run."""
    path.parent.mkdir(parents=True, exist_ok=True)
    columns, names = [], []
    for (name, how), (t, s) in runs.items():
        columns += [np.asarray(t), np.asarray(s)]
        names += [f"t {name} {how} (s)", f"slide {name} {how} (m)"]
    n = max(len(c) for c in columns)
    table = np.full((n, len(columns)), np.nan)
    for j, c in enumerate(columns):
        table[:len(c), j] = c
    np.savetxt(path, table, delimiter=",", header=",".join(names), comments="")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
