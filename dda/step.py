"""One DDA time step as a pure function: ``step(model, state, dt, solver) -> (trial, report)``.

The step builds its problem from the committed :class:`StepState` alone (METHOD.md sections 1
to 5): the block system (stiffness, Newmark inertia, loads, constraint springs), the known
motion of fixed, shaken and moved blocks, contact detection with the committed contacts
carried over, the contact element, the intact bolts (:mod:`dda.bolts`; a bolt above its
strength at the end breaks and the step is solved again without it); a
:class:`dda.solvers.NonlinearSolver` solves it. The trial is then accepted or refused by
three checks, and a refused trial is simply dropped:

- no vertex may move farther than half the contact search distance (two blocks closing on
  each other close their gap by twice the largest move; beyond it a contact may be missed);
- no free block may move farther than ``max_displacement_ratio`` of its size;
- the penetration guard (:func:`dda.contact.penetration.penetration_guard`).

Nothing here changes its inputs: a step that is refused costs nothing to undo, and the
caller (:class:`dda.Simulation`) decides what to do with the report (cut dt, widen the
search, stop).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from dda import geometry
from dda.contact import element as element_module
from dda.contact.contacts import OPEN, ContactSet, carry_over
from dda.contact.dashpot import (
    contact_mass,
    dashpot_stiffness,
    shear_dashpot_end,
    shear_dashpot_start,
)
from dda.contact.detection import (
    TOUCH_TOLERANCE,
    CandidateContacts,
    bounding_boxes,
    broad_phase,
    keep_closed,
    narrow_phase,
    pairs_with_free_block,
)
from dda.contact.element import ContactElement, LawGroups
from dda.contact.faces import FACE_ANGLE
from dda.contact.penetration import (
    GuardReport,
    _untracked_reason,
    held_by_contact,
    penetration_guard,
)
from dda.contact.tangent import SPRING_TERMS
from dda.errors import SimulationError
from dda.kernels.blocks import step_end, step_start_at
from dda.kernels.dashpot import dashpot_stiffnesses
from dda.kernels.open_close import as_float64
from dda.kernels.small_step import FALLBACK, MOVED, NOT_SOLVED, TOO_FAR, UNTRACKED, contact_step
from dda.model import Model
from dda.profiling import count_solve, section
from dda.solvers import legacy as legacy_module
from dda.solvers import newton as newton_module
from dda.solvers import open_close as oc
from dda.solvers.base import NonlinearSolver, StepProblem, StepSolution
from dda.solvers.linear import DENSE_LIMIT, SystemPattern
from dda.solvers.newmark import effective_system, updated_velocity
from dda.solvers.open_close import dense_layout, gap_round_off, pass_rules

__all__ = ["StepSettings", "StepState", "StepReport", "step", "search_distance",
           "deepest_spring", "SEARCH_FACTOR"]

# a scene whose blocks have no damping, loads or constraint springs takes the compiled block
# kernels (dda.kernels.blocks), and every scene the compiled impact dashpots
# (dda.kernels.dashpot): the numpy path's bits, some 60 us less of a 2-block step; False
# sends every scene through numpy (the reference the kernels are tested against)
BLOCK_KERNELS = True

# the contact element's law-independent arrays and dashpots from one kernel call
# (ContactElement.compiled; the same bits, some 40 us less of a 2-block step); False builds
# them through the constructor and the dashpot kernels
COMPILED_ELEMENT = True

# a small scene's common step (the same contacts as the last step, carried over whole) runs
# from its detection to its guard in one kernel call (dda.kernels.small_step; the same bits as
# the composed path, which takes every other step); False: every step composed
SMALL_STEP = True

_NO_MOVES = np.zeros((0, 2))
_NO_BOLT_POINTS = np.zeros((0, 2, 2))
_NO_BOLTS_BROKEN = np.zeros(0, dtype=bool)

# the search distance is this multiple of the step's predicted largest vertex displacement
SEARCH_FACTOR = 2.5


@dataclass(frozen=True)
class StepSettings:
    """How a step is taken (the :class:`dda.Simulation` arguments of the same names)."""

    velocity_carry: float = 1.0
    max_open_close: int = 12
    max_displacement_ratio: float = 0.25
    penetration_tolerance: float = 0.01


@dataclass(frozen=True)
class StepState:
    """Everything a step changes: the state of the blocks and contacts at one time.

    Attributes
    ----------
    time : s
    x : (n_vertices, 2) vertex positions
    velocity : (n_blocks, 6) block velocities
    stress : (n_blocks, 3) block stresses
    rotation : (n_blocks,) rigid rotation from the start
    centroid : (n_blocks, 2) block centroids
    contacts : the committed contacts with their law histories
    load_points, spring_points : where the material points of loads and springs are now
    known_u : (n_blocks, 2) known translation of the blocks whose motion is given
    shaking : the shaking integrators' states, one per shaken block
    last_move : the largest vertex displacement of the last step (m)
    untracked : the deepest untracked penetration left in this state, in tolerances
    penetration : the deepest vertex inside another block, tracked or not (m)
    bolt_points : (n_bolts, 2, 2) where the bolts' two material points are now
    bolt_broken : (n_bolts,) bool, the bolts that have broken
    """

    time: float
    x: np.ndarray
    velocity: np.ndarray
    stress: np.ndarray
    rotation: np.ndarray
    centroid: np.ndarray
    contacts: ContactSet
    load_points: np.ndarray
    spring_points: np.ndarray
    known_u: np.ndarray
    shaking: tuple = ()
    last_move: float = 0.0
    untracked: float = 0.0
    penetration: float = 0.0
    bolt_points: np.ndarray = field(default_factory=lambda: _NO_BOLT_POINTS)
    bolt_broken: np.ndarray = field(default_factory=lambda: _NO_BOLTS_BROKEN)

    @classmethod
    def initial(cls, model: Model) -> StepState:
        """The state a run of ``model`` starts from."""
        nb = model.n_blocks
        bolts = {}
        if model.bolts is not None:
            bolts = {"bolt_points": model.bolts.points.copy(),
                     "bolt_broken": np.zeros(len(model.bolts), dtype=bool)}
        return cls(time=0.0, x=model.x_initial.copy(), velocity=model.initial_velocity(),
                   stress=model.stress_initial.copy(), rotation=np.zeros(nb),
                   centroid=model.centroid_initial.copy(), contacts=model.initial_contacts(),
                   load_points=model.load_initial.copy(),
                   spring_points=model.spring_initial.copy(), known_u=np.zeros((nb, 2)),
                   shaking=tuple(s.history.initial() for s in model.shakes), **bolts)

    def bolt_forces(self, model: Model) -> np.ndarray:
        """(n_bolts,) the bolts' axial forces in this state (N per m, tension positive; 0
        for a broken one)."""
        if model.bolts is None:
            return np.zeros(0)
        return model.bolts.forces(self.bolt_points, self.bolt_broken)


@dataclass(frozen=True)
class StepReport:
    """How a step went: converged or why not, and what it cost."""

    converged: bool
    reason: str = ""
    iterations: int = 0
    open_close_passes: int = 0
    residual_norms: list = field(default_factory=list)
    search_hint: float = 0.0  # a wider search distance a retry should use (m)
    unknowns: int = 0
    pairs: int = 0
    penetration: float = 0.0
    spring_penetration: float = 0.0
    untracked: float = 0.0  # the deepest untracked penetration, in penetration tolerances
    untracked_held: bool = False  # ... and a closed contact holds its vertex (GuardReport)

    @classmethod
    def of(cls, sol: StepSolution, unknowns: int, pairs: int, reason: str = "",
           search_hint: float = 0.0, guard=None) -> StepReport:
        """The report of a step the solver answered with ``sol``; a ``reason`` refuses it
        even when the solver converged."""
        guard = guard or GuardReport()
        return cls(sol.converged and not reason, reason or sol.reason, sol.iterations,
                   sol.open_close_passes, list(sol.residual_norms), search_hint, unknowns,
                   pairs, guard.deepest, guard.spring_deepest, guard.untracked, guard.held)


@dataclass(frozen=True)
class _Detected:
    contacts: ContactSet
    fresh: np.ndarray
    geometry: object
    pairs: np.ndarray
    n_pairs: int
    new: np.ndarray | None = None  # the contacts found anew (None: as ``fresh``)


def step(model: Model, state: StepState, dt: float, solver: NonlinearSolver,
         settings: StepSettings | None = None,
         search_hint: float = 0.0) -> tuple[StepState | None, StepReport]:
    """Take one step of ``dt`` from ``state``: the trial state, or None, and the report.

    ``search_hint`` widens the contact search distance (m) after a step that moved farther
    than predicted. Raises :class:`dda.SimulationError` when two blocks meet that have no
    joint.
    """
    settings = settings or StepSettings()
    t1 = state.time + dt
    # a static analysis carries no velocity: no inertial force term
    carry = settings.velocity_carry
    plain = BLOCK_KERNELS and model.plain_blocks
    if plain:
        ints, k_eff, f_eff, v_eff, speed = _plain_start(model, state, dt, carry)
    else:
        ints = geometry.polygon_integrals(state.x, model.offsets, model.topo.nxt)
        k, m, c, f = model.block_forces(t1, ints, state.stress, state.load_points,
                                        state.spring_points, state.x)
        v_eff = state.velocity * carry if carry else None
        k_eff, f_eff = effective_system(k, m, f, v_eff, dt, c)
        speed = None
    d_known = np.zeros((model.n_blocks, 6))
    if model.moves_known:
        known_u, known_v, shaking = model.known_motion(t1, state.known_u, state.shaking)
        d_known[:, :2] = known_u - state.known_u
        d_known[model.free] = 0.0
        known_du = d_known[~model.free, :2]
    else:  # the known blocks stand still (the arrays are shared, never changed in place)
        known_u, known_v, shaking, known_du = state.known_u, None, state.shaking, _NO_MOVES
    d0 = search_distance(model, state, dt, carry, ints.centroid, known_du, search_hint, speed)
    # the intact bolts (dda.bolts): the anchored ones in the blocks' system, the term of those
    # between two free blocks (None in a scene without such bolts)
    bolts, blocks_only = None, (k_eff, f_eff)
    if model.bolts is not None:
        with section("assembly"):
            k_eff, f_eff, bolts = model.bolts.system(state.bolt_points, state.bolt_broken,
                                                     ints.centroid, model.free, k_eff, f_eff,
                                                     d_known)
    if plain and carry and SMALL_STEP and bolts is None:
        done = _small_step(model, state, dt, solver, settings, d0, ints, k_eff, f_eff, v_eff,
                           (known_u, known_v, d_known, shaking))
        # (a trial in which a bolt breaks is solved again by the composed path below)
        if done is not None and (model.bolts is None or not _overloaded(model, state, done)):
            return done
    found = _detect(model, state, d0, settings.penetration_tolerance)
    element = _element(model, state, found, ints, dt if carry else 0.0)
    element.laws.dt = dt  # a rate-dependent law's (FrictionLaw.uses_dt), static steps too
    problem = StepProblem(dt=dt, block_k=k_eff, block_f=f_eff, free=model.free,
                          d_known=d_known, element=element,
                          max_open_close=settings.max_open_close, rigid=model.rigid,
                          factors=_factors(solver), bolts=bolts)
    sol = solver.solve_step(problem)
    broken = state.bolt_broken
    if model.bolts is not None and sol.converged:
        sol, problem, broken = _break_bolts(model, state, solver, problem, sol, ints.centroid,
                                            blocks_only)
    if element.shear_dashpot is not None and sol.contacts is not None:
        shear_dashpot_end(sol.contacts, *element.shear_dashpot)
    costs = (problem.pattern.unknowns, found.n_pairs)
    if not sol.converged:
        return None, StepReport.of(sol, *costs)
    if plain:
        ended = _Ended(*step_end(state.x, model.topo.block, model.offsets, ints.centroid,
                                 sol.d, model.free, model.size,
                                 state.velocity if v_eff is None else v_eff, v_eff is not None,
                                 2.0 / dt, model.elasticity, state.stress,
                                 state.rotation)[1:])  # (the moves themselves: unused)
    else:
        ended = _ended(model, state, ints.centroid, sol.d)
    refused = _refusal(model, ended, d0, settings.max_displacement_ratio)
    if refused is not None:
        return None, StepReport.of(sol, *costs, reason=refused[0], search_hint=refused[1])
    x_new = ended.x_new
    with section("guard"):
        # no vertex moved farther than d0 (checked above), so the pairs whose boxes
        # overlap at the end of the step are among the detection's, grown by d0
        guard = penetration_guard(model, x_new, sol.contacts, element.normal_penalty,
                                  found.pairs, settings.penetration_tolerance,
                                  dashpot=element.dashpot)
    report = StepReport.of(sol, *costs, reason=guard.reason, guard=guard)
    if guard.reason:
        return None, report
    trial = _advanced(model, state, dt, sol, ints.centroid, ended, v_eff,
                      (known_u, known_v, d_known, shaking), guard, broken)
    return trial, report


def _overloaded(model, state, done) -> bool:
    """Whether a bolt of the small step's trial (``done``: trial and report) is above its
    strength."""
    trial = done[0]
    if trial is None:
        return False
    return model.bolts.to_break(trial.bolt_forces(model), trial.bolt_broken) >= 0


def _break_bolts(model, state, solver, problem, sol, centroid, blocks_only):
    """The step's solution once no intact bolt is above its strength at its end
    (:mod:`dda.bolts`: the most overloaded breaks and the step is solved again from its
    start without it, until none is); ``(solution, problem, broken flags)``. ``blocks_only``
    is the blocks' effective system without the bolts. The passes and iterations of every
    solve are counted in the solution's."""
    bolts = model.bolts
    broken = state.bolt_broken
    passes = iterations = 0
    while sol.converged:
        ends = bolts.moved(state.bolt_points, centroid, sol.d)
        i = bolts.to_break(bolts.forces(ends, broken), broken)
        if i < 0:
            break
        broken = broken.copy()
        broken[i] = True
        passes += sol.open_close_passes
        iterations += sol.iterations
        k, f, coupled = bolts.system(state.bolt_points, broken, centroid, model.free,
                                     *blocks_only, problem.d_known)
        problem = replace(problem, block_k=k, block_f=f, bolts=coupled)
        sol = solver.solve_step(problem)
    sol.open_close_passes += passes
    sol.iterations += iterations
    return sol, problem, broken


