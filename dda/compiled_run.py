"""Runs of small steps in one kernel call (:mod:`dda.kernels.run_steps`), for
:meth:`dda.Simulation.run`.

A 2-block step of ``benchmarks/small_step.py`` costs some 30 us in its kernels and 150 us of
Python around them. Where nothing in a run needs Python between two steps, a
:class:`StepRuns` hands a batch of steps to :func:`dda.kernels.run_steps.run_steps` and writes
back what the steps would have written one by one: the committed state, the stats rows, the
recorded steps and the step control's counts. The steps are the same to the bit as those
:func:`dda.step.step` takes (``tests/test_compiled_run.py``).

A batch is tried when the run has no callback (it sees every step) and no writer but a
:class:`dda.io.VTUWriter` that thins its series (a batch stops at each step whose frame it
writes; and before each step after which the run writes its checkpoint, which the run takes
the usual way), the scene's blocks are plain (:attr:`dda.model.Model.plain_blocks`; a known
motion is worked out for the batch's steps first), no bolts, a dynamic analysis, the step
control at its full dt with no search hint, and the step one :func:`dda.step.step` takes in
one kernel call (:func:`dda.step.contact_step_arguments`). A batch stops before a step that
needs anything else (a refused step, a slip reversal to locate, the run's last step) and the
run takes that step the usual way; after a batch that took no step, the next try waits 1, 2,
4 ... 64 steps.

In the stats a batch's steps share its wall time evenly, all of it under ``solve_time``.
"""

from __future__ import annotations

import sys
import time as _time
from dataclasses import replace
from types import SimpleNamespace

import numpy as np

from dda import recorder as recorder_module
from dda import slip_events
from dda import step as step_module
from dda.contact.contacts import ContactSet
from dda.io.vtu import VTUWriter
from dda.kernels.run_steps import FRAME, ROW_FIELDS, STEPS_DONE, run_steps
from dda.kernels.small_step import contact_step
from dda.penalty_advice import SOFT_DEPTH, STIFF_CUTS
from dda.profiling import SECTIONS
from dda.solvers.linear import DENSE_LIMIT

__all__ = ["COMPILED_RUN", "StepRuns"]

#: take runs of small steps in one kernel call (False: every step through dda.step.step)
COMPILED_RUN = True

#: the steps of the first batch, and the most of one (a batch that took all its steps in
#: under ``BATCH_SECONDS`` is doubled: Ctrl-C and the progress bar wait for the end of a
#: batch; one that a step stopped gives the next twice its steps)
FIRST_BATCH, MOST_BATCH, BATCH_SECONDS = 64, 2048, 0.05
#: the fewest steps a batch is given after one that a step stopped
MIN_BATCH = 16
#: the longest wait (Python steps) before a batch is tried again after one that took none
MOST_WAIT = 64

_SOLVE = SECTIONS.index("solve")
_STEP = step_module.step
_ROW = {name: i for i, name in enumerate(ROW_FIELDS)}


