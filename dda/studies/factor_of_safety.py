"""Factor of safety by strength reduction: the largest F the joints can be weakened by.

``fos = dda.studies.strength_reduction(scene)`` divides every joint's strength by trial
factors ``F`` (``tan(phi_F) = tan(phi) / F``, ``c_F = c / F``: :mod:`dda.studies.reduction`),
runs each weakened scene for a while and calls it stable or failed by how far its free blocks move
(:class:`Criterion`), and narrows the bracket ``F_stable < F < F_failed`` until it is within
a tolerance. Each trial is a :class:`~dda.studies.sweep.Case` run by the sweep runner
(:func:`~dda.studies.sweep.sweep`), so the trials of a round run in parallel on any
:class:`concurrent.futures.Executor`: local processes by default, a Dask cluster with
``executor=distributed.Client(...).get_executor()``.

**The trial** (:class:`Criterion`). With the fully implicit solver a trial is a *static*
analysis (the velocity is set to zero at the start of every step, METHOD.md section 2): a
step then moves a block by ``a dt^2 / 2``, where ``a`` is its unbalanced acceleration
(out-of-balance force over mass). A stable scene finds its equilibrium and stops; an
unstable one creeps by the same amount every step, however small ``a`` is, so the last
step's ``a = 2 dx / dt^2`` measures the out-of-balance force itself. With legacy DDA a trial
is *dynamic* (the scene moves from rest under its weight): its pull-back friction does not
hold a static trial's long steps (below). A trial is ``N`` steps of ``dt`` (length ``T =
N dt``), and a free block (not fixed, shaken or moved by a prescribed motion) *fails* when

1. it moves more than its threshold ``d_b`` during the second half of the trial (the first
   half lets the scene settle on its springs), or
2. at the end, its last step's rate exceeds the end threshold: static, the unbalanced
   acceleration ``2 dx / dt^2 > a_min = resolution g`` (1e-3 g); dynamic, the speed
   ``dx / dt > v_b = d_b / (T / 2)`` (it would cover its threshold in another half trial),
   or
3. it has moved more than ``10 d_b`` since the start.

A trial stops as soon as (1) or (3) decides it; the blocks listed as failing are those that
had moved at least a tenth of their criterion by then (the mechanism). ``d_b`` is
``displacement_ratio`` (1%) of the block's size (the square root of its area) unless an
absolute ``displacement`` is given; a movement is the largest displacement of the block's
vertices. A static trial counts only its steps of a quarter of ``dt`` or more (the far
shorter steps taken while the contacts settle do not count; it may run ``SETTLE_ALLOWANCE``
(10) times ``T`` to make them): its second half starts after ``N / 2`` of them. The
smallest unbalanced acceleration the displacement test (1) detects is ``4 d / (N dt^2)``
(static) or ``8 d / (3 T^2)`` (dynamic, from rest); the default trial makes it ``a_min``
for the smallest free block::

    static:   dt = sqrt(4 d_min / (N a_min)),   T = N dt     (N = 40 steps)
    dynamic:  T = sqrt(8 d_min / (3 a_min)),    dt = T / N   (N = 200 steps)

so that for a block creeping at a steady rate (1) and (2) are the same test. A static ``dt``
is not a time step of any motion; it is capped at 50 periods of the lightest free block on
the stiffest joint, half the bound above which a dynamic simulation warns
(:func:`dda.plausibility.check_time_step`; the cap came when static steps were warned about
too, and was kept); test (2) keeps the resolution. On the two toppling columns
of the tests (1 m blocks, 10 GN/m) that is 40 steps of 0.157 s instead of 0.319 s: the same
factor (1.298).

**Resolution.** Near the factor of safety ``F*`` the out-of-balance force is small: a block on
an incline of ``theta`` at ``F = F* (1 + delta)`` has ``a = g sin(theta) delta / (1 +
delta)``. A trial calls it stable while ``a < a_min``, so the search may place ``F`` above
``F*`` by up to ``delta = resolution / sin(theta)``, 0.24% at 25 degrees with the default
1e-3; a finer ``resolution`` costs a longer dynamic trial (a static one tests it at its
last step).
Measured on a 0.5 m block on a 25 degree incline, phi 30 (``F* = 1.2381``), one trial at
``F* (1 + delta)``:

==========================  =============  =========  =========  =========  ==========
criterion ratio at delta    -1% and -0.1%  +0.1%      +0.2%      +0.3%      cost/trial
==========================  =============  =========  =========  =========  ==========
static, Newton or legacy    0.0002         0.42       0.84       1.26 fail  10 ms (40)
dynamic, Newton             0.0003-0.0016  0.65       1.21 fail  1.60 fail  31 ms (200)
dynamic, legacy             0.0002         0.47       0.93       1.43 fail  28 ms (200)
==========================  =============  =========  =========  =========  ==========

The static ratio grows linearly, 0.42 per 0.1%: it crosses 1 at ``delta = 0.237%``, the
designed ``1e-3 / sin 25``. A stable trial settles to 2e-4 (the elastic settling on the
springs, counted by test 3); its last step's unbalanced acceleration is 1e-15 g. The search
then finds ``F = 1.244`` (+0.46%) with every solver and analysis. On the two toppling
columns of the tests, legacy DDA's static trials went wrong: at ``F = 1.2`` (Goodman and
Bray's 1.3034) the slender column turned by 28 mrad against a square that stood still,
OPEN-CLOSE not settling 18 times, and the search gave 1.192 (-8.6%), not monotonic in
``F``; its dynamic trials give 1.298 (-0.40%), as do Newton's static and dynamic ones.
Hence ``analysis="auto"``: static for Newton (a third of the cost, and clearer: a stable
trial settles to 2e-4 of the criterion, a dynamic one to up to 2e-3 on the incline and 5e-3
on the columns), dynamic for legacy DDA. (Measured again on 2026-12-07, after the solvers'
later changes: legacy DDA's static trials give the two columns 1.2982, as its dynamic ones
do; on the four columns below 1.8757 (+1.7%, the fragile equilibrium Newton's static trials
also stand on) against the dynamic 1.8281 (-0.9%). Where a bolt can break, "auto" is static
for legacy DDA too: :class:`Criterion`.)

**A static trial can stand on a fragile equilibrium above F*.** Four columns on stepped
treads (heights 0.6 / 1.2 / 1.8 / 1.5 m, 0.5 m wide, psi 20, phi 50 base / 40 sides: Goodman
and Bray's ``F* = 1.8444``): Newton's static trials fail at 1.855-1.89 and above 1.897 but
stand at 1.893-1.896, held by a ninth contact, the toe of the fourth column on the third
column's face, loaded on its friction cone (a rigid-block check finds admissible forces with
it up to F = 2.147, without it up to exactly 1.8444). Whether a trial closes that contact is
decided in its first steps at a scale of 1e-7 m: by the size of its first step, which the
OPEN-CLOSE cuts of that step set (a full first step opens it, one of dt/8 closes it). Given a
rotation rate of 1e-5 rad/s, that equilibrium topples; dynamic trials never reach it and
fail from 1.84 up, with both solvers. A search of one trial a round landed in the window and
gave 1.902 (+3.1%); the default two a round give 1.8597 (+0.8%).

**The search.** Round 0 runs ``per_round`` factors spread geometrically over ``bracket``
(ends included, at least the two ends); while every trial is stable (or every one failed)
the bracket is widened by factors of 2 up to ``limits``. Then each round runs ``per_round``
factors spread geometrically inside the bracket ``(F_stable, F_failed)`` (a k-section:
bisection when ``per_round`` is 1), all at once on the executor, and the bracket shrinks to
the largest stable factor below the smallest failed one. It stops when ``F_failed / F_stable
- 1 <= tolerance`` and reports ``F = sqrt(F_stable F_failed)``.
"""