def _small_step(model, state, dt, solver, settings, d0, ints, k_eff, f_eff, v_eff, known):
    """:func:`step` from the detection on through :func:`dda.kernels.small_step.
    contact_step`, or None when the step is not one it takes (then the composed path does).

    It takes a dynamic step of a scene of plain blocks with one built-in law, a dense system,
    contacts in the committed state, and the solver's own one-call dense step
    (:class:`dda.solvers.LegacyPullBack`, :class:`dda.solvers.NewtonRaphson`)."""
    arguments = contact_step_arguments(model, state, dt, solver, settings, d0, ints, k_eff,
                                       f_eff, v_eff, known)
    if arguments is None:
        return None
    args, pattern, sliding = arguments
    c = state.contacts
    newton = args[0]
    with section("solve"):
        (status, counts, numbers_out, d, norms, trial_state, rows, x_new, velocity, stress,
         rotation, centroid) = contact_step(*args)
    if status == FALLBACK:
        return None
    xi0, t_n, t_s, g_se, slip, sliding_out, ago = rows
    (solver_status, oc_status, oc_passes, passes, iterations, solves, n_pairs, worst, gv, gk,
     on_edge) = counts.tolist()
    largest, worst_move, scale, deepest, spring, untracked, gdepth, gtol = numbers_out.tolist()
    count_solve(solves)
    costs = (pattern.unknowns, n_pairs)
    if status == NOT_SOLVED:
        return None, StepReport.of(_small_failure(newton, solver, solver_status, oc_status,
                                                  oc_passes, passes, iterations, d, norms,
                                                  scale), *costs)
    history = {"g_se": g_se, "slip": slip}
    if sliding:
        history["sliding"] = sliding_out
    sol = StepSolution(d, ContactSet(c.vertex, c.edge, c.bj, c.bk, trial_state, xi0, t_n, t_s,
                                     history, ago.astype(np.int64)), True, passes,
                       iterations if newton else passes, "", norms.tolist() if newton else [])
    ended = _Ended(x_new, largest, worst, worst_move, velocity, stress, rotation, centroid)
    if status == MOVED or status == TOO_FAR:
        refused = _refusal(model, ended, d0, settings.max_displacement_ratio)
        return None, StepReport.of(sol, *costs, reason=refused[0], search_hint=refused[1])
    reason, held = "", False
    if status == UNTRACKED:
        reason = _untracked_reason(model, x_new, bool(on_edge), gv, gk, gdepth, gtol)
        held = held_by_contact(sol.contacts, model.topo, gv, gk, bool(on_edge))
    guard = GuardReport(reason, deepest, spring, untracked, held)
    report = StepReport.of(sol, *costs, reason=reason, guard=guard)
    if reason:
        return None, report
    return _advanced(model, state, dt, sol, ints.centroid, ended, v_eff, known, guard), report


