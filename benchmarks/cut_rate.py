"""Issue 19's cut-rate target judged on several cuts of the same rock mass, not one.

The shaken cut slope of ``examples/jointed_slope.py`` is chaotic: one run's count of cut
steps moves by 10-15 with any change to the solvers' path, and two cuts of the same rock mass
(``build_scene(seed=...)``: the same joint sets, the cross joints' traces drawn again) gave
0.58% and 2.35% of steps cut under the same solver. So this benchmark runs each solver on
``--seeds`` cuts (default 0-4) for ``--seconds`` of shaking (default 10) at the example's
settings (dt 2e-3 asked for, joints of 5e10 N/m, ``max_open_close`` 30) and prints, for each
run and pooled over the cuts:

- steps and cut steps, and the share cut (the issue's target: under 1%);
- the cuts split into *tries* (a step size just doubled back that failed before holding
  ``StepControl.grow_after`` steps) and *hard* steps (cut at the size that had been working);
- the cuts in the first 0.35 s (0.05 s of settling under gravity and the first shaking
  period, when the mass finds its contacts) and after;
- OPEN-CLOSE passes a step, CPU seconds, and the face blocks' median motion (mm).

Each run is its own process (``--workers`` at a time). Writes ``benchmarks/results/cut_rate.md``
(another path with ``--out``). About 30 minutes on two cores with the defaults
(``--auto --seconds 3``: about 20; ``--auto``, 10 s: about an hour, ``results/
cut_rate_auto_10s.md``).

``--auto`` runs the same cuts with the penalty and dt chosen by the simulation
(``JointMaterial("auto", "auto", ...)``, ``dt="auto"``: 2e10 N/m at about 2.4e-4 s here under
legacy DDA, 4.3e-4 s under Newton, whose ``auto_kappa`` is 10), whose steps are four to eight
times as many; ``--out`` then defaults to ``results/cut_rate_auto.md``. ``--auto-dt`` keeps the
example's 5e10 N/m and lets the simulation choose dt for it (``dt="auto"``: about 1.5e-4 s
under legacy DDA, 2.7e-4 s under Newton, set by the lightest block's 185 kg; ``--out``
defaults to ``results/cut_rate_auto_dt.md``): the cut rate at the example's penalty with the
step its rule gives that penalty.

Run:  python benchmarks/cut_rate.py [--seeds 0 1 2 3 4] [--solvers legacy newton]
                                    [--seconds 10] [--auto | --auto-dt] [--workers 2]
                                    [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
#: the settling under gravity and the first period of shaking (s)
EARLY = 0.35


def one_run(solver: str, seed: int, seconds: float, auto: bool = False,
            auto_dt: bool = False) -> dict:
    """One cut of the slope through ``seconds`` of shaking: the counts printed above
    (``auto``: penalty and dt chosen; ``auto_dt``: dt alone)."""
    sys.path.insert(0, str(ROOT / "examples"))
    import jointed_slope as js

    import dda
    from dda.contact import JointMaterial
    from dda.registry import make_solver
    from dda.step_control import StepControl

    tries: list[bool] = []

    class LoggedControl(StepControl):
        """The run's step control, noting whether each cut was a try at a doubled size."""

        def cut(self, dt, reason):
            tries.append(bool(self.probing))
            super().cut(dt, reason)

    scene, base, blocks = js.build_scene(seed=seed)
    face = js.face_blocks(scene, blocks)
    if auto:
        scene.set_joint(JointMaterial("auto", "auto", scene.default_joint.friction))
    sim = dda.Simulation(scene, dt="auto" if auto or auto_dt else 2e-3,
                         solver=make_solver(solver),
                         max_open_close=30)
    sim.control = LoggedControl(sim.dt)
    cpu = time.process_time()
    result = sim.run(seconds, progress=False)
    cpu = time.process_time() - cpu
    cuts = result.stats.cuts
    early = [t < EARLY for t, _, _ in cuts]
    times = np.asarray(result.stats["time"])
    moved = js.face_motion(result, base, face)
    return dict(solver=solver, seed=seed, blocks=len(blocks), seconds=seconds, dt=sim.dt,
                penalty=float(sim.model.joints.normal_penalty[0]),
                steps=int(len(times)), cuts=len(cuts), tries=int(sum(tries)),
                early_steps=int(np.sum(times < EARLY)), early_cuts=int(sum(early)),
                passes=float(np.mean(result.stats["open_close_passes"])), cpu=cpu,
                moved_mm=1e3 * float(np.median(moved)))


