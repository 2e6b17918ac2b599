"""A fixed set of small scenes run under both solvers, their end states kept to compare a
change against: same bits, round-off, or another path.

Run:  python benchmarks/regression_set.py --save FILE.npz      (before a change)
      python benchmarks/regression_set.py --compare FILE.npz   (after it)
      [--only NAME ...] [--list]

Each scene (the hard cases of ``tests/stability/scenes.py``, the inclines under the three
built-in laws, the README demo's slope, the direct shear, the moving base and a 3 x 3 stack)
runs for a short, fixed time under ``LegacyPullBack`` and ``NewtonRaphson``. What is kept of
each run: the steps taken and cut, the OPEN-CLOSE passes and solves, and the end state's
vertices, velocities, stresses and contact forces. ``--compare`` prints, scene by scene, the
largest difference of each array (``same`` when bit for bit) and the step counts when they
differ; its exit status is 0 whatever it finds (the reading is the reader's: a chaotic scene
may take another path for a change of round-off).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import dda  # noqa: E402
from dda.contact import BartonBandis, CoulombSingle, StaticDynamicTransition  # noqa: E402


def _stability(name, *args):
    from tests.stability import scenes

    made = getattr(scenes, name)(*args)
    if len(made) == 4:  # (scene, dt, duration, work)
        scene, dt, duration, _ = made
        return scene, dt, duration
    scene, duration = made  # the impacts: (scene, duration); dt 1e-3
    return scene, 1e-3, duration


def _incline(law):
    from tests.stability import scenes

    scene, dt, _, _ = scenes.incline(law)
    return scene, dt, 0.4


def _demo():
    sys.path.insert(0, str(ROOT / "examples"))
    from shaking_slope import build_scene

    return build_scene()[0], 1e-3, 1.0


def _shear_box():
    from dda.studies.cases import shear_box

    return shear_box(1e-4)[0], 1e-3, 0.2


def _moving_base():
    from dda.studies.cases import moving_base

    return moving_base()[0], 1e-3, 1.0


def _stack():
    from tests.conftest import stack_scene

    return stack_scene(3), 1e-3, 0.2


SCENES = {
    "stiff penalty": lambda: _stability("stiff_penalty"),
    "fast impact": lambda: _stability("fast_impact"),
    "tower": lambda: _stability("tower"),
    "corner impact 30": lambda: _stability("corner_impact", 30.0),
    "sliver": lambda: _stability("sliver"),
    "spinning": lambda: _stability("spinning"),
    "incline coulomb": lambda: _incline(CoulombSingle(phi=30.0)),
    "incline transition": lambda: _incline(StaticDynamicTransition(35.0, 25.0)),
    "incline barton": lambda: _incline(BartonBandis(jrc=10.0, jcs=50e6, phi_r=28.0)),
    "static far above dynamic": lambda: _stability("static_far_above_dynamic"),
    "shaken cut slope": lambda: _stability("shaken_cut_slope"),
    "stopper": lambda: _stability("stopper_impact"),
    "block on block": lambda: _stability("block_on_block"),
    "corner on corner": lambda: _stability("corner_on_corner"),
    "notch": lambda: _stability("notch"),
    "ell on a step": lambda: _stability("ell_on_a_step"),
    "lip": lambda: _stability("lip"),
    "demo": _demo,
    "shear box": _shear_box,
    "moving base": _moving_base,
    "stack 3x3": _stack,
}

SOLVERS = {"legacy": dda.solvers.LegacyPullBack, "newton": dda.solvers.NewtonRaphson}


def run(name: str, solver: str) -> dict[str, np.ndarray]:
    """The kept arrays of one scene under one solver."""
    scene, dt, duration = SCENES[name]()
    sim = dda.Simulation(scene, dt=dt, solver=SOLVERS[solver]())
    result = sim.run(duration, progress=False)
    state = sim.committed
    st = result.stats
    c = state.contacts
    return {
        "steps": np.array([len(st), len(st.cuts)]),
        "passes": np.asarray(st["open_close_passes"]),
        "solves": np.asarray(st["solves"]),
        "x": state.x, "velocity": state.velocity, "stress": state.stress,
        "contact_state": np.asarray(c.state),
        "contact_vertex": np.asarray(c.vertex), "contact_edge": np.asarray(c.edge),
    }


def collect(names) -> dict[str, np.ndarray]:
    out = {}
    for name in names:
        for solver in SOLVERS:
            t0 = time.perf_counter()
            try:
                arrays = run(name, solver)
            except Exception as exc:  # a run that stops is a result too
                arrays = {"error": np.array(f"{type(exc).__name__}: {exc}")}
            for key, value in arrays.items():
                out[f"{name}|{solver}|{key}"] = value
            print(f"  {name:28s} {solver:7s} {time.perf_counter() - t0:6.1f} s", flush=True)
    return out


def _difference(a: np.ndarray, b: np.ndarray) -> str:
    if a.shape != b.shape:
        return f"shape {a.shape} -> {b.shape}"
    if a.dtype.kind in "iub" or a.dtype.kind in "US":
        return "same" if np.array_equal(a, b) else f"{int(np.sum(a != b))} differ"
    if np.array_equal(a, b):
        return "same"
    return f"{float(np.max(np.abs(a - b))):.3g}"


def compare(old: dict, new: dict) -> None:
    scenes = sorted({k.rsplit("|", 1)[0] for k in old} | {k.rsplit("|", 1)[0] for k in new})
    identical = 0
    for run_key in scenes:
        keys = sorted({k for k in list(old) + list(new) if k.startswith(run_key + "|")})
        diffs = {}
        for k in keys:
            field = k.rsplit("|", 1)[1]
            if k not in old or k not in new:
                diffs[field] = "missing in " + ("old" if k not in old else "new")
                continue
            d = _difference(np.asarray(old[k]), np.asarray(new[k]))
            if d != "same":
                diffs[field] = d
        if not diffs:
            identical += 1
            continue
        steps = ""
        if f"{run_key}|steps" in old and f"{run_key}|steps" in new:
            steps = f" (steps, cuts {tuple(old[run_key + '|steps'])} -> " \
                    f"{tuple(new[run_key + '|steps'])})"
        print(f"{run_key}{steps}: " + ", ".join(f"{f} {d}" for f, d in diffs.items()))
    print(f"{identical} of {len(scenes)} runs bit for bit the same")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--save", type=Path)
    ap.add_argument("--compare", type=Path)
    ap.add_argument("--only", nargs="*", default=None, help="scene names (default: all)")
    ap.add_argument("--list", action="store_true")
    args = ap.parse_args(argv)
    if args.list:
        print("\n".join(SCENES))
        return
    names = args.only or list(SCENES)
    unknown = [n for n in names if n not in SCENES]
    if unknown:
        ap.error(f"unknown scenes {unknown}; --list names them")
    if not args.save and not args.compare:
        ap.error("give --save FILE or --compare FILE")
    new = collect(names)
    if args.save:
        np.savez_compressed(args.save, **new)
        print(f"wrote {args.save}")
    if args.compare:
        with np.load(args.compare) as f:
            old = {k: f[k] for k in f.files if k.split("|")[0] in names}
        compare(old, new)


if __name__ == "__main__":
    main()