from __future__ import annotations

import copy
import math
import pickle
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from dda.errors import SimulationError
from dda.runtime import usable_cores
from dda.simulation import Simulation
from dda.studies.reduction import reduced_scene
from dda.studies.sweep import Case, Study, SweepRows, make_solver, sweep

__all__ = ["Criterion", "TrialPlan", "StrengthReductionTrial", "StrengthReduction",
           "strength_reduction", "analysis_for", "GROSS_MOVEMENT"]

#: a block that has moved this many thresholds since the start has failed, whatever follows
GROSS_MOVEMENT = 10.0
#: in a failed trial, the blocks listed as failing: those whose criterion ratio reached this
#: share of 1 when the trial was decided (the mechanism: on the five toppling columns of the
#: tests they stood at 0.48 to 1.0 when the first one crossed 1, at F 0.75% above F*; standing
#: blocks settle to about 1e-4)
FAILING_SHARE = 0.1
#: a static trial may run this many times its nominal length (``steps dt``) to make its
#: full-length steps: steps cut while the contacts settle do not count (the 313-block slope
#: of ``examples/jointed_slope.py`` settled in 0.86 s of pseudo time at 0.02 s steps, 2,460
#: steps mostly of 4e-5 to 6e-4 s)
SETTLE_ALLOWANCE = 10.0
#: a static trial's step counts when it is at least this share of the trial's dt: the step
#: control may hold a step at half its size for good (the two columns of the tests near F*:
#: 800 steps of dt / 2 in a trial of 40), while settling steps are far shorter
FULL_STEP = 0.25
#: the default steps of a trial, per analysis
DEFAULT_STEPS = {"static": 40, "dynamic": 200}


