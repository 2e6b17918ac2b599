"""Rock slope on a shaking table with and without the static-to-dynamic friction transition.

The case of S 3(2) (Adachi et al. 2017): two Ryukyu limestone blocks on a joint dipping 15
degrees, with kn 10 GN/m and ks 10 MN/m. The paper's input record is not public. The table
here shakes at 2 Hz, with the amplitude raised in eight steps of 2 s each to 670 gal
(``dda.studies.cases.stepped_table``), for 16 s. A lip on the lower block stops the slide
after 10.5 cm.

Three joints are run:

- ``single``: phi_s = phi_d = 40.5 degrees, one angle. Sliding starts on time but moves too
  little.
- ``transition``: phi_s 40.5, phi_d 31.6 degrees (tilt tests), each vertex contact judged on
  its own (the papers' rule). Once sliding it moves far more.
- ``face``: the same angles, but the two contacts of the face start sliding together when the
  face's shear force reaches its static strength (``onset="face"``), as the rigid block does.

Why ``transition`` slides farther than the rigid block: the shaking rocks the block, so the two
contacts at the ends of its base carry unequal normal forces while they share the shear force.
The lightly pressed end reaches tan(phi_s) first, drops to tan(phi_d) and hands the difference
to the other end, which then yields too. In the short run of the tests (0.5 s per level) the
block starts sliding at a total shear-to-normal force ratio of 0.82 instead of tan(40.5) =
0.854, 8 ms before the rigid block, and keeps the 11 mm/s it gained through the whole slip
event. Over the 16 s run it slides 9-11% farther per event. With ``onset="face"`` the two
contacts yield together, as a rigid block does, and the slide follows the rigid block (0.4%).

The joints' shear dashpot (``JointMaterial.shear_dashpot``, on by default) damps the block's
vibration on its soft shear springs (10 MN/m, a 12 ms period) after each slide event. Without
it (``--no-shear-dashpot``, the papers' joints) only Newmark's gamma = 1 damps that vibration,
strongly at dt 1e-3 and weakly at the paper's dt 1e-4 (``--full``), and the face joint's gap to
the rigid block is 0.42% at dt 1e-3 but 11.0% at dt 1e-4; with it, 0.43% and 0.31% (before
slip reversals were located within their steps, ``dda.slip_events``: 0.69% and 10.95%, 0.70%
and 0.30%). The
per-contact onset is the one joint the dashpot makes worse: it starts a level early (8.25 s
against the rigid block's 10.22 s, 68.5%), because the two ends share the shear force by their
history, which the dashpot changes, and the lightly pressed end then reaches tan(phi_s) at the
level before (without the dashpot 12.1% at dt 1e-3, where it starts at 10.221 s with the
rigid block, and 16.5% at 1e-4, where a few mm slip at 8.25 s already: the description
above).

Each run is compared with a rigid-block Newmark sliding computation with the same friction
(``dda.studies.references.sliding_block``). The comparison reports the start of sliding and
the largest gap in the slide history until the stopper.

Writes:

- ``OUT/rock_slope.png``: table acceleration and slide against time;
- ``OUT/rock_slope.csv``: the plotted numbers;
- ``OUT/rock_slope_*.vtu`` and ``OUT/rock_slope.pvd``: the last run (``face``), every 20 ms.

Run:  python examples/rock_slope.py [--out DIR] [--dt S] [--hold S] [--joints A,B] [--full]
      [--no-shear-dashpot]
      (--full: dt 1e-4 s as in the paper, about 2 minutes)
"""

from __future__ import annotations

import argparse
import csv
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import dda
from dda.contact import CoulombSingle, StaticDynamicTransition
from dda.studies.cases import SLOPE_DIP, SLOPE_STOP, rock_slope, slide_down_dip, stepped_table
from dda.studies.references import sliding_block

PHI_S, PHI_D = 40.5, 31.6
LEVELS = 8
JOINTS = {
    "single": (lambda: CoulombSingle(PHI_S), None),
    "transition": (lambda: StaticDynamicTransition(PHI_S, PHI_D, onset="contact"), PHI_D),
    "face": (lambda: StaticDynamicTransition(PHI_S, PHI_D, onset="face"), PHI_D),
}
LABELS = {"single": "one angle", "transition": "transition, per-contact onset",
          "face": "transition, face onset"}
#: a slide counts as started once it exceeds this (m); the rigid start is exact
START_LEVEL = 1e-4
#: the comparison ends when either slide reaches this fraction of the stopper distance
NEAR_STOPPER = 0.95


def run_joint(name: str, table, duration: float, dt: float, writer=None,
              shear_dashpot: bool = True) -> dict:
    """One DDA run and its rigid-block reference (``shear_dashpot`` False: the papers'
    joint, without :attr:`dda.contact.JointMaterial.shear_dashpot`)."""
    make_law, phi_d = JOINTS[name]
    scene, lower, upper = rock_slope(make_law(), table)
    scene.set_joint(replace(scene.default_joint, shear_dashpot=shear_dashpot))
    sim = dda.Simulation(scene, dt=dt, solver=dda.solvers.NewtonRaphson())
    start = time.perf_counter()
    result = sim.run(duration, output=writer)
    wall = time.perf_counter() - start
    t = np.asarray(result.time)
    slide = slide_down_dip(result, lower, upper)
    slide = slide - slide[0]
    mu_d = None if phi_d is None else np.tan(np.radians(phi_d))
    ref = sliding_block(table, t, np.tan(np.radians(PHI_S)), mu_d, dip=SLOPE_DIP,
                        breakpoints=table.breakpoints)
    return compare(name, t, slide, ref.slip, ref.start_time()) | {
        "wall_time": wall, "steps": len(result.stats.time), "dt_cuts": len(result.stats.cuts)}


