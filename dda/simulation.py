"""Simulation: the step loop, OPEN-CLOSE through a solver, commit/revert, adaptive dt, recorders.

Every step is built from the committed state (blocks and contacts) into a trial; the trial is
committed only when the solver has converged, otherwise it is dropped and the step is tried
again with half the step size. All work inside a step is on arrays over blocks and contacts.
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
import threading
import time as _time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dda import geometry
from dda._checks import finite_number
from dda.contact.contacts import OPEN, SLIP, ContactSet, carry_over
from dda.contact.detection import (
    CandidateContacts,
    VertexTopology,
    bounding_boxes,
    broad_phase,
    narrow_phase,
)
from dda.contact.element import ContactElement, LawGroups
from dda.contact.kinematics import contact_geometry
from dda.contact.penetration import untracked_depth, vertex_penetrations
from dda.penalty_advice import (
    SOFT_DEPTH,
    STIFF_CUTS,
    STIFF_SHARE,
    PenaltyWarning,
    contact_cut,
    soft_penalty_advice,
    stiff_penalty_advice,
)
from dda.profiling import StepProfile, section
from dda.result import Frame, Result
from dda.scene import Scene
from dda.solvers.base import NonlinearSolver, StepProblem
from dda.solvers.newmark import effective_system, updated_velocity
from dda.solvers.newton import NewtonRaphson

__all__ = ["Simulation", "SimulationError", "PenaltyWarning"]

# a step is cut at most this many times in a row before the run stops
MAX_CUTS = 12
# after this many good steps in a row a cut step size is doubled again
GROW_AFTER = 8
# the search distance is this multiple of the step's predicted largest vertex displacement
SEARCH_FACTOR = 2.5
# times a step is tried again with a wider search before its dt is cut instead
MAX_WIDENINGS = 2
# layout of the checkpoint files written by Simulation.run
CHECKPOINT_VERSION = 3  # 2: Simulation.damping; 3: the penetration guard


class SimulationError(RuntimeError):
    """A run that cannot go on; ``result`` holds the steps done before."""

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


@dataclass
class _Committed:
    """The committed state of the blocks and contacts at one time."""

    time: float
    x: np.ndarray
    velocity: np.ndarray
    stress: np.ndarray
    rotation: np.ndarray
    contacts: ContactSet
    load_points: np.ndarray
    spring_points: np.ndarray
    known_u: np.ndarray
    last_move: float
    centroid: np.ndarray
    # the deepest untracked penetration left in this state, in penetration tolerances
    untracked: float = 0.0
    # the deepest vertex inside another block, tracked or not (m)
    penetration: float = 0.0


class Simulation:
    """A DDA run of a scene.

    Parameters
    ----------
    scene : Scene
    dt : float
        Step size (s). Steps are cut when a step does not converge and grow back afterwards.
    solver : NonlinearSolver, optional
        How one step is solved: ``NewtonRaphson()`` (the default, fully implicit) or
        ``LegacyPullBack()`` (original DDA).
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
        does not converge; dt grows back (doubling) after ``GROW_AFTER`` quiet steps. Every
        cut is in ``result.stats.cuts`` as (time, dt, reason).
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

    def __init__(self, scene: Scene, dt: float, solver: NonlinearSolver | None = None,
                 analysis: str = "dynamic", velocity_carry: float = 1.0,
                 max_open_close: int = 12, record_every: int = 1, output=None,
                 max_displacement_ratio: float = 0.25, penetration_tolerance: float = 0.01):
        if not isinstance(scene, Scene):
            raise TypeError(f"Simulation: scene must be a dda.Scene, got {scene!r}")
        self.dt = finite_number("dt", dt, positive=True, where="Simulation")
        if solver is None:
            solver = NewtonRaphson()
        if not isinstance(solver, NonlinearSolver):
            raise TypeError(f"Simulation: solver must be a NonlinearSolver, got {solver!r}")
        if analysis not in ("dynamic", "static"):
            raise ValueError(
                f"Simulation: analysis must be 'dynamic' or 'static', got {analysis!r}"
            )
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
        self._setup()

    # ------------------------------------------------------------------ setup
    def _setup(self):
        sc = self.scene
        blocks = sc._blocks
        nb = len(blocks)
        self.n_blocks = nb
        x0, offsets = sc.vertex_arrays()
        self.offsets = offsets
        self.topo = VertexTopology.from_offsets(offsets)
        self.x_initial = x0.copy()
        ints = geometry.polygon_integrals(x0, offsets)
        self.centroid_initial = ints.centroid.copy()
        self.size = np.sqrt(ints.area)  # a length scale per block
        # a half-width per block (2 area / perimeter: half the side of a square, about half
        # the thickness of a slab): the penetration guard's tolerance is a fraction of it
        edges = x0[self.topo.nxt] - x0
        perimeter = np.add.reduceat(np.hypot(edges[:, 0], edges[:, 1]), offsets[:-1])
        self.thickness = 2.0 * ints.area / perimeter
        self.density = np.array([b.material.density for b in blocks])
        self.elasticity = np.stack([b.material.elasticity() for b in blocks])
        young = np.array([b.material.young for b in blocks])

        # blocks whose motion is known carry no unknowns; rigid ones carry no strain unknowns
        self.free = np.array([not b.fixed for b in blocks])
        rigid = np.array([b.rigid for b in blocks], dtype=bool)
        self.rigid = rigid if rigid.any() else None
        self.shakes = list(sc._shakes)
        full = [m for m in sc._motions if not m.springs]
        self.partial = [m for m in sc._motions if m.springs]
        self.full_motions = full
        for s in self.shakes:
            self.free[s.block] = False
        for m in full:
            self.free[m.block] = False
        self.constraint_penalty = 100.0 * young.max()
        # Rayleigh damping coefficients per block, None for a scene without damping
        self.damping = sc.damping_coefficients()

        # joints: one table of unique joints, a default and sorted per-pair overrides
        joints, index_of = [], {}

        def joint_id(j):
            if id(j) not in index_of:
                index_of[id(j)] = len(joints)
                joints.append(j)
            return index_of[id(j)]

        default = sc._joints.default
        self.default_joint = joint_id(default) if default is not None else -1
        keys = np.array([a * nb + b for (a, b) in sc._joints.pairs], dtype=np.int64)
        ids = np.array([joint_id(j) for j in sc._joints.pairs.values()], dtype=np.int64)
        order = np.argsort(keys)
        self.pair_keys, self.pair_joint = keys[order], ids[order]
        laws, law_of = [], {}
        for j in joints:
            if id(j.friction) not in law_of:
                law_of[id(j.friction)] = len(laws)
                laws.append(j.friction)
        self.laws = laws
        self.joint_pn = np.array([j.normal_penalty for j in joints], dtype=float)
        self.joint_ps = np.array([j.shear_penalty for j in joints], dtype=float)
        self.joint_law = np.array([law_of[id(j.friction)] for j in joints], dtype=np.int64)
        fields = {}  # the history fields of every law in the scene
        for law in laws:
            fields.update(law.history_fields())
        self.history_fields = fields

        # initial state
        vel = np.zeros((nb, 6))
        for i, b in enumerate(blocks):
            vel[i, :2] = b.velocity
            vel[i, 2] = b.angular_velocity
        vel[~self.free] = 0.0
        loads = np.array([ld.point for ld in sc._loads]).reshape(-1, 2)
        self.load_block = np.array([ld.block for ld in sc._loads], dtype=np.int64)
        self.load_constant = np.array([ld.force(0.0) if ld.force.constant else (0.0, 0.0)
                                       for ld in sc._loads]).reshape(-1, 2)
        self.load_varying = [(i, ld.force) for i, ld in enumerate(sc._loads)
                             if not ld.force.constant]
        # spring constraints: one penalty spring per point (default: every vertex) of each
        # such block, as arrays; the points are material points that move with the block
        spring_points = [m.points if m.points is not None
                         else x0[offsets[m.block]:offsets[m.block + 1]] for m in self.partial]
        counts = np.array([len(p) for p in spring_points], dtype=np.int64)
        self.pc_initial = (np.concatenate(spring_points) if spring_points
                           else np.zeros((0, 2)))
        self.pc_block = np.repeat(np.array([m.block for m in self.partial], dtype=np.int64),
                                  counts)
        self.pc_motion = np.repeat(np.arange(len(self.partial)), counts)
        self.pc_mask = np.array([m.displacement.mask for m in self.partial],
                                dtype=float).reshape(-1, 2)[self.pc_motion]
        self.pc_penalty = np.array([m.penalty or self.constraint_penalty
                                    for m in self.partial]).reshape(-1)[self.pc_motion]
        self.state = _Committed(
            time=0.0, x=x0.copy(), velocity=vel, stress=np.zeros((nb, 3)),
            rotation=np.zeros(nb), contacts=ContactSet.empty(fields), load_points=loads,
            spring_points=self.pc_initial.copy(),
            known_u=np.zeros((nb, 2)), last_move=0.0, centroid=ints.centroid.copy(),
        )
        self._steps_done = 0
        self._contact_cuts = 0  # steps cut because the contacts would not settle
        self._warned: set[str] = set()  # the penalty warnings given (each once)
        self._search_hint = 0.0
        self._dt_now = self.dt
        self._good_steps = 0
        self._resume_end = None  # the end of an interrupted run (set by resume)
        self._last_writer = None  # the writer of the last frame written, and its time
        self._last_written_time = None
        self._resume_checkpoint = None

    # ------------------------------------------------------------------ helpers
    def _joint_index(self, bj, bk):
        key = np.minimum(bj, bk) * self.n_blocks + np.maximum(bj, bk)
        out = np.full(len(key), self.default_joint, dtype=np.int64)
        if len(self.pair_keys):
            pos = np.clip(np.searchsorted(self.pair_keys, key), 0, len(self.pair_keys) - 1)
            hit = self.pair_keys[pos] == key
            out[hit] = self.pair_joint[pos[hit]]
        return out

    def _deepest_penetration(self) -> float:
        """Deepest penetration of the committed closed contacts (m): soft penalties let
        contacts sink further than a fixed limit, and a closed contact must never be lost."""
        c = self.state.contacts
        closed = c.state != OPEN
        if not closed.any():
            return 0.0
        pn = self.joint_pn[self._joint_index(c.bj[closed], c.bk[closed])]
        return float(np.max(-c.t_n[closed] / pn))

    def _known_motion(self, t1):
        """Known translation at t1 and velocity of every block whose motion is prescribed."""
        u = self.state.known_u.copy()
        v = np.zeros((self.n_blocks, 2))
        for s in self.shakes:
            u[s.block], v[s.block] = s.history.state(t1)
        for m in self.full_motions:
            u[m.block] = m.displacement(t1)
        return u, v

    def _block_forces(self, t1, ints, centroid):
        """Block stiffness, mass, damping and external forces (METHOD.md sections 1 and 2).

        Returns (nb, 6, 6) k, m and c (None without damping) and (nb, 6) f.
        """
        st = self.state
        nb = self.n_blocks
        k = geometry.stiffness_matrices(ints.area, self.elasticity)
        m = geometry.mass_matrices(ints, self.density)
        c = None
        if self.damping is not None:  # C = alpha M + beta K_e, before any penalty spring
            alpha, beta = self.damping
            c = alpha[:, None, None] * m + beta[:, None, None] * k
        f = np.zeros((nb, 6))
        if self.scene.gravity:
            f[:, 1] -= self.scene.gravity * self.density * ints.area
        f[:, 3:] -= ints.area[:, None] * st.stress
        if len(self.load_block):
            forces = self.load_constant.copy()
            for i, history in self.load_varying:  # one user callable per time-varying load
                forces[i] = history(t1)
            t = geometry.t_matrix(st.load_points, centroid[self.load_block])
            np.add.at(f, self.load_block, np.einsum("lij,li->lj", t, forces))
        if len(self.pc_block):
            # penalty springs p T^T T on the constrained directions of each point (METHOD s. 1)
            u = np.array([mo.displacement(t1) for mo in self.partial])[self.pc_motion]
            xv = st.spring_points
            t = geometry.t_matrix(xv, centroid[self.pc_block]) * self.pc_mask[:, :, None]
            target = (self.pc_initial + u - xv) * self.pc_mask
            p = self.pc_penalty
            np.add.at(k, self.pc_block, p[:, None, None] * np.einsum("vij,vik->vjk", t, t))
            np.add.at(f, self.pc_block, p[:, None] * np.einsum("vij,vi->vj", t, target))
        return k, m, c, f

    def _search_distance(self, dt, centroid, known_du):
        st = self.state
        t = geometry.t_matrix(st.x, centroid[self.topo.block])
        vv = np.einsum("vij,vj->vi", t, st.velocity[self.topo.block] * self.velocity_carry)
        predicted = np.max(np.hypot(vv[:, 0], vv[:, 1])) * dt if len(vv) else 0.0
        predicted += 0.5 * abs(self.scene.gravity) * dt * dt
        if len(known_du):
            predicted = max(predicted, float(np.max(np.hypot(known_du[:, 0], known_du[:, 1]))))
        floor = 1e-6 * float(np.min(self.size))
        return SEARCH_FACTOR * max(predicted, st.last_move, self._search_hint) + floor

    # ------------------------------------------------------------------ one step
    def _try_step(self, dt):
        """Build the step's problem from the committed state and solve it (no commit)."""
        st = self.state
        t1 = st.time + dt
        ints = geometry.polygon_integrals(st.x, self.offsets, self.topo.nxt)
        centroid = ints.centroid
        k, m, c, f = self._block_forces(t1, ints, centroid)
        # a static analysis carries no velocity: no inertial force term
        v_eff = st.velocity * self.velocity_carry if self.velocity_carry else None
        k_eff, f_eff = effective_system(k, m, f, v_eff, dt, c)

        known_u, known_v = self._known_motion(t1)
        d_known = np.zeros((self.n_blocks, 6))
        d_known[:, :2] = known_u - st.known_u
        d_known[self.free] = 0.0

        d0 = self._search_distance(dt, centroid, d_known[~self.free, :2])
        # how deep behind an edge a vertex is still taken for a contact: twice the deepest
        # vertex of the committed state (found by the guard, tracked or not) plus the
        # search distance; detection takes a negative gap only for a vertex inside the
        # edge's block, so no far edge of a thin block is taken for a contact
        pen_limit = max(2.0 * d0, 1e-3 * float(np.min(self.size)),
                        2.0 * max(self._deepest_penetration(), st.penetration) + d0)
        if self.n_blocks > 1:
            with section("detection"):
                # a vertex sunk deeper than a quarter of the guard's tolerance is held by
                # the edge nearest to it, and two such corners get a spring each
                sunk = 0.25 * self.penetration_tolerance * float(np.min(self.thickness))
                pairs = self._pairs(st.x, max(d0, pen_limit))
                cand = narrow_phase(st.x, self.topo, d0, pen_limit, pairs, sunk)
                contacts, fresh, geom = carry_over(st.contacts, cand, st.x, self.topo.nxt,
                                                   self.topo.prv, self.n_blocks)
        else:  # a single block: nothing to detect
            pairs = np.zeros((0, 2), dtype=np.int64)
            cand = CandidateContacts(*(np.zeros(0, dtype=np.int64) for _ in range(4)))
            contacts, fresh, geom = carry_over(st.contacts, cand, st.x, self.topo.nxt,
                                               self.topo.prv, self.n_blocks)
        joint = self._joint_index(contacts.bj, contacts.bk)
        if np.any(joint < 0):
            i = int(np.flatnonzero(joint < 0)[0])
            raise SimulationError(
                f"no joint between {self.scene.blocks[contacts.bj[i]]} and "
                f"{self.scene.blocks[contacts.bk[i]]}; set a default joint"
            )
        laws = LawGroups.build(self.joint_law[joint], self.laws)
        laws.initial_history(contacts.history, fresh)
        element = ContactElement(contacts, st.x, centroid, self.topo.nxt, self.topo.prv,
                                 self.joint_pn[joint], self.joint_ps[joint], laws, geom)
        problem = StepProblem(dt=dt, block_k=k_eff, block_f=f_eff, free=self.free,
                              d_known=d_known, element=element,
                              max_open_close=self.max_open_close, rigid=self.rigid)
        sol = self.solver.solve_step(problem)
        sol.unknowns = problem.pattern.unknowns
        sol.pairs = cand.pairs
        if not sol.converged:
            return None, sol
        d = sol.d
        move = geometry.vertex_displacements(st.x, centroid[self.topo.block], d[self.topo.block])
        distance = np.hypot(move[:, 0], move[:, 1])
        largest = float(np.max(distance))
        # two blocks closing on each other close their gap by up to twice the largest move:
        # a vertex that moved more than half the search distance may have met an edge that
        # was not searched
        if 2.0 * largest > d0:
            sol.converged = False
            sol.reason = (f"a vertex moved {largest:.3g} m, more than half the contact search "
                          f"distance {d0:.3g} m")
            sol.search_hint = 2.0 * largest
            return None, sol
        per_block = np.zeros(self.n_blocks)
        np.maximum.at(per_block, self.topo.block, distance)
        ratio = np.where(self.free, per_block / self.size, 0.0)
        worst = int(np.argmax(ratio))
        if ratio[worst] > self.max_displacement_ratio:
            sol.converged = False
            sol.reason = (f"{self.scene.blocks[worst]} moved {per_block[worst]:.3g} m in one "
                          f"step, more than max_displacement_ratio {self.max_displacement_ratio:g}"
                          f" of its size {self.size[worst]:.3g} m")
            return None, sol
        x_new = st.x + move
        with section("guard"):
            # no vertex moved farther than d0 (checked above), so the pairs whose boxes
            # overlap at the end of the step are among the detection's, grown by d0
            refused = self._guard(x_new, sol, self.joint_pn[joint], pairs)
        if refused:
            sol.converged = False
            sol.reason = refused
            return None, sol
        vel = np.where(self.free[:, None], updated_velocity(d, v_eff, dt), 0.0)
        if self.rigid is not None:
            vel[self.rigid, 3:] = 0.0
        vel[~self.free, :2] = known_v[~self.free]
        for mo in self.full_motions:
            vel[mo.block, :2] = d_known[mo.block, :2] / dt
        stress = st.stress + np.where(
            self.free[:, None], np.einsum("bij,bj->bi", self.elasticity, d[:, 3:]), 0.0
        )
        load_points = st.load_points
        if len(self.load_block):
            load_points = load_points + geometry.vertex_displacements(
                load_points, centroid[self.load_block], d[self.load_block])
        spring_points = st.spring_points
        if len(self.pc_block):
            spring_points = spring_points + geometry.vertex_displacements(
                spring_points, centroid[self.pc_block], d[self.pc_block])
        new = _Committed(
            time=t1, x=x_new, velocity=vel, stress=stress,
            rotation=st.rotation + d[:, 2], contacts=sol.contacts, load_points=load_points,
            spring_points=spring_points,
            known_u=known_u, last_move=largest, untracked=sol.untracked,
            penetration=sol.penetration,
            # a step maps each block affinely, which carries its centroid by (u0, v0)
            centroid=centroid + d[:, :2],
        )
        return new, sol

    def _advise_on_penalty(self):
        """Warn once (:class:`dda.penalty_advice.PenaltyWarning`) when the committed springs
        sink too deep for their penalty, and once when the steps keep being cut because the
        contacts would not settle (a penalty too stiff for the step size)."""
        if "soft" not in self._warned:
            c = self.state.contacts
            closed = np.flatnonzero(c.state != OPEN)
            if len(closed):
                pn = self.joint_pn[self._joint_index(c.bj[closed], c.bk[closed])]
                depth = -c.t_n[closed] / pn
                half = np.minimum(self.thickness[c.bj[closed]], self.thickness[c.bk[closed]])
                if np.any(depth > SOFT_DEPTH * half):
                    names = [f"{self.scene.blocks[j]} on {self.scene.blocks[k]}"
                             for j, k in zip(c.bj[closed], c.bk[closed], strict=True)]
                    message = soft_penalty_advice(depth, half, pn, names)
                    if message:
                        self._warned.add("soft")
                        warnings.warn(message, PenaltyWarning, stacklevel=4)
        if ("stiff" not in self._warned and self._contact_cuts >= STIFF_CUTS
                and self._contact_cuts >= STIFF_SHARE * self._steps_done and self.free.any()):
            mass = self.density * self.size**2  # the blocks' masses at the start
            light = int(np.flatnonzero(self.free)[np.argmin(mass[self.free])])
            message = stiff_penalty_advice(self._contact_cuts, self._steps_done,
                                           float(self.joint_pn.max()), float(mass[light]),
                                           self.dt, str(self.scene.blocks[light]))
            if message:
                self._warned.add("stiff")
                warnings.warn(message, PenaltyWarning, stacklevel=4)

    def _pairs(self, x, margin) -> np.ndarray:
        """Block pairs whose boxes, grown by ``margin``, overlap, less those of two blocks
        whose motion is known (fixed, shaken, moved): a contact between them acts on no
        unknown, and its spring (two fixed blocks built touching or overlapping) would only
        hold fictitious energy."""
        pairs = broad_phase(bounding_boxes(x, self.offsets), margin)
        return pairs[self.free[pairs[:, 0]] | self.free[pairs[:, 1]]]

    def _guard(self, x_new, sol, normal_penalty, pairs) -> str:
        """The penetration guard on a step's trial: '' when every vertex inside another block
        is held by a closed contact at its depth, else why the step is refused.

        Sets ``sol.penetration`` (the deepest vertex inside another block, m) and
        ``sol.spring_penetration`` (the deepest closed spring, m).
        """
        if self.n_blocks < 2:
            return ""
        pen = vertex_penetrations(x_new, self.topo, pairs=pairs)
        c = sol.contacts
        closed = c.state != OPEN
        sol.penetration = pen.deepest
        sol.spring_penetration = float(np.max(-c.t_n[closed] / normal_penalty[closed],
                                              initial=0.0))
        if len(pen) == 0:
            return ""
        tol = self.penetration_tolerance * np.minimum(
            self.thickness[self.topo.block[pen.vertex]], self.thickness[pen.block])
        ratio = untracked_depth(pen, c, normal_penalty, self.topo) / tol
        sol.untracked = float(np.max(ratio))
        bad = ratio > 1.0
        if not bad.any():
            return ""
        i = int(np.argmax(ratio))
        v = int(pen.vertex[i])
        j = int(self.topo.block[v])
        k = int(pen.block[i])
        local = v - int(self.offsets[j])
        return (f"untracked penetration: vertex {local} of {self.scene.blocks[j]} "
                f"(at {x_new[v, 0]:.6g}, {x_new[v, 1]:.6g}) is {pen.depth[i]:.3g} m inside "
                f"{self.scene.blocks[k]}, and no closed contact holds it "
                f"(tolerance {tol[i]:.3g} m)")

    def _snapshots(self):
        return [s.history.snapshot() for s in self.shakes]

    def _restore(self, snaps):
        for s, snap in zip(self.shakes, snaps, strict=True):
            s.history.restore(snap)

    # ------------------------------------------------------------------ run
    def run(self, duration: float | None = None, output=None, progress: bool | None = None,
            checkpoint=None, checkpoint_every: int = 100) -> Result:
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
            File to keep the run's state in, written (atomically) every ``checkpoint_every``
            steps, when the run is interrupted (Ctrl-C, SIGTERM) and at its end;
            :meth:`resume` goes on from it. The scene must be picklable: its callables
            module-level functions, not lambdas. A resumed simulation keeps writing to the
            file it came from unless given another.
        checkpoint_every : int
            Steps between checkpoints.

        Returns
        -------
        Result
            The recorded steps of this run, starting with the state it started from.

        Raises
        ------
        SimulationError
            When a step cannot be made to converge even with a much smaller dt; its
            ``result`` holds the steps done before (and the writer has written them).
        KeyboardInterrupt
            On Ctrl-C or SIGTERM, after the steps done are written and checkpointed.
        """
        if duration is None:
            if self._resume_end is None:
                raise ValueError("Simulation.run: give the duration (only a simulation from "
                                 "Simulation.resume may leave it out)")
            duration = self._resume_end - self.state.time
            if duration <= 1e-12 * max(1.0, self._resume_end):
                raise ValueError(f"Simulation.run: the resumed run already ended at t = "
                                 f"{self._resume_end:g} s; give a duration to go on")
        duration = finite_number("duration", duration, positive=True, where="run")
        if checkpoint is None and self._resume_checkpoint is not None:
            checkpoint, checkpoint_every = self._resume_checkpoint
        if checkpoint is not None:
            checkpoint = Path(checkpoint)
            if int(checkpoint_every) < 1:
                raise ValueError("Simulation.run: checkpoint_every must be at least 1, got "
                                 f"{checkpoint_every!r}")
            checkpoint_every = int(checkpoint_every)
            checkpoint.parent.mkdir(parents=True, exist_ok=True)
        t_end = self.state.time + duration
        for s in self.shakes:
            s.history.check_covers(t_end)
        writer = output if output is not None else self.output
        if checkpoint is not None:
            self._checkpoint_payload(writer, t_end, checkpoint, checkpoint_every)  # picklable?
        n_steps = int(np.ceil(duration / self.dt - 1e-9))
        if progress is None:
            progress = n_steps > 2000 and sys.stderr.isatty()
        bar = _Progress(t_end, self.state.time) if progress else None
        result = Result(self.scene, [b.name for b in self.scene.blocks])
        self._record(result, writer)
        since_record = 0
        previous_term = _raise_on_sigterm()
        try:
            while self.state.time < t_end - 1e-12 * max(1.0, t_end):
                self._advance(result, t_end)
                since_record += 1
                last = self.state.time >= t_end - 1e-12 * max(1.0, t_end)
                if since_record >= self.record_every or last:
                    self._record(result, writer)
                    since_record = 0
                if checkpoint is not None and (self._steps_done % checkpoint_every == 0
                                               or last):
                    self.save_checkpoint(checkpoint, writer, t_end, checkpoint_every)
                if bar:
                    bar.update(self.state.time)
        except SimulationError as exc:
            exc.result = result
            raise
        except KeyboardInterrupt:
            if checkpoint is not None:  # the committed state is whole: keep it
                self.save_checkpoint(checkpoint, writer, t_end, checkpoint_every)
            raise
        finally:
            if previous_term is not None:
                signal.signal(signal.SIGTERM, previous_term[0])
            if bar:
                bar.close()
            if writer is not None:
                writer.close()
        return result

    # ------------------------------------------------------------------ checkpoints
    def _checkpoint_payload(self, writer, t_end, path, every) -> bytes:
        data = {"version": CHECKPOINT_VERSION, "simulation": self, "writer": writer,
                "end": t_end, "checkpoint": (str(path), every)}
        try:
            return pickle.dumps(data, protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as exc:  # pickle raises several types for what it cannot save
            raise ValueError(
                f"Simulation.run: checkpoint cannot save this simulation ({exc}); give the "
                "scene module-level functions instead of lambdas or local functions (for "
                "shaking, loads and prescribed motions), or a recorded accelerogram"
            ) from None

    def save_checkpoint(self, path, writer=None, end: float | None = None,
                        every: int = 100) -> None:
        """Write the committed state, the step control and the writer to ``path``.

        The file is written to a temporary name first and then renamed, so an interruption
        never leaves a half-written checkpoint. ``end`` is the time the run was to reach.
        """
        path = Path(path)
        payload = self._checkpoint_payload(writer, self.state.time if end is None else end,
                                           path, every)
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_bytes(payload)
        os.replace(tmp, path)

    @classmethod
    def resume(cls, path) -> Simulation:
        """The simulation kept in a checkpoint file of :meth:`run`, ready to go on.

        ``Simulation.resume(path).run()`` finishes the interrupted run: same steps, same
        numbers as a run that was never interrupted, and the same writer goes on numbering its
        files where the checkpoint left it. Only resume files you wrote yourself: a
        checkpoint is a pickle.
        """
        path = Path(path)
        if not path.is_file():
            raise ValueError(f"Simulation.resume: no checkpoint file {path}")
        try:
            data = pickle.loads(path.read_bytes())
        except Exception as exc:
            raise ValueError(f"Simulation.resume: {path} is not a readable checkpoint "
                             f"({type(exc).__name__}: {exc})") from None
        if not isinstance(data, dict) or data.get("version") != CHECKPOINT_VERSION:
            raise ValueError(f"Simulation.resume: {path} is not a checkpoint of this version "
                             f"of dda (layout {CHECKPOINT_VERSION})")
        sim = data["simulation"]
        sim.output = data["writer"]
        sim._resume_end = data["end"]
        sim._resume_checkpoint = data["checkpoint"]
        return sim

    def _advance(self, result, t_end):
        """Take one step, cutting dt as often as needed; commit it and log its stats."""
        tries = 0
        widened = 0
        profile = StepProfile()
        start = _time.perf_counter()
        while True:
            remaining = t_end - self.state.time
            dt = min(self._dt_now, remaining)
            if remaining - dt < 1e-6 * dt:
                dt = remaining  # no sliver of a step left over at the end
            snaps = self._snapshots()
            try:
                with profile.active():
                    new, sol = self._try_step(dt)
            except BaseException:  # an interrupt mid-step: leave the committed state whole
                self._restore(snaps)
                raise
            if new is not None:
                break
            self._restore(snaps)
            tries += 1
            hint = sol.search_hint
            if hint > self._search_hint and widened < MAX_WIDENINGS:
                # the step moved farther than predicted: search wider and try it again
                self._search_hint = hint
                widened += 1
                continue
            result.stats.cuts.append((self.state.time, dt, sol.reason))
            if contact_cut(sol.reason):
                self._contact_cuts += 1
            self._dt_now = dt / 2.0
            self._good_steps = 0
            if sol.untracked > 1.0 and self.state.untracked > 0.5:
                # the vertex is already half the tolerance in, untracked, at the start of the
                # step: any step that moves it on is refused, and smaller ones only creep
                raise SimulationError(
                    f"the run cannot go on at t = {self.state.time:.6g} s: {sol.reason}; it "
                    f"was already {self.state.untracked:.2g} tolerances deep, untracked, at the "
                    "start of the step, so a smaller dt cannot help (contact detection missed "
                    "it: please report the scene)"
                )
            if tries > MAX_CUTS:
                raise SimulationError(
                    f"the run cannot go on at t = {self.state.time:.6g} s: {sol.reason} "
                    f"(step cut {tries} times down to dt = {dt:.3g} s)"
                )
        self.state = new
        self._search_hint = 0.0
        self._steps_done += 1
        self._advise_on_penalty()
        self._good_steps += 1
        if self._dt_now < self.dt and self._good_steps >= GROW_AFTER:
            self._dt_now = min(self.dt, 2.0 * self._dt_now)
            self._good_steps = 0
        c = new.contacts
        result.stats.append(
            time=new.time, dt=dt, iterations=sol.iterations,
            open_close_passes=sol.open_close_passes, contacts=len(c),
            closed=int(np.count_nonzero(c.state != OPEN)),
            sliding=int(np.count_nonzero(c.state == SLIP)), retries=tries,
            wall_time=_time.perf_counter() - start, solves=profile.solves,
            unknowns=sol.unknowns, pairs=sol.pairs, penetration=sol.penetration,
            spring_penetration=sol.spring_penetration,
            residual_norms=sol.residual_norms,
            **{f"{name}_time": sec for name, sec in profile.seconds.items()},
        )

    # ------------------------------------------------------------------ recording
    def energy(self):
        """The mechanical energy of the committed state (:func:`dda.energy.energy`)."""
        from dda.energy import energy

        return energy(self)

    def frame(self) -> Frame:
        """The committed state as a :class:`dda.result.Frame`."""
        st = self.state
        ints = geometry.polygon_integrals(st.x, self.offsets, self.topo.nxt)
        blk = self.topo.block
        t = geometry.t_matrix(st.x, ints.centroid[blk])
        vv = np.einsum("vij,vj->vi", t, st.velocity[blk])
        c = st.contacts
        closed = c.state != OPEN
        if len(c):
            g = contact_geometry(st.x, c.vertex, c.edge, self.topo.nxt)
            point, normal = g.p1, g.normal
        else:
            point = normal = np.zeros((0, 2))
        return Frame(
            time=st.time, vertices=st.x.copy(), offsets=self.offsets,
            vertex_displacement=st.x - self.x_initial, vertex_velocity=vv,
            displacement=ints.centroid - self.centroid_initial, velocity=st.velocity.copy(),
            rotation=st.rotation.copy(), stress=st.stress.copy(),
            contact_point=point[closed], contact_normal=normal[closed],
            contact_blocks=np.stack([c.bj, c.bk], axis=1)[closed],
            normal_force=-c.t_n[closed], shear_force=c.t_s[closed],
            contact_state=c.state[closed].astype(np.int64),
        )

    def _pair_forces(self):
        """Per block pair: key, total force on the higher-index block, weighted normal."""
        c = self.state.contacts
        closed = np.flatnonzero(c.state != OPEN)
        if len(closed) == 0:
            return np.zeros(0, dtype=np.int64), np.zeros((0, 2)), np.zeros((0, 2))
        g = contact_geometry(self.state.x, c.vertex[closed], c.edge[closed], self.topo.nxt)
        bj, bk = c.bj[closed], c.bk[closed]
        t_n, t_s = c.t_n[closed], c.t_s[closed]
        on_j = -(t_n[:, None] * g.normal + t_s[:, None] * g.tau)
        j_high = bj > bk
        sign = np.where(j_high, 1.0, -1.0)[:, None]
        force = sign * on_j
        normal = sign * g.normal * np.abs(t_n)[:, None]
        key = np.minimum(bj, bk) * self.n_blocks + np.maximum(bj, bk)
        keys, inv = np.unique(key, return_inverse=True)
        f = np.zeros((len(keys), 2))
        n = np.zeros((len(keys), 2))
        np.add.at(f, inv, force)
        np.add.at(n, inv, normal)
        return keys, f, n

    def _record(self, result, writer):
        st = self.state
        keys, f, n = self._pair_forces()
        # the result needs block centroids only; a full Frame is built when a writer asks
        result.record(st.time, st.centroid - self.centroid_initial, st.rotation, st.velocity,
                      st.stress, keys, f, n)
        if writer is None:
            return
        # a run that goes on, or resumes, starts at the writer's last frame: not twice
        last = getattr(writer, "last_time", None)
        if last is None and writer is self._last_writer:
            last = self._last_written_time
        if last != st.time:
            writer.write(self.frame())
            result.frames_written += 1
            self._last_writer, self._last_written_time = writer, st.time


def _raise_on_sigterm():
    """Turn SIGTERM into KeyboardInterrupt for the run (main thread only).

    Returns ``(old handler,)`` to restore, or None off the main thread.
    """
    if threading.current_thread() is not threading.main_thread():
        return None

    def interrupt(signum, frame):
        raise KeyboardInterrupt(f"signal {signum}")

    return (signal.signal(signal.SIGTERM, interrupt),)


class _Progress:
    """A minimal progress bar on stderr (no dependency)."""

    def __init__(self, t_end, t_start):
        self.t_end, self.t_start = t_end, t_start
        self.start = _time.perf_counter()
        self.last = 0.0

    def update(self, t):
        now = _time.perf_counter()
        if now - self.last < 0.2 and t < self.t_end:
            return
        self.last = now
        frac = (t - self.t_start) / (self.t_end - self.t_start)
        bar = "#" * int(30 * frac)
        eta = (now - self.start) * (1 - frac) / max(frac, 1e-9)
        sys.stderr.write(f"\r  t = {t:9.4f} s [{bar:<30}] {100 * frac:5.1f}%  eta {eta:6.1f} s")
        sys.stderr.flush()

    def close(self):
        sys.stderr.write("\n")
        sys.stderr.flush()