def _small_failure(newton, solver, solver_status, oc_status, oc_passes, passes, iterations, d,
                   norms, scale) -> StepSolution:
    """The failed solution of :func:`_small_step`'s solver, as the solver's own dense step
    words it (:mod:`dda.solvers.legacy`, :mod:`dda.solvers.newton`)."""
    if not newton:
        return StepSolution(None, None, False, passes, passes,
                            oc.dense_failure(solver_status, passes))
    unsettled = oc_status == oc.NOT_SETTLED and solver.unsettled_predictor
    if oc_status != oc.CONVERGED and not unsettled:
        return StepSolution(None, None, False, passes, 0, oc.dense_failure(oc_status, oc_passes))
    sol = newton_module._solution(None, solver_status, iterations, d, norms, scale, None, None,
                                  None, None, None)
    sol.open_close_passes = passes
    if unsettled:
        sol.reason = (f"{oc.dense_failure(oc_status, oc_passes)}, and from its last pass "
                      f"{sol.reason}")
    return sol


def contact_step_arguments(model, state, dt, solver, settings, d0, ints, k_eff, f_eff, v_eff,
                           known):
    """The arguments of :func:`dda.kernels.small_step.contact_step` for a step of ``dt`` from
    ``state`` (with :func:`step`'s start: ``d0``, the blocks' integrals and effective system,
    the carried velocity and the known motion), the scene's
    :class:`dda.solvers.linear.SystemPattern` and whether the law keeps a ``sliding``
    history; None when it is not a step :func:`_small_step` takes."""
    c = state.contacts
    m = len(c)
    kind = type(solver)
    newton = kind is newton_module.NewtonRaphson
    # it stands for the solvers' own solve_step and this module's detection: a solver
    # whose solve_step is wrapped, or a detection function swapped, takes the composed path
    if not (m and COMPILED_ELEMENT and oc.DENSE_PASSES and oc.PASS_LOG is None
            and element_module.KERNEL_LAWS and "solve_step" not in solver.__dict__
            and narrow_phase is _NARROW_PHASE and keep_closed is _KEEP_CLOSED
            and (newton and newton_module.DENSE_NEWTON and newton_module.NEWTON_DENSE_STEP
                 and kind.solve_step is _NEWTON_SOLVE_STEP
                 or kind is legacy_module.LegacyPullBack and legacy_module.LEGACY_DENSE_STEP
                 and kind.solve_step is _LEGACY_SOLVE_STEP)):
        return None
    constants = _small_step_constants(model)
    if constants is None:
        return None
    law, initial, zeta, zeta_s, rigid, faces = constants
    history = c.history
    sliding = history.get("sliding")
    if (len(history) != 2 + (sliding is not None) or "g_se" not in history
            or "slip" not in history or (sliding is None and law[0] != 0)):
        return None
    factors = _factors(solver)
    args = (model.free, c.bj, c.bk, model.rigid)
    pattern = (SystemPattern(*args) if factors is None else factors.kept(
        "pattern", args, lambda: SystemPattern(*args, cache=factors)))
    if pattern.n > DENSE_LIMIT or pattern.unknowns == 0:
        return None
    joints = model.joints
    return (newton, state.x, model.offsets, model.topo.nxt, model.topo.prv, model.topo.block,
            model.free, model.thickness, model.size, model.density, model.elasticity,
            state.stress, state.rotation, ints.centroid, ints.area, ints.sxx, ints.syy, v_eff,
            float(dt), float(d0), float(state.penetration), model.min_size,
            float(settings.penetration_tolerance), model.min_thickness,
            float(settings.max_displacement_ratio), joints.pair_keys, joints.pair_joint,
            joints.default, joints.normal_penalty, joints.shear_penalty, zeta, zeta_s,
            c.vertex, c.edge, c.bj, c.bk, c.state, c.xi0, c.t_n, c.t_s, history["g_se"],
            history["slip"], np.zeros(m) if sliding is None else sliding,
            np.asarray(c.held_ago, dtype=np.int64), law, initial,
            k_eff, f_eff, known[2], *dense_layout(pattern), SPRING_TERMS, oc.GAP_ROUND_OFF,
            oc._COORDINATE_ROUND_OFF, settings.max_open_close, float(oc.SETTLE_BAND),
            (*pass_rules(), oc.RETRY_PATIENCE, oc.LAG_SECANT_FROM, oc.cycle_measure(solver),
             oc.cycle_memory(solver)),
            bool(getattr(solver, "unsettled_predictor", False)),
            int(getattr(solver, "max_iter", 1)), newton_module.PREDICTOR_ITERATIONS,
            float(newton_module.PREDICTOR_CONTRACTION), float(getattr(solver, "tol", 1.0)),
            newton_module.ROUND_OFF,
            newton_module.LINE_SEARCH_HALVINGS, newton_module.CYCLE_LENGTH,
            bool(newton_module.REVERSED_STICK), *newton_module._hold_rule(), rigid, faces,
            _FACE_COS, bool(newton_module.NOISE_FLOOR)), pattern, sliding is not None