# ---------------------------------------------------------------------- the criterion
@dataclass(frozen=True)
class Criterion:
    """How a trial runs and when it calls the scene failed (module docstring).

    Parameters
    ----------
    analysis : {"auto", "static", "dynamic"}
        Static: the velocity is reset every step, an unstable block creeps step after step.
        Dynamic: the scene moves from rest under its weight. "auto" (the default): static
        with the fully implicit solver, dynamic with legacy DDA (whose pull-back friction
        does not hold a static trial's long steps; module docstring), but static with legacy
        DDA too where a bolt can break: released from rest, a block overshoots onto a slack
        bolt and friction holds it there, so a dynamic trial leaves the bolt with up to
        twice its static force and breaks it below the factor of safety (a wet bolted block
        on a 25 degree plane: 1.88 times, ``F`` 16% low).
    resolution : float
        The smallest unbalanced acceleration a trial must detect, as a fraction of gravity:
        a static trial's end test, and what sets a dynamic trial's duration.
    displacement_ratio : float
        A block's threshold ``d_b`` as a fraction of its size (square root of its area).
    displacement : float, optional
        One threshold (m) for every block instead.
    velocity : float, optional
        Dynamic trials: the end speed (m/s) above which a block fails; default ``d_b / (T /
        2)``. (A static trial tests its last step's unbalanced acceleration against
        ``resolution`` instead.)
    steps : int, optional
        Steps of a trial (default 40 static, 200 dynamic).
    duration : float, optional
        Length of a trial (s; in a static analysis a pseudo time: a step of ``dt`` moves a
        block by ``a dt^2 / 2``). Default: from ``resolution``. ``dt = duration / steps``.

    Examples
    --------
    >>> Criterion(analysis="dynamic").analysis, Criterion().resolution
    ('dynamic', 0.001)
    >>> from dda.studies.factor_of_safety import analysis_for
    >>> analysis_for("auto", "newton"), analysis_for("auto", "legacy")
    ('static', 'dynamic')
    """

    analysis: str = "auto"
    resolution: float = 1e-3
    displacement_ratio: float = 0.01
    displacement: float | None = None
    velocity: float | None = None
    steps: int | None = None
    duration: float | None = None

    def __post_init__(self):
        if self.analysis not in ("auto", *DEFAULT_STEPS):
            raise ValueError(f"Criterion: analysis must be 'auto', 'static' or 'dynamic', "
                             f"got {self.analysis!r}")
        for name in ("resolution", "displacement_ratio", "displacement", "velocity",
                     "duration"):
            value = getattr(self, name)
            if value is None and name not in ("resolution", "displacement_ratio"):
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                    math.isfinite(value) and value > 0):
                raise ValueError(f"Criterion: {name} must be a positive number, got {value!r}")
        if self.steps is not None and (isinstance(self.steps, bool) or not isinstance(
                self.steps, (int, np.integer)) or self.steps < 2):
            raise ValueError(f"Criterion: steps must be a whole number of at least 2, got "
                             f"{self.steps!r}")

    def plan(self, scene, solver="newton") -> TrialPlan:
        """The trial this criterion gives for ``scene`` and ``solver`` (a name or a solver):
        its analysis, step, length and thresholds."""
        from dda.model import Model

        analysis = analysis_for(self.analysis, solver, scene)
        scene.validate()
        if scene.shakes:
            names = ", ".join(repr(scene.blocks[sh.block].name) for sh in scene.shakes)
            raise ValueError(
                f"strength_reduction: the scene shakes {names}; the factor of safety by "
                "strength reduction is that of a scene under its weight and steady loads, "
                "which a trial judges by whether its blocks come to rest: take the shaking "
                "out (a pseudo-static seismic load can be a point load k W on each block)")
        varying = [ld.force.name for ld in scene.point_loads if not ld.force.constant]
        if varying:
            raise ValueError(
                f"strength_reduction: the {', '.join(varying)} changes with time; a "
                "trial runs in a pseudo time of its own and would meet such a load at an "
                "arbitrary point of its history (a load ramped over 5, 20 or 100 s gave F = "
                "1.18, 1.34 and 1.48 for one block): give each load the constant force it "
                "is judged at")
        model = Model(scene)
        watched = model.free.copy()
        for m in scene.motions:  # a block moved by springs is driven, not failing
            watched[m.block] = False
        if not watched.any():
            raise ValueError("strength_reduction: the scene has no free block (one that is "
                             "not fixed, shaken or moved): nothing can fail")
        size = model.size
        if self.displacement is not None:
            threshold = np.full(len(size), float(self.displacement))
        else:
            threshold = self.displacement_ratio * size
        d_min = float(threshold[watched].min())
        steps = int(self.steps or DEFAULT_STEPS[analysis])
        if self.duration is None and not scene.gravity > 0.0:
            raise ValueError("strength_reduction: a scene without gravity has no "
                             "acceleration to set the trial's length by; give "
                             "Criterion(duration=...)")
        a_min = self.resolution * scene.gravity
        if self.duration is not None:
            duration = float(self.duration)
        elif analysis == "static":  # capped: the rate test below keeps the resolution
            dt = math.sqrt(4.0 * d_min / (steps * a_min))
            duration = steps * min(dt, _step_cap(model, dt))
        else:
            duration = math.sqrt(8.0 * d_min / (3.0 * a_min))
        dt = duration / steps
        if not a_min > 0.0:  # no gravity: what the displacement test resolves
            a_min = (4.0 * d_min / (steps * dt * dt) if analysis == "static"
                     else 8.0 * d_min / (3.0 * duration ** 2))
        if analysis == "static":  # the last step's unbalanced acceleration 2 dx / dt^2
            rate = np.full(len(size), a_min)
        elif self.velocity is not None:
            rate = np.full(len(size), float(self.velocity))
        else:
            rate = threshold / (0.5 * duration)
        return TrialPlan(self, analysis, dt, duration, steps, watched, threshold, rate)


