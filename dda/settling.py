"""A dynamic run's settled start: the scene at rest under its loads before t = 0.

A dynamic run from rest (``Simulation(start="rest")``, the default) switches gravity and the
loads on at t = 0 over contact springs that carry nothing: the blocks drop onto their springs
and bounce (README, "A dynamic run's start"). A block let go on a plane then rides that bounce
(+8% and +12% of slide in 1 s with everything "auto"), an arch's joints overshoot their static
forces. ``Simulation(start="settled")`` first brings the scene to rest as it stands before
t = 0: static steps (velocity zero at each step's start, METHOD.md section 2) with

- every joint's friction *held*: its shear spring sticks whatever its force
  (:class:`HeldFriction`; a joint still opens under tension), as if the blocks were held in
  place until the run starts;
- gravity, the initial stresses, water, bolts and the loads at their values at t = 0;
- the blocks whose motion is given standing where they are at t = 0.

The settled state keeps the springs' forces (normal and shear), the blocks' strains and the
bolts' stretch; the clock goes back to 0 and the blocks take their given initial velocities.
At the first dynamic step the joints' own friction laws take over: a shear spring above its
strength slides at once at the strength, with the normal force already in place.

The static steps are legacy DDA's, whatever the run's solver: with every joint held there is
no friction to return, the equilibrium is the same linear one, and legacy DDA's OPEN-CLOSE
rules settle contacts that cycle between open and closed, where Newton's iterations stall
(the cut slope of ``examples/jointed_slope.py``: a static step of Newton's with every joint
stuck stalled at 2.4e-5 of the forces at every step size down to 1e-5 s; legacy DDA's settled
it in 11 steps of 0.019 s).

The static steps stop once the last one moved no vertex more than ``SETTLED_MOVE`` of the
smallest free block's size. A step of ``dt`` that moves a block of mass ``m`` by ``d`` leaves
at most an unbalanced force ``2 m d / dt^2`` (its inertia term): at rule 9's static step
(:mod:`dda.auto_settings`) that is some 1e-5 of its weight. A scene that does not stand with
its joints held (a mechanism of hinges, a block in the air) moves on instead: the settle stops
with a :class:`dda.SimulationError` once a block has moved ``MECHANISM_MOVE`` of its size, or
after ``SETTLE_STEPS`` steps.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace

import numpy as np

from dda.auto_settings import static_step
from dda.contact.detection import Memo
from dda.contact.friction import FrictionLaw, FrictionTrial
from dda.errors import SimulationError
from dda.model import Model
from dda.solvers.legacy import LegacyPullBack
from dda.step import StepSettings, StepState, step

__all__ = ["HeldFriction", "Settling", "held_model", "settle"]

#: static steps at most
SETTLE_STEPS = 400
#: the largest vertex move of the last static step, as a fraction of the smallest free
#: block's size, below which the scene has settled
SETTLED_MOVE = 1e-7
#: a block that moves this fraction of its size while settling does not stand: the settle
#: stops with an error
MECHANISM_MOVE = 0.1
#: cuts of the settle's step in a row before it gives up
MAX_CUTS = 12


class HeldFriction(FrictionLaw):
    """A friction law held on its stick branch: ``t_s = p_s (g_se + delta_g_s)``, never
    slipping, whatever the normal force.

    It keeps the history fields of the law it holds (``law``) and updates them as that
    law's own stick branch does (:meth:`FrictionLaw.stick`), so a contact's history passes
    from the held law to its own without a change. Consistent tangent: ``p_s`` and 0.
    """

    name = "held"

    def __init__(self, law: FrictionLaw):
        self.law = law

    def __repr__(self):
        return f"HeldFriction({self.law!r})"

    def history_fields(self):
        return self.law.history_fields()

    def initial_state(self, n):
        return self.law.initial_state(n)

    def kept_when_open(self):
        return self.law.kept_when_open()

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length, faces=None,
                   dt=None) -> FrictionTrial:
        return self.law.stick(committed, delta_g_s, shear_penalty)

    def tangent(self, trial, normal_penalty, shear_penalty):
        n = len(trial.t_s)
        return np.broadcast_to(shear_penalty, (n,)).astype(float), np.zeros(n)

    def elastic_update(self, committed, delta_g_s):
        return self.law.elastic_update(committed, delta_g_s)

    def stick(self, committed, delta_g_s, shear_penalty):
        return self.law.stick(committed, delta_g_s, shear_penalty)


@dataclass(frozen=True)
class Settling:
    """How a settled start went.

    Attributes
    ----------
    steps : static steps taken
    dt : their size (s; the last one's, after any cut)
    largest : the largest vertex displacement from the scene's geometry (m)
    block : the block of that vertex (its label)
    last_move : the largest vertex move of the last step (m)
    cuts : steps refused and tried again at half the size
    """

    steps: int
    dt: float
    largest: float
    block: str
    last_move: float
    cuts: int = 0

    @property
    def text(self) -> str:
        """One line for :attr:`dda.Simulation.choices`."""
        cut = f" ({self.cuts} cut)" if self.cuts else ""
        return (f"start: settled in {self.steps} static steps of {self.dt:.3g} s{cut} with the "
                f"joints' friction held (the largest move {self.largest:.3g} m, of "
                f"{self.block}; the last step's {self.last_move:.3g} m), then the joints' "
                "own friction from t = 0")


def held_model(model: Model) -> Model:
    """A copy of ``model`` for the settle: friction held (:class:`HeldFriction`), no
    dashpots, the given motions standing still and the loads at their values at t = 0. The
    arrays are shared with ``model``; neither changes them."""
    held = copy.copy(model)
    joints = model.joints
    held.joints = replace(joints, laws=tuple(HeldFriction(law) for law in joints.laws),
                          damping_ratio=None, shear_damping_ratio=None)
    held.shakes = ()
    held.full_motions = ()
    held.memo = Memo(size=2)

    def block_forces(t1, *args, **kwargs):  # the loads as they are at t = 0
        return Model.block_forces(held, 0.0, *args, **kwargs)

    held.block_forces = block_forces
    return held


def settle(model: Model, state: StepState, settings: StepSettings,
           dt: float | None = None) -> tuple[StepState, Settling]:
    """Bring ``state`` to rest under the loads at t = 0 with the joints' friction held
    (module docstring); the settled state at t = 0 and how it went.

    Parameters
    ----------
    model : the run's model (its penalties chosen)
    state : the state at t = 0 (the run's start)
    settings : the run's step settings (their velocity carry is not used: the steps are
        static)
    dt : the static step (s); default :func:`dda.auto_settings.static_step`

    Raises
    ------
    SimulationError
        When the scene does not settle: a block moves ``MECHANISM_MOVE`` of its size, the
        step is cut ``MAX_CUTS`` times in a row, or ``SETTLE_STEPS`` steps do not do.
    """
    if state.time != 0.0:
        raise ValueError(f"settle: only a run's start can be settled (t = {state.time:g} s)")
    held = held_model(model)
    solver = LegacyPullBack()  # (whatever the run's: module docstring)
    try:
        dt0 = static_step(model) if dt is None else float(dt)
    except ValueError as exc:
        raise ValueError(f"start='settled': {exc}; give Simulation.settle a dt") from None
    static = replace(settings, velocity_carry=0.0)
    free = model.free
    limit = MECHANISM_MOVE * model.size[model.topo.block]
    moving = free[model.topo.block]
    settled_move = SETTLED_MOVE * float(np.min(model.size[free]))
    now, hint, cuts, steps, move, refused = dt0, 0.0, 0, 0, np.inf, 0
    while steps < SETTLE_STEPS:
        trial, report = step(held, state, now, solver, static, hint)
        if trial is None:
            if report.search_hint > hint:
                hint = report.search_hint
                continue
            cuts += 1
            refused += 1
            if cuts > MAX_CUTS:
                raise SimulationError(
                    f"start='settled': the static step was cut {MAX_CUTS} times in a row "
                    f"after {steps} steps ({report.reason}); the scene may not stand with "
                    "its joints held: start from rest (start='rest')")
            now /= 2.0
            continue
        state, cuts, steps = trial, 0, steps + 1
        moved = np.hypot(*(state.x - model.x_initial).T)
        over = np.flatnonzero(moving & (moved > limit))
        if over.size:
            v = int(over[np.argmax(moved[over] / limit[over])])
            b = int(model.topo.block[v])
            raise SimulationError(
                f"start='settled': the scene does not stand with its joints held: "
                f"{model.block_label(b)} moved {moved[v]:.3g} m ({moved[v] / model.size[b]:.0%}"
                f" of its size) in {steps} static steps (a mechanism, or a block with "
                "nothing under it); start it from rest (start='rest') to watch it move")
        move = state.last_move
        # (a cut step moves less under the same unbalanced force: judged at its own size)
        if steps >= 2 and move <= settled_move * (now / dt0) ** 2:
            break
        now = min(2.0 * now, dt0)
    else:
        raise SimulationError(
            f"start='settled': the scene did not settle in {SETTLE_STEPS} static steps (the "
            f"last moved {move:.3g} m, settled is {settled_move:.3g} m); start from rest "
            "(start='rest')")
    moved = np.where(moving, np.hypot(*(state.x - model.x_initial).T), 0.0)
    v = int(np.argmax(moved))
    record = Settling(steps, now, float(moved[v]), model.block_label(model.topo.block[v]),
                      float(move), refused)
    settled = replace(state, time=0.0, velocity=model.initial_velocity(), last_move=0.0)
    return settled, record