def _small_step_constants(model):
    """What :func:`_small_step` passes of the model's one law and joints, kept with the
    model while its joint table is the same object; None when the scene has none to pass
    (several laws, or a law without a kernel)."""
    joints = model.joints
    kept = model.__dict__.get("_small_step_constants")
    if kept is not None and kept[0] is joints:
        return kept[1]
    constants = None
    if len(joints.laws) == 1 and model.n_blocks > 1:
        law = joints.laws[0]
        numbers = law._kernel_parameters()
        if numbers is not None:
            initial = law.history_fields()
            zeta = joints.damping_ratio
            zeta_s = getattr(joints, "shear_damping_ratio", None)
            constants = (
                (int(numbers[0]), *(float(v) for v in numbers[1:])),
                (float(initial["g_se"]), float(initial["slip"]),
                 float(initial.get("sliding", 0.0))),
                _NO_ZETA if zeta is None else np.ascontiguousarray(zeta, dtype=np.float64),
                _NO_ZETA if zeta_s is None else np.ascontiguousarray(zeta_s, dtype=np.float64),
                np.zeros(model.n_blocks, dtype=np.bool_) if model.rigid is None
                else np.asarray(model.rigid, dtype=np.bool_), bool(law.uses_faces))
    model.__dict__["_small_step_constants"] = (joints, constants)
    return constants


