"""The energy of a committed state (dda.energy)."""

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.energy import energy
from dda.materials import LinearElastic
from tests.conftest import box


def test_a_resting_block_stores_its_weight_in_the_contact_springs():
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(-1, -0.5, 2, 0.5), rock, fixed=True)
    scene.add_block(box(0, 0, 0.4, 0.2), rock)
    pn = 1e8
    scene.set_joint(JointMaterial(normal_penalty=pn, shear_penalty=pn,
                                  friction=CoulombSingle(phi=30.0)))
    sim = dda.Simulation(scene, dt=1e-3)
    start = sim.energy()
    sim.run(0.5)
    e = sim.energy()
    weight = 0.4 * 0.2 * 2500.0 * 9.81
    # two corner springs share the weight: 2 x (W/2)^2 / (2 p_n)
    assert e.contact == pytest.approx(weight**2 / (4 * pn), rel=0.02)
    assert e.kinetic < 1e-3 * e.contact
    assert 0 < e.strain < 0.1 * e.contact
    # the block sank by at least W / (2 p_n); the springs hold at most half of what it lost
    assert start.potential - e.potential >= 2 * e.contact
    assert e.total < start.total


def _table_block(shake=True, **joint):
    """A 1 x 0.5 m block (1,250 kg/m) on a table shaken at 1 g, 2 Hz (it slides)."""
    rock = LinearElastic(young=1e10, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    table = scene.add_block([(0, 0), (4, 0), (4, 0.5), (0, 0.5)], rock, fixed=True,
                            name="table")
    scene.add_block([(1.5, 0.5), (2.5, 0.5), (2.5, 1.0), (1.5, 1.0)], rock, name="block")
    scene.set_joint(JointMaterial(1e10, 1e10, CoulombSingle(phi=30.0), **joint))
    if shake:
        scene.shake(table, acceleration=lambda t: (9.81 * np.sin(2 * np.pi * 2.0 * t), 0.0))
    return scene


@pytest.mark.parametrize("solver", ["legacy", "newton"])
def test_the_work_ledger_balances_a_block_sliding_on_a_shaken_table(solver):
    """The table's work less the block's gain is what friction took: mu m g times the slip
    path, to Newmark's gamma = 1 damping (first order in dt: 1.3% at 1e-3 s, 0.32% at
    2.5e-4 s), with the dashpots off. ``energy().total`` could not be balanced: it counts
    the table's own motion and weight (an earthquake engineer's review)."""
    from dda.energy import WorkLedger

    sim = dda.Simulation(_table_block(restitution=1.0, shear_dashpot=False), dt=2.5e-4,
                         solver=solver)
    ledger = WorkLedger(sim)
    lost = []

    def step(state, report):
        ledger(state, report)
        lost.append(ledger.dissipated())

    result = sim.run(1.0, callback=step, progress=False)
    slip = result.displacement("block")[:, 0] - result.displacement("table")[:, 0]
    friction = np.tan(np.radians(30.0)) * 1250.0 * 9.81 * np.abs(np.diff(slip)).sum()
    assert ledger.work_loads == 0.0 and ledger.work_known > 1000.0
    assert ledger.dissipated() == pytest.approx(friction, rel=0.006)
    # nothing comes out of nowhere (with the table's force averaged over each step instead
    # of its end's, as the step applies it, D dipped to -2e-5 of the work)
    assert min(lost) > -1e-9 * ledger.work_known
    # the free blocks' energy leaves the table out: its kinetic energy and weight
    whole, free = sim.energy(), energy(sim, free_only=True)
    block_v = sim.committed.velocity[1]
    assert free.kinetic == pytest.approx(0.5 * 1250.0 * (block_v[0] ** 2 + block_v[1] ** 2),
                                         rel=1e-3)
    assert whole.potential - free.potential == pytest.approx(
        2500.0 * 2.0 * 9.81 * (0.25 + result.displacement("table")[-1, 1]), rel=1e-9)


def test_the_work_ledger_counts_a_point_loads_work():
    """A block pushed along a frictionless floor by 1 kN from rest: the load's work is its
    kinetic energy, F x, to the dashpots' and gamma = 1's small share."""
    from dda.energy import WorkLedger

    scene = _table_block(shake=False)
    scene.set_joint(JointMaterial(1e10, 1e10, CoulombSingle(phi=0.0), restitution=1.0,
                                  shear_dashpot=False))
    scene.add_point_load("block", point=(2.0, 0.75), force=(1000.0, 0.0))
    sim = dda.Simulation(scene, dt=1e-3)
    ledger = WorkLedger(sim)
    result = sim.run(0.5, callback=ledger, progress=False)
    x = result.displacement("block")[-1, 0]
    assert ledger.work_loads == pytest.approx(1000.0 * x, rel=1e-9)
    assert x == pytest.approx(0.5 * 0.8 * 0.5**2, rel=1e-3)  # a = F / m = 0.8 m/s^2
    assert 0.0 <= ledger.dissipated() < 1e-2 * ledger.work_loads
