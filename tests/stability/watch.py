"""Run a scene step by step and watch the stability invariants of issue 7."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda import geometry


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

    @property
    def energy_gain(self) -> float:
        """Largest energy gain over the start, relative to the energy the scene can set free."""
        return (self.energy_peak - self.energy0) / self.scale


def smallest_dimension(sim) -> float:
    """Smallest width of any block: over its edges, the largest distance of a vertex from the
    edge's line, and the least of those (convex blocks)."""
    x, offsets = sim.state.x, sim.offsets
    widths = []
    for b in range(sim.n_blocks):  # once per run, not per step
        p = x[offsets[b]:offsets[b + 1]]
        e = np.roll(p, -1, axis=0) - p
        n = np.stack([-e[:, 1], e[:, 0]], axis=1) / np.linalg.norm(e, axis=1)[:, None]
        dist = np.abs(np.einsum("ekj,ej->ek", p[None, :, :] - p[:, None, :], n))
        widths.append(float(dist.max(axis=1).min()))
    return min(widths)


def energy_scale(sim) -> float:
    """The energy a scene can set free: its kinetic energy plus the potential energy of every
    block above the scene's lowest point."""
    e = sim.energy()
    ints = geometry.polygon_integrals(sim.state.x, sim.offsets)
    g = sim.scene.gravity or 0.0
    drop = ints.centroid[:, 1] - sim.state.x[:, 1].min()
    return e.kinetic + float(np.sum(g * sim.density * ints.area * drop * sim.free))


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
        pen = max(pen, sim._deepest_penetration())
    return Watched(steps, e0, peak, scale, done, pen, smallest, cuts, sim)


def assert_stable(w: Watched):
    """The invariants: finite (checked while running); energy never above the start plus the
    work put in, by more than 1 % of the energy the scene can set free; penetration below 1 %
    of the smallest block dimension."""
    assert w.energy_gain <= 0.01, (
        f"energy rose by {w.energy_peak - w.energy0:.4g} J/m ({100 * w.energy_gain:.2f} % of "
        f"{w.scale:.4g})")
    assert w.penetration < 0.01 * w.smallest, (
        f"penetration {w.penetration:.3g} m, smallest block {w.smallest:.3g} m")
