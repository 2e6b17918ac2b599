"""The ``dda`` command: run a scene file or script, run the demo, render a series, describe a
scene.

    dda run SCENE.toml|SCRIPT.py|RUN.ckpt [--out DIR] [--duration S] [--no-progress]
                                          [--allow-outside-output]
    dda demo [--out DIR] [--duration S] [--no-progress]
    dda render OUT/case.pvd [--png FILE] [--gif FILE] [--mp4 FILE] [--field NAME] [--frame N]
                            [--relative-to BLOCK|auto|none] [--fps F] [--max-frames N]
    dda info SCENE.toml|SCRIPT.py
    dda fos SCENE.toml [--tolerance T] [--analysis auto|static|dynamic] [--resolution G]
                       [--displacement-ratio R] [--workers N] [--picture FILE] [--csv FILE]
                       [--no-progress]

Exit codes: 0 done; 1 a run that stopped (SimulationError: its files so far are written);
2 a mistake in the input (a scene file's error, a path that cannot be written, a bad
option); 130 interrupted (Ctrl-C, SIGTERM).
"""

from __future__ import annotations

import argparse
import runpy
import sys
import tempfile
import time
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from dda.io.vtu import VTUWriter

__all__ = ["main"]


def _run_scene(path, out, duration, progress, outside=False, start=None):
    from dda.io.scene_file import load_scene

    loaded = load_scene(path, allow_outside_output=outside)
    if start is not None:  # --start overrides the file's [simulation] start
        loaded.settings = {**loaded.settings, "start": start}
    if out is None and loaded.output_dir is None:
        out = Path("out") / Path(path).stem
    writer = loaded.writer(out)
    duration = duration if duration is not None else loaded.duration
    if duration is None:
        raise SystemExit(f"{loaded.path.name}: give [simulation] duration or --duration")
    sim = loaded.simulation()
    print(f"{loaded.path.name}: {len(loaded.blocks)} blocks, solver {loaded.solver!r}, "
          f"dt {sim.dt:g} s")
    for line in sim.choices.splitlines():  # what "auto" settings chose, and why
        print(f"  auto: {line}")
    if sim.start == "settled":
        print(f"  {sim.settle().text}")
    ckpt = loaded.checkpoint_settings(out)
    result = sim.run(duration, output=writer, progress=progress, **ckpt)
    print(result.stats.summary())
    if writer is not None:
        print(f"wrote {len(writer.files)} VTU files and {writer.pvd_path}")
    if ckpt:
        print(f"checkpoint {ckpt['checkpoint']}")
    return result


def _resume(path, duration, progress, outside=False):
    from dda.simulation import Simulation

    sim = Simulation.resume(path, allow_outside_output=outside)
    print(f"{path}: resuming at t = {sim.committed.time:g} s")
    result = sim.run(duration, progress=progress)
    print(result.stats.summary())
    return result


def _run_script(path, out):
    argv = [str(path)] + (["--out", str(out)] if out is not None else [])
    saved = sys.argv
    sys.argv = argv
    try:
        runpy.run_path(str(path), run_name="__main__")
    finally:
        sys.argv = saved


def cmd_run(args):
    path = Path(args.scene)
    if not path.is_file():
        raise SystemExit(f"dda run: no file {path}")
    if path.suffix == ".py":
        given = [flag for flag, on in (("--duration", args.duration is not None),
                                       ("--no-progress", args.no_progress),
                                       ("--allow-outside-output", args.allow_outside_output),
                                       ("--start", args.start is not None))
                 if on]
        if given:  # (a script reads its own arguments; these would be dropped silently)
            raise SystemExit(
                f"dda run: {', '.join(given)} applies to a scene file or a checkpoint, not to "
                f"a script; a script gets --out only, in its sys.argv (run it as "
                f"'python {path} ...' to give it its own options)")
        _run_script(path, args.out)
    elif path.suffix == ".ckpt":
        if args.start is not None:
            raise SystemExit("dda run: --start applies to a scene file; a checkpoint goes on "
                             "from where its run stopped")
        _resume(path, args.duration, _progress(args), args.allow_outside_output)
    else:
        _run_scene(path, args.out, args.duration, _progress(args),
                   args.allow_outside_output, args.start)
    return 0


