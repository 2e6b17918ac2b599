"""A step computes only the effects its scene calls for (issue 8, item 1)."""

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial, StaticDynamicTransition
from dda.materials import LinearElastic
from dda.solvers import LegacyPullBack, NewtonRaphson
from dda.solvers.newmark import effective_system, updated_velocity
from tests.conftest import box, incline_scene

SOLVERS = [LegacyPullBack(), NewtonRaphson()]
IDS = ["legacy", "newton"]
ROCK = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
JOINT = JointMaterial(normal_penalty=1e9, shear_penalty=1e9, friction=CoulombSingle(phi=30.0))


def test_a_lone_block_does_no_detection_work():
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 1, 1), ROCK)
    stats = dda.Simulation(scene, dt=1e-3).run(0.02).stats
    assert len(stats) == 20
    assert np.all(stats.pairs == 0) and np.all(stats.contacts == 0)
    assert np.all(stats.detection_time == 0.0)
    assert np.all(stats.contact_element_time == 0.0) and np.all(stats.return_map_time == 0.0)


def test_blocks_far_apart_hand_no_pair_to_the_narrow_phase():
    scene = dda.Scene(gravity=9.81)
    for i in range(5):
        scene.add_block(box(3.0 * i, 0, 1, 1), ROCK)
    scene.set_joint(JOINT)
    stats = dda.Simulation(scene, dt=1e-3).run(0.02).stats
    assert np.all(stats.pairs == 0) and np.all(stats.contacts == 0)
    assert np.all(stats.return_map_time == 0.0)


def test_touching_blocks_are_pairs():
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 3, 1), ROCK, fixed=True)
    scene.add_block(box(1, 1, 1, 1), ROCK)
    scene.set_joint(JOINT)
    stats = dda.Simulation(scene, dt=1e-3).run(0.005).stats
    assert np.all(stats.pairs == 1) and np.all(stats.contacts == 2)


@pytest.mark.parametrize("solver", SOLVERS, ids=IDS)
def test_ninety_fixed_of_a_hundred_blocks_solve_ten(solver):
    # a 10 x 10 grid of pedestals: the top row is free, the other 90 blocks are fixed
    scene = dda.Scene(gravity=9.81)
    free = []
    for row in range(10):
        for col in range(10):
            b = scene.add_block(box(1.2 * col, row, 1.0, 1.0), ROCK, fixed=row < 9)
            if row == 9:
                free.append(b)
    scene.set_joint(JOINT)
    result = dda.Simulation(scene, dt=1e-3, solver=solver).run(0.02)
    assert np.all(result.stats.unknowns == 60)
    # the ten free blocks do not touch each other: each moves as one block on one pedestal
    alone = dda.Scene(gravity=9.81)
    alone.add_block(box(0, 8, 1, 1), ROCK, fixed=True)
    one = alone.add_block(box(0, 9, 1, 1), ROCK)
    alone.set_joint(JOINT)
    single = dda.Simulation(alone, dt=1e-3, solver=solver).run(0.02)
    assert np.all(single.stats.unknowns == 6)
    expected = single.displacement(one)
    assert np.abs(expected[:, 1]).max() > 1e-6  # it settles into its joint
    for b in free:
        np.testing.assert_allclose(result.displacement(b), expected, rtol=1e-6, atol=1e-12)


def test_fixed_and_shaken_blocks_have_no_unknowns():
    scene = dda.Scene(gravity=9.81)
    base = scene.add_block(box(0, 0, 3, 1), ROCK, fixed=True)
    scene.add_block(box(1, 1, 1, 1), ROCK)
    scene.add_block(box(1, 2, 1, 1), ROCK, rigid=True)
    scene.shake(base, acceleration=lambda t: (1.0, 0.0))
    scene.set_joint(JOINT)
    result = dda.Simulation(scene, dt=1e-3).run(0.005)
    assert np.all(result.stats.unknowns == 6 + 3)


@pytest.mark.parametrize("solver", SOLVERS, ids=IDS)
def test_rigid_block_slides_down_the_incline_as_the_elastic_one(solver):
    runs = {}
    for rigid in (False, True):
        scene, top, t = incline_scene(phi=20.0, rigid=rigid)
        result = dda.Simulation(scene, dt=1e-3, solver=solver).run(duration=1.0)
        runs[rigid] = (result, result.displacement(top) @ t)
        assert np.all(result.stats.unknowns == (3 if rigid else 6))
    (_, s_elastic), (rigid, s_rigid) = runs[False], runs[True]
    assert s_rigid[-1] == pytest.approx(s_elastic[-1], rel=0.01)
    # and both slide at Coulomb's acceleration, g (sin 30 - cos 30 tan 20), within 2%
    m = rigid.time > 0.3
    accel = -2 * np.polyfit(rigid.time[m], s_rigid[m], 2)[0]
    th, phi = np.radians(30.0), np.radians(20.0)
    assert accel == pytest.approx(9.81 * (np.sin(th) - np.cos(th) * np.tan(phi)), rel=0.02)


@pytest.mark.parametrize("solver", SOLVERS, ids=IDS)
def test_rigid_block_does_not_strain(solver):
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 3, 1), ROCK, fixed=True)
    top = scene.add_block(box(1, 1, 1, 1), ROCK, rigid=True)
    scene.set_joint(JOINT)
    sim = dda.Simulation(scene, dt=1e-3, solver=solver)
    result = sim.run(0.1)
    assert np.all(sim.state.stress[top.index] == 0.0)
    assert np.all(sim.state.velocity[top.index, 3:] == 0.0)
    # it rests on its two corners: the joint carries its weight
    assert result.joint_force(0, top)[-1, 0] == pytest.approx(2500.0 * 9.81, rel=1e-3)
    # the vertices keep their distances (no strain): the square stays a unit square
    x = sim.state.x[4:8]
    sides = np.hypot(*(np.roll(x, -1, axis=0) - x).T)
    np.testing.assert_allclose(sides, 1.0, atol=1e-12)


def test_rigid_must_be_a_bool():
    with pytest.raises(TypeError, match="rigid"):
        dda.Scene().add_block(box(0, 0, 1, 1), ROCK, rigid="yes")


def test_static_step_has_no_inertial_force_term():
    k = np.eye(6)[None] * 2.0
    m = np.eye(6)[None] * 3.0
    f = np.arange(6.0)[None]
    k0, f0 = effective_system(k, m, f, None, 0.1)
    k1, f1 = effective_system(k, m, f, np.zeros((1, 6)), 0.1)
    np.testing.assert_array_equal(k0, k1)
    np.testing.assert_array_equal(f0, f1)
    assert f0 is f  # not even a zero term is computed
    d = np.ones((1, 6))
    np.testing.assert_array_equal(updated_velocity(d, None, 0.1),
                                  updated_velocity(d, np.zeros((1, 6)), 0.1))


def test_no_gravity_no_body_force():
    scene = dda.Scene(gravity=None)
    b = scene.add_block(box(0, 5, 1, 1), ROCK)
    result = dda.Simulation(scene, dt=1e-2).run(0.5)
    assert np.all(result.displacement(b) == 0.0)


def test_friction_history_only_for_the_laws_present():
    scene, top, t = incline_scene(phi=20.0)
    assert set(dda.Simulation(scene, dt=1e-3).model.joints.history_fields) == {"g_se", "slip"}
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=StaticDynamicTransition(30.0, 20.0)))
    fields = dda.Simulation(scene, dt=1e-3).model.joints.history_fields
    assert set(fields) == {"g_se", "slip", "sliding"}
