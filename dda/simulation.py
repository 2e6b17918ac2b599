"""Simulation: the run loop of DDA (METHOD.md section 5).

A run takes pure steps (:func:`dda.step.step`) from the committed :class:`dda.step.StepState`:
a trial that the step accepts is committed, one it refuses is dropped and the step is tried
again as :class:`dda.step_control.StepControl` says (a wider search, then half the step
size). Recording (:class:`dda.recorder.Recorder`), the progress bar and the penalty advice
watch the committed states; checkpoints (:mod:`dda.io.checkpoint`) keep them.
"""

from __future__ import annotations

import sys
import time as _time
from pathlib import Path

import numpy as np
from numba.core import event as numba_event

from dda import slip_events
from dda._checks import finite_number
from dda.auto_settings import choose
from dda.compiled_run import StepRuns
from dda.contact.contacts import SLIP, STICK
from dda.errors import FrictionLawError, SimulationError
from dda.io.checkpoint import (
    CHECKPOINT_VERSION,
    checkpoint_payload,
    read_checkpoint,
    write_checkpoint,
)
from dda.kernels import cache as kernel_cache
from dda.model import Model
from dda.penalty_advice import PenaltyAdvisor, PenaltyWarning, natural_step
from dda.plausibility import (
    PlausibilityWarning,
    check_rate_laws_static,
    check_shaking_resolution,
    check_time_step,
    check_water_table,
)
from dda.profiling import StepProfile
from dda.progress import ProgressBar
from dda.recorder import Recorder, frame
from dda.result import Frame, Result
from dda.runtime import blas_threads, run_environment
from dda.scene import Scene
from dda.settling import Settling, settle
from dda.solvers.base import NonlinearSolver
from dda.solvers.newton import NewtonRaphson
from dda.step import StepSettings, StepState, step
from dda.step_control import StepControl

__all__ = ["Simulation", "SimulationError", "PenaltyWarning", "PlausibilityWarning",
           "CHECKPOINT_VERSION", "MIN_DT", "MAX_DT"]

#: the shortest and the longest step a simulation takes (s): a contact's period is
#: microseconds at the stiffest (a 1 cm block at 1000 times the rock's modulus) and a block's
#: motion is seconds; outside them the arithmetic of a step overflows (dt 1e300) or a run
#: never ends (dt 1e-300)
MIN_DT = 1e-9
MAX_DT = 1e3

#: the stats columns of the step profile's sections, in its order