def _progress(args) -> bool:
    return not args.no_progress and sys.stderr.isatty()


def cmd_demo(args):
    demo = resources.files("dda") / "scenes" / "demo.toml"
    with resources.as_file(demo) as path:
        _run_scene(path, args.out or "out/stack_demo", args.duration, _progress(args))
    return 0


def cmd_render(args):
    from dda import plot

    for option, name in (("--gif", args.gif), ("--mp4", args.mp4)):
        if name and Path(name).suffix.lower() != f".{option[2:]}":
            raise ValueError(f"{option} {name}: the file name must end in "
                             f".{option[2:]}")
    if not (args.png or args.gif or args.mp4):
        args.png = str(Path(args.pvd).with_suffix(".png"))
    if args.png:
        png = plot.render_frame(args.pvd, args.png, frame=args.frame, field=args.field,
                                relative_to=args.relative_to)
        print(f"wrote {png}")
    movies = [m for m in (args.gif, args.mp4) if m]
    if movies:  # each frame drawn once for both
        for made in plot.animate_to(movies, args.pvd, field=args.field, fps=args.fps,
                                    max_frames=args.max_frames,
                                    relative_to=args.relative_to):
            print(f"wrote {made}")
    return 0


def _time_steps(sim, steps: int, budget: float):
    """Run ``sim`` for its first steps and time them: the start-up (3 steps, in which the
    compiled kernels load), then chunks of doubling length while ``budget`` seconds last.
    Returns (seconds per step after the start-up, the start-up's seconds, steps timed after
    it, start-up steps)."""
    warm = min(3, steps)
    start = time.perf_counter()
    sim.run(warm * sim.dt, progress=False)
    startup = time.perf_counter() - start
    done, spent, chunk = 0, 0.0, 1
    while done < steps - warm and spent < budget:
        n = min(chunk, steps - warm - done)
        start = time.perf_counter()
        done += len(sim.run(n * sim.dt, progress=False).stats)
        spent += time.perf_counter() - start
        chunk *= 2
    return (spent / done if done else 0.0), startup, done, warm


