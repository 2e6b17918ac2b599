"""A jointed rock slope cut from two joint sets, shaken: several hundred blocks.

The rock mass (a 20 m high slope face at 59 degrees, 40 m deep at its base) is cut by
bedding dipping 25 degrees out of the face, 1 m apart, and cross joints dipping 70 degrees
into it, 1.6 m apart, 80% persistent in 5 m traces (``dda.geometry.cut_blocks``); slivers
thinner than 10 cm are dropped. It rests on a base, against a back wall fixed to it, that
shakes horizontally at 2 Hz, 0.3 g, after 0.05 s of settling under gravity.

With these defaults (legacy DDA, 0.3 s, joints of 5e10 N/m) the run takes about 30 s: 1,048
steps, 46 of them cut because OPEN-CLOSE did not settle in 30 passes, and the face blocks end
21.94 mm (median) and 27.10 mm (most) from where they started relative to the base (36-38 s
beside other runs on two cores, 2026-12-06); on a machine with AVX-512, where numpy's
vectorized functions round some last bits otherwise, 990 steps, 47 cut, 21.97 / 27.45 mm in
23-24 s (2026-12-07; the same with the first step's touching tolerance of
``dda.contact.detection``, which taken at every step sent this run, as stiff as it is for its
dt, another way: 1,210 steps, 43 cut, 21.97 / 27.58 mm); since legacy DDA measures its cycle
rule over a contact's group of touching blocks (``dda.solvers.open_close.CYCLE_GROUP``, the
same day), 910 steps, 41 cut, 21.86 / 27.27 mm in 24 s; since it measures a contact held at the
end of one of its last 8 steps on the contact's own blocks (``LegacyPullBack``'s
``cycle_memory``, 2026-12-08), 1,064 steps, 51 cut, 22.18 / 27.70 mm in 24 s.
``--solver newton``: 801 steps, 21 cut, 22.35 / 26.52 mm (77 s beside two other runs on two
cores; 38 s for 656 steps in an earlier version, alone); on the AVX-512 machine 710 steps, 32
cut, 21.90 / 26.03 mm (42 s of CPU beside another run; 702, 27, 21.77 / 26.13 mm before Newton
held contacts that cycle, 2026-12-07). The penalty is stiff for dt (540 times the lightest
block's inertia at 2e-3 s): a 1 x 1.6 m block's contact period is 1.8 ms and the lightest
block's (185 kg) 0.4 ms, so the contacts settle only at a fraction of the 2e-3 s asked for and
the steps average 2.9e-4 s; ``dda.PenaltyWarning`` says so after 20 cuts, and advises 2e10 N/m
(no softer: the rule's 2 E for a jointed mass, below) at 4.3e-4 s, or 2.7e-4 s at 5e10 N/m.
About half the cuts are tries at twice the working step that fail (20 of 35 in an earlier
version of the run), the rest steps whose OPEN-CLOSE ends in a cycle of a few contacts' states
and lagged normal forces.

``--auto`` leaves the penalty and dt to the simulation (``dda.auto_settings``; ``sim.choices``
is printed): blocks carry blocks here, so the penalty is twice the rock's Young's modulus, 2e10
N/m, at dt 2.4e-4 s under legacy DDA (3 times the lightest block's inertia) and 4.3e-4 s under
Newton (10 times). It runs the 0.3 s in about 22 s (legacy: 1,274 steps, none cut) and 23 s
(Newton: 698 steps, none cut; 43 s and 1,274 steps with 3 times the inertia), and the face
blocks move 23.4 / 29.4 mm and 22.9 / 27.9 mm (23.7 / 28.5 mm at 2.4e-4 s). Joints softer than
the rock make the whole mass softer and its face moves further (legacy, 0.3 s, median / most):
55 / 85 mm at 2.2e9 N/m (57 / 89 and 61 / 107 mm at dt 3.6e-4 and 1.8e-4: it is the penalty,
not dt), 38 / 65 mm at 5e9, 31 / 42 mm at 1e10, 29 / 46 mm at 2e10, 27 / 51 mm at 5e10
(measured before the joints' impact dashpot).

Through 10 s of shaking (``--duration 10``) the face slides out along a bedding plane: legacy
DDA took 145 s of wall time (6,289 steps, 110 cut) and its face blocks ended 400 mm (median)
and 413 mm (most) from where they started (with the cycle rule measured over a contact's
group of touching blocks, 2026-12-07: 6,381 steps, 124 cut, 126 s, 399 / 413 mm; with its
memory of held contacts, 2026-12-08: 6,340 steps, 113 cut, 123 s, 397 / 414 mm), Newton
231 s (6,074 steps, 97 cut) and 397 / 411 mm (the two side by side on two cores; 6,892
steps and 113 cut, 5,961 and 89, in issue 19's twenty-third part); under ``--auto``, 8.6 min
of CPU (legacy) and 16.5 min (Newton) (issue 19's ninth part). The shaken slope is
chaotic at the millimetre: round-off (another sparse solver, another order of summation)
moves the face by several millimetres, and the numbers above move with every change to the
solvers' arithmetic. ``benchmarks/README.md`` ("The cut slope example over time") keeps them
as they moved, with what the joints' dashpots and the detection fixes did to them.

An order-of-magnitude check, not a validation: on the 25 degree bedding with phi 35 degrees, a
block starts to slide out of the face once the base pushes into the slope at more than tan(35 -
25) = 0.18 g, which 0.3 g exceeds for about 0.15 s of the run. An energy audit of the default
run (before issue 19's changes, not redone since): the base and the back wall put 180 kJ/m into
the blocks through their contacts, the blocks gain 110 kJ/m, and at no step do they hold more
than they started with plus that work (``tests/stability`` checks the same on a 31-block cut,
``KnownMotionWork``).

``--seed N`` draws the cross joints' traces again: another cut of the same rock mass, with the
same joint sets. Cuts differ: over 10 s at these settings the share of steps cut was 0.80-3.08%
(legacy) and 0.58-2.35% (Newton) over seeds 0-4, this one (seed 0) in the middle
(``benchmarks/cut_rate.py``). Where a larger wedge slides, legacy DDA's explicit friction shows
its first-order error in dt: on seed 4 the face moved 249 mm (median) in 3 s under legacy DDA
and 127 mm under Newton at these settings, 216 / 147 mm under ``--auto`` (dt 2.4e-4 s), and 164
/ 136 mm at 2e10 N/m and dt 1.2e-4 s; on seed 0 the two agree within 1% after 10 s. Newton's
``--auto`` at 4.3e-4 s moved the five cuts' faces 135 / 150 / 143 / 167 / 134 mm in 3 s, at
2.4e-4 s (3 times the inertia) 136 / 157 / 123 / 131 / 147 and at 1.2e-4 s 206 / 174 / 136 mm
on seeds 2 / 3 / 4: near their limit these wedges move by tens of percent with the step either
way. Under ``--auto`` through 10 s (legacy at 2.4e-4 s, Newton at 4.3e-4 s) the five cuts had
19 of 208,458 steps cut (legacy) and 1 of 114,117 (Newton), in 9.4-14.2 and 11.1-12.7 minutes
of CPU a run on a machine about a quarter slower than the figures above
(``results/cut_rate_auto_10s.md``); the face moved 401-599 mm (median), and which wedge slides
out over 10 s is chaotic at that scale: the methods part on cuts 2 and 4, by 198 and 73 mm.
(Seeds 1-4 had lost joints to a block-cutting defect since fixed; cut again, through 10 s:
24 of 172,150 steps cut under legacy DDA and none of 94,211 under Newton, 6.5-8.7 minutes of
CPU a run, the face 425-510 mm and 426-703 mm; ``results/cut_rate_auto_10s_seeds1-4_recut.md``.)

``--dt auto`` keeps the joints' 5e10 N/m and lets the simulation choose dt for it
(``dda.auto_settings``, rule 6: the penalty at 3 times the lightest block's inertia under
legacy DDA, 10 under Newton: 1.5e-4 s and 2.7e-4 s). Over 2 s of shaking on the five cuts it
cut 0.07% (legacy) and 0.06% (Newton) of the steps (``benchmarks/cut_rate.py --auto-dt``),
against 0.6-3.1% per cut over 10 s at 2e-3 s: what the cuts at the defaults resolve is that
step, not the penalty. The 0.3 s of the defaults with ``--dt auto`` (the two solvers side by
side on two cores): legacy 2,030 steps, 4 cut, 40 s; Newton 1,183 steps, 8 cut, 47 s; the face
blocks 22.7 / 28.5 mm and 22.8 / 28.1 mm (median / most).

``--start settled`` starts the run from the slope at rest under gravity
(``Simulation(start="settled")``, :mod:`dda.settling`): 11 static steps with the joints held,
74 more with their own friction (some blocks slide off the back wall they hung on while
held, 0.61 mm at most), some 4 s. From rest the blocks drop onto their springs and bounce.
The 0.3 s then take legacy DDA 746 steps, 22 cut (from rest 910, 41 cut), and Newton 567,
21 cut (710, 32); the face blocks move 21.84 / 38.87 mm and 21.77 / 38.73 mm (median / most;
from rest 21.86 / 27.27 and 21.90 / 26.03): the median alike, the block that moves most 12
mm further under both solvers, as its contacts start at their friction limit (README, "A
dynamic run's start"). The settled start is also the one whose answer holds as dt falls:
at 2e-3 / 2.5e-4 / 6.25e-5 s Newton's face moves 21.77 / 38.73, 22.79 / 38.56 and 21.95 /
38.78 mm, where from rest the bounce moves it 21.90 / 26.03, 22.45 / 27.68 and 24.28 / 33.39
mm (legacy DDA alike; 2026-12-07).

``--cohesion PA`` gives the joints a cohesion (``CoulombSingle(phi=35, cohesion=PA)``). At 1
MPa the slope is glued: legacy DDA 1,712 steps, 88 cut, 26 s, the face blocks 0.40 / 0.89 mm;
Newton 13,592 steps, 495 cut, 260 s of CPU, 0.47 / 1.20 mm (runs two at a time on two cores).
At 10 kPa legacy DDA moves them 9.56 / 10.62 mm (1,216 steps, 51 cut; 1,424 steps, 44 cut
with the scene-wide cycle limit it had until 2026-12-07; Newton 11.29 / 13.18 mm). Newton runs these
because it holds closed a contact that cycles between open and closed at a small pull
(:data:`dda.solvers.newton.HOLD_CYCLING`): before, it stopped at t = 0.025 s at 1 MPa and
took 14,903 steps for 0.1 s at 10 kPa. It cuts more steps than legacy DDA because it holds
a contact only while it pulls by at most 1% of the forces on its own blocks; legacy DDA's
OPEN-CLOSE holds one against the largest force in its group of touching blocks, most often
the whole slope (measured against the scene's largest force, as it was until 2026-12-07, a
light block far from the others could hang by it; 2,087 steps, 86 cut, 31 s at 1 MPa).

Writes ``OUT/slope_*.vtu`` + ``OUT/slope.pvd`` (a frame every 0.05 s of simulated time, and
the run's end) and prints the blocks, how far the blocks of the face moved, and the cost
profile.

Run:  python examples/jointed_slope.py [--out DIR] [--duration S] [--dt S | --dt auto]
                                       [--solver legacy|newton] [--auto] [--seed N]
                                       [--start rest|settled] [--cohesion PA]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.geometry import JointSet, cut_blocks
from dda.materials import LinearElastic
from dda.registry import make_solver, solver_names

ROCK = LinearElastic(young=10e9, poisson=0.25, density=2600.0)
JOINT = JointMaterial(normal_penalty=5e10, shear_penalty=5e10, friction=CoulombSingle(phi=35.0))
MASS = [(20.0, 0.0), (60.0, 0.0), (60.0, 20.0), (32.0, 20.0)]  # toe, base, back, crest
SETS = [JointSet(dip=-25.0, spacing=1.0, offset=0.3),
        JointSet(dip=70.0, spacing=1.6, persistence=0.8, trace_length=5.0)]
SETTLE = 0.05


def shaking(t):
    """Base acceleration: nothing while the slope settles, then 0.3 g at 2 Hz."""
    if t < SETTLE:
        return (0.0, 0.0)
    return (0.3 * 9.81 * np.sin(4.0 * np.pi * (t - SETTLE)), 0.0)


def build_scene(min_size: float = 0.10, seed: int = 0, mass=MASS, acceleration=shaking):
    """The cut slope on a shaken base with a back wall: (scene, base, the blocks).

    ``mass`` is the rock mass (toe, base, back, crest; the default is the 20 m slope) and
    ``acceleration`` what the base and the wall follow (:meth:`dda.Scene.shake`: a callable
    or a pair ``(times, values)``)."""
    back_x, top = mass[1][0], max(y for _, y in mass)
    scene = dda.Scene(gravity=9.81)
    base = scene.add_block([(0, -3), (back_x + 4, -3), (back_x + 4, 0), (0, 0)], ROCK,
                           fixed=True, name="base")
    # the rock mass goes on behind the section: a wall on the base holds its back face
    back = scene.add_block([(back_x, 0), (back_x + 4, 0), (back_x + 4, top + 2),
                            (back_x, top + 2)], ROCK, fixed=True, name="back")
    blocks = [scene.add_block(b, ROCK, name=f"rock{i}")
              for i, b in enumerate(cut_blocks(mass, SETS, min_size=min_size, seed=seed))]
    scene.set_joint(JOINT)
    scene.shake(base, acceleration=acceleration)
    scene.shake(back, acceleration=acceleration)
    return scene, base, blocks


def face_motion(result, base, face) -> np.ndarray:
    """How far each of the ``face`` blocks ended from where it started, relative to the
    ``base`` (m)."""
    base_u = result.displacement(base)[-1]
    return np.array([np.hypot(*(result.displacement(b)[-1] - base_u)) for b in face])


def face_blocks(scene, blocks, depth: float = 2.0, mass=MASS):
    """The blocks within ``depth`` of the slope face (the ones that can fall)."""
    (x0, y0), (x1, y1) = mass[0], mass[3]
    n = np.array([y1 - y0, -(x1 - x0)]) / np.hypot(x1 - x0, y1 - y0)  # into the rock
    x, offsets = scene.vertex_arrays()
    out = []
    for b in blocks:
        corners = x[offsets[b.index]:offsets[b.index + 1]]
        if np.min((corners - [x0, y0]) @ n) < depth:
            out.append(b)
    return out


def _step(text: str):
    """``--dt``: seconds, or "auto"."""
    return "auto" if text == "auto" else float(text)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    ap.add_argument("--out", default="out/jointed_slope", help="output folder")
    ap.add_argument("--duration", type=float, default=0.3, help="simulated time, s")
    ap.add_argument("--dt", type=_step, default=2e-3,
                    help='time step, s, or "auto": chosen for the joints\' 5e10 N/m')
    ap.add_argument("--solver", choices=solver_names(), default="legacy")
    ap.add_argument("--seed", type=int, default=0,
                    help="another draw of the cross joints' traces (benchmarks/cut_rate.py)")
    ap.add_argument("--auto", action="store_true",
                    help='the penalty and dt chosen by the simulation ("auto"; --dt is ignored)')
    ap.add_argument("--start", choices=["rest", "settled"], default="rest",
                    help="settled: at rest under gravity before the run (dda.settling)")
    ap.add_argument("--cohesion", type=float, default=0.0,
                    help="the joints' cohesion, Pa (default 0)")
    args = ap.parse_args(argv)
    if not (np.isfinite(args.cohesion) and args.cohesion >= 0.0):
        ap.error(f"--cohesion must be a finite number of Pa, 0 or more, got {args.cohesion}")
    out = Path(args.out)
    scene, base, blocks = build_scene(seed=args.seed)
    if args.cohesion:
        scene.set_joint(JointMaterial(JOINT.normal_penalty, JOINT.shear_penalty,
                                      CoulombSingle(phi=35.0, cohesion=args.cohesion)))
    face = face_blocks(scene, blocks)
    print(f"{len(blocks)} blocks cut from the slope ({len(face)} on its face)")
    solver = make_solver(args.solver)
    if args.auto:
        scene.set_joint(JointMaterial("auto", "auto", scene.default_joint.friction))
    sim = dda.Simulation(scene, dt="auto" if args.auto else args.dt, solver=solver,
                         max_open_close=30, start=args.start)
    if sim.choices:
        print(sim.choices)
    if args.start == "settled":
        print(sim.settle().text)
    writer = dda.io.VTUWriter(out / "slope", interval=0.05)  # a frame every 0.05 s
    result = sim.run(args.duration, output=writer, progress=sys.stderr.isatty())
    moved = face_motion(result, base, face)
    print(f"after {args.duration:g} s the face blocks moved {1e3 * np.median(moved):.2f} mm "
          f"(median) and {1e3 * moved.max():.2f} mm (most) against the base")
    print(f"wrote {len(writer.files)} VTU files and {writer.pvd_path}")
    print(result.profile())
    return result, blocks, moved


if __name__ == "__main__":
    main()