def analysis_for(analysis: str, solver, scene=None) -> str:
    """The analysis of a trial: ``analysis`` itself, or for "auto" "dynamic" with legacy DDA
    (the solver "legacy" or a :class:`dda.solvers.LegacyPullBack`) and "static" with any
    other solver, or with any solver when ``scene`` has a bolt that can break
    (:class:`Criterion`)."""
    if analysis != "auto":
        return analysis
    if scene is not None and breakable_bolts(scene):
        return "static"
    from dda.solvers import LegacyPullBack

    legacy = solver == "legacy" if isinstance(solver, str) else isinstance(solver,
                                                                          LegacyPullBack)
    return "dynamic" if legacy else "static"


def breakable_bolts(scene) -> bool:
    """Whether ``scene`` has a bolt with a finite strength."""
    return any(b.strength is not None and math.isfinite(b.strength) for b in scene.bolts)


def _step_cap(model, dt: float) -> float:
    """The longest static step: ``DT_PERIODS / 2`` contact periods ``2 pi sqrt(m / p)`` of
    the lightest free block on the stiffest joint (:func:`dda.plausibility.check_time_step`
    warns at ``DT_PERIODS`` in a dynamic analysis). An "auto" penalty is the one the
    simulation would choose at ``dt`` (:func:`dda.auto_settings.choose`; at the capped step
    its inertia rule, ``2 kappa m / dt^2`` with kappa 3 to 10, comes to at most ``20 / (100
    pi)^2`` of that penalty, so the choice stands)."""
    from dda.auto_settings import choose, static_step_cap

    penalties = np.asarray(model.joints.normal_penalty, dtype=float)
    if np.isnan(penalties).any():
        auto = choose(model, None, dt, auto_penalty=True).normal_penalty
        penalties = np.where(np.isnan(penalties), auto, penalties)
    return static_step_cap(model, penalties)


@dataclass(frozen=True, eq=False)
class TrialPlan:
    """A :class:`Criterion` made concrete for one scene.

    Attributes
    ----------
    criterion : Criterion
    analysis : "static" or "dynamic"
    dt, duration : float
        Step and length of a trial (s).
    steps : int
    watched : (n_blocks,) bool
        The blocks the criterion judges (free, not moved by a prescribed motion).
    threshold : (n_blocks,) float
        ``d_b`` (m).
    rate : (n_blocks,) float
        The end rate above which a block fails: static, the unbalanced acceleration ``a_min``
        (m/s^2); dynamic, the speed ``v_b`` (m/s).
    """

    criterion: Criterion
    analysis: str
    dt: float
    duration: float
    steps: int
    watched: np.ndarray
    threshold: np.ndarray
    rate: np.ndarray

    def describe(self) -> str:
        """One line: the run and the thresholds."""
        d = self.threshold[self.watched]
        c = self.criterion
        what = (f"{c.displacement_ratio:g} of its size" if c.displacement is None
                else f"{c.displacement:g} m")
        span = f"{d.min():.3g} m" if np.ptp(d) <= 1e-12 * d.max() else \
            f"{d.min():.3g} to {d.max():.3g} m"
        if self.analysis == "static":
            end = (f"or its last step's unbalanced acceleration exceeds "
                   f"{self.rate[self.watched].min():.3g} m/s2")
        else:
            end = "or it ends faster than that per half run"
        return (f"{self.analysis} trials of {self.steps} steps of {self.dt:.4g} s; a free "
                f"block fails when it moves more than {what} ({span}) in the second half, "
                f"more than {GROSS_MOVEMENT:g} times that in all, {end}")