def describe(loaded, budget: float = 2.0) -> str:
    """What ``dda info`` prints: blocks, joints, effects, contacts at the start, and the cost
    estimated from steps actually run: the first 3 (the compiled kernels load: a start-up cost
    every run pays), then as many as ``budget`` seconds allow, the run's own cost when that is
    all of them, and one VTU frame's write times the frames."""
    from dda.contact.detection import (
        TOUCH_TOLERANCE,
        bounding_boxes,
        broad_phase,
        narrow_phase,
        pairs_with_free_block,
    )

    scene = loaded.scene
    sim = loaded.simulation()
    model = sim.model
    inputs = scene.block_inputs
    n = len(inputs)
    fixed = int(np.count_nonzero(~model.free))
    rigid = sum(1 for i, b in enumerate(inputs) if b.rigid and model.free[i])
    unknowns = 6 * int(np.count_nonzero(model.free)) - 3 * rigid
    size = float(np.max(model.size))
    # blocks whose motion is known never get a contact between them (step._pairs)
    pairs = pairs_with_free_block(broad_phase(bounding_boxes(model.x_initial, model.offsets),
                                              1e-6 * size), model.free)
    touch = narrow_phase(model.x_initial, model.topo, 1e-6 * size, 1e-6 * size, pairs,
                         touch=TOUCH_TOLERANCE)
    laws = ", ".join(sorted({type(law).__name__ for law in model.joints.laws}))
    lines = [
        f"scene      {loaded.path}",
        f"blocks     {n} ({n - fixed} free of which {rigid} rigid, {fixed} fixed or moved)",
        f"vertices   {len(model.x_initial)}",
        f"unknowns   {unknowns}",
        f"contacts   {len(touch)} vertex-edge pairs touching at the start "
        f"({touch.pairs} block pair{'' if touch.pairs == 1 else 's'})",
        f"joints     {len(model.joints.normal_penalty)} ({laws})",
        f"effects    {', '.join(loaded.effects) or 'none'}",
        f"solver     {loaded.solver!r}, dt {sim.dt:g} s, {sim.analysis}",
    ]
    # what "auto" settings chose, and why (dda.auto_settings)
    lines += [("auto       " if k == 0 else "           ") + line
              for k, line in enumerate(sim.choices.splitlines())]
    if sim.start == "settled":
        lines.append("start      settled: static steps to rest under the loads at t = 0, the "
                     "joints' friction held, then their own (dda.settling; not timed below)")
    if loaded.duration is not None:
        # a record that ends before the run: the run refuses it at once, and so does this
        for s in model.shakes:
            s.history.check_covers(sim.committed.time + loaded.duration)
        steps = int(np.ceil(loaded.duration / sim.dt - 1e-9))
        per_step, startup, done, warm = _time_steps(sim, steps, budget)
        # 'dda run' writes a VTU frame every [output] every steps, or one each [output]
        # interval of simulated time (a script's run: its writer's, or none): time one
        interval = getattr(loaded, "interval", None)
        if interval:  # a frame at the first step at least interval after the last one,
            # and the run's last
            every = max(int(np.ceil(interval / sim.dt - 1e-9)), 1)
            frames = steps // every + 1 + (1 if steps % every else 0)
        else:
            frames = 0 if loaded.every is None else steps // max(loaded.every, 1) + 1
        per_frame = 0.0
        if frames:
            with tempfile.TemporaryDirectory() as folder:
                writer = VTUWriter(Path(folder) / "frame")
                times = []
                for _ in range(3):  # the first loads meshio's writer
                    start = time.perf_counter()
                    writer.write(sim.frame())
                    times.append(time.perf_counter() - start)
                writer.close()
                per_frame = float(np.mean(times[1:]))
        total = startup + per_step * (steps - warm) + per_frame * frames
        timed = ("all of them" if warm + done >= steps else
                 f"steps {warm + 1} to {warm + done}; cuts add more")
        writes = (f" and {1e3 * per_frame:.3g} ms for each of {frames} VTU frames" if frames
                  else "; no VTU frames")
        # (at least: a cut step, or one shortened at a located slip reversal, adds steps)
        lines.append(f"cost       {loaded.duration:g} s = {steps} steps of {sim.dt:.3g} s or more; "
                     f"about {total:.3g} s: "
                     f"{startup:.2g} s to start, {1e3 * per_step:.3g} ms per step (timed on "
                     f"{timed}){writes}")
    return "\n".join(lines)


class _FirstRun(BaseException):  # not an Exception: a script's ``except Exception`` lets it by
    """Raised in place of a script's first :meth:`dda.Simulation.run`: the simulation, the
    duration and the output it was given."""


@dataclass
class _ScriptRun:
    """A script's first simulation, as :func:`describe` reads a scene file's."""

    path: str  # the script, and which of its simulations this is
    sim: object
    duration: float | None
    every: int | None  # VTU frames every this many steps (None: the run writes none)
    interval: float | None = None  # ... or one each this much simulated time (s)

    @property
    def scene(self):
        return self.sim.scene

    @property
    def solver(self):
        return self.sim.solver

    @property
    def effects(self) -> list:
        return scene_effects(self.sim.scene)

    def simulation(self):
        return self.sim


def scene_effects(scene) -> list:
    """What a :class:`dda.Scene` holds beyond its blocks and joints, in words (a scene file's
    ``effects``)."""
    names = [b.name for b in scene.blocks]
    out = ["gravity"] if scene.gravity else []
    out += [f"shaking of {names[s.block]}" for s in scene.shakes]
    out += [f"prescribed motion of {names[m.block]}" for m in scene.motions]
    out += [f"point load on {names[p.block]}" for p in scene.point_loads]
    if scene.bolts:
        out.append(f"{len(scene.bolts)} bolt{'s' if len(scene.bolts) > 1 else ''}")
    if scene.damping_settings:
        out.append("damping")
    if scene.water is not None:
        out.append("water table")
    return out


