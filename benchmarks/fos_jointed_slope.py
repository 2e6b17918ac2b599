"""Factor of safety of the jointed slope of ``examples/jointed_slope.py`` by strength reduction.

The 20 m slope (face at 59 degrees) cut by bedding dipping 25 degrees out of the face, 1 m
apart, and cross joints dipping 70 degrees into it (313 blocks, 5e10 N/m, phi 35 degrees),
on a fixed base against a fixed back wall, without the example's shaking. Blocks cut free
by the bedding daylight in the face, so planar sliding on the bedding gives the reference
``F = tan 35 / tan 25 = 1.5016``.

``dda.studies.strength_reduction`` with its defaults (static trials of 40 steps, a
resolution of 1e-3 g, a 1% bracket), its trials on ``--workers`` local processes, or on a
Dask cluster with ``--scheduler tcp://host:8786``. Writes ``results/fos_jointed_slope.md``
(F, the trials), ``.csv`` (the trials) and ``.png`` (the failing blocks, the trials).

Measured (``results/fos_jointed_slope.md``, two workers): F = 1.5015 (stable at 1.4951,
failed at 1.5080; -0.01% against planar sliding), 68 blocks sliding out on a bedding plane;
12 trials in 6 rounds, 1,357 s of CPU, 951 s of wall time. A trial costs 76-133 s of CPU
(274 s at F = 0.5), most of it the first 2,300 to 4,700 steps, in which the stiff contacts
settle at 4e-5 to 1e-3 s (the trial's own steps are 0.019 s). An earlier run on one worker,
bracket 1..2: 1.505 (1.501 / 1.509), 9 trials.

Run:  python benchmarks/fos_jointed_slope.py [--workers N] [--scheduler ADDRESS]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import dda
from dda.geometry import cut_blocks
from dda.studies.sweep import markdown_table, write_csv

HERE = Path(__file__).resolve().parent


def build_scene(min_size: float = 0.10, seed: int = 0):
    """The example's cut slope on a fixed base against a fixed back wall (no shaking)."""
    sys.path.insert(0, str(HERE.parent / "examples"))
    from jointed_slope import JOINT, MASS, ROCK, SETS

    mass = MASS
    back_x, top = mass[1][0], max(y for _, y in mass)
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(0, -3), (back_x + 4, -3), (back_x + 4, 0), (0, 0)], ROCK, fixed=True,
                    name="base")
    scene.add_block([(back_x, 0), (back_x + 4, 0), (back_x + 4, top + 2), (back_x, top + 2)],
                    ROCK, fixed=True, name="back")
    for i, b in enumerate(cut_blocks(mass, SETS, min_size=min_size, seed=seed)):
        scene.add_block(b, ROCK, name=f"rock{i}")
    scene.set_joint(JOINT)
    return scene


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2, help="local worker processes")
    ap.add_argument("--scheduler", help="a Dask scheduler's address (instead of --workers)")
    ap.add_argument("--out", default=str(HERE / "results"), help="output folder")
    args = ap.parse_args(argv)
    scene = build_scene()
    planar = math.tan(math.radians(35.0)) / math.tan(math.radians(25.0))
    start = time.perf_counter()
    warnings.simplefilter("ignore", dda.PenaltyWarning)  # the stiff contacts: cut steps
    if args.scheduler:
        from distributed import Client

        with Client(args.scheduler) as client:
            fos = dda.studies.strength_reduction(scene, executor=client.get_executor())
    else:
        with ProcessPoolExecutor(args.workers) as pool:
            fos = dda.studies.strength_reduction(scene, executor=pool,
                                                 per_round=args.workers)
    wall = time.perf_counter() - start
    print(fos)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    columns = ["round", "factor", "stable", "movement", "max_displacement", "trial_time",
               "steps", "dt_cuts", "cpu_time"]
    lo, hi = fos.bracket
    text = (f"# Factor of safety of the jointed slope by strength reduction\n\n"
            f"`python benchmarks/fos_jointed_slope.py` ({len(scene.blocks)} blocks, "
            f"{args.scheduler or f'{args.workers} local workers'}).\n\n"
            f"F = {fos.factor:.4f} (stable at {lo:.4f}, failed at {hi:.4f}); planar sliding "
            f"on the 25 degree bedding: tan 35 / tan 25 = {planar:.4f} "
            f"({100 * (fos.factor / planar - 1):+.2f}%). {len(fos.failing_blocks)} blocks "
            f"fail at {hi:.4f}. {len(fos.trials)} trials in {fos.rounds} rounds, "
            f"{sum(r['cpu_time'] for r in fos.trials):.0f} s of CPU, {wall:.0f} s of wall "
            f"time.\n\n{fos.plan.describe()}.\n\n"
            + markdown_table(fos.trials, columns, {"factor": ".4f", "movement": ".3g",
                                                   "max_displacement": ".3g",
                                                   "trial_time": ".3g", "cpu_time": ".1f"}))
    (out / "fos_jointed_slope.md").write_text(text)
    write_csv(fos.trials, out / "fos_jointed_slope.csv")
    fos.picture(out / "fos_jointed_slope.png")
    print(f"wrote {out / 'fos_jointed_slope.md'}, .csv and .png")
    return fos


if __name__ == "__main__":
    main()
