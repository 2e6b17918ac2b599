"""Run a scene step by step and watch the stability invariants of issue 7."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda import geometry
from dda.contact.detection import bounding_boxes, broad_phase
from dda.contact.penetration import released_depth, untracked_depth, vertex_penetrations
from dda.energy import WorkLedger, energy
from dda.step import deepest_spring


@dataclass
class Watched:
    steps: int
    energy0: float
    energy_peak: float  # largest total energy minus the work put in
    scale: float  # the energy the scene can set free (energy_scale)
    work: float
    penetration: float  # deepest penetration seen after any step (m)
    smallest: float  # smallest block dimension (m)
    cuts: int
    sim: object
    # the largest excess, over the steps, of a vertex inside another block (found
    # geometrically) over the closed springs that hold it, and the guard's default tolerance
    untracked: float = 0.0
    tolerance: float = np.inf

    @property
    def energy_gain(self) -> float:
        """Largest energy gain over the start, relative to the energy the scene can set free."""
        return (self.energy_peak - self.energy0) / self.scale


def smallest_dimension(sim) -> float:
    """Smallest width of any block: over its edges, the largest distance of a vertex from the
    edge's line, and the least of those (convex blocks)."""
    x, offsets = sim.state.x, sim.model.offsets
    widths = []
    for b in range(sim.model.n_blocks):  # once per run, not per step
        p = x[offsets[b]:offsets[b + 1]]
        e = np.roll(p, -1, axis=0) - p
        n = np.stack([-e[:, 1], e[:, 0]], axis=1) / np.linalg.norm(e, axis=1)[:, None]
        dist = np.abs(np.einsum("ekj,ej->ek", p[None, :, :] - p[:, None, :], n))
        widths.append(float(dist.max(axis=1).min()))
    return min(widths)


def untracked(sim) -> float:
    """How much deeper than the closed springs that hold it the deepest vertex inside another
    block is (m). The vertices inside are found geometrically (contact detection is not
    asked): of a free block inside another block, or of any block inside a free one."""
    x, offsets = sim.state.x, sim.model.offsets
    pairs = broad_phase(bounding_boxes(x, offsets), 0.0)
    pairs = pairs[sim.model.free[pairs[:, 0]] | sim.model.free[pairs[:, 1]]]
    pen = vertex_penetrations(x, sim.model.topo, pairs=pairs)
    c = sim.state.contacts
    model = sim.model
    joint = model.joint_index(c.bj, c.bk)
    pn = model.joints.normal_penalty[joint] if len(c) else np.zeros(0)
    # an open contact that its impact dashpot let go with the vertex still inside holds it
    # at its gap until the vertex is out
    zeta = model.joints.damping_ratio
    released = (None if zeta is None or not len(c) else
                released_depth(x, c, model.topo, zeta[joint] > 0.0))
    return float(np.max(untracked_depth(pen, c, pn, sim.model.topo, released), initial=0.0))


def guard_tolerance(sim) -> float:
    """1 % of the thinnest block's half-width 2 area / perimeter (the guard's default)."""
    return 0.01 * float(np.min(sim.model.thickness))


def energy_scale(sim) -> float:
    """The energy a scene can set free: its kinetic energy plus the potential energy of every
    block above the scene's lowest point."""
    e = sim.energy()
    ints = geometry.polygon_integrals(sim.state.x, sim.model.offsets)
    g = sim.scene.gravity or 0.0
    drop = ints.centroid[:, 1] - sim.state.x[:, 1].min()
    return e.kinetic + float(np.sum(g * sim.model.density * ints.area * drop * sim.model.free))


def watch(sim, duration: float, work=None, chunk: int = 1) -> Watched:
    """Run ``sim`` for ``duration`` and check the state after every ``chunk`` steps.

    ``work(sim)`` is the work put in since the start (J/m), for scenes with loads. Raises
    AssertionError at the first non-finite state.
    """
    e0 = sim.energy().total
    peak = e0
    pen = 0.0
    cuts = steps = 0
    t_end = sim.state.time + duration
    smallest = smallest_dimension(sim)
    scale = energy_scale(sim)
    done = 0.0
    excess = 0.0
    while sim.state.time < t_end - 1e-9:
        span = min(chunk * sim.dt, t_end - sim.state.time)
        result = sim.run(span)
        steps += len(result.stats.time)
        cuts += len(result.stats.cuts)
        st = sim.state
        for name in ("x", "velocity", "stress"):
            assert np.all(np.isfinite(getattr(st, name))), f"{name} not finite at {st.time}"
        assert np.all(np.isfinite(st.contacts.t_n)) and np.all(np.isfinite(st.contacts.t_s))
        done = work(sim) if work is not None else 0.0
        peak = max(peak, sim.energy().total - done)
        pen = max(pen, deepest_spring(sim.model, sim.committed.contacts))
        excess = max(excess, untracked(sim))
    return Watched(steps, e0, peak, scale, done, pen, smallest, cuts, sim, excess,
                   guard_tolerance(sim))


def assert_stable(w: Watched):
    """The invariants: finite (checked while running); energy never above the start plus the
    work put in, by more than 1 % of the energy the scene can set free; penetration below 1 %
    of the smallest block dimension."""
    assert w.energy_gain <= 0.01, (
        f"energy rose by {w.energy_peak - w.energy0:.4g} J/m ({100 * w.energy_gain:.2f} % of "
        f"{w.scale:.4g})")
    assert w.penetration < 0.01 * w.smallest, (
        f"penetration {w.penetration:.3g} m, smallest block {w.smallest:.3g} m")
    assert_tracked(w)


def assert_tracked(w: Watched):
    """After every step no vertex inside another block is deeper than the closed springs that
    hold it, give or take the guard's default tolerance (of the thinnest block)."""
    assert w.untracked <= w.tolerance, (
        f"a vertex {w.untracked:.3g} m deeper inside another block than any closed spring "
        f"(tolerance {w.tolerance:.3g} m)")


class KnownMotionWork:
    """Work put into the free blocks by the blocks whose motion is known (shaken, moved).

    :class:`dda.energy.WorkLedger`'s ``work_known`` (the contact force each known block
    pushes the free blocks with, trapezoidal over each step, dotted with its displacement),
    plus the change of the known blocks' own kinetic and potential energy, which
    ``sim.energy()`` counts but nothing inside the scene pays for. ``watch(sim, T,
    work=KnownMotionWork(sim), chunk=1)`` then checks that the energy never rises above the
    start plus this work.
    """

    def __init__(self, sim):
        self.ledger = WorkLedger(sim)
        self.own0 = self._own_energy(sim)

    @staticmethod
    def _own_energy(sim):
        """The known blocks' own energy: all of it less the free blocks'."""
        return sim.energy().total - energy(sim, free_only=True).total

    def __call__(self, sim) -> float:
        self.ledger(sim.committed)
        return self.ledger.work_known + self._own_energy(sim) - self.own0