def _first_run(path) -> _ScriptRun:
    """Run the script at ``path`` until it first calls :meth:`dda.Simulation.run` in this
    process, and stop it there: that simulation, as it was about to run."""
    from dda.simulation import Simulation

    real = Simulation.run

    def caught(self, duration=None, output=None, *args, **kwargs):
        raise _FirstRun(self, duration, output)

    Simulation.run = caught
    try:
        _run_script(path, None)
    except _FirstRun as first:
        sim, duration, output = first.args
        writer = output if output is not None else sim.output
        every = getattr(writer, "every", None)
        if duration is None and sim._resume_end is not None:
            duration = sim._resume_end - sim.committed.time
        return _ScriptRun(f"{path} (the first simulation it runs)", sim, duration, every,
                          getattr(writer, "interval", None))
    finally:
        Simulation.run = real
    raise ValueError(f"{path} ran to its end without running a dda.Simulation in its own "
                     "process (a sweep's workers run theirs elsewhere): nothing to describe")


def cmd_info(args):
    from dda.io.scene_file import load_scene

    path = Path(args.scene)
    if path.suffix == ".py":
        if not path.is_file():
            raise SystemExit(f"dda info: no file {path}")
        print(describe(_first_run(path)))
    else:
        print(describe(load_scene(path)))
    return 0