_NO_ZETA = np.zeros(0)
_FACE_COS = float(np.cos(np.radians(FACE_ANGLE)))
_NARROW_PHASE, _KEEP_CLOSED = narrow_phase, keep_closed
_LEGACY_SOLVE_STEP = legacy_module.LegacyPullBack.solve_step
_NEWTON_SOLVE_STEP = newton_module.NewtonRaphson.solve_step


def search_distance(model, state, dt, carry, centroid, known_du, search_hint=0.0,
                    speed=None) -> float:
    """How far from a vertex contacts are looked for in a step (m).

    ``SEARCH_FACTOR`` times the largest of the predicted vertex displacement (velocity times
    dt plus the fall under gravity), the known blocks' moves, the last step's largest move
    and the hint, plus a floor of 1e-6 of the smallest block. ``centroid`` are the blocks'
    centroids at the step's start; ``speed``, the largest vertex speed ``|T(x) carry v|``
    when it is known (:func:`dda.kernels.blocks.step_start`).
    """
    if speed is None:
        t = geometry.t_matrix(state.x, centroid[model.topo.block])
        vv = np.einsum("vij,vj->vi", t, state.velocity[model.topo.block] * carry)
        speed = np.hypot(vv[:, 0], vv[:, 1]).max() if len(vv) else 0.0
    predicted = speed * dt
    predicted += 0.5 * abs(model.gravity or 0.0) * dt * dt
    if len(known_du):
        predicted = max(predicted, float(np.hypot(known_du[:, 0], known_du[:, 1]).max()))
    floor = 1e-6 * model.min_size
    return SEARCH_FACTOR * max(predicted, state.last_move, search_hint) + floor


