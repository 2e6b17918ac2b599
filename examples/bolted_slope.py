"""How safe is a jointed rock slope, dry, wet, and bolted: the factor of safety by strength
reduction (issue 23).

The slope is an 8 m version of ``examples/jointed_slope.py``'s cut (a face at 59 degrees,
bedding dipping 25 degrees out of the face 1 m apart, cross joints dipping 70 degrees into it,
80% persistent; phi 35 degrees on every joint), on a fixed base against a fixed back wall.
Three factors of safety, each by strength reduction of every joint (``tan(phi) / F``,
:func:`dda.studies.strength_reduction`):

1. dry: planar sliding on the bedding, ``F = tan 35 / tan 25 = 1.50``, found within 1%;
2. with a water table after heavy rain (from the toe up to 1.6 m below the crest where the
   mass meets the back wall, 1 m below it behind the wall): the pressure in the joints
   (:meth:`dda.Scene.set_water_table`) lifts the blocks off their bedding and F falls below
   1.3;
3. wet and bolted: a pattern of rock bolts (:meth:`dda.Scene.add_bolt`), each from 0.2 m
   inside the surface 3 m straight in (normal to the face, or down from the top), ties the
   block it starts in to the one its far end is in; F rises above 1.3 again. A bolt is an
   axial spring between its two ends only: it does not tie the blocks it passes through
   (each crosses 3 to 6 blocks here) and has no dowel action across a joint. On the 25
   degree bedding the face bolts pull, while the vertical bolts from the top shorten as the
   blocks above the bedding slide, and push (compression is carried without limit): wet,
   at F = 1.4 (a static trial), the four lower face bolts end at 4.8-8.6 kN/m of tension,
   the seven from the top at 0.26-4.0 kN/m of compression.

It writes, for a report, ``OUT/slope.png`` (the slope, its water table and its bolts),
``OUT/fos_dry.png``, ``OUT/fos_wet.png`` and ``OUT/fos_bolted.png`` (the failing blocks in red
and every trial's movement against F) and ``OUT/factors.csv``, and prints the three factors
with their trials. The trials run on a process pool of one worker a core (``--workers``); any
``concurrent.futures`` executor would do, a Dask cluster's too.

Run:  python examples/bolted_slope.py [--out DIR] [--workers N] [--tolerance 0.01]
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

import dda
from dda.geometry import cut_blocks

sys.path.insert(0, str(Path(__file__).resolve().parent))
import jointed_slope as SLOPE  # noqa: E402  (the cut's joint sets, rock and joints)

#: the 8 m slope: toe, base of the back wall, its top, crest (m)
MASS = [(0.4 * x, 0.4 * y) for x, y in SLOPE.MASS]
#: after heavy rain: dry at the toe, 1.6 m below the crest at the wall's face (x = 24 m) and
#: 1 m below it at x = 28 m (m)
WATER_TABLE = [(0.0, 0.0), (8.0, 0.0), (12.0, 4.5), (28.0, 7.0)]
#: the bolts: spacing along the top surface and the face (m), axial stiffness (N/m per m of
#: slope; a 25 mm bar, E 200 GPa, 3 m long at 1.5 m spacing in plane strain: E A / (L s) =
#: 2.2e7) and tensile strength (N/m: 250 kN a bar at 1.5 m)
BOLT_SPACING, BOLT_STIFFNESS, BOLT_STRENGTH = 1.5, 2.2e7, 1.7e5


def build_scene(water: bool = False, bolts: bool = False):
    """The slope on its fixed base and wall: (scene, the cut blocks, the bolt ends)."""
    back_x, top = MASS[1][0], max(y for _, y in MASS)
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(0, -3), (back_x + 4, -3), (back_x + 4, 0), (0, 0)], SLOPE.ROCK,
                    fixed=True, name="base")
    scene.add_block([(back_x, 0), (back_x + 4, 0), (back_x + 4, top + 2), (back_x, top + 2)],
                    SLOPE.ROCK, fixed=True, name="back")
    pieces = cut_blocks(MASS, SLOPE.SETS, min_size=0.10, seed=0)
    blocks = [scene.add_block(b, SLOPE.ROCK, name=f"rock{i}") for i, b in enumerate(pieces)]
    scene.set_joint(SLOPE.JOINT)
    if water:
        scene.set_water_table(WATER_TABLE)
    ends = []
    if bolts:
        for a, point_a, b, point_b in bolt_pattern(scene, blocks):
            scene.add_bolt(a, point_a, b, point_b, stiffness=BOLT_STIFFNESS,
                           strength=BOLT_STRENGTH)
            ends.append((point_a, point_b))
    return scene, blocks, ends


def _block_at(scene, blocks, point):
    """The cut block that holds ``point`` (strictly inside), or None."""
    from matplotlib.path import Path as Polygon

    x, offsets = scene.vertex_arrays()
    for b in blocks:
        if Polygon(x[offsets[b.index]:offsets[b.index + 1]]).contains_point(point):
            return b
    return None


def bolt_pattern(scene, blocks, length: float = 3.0):
    """Bolts every ``BOLT_SPACING`` along the top surface and the face, each from 0.2 m in
    from the surface straight into the slope (normal to the surface) for ``length``: from the
    block it starts in to the block its far end is in, where they differ."""
    (x0, y0), (x1, y1) = MASS[0], MASS[3]           # toe, crest
    face = np.array([x1 - x0, y1 - y0]) / np.hypot(x1 - x0, y1 - y0)
    into_face = np.array([face[1], -face[0]])        # normal to the face, into the rock
    lines = []
    for s in np.arange(0.75, np.hypot(x1 - x0, y1 - y0), BOLT_SPACING):
        lines.append((np.array([x0, y0]) + s * face, into_face))
    for x in np.arange(x1 + 0.75, MASS[1][0] - 0.5, BOLT_SPACING):
        lines.append((np.array([x, y1]), np.array([0.0, -1.0])))
    out = []
    for start, direction in lines:
        a_point = start + 0.2 * direction
        b_point = start + (0.2 + length) * direction
        a, b = _block_at(scene, blocks, a_point), _block_at(scene, blocks, b_point)
        if a is not None and b is not None and a != b:
            out.append((a, tuple(a_point), b, tuple(b_point)))
    return out


def picture(scene, blocks, ends, path):
    """The slope, its water table and its bolts."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    x, offsets = scene.vertex_arrays()
    polys = [x[offsets[i]:offsets[i + 1]] for i in range(len(offsets) - 1)]
    fixed = [b.fixed for b in scene.block_inputs]
    fig, ax = plt.subplots(figsize=(9, 4.2))
    ax.add_collection(PolyCollection(polys, facecolors=["0.55" if f else "0.88" for f in fixed],
                                     edgecolors="k", linewidths=0.5))
    table = np.array(WATER_TABLE)
    ax.plot(table[:, 0], table[:, 1], color="tab:blue", lw=2, label="water table")
    for k, (a, b) in enumerate(ends):
        ax.plot([a[0], b[0]], [a[1], b[1]], color="tab:red", lw=2,
                label="rock bolts" if k == 0 else None)
    ax.set_aspect("equal")
    ax.autoscale()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper left")
    ax.set_title(f"{len(blocks)} blocks; {len(ends)} bolts, {BOLT_SPACING:g} m apart")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    ap.add_argument("--out", default="out/bolted_slope", help="output folder")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                    help="processes the trials run on")
    ap.add_argument("--tolerance", type=float, default=0.01,
                    help="relative width of the factor's final bracket")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    with ProcessPoolExecutor(args.workers) as pool:
        for case, water, bolts in (("dry", False, False), ("wet", True, False),
                                   ("bolted", True, True)):
            scene, blocks, ends = build_scene(water, bolts)
            if bolts:
                picture(scene, blocks, ends, out / "slope.png")
            start = time.perf_counter()
            fos = dda.studies.strength_reduction(scene, executor=pool,
                                                 tolerance=args.tolerance)
            wall = time.perf_counter() - start
            fos.picture(out / f"fos_{case}.png")
            print(f"{case:>6}: {fos}\n        ({wall:.0f} s of wall time)")
            rows.append({"case": case, "factor": round(fos.factor, 4),
                         "stable_at": round(fos.bracket[0], 4),
                         "failed_at": round(fos.bracket[1], 4), "trials": len(fos.trials),
                         "bolts": len(ends), "wall_s": round(wall, 1)})
    with open(out / "factors.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {out / 'slope.png'}, {out}/fos_*.png and {out / 'factors.csv'}")
    return rows


if __name__ == "__main__":
    main()
