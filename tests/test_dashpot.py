"""The joints' impact dashpot (dda.contact.dashpot): its numbers, and impacts it governs."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.contact.dashpot import contact_mass, damping_ratio
from dda.materials import LinearElastic
from tests.conftest import capture_step_problem


@pytest.mark.parametrize("e", [0.05, 0.3, 0.7, 0.95])
def test_the_damping_ratio_gives_back_the_restitution(e):
    zeta = damping_ratio(e)
    assert 0.0 < zeta < 1.0
    assert math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta**2)) == pytest.approx(e, rel=1e-12)


def test_the_ends_are_no_dashpot_and_critical_damping():
    assert damping_ratio(1.0) == 0.0 and damping_ratio(0.0) == 1.0


@pytest.mark.parametrize("bad", [-0.1, 1.2, float("nan"), "none"])
def test_a_restitution_outside_0_to_1_is_refused(bad):
    with pytest.raises(ValueError, match="restitution"):
        JointMaterial(1e9, 1e9, CoulombSingle(phi=30.0), restitution=bad)


def test_the_contact_mass_of_a_corner_is_its_block_turning_about_its_centroid():
    """A 15 x 45 cm block's corner on a fixed base, the normal vertical: m / (1 + a^2 m / I)
    with a = 0.075 m and I = m (b^2 + h^2) / 12, that is m / 1.3."""
    m, b, h = 145.6, 0.15, 0.45
    inertia = m * (b * b + h * h) / 12.0
    point, normal = np.array([[0.075, -0.225]]), np.array([[0.0, 1.0]])
    got = contact_mass(point, normal, np.zeros((1, 2)), np.array([[0.0, -1.0]]),
                       np.array([m]), np.array([np.inf]), np.array([inertia]),
                       np.array([np.inf]))
    assert got[0] == pytest.approx(m / 1.3, rel=1e-12)


def drop(restitution, dt, solver, penalty=1e8):
    """A 0.2 m square falling flat at 2 m/s onto a fixed floor, no gravity: the vertical
    velocity after the impact over the one before, and the largest kinetic energy over the
    first."""
    rock = LinearElastic(young=1e10, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=0.0)
    scene.add_block([(-1, -0.3), (1, -0.3), (1, 0), (-1, 0)], rock, fixed=True)
    brick = scene.add_block([(-0.1, 1e-3), (0.1, 1e-3), (0.1, 0.201), (-0.1, 0.201)], rock,
                            velocity=(0.0, -2.0))
    scene.set_joint(JointMaterial(penalty, penalty, CoulombSingle(phi=30.0),
                                  restitution=restitution))
    solver = dda.solvers.NewtonRaphson() if solver == "newton" else dda.solvers.LegacyPullBack()
    result = dda.Simulation(scene, dt=dt, solver=solver).run(0.01, progress=False)
    v = result.velocity(brick)[:, 1]
    return v[-1] / 2.0, float(np.max(v**2) / 4.0)


def released_rebound(zeta):
    """The rebound of a mass on a linear spring-dashpot of damping ratio ``zeta`` that lets
    go where the spring's and the dashpot's force is back at zero (the contact's release,
    :attr:`dda.contact.ContactElement.release`), by integrating x'' = -x - 2 zeta x'."""
    def force_zero(t, y):
        return y[0] + 2.0 * zeta * y[1]

    force_zero.terminal, force_zero.direction = True, -1
    sol = solve_ivp(lambda t, y: [y[1], -2.0 * zeta * y[1] - y[0]], (0.0, 100.0), [0.0, 1.0],
                    events=force_zero, rtol=1e-11, atol=1e-14)
    return -float(sol.y_events[0][0][1])


def test_the_released_rebound_of_critical_damping_is_e_to_the_minus_2():
    assert released_rebound(1.0) == pytest.approx(math.exp(-2.0), rel=1e-7)


@pytest.mark.parametrize("solver", ["legacy", "newton"])
def test_a_flat_impact_without_bounce_rebounds_as_its_dashpot_says_at_any_step(solver):
    """A face lands on two corners, each with the contact mass of a corner (0.4 of the
    block's here, where they share it half and half as it lands flat): the face gets
    2 sqrt(0.2) = 0.89 of the damping ratio asked for, and lets go where its force is zero, so
    at ``restitution`` 0 it rebounds at 0.157 (the nominal coefficient is where the spring is
    back at its length). Resolved over 10 or 100 steps of its contact (dt 1e-4, 2e-5), within
    3% of that (0.152, 0.157), and the kinetic energy never grows."""
    face = released_rebound(2.0 * math.sqrt(0.2) * damping_ratio(0.0))
    for dt in (1e-4, 2e-5):
        rebound, most = drop(0.0, dt, solver)
        assert rebound == pytest.approx(face, rel=0.03)
        assert most <= 1.0 + 1e-9


@pytest.mark.parametrize("solver", ["legacy", "newton"])
def test_a_partial_restitution_converges_to_its_dashpot(solver):
    """At ``restitution`` 0.5 the face's released rebound is 0.582; Newmark's gamma = 1
    damps the lightly damped spring too where it is resolved coarsely (0.536 at dt 1e-4, 22
    steps of contact), and the rebound converges as dt falls (0.5745 at 2e-5, 0.5821 at 5e-6)."""
    face = released_rebound(2.0 * math.sqrt(0.2) * damping_ratio(0.5))
    rebounds = [drop(0.5, dt, solver)[0] for dt in (1e-4, 2e-5, 5e-6)]
    errors = np.abs(np.array(rebounds) / face - 1.0)
    assert errors[2] < 0.005 and errors[1] < 0.02 and errors[0] < 0.1
    assert errors[0] > errors[1] > errors[2]


def test_a_static_analysis_takes_no_dashpot():
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(-1, -0.3), (1, -0.3), (1, 0), (-1, 0)], rock, fixed=True)
    scene.add_block([(-0.1, 0), (0.1, 0), (0.1, 0.2), (-0.1, 0.2)], rock)
    scene.set_joint(JointMaterial(1e9, 1e9, CoulombSingle(phi=30.0), restitution=0.0))
    for analysis, has in (("static", False), ("dynamic", True)):
        sim = dda.Simulation(scene, dt=1e-3, analysis=analysis,
                             solver=dda.solvers.NewtonRaphson())
        sim.run(2e-3, progress=False)
        assert (capture_step_problem(sim, 1e-3).element.dashpot is not None) == has