class StepRuns:
    """The batches of one :meth:`dda.Simulation.run` (module docstring).

    Parameters
    ----------
    sim : dda.Simulation
    result : the run's :class:`dda.result.Result`
    recorder : the run's :class:`dda.recorder.Recorder`
    checkpoint_every : the run's ``checkpoint_every`` when it writes checkpoints, else None
    """

    def __init__(self, sim, result, recorder, checkpoint_every: int | None = None):
        self.sim, self.result, self.recorder = sim, result, recorder
        self.checkpoint_every = checkpoint_every
        self.size = FIRST_BATCH
        self.wait = 0  # Python steps before the next try
        self.misses = 0  # batches in a row that took no step

    @staticmethod
    def possible(sim, writer, callback) -> bool:
        """Whether a run of ``sim`` with these may take batches at all."""
        model = sim.model
        # (a batch stands for dda.step.step and its one kernel call: a run whose step or
        # kernel is wrapped, to watch or change each step, takes every step that way)
        simulation = sys.modules["dda.simulation"]
        # (a series of every step: a frame, in Python, after each step)
        thinned = writer is None or type(writer) is VTUWriter and (
            writer.every > 1 or writer.interval is not None or sim.record_every > 1)
        return (COMPILED_RUN and thinned and callback is None
                and simulation.step is _STEP and step_module.contact_step is contact_step
                and step_module.BLOCK_KERNELS and step_module.SMALL_STEP
                and model.plain_blocks and model.bolts is None
                and sim.velocity_carry > 0.0 and model.n_blocks > 1
                # (a sparse system is never the one-call step's; and the pattern a try
                # would build replaces the one its solver keeps, and its analysis)
                and 6 * int(np.count_nonzero(model.free)) <= DENSE_LIMIT)

    def advance(self, t_end: float, bar=None) -> int:
        """Take a batch of steps towards ``t_end`` if it may: the steps taken (0: the run
        takes its next step the usual way)."""
        if self.wait > 0:
            self.wait -= 1
            return 0
        room = self._room()
        if room == 0:  # the next step writes the checkpoint: the run's to take (no miss)
            return 0
        steps, why = self._batch(t_end, bar, room)
        if steps == 0:
            self.misses += 1
            self.wait = min(MOST_WAIT, 2 ** (self.misses - 1))
        else:
            self.misses = 0
            if why != STEPS_DONE:  # the next step is the run's to take
                self.wait = 1
        return steps

    def _room(self) -> int:
        """The most steps a batch may take before the step after which the run writes its
        checkpoint (every ``checkpoint_every`` accepted steps)."""
        every = self.checkpoint_every
        if every is None:
            return MOST_BATCH
        return every - 1 - self.sim.control.steps % every

    def _batch(self, t_end, bar, room=MOST_BATCH):
        sim = self.sim
        model, control, advisor = sim.model, sim.control, sim.advisor
        dt = control.dt
        if not (control.dt_now == dt and not control.probing and control.search_hint == 0.0
                and ("stiff" in advisor.warned or control.contact_cuts < STIFF_CUTS)):
            return 0, STEPS_DONE
        state = sim.committed
        writing = self._writer_arguments(state)
        if writing is None:
            return 0, STEPS_DONE
        settings = sim.settings
        carry = settings.velocity_carry
        # the first step's arguments as dda.step.step makes them (the kernel makes each
        # step's own again)
        ints, k_eff, f_eff, v_eff, speed = step_module._plain_start(model, state, dt, carry)
        known = (state.known_u, None, np.zeros((model.n_blocks, 6)), state.shaking)
        d0 = step_module.search_distance(model, state, dt, carry, ints.centroid,
                                         step_module._NO_MOVES, 0.0, speed)
        arguments = step_module.contact_step_arguments(model, state, dt, sim.solver, settings,
                                                       d0, ints, k_eff, f_eff, v_eff, known)
        if arguments is None:
            return 0, STEPS_DONE
        args, pattern, has_sliding = arguments
        gravity = float(model.gravity or 0.0)
        free = model.free
        start = _time.perf_counter()
        # whole steps of dt, none the run's last or a checkpoint's, and no more than reach
        # the writer's next frame (the known motion of a step the batch does not take is
        # work lost)
        size = _whole_steps(control, state.time, t_end,
                            min(self.size, room, self._steps_to_frame(writing, state.time, dt)))
        if size == 0:
            return 0, STEPS_DONE
        motions = _known_motions(model, state, dt, size) if model.moves_known else None
        (steps, why, t, x, velocity, stress, rotation, centroid, c_state, rows, last_move,
         untracked, penetration, wait, since, stats, norms, n_norms, records, rec_time,
         rec_disp, rec_rot, rec_vel, rec_stress, pair_at, pair_keys, pair_force,
         pair_normal) = run_steps(
            size, state.velocity,
            state.centroid, float(state.last_move), float(state.untracked), float(state.time),
            gravity, float(carry), 2.0 / dt**2, 2.0 / dt, 0.5 * abs(gravity) * dt * dt,
            1e-6 * model.min_size, float(step_module.SEARCH_FACTOR),
            bool(sim.locate_reversals and sim.velocity_carry > 0.0), int(control.reversal_wait),
            float(slip_events.MIN_FRACTION), float(slip_events.NORMAL_RATIO),
            np.where(free, carry, 1.0), "soft" not in advisor.warned,
            SOFT_DEPTH * model.min_thickness * float(model.joints.normal_penalty.min()),
            int(self.recorder.every), int(self.recorder.since), model.centroid_initial,
            model.rigid is not None, bool(has_sliding), int(getattr(sim.solver, "max_iter", 1))
            + 8, motions is not None, *(_NO_MOTION if motions is None else motions[1:4]),
            _full_blocks(model), *writing, *args)
        wall = _time.perf_counter() - start
        if steps == 0:
            return 0, why
        if wall > BATCH_SECONDS:
            self.size = max(MIN_BATCH, self.size // 2)
        elif steps == size and why == STEPS_DONE:
            self.size = min(MOST_BATCH, 2 * self.size)
        elif why != FRAME:  # (stopped by a step: as long again, and more)
            self.size = max(MIN_BATCH, min(self.size, 2 * steps))
        c = state.contacts
        history = {"g_se": rows[3], "slip": rows[4]}
        if has_sliding:
            history["sliding"] = rows[5]
        moved = {} if motions is None else {"known_u": motions[0][steps - 1].copy(),
                                             "shaking": motions[4][steps - 1]}
        sim.committed = replace(
            state, **moved, time=float(t), x=x, velocity=velocity, stress=stress, rotation=rotation,
            centroid=centroid, contacts=ContactSet(c.vertex, c.edge, c.bj, c.bk, c_state,
                                                   rows[0], rows[1], rows[2], history,
                                                   rows[6].astype(np.int64)),
            last_move=float(last_move), untracked=float(untracked),
            penetration=float(penetration))
        self._stats(stats, norms, n_norms, steps, dt, wall, pattern.unknowns, args[0])
        self._records(records, rec_time, rec_disp, rec_rot, rec_vel, rec_stress, pair_at,
                      pair_keys, pair_force, pair_normal)
        self.recorder.since = int(since)
        self._frames(rec_time, why)
        control.steps += steps
        control.good_steps += steps
        control.tried_untracked = -1.0
        control.reversal_wait = int(wait)
        # (a no-op but where the last step failed the quick test for soft springs)
        advisor.observe(sim.committed, control.steps, control.contact_cuts)
        if bar is not None:
            bar(sim.committed, SimpleNamespace(
                open_close_passes=int(stats[:, _ROW["open_close_passes"]].sum())), steps=steps)
        return steps, why

    def _writer_arguments(self, state):
        """The kernel's ``(writer_mode, frames_to_due, due_after)`` for the run's writer, or
        None when a batch may not take the next step (the writer has a frame after the
        committed state: a resumed run's)."""
        writer = self.recorder.writer
        if writer is None:
            return 0, 0, 0.0
        last = writer.last_time
        if last is None and writer is self.recorder.written[0]:
            last = self.recorder.written[1]
        if last is not None and not last <= state.time:
            return None
        if writer.interval is None:
            return 1, int(writer.frames_to_due()), 0.0
        return 2, 0, float(writer.due_after())

    def _steps_to_frame(self, writing, time, dt) -> int:
        """The steps from ``time`` to the one whose record the writer takes next, at most
        MOST_BATCH (writing: :meth:`_writer_arguments`)."""
        mode, frames_to_due, due_after = writing
        if mode == 0:
            return MOST_BATCH
        to_record = self.recorder.every - self.recorder.since
        if mode == 1:
            return min(MOST_BATCH, to_record + frames_to_due * self.recorder.every)
        steps = 0
        while steps < MOST_BATCH:
            steps += 1
            time = time + dt
            if steps >= to_record and (steps - to_record) % self.recorder.every == 0 and (
                    time >= due_after):
                break
        return steps

    def _frames(self, rec_time, why):
        """The writer's part of the batch's records (Recorder._record's): the frame of the
        last step when it was due, the others counted as skipped."""
        writer = self.recorder.writer
        if writer is None:
            return
        n = len(rec_time)
        for r in range(n):
            if r == n - 1 and why == FRAME:
                writer.write(recorder_module.frame(self.sim.model, self.sim.committed))
            else:
                writer.skip(float(rec_time[r]))
                self.recorder._skipped = float(rec_time[r])  # (Recorder.stop writes it)
            self.result.frames_written += 1

    def _stats(self, stats, norms, n_norms, steps, dt, wall, unknowns, newton):
        """The batch's rows in :class:`dda.result.StepStats` (Simulation._advance's)."""
        share = wall / steps
        sections = [0.0] * len(SECTIONS)
        sections[_SOLVE] = share
        self.result.stats.batched += steps
        append = self.result.stats.append_row
        for i, row in enumerate(stats.tolist()):
            (t, iterations, passes, contacts, closed, sliding, solves, pairs, pen,
             spring) = row
            append((t, dt, int(iterations), int(passes), int(contacts), int(closed),
                    int(sliding), 0, share, int(solves), unknowns, int(pairs), pen, spring,
                    *sections),
                   norms[i, :n_norms[i]].tolist() if newton else [])

    def _records(self, records, rec_time, rec_disp, rec_rot, rec_vel, rec_stress, pair_at,
                 pair_keys, pair_force, pair_normal):
        """The batch's recorded steps in the run's :class:`dda.result.Result`."""
        record = self.result.record
        for r in range(len(records)):
            a, b = pair_at[r], pair_at[r + 1]
            record(rec_time[r], rec_disp[r], rec_rot[r], rec_vel[r], rec_stress[r],
                   pair_keys[a:b].copy(), pair_force[a:b].copy(), pair_normal[a:b].copy())


_NO_MOTION = (np.zeros((1, 1, 6)), np.zeros((1, 1, 2)), np.zeros(1))


def _full_blocks(model) -> np.ndarray:
    """The blocks moved in full (:attr:`dda.model.Model.full_motions`), in their order."""
    kept = model.__dict__.get("_full_blocks")
    if kept is None:
        kept = model.__dict__["_full_blocks"] = np.array(
            [m.block for m in model.full_motions], dtype=np.int64)
    return kept


def _whole_steps(control, time, t_end, most) -> int:
    """How many of the next steps from ``time`` (at most ``most``) the step control gives the
    whole dt (:meth:`dda.step_control.StepControl.step_size`), none of them the run's last
    (Simulation._steps' end test): the steps a batch may take."""
    guard = t_end - 1e-12 * max(1.0, t_end)
    dt = control.dt
    steps = 0
    while steps < most and control.step_size(t_end - time) == dt and time + dt < guard:
        time = time + dt
        steps += 1
    return steps


def _known_motions(model, state, dt, steps):
    """The known motion of each of the next ``steps`` steps from ``state``: ``(known_u,
    d_known, known_v, largest known move, shaking)``, each indexed by step, as
    :func:`dda.step.step` works them out one step at a time
    (:meth:`dda.model.Model.known_motion`), to the same bits: the shaken blocks' histories
    over all the steps at once (:meth:`dda.effects.AccelerationHistory.advance_many`)."""
    free = model.free
    times = np.empty(steps)
    t = state.time
    for k in range(steps):  # (the times as the steps reach them: t + dt, one by one)
        t = t + dt
        times[k] = t
    us = np.repeat(state.known_u[None], steps, axis=0)
    vs = np.zeros((steps, model.n_blocks, 2))
    histories = []
    for s, start in zip(model.shakes, state.shaking, strict=True):
        u, v, after = s.history.advance_many(start, times)
        us[:, s.block], vs[:, s.block] = u, v
        histories.append(after)
    for m in model.full_motions:
        for k, t in enumerate(times.tolist()):
            us[k, m.block] = m.displacement(t)
    ds = np.zeros((steps, model.n_blocks, 6))
    ds[:, :, :2] = np.diff(us, axis=0, prepend=state.known_u[None])
    ds[:, free] = 0.0
    known = ds[:, ~free, :2]
    most = (np.hypot(known[..., 0], known[..., 1]).max(axis=1) if known.shape[1]
            else np.zeros(steps))
    shakings = _Shakings(histories)
    return us, ds, vs, most, shakings


class _Shakings:
    """``shakings[k]``: the state's ``shaking`` after the k-th step of a batch."""

    def __init__(self, histories):
        self.histories = histories

    def __getitem__(self, k: int) -> tuple:
        return tuple(h[k] for h in self.histories)
