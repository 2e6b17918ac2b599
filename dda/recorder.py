"""Recording a run: the result's rows and the writer's frames, from committed states only.

The numerics never record; :class:`dda.Simulation` hands each committed
:class:`dda.step.StepState` to a :class:`Recorder`, which keeps every ``every``-th one (and
the last) in the :class:`dda.result.Result` and passes it, as a :class:`dda.result.Frame`, to
the writer.
"""

from __future__ import annotations

import numpy as np

from dda import geometry
from dda.contact.contacts import OPEN
from dda.contact.kinematics import contact_geometry
from dda.kernels.forces import pair_force_sums
from dda.kernels.open_close import as_float64
from dda.result import Frame

__all__ = ["Recorder", "frame", "pair_forces"]


def frame(model, state) -> Frame:
    """A committed state as a :class:`dda.result.Frame` (what a writer writes)."""
    ints = geometry.polygon_integrals(state.x, model.offsets, model.topo.nxt)
    blk = model.topo.block
    t = geometry.t_matrix(state.x, ints.centroid[blk])
    vv = np.einsum("vij,vj->vi", t, state.velocity[blk])
    c = state.contacts
    closed = c.state != OPEN
    if len(c):
        g = contact_geometry(state.x, c.vertex, c.edge, model.topo.nxt)
        point, normal = g.p1, g.normal
    else:
        point = normal = np.zeros((0, 2))
    origin = model.origin
    shift = origin.any()  # back to the scene's coordinates
    if shift:
        point = point + origin
    return Frame(
        time=state.time, vertices=state.x + origin if shift else state.x.copy(),
        offsets=model.offsets,
        vertex_displacement=state.x - model.x_initial, vertex_velocity=vv,
        displacement=ints.centroid - model.centroid_initial, velocity=state.velocity.copy(),
        rotation=state.rotation.copy(), stress=state.stress.copy(),
        contact_point=point[closed], contact_normal=normal[closed],
        contact_blocks=np.stack([c.bj, c.bk], axis=1)[closed],
        normal_force=-c.t_n[closed], shear_force=c.t_s[closed],
        contact_state=c.state[closed].astype(np.int64),
        block_names=tuple(b.name for b in model.scene.blocks),
        shaken=np.array([s.block for s in model.shakes], dtype=np.int64),
        **_bolt_fields(model, state, origin if shift else None),
    )


def _bolt_fields(model, state, origin=None) -> dict:
    """The bolts' fields of a :class:`dda.result.Frame` (none in a scene without bolts)."""
    if model.bolts is None:
        return {}
    points = state.bolt_points + origin if origin is not None else state.bolt_points.copy()
    return {"bolt_points": points, "bolt_force": state.bolt_forces(model),
            "bolt_broken": state.bolt_broken.copy()}


def pair_forces(model, state):
    """Per block pair with closed contacts: its :func:`dda.contact.contacts.pair_key`, the
    total force on the higher-index block, and the normal weighted by the normal forces."""
    c = state.contacts
    # the contacted edges' frames as contact_geometry has them (P2 = next(e), P3 = e),
    # summed per pair in compiled code (dda.kernels.forces), which picks the closed contacts
    return pair_force_sums(as_float64(state.x), model.topo.nxt, c.state, c.edge, c.bj, c.bk,
                           as_float64(c.t_n), as_float64(c.t_s), model.n_blocks)


class Recorder:
    """Keeps every ``every``-th committed state of a run (and the last) and writes it.

    Parameters
    ----------
    model : dda.model.Model
    result : dda.result.Result that receives the rows
    writer : optional writer (``write(frame)``, ``close()``, optionally ``last_time``, and
        ``due(time)`` with ``skip(time)``: a frame the writer says is not due is not built,
        only counted, as :class:`dda.io.VTUWriter` thins a series; and ``write_extra(frame)``
        for a frame beside ``every``'s cadence, which a writer that thins must not count;
        a writer that thins without it gets ``write(frame, last=True)``)
    every : record every this many steps
    written : ``(writer, time)`` of the last frame written by an earlier run of the same
        simulation: a run that goes on starts at that frame and must not write it twice
    since : committed steps since the last one recorded by an earlier run that stopped
        before its end (or a checkpoint's): a run that goes on keeps the cadence of one
        never stopped
    """

    def __init__(self, model, result, writer=None, every: int = 1, written=(None, None),
                 since: int = 0):
        self.model, self.result, self.writer, self.every = model, result, writer, every
        self.written = written
        self.since = int(since) % every

    def start(self, state) -> None:
        """Record the state a run starts from (beside the cadence when a run goes on from a
        step between recorded ones)."""
        self._record(state, extra=self.since != 0)

    def committed(self, state, last: bool) -> None:
        """A step was committed; record it when it is the ``every``-th or the ``last``."""
        self.since += 1
        if self.since >= self.every:
            self._record(state, end=last)
            self.since = 0
        elif last:  # the run's end, recorded beside the cadence, which a run after keeps
            self._record(state, end=True, extra=True)

    def stop(self, state) -> None:
        """The run stopped before its end (interrupted, or a step that could not go on): its
        last committed state is recorded and written, as a run's end is (a thinned series of
        a stopped run ended up to ``every`` - 1 frames short of where it stopped)."""
        times = self.result.time
        if not len(times) or times[-1] != state.time:
            self._record(state, end=True, extra=True)
        elif self.__dict__.get("_skipped") == state.time:  # recorded, but its frame skipped
            self.writer.write(frame(self.model, state), last=True)
            self.written = (self.writer, state.time)

    def _record(self, state, end=False, extra=False):
        """Record ``state``: a row, and a frame for the writer. ``end``: a run's end (a
        thinned series ends there); ``extra``: beside ``every``'s cadence (a run's end or
        stop between recorded steps, or the start of a run that goes on from one), a frame
        a writer with ``write_extra`` writes without counting it in its own thinning."""
        keys, f, n = pair_forces(self.model, state)
        # the result needs block centroids only; a full Frame is built when a writer asks
        self.result.record(state.time, state.centroid - self.model.centroid_initial,
                           state.rotation, state.velocity, state.stress, keys, f, n)
        if self.model.bolts is not None:
            self.result.record_bolts(state.bolt_forces(self.model), state.bolt_broken)
        writer = self.writer
        if writer is None:
            return
        written = getattr(writer, "last_time", None)
        if written is None and writer is self.written[0]:
            written = self.written[1]
        if written != state.time:
            # a series thinned by its writer (VTUWriter's every, interval) ends at the
            # run's end (a writer that does not thin takes write(frame) alone)
            thinned = (getattr(writer, "every", 1) > 1
                       or getattr(writer, "interval", None) is not None)
            due = getattr(writer, "due", None) if hasattr(writer, "skip") else None
            if extra and hasattr(writer, "write_extra"):
                writer.write_extra(frame(self.model, state))
            elif (end or extra) and thinned:
                if not extra and due is not None and not due(state.time):
                    writer.skip(state.time)  # a frame of the cadence: counted as it comes
                writer.write(frame(self.model, state), last=True)
            elif extra:
                writer.write(frame(self.model, state))
            elif due is None or due(state.time):
                writer.write(frame(self.model, state))
            else:  # (a frame the writer would not write: not built)
                writer.skip(state.time)
                self._skipped = state.time
            self.result.frames_written += 1
            self.written = (writer, state.time)