# ---------------------------------------------------------------------- one trial
class _Decided(SimulationError):
    """Raised by the trial's watch to end a run whose outcome is known."""


class _Watch:
    """Follows a trial's committed steps: how far each block has moved, in the second half
    and in the last step; raises :class:`_Decided` once a block fails, or (static) once the
    trial has made its steps at full length.

    A static trial counts the steps of at least ``FULL_STEP`` (a quarter) of its ``dt``
    (the far shorter steps taken while the contacts settle do not count): its second half
    starts after ``steps / 2`` of them, it ends after ``steps``. A dynamic trial's second
    half starts at half its duration."""

    def __init__(self, x0, offsets, plan: TrialPlan):
        self.x0 = x0
        self.starts = offsets[:-1]
        self.plan = plan
        self.static = plan.analysis == "static"
        self.full = 0  # steps at full length (static)
        self.x_settle = None
        self.x_prev, self.t_prev = x0, 0.0
        self.x_last, self.t_last = x0, 0.0
        self.note = ""

    def _moved(self, a, b):
        """Per block, the largest distance a vertex moved from ``b`` to ``a``."""
        d = a - b
        return np.maximum.reduceat(np.hypot(d[:, 0], d[:, 1]), self.starts)

    def __call__(self, state, report):
        self.x_prev, self.t_prev = self.x_last, self.t_last
        self.x_last, self.t_last = state.x.copy(), float(state.time)
        plan = self.plan
        if self.static:
            self.full += self.t_last - self.t_prev >= FULL_STEP * plan.dt * (1.0 - 1e-9)
            second_half = self.full >= plan.steps // 2
        else:
            second_half = self.t_last >= 0.5 * plan.duration * (1.0 - 1e-9)
        if self.x_settle is None and second_half:
            self.x_settle = self.x_last
        if (self.ratios(rate=False) > 1.0).any():
            raise _Decided("a block failed")
        if self.static and self.full >= plan.steps:
            raise _Decided("the trial made its steps")

    def movements(self, rate=True):
        """Per block: total movement, movement in the second half, and the rate of the last
        step (static: its unbalanced acceleration ``2 dx / dt^2``; dynamic: its speed),
        zero in the first half (the first steps' settling on the springs is no failure) and
        when ``rate`` is False."""
        total = self._moved(self.x_last, self.x0)
        late = (np.zeros_like(total) if self.x_settle is None
                else self._moved(self.x_last, self.x_settle))
        span = self.t_last - self.t_prev
        if not rate or self.x_settle is None or span <= 0.0:
            end = np.zeros_like(total)
        elif self.static:
            end = 2.0 * self._moved(self.x_last, self.x_prev) / (span * span)
        else:
            end = self._moved(self.x_last, self.x_prev) / span
        return total, late, end

    def ratios(self, rate=True):
        """Per block, the largest of the criterion ratios (1 or more: failed); the end rate's
        only with ``rate`` (it is judged at the end: a step's rate while the scene still
        settles is no failure)."""
        total, late, end = self.movements(rate)
        p = self.plan
        r = np.maximum.reduce([late / p.threshold, end / p.rate,
                               total / (GROSS_MOVEMENT * p.threshold)])
        return np.where(p.watched, r, 0.0)

    def measures(self, result) -> dict:
        """The trial's row (the sweep's ``error`` callable)."""
        total, late, rate = self.movements()
        w = self.plan.watched
        ratios = self.ratios()
        # a run stopped by an error before it was decided found no equilibrium: failed
        failed = bool((ratios > 1.0).any()) or bool(self.note)
        failing = np.zeros(len(ratios), dtype=bool)
        if failed:  # the blocks that moved with the failure
            failing = ratios >= FAILING_SHARE
            if not failing.any():
                failing = w & (ratios >= ratios[w].max())
        names = [b.name for b in result.scene.blocks]
        return {"stable": not failed, "movement": float(ratios.max()),
                "max_displacement": float(total[w].max()),
                "late_displacement": float(late[w].max()),
                "end_rate": float(rate[w].max()),
                "failing_blocks": tuple(names[i] for i in np.flatnonzero(failing)),
                "trial_time": self.t_last, "note": self.note}