def deepest_spring(model, contacts) -> float:
    """Deepest penetration of the committed closed springs (m)."""
    return model.deepest_spring(contacts)


def _detect(model, state, d0, tolerance) -> _Detected:
    """The step's contacts: detection within ``d0``, the committed ones carried over."""
    # how deep behind an edge a vertex is still taken for a contact: twice the deepest
    # vertex of the committed state (found by the guard, tracked or not) plus the search
    # distance; detection takes a negative gap only for a vertex inside the edge's block, so
    # no far edge of a thin block is taken for a contact (soft penalties let contacts sink
    # further than a fixed limit, and a closed contact must never be lost)
    pen_limit = max(2.0 * d0, 1e-3 * model.min_size,
                    2.0 * max(deepest_spring(model, state.contacts), state.penetration) + d0)
    topo = model.topo
    if model.n_blocks > 1:
        with section("detection"):
            # a vertex sunk deeper than a quarter of the guard's tolerance (of the thinner
            # block of its pair) is held by the edge nearest to it, and two such corners get
            # a spring each
            sunk = 0.25 * tolerance * model.thickness
            boxes = bounding_boxes(state.x, model.offsets)
            pairs = _pairs(model, boxes, max(d0, pen_limit))
            # blocks built touching (overlaps the scene accepts) touch at the first step
            touch = TOUCH_TOLERANCE if state.time == 0.0 else 0.0
            cand = narrow_phase(state.x, topo, d0, pen_limit, pairs, sunk, boxes, touch)
            closed = state.contacts.state != OPEN
            cand = keep_closed(cand, state.contacts.vertex[closed], state.contacts.edge[closed],
                               state.x, topo, d0, pen_limit, model.n_blocks, sunk)
            contacts, fresh, geom, new = carry_over(state.contacts, cand, state.x, topo.nxt,
                                                    topo.prv, model.n_blocks, with_new=True)
    else:  # a single block: nothing to detect
        pairs = np.zeros((0, 2), dtype=np.int64)
        cand = CandidateContacts(*(np.zeros(0, dtype=np.int64) for _ in range(4)))
        contacts, fresh, geom, new = carry_over(state.contacts, cand, state.x, topo.nxt,
                                                topo.prv, model.n_blocks, with_new=True)
    return _Detected(contacts, fresh, geom, pairs, cand.pairs, new)


def _pairs(model, boxes, margin) -> np.ndarray:
    """Block pairs whose ``boxes``, grown by ``margin``, overlap, less those of two blocks
    whose motion is known (fixed, shaken, moved): a contact between them acts on no unknown,
    and its spring (two fixed blocks built touching or overlapping) would only hold
    fictitious energy."""
    return pairs_with_free_block(broad_phase(boxes, margin), model.free)


