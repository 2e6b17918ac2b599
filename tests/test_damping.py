"""Viscous (Rayleigh) damping, C = alpha M + beta K_e (issue 8, item 1; METHOD.md section 2).

Newmark with gamma = 1 turns ``M a + C v = 0`` into ``v_{n+1} = v_n / (1 + alpha dt)`` for a
free block with mass damping: backward Euler of ``v' = -alpha v``, so the run converges to
``exp(-alpha t)`` at first order. Stiffness damping acts on the strain unknowns only.
"""

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic
from dda.solvers import LegacyPullBack, NewtonRaphson
from tests.conftest import box

SOLVERS = [LegacyPullBack(), NewtonRaphson()]
IDS = ["legacy", "newton"]
ROCK = LinearElastic(young=1e9, poisson=0.25, density=2500.0)


def flying_block(alpha=0.0, beta=0.0, velocity=(2.0, -1.0), spin=3.0):
    scene = dda.Scene()
    b = scene.add_block(box(0, 0, 1, 0.5), ROCK, velocity=velocity, angular_velocity=spin)
    scene.set_damping(mass=alpha, stiffness=beta)
    return scene, b


@pytest.mark.parametrize("solver", SOLVERS, ids=IDS)
def test_mass_damping_slows_every_velocity_by_the_backward_euler_factor(solver):
    alpha, dt, n = 4.0, 0.01, 50
    scene, b = flying_block(alpha)
    sim = dda.Simulation(scene, dt=dt, solver=solver)
    result = sim.run(n * dt)
    factor = (1.0 / (1.0 + alpha * dt)) ** np.arange(n + 1)
    v = result.velocity(b)
    np.testing.assert_allclose(v[:, 0], 2.0 * factor, rtol=1e-10)
    np.testing.assert_allclose(v[:, 1], -1.0 * factor, rtol=1e-10)
    np.testing.assert_allclose(v[:, 2], 3.0 * factor, rtol=1e-10)


def test_mass_damping_converges_to_the_exponential_at_first_order():
    alpha, duration = 4.0, 0.5
    errors = []
    for dt in (0.01, 0.005, 0.0025):
        scene, b = flying_block(alpha, spin=0.0)
        result = dda.Simulation(scene, dt=dt).run(duration)
        exact = 2.0 * np.exp(-alpha * duration)
        errors.append(abs(result.velocity(b)[-1, 0] - exact) / exact)
        # the distance flown: integral of 2 exp(-alpha t)
        flown = result.displacement(b)[-1, 0]
        assert flown == pytest.approx(2.0 / alpha * (1 - np.exp(-alpha * duration)),
                                      rel=0.05)
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] < 0.01
    np.testing.assert_allclose(rates, 1.0, atol=0.05)


def test_stiffness_damping_leaves_rigid_motion_alone():
    scene, b = flying_block(beta=0.01)
    result = dda.Simulation(scene, dt=0.01).run(0.3)
    v = result.velocity(b)
    np.testing.assert_allclose(v[:, :3], np.tile([2.0, -1.0, 3.0], (len(v), 1)), rtol=1e-12)


def strain_oscillator(beta, dt, n, load=1e3):
    """A 2 m x 1 m free block (nu 0) pulled apart by two opposite point loads; returns the
    recorded ex history and the single-unknown Newmark recursion of the same mode."""
    mat = LinearElastic(young=1e9, poisson=0.0, density=2500.0)
    scene = dda.Scene()
    b = scene.add_block(box(-1.0, -0.5, 2.0, 1.0), mat)
    scene.add_point_load(b, point=(1.0, 0.0), force=(load, 0.0))
    scene.add_point_load(b, point=(-1.0, 0.0), force=(-load, 0.0))
    scene.set_damping(stiffness=beta)
    sim = dda.Simulation(scene, dt=dt)
    ex = [0.0]
    for _ in range(n):
        sim.run(dt)
        ex.append(sim.state.stress[0, 0] / mat.young)
    # the ex mode alone: m = rho Sxx, k = E A, generalized force L P (L = 2 m between loads)
    m, k, f = 2500.0 * 2.0**3 / 12.0, 1e9 * 2.0, 2.0 * load
    c = beta * k
    u, v, ref = 0.0, 0.0, [0.0]
    for _ in range(n):
        d = (f - k * u + (2.0 / dt) * m * v + c * v) / (k + 2.0 * m / dt**2 + 2.0 * c / dt)
        u, v = u + d, 2.0 * d / dt - v
        ref.append(u)
    return np.array(ex), np.array(ref), np.sqrt(k / m), f / k


def test_stiffness_damping_matches_the_one_mode_recursion():
    ex, ref, omega, static = strain_oscillator(beta=2e-4, dt=2e-5, n=300)
    assert np.abs(ex).max() > 1.5 * static  # it oscillates about the static strain
    # the block's geometry moves by strains of 1e-6: agreement to 1e-4 of the static strain
    np.testing.assert_allclose(ex, ref, atol=1e-4 * static)


