"""The jointed slope shaken by a recorded motion: a PEER NGA .AT2 or K-NET / KiK-net file.

The slope of ``jointed_slope.py`` (the same rock, joints and joint sets: bedding dipping 25
degrees out of the face, 1 m apart, cross joints dipping 70 degrees into it) rests on a base
and against a back wall that follow a recorded accelerogram, horizontally
(``dda.io.records``). A record from PEER's NGA database (``.AT2``, in g) or from K-NET /
KiK-net (``.EW``, ``.NS``, ``.EW2`` ..., counts times the file's scale factor, less their
mean) is read with ``--record FILE``; ``--baseline`` takes a trend away (``quadratic`` is the
classic correction; PEER's records are corrected already, so the default is none).

No record is shipped with dda. Without ``--record`` the example makes one and says so: a
deterministic synthetic motion (:func:`synthetic_record`: white noise of a fixed seed
filtered to 1 - 8 Hz, under an envelope that rises to its peak at 0.8 s and decays, its
trend taken away so the table ends at rest, scaled to 0.3 g), written as a PEER ``.AT2``
file in the output folder and read back as any record is.

The example cuts a smaller slope by default, the same section scaled to 8 m high, so that
it runs in seconds; ``--full`` shakes the 20 m slope of ``jointed_slope.py``. With the
defaults (the synthetic 4 s record at 100 Hz, 0.3 g, legacy DDA, dt 2e-3 s asked for) it cuts
62 blocks (17 on the face) and takes 8 to 11 s (2,032 steps, 6 cut, 1.85 OPEN-CLOSE passes a step);
the face blocks slip about 3 mm during the 0.3 g pulse at 0.5 s and a little more at 1.1 s,
and end 3.2 mm (median) and 3.6 mm (most) from where they started relative to the base,
which ends 4.7 mm from its start (the record's own displacement, 4.69 mm: the synthetic
record ends at rest but not where it started). With ``--full``: 311 blocks (39 on the face),
50 s (2,507 steps, 36 cut, 4.3 passes a step), the face 5.2 / 6.7 mm (1.8 minutes on the
machine of issue 22, two cores shared by four jobs).

Writes ``OUT/synthetic.AT2`` (without ``--record``), ``OUT/slope_*.vtu`` + ``OUT/slope.pvd``
and ``OUT/record.png`` (the record, the table's displacement, and how far the face moved),
and prints the record, the blocks, and how far the face blocks moved.

Run:  python examples/recorded_shaking.py [--record FILE] [--out DIR] [--duration S]
                                          [--scale F] [--baseline none|mean|linear|quadratic]
                                          [--dt S] [--solver legacy|newton] [--full]
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import numpy as np

import dda
from dda.io.records import G, baseline_correct, read_record, write_at2
from dda.registry import make_solver, solver_names


def _jointed_slope():
    """examples/jointed_slope.py, the slope this example shakes (imported by its path)."""
    spec = importlib.util.spec_from_file_location(
        "jointed_slope", Path(__file__).resolve().parent / "jointed_slope.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


SLOPE = _jointed_slope()
#: the 20 m section scaled by 0.4: toe, base, back, crest (an 8 m high face at 59 degrees)
SMALL = [(0.4 * x, 0.4 * y) for x, y in SLOPE.MASS]


def synthetic_record(duration: float = 4.0, dt: float = 0.01, pga: float = 0.3 * G,
                     seed: int = 22, band=(1.0, 8.0), peak_time: float = 0.8):
    """A deterministic stand-in for a recorded accelerogram: ``(times, acceleration)`` in s
    and m/s^2.

    White noise of ``seed``, filtered to ``band`` Hz (cosine tapers half an octave wide),
    under the envelope ``(t / t_p)^2 exp(2 (1 - t / t_p))`` that peaks at ``peak_time``;
    then the quadratic baseline is taken away (:func:`dda.io.records.baseline_correct`, so a
    table that follows it ends at rest) and the peak scaled to ``pga``.
    """
    n = int(round(duration / dt)) + 1
    t = np.arange(n) * dt
    rng = np.random.default_rng(seed)
    spectrum = np.fft.rfft(rng.standard_normal(n))
    f = np.fft.rfftfreq(n, dt)
    lo, hi = band
    gain = np.clip((np.log2(f + 1e-12) - np.log2(lo / np.sqrt(2))) / 0.5, 0, 1) * np.clip(
        (np.log2(hi * np.sqrt(2)) - np.log2(f + 1e-12)) / 0.5, 0, 1)
    a = np.fft.irfft(spectrum * 0.5 * (1 - np.cos(np.pi * gain)), n)
    s = t / peak_time
    a *= s**2 * np.exp(2 * (1 - s))
    a = baseline_correct(t, a, "quadratic")
    return t, a * (pga / np.abs(a).max())


def write_synthetic(path: Path, **kwargs) -> Path:
    """:func:`synthetic_record` written as a PEER NGA ``.AT2`` file (values in g)."""
    t, a = synthetic_record(**kwargs)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_at2(path, a / G, dt=float(t[1] - t[0]),
              event="Synthetic motion (seed 22, 1-8 Hz), 2024, dda examples, H1")
    return path


def plot(result, record, base, moved_in_time, path: Path, scale: float = 1.0) -> float:
    """``OUT/record.png``: the record as the base followed it (times ``scale``), the base's
    displacement, and how far the face moved; returns the peak drawn (g)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2, ax3) = plt.subplots(3, 1, sharex=True, figsize=(7, 6.5))
    drawn = scale * record.acceleration / G  # the record as the base followed it
    ax1.plot(record.times, drawn, lw=0.7, color="0.3")
    ax1.set_ylabel("base acceleration (g)")
    scaled = "" if scale == 1.0 else f" x {scale:g}"
    ax1.set_title(f"Jointed slope shaken by {Path(record.path).name}{scaled}")
    ax2.plot(result.time, 1e3 * result.displacement(base)[:, 0], color="C0")
    ax2.set_ylabel("base displacement (mm)")
    median, most = moved_in_time
    ax3.plot(result.time, 1e3 * median, color="C3", label="median")
    ax3.plot(result.time, 1e3 * most, color="C1", label="most")
    ax3.set_ylabel("face blocks moved (mm)")
    ax3.set_xlabel("time (s)")
    ax3.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return float(np.abs(drawn).max())


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    ap.add_argument("--record", help="a PEER .AT2 or K-NET / KiK-net file (default: a "
                                     "synthetic record, written to the output folder)")
    ap.add_argument("--out", default="out/recorded_shaking", help="output folder")
    ap.add_argument("--duration", type=float, help="simulated time, s (default: the record's)")
    ap.add_argument("--scale", type=float, default=1.0, help="multiplies the record")
    ap.add_argument("--baseline", choices=["none", "mean", "linear", "quadratic"],
                    default="none", help="trend taken away from the record (default none)")
    ap.add_argument("--dt", type=float, default=2e-3, help="time step, s")
    ap.add_argument("--solver", choices=solver_names(), default="legacy")
    ap.add_argument("--full", action="store_true", help="the full 20 m slope (slow)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    if args.record is None:
        path = write_synthetic(out / "synthetic.AT2")
        print(f"no --record given: wrote a synthetic record (deterministic, seed 22) to {path}")
    else:
        path = Path(args.record)
    raw = read_record(path)
    record = raw.corrected(args.baseline)
    v_end, u_end = raw.end_motion()
    print(f"record {path.name} ({raw.format}, {raw.station or 'station ?'}, "
          f"{raw.direction or '?'}): {len(raw.times)} samples at dt {raw.dt:g} s "
          f"({raw.duration:g} s), peak {args.scale * raw.peak / G:.3f} g; a table following it "
          f"ends at {args.scale * v_end:.3g} m/s, {args.scale * u_end:.3g} m from its start"
          + (f" ({args.baseline} baseline: {args.scale * record.end_motion()[0]:.3g} m/s, "
             f"{args.scale * record.end_motion()[1]:.3g} m)" if args.baseline != "none" else ""))
    mass = SLOPE.MASS if args.full else SMALL
    table = (record.times, args.scale * record.acceleration)
    scene, base, blocks = SLOPE.build_scene(mass=mass, acceleration=table)
    face = SLOPE.face_blocks(scene, blocks, mass=mass)
    print(f"{len(blocks)} blocks cut from the {'20' if args.full else '8'} m slope "
          f"({len(face)} on its face)")
    duration = args.duration or raw.duration
    sim = dda.Simulation(scene, dt=args.dt, solver=make_solver(args.solver),
                         max_open_close=30)
    writer = dda.io.VTUWriter(out / "slope", interval=0.05)  # a frame every 0.05 s
    result = sim.run(duration, output=writer, progress=sys.stderr.isatty())
    base_u = result.displacement(base)
    moved = np.array([np.hypot(*(result.displacement(b) - base_u).T) for b in face])
    median, most = np.median(moved, axis=0), moved.max(axis=0)
    plot(result, record, base, (median, most), out / "record.png", args.scale)
    print(f"after {duration:g} s the face blocks moved {1e3 * median[-1]:.1f} mm (median) and "
          f"{1e3 * most[-1]:.1f} mm (most) against the base; the base ended "
          f"{1e3 * base_u[-1, 0]:.1f} mm from its start")
    print(f"wrote {len(writer.files)} VTU files, {writer.pvd_path} and {out / 'record.png'}")
    print(result.profile())
    return result, record, moved[:, -1]


if __name__ == "__main__":
    main()