def _table(rows: list[dict]) -> list[str]:
    lines = ["| solver | seed | blocks | steps | cut steps | share | tries / hard | "
             f"first {EARLY:g} s: cut / steps | after: share | passes a step | CPU s | "
             "face moved (median, mm) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        late = (r["cuts"] - r["early_cuts"]) / max(1, r["steps"] - r["early_steps"])
        lines.append(
            f"| {r['solver']} | {r['seed']} | {r['blocks']} | {r['steps']:,} | {r['cuts']} | "
            f"{100 * r['cuts'] / r['steps']:.2f}% | {r['tries']} / {r['cuts'] - r['tries']} | "
            f"{r['early_cuts']} / {r['early_steps']:,} | {100 * late:.2f}% | "
            f"{r['passes']:.2f} | {r['cpu']:.0f} | {r['moved_mm']:.0f} |")
    for solver in dict.fromkeys(r["solver"] for r in rows):
        mine = [r for r in rows if r["solver"] == solver]
        steps, cuts = sum(r["steps"] for r in mine), sum(r["cuts"] for r in mine)
        shares = [100 * r["cuts"] / r["steps"] for r in mine]
        lines.append(f"| {solver}, pooled | {len(mine)} seeds | | {steps:,} | {cuts} | "
                     f"**{100 * cuts / steps:.2f}%** (per cut {min(shares):.2f}-"
                     f"{max(shares):.2f}%) | {sum(r['tries'] for r in mine)} / "
                     f"{sum(r['cuts'] - r['tries'] for r in mine)} | | | | "
                     f"{sum(r['cpu'] for r in mine):.0f} | |")
    return lines


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    ap.add_argument("--solvers", nargs="+", default=["legacy", "newton"])
    ap.add_argument("--seconds", type=float, default=10.0)
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--auto", action="store_true", help='"auto" penalty and dt')
    mode.add_argument("--auto-dt", action="store_true",
                      help='the example\'s 5e10 N/m with dt "auto"')
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--one", nargs=2, metavar=("SOLVER", "SEED"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(one_run(args.one[0], int(args.one[1]), args.seconds, args.auto,
                                 args.auto_dt)))
        return
    if args.out is None:
        args.out = HERE / "results" / ("cut_rate_auto.md" if args.auto else
                                       "cut_rate_auto_dt.md" if args.auto_dt else
                                       "cut_rate.md")
    flags = ["--auto"] * args.auto + ["--auto-dt"] * args.auto_dt

    def launch(job):
        solver, seed = job
        out = subprocess.run([sys.executable, __file__, "--one", solver, str(seed),
                              "--seconds", str(args.seconds)] + flags,
                             capture_output=True, text=True, check=True)
        row = json.loads(out.stdout.strip().splitlines()[-1])
        print(f"{solver} cut {seed}: {row['cuts']} of {row['steps']} steps cut "
              f"({100 * row['cuts'] / row['steps']:.2f}%), {row['cpu']:.0f} s CPU", flush=True)
        return row

    jobs = [(s, seed) for s in args.solvers for seed in args.seeds]
    with ThreadPoolExecutor(max(1, args.workers)) as pool:
        rows = list(pool.map(launch, jobs))
    chosen = ", ".join(sorted({f"{r['solver']}: {r['penalty']:.2g} N/m at dt {r['dt']:.2g} s"
                               for r in rows}))
    setting = ("the penalty and dt chosen by the simulation: " + chosen if args.auto else
               "the example's joints, dt chosen by the simulation: " + chosen if args.auto_dt
               else "dt 2e-3 asked for, joints of 5e10 N/m")
    command = " ".join(["python benchmarks/cut_rate.py", *flags,
                        *([f"--seconds {args.seconds:g}"] * (args.seconds != 10.0))])
    lines = [f"# The cut slope's steps cut over {args.seconds:g} s of shaking, on "
             f"{len(args.seeds)} cuts of the rock mass", "",
             f"`{command}` ({setting}; {args.workers} runs at a time; CPU seconds of each "
             "run).", "",
             *_table(rows), ""]
    text = "\n".join(lines)
    print(text)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)


if __name__ == "__main__":
    main()