class _TrialSimulation(Simulation):
    """A simulation that watches its steps (:class:`_Watch`) and stops once decided."""

    def __init__(self, scene, plan: TrialPlan, **kw):
        super().__init__(scene, **kw)
        self.watch = _Watch(self.model.x_initial.copy(), self.model.offsets, plan)

    def run(self, duration=None, output=None, progress=None, **kw):
        try:
            return super().run(duration, output=output, progress=progress,
                               callback=self.watch)
        except _Decided as exc:
            return exc.result
        except SimulationError as exc:
            self.watch.note = f"stopped at t = {self.committed.time:.4g} s: {exc}"
            return exc.result


class StrengthReductionTrial(Study):
    """One trial of the strength reduction as a sweepable study: setting ``factor``.

    ``prepare(factor=F)`` gives the scene with every joint's strength divided by ``F``
    (:func:`dda.studies.reduction.reduced_scene`) as a simulation of ``plan``, and the
    measures of its row: ``stable``, ``movement`` (the largest criterion ratio: 1 or more is
    failed), ``max_displacement``, ``late_displacement`` (m, in the second half),
    ``end_rate`` (static: the last step's unbalanced acceleration, m/s^2; dynamic: its speed,
    m/s; in the second half), ``failing_blocks`` (a tuple of the names of
    the blocks that moved with the failure: at least a tenth of their criterion),
    ``trial_time`` (s reached: a failed trial stops once decided) and ``note`` (why a run
    stopped early on an error; such a trial counts as failed: no equilibrium was found).

    Parameters
    ----------
    scene : Scene
        The scene at full strength (sent to the workers by pickling).
    plan : TrialPlan
        From :meth:`Criterion.plan`.
    solver : str or NonlinearSolver
        A registry name ("newton", "legacy") or a solver instance.
    """

    name = "strength_reduction"

    def __init__(self, scene, plan: TrialPlan, solver="newton"):
        self.scene, self.plan, self.solver = scene, plan, solver

    def __repr__(self):
        return f"StrengthReductionTrial({self.scene!r}, solver={self.solver!r})"

    def prepare(self, factor=1.0):
        scene = reduced_scene(self.scene, factor)
        solver = (make_solver(self.solver) if isinstance(self.solver, str)
                  else copy.deepcopy(self.solver))
        plan = self.plan
        sim = _TrialSimulation(scene, plan, dt=plan.dt, solver=solver,
                               analysis=plan.analysis)
        # a static trial ends after its full-length steps (the watch), given time to settle
        length = SETTLE_ALLOWANCE * plan.duration if plan.analysis == "static" else \
            plan.duration
        return sim, length, sim.watch.measures


