"""A two-block rock slope on a shaking table: the main demo.

The geometry and materials follow the shaking-table test of S 3(2) (Adachi et al. 2017;
METHOD.md section 9; :func:`dda.studies.cases.rock_slope`): two Ryukyu limestone blocks on a
joint dipping 15 degrees, the lower one's face 380 mm wide along x, the upper block 240 mm
along x and 130 mm high; E = 7 GPa, nu = 0.33, unit weight 22 kN/m^3; kn = 10 GN/m. The
lower block is bolted to the table, which shakes horizontally at 2 Hz with an amplitude
raised in steps.

With one friction angle phi the upper block first slides down the joint when the table
accelerates away from the slope's toe faster than the joint can hold:
a_x > g tan(phi - 15 deg) (the table pulls the lower block from under the upper one). A lip at
the toe of the lower block (a non-convex block) stops the slide after 10.5 cm, as the stopper
of the test did.

Writes ``OUT/slope_*.vtu`` + ``OUT/slope.pvd`` (open in ParaView or pyvista) and
``OUT/slide.png``, and prints the slide at the end.

Run:  python examples/shaking_slope.py [--out DIR] [--duration S] [--dt S] [--phi DEG]
                                       [--solver newton|legacy]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import dda
from dda.contact import CoulombSingle
from dda.registry import make_solver, solver_names
from dda.studies.cases import SLOPE_DIP, SLOPE_STOP, rock_slope, slide_down_dip, stepped_table

G = 9.81
DIP = np.radians(SLOPE_DIP)
STOP = SLOPE_STOP  # slide down the joint at which the stopper holds the upper block (m)


def table_acceleration(peak_gal: float = 670.0, freq: float = 2.0, levels: int = 6,
                       hold: float = 1.0):
    """The table: a 2 Hz wave raised in ``levels`` steps, one every ``hold`` seconds, to
    ``peak_gal`` (:func:`dda.studies.cases.stepped_table`)."""
    return stepped_table(peak_gal, freq, levels, hold)


def slide_threshold(phi: float) -> float:
    """Table acceleration (m/s^2, towards the slope's back) at which the upper block slips:
    g tan(phi - 15 deg), from the block's balance in the table's frame."""
    return G * np.tan(np.radians(phi) - DIP)


def build_scene(phi: float = 31.6, peak_gal: float = 670.0):
    """The scene: a lower block with a 15 degree face (on the table) and an upper block on it
    (:func:`dda.studies.cases.rock_slope`), one friction angle, kn = ks = 10 GN/m."""
    return rock_slope(CoulombSingle(phi=phi), table_acceleration(peak_gal),
                      shear_penalty=10e9)


def slide_along_joint(result, lower, upper) -> np.ndarray:
    """Displacement of the upper block relative to the lower one, down the joint (m)."""
    return slide_down_dip(result, lower, upper)


def slide_start(result, slide, creep: float = 1e-5) -> float:
    """First time the slide exceeds ``creep`` metres beyond its elastic settling (its value at
    0.5 s); nan if it never does, or if the run ends before the settling does."""
    settled_at = np.searchsorted(result.time, 0.5)
    if settled_at >= len(slide):
        return float("nan")
    settled = slide[settled_at]
    moving = np.flatnonzero(slide - settled > creep)
    return float(result.time[moving[0]]) if len(moving) else float("nan")


def threshold_time(args) -> float:
    """First time the table acceleration exceeds the slip threshold (towards -x)."""
    accel = table_acceleration(args.peak)
    t = np.arange(0.0, args.duration, 1e-4)
    ax = np.array([accel(ti)[0] for ti in t])
    beyond = np.flatnonzero(-ax > slide_threshold(args.phi))
    return float(t[beyond[0]]) if len(beyond) else float("nan")


def plot(result, lower, upper, accel, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = result.time
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
    ax1.plot(t, [100 * accel(ti)[0] for ti in t], lw=0.8, color="0.3")
    ax1.set_ylabel("table acceleration (gal)")
    ax2.plot(t, 1e3 * slide_along_joint(result, lower, upper), color="C3")
    ax2.set_ylabel("slide down the joint (mm)")
    ax2.set_xlabel("time (s)")
    ax1.set_title("Two-block slope on a shaking table (DDA)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    ap.add_argument("--out", default="out/demo", help="output folder (default out/demo)")
    ap.add_argument("--duration", type=float, default=6.0, help="simulated time, s")
    ap.add_argument("--dt", type=float, default=1e-3, help="time step, s")
    ap.add_argument("--phi", type=float, default=31.6, help="joint friction angle, degrees")
    ap.add_argument("--peak", type=float, default=670.0, help="last amplitude step, gal")
    ap.add_argument("--solver", choices=solver_names(), default="newton",
                    help="fully implicit Newton-Raphson (default) or legacy DDA")
    args = ap.parse_args(argv)
    out = Path(args.out)
    scene, lower, upper = build_scene(args.phi, args.peak)
    writer = dda.io.VTUWriter(out / "slope", every=max(1, int(round(0.02 / args.dt))))
    solver = make_solver(args.solver)
    sim = dda.Simulation(scene, dt=args.dt, solver=solver)
    result = sim.run(args.duration, output=writer, progress=sys.stderr.isatty())
    accel = table_acceleration(args.peak)
    plot(result, lower, upper, accel, out / "slide.png")
    slide = slide_along_joint(result, lower, upper)
    start = slide_start(result, slide)
    when = (f"it starts at t = {start:.3f} s" if np.isfinite(start)
            else "it has not started by the end of the run")
    t_beyond = threshold_time(args)
    beyond = f"at t = {t_beyond:.3f} s" if np.isfinite(t_beyond) else "not within the run"
    print(f"slide down the joint after {args.duration:g} s: {1e3 * slide[-1]:.2f} mm; {when} "
          f"(table beyond g tan(phi - 15) = {100 * slide_threshold(args.phi):.0f} gal "
          f"{beyond})")
    print(f"wrote {len(writer.files)} VTU files, {writer.pvd_path} and {out / 'slide.png'}")
    print(result.profile())
    return result, slide


if __name__ == "__main__":
    main()
