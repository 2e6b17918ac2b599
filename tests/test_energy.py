"""The energy of a committed state (dda.energy)."""

import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
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