def compare(name, t, slide, rigid, rigid_start) -> dict:
    """Start times and the largest gap of the histories until the stopper."""
    moving = np.flatnonzero(slide > START_LEVEL)
    start = float(t[moving[0]]) if len(moving) else float("nan")
    near = np.flatnonzero((slide >= NEAR_STOPPER * SLOPE_STOP)
                          | (rigid >= NEAR_STOPPER * SLOPE_STOP))
    end = near[0] if len(near) else len(t) - 1
    scale = max(rigid[end], START_LEVEL)
    gap = np.abs(slide[: end + 1] - rigid[: end + 1]).max() / scale
    return {"joint": name, "time": t, "slide": slide, "rigid": rigid, "start": start,
            "rigid_start": rigid_start, "window_end": float(t[end]),
            "slide_at_end": slide[end], "rigid_at_end": rigid[end], "history_gap": gap}


def plot(runs: list[dict], table, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6),
                                   gridspec_kw={"height_ratios": [1, 2]})
    t = np.linspace(0, runs[0]["time"][-1], 8001)
    ax1.plot(t, [100 * table(ti)[0] for ti in t], lw=0.5, color="0.3")
    ax1.set_ylabel("table acceleration (gal)")
    for k, r in enumerate(runs):
        ax2.plot(r["time"], 1e3 * r["slide"], color=f"C{k}",
                 label=f"DDA, {LABELS[r['joint']]}")
        if r["joint"] == "face" and any(q["joint"] == "transition" for q in runs):
            continue  # its rigid block is the transition's
        ax2.plot(r["time"], 1e3 * np.minimum(r["rigid"], 2 * SLOPE_STOP), "--", color=f"C{k}",
                 lw=1, label=f"rigid block (no stopper), {LABELS[r['joint']].split(',')[0]}")
    ax2.axhline(1e3 * SLOPE_STOP, color="k", ls=":", lw=1, label="stopper")
    ax2.set_ylim(-5, 1.3e3 * SLOPE_STOP)
    ax2.set_xlabel("time (s)")
    ax2.set_ylabel("slide down the joint (mm)")
    ax2.legend(fontsize=8, loc="upper left")
    ax1.set_title(f"Rock slope on a shaking table: phi_s {PHI_S}, phi_d {PHI_D} deg",
                  fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_csv(runs: list[dict], table, path: Path):
    """The slides of every run and their rigid blocks on the first run's record times.

    A run whose steps were cut has records at other times than the others (the stopper's
    impact cuts steps), so each is interpolated linearly onto the first run's times.
    """
    grid = runs[0]["time"]
    columns = [np.interp(grid, r["time"], r[k]) for r in runs for k in ("slide", "rigid")]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time_s", "table_gal"] + [f"{r['joint']}_{k}_mm" for r in runs
                                                for k in ("dda", "rigid")])
        for i, ti in enumerate(grid):
            w.writerow([f"{ti:.4f}", f"{100 * table(ti)[0]:.2f}"]
                       + [f"{1e3 * c[i]:.4f}" for c in columns])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    ap.add_argument("--out", default="out/rock_slope", help="output folder")
    ap.add_argument("--dt", type=float, default=1e-3, help="time step, s (default 1e-3)")
    ap.add_argument("--hold", type=float, default=2.0,
                    help="seconds per amplitude step (default 2: 16 s in all)")
    ap.add_argument("--full", action="store_true", help="dt 1e-4 s, as in the paper")
    ap.add_argument("--no-shear-dashpot", action="store_true",
                    help="the papers' joints: no damping of the closed contacts' shear springs "
                         "(JointMaterial.shear_dashpot False)")
    ap.add_argument("--joints", default=",".join(JOINTS),
                    help=f"comma-separated joints to run (default {','.join(JOINTS)})")
    args = ap.parse_args(argv)
    joints = [j.strip() for j in args.joints.split(",") if j.strip()]
    unknown = sorted(set(joints) - set(JOINTS))
    if unknown or not joints:
        ap.error(f"--joints: unknown {unknown}; choose from {', '.join(JOINTS)}")
    dt = 1e-4 if args.full else args.dt
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table = stepped_table(670.0, 2.0, LEVELS, args.hold)
    duration = LEVELS * args.hold
    runs = []
    for name in joints:
        writer = None
        if name == joints[-1]:
            # a frame every 20 ms of simulated time (a step count drifts: the steps split
            # where a slip reverses)
            writer = dda.io.VTUWriter(out / "rock_slope", interval=0.02)
        runs.append(run_joint(name, table, duration, dt, writer,
                               not args.no_shear_dashpot))
    plot(runs, table, out / "rock_slope.png")
    write_csv(runs, table, out / "rock_slope.csv")
    print(f"rock slope, 2 Hz to 670 gal in {LEVELS} steps of {args.hold:g} s, dt {dt:g} s")
    print("joint       start DDA  start rigid  compared until  DDA (mm)  rigid (mm)  "
          "largest gap  wall (s)  dt cuts")
    for r in runs:
        print(f"{r['joint']:10s}  {r['start']:9.3f}  {r['rigid_start']:11.3f}  "
              f"{r['window_end']:14.2f}  {1e3 * r['slide_at_end']:8.2f}  "
              f"{1e3 * r['rigid_at_end']:10.2f}  {100 * r['history_gap']:10.2f}%  "
              f"{r['wall_time']:8.1f}  {r['dt_cuts']:7d}")
    print(f"wrote {out / 'rock_slope.png'}, {out / 'rock_slope.csv'} and "
          f"{out / 'rock_slope.pvd'}")
    return runs


if __name__ == "__main__":
    main()
