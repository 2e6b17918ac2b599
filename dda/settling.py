"""A dynamic run's settled start: the scene at rest under its loads before t = 0.

A dynamic run from rest (``Simulation(start="rest")``, the default) switches gravity and the
loads on at t = 0 over contact springs that carry nothing: the blocks drop onto their springs
and bounce (README, "A dynamic run's start"). A block let go on a plane then rides that bounce
(+8% and +12% of slide in 1 s with everything "auto"), an arch's joints overshoot their static
forces. ``Simulation(start="settled")`` first brings the scene to rest as it stands before
t = 0, by static steps (velocity zero at each step's start, METHOD.md section 2) with
gravity, the initial stresses, water, bolts and the loads at their values at t = 0 and the
blocks whose motion is given standing where they are at t = 0:

1. with every joint's friction *held* (:class:`HeldFriction`: its shear spring sticks
   whatever its force; a joint still opens under tension), as if the blocks were held in
   place. This finds the normal forces without letting anything slide away;
2. then with the joints' own friction, from that state: a block that hung on a wall or a
   neighbour by shear beyond their strength slides down until its joints carry it (two
   blocks in a slot: the walls held 30% of their weight in shear with no normal force; the
   311-block cut slope of ``examples/jointed_slope.py``: 582 of 1,481 contacts beyond their
   strength). A block that slides on instead (``RELEASE_MOVE`` of its size: one that its
   friction cannot hold, a block let go on a plane) is held where step 1 left it
   (:func:`holding_model`), as are those still moving alike (their move a step not
   shrinking) when ``RELEASE_STEPS`` are done, and the steps start again from step 1's
   state, up to ``RELEASE_ROUNDS`` times. A rest found at a long step
   is tried at one ``CONFIRM_FACTOR`` times shorter (friction's explicit lag can hold a
   state at the long step that shorter ones move). When the steps settle, their state is
   handed over; when they do not, step 1's, with a warning;
3. the held blocks' faces whose shear is beyond a contact's strength share it over their
   contacts by strength (:func:`share_by_strength`): at t = 0 every contact of a face that
   is let go is at its limit, as a sliding face is.

The clock then goes back to 0 and the blocks take their given initial velocities. The
springs keep their forces (normal and shear), the blocks their strains, the bolts their
stretch. Every closed contact starts the run marked sliding, so that its own law judges it
in the first step (legacy DDA's explicit rule would keep one that starts a step sticking
stuck to the step's end).

The static steps are legacy DDA's, whatever the run's solver: the equilibrium is the same,
and legacy DDA's OPEN-CLOSE rules settle contacts that cycle between open and closed, where
Newton's iterations stalled (the cut slope with every joint stuck: a static step of Newton's
stalled at 2.4e-5 of the forces at every step size down to 1e-5 s; legacy DDA's settled it
in 11 steps of 0.019 s). Newton now holds such contacts closed
(:data:`dda.solvers.newton.HOLD_CYCLING`), but only while they pull by 1% of the forces on
their own blocks: its static steps did not settle the slope in 400 (the last moved 1.25e-7
m, 37 s); held against the scene's largest force, as OPEN-CLOSE holds them, they settled it
in 9 + 43 steps (16 cut, 3.3 s) against legacy DDA's 11 + 74 (22 cut, about 4 s).

The static steps stop once the last one moved no vertex more than ``SETTLED_MOVE`` of the
smallest free block's size, at rule 9's static step (:func:`dda.auto_settings.static_step`;
a shorter step, which moves less under the same unbalanced force, is judged at its own
size). A step of ``dt`` that moves a block of mass ``m`` by ``d`` leaves at most an
unbalanced force ``2 m d / dt^2`` (its inertia term): at rule 9's step some 1e-5 of its
weight. A scene that does not stand with its joints held (a mechanism of hinges, a block in
the air) keeps moving alike from step to step where a settling one relaxes: the settle stops
with a :class:`dda.SimulationError` once such a block has moved ``MECHANISM_MOVE`` of its
size, or after ``SETTLE_STEPS`` steps. The settle is not a run: a law's history sees its
static steps as time (a rate or ageing law's own clock, if it keeps one).
"""

from __future__ import annotations

import copy
import warnings
from dataclasses import MISSING, dataclass, fields, replace

import numpy as np