def cmd_fos(args):
    """``dda fos SCENE.toml``: the factor of safety by strength reduction, its trials."""
    from concurrent.futures import ProcessPoolExecutor

    from dda.io.scene_file import load_scene
    from dda.studies.factor_of_safety import Criterion, strength_reduction

    loaded = load_scene(args.scene)
    criterion = Criterion(analysis=args.analysis, resolution=args.resolution,
                          displacement_ratio=args.displacement_ratio)
    workers = args.workers or None
    with ProcessPoolExecutor(max_workers=workers) as pool:
        try:
            fos = strength_reduction(loaded.scene, executor=pool, criterion=criterion,
                                     tolerance=args.tolerance, solver=loaded.solver,
                                     per_round=workers, progress=_progress(args))
        except TypeError as exc:  # a friction law without a reduction, a scene not to pickle
            raise ValueError(str(exc)) from None
    print(fos)
    print(fos.trials.table(["round", "factor", "stable", "movement", "max_displacement",
                            "failing_blocks", "trial_time", "steps", "cpu_time"]))
    if args.picture:
        fos.picture(args.picture)
        print(f"wrote {args.picture}")
    if args.csv:
        from dda.studies.sweep import write_csv

        print(f"wrote {write_csv(fos.trials, args.csv)}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="dda", description="2D Discontinuous Deformation "
                                 "Analysis: run scene files, render their output.")
    from dda import __version__

    ap.add_argument("--version", action="version", version=f"dda {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("run", help="run a TOML scene or a Python script, or resume a "
                       "checkpoint")
    p.add_argument("scene", help="SCENE.toml, SCRIPT.py or RUN.ckpt (a checkpoint of a run "
                   "to finish, or to go on for --duration)")
    p.add_argument("--out", help="output folder (default: the scene's [output] dir, under "
                   "the scene file's folder, or else out/NAME under the current folder)")
    p.add_argument("--duration", type=float, help="simulated time (s), overrides the file's")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--start", choices=["rest", "settled"], default=None,
                   help="how a dynamic run starts, overrides the file's [simulation] start: "
                   "rest (the loads switched on at t = 0) or settled (at rest under them "
                   "first; dda.settling)")
    p.add_argument("--allow-outside-output", action="store_true",
                   help="let a scene file's [output] dir be absolute or climb out of the "
                   "file's folder with '..', and a resumed checkpoint write its VTU series "
                   "outside the checkpoint's folder (both refused by default)")
    p.set_defaults(func=cmd_run)
    p = sub.add_parser("demo", help="run a shaken stack of blocks (writes out/stack_demo)")
    p.add_argument("--out", help="output folder (default: out/stack_demo under the current "
                   "folder)")
    p.add_argument("--duration", type=float, help="simulated time (s; default: the demo "
                   "scene's own, dda/scenes/demo.toml)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_demo)
    p = sub.add_parser("render", help="render a PVD series to PNG, GIF and/or MP4 (pyvista)")
    p.add_argument("pvd", help="the series' PVD file (as `dda run` writes it)")
    p.add_argument("--png", help="PNG of one frame (default: next to the PVD)")
    p.add_argument("--gif", help="animation, GIF")
    p.add_argument("--mp4", help="animation, MP4 (H.264; needs dda[vis])")
    p.add_argument("--field", default="displacement", help="cell field to colour by: "
                   "displacement, velocity, rotation, stress, ... (its unit may be left out; "
                   "a vector's magnitude, or one part: displacement:x, velocity:y, stress:sx, "
                   "sy, txy, mean, s1, s2, tmax)")
    p.add_argument("--relative-to", default="auto", metavar="BLOCK", help="colour "
                   "displacement, velocity or rotation relative to this block's: its name or "
                   "its block_id (a block's name if a block has it, else an integer is a "
                   "block_id); 'auto' (the default): the shaken block when the files mark "
                   "one; 'none': as they are")
    p.add_argument("--frame", type=int, default=-1, help="frame of the PNG (default last)")
    p.add_argument("--fps", type=float, default=10.0,
                   help="frames per second of the GIF and MP4 (default 10)")
    p.add_argument("--max-frames", type=int, default=None, metavar="N",
                   help="the GIF and MP4 take N frames evenly spread over the series "
                   "(default: every frame; each takes about 0.2 s to draw)")
    p.set_defaults(func=cmd_render)
    p = sub.add_parser("fos", help="the factor of safety of a scene by strength reduction "
                       "of its joints (dda.studies.strength_reduction)")
    p.add_argument("scene", help="SCENE.toml (its [simulation] solver is used; its dt and "
                   "duration are not: each trial makes its own)")
    p.add_argument("--tolerance", type=float, default=0.01,
                   help="relative width of the final bracket (default 0.01)")
    p.add_argument("--analysis", choices=["auto", "static", "dynamic"], default="auto",
                   help="the trials' analysis (default: static with newton, dynamic with "
                   "legacy)")
    p.add_argument("--resolution", type=float, default=1e-3,
                   help="smallest unbalanced acceleration a trial detects, in g (1e-3)")
    p.add_argument("--displacement-ratio", type=float, default=0.01,
                   help="a block fails when it moves this share of its size (0.01)")
    p.add_argument("--workers", type=int, default=0,
                   help="worker processes, and trials a round (default: one a core)")
    p.add_argument("--picture", help="write the picture (scene and trials) to this file")
    p.add_argument("--csv", help="write the trials to this CSV file")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_fos)
    p = sub.add_parser("info", help="blocks, contacts, effects and estimated cost of a scene "
                       "(of a script: of the first simulation it runs)")
    p.add_argument("scene", help="SCENE.toml, or SCRIPT.py: the script runs until it first "
                   "calls Simulation.run, and that simulation is described")
    p.set_defaults(func=cmd_info)
    args = ap.parse_args(argv)
    from dda.io.scene_file import SceneFileError
    from dda.simulation import SimulationError

    try:
        return args.func(args)
    except (SceneFileError, ValueError, ImportError) as exc:
        print(f"dda {args.command}: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # an output folder that is a file, a path not writable, ...
        print(f"dda {args.command}: {exc.strerror or exc}"
              + (f": {exc.filename}" if exc.filename else ""), file=sys.stderr)
        return 2
    except SimulationError as exc:  # the steps done are written; the message says why
        print(f"dda {args.command}: the run stopped: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: the run said where it stopped
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
