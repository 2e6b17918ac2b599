"""Issue 19's whole-run targets: the seed rock slope at the paper's resolution, the shaken cut
slope per simulated second, and the growth of a step's cost with the number of blocks.

Run:  python benchmarks/targets.py [--rock-slope-seconds S] [--cut-slope-seconds S]
                                   [--solvers legacy newton newton-unsettled]
                                   [--cases rock cut cut-auto]

``newton-unsettled`` is ``NewtonRaphson(unsettled_predictor=True)`` (Newton iterates from an
OPEN-CLOSE that did not settle instead of cutting the step); it runs the cut slope's cases only.

Prints, for each solver:

- ``rock slope``: the two-block rock slope of ``examples/rock_slope.py`` (face-onset joint,
  2 Hz to 670 gal) at dt 1e-4 as in the paper, for ``--rock-slope-seconds`` (default 16:
  the whole run, 160,000 steps; a multiple of 4 s, the table's eight levels of whole
  periods): wall and CPU seconds, steps, dt cuts. Target: under 60 s.
- ``cut slope``: the 311-block jointed slope of ``examples/jointed_slope.py`` (dt 2e-3
  requested) for ``--cut-slope-seconds`` (default 0.3) of shaking, and its CPU seconds per
  simulated second times 10 (the issue's 10 s of earthquake). Target: under 30 minutes. Also
  the share of its steps cut (target: under 1%) and its OPEN-CLOSE passes per step.
- ``cut slope (auto)``: the same slope with ``JointMaterial("auto", "auto", ...)`` and
  ``dt="auto"`` (``dda.auto_settings``), the same measures.
- the growth exponent of the cost of a step with the number of blocks, fitted to the N x N
  stacks of ``benchmarks/results/stacks.md`` (run ``benchmarks/stacks.py`` first). Target:
  at most 1.2.

Each run is its own process. Writes ``benchmarks/results/targets.md`` (a run of fewer cases,
solvers or seconds only with ``--out``).
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def rock_slope(solver: str, seconds: float) -> dict:
    sys.path.insert(0, str(ROOT / "examples"))
    from rock_slope import JOINTS, LEVELS

    import dda
    from dda.studies.cases import rock_slope as scene_of
    from dda.studies.cases import stepped_table

    hold = seconds / LEVELS
    scene, _, _ = scene_of(JOINTS["face"][0](), stepped_table(670.0, 2.0, LEVELS, hold))
    sim = dda.Simulation(scene, dt=1e-4, solver=_solver(solver))
    wall, cpu = time.perf_counter(), time.process_time()
    result = sim.run(seconds, progress=False)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    return {"case": "rock slope", "solver": solver, "seconds": seconds, "wall": wall,
            "cpu": cpu, "steps": len(result.stats), "cuts": len(result.stats.cuts),
            "passes": float(np.mean(result.stats["open_close_passes"]))}


def cut_slope(solver: str, seconds: float, auto: bool = False) -> dict:
    sys.path.insert(0, str(ROOT / "examples"))
    from jointed_slope import build_scene

    import dda
    from dda.contact import JointMaterial

    scene, _, _ = build_scene()
    dt = 2e-3
    if auto:
        scene.set_joint(JointMaterial("auto", "auto", scene.default_joint.friction))
        dt = "auto"
    sim = dda.Simulation(scene, dt=dt, solver=_solver(solver), max_open_close=30)
    wall, cpu = time.perf_counter(), time.process_time()
    result = sim.run(seconds, progress=False)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    st = result.stats
    return {"case": "cut slope (auto)" if auto else "cut slope", "solver": solver,
            "seconds": seconds, "wall": wall,
            "cpu": cpu, "steps": len(st), "cuts": len(st.cuts),
            "passes": float(np.mean(st["open_close_passes"])),
            "dt_median": float(np.median(np.diff(np.asarray(st["time"]), prepend=0.0)))}


def _solver(name: str):
    """A registered solver by name, or ``newton-unsettled``."""
    from dda.registry import make_solver
    from dda.solvers import NewtonRaphson

    if name == "newton-unsettled":
        return NewtonRaphson(unsettled_predictor=True)
    return make_solver(name)


def growth_exponent(path: Path) -> dict[str, float]:
    """Least-squares slope of log(ms/step) against log(blocks), per solver, from stacks.md."""
    rows = {}
    for line in path.read_text().splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        # the first table's rows (blocks, contacts, solver, ms/step, ...); the second table
        # (passes by the contacts switched) has the solver in its second column
        if (len(cells) > 4 and re.fullmatch(r"[\d,]+", cells[0])
                and re.fullmatch(r"[\d,]+", cells[1]) and cells[2] in ("legacy", "newton")):
            rows.setdefault(cells[2], []).append((float(cells[0].replace(",", "")),
                                                  float(cells[3])))
    out = {}
    for solver, pts in rows.items():
        if len(pts) >= 2:
            b, ms = np.log(np.array(pts)).T
            out[solver] = float(np.polyfit(b, ms, 1)[0])
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rock-slope-seconds", type=float, default=16.0)
    ap.add_argument("--cut-slope-seconds", type=float, default=0.3)
    ap.add_argument("--solvers", nargs="+", default=["legacy", "newton", "newton-unsettled"])
    ap.add_argument("--cases", nargs="+", default=["rock", "cut", "cut-auto"],
                    choices=["rock", "cut", "cut-auto"])
    ap.add_argument("--one", nargs=3, help=argparse.SUPPRESS)
    ap.add_argument("--out", default=None,
                    help="the table (default: results/targets.md for the whole run; a run of "
                         "fewer cases, solvers or seconds writes none unless given one)")
    args = ap.parse_args(argv)
    if "rock" in args.cases and not args.one:
        sys.path.insert(0, str(ROOT / "examples"))
        from rock_slope import LEVELS

        whole = LEVELS * 0.5  # each of the table's levels lasts whole periods of its 2 Hz
        if args.rock_slope_seconds <= 0 or abs(args.rock_slope_seconds / whole
                                               - round(args.rock_slope_seconds / whole)) > 1e-9:
            ap.error(f"--rock-slope-seconds must be a multiple of {whole:g} s (the shaking "
                     f"steps through {LEVELS} levels of whole 2 Hz periods)")
    if args.out is None and all(getattr(args, k) == ap.get_default(k) for k in (
            "rock_slope_seconds", "cut_slope_seconds", "solvers", "cases")):
        args.out = str(HERE / "results" / "targets.md")
    if args.one:
        case, solver, seconds = args.one
        run = {"rock": rock_slope, "cut": cut_slope,
               "cut-auto": lambda *a: cut_slope(*a, auto=True)}[case]
        print(json.dumps(run(solver, float(seconds))))
        return None
    rows = []
    seconds_of = {"rock": args.rock_slope_seconds, "cut": args.cut_slope_seconds,
                  "cut-auto": args.cut_slope_seconds}
    for case in args.cases:
        seconds = seconds_of[case]
        for solver in args.solvers:
            if case == "rock" and solver == "newton-unsettled":
                continue  # the cut slope's option: the rock slope is under its target without it
            out = subprocess.run([sys.executable, __file__, "--one", case, solver,
                                  str(seconds)], capture_output=True, text=True, check=True)
            r = json.loads(out.stdout.strip().splitlines()[-1])
            rows.append(r)
            print(_line(r), flush=True)
    growth = growth_exponent(HERE / "results" / "stacks.md")
    for solver, g in growth.items():
        print(f"growth of a step with blocks (stacks.md), {solver}: blocks^{g:.2f} (target 1.2)")
    text = ("# Issue 19's whole-run targets (`python benchmarks/targets.py`)\n\n"
            + "".join(f"- {_line(r)}\n" for r in rows)
            + "".join(f"- growth of a step with blocks (N x N stacks), {s}: blocks^{g:.2f} "
                      "(target at most 1.2)\n" for s, g in growth.items()))
    if args.out is None:  # a part of the run must not overwrite the whole run's table
        print("a partial run: results/targets.md not written (--out FILE to keep it)")
        return rows
    Path(args.out).write_text(text)
    print(f"wrote {args.out}")
    return rows


def _line(r) -> str:
    head = (f"{r['case']}, {r['solver']}: {r['seconds']:g} s simulated in {r['wall']:.1f} s wall, "
            f"{r['cpu']:.1f} s CPU, {r['steps']} steps, {r['cuts']} dt cuts "
            f"({100 * r['cuts'] / max(r['steps'], 1):.1f}%), {r['passes']:.2f} OPEN-CLOSE "
            "passes/step")
    if r["case"] == "rock slope":
        return head + " (target: the 16 s run under 60 s)"
    return head + (f"; 10 s of shaking at this rate: {10 * r['cpu'] / r['seconds'] / 60:.0f} "
                   "min CPU (target 30 min, and under 1% of steps cut)")


if __name__ == "__main__":
    main()
