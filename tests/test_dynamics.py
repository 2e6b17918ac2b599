"""Whole runs against analytical answers: free fall, spin, rest, incline, a column."""

import numpy as np
import pytest

import dda
from dda import geometry
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic
from tests.conftest import box, incline_scene

G = 9.81
SOLVERS = [dda.solvers.LegacyPullBack(), dda.solvers.NewtonRaphson()]
SOLVER_IDS = ["legacy", "newton"]


def test_free_fall_is_exact():
    rock = LinearElastic(young=1e9, poisson=0.2, density=2000.0)
    scene = dda.Scene(gravity=G)
    b = scene.add_block(box(0, 0, 1, 0.5), rock, velocity=(0.3, 1.0))
    result = dda.Simulation(scene, dt=1e-3).run(duration=1.0)
    t = result.time
    d = result.displacement(b)
    np.testing.assert_allclose(d[1:, 1], 1.0 * t[1:] - G * t[1:] ** 2 / 2, rtol=1e-9)
    np.testing.assert_allclose(d[1:, 0], 0.3 * t[1:], rtol=1e-9)
    np.testing.assert_allclose(result.velocity(b)[-1, 1], 1.0 - G * 1.0, rtol=1e-9)


def test_free_spin_keeps_area_and_speed():
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene()
    b = scene.add_block(box(0, 0, 2, 1), rock, angular_velocity=1.0)
    sim = dda.Simulation(scene, dt=1e-2)
    result = sim.run(duration=10.0)
    area = geometry.polygon_integrals(sim.state.x, sim.model.offsets).area[0]
    assert abs(area - 2.0) / 2.0 < 0.005
    assert area == pytest.approx(2.0, rel=1e-9)  # the finite-rotation update is exact
    assert result.rotation(b)[-1] == pytest.approx(10.0, rel=1e-9)
    assert np.abs(result.displacement(b)).max() < 1e-9


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_block_at_rest_on_base(rock, solver):
    scene = dda.Scene(gravity=G)
    base = scene.add_block(box(0, 0, 1, 0.2), rock, fixed=True, name="base")
    top = scene.add_block(box(0.4, 0.2, 0.2, 0.2), rock, name="top")
    scene.set_joint(JointMaterial(normal_penalty=2e9, shear_penalty=2e9,
                                  friction=CoulombSingle(phi=36.4)))
    result = dda.Simulation(scene, dt=1e-3, record_every=100, solver=solver).run(duration=10.0)
    d = result.displacement(top)
    settle = d[len(d) // 10 :]
    assert np.ptp(settle, axis=0).max() < 1e-6  # no drift once settled
    assert np.abs(d).max() < 1e-6
    weight = rock.density * G * 0.2 * 0.2
    force = result.joint_force(base, top)
    assert force[-1, 0] == pytest.approx(weight, rel=1e-3)
    assert abs(force[-1, 1]) < 1e-6 * weight
    assert np.abs(result.rotation(top)).max() < 1e-9


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_incline_stick_holds(solver):
    scene, top, t = incline_scene(phi=40.0)
    result = dda.Simulation(scene, dt=1e-3, solver=solver).run(duration=1.0)
    s = result.displacement(top) @ t
    assert abs(s[-1]) < 2e-5  # the elastic settling of the shear spring only
    late = s[result.time > 0.5]
    assert np.ptp(late) < 1e-7  # no creep


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_incline_slides_at_coulomb_acceleration(solver):
    scene, top, t = incline_scene(phi=20.0)
    result = dda.Simulation(scene, dt=1e-3, solver=solver).run(duration=1.0)
    s = result.displacement(top) @ t
    m = result.time > 0.3
    accel = -2 * np.polyfit(result.time[m], s[m], 2)[0]
    expected = G * (np.sin(np.radians(30)) - np.cos(np.radians(30)) * np.tan(np.radians(20)))
    assert accel == pytest.approx(expected, rel=0.02)


def _column_settlement(k, n, rho, h, young, pn):
    """Static settlement of block k's centroid in a column of n unit-wide blocks of height h.

    Interface i carries the weight of the n - i blocks above it on two vertex springs; block i
    shortens under the mean of its top and bottom stress (uniform strain, plane stress).
    """
    w = rho * G * h
    s = 0.0
    for i in range(k + 1):
        s += (n - i) * w / (2 * pn)
        s += (n - i - 0.5) * w / young * h * (1.0 if i < k else 0.5)
    return s


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_column_of_ten_blocks_stands(rock, solver):
    scene = dda.Scene(gravity=G)
    base = scene.add_block(box(-1, -0.5, 3, 0.5), rock, fixed=True)
    blocks = [scene.add_block(box(0, 0.3 * i, 1, 0.3), rock) for i in range(10)]
    pn = 1e10
    scene.set_joint(JointMaterial(normal_penalty=pn, shear_penalty=pn,
                                  friction=CoulombSingle(phi=30)))
    result = dda.Simulation(scene, dt=2e-3, solver=solver).run(duration=5.0)
    weight = rock.density * G * 0.3 * 10
    for k, b in enumerate(blocks):
        d = result.displacement(b)
        assert np.abs(d[:, 0]).max() < 1e-9
        assert np.abs(result.rotation(b)).max() < 1e-9
        static = _column_settlement(k, 10, rock.density, 0.3, rock.young, pn)
        assert -d[-1, 1] == pytest.approx(static, rel=0.01)
        assert np.abs(d[:, 1]).max() < 2.0 * static  # at most the dynamic overshoot of a step load
        assert np.abs(result.velocity(b)[-1, :3]).max() < 1e-6
    assert result.joint_force(base, blocks[0])[-1, 0] == pytest.approx(weight, rel=1e-3)


def _kinetic_energy(result, block, mass, inertia):
    v = result.velocity(block)
    return 0.5 * mass * (v[:, 0] ** 2 + v[:, 1] ** 2) + 0.5 * inertia * v[:, 2] ** 2


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_sliding_block_stops_at_coulomb_distance_and_stays(rock, solver):
    """v0^2 / (2 mu g): the slip must turn to stick when it would reverse."""
    scene = dda.Scene(gravity=G)
    base = scene.add_block(box(0, 0, 3, 0.2), rock, fixed=True, name="base")
    top = scene.add_block(box(0.2, 0.2, 0.2, 0.1), rock, velocity=(1.0, 0.0), name="top")
    scene.set_joint(JointMaterial(normal_penalty=2e9, shear_penalty=2e9,
                                  friction=CoulombSingle(phi=30)))
    result = dda.Simulation(scene, dt=1e-3, solver=solver).run(duration=0.6)
    mu = np.tan(np.radians(30))
    stop = 1.0**2 / (2 * mu * G)
    x = result.displacement(top)[:, 0]
    assert x[-1] == pytest.approx(stop, rel=0.01)
    after = result.time > 1.0 / (mu * G) + 0.02
    assert np.ptp(x[after]) < 1e-6  # stays stopped: no creep, no reversal
    assert result.joint_force(base, top)[-1, 1] == pytest.approx(0.0, abs=1.0)


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_block_sliding_into_a_wall_gains_no_energy(rock, solver):
    scene = dda.Scene(gravity=G)
    scene.add_block(box(0, 0, 2, 0.2), rock, fixed=True, name="floor")
    scene.add_block(box(0.75, 0.2, 0.1, 0.3), rock, fixed=True, name="wall")
    top = scene.add_block(box(0.5, 0.2, 0.24, 0.13), rock, velocity=(0.5, 0.0), name="top")
    scene.set_joint(JointMaterial(normal_penalty=1e10, shear_penalty=1e10,
                                  friction=CoulombSingle(phi=31.6)))
    result = dda.Simulation(scene, dt=1e-3, solver=solver).run(duration=0.5)
    mass = rock.density * 0.24 * 0.13
    inertia = mass * (0.24**2 + 0.13**2) / 12
    energy = _kinetic_energy(result, top, mass, inertia)
    energy += mass * G * result.displacement(top)[:, 1]
    assert result.displacement(top)[:, 0].max() > 0.0099  # it reached the wall at x = 0.75
    assert energy.max() <= energy[0] * 1.01
    assert np.all(np.isfinite(energy))


def test_static_analysis_settles_the_column_without_overshoot(rock):
    """analysis="static" zeroes the velocity each step: the column creeps into its static
    settlement and never passes it."""
    scene = dda.Scene(gravity=G)
    scene.add_block(box(-1, -0.5, 3, 0.5), rock, fixed=True)
    blocks = [scene.add_block(box(0, 0.3 * i, 1, 0.3), rock) for i in range(10)]
    pn = 1e10
    scene.set_joint(JointMaterial(normal_penalty=pn, shear_penalty=pn,
                                  friction=CoulombSingle(phi=30)))
    result = dda.Simulation(scene, dt=2e-3, analysis="static").run(duration=0.5)
    for k, b in enumerate(blocks):
        d = -result.displacement(b)[:, 1]
        static = _column_settlement(k, 10, rock.density, 0.3, rock.young, pn)
        # the hand formula ignores the lateral restraint of the shear springs (0.3 % stiffer)
        assert d[-1] == pytest.approx(static, rel=1e-2)
        assert d.max() <= d[-1] * (1 + 1e-6)
        # the recorded velocity is the step's creep rate (reset at the next step's start)
        assert np.abs(result.velocity(b)[-1]).max() < 1e-9


@pytest.mark.parametrize("carry", [0.0, 0.5, 0.9])
def test_velocity_carry_ratio_scales_the_velocity_each_step(carry):
    scene = dda.Scene()
    b = scene.add_block(box(0, 0, 1, 1), LinearElastic(young=1e9, poisson=0.2, density=1e3),
                        velocity=(2.0, 0.0))
    result = dda.Simulation(scene, dt=1e-2, velocity_carry=carry).run(duration=0.05)
    # d = dt * carry * v_n and v_{n+1} = 2 d / dt - carry * v_n = carry * v_n
    np.testing.assert_allclose(result.velocity(b)[:, 0], 2.0 * carry ** np.arange(6),
                               rtol=1e-12, atol=1e-15)


def _slide_over(base_top_vertices, rock, solver):
    scene = dda.Scene(gravity=G)
    scene.add_block(base_top_vertices, rock, fixed=True, name="base")
    top = scene.add_block(box(0.2, 0.2, 0.2, 0.1), rock, velocity=(1.0, 0.0), name="top")
    scene.set_joint(JointMaterial(normal_penalty=2e9, shear_penalty=2e9,
                                  friction=CoulombSingle(phi=30)))
    sim = dda.Simulation(scene, dt=1e-3, solver=solver)
    return sim, sim.run(duration=0.3).displacement(top)


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_contact_moves_onto_the_next_edge_with_its_history(rock, solver):
    """A base whose top face is split into collinear edges at x = 0.25 and 0.45 behaves like
    one face: the contacts move onto the next edge and keep their state and shear history."""
    plain = [(0, 0), (3, 0), (3, 0.2), (0, 0.2)]
    split = [(0, 0), (3, 0), (3, 0.2), (0.45, 0.2), (0.25, 0.2), (0, 0.2)]
    sim_plain, d_plain = _slide_over(plain, rock, solver)
    sim_split, d_split = _slide_over(split, rock, solver)
    assert d_split[-1, 0] > 0.06  # both corners (at 0.2 and 0.4) crossed a split
    np.testing.assert_allclose(d_split, d_plain, atol=1e-9)
    assert len(sim_split.state.contacts) == 2


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_soft_penalty_keeps_a_deep_contact(rock, solver):
    """A penalty soft enough to let the block sink 3 mm must not lose the contact."""
    scene = dda.Scene(gravity=G)
    base = scene.add_block(box(0, 0, 1, 0.2), rock, fixed=True)
    top = scene.add_block(box(0.4, 0.2, 0.2, 0.2), rock)
    pn = 1.5e5
    scene.set_joint(JointMaterial(normal_penalty=pn, shear_penalty=pn,
                                  friction=CoulombSingle(phi=30)))
    # static DDA keeps the 2 M / dt^2 term: with a penalty this soft, dt must be large for it
    # to settle in a few steps (2 M / dt^2 = 7e4 N/m here, against 3e5 N/m of springs)
    result = dda.Simulation(scene, dt=0.05, analysis="static", solver=solver).run(2.0)
    weight = rock.density * G * 0.04
    assert result.joint_force(base, top)[-1, 0] == pytest.approx(weight, rel=1e-3)
    sink = weight / (2 * pn)
    assert sink > 2e-3
    assert -result.displacement(top)[-1, 1] == pytest.approx(sink, rel=0.01)


def test_run_ends_exactly_on_the_duration_without_a_sliver_step():
    scene = dda.Scene(gravity=G)
    scene.add_block(box(0, 0, 1, 1), LinearElastic(young=1e9, poisson=0.2, density=1e3))
    # the block falls up to 0.98 m per step: let it, this test is about the step count
    sim = dda.Simulation(scene, dt=0.1, max_displacement_ratio=10.0)
    result = sim.run(duration=0.3)  # 0.1 + 0.1 + 0.1 is 0.30000000000000004 in floats
    result = sim.run(duration=0.7)
    assert result.time[-1] == pytest.approx(1.0, abs=1e-12)
    assert result.stats["dt"].min() > 0.09
