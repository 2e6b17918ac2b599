"""The mechanical energy of a committed state: a stability check for long and hard runs.

The energy of the blocks (METHOD.md section 1) and of the contact springs (section 4):

    kinetic    0.5 v^T M v per block (v the six velocities, M = rho int T^T T dA)
    potential  rho g A y_c per block (from y = 0)
    strain     0.5 A sigma^T D^-1 sigma per block
    contact    0.5 t_n^2 / p_n + 0.5 t_s^2 / p_s per closed contact
    bolt       0.5 N^2 / k per intact bolt (:mod:`dda.bolts`; a break releases it)
    water      int_A p dA over the free blocks, p the water pressure
               (:func:`dda.water.water_energy`: the buoyancy's potential)

Friction and Newmark's gamma = 1 only take energy out, so a run without loads, shaking or
prescribed motion must never end with more than it started with (``tests/stability``); the
water's pressure, a fixed field, is no exception: its work is the fall of its potential. The
exception is a block whose area changes: its weight and mass follow its current area.
Compressed by deep water it gains energy: a 1 m cube (E 1 GPa, density 1,500) sinking 650 m
in 20 s gained 32.5 kJ/m, its strain energy, whatever dt, and 1/E of it (329 J/m at E 1e11).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda import geometry
from dda.bolts import bolt_energy
from dda.contact.contacts import OPEN
from dda.water import water_energy

__all__ = ["Energy", "WorkLedger", "energy"]


@dataclass(frozen=True)
class Energy:
    """Energy per unit thickness (J/m) of one committed state, by kind."""

    kinetic: float
    potential: float
    strain: float
    contact: float
    bolt: float = 0.0
    water: float = 0.0

    @property
    def total(self) -> float:
        return (self.kinetic + self.potential + self.strain + self.contact + self.bolt
                + self.water)


def energy(sim, state=None, free_only: bool = False) -> Energy:
    """The energy of a committed state (see the module docstring).

    ``sim`` is a :class:`dda.Simulation` (its committed state), or a :class:`dda.model.Model`
    with ``state`` the :class:`dda.step.StepState` to measure.

    Fixed and shaken blocks count too: their kinetic energy is that of the prescribed motion.
    With ``free_only`` only the blocks with unknowns count (their springs, bolts and water
    too): the energy an energy balance under shaking follows (:class:`WorkLedger`), without
    the table's own motion and weight, which nothing in the scene pays for.

    Examples
    --------
    >>> import dda
    >>> from dda.materials import LinearElastic
    >>> scene = dda.Scene(gravity=10.0)
    >>> b = scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)],
    ...                     LinearElastic(young=1e9, poisson=0.2, density=1000.0))
    >>> sim = dda.Simulation(scene, dt=0.01)
    >>> _ = sim.run(0.1)
    >>> e = sim.energy()  # a free fall turns potential energy into kinetic energy
    >>> round(e.kinetic + e.potential, 6), round(e.potential, 1)
    (5000.0, 4500.0)
    """
    model = getattr(sim, "model", sim)
    if state is None and not hasattr(sim, "committed"):
        raise TypeError("energy(model, state): give the state to measure with a Model")
    st = sim.committed if state is None else state
    ints = geometry.polygon_integrals(st.x, model.offsets)
    mass = geometry.mass_matrices(ints, model.density)
    counted = model.free if free_only else np.ones(model.n_blocks, dtype=bool)
    v = np.where(counted[:, None], st.velocity, 0.0)
    kinetic = 0.5 * float(np.einsum("bi,bij,bj->", v, mass, v))
    g = model.gravity or 0.0
    # from y = 0 of the scene's coordinates: about the model's origin, plus the constant
    # of each block's mass at the origin's height (a far scene's area, which strain
    # changes, times its y of 4e6 m made energy that never was)
    potential = float(np.sum(counted * g * model.density * ints.area * ints.centroid[:, 1]))
    origin_y = float(model.origin[1])
    if origin_y:
        potential += float(np.sum(counted * g * model.density * model.size**2)) * origin_y
    compliance = np.linalg.inv(model.elasticity)
    strain = 0.5 * float(np.einsum("b,bi,bij,bj->", ints.area * counted, st.stress,
                                   compliance, st.stress))
    c = st.contacts
    closed = c.state != OPEN
    contact = 0.0
    if closed.any():
        joint = model.joint_index(c.bj[closed], c.bk[closed])
        contact = 0.5 * float(np.sum(c.t_n[closed] ** 2 / model.joints.normal_penalty[joint]
                                     + c.t_s[closed] ** 2 / model.joints.shear_penalty[joint]))
    bolt = bolt_energy(model.bolts, st.bolt_points, st.bolt_broken)
    water = 0.0
    if model.water is not None:
        water = water_energy(model.water, st.x, model.topo.nxt, model.water_edges)
    return Energy(kinetic, potential, strain, contact, bolt, water)


class WorkLedger:
    """An energy balance of a run: the work put into the free blocks, and what was lost.

    The free blocks' energy (:func:`energy` with ``free_only``) changes by the work done on
    them from outside,

        E_free(t) - E_free(0) = W_known + W_loads - D,

    ``W_known`` the work of the blocks whose motion is known (a shaking table, a moved block)
    through their contacts, step by step the contact springs' force each pushes the free
    blocks with at the step's end (as the implicit step applies it) dotted with its
    displacement; ``W_loads`` the work of the point loads, each step's force at its end dotted
    with its point's displacement; and ``D`` what friction, the dashpots, damping and
    Newmark's gamma = 1 took out. With the joints' dashpots off ``D`` never falls below zero;
    with them on, their force on the known blocks is not counted (a table moved 2 mm up by
    ``prescribe_motion``: D dipped to -2.8 to -3.7 J/m against 23 J/m put in, a review of
    2026-12-07). Not counted either: bolts anchored in a block whose motion is known, and
    the springs of a partial prescribed motion.

    Pass it as the run's ``callback`` (it is called after every committed step)::

        ledger = WorkLedger(sim)
        sim.run(10.0, callback=ledger)
        ledger.work_known, ledger.work_loads, ledger.dissipated()

    Parameters
    ----------
    sim : dda.Simulation
        Measured from its committed state when the ledger is made; a simulation that is to
        start settled (``start="settled"``) and has not yet is settled first
        (:meth:`dda.Simulation.settle`), so that the settle's own work is not counted.
    """

    def __init__(self, sim):
        if sim.settle_pending:
            sim.settle()
        from dda.recorder import pair_forces  # noqa: PLC0415 (the recorder imports much)

        self._pair_forces = pair_forces
        self.model = sim.model
        self.known = ~self.model.free
        self.work_known = 0.0
        self.work_loads = 0.0
        self.start = energy(self.model, sim.committed, free_only=True)
        self._u = sim.committed.known_u.copy()
        self._points = sim.committed.load_points.copy()
        self.now = self.start

    def _known_forces(self, state) -> np.ndarray:
        """(n_blocks, 2) the contact force each known block pushes the free blocks with."""
        keys, f, _ = self._pair_forces(self.model, state)
        nb = self.model.n_blocks
        lo, hi = keys // nb, keys % nb
        out = np.zeros((nb, 2))
        m = self.known[lo] & ~self.known[hi]  # f: the force on the higher-index block
        np.add.at(out, lo[m], f[m])
        m = self.known[hi] & ~self.known[lo]
        np.add.at(out, hi[m], -f[m])
        return out

    def __call__(self, state, report=None) -> None:
        model = self.model
        force, u = self._known_forces(state), state.known_u
        self.work_known += float(np.sum(force * (u - self._u)))
        self._u = u.copy()
        if len(model.load_block):
            loads = model.load_constant.copy()
            for i, history in model.load_varying:
                loads[i] = history(state.time)
            self.work_loads += float(np.sum(loads * (state.load_points - self._points)))
            self._points = state.load_points.copy()
        self.now = energy(model, state, free_only=True)

    def dissipated(self) -> float:
        """``D = W_known + W_loads - (E_free(now) - E_free(start))`` (J/m)."""
        return self.work_known + self.work_loads - (self.now.total - self.start.total)