from dda._checks import finite_number
from dda.auto_settings import static_step
from dda.contact.contacts import OPEN, SLIP, ContactSet, pair_key
from dda.contact.detection import Memo
from dda.contact.faces import contact_faces
from dda.contact.friction import FrictionLaw, FrictionTrial
from dda.contact.kinematics import contact_geometry, tributary_length
from dda.errors import SimulationError
from dda.model import Model
from dda.plausibility import PlausibilityWarning
from dda.solvers.legacy import LegacyPullBack
from dda.step import StepSettings, StepState, step

__all__ = ["HeldFriction", "Settling", "held_model", "holding_model", "settle",
           "share_by_strength"]

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
#: static steps with the joints' own friction after the held ones, at most
RELEASE_STEPS = 200
#: ... which give up once a block has moved this fraction of its size: it slides on
RELEASE_MOVE = 0.01
#: rounds of those steps, each holding the blocks the rounds before found sliding on
RELEASE_ROUNDS = 8
#: a rest found is tried at a step this many times shorter, up to this many times (a try
#: that moves goes on, the step growing back)
CONFIRM_FACTOR = 10.0
CONFIRMATIONS = 3
#: accepted steps in a row before a cut step doubles again
GROW_AFTER = 2
#: OPEN-CLOSE passes a static step of the settle may take (at least)
SETTLE_PASSES = 30


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
    steps : static steps taken with the joints' friction held
    dt : the size of the longest static step (s)
    largest : the largest vertex displacement from the scene's geometry (m)
    block : the block of that vertex (its label; "" when nothing moved)
    last_move : the largest vertex move of the last step (m)
    cuts : steps refused and tried again at half the size
    release_steps : static steps taken after those with the joints' own friction
    released : whether those settled too: the state handed over is then at rest with the
        joints' own friction; else (blocks slid on) it is the held one, and the shear that
        the joints' friction cannot carry is let go at t = 0
    bolts_broken : bolts broken while settling
    held_blocks : free blocks handed over held (those that slid on with their own friction;
        every free block when the state handed over is the held one)
    unsettled : why the steps with the joints' own friction did not come to rest, when they
        did not ("" when they did)
    """

    steps: int
    dt: float
    largest: float
    block: str
    last_move: float
    cuts: int = 0
    release_steps: int = 0
    released: bool = False
    bolts_broken: int = 0
    held_blocks: int = 0
    unsettled: str = ""

    @classmethod
    def from_data(cls, data: dict) -> Settling:
        """The record from its fields as plain data (a checkpoint's); ``ValueError`` when
        they are not this record's."""
        kinds = {f.name: f.type for f in fields(cls)}
        needed = {f.name for f in fields(cls) if f.default is MISSING}
        if not isinstance(data, dict) or not needed <= set(data) <= set(kinds):
            raise ValueError(f"expected the keys {sorted(kinds)}")
        kinds = {name: kind for name, kind in kinds.items() if name in data}
        cast = {"int": int, "float": float, "str": str, "bool": bool}
        values = {}
        for name, kind in kinds.items():
            value = data[name]
            ok = (isinstance(value, bool) if kind == "bool" else
                  isinstance(value, str) if kind == "str" else
                  isinstance(value, (int, float)) and not isinstance(value, bool))
            if not ok:
                raise ValueError(f"{name}: not a {kind}")
            values[name] = cast[kind](value)
        return cls(**values)

    @property
    def text(self) -> str:
        """One line for ``dda run`` and the README's examples."""
        cut = f", {self.cuts} cut" if self.cuts else ""
        if self.released and self.held_blocks:
            then = (f"then {self.release_steps} with their own friction but around "
                    f"{self.held_blocks} block{'s' if self.held_blocks > 1 else ''} that slide"
                    f"{'' if self.held_blocks > 1 else 's'} on with it, held (let go at t = 0)")
        elif self.released:
            then = (f"then {self.release_steps} with their own friction: at rest with it "
                    "from t = 0")
        else:
            then = (f"with their own friction not at rest ({self.unsettled or 'blocks slid on'}"
                    f", {self.release_steps} steps): the held state, its shear beyond the "
                    "joints' strength let go at t = 0")
        moved = (f"the largest move {self.largest:.3g} m, of {self.block}" if self.largest > 0
                 else "nothing moved")
        broken = (f"; {self.bolts_broken} bolt{'s' if self.bolts_broken > 1 else ''} broke"
                  if self.bolts_broken else "")
        return (f"start: settled in {self.steps} static steps with the joints' friction "
                f"held, {then} (steps of {self.dt:.3g} s{cut}; {moved}{broken})")


def held_model(model: Model, friction: str = "held") -> Model:
    """A copy of ``model`` for the settle: the joints' friction held (:class:`HeldFriction`;
    ``friction="own"``: their own laws), no dashpots, the given motions standing still and
    the loads at their values at t = 0. The arrays are shared with ``model``; neither
    changes them."""
    held = copy.copy(model)
    joints = model.joints
    laws = (tuple(HeldFriction(law) for law in joints.laws) if friction == "held"
            else joints.laws)
    held.joints = replace(joints, laws=laws, damping_ratio=None, shear_damping_ratio=None)
    held.shakes = ()
    held.full_motions = ()
    held.memo = Memo(size=2)

    def block_forces(t1, *args, **kwargs):  # the loads as they are at t = 0
        return Model.block_forces(held, 0.0, *args, **kwargs)

    held.block_forces = block_forces
    return held


@dataclass
class _Run:
    """What a series of static steps came to."""

    state: StepState
    settled: bool
    steps: int = 0
    refused: int = 0
    dt: float = 0.0
    move: float = np.inf
    why: str = ""
    sliding: np.ndarray | None = None  # the blocks that slid on, when that ended the steps
    longest: float = 0.0  # the longest step taken


def holding_model(model: Model, hold: np.ndarray) -> Model:
    """:func:`held_model` with the joints' own friction but for the pairs of a block of
    ``hold`` ((n_blocks,) bool), whose friction is held: the blocks that slide on with their
    own friction stay where the held steps left them while the rest settles."""
    out = held_model(model, friction="own")
    j = out.joints
    rows, n_laws, n = len(j.normal_penalty), len(j.laws), model.n_blocks
    held = np.flatnonzero(hold)
    a = np.repeat(held, n)
    b = np.tile(np.arange(n), len(held))
    keys = np.unique(pair_key(a[a != b], b[a != b], n))
    joint = j.index(keys)
    keys, joint = keys[joint >= 0], joint[joint >= 0] + rows  # (their held copies)
    mine = ~np.isin(j.pair_keys, keys)
    all_keys = np.concatenate([j.pair_keys[mine], keys])
    order = np.argsort(all_keys)
    out.joints = replace(
        j, pair_keys=all_keys[order],
        pair_joint=np.concatenate([j.pair_joint[mine], joint])[order],
        normal_penalty=np.concatenate([j.normal_penalty, j.normal_penalty]),
        shear_penalty=np.concatenate([j.shear_penalty, j.shear_penalty]),
        law=np.concatenate([j.law, j.law + n_laws]),
        laws=j.laws + tuple(HeldFriction(law) for law in j.laws))
    return out


def share_by_strength(model: Model, state: StepState, dt: float) -> ContactSet:
    """The contacts of ``state`` with each face's shear shared over its closed contacts in
    proportion to their strengths where one of them is beyond its own: the face's total
    kept, ``t_s_i = (sum t_s) S_i / sum S`` and ``g_se = t_s / p_s`` (a face: a block pair's
    contacts on one edge, :func:`dda.contact.faces.contact_faces`).

    Held, a pair's contacts share its shear by their springs (alike on a rigid block), not by
    their strengths: at t = 0 the one beyond its strength slid and the other held, and the
    block set off with a kick (a 0.5 x 1 m block on a plane 0.2 degrees past its friction:
    +6.3% of slide in 1 s, Newton; a review, 2026-12-07). Shared by strength, a pair at its
    limit reaches it at every contact at once, as a sliding face does, and one within it
    keeps every contact within. The strength ``S_i`` is the law's, from its return map at
    no further slip (its ``FrictionTrial.strength``); a law that keeps no ``g_se`` is left
    as it is.
    """
    c = state.contacts
    closed = c.state != OPEN
    if not closed.any():
        return c
    topo = model.topo
    geom = contact_geometry(state.x, c.vertex, c.edge, topo.nxt)
    length = tributary_length(state.x, c.vertex, geom, topo.prv, topo.nxt)
    rows = model.joint_index(c.bj, c.bk)
    law_of = model.joints.law[rows]
    ps = model.joints.shear_penalty[rows]
    strength = np.full(len(c), np.nan)
    for k, law in enumerate(model.joints.laws):
        on = np.flatnonzero(closed & (law_of == k))
        if not on.size or "g_se" not in law.history_fields():
            continue
        extra = {}
        if law.uses_faces:
            extra["faces"] = contact_faces(state.x, c.vertex[on], c.edge[on], topo.nxt,
                                           topo.prv)
        if law.uses_dt:
            extra["dt"] = dt
        trial = law.return_map({f: v[on] for f, v in c.history.items()}, np.zeros(on.size),
                               c.t_n[on], ps[on], length[on], **extra)
        strength[on] = np.abs(trial.strength)
    known = closed & np.isfinite(strength)
    over = known & (np.abs(c.t_s) > strength * (1.0 + 1e-9))
    if not over.any():
        return c
    # by face, not by block pair: a block in a channel touches one block on two faces whose
    # shear runs opposite ways, and a pair's sum turned the floor's shear round (+14,980
    # N/m against a strength of 1,515; a review, 2026-12-07)
    faces = contact_faces(state.x, c.vertex, c.edge, topo.nxt, topo.prv).index
    keys = pair_key(c.bj, c.bk, model.n_blocks)
    _, pair = np.unique(np.c_[keys, faces], axis=0, return_inverse=True)
    pair = pair.reshape(-1)
    # a pair is shared when one of its contacts is over, and all of them are known
    pair_over = np.bincount(pair, weights=over, minlength=pair.max() + 1) > 0
    pair_unknown = np.bincount(pair, weights=closed & ~known, minlength=pair.max() + 1) > 0
    total = np.bincount(pair, weights=np.where(known, c.t_s, 0.0), minlength=pair.max() + 1)
    held = np.bincount(pair, weights=np.where(known, strength, 0.0),
                       minlength=pair.max() + 1)
    share = known & (pair_over & ~pair_unknown & (held > 0.0))[pair]
    if not share.any():
        return c
    t_s = c.t_s.copy()
    t_s[share] = total[pair[share]] * strength[share] / held[pair[share]]
    history = dict(c.history)
    history["g_se"] = np.where(share, t_s / ps, c.history["g_se"])
    return replace(c, t_s=t_s, history=history)


def _on_the_way(paces) -> np.ndarray:
    """(n_blocks,) the blocks whose move over dt^2 in the last step was not below half the
    one before: still sliding, where a settling block's moves shrink step by step (none
    after a single step: a block that came to rest against a stop in it looked alike)."""
    return (paces[0] > 0.0) & (paces[1] >= 0.5 * paces[0])


def _contracting(moves: list, ratio: float = 0.5) -> bool:
    """Whether the last two steps each moved less than ``ratio`` of the step before: a
    settle relaxes geometrically, a block that slides or falls keeps moving alike."""
    return len(moves) < 3 or moves[-1] <= ratio * moves[-2] or moves[-2] <= ratio * moves[-3]


def _static_steps(model: Model, steps_model: Model, state: StepState, dt0: float,
                  dt_ref: float, static: StepSettings, max_steps: int,
                  mechanism: bool) -> _Run:
    """Static steps of ``steps_model`` (legacy DDA's) from ``state`` until the last one moved
    no vertex more than ``SETTLED_MOVE`` of the smallest free block's size (at ``dt_ref``;
    a shorter step, which moves less under the same unbalanced force, is judged at its
    own size), at most ``max_steps``. With ``mechanism`` a block that has moved
    ``MECHANISM_MOVE`` of its size and goes on moving alike is a :class:`SimulationError`;
    without, a block that has moved ``RELEASE_MOVE`` of its size from ``state`` ends the
    steps unsettled (it slides on)."""
    # (whatever the run's: module docstring) with the cycle rule measured over each contact's
    # group of touching blocks whatever the run's, and without the memory of held contacts:
    # on the contacts' own blocks the cut slope's held steps did not settle in 400; the
    # run's own steps judge the contacts that the settle held
    solver = LegacyPullBack(cycle_local=False, cycle_memory=0)
    free = model.free
    start = state.x
    limit = MECHANISM_MOVE * model.size[model.topo.block]
    moving = free[model.topo.block]
    settled_move = SETTLED_MOVE * float(np.min(model.size[free]))
    run = _Run(state, False, dt=dt0)
    now, hint, cuts, moves, quiet = dt0, 0.0, 0, [], 0
    confirms, confirming = 0, False  # rests found at a long step and tried at a short one
    # each free block's largest move over the last two steps, over dt^2 (the unbalanced
    # force it stands for): a block whose move does not shrink is still on its way
    previous, paces = state.x, [np.zeros(model.n_blocks), np.zeros(model.n_blocks)]
    while run.steps < max_steps:
        trial, report = step(steps_model, run.state, now, solver, static, hint)
        if trial is None:
            if report.search_hint > hint:
                hint = report.search_hint
                continue
            cuts += 1
            run.refused += 1
            if cuts > MAX_CUTS:
                run.why = f"the static step was cut {MAX_CUTS} times in a row ({report.reason})"
                if mechanism:
                    raise SimulationError(
                        f"start='settled': {run.why} after {run.steps} steps; the scene may "
                        f"not stand with its joints held: {_FROM_REST}")
                return run
            now /= 2.0
            quiet = 0
            continue
        run.state, run.steps, run.dt, cuts, quiet = trial, run.steps + 1, now, 0, quiet + 1
        run.longest = max(run.longest, now)
        run.move = trial.last_move
        if not mechanism:  # (the held steps judge the whole scene's moves instead)
            pace = np.zeros(model.n_blocks)
            np.maximum.at(pace, model.topo.block, np.hypot(*(trial.x - previous).T))
            paces = [paces[1], pace / now**2]
            previous = trial.x
        moves.append(run.move / now**2)  # (the unbalanced force it stands for, per mass)
        if run.steps >= 2 and run.move <= settled_move * (now / dt_ref) ** 2:
            # a long static step is nearly a solve of the stiffness alone: a state that
            # friction's explicit lag holds at it may still move under a step a tenth as
            # long (two columns of five blocks in a slot: the floor at 0.883 of their
            # weight, at rest at 0.319 s, 0.931 once the shorter steps had settled it)
            # (the held steps have no friction to lag: their rest needs no confirming)
            if (mechanism or confirming or confirms >= CONFIRMATIONS
                    or now < CONFIRM_FACTOR * dt_ref * 1e-3):
                run.settled = True
                return run
            # (the step grows back from there: at the short step alone the slope's
            # cuts took more than 200 steps to settle)
            confirms += 1
            now, quiet, confirming = now / CONFIRM_FACTOR, 0, True
            continue
        confirming = False
        if not mechanism:
            moved = np.hypot(*(trial.x - start).T)
            size = model.size[model.topo.block]
            far = moving & (moved > RELEASE_MOVE * size)
            sliding = np.zeros(model.n_blocks, dtype=bool)
            if far.any():
                # only those past the mark: one on its way may yet come to rest (a block
                # sliding 5 mm to a stop, held with the first past the mark at a static
                # step of 0.03 s, was let go above the stop and struck it at 0.086 m/s; a
                # review). The next round finds it if it goes on.
                sliding[model.topo.block[far]] = True
                run.why = "blocks slide on"
                run.sliding = sliding
                return run
        elif not _contracting(moves):
            moved = np.hypot(*(trial.x - start).T)
            over = np.flatnonzero(moving & (moved > limit))
            if over.size:
                v = int(over[np.argmax(moved[over] / limit[over])])
                b = int(model.topo.block[v])
                broken = np.flatnonzero(trial.bolt_broken)
                also = (f"; bolt{'s' if broken.size > 1 else ''} "
                        f"{', '.join(str(int(i)) for i in broken)} (Scene.add_bolt's "
                        "numbers) broke under the load" if broken.size else "")
                raise SimulationError(
                    f"start='settled': the scene does not stand with its joints held: "
                    f"{model.block_label(b)} moved {moved[v]:.3g} m "
                    f"({moved[v] / model.size[b]:.0%} of its size) in {run.steps} static "
                    f"steps and goes on alike (a mechanism, or a block with nothing under "
                    f"it{also}); {_FROM_REST}")
        if quiet >= GROW_AFTER:  # (doubled after every step, every other try was refused)
            now, quiet = min(2.0 * now, dt0), 0
    run.why = f"not settled in {max_steps} static steps"
    if not mechanism:
        # blocks still on their way after all the steps: too slow to reach the mark (a block
        # 1 degree past its friction at the cut slope's static step of 0.019 s; a review:
        # the whole scene then went back to its held state)
        slow = _on_the_way(paces) & model.free & (paces[1] * run.dt**2 > settled_move)
        if slow.any():
            run.why = "blocks slide on slowly"
            run.sliding = slow
    if mechanism:
        short = (f"; the static step, {dt0:.3g} s, is {dt0 / dt_ref:.2g} of rule 9's "
                 f"{dt_ref:.3g} s, and at it a settle is slow to see: give a longer one, or "
                 "none" if dt0 < 0.1 * dt_ref else "")
        raise SimulationError(
            f"start='settled': the scene did not settle in {max_steps} static steps (the last "
            f"moved {run.move:.3g} m, settled is {settled_move * (run.dt / dt_ref) ** 2:.3g} "
            f"m){short}; or {_FROM_REST}")
    return run


_FROM_REST = ("start it from rest to watch it move (Simulation(start='rest'); in a scene "
              "file [simulation] start = \"rest\")")


def settle(model: Model, state: StepState, settings: StepSettings,
           dt: float | None = None) -> tuple[StepState, Settling]:
    """Bring ``state`` to rest under the loads at t = 0 (module docstring): the settled
    state at t = 0 and how it went.

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
        When the scene does not stand with its joints held: a block that has moved
        ``MECHANISM_MOVE`` of its size goes on moving alike, the step is cut ``MAX_CUTS``
        times in a row, or ``SETTLE_STEPS`` steps do not do.
    """
    if state.time != 0.0:
        raise ValueError(f"settle: only a run's start can be settled (t = {state.time:g} s)")
    try:
        dt_ref = static_step(model)
    except ValueError:
        dt_ref = None
    if dt is None:
        if dt_ref is None:
            raise ValueError("start='settled': the scene has no gravity and no joint penalty "
                             "to set a static step by; give Simulation.settle a dt")
        dt0 = dt_ref
    else:
        dt0 = finite_number("dt", dt, positive=True, where="Simulation.settle")
    dt_ref = dt0 if dt_ref is None else dt_ref
    # (more OPEN-CLOSE passes than a run's default: a settle's first step closes every
    # contact at once, and a pass costs less than a cut step)
    static = replace(settings, velocity_carry=0.0,
                     max_open_close=max(settings.max_open_close, SETTLE_PASSES))
    held = _static_steps(model, held_model(model), state, dt0, dt_ref, static, SETTLE_STEPS,
                         mechanism=True)
    # the joints' own friction, but held around the blocks that slide on with it (found
    # round by round, each round from the held state again)
    hold = np.zeros(model.n_blocks, dtype=bool)
    release_steps, refused = 0, held.refused
    for _ in range(RELEASE_ROUNDS):
        released = _static_steps(model, holding_model(model, hold), held.state, dt0, dt_ref,
                                 static, RELEASE_STEPS, mechanism=False)
        release_steps += released.steps
        refused += released.refused
        new = 0 if released.sliding is None else int(np.count_nonzero(released.sliding
                                                                       & ~hold))
        if released.settled or not new:
            break
        hold |= released.sliding
    else:
        released.why = (f"{RELEASE_ROUNDS} rounds found blocks sliding on, the last {new} "
                        "more")
    final = released if released.settled else held
    if not released.settled:
        warnings.warn(PlausibilityWarning(
            f"start='settled': with the joints' own friction the scene did not come to rest "
            f"({released.why}); the held state is handed over, and its shear beyond the "
            "joints' strength is let go at t = 0 (a jolt, as from rest)"), stacklevel=3)
        hold[:] = model.free
    contacts = share_by_strength(model, final.state, dt0)
    free = model.free
    moving = free[model.topo.block]
    moved = np.where(moving, np.hypot(*(final.state.x - model.x_initial).T), 0.0)
    v = int(np.argmax(moved))
    record = Settling(held.steps, max(held.longest, released.longest), float(moved[v]),
                      model.block_label(model.topo.block[v]) if moved[v] > 0 else "",
                      float(final.move), refused,
                      release_steps, released.settled,
                      int(np.count_nonzero(final.state.bolt_broken)),
                      int(np.count_nonzero(hold & model.free)),
                      "" if released.settled else released.why)
    # released at t = 0: every closed contact starts the run marked sliding, so that its law
    # judges it in the first step (legacy DDA's explicit rule keeps a contact that starts a
    # step sticking stuck to the step's end: a floor moved at 0.126 m/s from t = 0 dragged
    # the block it held to its own speed in one step, 0.06 mm of slip in 0.5 s against 1.07)
    c = replace(contacts, state=np.where(contacts.state != OPEN, SLIP,
                                         OPEN).astype(contacts.state.dtype))
    settled = replace(final.state, time=0.0, velocity=model.initial_velocity(),
                      last_move=0.0, contacts=c)
    return settled, record