def _element(model, state, found: _Detected, ints, dt: float) -> ContactElement:
    """The contact element of the detected contacts, each with its joint's penalties, impact
    dashpot and law (new and open contacts get their law's initial history). ``dt`` 0: a
    static step, which takes no dashpot."""
    contacts = found.contacts
    joint = model.joint_index(contacts.bj, contacts.bk)
    if model.joints.default < 0 and np.any(joint < 0):
        i = int(np.flatnonzero(joint < 0)[0])
        raise SimulationError(
            f"no joint between {model.block_label(contacts.bj[i])} and "
            f"{model.block_label(contacts.bk[i])}; set a default joint"
        )
    if len(model.joints.laws) == 1:  # one law: LawGroups.build's groups without the sort
        m = len(contacts)
        laws = LawGroups([(model.joints.laws[0], np.arange(m))] if m else [])
    else:
        laws = LawGroups.build(model.joints.law[joint], list(model.joints.laws))
    laws.initial_history(contacts.history, found.fresh,
                         found.fresh if found.new is None else found.new)
    pn = model.joints.normal_penalty[joint]
    if COMPILED_ELEMENT and BLOCK_KERNELS and len(contacts):
        return _compiled_element(model, state, found, ints, dt, joint, laws, pn)
    element = ContactElement(contacts, state.x, ints.centroid, model.topo.nxt, model.topo.prv,
                             pn, model.joints.shear_penalty[joint], laws, found.geometry)
    zeta = model.joints.damping_ratio
    if zeta is not None and dt > 0.0 and len(contacts):
        if BLOCK_KERNELS:
            g = element.geometry
            element.dashpot = dashpot_stiffnesses(
                zeta[joint], as_float64(pn), as_float64(g.p1), as_float64(g.normal),
                contacts.bj, contacts.bk, ints.centroid, model.free, model.density, ints.area,
                ints.sxx, ints.syy, float(dt))
        else:
            element.dashpot = dashpot_stiffness(zeta[joint], pn, _contact_mass(
                model, ints, contacts, element.geometry), dt)
    zeta_s = getattr(model.joints, "shear_damping_ratio", None)
    if zeta_s is not None and dt > 0.0 and len(contacts) and "g_se" in contacts.history:
        _with_shear_dashpot(model, ints, element, zeta_s[joint], dt)
    return element


def _compiled_element(model, state, found, ints, dt, joint, laws, pn) -> ContactElement:
    """:func:`_element` through :meth:`ContactElement.compiled` (the same arrays)."""
    damped = dt > 0.0
    zeta = model.joints.damping_ratio
    zeta_s = getattr(model.joints, "shear_damping_ratio", None)
    return ContactElement.compiled(
        found.contacts, state.x, ints.centroid, model.topo.nxt, model.topo.prv, pn,
        model.joints.shear_penalty[joint], laws, found.geometry,
        (model.free, model.density, ints.area, ints.sxx, ints.syy), float(dt),
        gap_round_off(), zeta[joint] if damped and zeta is not None else None,
        zeta_s[joint] if damped and zeta_s is not None else None)


def _with_shear_dashpot(model, ints, element, zeta, dt) -> None:
    """The step's element with its contacts' shear dashpots (:func:`dda.contact.dashpot.
    shear_dashpot_start`): the effective shear penalty, the scaled committed ``g_se``, and in
    ``element.shear_dashpot`` what the step's end needs to undo them."""
    contacts, g = element.contacts, element.geometry
    ps = as_float64(element.shear_penalty)
    tangent = np.ascontiguousarray(np.column_stack((g.normal[:, 1], -g.normal[:, 0])))
    if BLOCK_KERNELS:
        cs = dashpot_stiffnesses(zeta, ps, as_float64(g.p1), tangent, contacts.bj, contacts.bk,
                                 ints.centroid, model.free, model.density, ints.area, ints.sxx,
                                 ints.syy, float(dt))
    else:
        cs = dashpot_stiffness(zeta, ps, _contact_mass(model, ints, contacts, g, tangent), dt)
    g_se0 = np.array(contacts.history["g_se"], dtype=float)
    element.shear_penalty, contacts.history["g_se"] = shear_dashpot_start(ps, cs, g_se0)
    element.shear_dashpot = (ps, cs, g_se0)


def _contact_mass(model, ints, contacts, geom, direction=None) -> np.ndarray:
    """(m,) the mass each contact's impact dashpot sees along its normal, or along
    ``direction`` (:func:`dda.contact.dashpot.contact_mass`), from the blocks at the step's
    start."""
    mass = np.where(model.free, model.density * ints.area, np.inf)
    inertia = np.where(model.free, model.density * (ints.sxx + ints.syy), np.inf)
    bj, bk = contacts.bj, contacts.bk
    return contact_mass(geom.p1, geom.normal if direction is None else direction,
                        ints.centroid[bj], ints.centroid[bk], mass[bj],
                        mass[bk], inertia[bj], inertia[bk])