def test_stiffness_damping_gives_the_damping_ratio_beta_omega_over_2():
    # period 2 pi / omega = 2.6 ms; 200 steps a period, 6 periods
    omega = np.sqrt(1e9 * 2.0 / (2500.0 * 8.0 / 12.0))
    dt = 2 * np.pi / omega / 200
    zeta = 0.02
    damped, _, _, static = strain_oscillator(2 * zeta / omega, dt, 1200)
    undamped, _, _, _ = strain_oscillator(0.0, dt, 1200)
    t = dt * np.arange(len(damped))

    def peaks(x):  # amplitude about the static strain, at each local maximum
        y = x - static
        i = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:])) + 1
        return t[i], y[i]

    (td, ad), (tu, au) = peaks(damped), peaks(undamped)
    assert len(ad) >= 5 and len(au) >= 5
    np.testing.assert_allclose(td[:5], tu[:5], rtol=0.01)  # the same peaks, paired
    # Newmark's gamma = 1 damps both runs alike; the ratio is the viscous part alone
    rate = -np.polyfit(td[:5], np.log(ad[:5] / au[:5]), 1)[0]
    assert rate == pytest.approx(zeta * omega, rel=0.05)


def test_a_scene_without_damping_has_no_damping_term():
    scene, _ = flying_block()
    assert dda.Simulation(scene, dt=0.01).model.damping is None  # zero coefficients: no term
    scene = dda.Scene()
    scene.add_block(box(0, 0, 1, 1), ROCK)
    assert dda.Simulation(scene, dt=0.01).model.damping is None
    scene.set_damping(mass=1.0)
    alpha, beta = dda.Simulation(scene, dt=0.01).model.damping
    assert alpha.tolist() == [1.0] and beta.tolist() == [0.0]


def test_damping_of_some_blocks_only_and_overrides():
    scene = dda.Scene()
    a = scene.add_block(box(0, 0, 1, 1), ROCK, velocity=(1.0, 0.0))
    b = scene.add_block(box(3, 0, 1, 1), ROCK, velocity=(1.0, 0.0), name="b")
    c = scene.add_block(box(6, 0, 1, 1), ROCK, velocity=(1.0, 0.0))
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=30.0)))
    scene.set_damping(mass=2.0)
    scene.set_damping(mass=0.0, blocks=["b"])
    scene.set_damping(mass=5.0, stiffness=1e-3, blocks=c)
    alpha, beta = scene.damping_coefficients()
    assert alpha.tolist() == [2.0, 0.0, 5.0] and beta.tolist() == [0.0, 0.0, 1e-3]
    dt = 0.01
    result = dda.Simulation(scene, dt=dt).run(0.1)
    assert result.velocity(a)[-1, 0] == pytest.approx((1 + 2.0 * dt) ** -10, rel=1e-10)
    assert result.velocity(b)[-1, 0] == pytest.approx(1.0, rel=1e-12)
    assert result.velocity(c)[-1, 0] == pytest.approx((1 + 5.0 * dt) ** -10, rel=1e-10)


@pytest.mark.parametrize("solver", SOLVERS, ids=IDS)
def test_a_damped_fall_reaches_the_terminal_velocity_g_over_alpha(solver):
    # v' = -g - alpha v: backward Euler keeps the fixed point v = -g / alpha exactly
    alpha, g, dt = 10.0, 9.81, 1e-3
    scene = dda.Scene(gravity=g)
    b = scene.add_block(box(0, 0, 1, 1), ROCK)
    scene.set_damping(mass=alpha)
    result = dda.Simulation(scene, dt=dt, solver=solver, max_displacement_ratio=10).run(1.0)
    v = result.velocity(b)[:, 1]
    t = result.time
    assert v[-1] == pytest.approx(-g / alpha, rel=1e-4)
    np.testing.assert_allclose(v, -(g / alpha) * (1 - np.exp(-alpha * t)), atol=0.01 * g / alpha)


@pytest.mark.parametrize("kwargs, match", [
    ({"mass": -1.0}, "mass must not be negative"),
    ({"stiffness": float("nan")}, "stiffness must be finite"),
    ({"mass": "x"}, "mass must be a number"),
    ({"mass": 1.0, "blocks": ["nope"]}, "no block named 'nope'"),
    ({"mass": 1.0, "blocks": 3.5}, "blocks must be a list"),
])
def test_damping_input_errors(kwargs, match):
    scene = dda.Scene()
    scene.add_block(box(0, 0, 1, 1), ROCK)
    with pytest.raises((ValueError, TypeError), match=match):
        scene.set_damping(**kwargs)