class Simulation:
    """A DDA run of a scene.

    Parameters
    ----------
    scene : Scene
    dt : float or "auto"
        Step size (s). Steps are cut when a step does not converge and grow back afterwards.
        ``"auto"``: chosen from the scene and the solver (:mod:`dda.auto_settings`), as are
        the penalties of joints given as ``"auto"``; a penalty given as a number shortens it
        to keep that penalty at the solver's multiple of the lightest free block's inertia
        (rule 6); :attr:`choices` says what and why.
    solver : NonlinearSolver or str, optional
        How one step is solved: ``NewtonRaphson()`` (the default, fully implicit) or
        ``LegacyPullBack()`` (original DDA); or a solver's registered name with its default
        settings (``"newton"``, ``"legacy"``, one added by :func:`dda.registry.
        register_solver`, or an import path ``"module:Class"``; :func:`dda.registry.
        make_solver`).
    analysis : {"dynamic", "static"}
        "static" sets the velocity to zero at the start of every step (METHOD.md section 2).
    velocity_carry : float
        Fraction in [0, 1] of the velocity carried into the next step (1: fully dynamic).
    max_open_close : int
        OPEN-CLOSE passes allowed before the step is cut.
    record_every : int
        Record (and write) every this many steps.
    max_displacement_ratio : float
        Largest distance a free block's vertex may move in one step, as a fraction of the
        block's size (the square root of its area). A step that moves a block farther is
        cut, as is one whose OPEN-CLOSE iteration does not settle or whose Newton iteration
        does not converge; dt grows back (doubling) after ``control.grow_after`` quiet steps
        (:class:`dda.step_control.StepControl`). Every cut is in ``result.stats.cuts`` as
        (time, dt, reason).
    penetration_tolerance : float
        The penetration guard: after every step, before it is committed, every vertex that
        lies inside another block is found geometrically (:mod:`dda.contact.penetration`).
        One that no closed contact holds at (at least) its depth, give or take this fraction
        of the thinner block's half-width (``2 area / perimeter``: half a square's side), is
        an untracked penetration: the step is refused and tried again with a smaller dt, and
        a run that cannot get past it stops with a :class:`SimulationError` naming the
        vertex, the two blocks, the depth and the time. ``result.stats.penetration`` is the
        deepest vertex found per step, ``result.stats.spring_penetration`` the deepest
        closed spring.
    output : writer, optional
        For example ``dda.io.VTUWriter("out/case")``; can also be given to :meth:`run`.
    locate_reversals : bool, optional
        Take a step in which a sliding contact reverses again, ended where its slip velocity
        crosses zero (:mod:`dda.slip_events`: the friction force flips there, and a step
        that applies one direction's friction to the whole of it lets the velocity err by up
        to ``2 mu g dt``). None (the default): in scenes of at most
        :data:`dda.slip_events.AUTO_BLOCKS` free blocks, where a block's slide is what is
        asked and a retaken step costs little; in a jointed mass many contacts reverse by
        micrometres in most steps. Each located reversal is in ``result.stats.reversals``
        as (time, share of the step).
    start : {"rest", "settled"}
        How a dynamic run starts. "rest" (the default): the scene as built, gravity and the
        loads switched on at t = 0 over contact springs that carry nothing yet, so the blocks
        drop onto their springs and bounce ("A dynamic run's start" in the README).
        "settled": the first :meth:`run` first brings the scene to rest under its loads at
        t = 0 by static steps, first with the joints' friction held, then with their own,
        and runs from there (:mod:`dda.settling`; :meth:`settle`). Only for a dynamic
        analysis (a static one settles by its own steps).

    Attributes
    ----------
    model : dda.model.Model
        The scene compiled into arrays (built once).
    committed : dda.step.StepState
        The committed state (``state`` is the same); :func:`dda.step.step` makes trials of it.
    control : dda.step_control.StepControl
        The step size now, cuts and growth.
    choices : str
        What was chosen for "auto" settings (dt, penalties) and why, one line each; empty
        when nothing was "auto".
    settling : dda.settling.Settling or None
        How the settled start went (steps, step size, largest move), once it has.

    Examples
    --------
    >>> import dda
    >>> from dda.materials import LinearElastic
    >>> scene = dda.Scene(gravity=9.81)
    >>> b = scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)],
    ...                     LinearElastic(young=1e9, poisson=0.2, density=1000.0))
    >>> result = dda.Simulation(scene, dt=0.01).run(duration=0.1)
    >>> round(float(result.displacement(b)[-1, 1]), 6)  # -g t^2 / 2
    -0.04905
    """

    def __init__(self, scene: Scene, dt: float, solver: NonlinearSolver | str | None = None,
                 analysis: str = "dynamic", velocity_carry: float = 1.0,
                 max_open_close: int = 12, record_every: int = 1, output=None,
                 max_displacement_ratio: float = 0.25, penetration_tolerance: float = 0.01,
                 locate_reversals: bool | None = None, start: str = "rest"):
        if not isinstance(scene, Scene):
            hint = ("; dda.load_scene gives a LoadedScene: pass its .scene, or call its "
                    ".simulation() for the file's settings"
                    if type(scene).__name__ == "LoadedScene" else "")
            raise TypeError(f"Simulation: scene must be a dda.Scene, got {scene!r}{hint}")
        auto_dt = isinstance(dt, str)
        if auto_dt and dt != "auto":
            raise ValueError(f"Simulation: dt must be a number (s) or 'auto', got {dt!r}")
        self.dt = None if auto_dt else finite_number("dt", dt, positive=True,
                                                     where="Simulation")
        if self.dt is not None and not MIN_DT <= self.dt <= MAX_DT:
            raise ValueError(f"Simulation: dt must lie between {MIN_DT:g} and {MAX_DT:g} s, "
                             f"got {self.dt:g} (a step is seconds, not steps per second)")
        if solver is None:
            solver = NewtonRaphson()
        elif isinstance(solver, str):
            from dda.registry import RegistryError, make_solver  # (it imports the solvers)

            try:
                solver = make_solver(solver)
            except RegistryError as exc:
                raise RegistryError(f"Simulation: {exc}") from None
        if not isinstance(solver, NonlinearSolver):
            raise TypeError(f"Simulation: solver must be a NonlinearSolver, got {solver!r}")
        if analysis not in ("dynamic", "static"):
            raise ValueError(
                f"Simulation: analysis must be 'dynamic' or 'static', got {analysis!r}"
            )
        if start not in ("rest", "settled"):
            raise ValueError(f"Simulation: start must be 'rest' or 'settled', got {start!r}")
        if start == "settled" and analysis == "static":
            raise ValueError("Simulation: start='settled' is for a dynamic analysis (a static "
                             "one brings the scene to rest by its own steps)")
        carry = finite_number("velocity_carry", velocity_carry, where="Simulation")
        if not 0.0 <= carry <= 1.0:
            raise ValueError(f"Simulation: velocity_carry must lie in [0, 1], got {carry}")
        if int(max_open_close) < 1:
            raise ValueError("Simulation: max_open_close must be at least 1")
        if int(record_every) < 1:
            raise ValueError("Simulation: record_every must be at least 1")
        self.max_displacement_ratio = finite_number(
            "max_displacement_ratio", max_displacement_ratio, positive=True, where="Simulation")
        self.penetration_tolerance = finite_number(
            "penetration_tolerance", penetration_tolerance, positive=True, where="Simulation")
        scene.validate()
        self.scene = scene
        self.solver = solver
        self.analysis = analysis
        self.velocity_carry = 0.0 if analysis == "static" else carry
        self.max_open_close = int(max_open_close)
        self.record_every = int(record_every)
        self.output = output
        self.model = Model(scene)
        if locate_reversals is None:
            locate_reversals = (int(np.count_nonzero(self.model.free))
                                <= slip_events.AUTO_BLOCKS)
        elif not isinstance(locate_reversals, bool | np.bool_):
            raise TypeError("Simulation: locate_reversals must be True, False or None (by the "
                            f"scene's size), got {locate_reversals!r}")
        self.locate_reversals = bool(locate_reversals)
        self.start = start
        self.settling = None
        self.choices = ""
        auto_penalty = bool(self.model.joints.auto)
        if auto_dt or auto_penalty:
            choice = choose(self.model, solver, self.dt,
                            shakes=[s.history for s in scene.shakes],
                            auto_penalty=self.model.joints.auto,
                            speeds=(self.model.initial_speeds() if analysis == "dynamic"
                                    else None), dynamic=analysis == "dynamic")
            self.dt = choice.dt
            if self.model.joints.auto:
                self.model.joints = self.model.joints.with_penalties(choice.normal_penalty,
                                                                     choice.shear_penalty)
            self.choices = choice.text
        if analysis == "dynamic":  # a static step solves for equilibrium: no period
            check_time_step(self.model, self.dt)
            check_shaking_resolution(self.model, self.dt, solver,
                                     [s.history for s in scene.shakes], not auto_dt,
                                     not auto_penalty)
        else:
            check_rate_laws_static(self.model.joints.laws, self.dt)
        check_water_table(self.model)
        self.committed = StepState.initial(self.model)
        self.control = StepControl(self.dt, natural_dt=natural_step(self.model))
        self.advisor = PenaltyAdvisor(self.model, self.dt)
        self._resume_end = None  # the end of an interrupted run (set by resume)
        self._resume_checkpoint = None
        self._written = (None, None)  # the writer of the last frame written, and its time
        # committed steps since the last recorded one (record_every's cadence across a stop)
        self._record_since = 0

    @property
    def state(self) -> StepState:
        """The committed state (the same as :attr:`committed`)."""
        return self.committed

    @state.setter
    def state(self, value: StepState) -> None:
        self.committed = value

    @property
    def settings(self) -> StepSettings:
        """How each step is taken, from this simulation's arguments."""
        return StepSettings(self.velocity_carry, self.max_open_close,
                            self.max_displacement_ratio, self.penetration_tolerance)

    def _run_settings(self) -> dict:
        """What a run's :class:`Result` says it was (:meth:`Result.to_xarray`'s attributes)."""
        return {"dt": float(self.dt), "solver": repr(self.solver), "analysis": self.analysis,
                "velocity_carry": float(self.velocity_carry),
                "record_every": int(self.record_every), "choices": self.choices,
                "start": self.start,
                "settling": "" if self.settling is None else self.settling.text}

    def energy(self):
        """The mechanical energy of the committed state (:func:`dda.energy.energy`)."""
        from dda.energy import energy

        return energy(self)

    def frame(self) -> Frame:
        """The committed state as a :class:`dda.result.Frame`."""
        return frame(self.model, self.committed)

    def run(self, duration: float | None = None, output=None, progress: bool | None = None,
            checkpoint=None, checkpoint_every: int = 100, callback=None) -> Result:
        """Run the simulation for ``duration`` seconds from where it stands.

        Parameters
        ----------
        duration : float, optional
            Simulated time to add (s). Only a simulation from :meth:`resume` may leave it out:
            it then runs to the end of the run that was interrupted.
        output : writer, optional
            Overrides the writer given to the constructor for this run.
        progress : bool, optional
            Show a progress bar on stderr; by default on for runs of more than 2,000 steps
            when stderr is a terminal.
        checkpoint : str or Path, optional
            File kept (:mod:`dda.io.checkpoint`) every ``checkpoint_every`` steps, on Ctrl-C
            or SIGTERM and at the end, for :meth:`resume`; the scene's callables must be
            module-level functions (kept by import path) or samples
            (:class:`dda.effects.TimeTable`). A resumed run keeps its file unless given
            another.
        checkpoint_every : int
            Steps between checkpoints.
        callback : callable, optional
            Called as ``callback(state, report)`` after every committed step with the
            :class:`dda.step.StepState` and its :class:`dda.step.StepReport` (live plots, own
            logs; an exception it raises ends the run, the steps done written).

        Returns
        -------
        Result
            The recorded steps of this run, starting with the state it started from.

        Raises
        ------
        SimulationError
            When a step cannot be made to converge even with a much smaller dt; its
            ``result`` holds the steps done (written). KeyboardInterrupt on Ctrl-C or SIGTERM,
            after the steps done are written and checkpointed.
        """
        t_end, writer, checkpoint = self._prepare(duration, output, checkpoint,
                                                  checkpoint_every)
        if self.settle_pending:
            self.settle()
        result = Result(self.scene, [b.name for b in self.scene.blocks],
                        record_every=self.record_every, settings=self._run_settings(),
                        initial_centroid=self.model.centroid_initial
                        + self.model.origin)
        bar = self._progress_bar(progress, t_end, result.stats)
        recorder = Recorder(self.model, result, writer, self.record_every, self._written,
                            self.__dict__.get("_record_since", 0))
        recorder.start(self.committed)
        watchers = [w for w in (bar, callback) if w is not None]
        # Ctrl-C and SIGTERM stop the run at the end of a step until the writer is closed (a
        # second one during the checkpoint save must not kill the process before the files
        # are complete); one BLAS thread
        with run_environment() as interrupts, numba_event.install_listener(
                "numba:compiler_lock", numba_event.TimingListener()) as kernels:
            # (numba holds its compiler lock while it compiles a kernel or loads one from its
            # cache: the start-up of a process's first run, not the steps' own cost)
            try:
                self._steps(result, t_end, recorder, writer, checkpoint, watchers,
                            interrupts)
            except SimulationError as exc:
                self._stop_recording(recorder)
                exc.result = result
                raise
            except KeyboardInterrupt:
                self._stop_recording(recorder)
                if checkpoint is not None:  # the committed state is whole: keep it
                    self.save_checkpoint(checkpoint[0], writer, t_end, checkpoint[1])
                if bar:
                    bar.close()
                    bar = None
                print(self._stopped(checkpoint), file=sys.stderr, flush=True)
                raise
            except Exception:  # a callback's, or a writer's: the steps done are written
                self._stop_recording(recorder)
                raise
            finally:
                if kernels.done:
                    result.stats.kernel_time = (getattr(result.stats, "kernel_time", 0.0)
                                                + kernels.duration)
                if bar:
                    bar.close()
                if writer is not None:
                    writer.close()
        return result

    @property
    def settle_pending(self) -> bool:
        """Whether the run is to start settled (``start="settled"``) and has not yet: the
        first :meth:`run` (or a :class:`dda.energy.WorkLedger` made before it) settles it."""
        return (self.start == "settled" and self.settling is None
                and self.committed.time == 0.0 and not self.control.steps)

    def settle(self, dt: float | None = None) -> Settling:
        """Bring the run's start to rest under its loads at t = 0 (:func:`dda.settling.settle`:
        static steps with the joints' friction held, then with their own): the committed
        state becomes the settled one, at t = 0 with the blocks' given velocities,
        :attr:`settling` says how it went and :attr:`start` becomes "settled".

        ``run`` calls it first under ``start="settled"``; call it yourself to look at the
        settled state before a run. ``dt`` is the static step (default: rule 9's,
        :func:`dda.auto_settings.static_step`). The displacements of a run from it are from
        the scene's geometry: its first frame holds the settlement.

        Raises
        ------
        ValueError
            On a static analysis, or after the run has started.
        SimulationError
            When the scene does not stand with its joints held (a mechanism, a block in the
            air): it then needs a start from rest.
        """
        if self.analysis == "static":
            raise ValueError("Simulation.settle: a static analysis brings the scene to rest "
                             "by its own steps")
        if self.committed.time != 0.0 or self.control.steps or self.settling is not None:
            raise ValueError("Simulation.settle: only a run's start can be settled, once (t = "
                             f"{self.committed.time:g} s, {self.control.steps} steps taken)")
        with blas_threads():
            self.committed, self.settling = settle(self.model, self.committed, self.settings,
                                                   dt)
        self.start = "settled"
        return self.settling

    def _stop_recording(self, recorder) -> None:
        """Record and write the last committed state of a run stopped early
        (:meth:`Recorder.stop`), and remember it as written: a run that goes on must not
        write it again. A writer that fails here does not hide why the run stopped."""
        try:
            recorder.stop(self.committed)
        except Exception:  # noqa: BLE001 - the run's own exception is the one to raise
            return
        self._written = recorder.written

    def _stopped(self, checkpoint) -> str:
        """The line an interrupted run prints: when it stopped and how to go on."""
        t = self.committed.time
        if checkpoint is None:
            return (f"dda: stopped at t = {t:g} s after {self.control.steps} steps; no "
                    "checkpoint was set (to be able to resume: [output] checkpoint = "
                    "\"run.ckpt\" in a scene file, run(..., checkpoint=PATH) in Python)")
        return (f"dda: stopped at t = {t:g} s after {self.control.steps} steps; resume with: "
                f"dda run {checkpoint[0]}")

    def _progress_bar(self, progress, t_end, stats):
        """A progress bar when asked for, or by default for a long run on a terminal."""
        if progress is None:
            steps = (t_end - self.committed.time) / self.dt
            progress = steps > 2000 and sys.stderr.isatty()
        if not progress:
            return None
        note = ""
        if kernel_cache.COLD:  # the first run of an install: numba compiles as it goes
            kernel_cache.COLD = False
            note = "compiling the kernels first, once: a minute or two"
        return ProgressBar(t_end, self.committed.time, stats, note=note)

    def _steps(self, result, t_end, recorder, writer, checkpoint, watchers, interrupts):
        """Step to ``t_end``: commit, record, checkpoint and tell the watchers each step; stop
        after a step when ``interrupts`` (:class:`dda.runtime.Interrupts`) got a signal."""
        settings = self.settings
        bar = next((w for w in watchers if isinstance(w, ProgressBar)), None)
        runs = (StepRuns(self, result, recorder, None if checkpoint is None else checkpoint[1])
                if StepRuns.possible(self, writer,
                                     next((w for w in watchers if w is not bar), None))
                else None)
        while self.committed.time < t_end - 1e-12 * max(1.0, t_end):
            if runs is not None and runs.advance(t_end, bar):
                # (a batch never takes the run's last step, and its watcher is the bar)
                self._record_since = recorder.since
                interrupts.check()
                continue
            report = self._advance(result, t_end, settings)
            last = self.committed.time >= t_end - 1e-12 * max(1.0, t_end)
            recorder.committed(self.committed, last)
            self._written, self._record_since = recorder.written, recorder.since
            if checkpoint is not None and (self.control.steps % checkpoint[1] == 0 or last):
                self.save_checkpoint(checkpoint[0], writer, t_end, checkpoint[1])
            for watch in watchers:
                watch(self.committed, report)
            interrupts.check()

    def _prepare(self, duration, output, checkpoint, every):
        """The run's end time, writer and ``(checkpoint path, every)`` (or None), checked."""
        if duration is None:
            if self._resume_end is None:
                raise ValueError("Simulation.run: give the duration (only a simulation from "
                                 "Simulation.resume may leave it out)")
            duration = self._resume_end - self.committed.time
            if duration <= 1e-12 * max(1.0, self._resume_end):
                raise ValueError(f"Simulation.run: the resumed run already ended at t = "
                                 f"{self._resume_end:g} s; give a duration to go on")
        duration = finite_number("duration", duration, positive=True, where="run")
        if checkpoint is None and self._resume_checkpoint is not None:
            checkpoint, every = self._resume_checkpoint
        if checkpoint is not None:
            checkpoint = Path(checkpoint)
            if int(every) < 1:
                raise ValueError("Simulation.run: checkpoint_every must be at least 1, got "
                                 f"{every!r}")
            checkpoint = (checkpoint, int(every))
            checkpoint[0].parent.mkdir(parents=True, exist_ok=True)
        t_end = self.committed.time + duration
        for s in self.model.shakes:
            s.history.check_covers(t_end)
        writer = output if output is not None else self.output
        last = getattr(writer, "last_time", None)
        if last is not None and last > self.committed.time + 1e-9 * max(1.0, abs(last)):
            raise ValueError(
                f"Simulation.run: the writer's series already reaches t = {last:g} s and this "
                f"run starts at t = {self.committed.time:g} s: its frames would go back in "
                "time in one .pvd; give each simulation its own writer (or prefix)")
        if checkpoint is not None:  # fail now, not at the first checkpoint, if it cannot
            checkpoint_payload(self, writer, t_end, *checkpoint)
        return t_end, writer, checkpoint

    def _advance(self, result, t_end, settings):
        """Take one step, trying it again as the step control says; commit it, log its
        stats."""
        control = self.control
        tries = widened = 0
        profile = StepProfile()
        start = _time.perf_counter()
        short = False  # the step's first try was cut short by the run's end
        while True:
            dt = control.step_size(t_end - self.committed.time)
            if tries == 0:
                short = dt < control.dt_now * (1.0 - 1e-9)
            try:
                with profile.active():
                    trial, report = step(self.model, self.committed, dt, self.solver,
                                         settings, control.search_hint)
                if trial is not None and self.locate_reversals and self.velocity_carry > 0.0:
                    trial, report, dt = self._reversal_located(trial, report, dt, settings,
                                                               profile, result)
            except FrictionLawError as exc:
                raise FrictionLawError(
                    f"the run cannot go on at t = {self.committed.time:.6g} s (a step of "
                    f"{dt:.3g} s): {exc}") from None
            if trial is not None:
                break
            tries += 1
            if control.widen(report.search_hint, widened):  # moved farther than predicted
                widened += 1
                continue
            result.stats.cuts.append((self.committed.time, dt, report.reason))
            control.cut(dt, report.reason)
            control.check_can_go_on(report, tries, dt, self.committed,
                                    lambda: self.advisor.soft_advice(self.committed),
                                    short_step=short)
        self.committed = trial
        control.accepted()
        self.advisor.observe(trial, control.steps, control.contact_cuts)
        c = trial.contacts
        states = np.bincount(c.state, minlength=3)  # open, stick, slip
        # the row in StepStats.FIELDS order (the parts' seconds in SECTIONS order)
        result.stats.append_row(
            (trial.time, dt, report.iterations, report.open_close_passes, len(c),
             int(states[STICK] + states[SLIP]), int(states[SLIP]), tries,
             _time.perf_counter() - start, profile.solves, report.unknowns, report.pairs,
             report.penetration, report.spring_penetration, *profile.seconds.values()),
            report.residual_norms)
        return report

    def _reversal_located(self, trial, report, dt, settings, profile, result):
        """The step ended where a sliding contact's slip velocity crosses zero, if one
        reversed in it (:mod:`dda.slip_events`); else the step as it was."""
        control = self.control
        if control.reversal_wait > 0:
            return trial, report, dt
        full = dt
        least = slip_events.MIN_FRACTION
        for _ in range(slip_events.ITERATIONS):
            phi = slip_events.reversal_fraction(self.model.topo.nxt, self.committed, trial,
                                                self.velocity_carry, self.model.free)
            # (and not below that share of the step size asked for: a step control that has
            # cut far below it is resolving something else)
            if (phi is None or not least < phi < 1.0 - least
                    or phi * dt < least * control.dt):
                break
            with profile.active():
                short, again = step(self.model, self.committed, phi * dt, self.solver,
                                    settings, control.search_hint)
            if short is None:  # the shorter step did not go through: keep the longer
                break
            trial, report, dt = short, again, phi * dt
        if dt < full:
            result.stats.reversals.append((self.committed.time, dt / full))
            control.reversal_wait = slip_events.WAIT
        return trial, report, dt

    # ------------------------------------------------------------------ checkpoints
    def save_checkpoint(self, path, writer=None, end: float | None = None,
                        every: int = 100) -> None:
        """Write the committed state, the step control and the writer to ``path``
        (atomically: :mod:`dda.io.checkpoint`). ``end`` is the time the run was to reach."""
        end = self.committed.time if end is None else end
        write_checkpoint(path, checkpoint_payload(self, writer, end, path, every))

    @classmethod
    def resume(cls, path, allow_outside_output: bool = False) -> Simulation:
        """The simulation kept in a checkpoint file of :meth:`run`, ready to go on.

        ``Simulation.resume(path).run()`` finishes the interrupted run: same steps, same
        numbers as a run that was never interrupted, and the same writer goes on numbering its
        files where the checkpoint left it. A checkpoint is data, not a pickle
        (:mod:`dda.io.checkpoint`): reading one imports the modules of the laws and functions
        it names and runs nothing else, and a file that is not a checkpoint of this version
        gives a ``ValueError`` that says why. The run goes on checkpointing to ``path``,
        and its VTU series where it was if that was in ``path``'s folder (or below it); one
        that was elsewhere needs ``allow_outside_output`` (a checkpoint from someone else
        writes nowhere but beside itself).
        """
        data = read_checkpoint(path, allow_outside_output)
        sim = data["simulation"]
        sim.output = data["writer"]
        sim._resume_end = data["end"]
        sim._resume_checkpoint = data["checkpoint"]
        return sim