@dataclass(frozen=True)
class _Ended:
    """The blocks at the end of a step (:func:`dda.kernels.blocks.step_end`'s outputs)."""

    x_new: np.ndarray
    largest: float
    worst: int
    worst_move: float
    velocity: np.ndarray | None = None  # None: not updated yet (the numpy path)
    stress: np.ndarray | None = None
    rotation: np.ndarray | None = None
    centroid: np.ndarray | None = None


def _ended(model, state, centroid, d) -> _Ended:
    """The vertex moves of ``d`` and what the checks need of them (numpy)."""
    move = geometry.vertex_displacements(state.x, centroid[model.topo.block],
                                         d[model.topo.block])
    distance = np.hypot(move[:, 0], move[:, 1])
    per_block = np.maximum.reduceat(distance, model.offsets[:-1])
    ratio = np.where(model.free, per_block / model.size, 0.0)
    worst = int(np.argmax(ratio))
    return _Ended(state.x + move, float(distance.max()), worst, float(per_block[worst]))


def _refusal(model, ended: _Ended, d0, max_ratio):
    """None when the step's moves are acceptable, else ``(reason, search hint)``."""
    largest = ended.largest
    # two blocks closing on each other close their gap by up to twice the largest move: a
    # vertex that moved more than half the search distance may have met an edge that was
    # not searched
    if 2.0 * largest > d0:
        return (f"a vertex moved {largest:.3g} m, more than half the contact search "
                f"distance {d0:.3g} m", 2.0 * largest)
    worst, moved = ended.worst, ended.worst_move
    if model.free[worst] and moved / model.size[worst] > max_ratio:
        return (f"{model.block_label(worst)} moved {moved:.3g} m in one step, more "
                f"than max_displacement_ratio {max_ratio:g} of its size "
                f"{model.size[worst]:.3g} m", 0.0)
    return None


def _advanced(model, state, dt, sol, centroid, ended: _Ended, v_eff, known,
              guard, bolt_broken=None) -> StepState:
    """The trial state at the end of an accepted step (Newmark update, METHOD.md s. 2)."""
    known_u, known_v, d_known, shaking = known
    d = sol.d
    free = model.free
    if ended.velocity is None:
        vel = np.where(free[:, None], updated_velocity(d, v_eff, dt), 0.0)
        stress = state.stress + np.where(
            free[:, None], np.einsum("bij,bj->bi", model.elasticity, d[:, 3:]), 0.0)
        rotation, centroid_new = state.rotation + d[:, 2], centroid + d[:, :2]
    else:
        vel, stress = ended.velocity, ended.stress
        rotation, centroid_new = ended.rotation, ended.centroid
    if model.rigid is not None:
        vel[model.rigid, 3:] = 0.0
    if known_v is not None:  # (None: the known blocks stand still, their velocity 0)
        vel[~free, :2] = known_v[~free]
    for mo in model.full_motions:
        vel[mo.block, :2] = d_known[mo.block, :2] / dt
    load_points = state.load_points
    if len(model.load_block):
        load_points = load_points + geometry.vertex_displacements(
            load_points, centroid[model.load_block], d[model.load_block])
    spring_points = state.spring_points
    if len(model.spring_block):
        spring_points = spring_points + geometry.vertex_displacements(
            spring_points, centroid[model.spring_block], d[model.spring_block])
    bolt_points = state.bolt_points
    if model.bolts is not None:
        bolt_points = model.bolts.moved(bolt_points, centroid, d)
    return StepState(
        time=state.time + dt, x=ended.x_new, velocity=vel, stress=stress,
        rotation=rotation,
        # a step maps each block affinely, which carries its centroid by (u0, v0)
        centroid=centroid_new, contacts=sol.contacts, load_points=load_points,
        spring_points=spring_points, known_u=known_u, shaking=shaking,
        last_move=ended.largest, untracked=guard.untracked, penetration=guard.deepest,
        bolt_points=bolt_points,
        bolt_broken=state.bolt_broken if bolt_broken is None else bolt_broken,
    )


def _plain_start(model, state, dt, carry):
    """The blocks' integrals, effective system, carried velocity (None in a static step) and
    largest predicted vertex speed, from :func:`dda.kernels.blocks.step_start_at`."""
    x = state.x
    area, centroid, sxx, syy, sxy, k_eff, f_eff, v_eff, speed = step_start_at(
        x, model.offsets, model.topo.nxt, model.density, model.elasticity,
        float(model.gravity or 0.0), state.stress, model.topo.block, state.velocity,
        float(carry), 2.0 / dt**2, 2.0 / dt, bool(carry))
    ints = geometry.PolygonIntegrals(area=area, centroid=centroid, sxx=sxx, syy=syy, sxy=sxy)
    return ints, k_eff, f_eff, (v_eff if carry else None), speed


def _factors(solver):
    """The solver's kept factorizations (a solver that is not a NonlinearSolver has none)."""
    factors = getattr(solver, "factors", None)
    return factors() if callable(factors) else None