# ---------------------------------------------------------------------- the result
@dataclass(eq=False)
class StrengthReduction:
    """The factor of safety by strength reduction and how it was found.

    Attributes
    ----------
    factor : float
        ``sqrt(F_stable F_failed)`` of the final bracket; ``inf`` when the scene stood at the
        highest factor tried, ``nan`` when it failed at the lowest.
    bracket : (float, float)
        The largest stable and the smallest failed factor.
    trials : SweepRows
        One row a trial, in the order run (``round``, ``factor``, the measures of
        :class:`StrengthReductionTrial`, ``cpu_time``, ``steps``, ...).
    failing_blocks : list of Block
        The blocks that failed at the smallest failed factor (handles of ``scene``).
    plan : TrialPlan
        The trial's run and thresholds.
    tolerance : float
    scene : Scene
    notes : list of str
        Anything odd: a stable trial above a failed one, trials stopped by an error.
    """

    factor: float
    bracket: tuple[float, float]
    trials: SweepRows
    failing_blocks: list
    plan: TrialPlan
    tolerance: float
    scene: object
    notes: list = field(default_factory=list)

    @property
    def rounds(self) -> int:
        """How many rounds of trials ran."""
        return 1 + max((r["round"] for r in self.trials), default=-1)

    def __repr__(self):
        lo, hi = self.bracket
        cpu = sum(r.get("cpu_time", 0.0) for r in self.trials)
        lines = [f"StrengthReduction: F = {self.factor:.4g} (stable at {lo:.4g}, failed at "
                 f"{hi:.4g}; tolerance {self.tolerance:g})",
                 f"  {len(self.trials)} trials in {self.rounds} rounds, {cpu:.3g} s of CPU",
                 "  failing blocks at F = {:.4g}: {}".format(
                     hi, ", ".join(b.name for b in self.failing_blocks) or "none"),
                 f"  {self.plan.describe()}"]
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)

    def picture(self, path=None):
        """The scene with its failing blocks coloured, and the trials' movement against F.

        Parameters
        ----------
        path : str or Path, optional
            Write the figure there (PNG, PDF, SVG by suffix) and close it.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from dda.studies.fos_picture import picture

        return picture(self, path)


# ---------------------------------------------------------------------- the search
def _workers(executor) -> int:
    """How many trials the executor runs at once, as far as can be told (2 if not)."""
    if executor is None:
        return usable_cores()
    n = getattr(executor, "_max_workers", None)
    if isinstance(n, int) and n > 0:
        return n
    client = getattr(executor, "_client", None)  # a Dask ClientExecutor
    if client is not None:
        try:
            return max(1, int(sum(client.nthreads().values())))
        except Exception:  # noqa: BLE001 - any failure to ask: fall back
            pass
    return 2


def strength_reduction(scene, executor: Executor | None = None, *,
                       criterion: Criterion | None = None, bracket=(0.5, 4.0),
                       tolerance: float = 0.01, per_round: int | None = None,
                       solver="newton", limits=(1.0 / 64.0, 64.0),
                       progress: bool | None = False) -> StrengthReduction:
    r"""The factor of safety of ``scene`` by strength reduction of its joints.

    Every joint's friction law is weakened by trial factors ``F``,

    .. math:: \tan\phi_F = \tan\phi / F, \qquad c_F = c / F,

    (:func:`dda.studies.reduction.reduce_friction`), each weakened scene runs as a trial
    (:class:`Criterion`) and is stable or failed; the bracket ``F_stable < F* < F_failed``
    is narrowed until ``F_failed / F_stable - 1 <= tolerance`` (module docstring).

    Parameters
    ----------
    scene : Scene
        At full strength. Its water, loads and other effects are kept as they are.
    executor : concurrent.futures.Executor, optional
        Where the trials run (the sweep runner's :func:`~dda.studies.sweep.sweep`). Default:
        a process pool, one worker a core. ``distributed.Client(...).get_executor()`` runs
        them on a Dask cluster. The scene travels to the workers pickled.
    criterion : Criterion, optional
        The trial and its thresholds (default ``Criterion()``: static, 40 steps, 1% of a
        block's size, a resolution of 1e-3 g).
    bracket : (float, float)
        Factors tried first (widened by factors of 2 within ``limits`` if both stand or both
        fail).
    tolerance : float
        Relative width of the final bracket.
    per_round : int, optional
        Factors tried at once each round; default: the executor's workers (at most 16).
    solver : str or NonlinearSolver
        "newton" (default), "legacy", or a solver instance.
    limits : (float, float)
        The lowest and highest factor the search goes to.
    progress : bool, optional
        A progress bar a round (the sweep's).

    Returns
    -------
    StrengthReduction
        ``factor``, ``bracket``, ``trials``, ``failing_blocks``, ``picture(path)``.

    Examples
    --------
    >>> import math
    >>> import dda
    >>> from concurrent.futures import ThreadPoolExecutor
    >>> from dda.contact import CoulombSingle, JointMaterial
    >>> from dda.materials import LinearElastic
    >>> rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    >>> scene = dda.Scene(gravity=9.81)   # a block on a 1:2 slope, phi 40 degrees
    >>> _ = scene.add_block([(0, 0), (4, 0), (4, 2)], rock, fixed=True)
    >>> _ = scene.add_block([(2, 1), (2.4, 1.2), (2.2, 1.6), (1.8, 1.4)], rock, name="top")
    >>> scene.set_joint(JointMaterial(1e9, 1e9, CoulombSingle(phi=40.0)))
    >>> with ThreadPoolExecutor(1) as pool:
    ...     fos = strength_reduction(scene, executor=pool, tolerance=0.02)
    >>> round(fos.factor / (math.tan(math.radians(40.0)) / 0.5), 2)  # F = tan(phi) / tan(theta)
    1.0
    >>> [b.name for b in fos.failing_blocks]
    ['top']
    """
    criterion = Criterion() if criterion is None else criterion
    if not isinstance(criterion, Criterion):
        raise TypeError(f"strength_reduction: criterion must be a Criterion, got {criterion!r}")
    lo, hi = (float(v) for v in bracket)
    f_min, f_max = (float(v) for v in limits)
    if not (0.0 < f_min <= lo < hi <= f_max and math.isfinite(f_max)):
        raise ValueError(f"strength_reduction: need 0 < limits[0] <= bracket[0] < bracket[1] "
                         f"<= limits[1] < inf, got bracket {bracket!r}, limits {limits!r}")
    if not (isinstance(tolerance, (int, float)) and 0.0 < tolerance < 1.0):
        raise ValueError(f"strength_reduction: tolerance must lie in (0, 1), got {tolerance!r}")
    reduced_scene(scene, 1.0)  # every joint's law can be reduced: fail now, not in a worker
    plan = criterion.plan(scene, solver)
    study = StrengthReductionTrial(scene, plan, solver)
    k = per_round if per_round is not None else min(_workers(executor), 16)
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"strength_reduction: per_round must be a whole number >= 1, got {k!r}")
    own = executor is None
    if own or isinstance(executor, ProcessPoolExecutor):
        _check_pickles(study)
    if own:
        executor = ProcessPoolExecutor(max_workers=min(k, usable_cores()))
    try:
        return _search(study, executor, k, lo, hi, f_min, f_max, tolerance, progress)
    finally:
        if own:
            executor.shutdown(cancel_futures=True)


def _check_pickles(study):
    try:
        pickle.dumps(study)
    except Exception as exc:  # noqa: BLE001 - pickle raises many kinds
        raise TypeError(
            "strength_reduction: the scene cannot be sent to worker processes (pickling it "
            f"failed: {exc}); define its functions (shaking, loads) at a module's top level "
            "instead of as lambdas or local functions, or pass an executor that needs no "
            "pickling, such as concurrent.futures.ThreadPoolExecutor") from None


def _search(study, executor, k, lo, hi, f_min, f_max, tolerance, progress):
    rows: list[dict] = []
    outcome: dict[float, bool] = {}
    notes: list[str] = []
    if study.plan.analysis == "dynamic" and breakable_bolts(study.scene):
        notes.append("dynamic trials release the scene from rest: a block overshoots onto a "
                     "slack bolt, which can keep up to twice its static force and break "
                     "below the factor of safety; Criterion(analysis='static') judges "
                     "bolts that can break by their static load")

    def run(factors, round_no):
        factors = sorted({float(f) for f in factors} - set(outcome))
        cases = [Case(study, {"factor": f}) for f in factors]
        for r in sweep(cases, executor=executor, progress=progress, on_error="raise"):
            r = {"round": round_no, **r}
            r.pop("study", None)
            r.pop("error", None)
            rows.append(r)
            outcome[r["factor"]] = bool(r["stable"])
            if r.get("note"):
                notes.append(f"the trial at F = {r['factor']:.4g} {r['note']} (counted as "
                             "failed)")

    run(np.geomspace(lo, hi, max(2, k)), 0)
    round_no = 1
    while True:
        known = sorted(outcome)
        failed = [f for f in known if not outcome[f]]
        if not failed:
            top = known[-1]
            if top >= f_max:
                return _result(study, rows, math.inf, (top, math.inf), tolerance, notes,
                               f"stable at every factor up to the limit {f_max:g}")
            run([min(top * 2.0 ** i, f_max) for i in range(1, k + 1)], round_no)
        else:
            f_fail = failed[0]
            stable = [f for f in known if outcome[f] and f < f_fail]
            if not stable:
                if f_fail <= f_min:
                    return _result(study, rows, math.nan, (0.0, f_fail), tolerance, notes,
                                   f"failed at every factor down to the limit {f_min:g}")
                run([max(f_fail / 2.0 ** i, f_min) for i in range(1, k + 1)], round_no)
            else:
                f_stable = stable[-1]
                if f_fail / f_stable - 1.0 <= tolerance:
                    above = [f for f in known if outcome[f] and f > f_fail]
                    if above:
                        notes.append(f"stable at F = {', '.join(f'{f:.4g}' for f in above)}, "
                                     f"above the failed F = {f_fail:.4g}: the outcome is not "
                                     "monotonic in F (a finer criterion may help)")
                    return _result(study, rows, math.sqrt(f_stable * f_fail),
                                   (f_stable, f_fail), tolerance, notes)
                run(np.geomspace(f_stable, f_fail, k + 2)[1:-1], round_no)
        round_no += 1


def _result(study, rows, factor, bracket, tolerance, notes, why=None):
    if why:
        notes = [*notes, why]
    scene = study.scene
    failing = []
    at = [r for r in rows if r["factor"] == bracket[1]]
    if at and at[0]["failing_blocks"]:
        failing = [scene.block(n) for n in at[0]["failing_blocks"]]
    return StrengthReduction(factor=factor, bracket=bracket, trials=SweepRows(rows),
                             failing_blocks=failing, plan=study.plan, tolerance=tolerance,
                             scene=scene, notes=list(notes))
