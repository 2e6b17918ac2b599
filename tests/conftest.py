"""Shared scene builders for the tests."""

from dataclasses import replace

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic


@pytest.fixture
def rock():
    return LinearElastic(young=14.9e9, poisson=0.2, density=2198.0)


def box(x0, y0, w, h):
    """Counter-clockwise rectangle with its lower-left corner at (x0, y0)."""
    return [(x0, y0), (x0 + w, y0), (x0 + w, y0 + h), (x0, y0 + h)]


def incline_scene(phi, slope_deg=30.0, penalty=1e9, gravity=9.81, rigid=False):
    """A 0.5 m square block (rigid or not) on a fixed wedge whose top face rises at slope_deg."""
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=gravity)
    th = np.radians(slope_deg)
    length = 4.0
    scene.add_block(
        [(0, 0), (length * np.cos(th), 0), (length * np.cos(th), length * np.sin(th))],
        rock, fixed=True, name="base",
    )
    t = np.array([np.cos(th), np.sin(th)])
    n = np.array([-np.sin(th), np.cos(th)])
    p0 = 2.5 * t
    a = 0.5
    top = scene.add_block([p0, p0 + a * t, p0 + a * t + a * n, p0 + a * n], rock, name="top",
                          rigid=rigid)
    scene.set_joint(JointMaterial(normal_penalty=penalty, shear_penalty=penalty,
                                  friction=CoulombSingle(phi=phi)))
    return scene, top, t


def wedge_scene(penalty=1e7, law=None, restitution=1.0):
    """A block sliding on a free 30 degree wedge that rests on a fixed floor.

    The block's contacts lie on the wedge's moving edge, so g_n and g_s are nonlinear in the
    unknowns (the geometric terms of the tangent matter); a soft penalty makes them large.
    ``restitution``: the joints' impact dashpot (1: none).
    """
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    th = np.radians(30)
    length = 2.0
    floor = scene.add_block([(-1, -0.3), (3, -0.3), (3, 0), (-1, 0)], rock, fixed=True,
                            name="floor")
    wedge = scene.add_block([(0, 0), (length * np.cos(th), 0),
                             (length * np.cos(th), length * np.sin(th))], rock, name="wedge")
    t = np.array([np.cos(th), np.sin(th)])
    n = np.array([-np.sin(th), np.cos(th)])
    p0, a = 1.0 * t, 0.3
    top = scene.add_block([p0, p0 + a * t, p0 + a * t + a * n, p0 + a * n], rock, name="top")
    scene.set_joint(JointMaterial(normal_penalty=penalty, shear_penalty=penalty,
                                  friction=law if law is not None else CoulombSingle(phi=20),
                                  restitution=restitution))
    scene.set_joint(JointMaterial(normal_penalty=penalty, shear_penalty=penalty,
                                  friction=CoulombSingle(phi=45), restitution=restitution),
                    between=(floor, wedge))
    return scene, wedge, top


def capture_step_problem(sim, dt):
    """Run ``sim`` one more step and return that step's StepProblem (as the solver saw it)."""
    from dda.solvers import newton

    captured = {}
    original = newton.NewtonRaphson.solve_step

    def spy(self, problem):
        captured["problem"] = problem
        return original(self, problem)

    newton.NewtonRaphson.solve_step = spy
    try:
        sim.run(dt)
    finally:
        newton.NewtonRaphson.solve_step = original
    return captured["problem"]


def shaken_block_scene(phi, amplitude, freq=2.0):
    """A 0.2 m block on a 2 m table shaken by ``amplitude sin(2 pi freq t)`` (m/s^2)."""
    rock = LinearElastic(young=1e9, poisson=0.2, density=2000.0)
    scene = dda.Scene(gravity=9.81)
    table = scene.add_block(box(0, 0, 2, 0.2), rock, name="table")
    top = scene.add_block(box(0.9, 0.2, 0.2, 0.2), rock, name="top")
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=phi)))
    scene.shake(table, acceleration=lambda t: (amplitude * np.sin(2 * np.pi * freq * t), 0.0))
    return scene, table, top


def stack_scene(n, restitution=None, shear_dashpot=None):
    """The N x N stack of 1 m squares on a fixed base of ``benchmarks/stacks.py`` (E 10 GPa,
    p 1e10 N/m, phi 35 degrees), with the joint's default impact dashpots; ``restitution=1``
    takes them off, as the benchmark does (its scenes are Berkeley's C code's, which has none),
    ``shear_dashpot=False`` the shear one alone."""
    stone = LinearElastic(young=10e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(-1.0, -1.0), (n + 1.0, -1.0), (n + 1.0, 0.0), (-1.0, 0.0)], stone,
                    fixed=True)
    for i in range(n):
        for j in range(n):
            scene.add_block([(j, i), (j + 1, i), (j + 1, i + 1), (j, i + 1)], stone)
    joint = JointMaterial(normal_penalty=1e10, shear_penalty=1e10,
                          friction=CoulombSingle(phi=35.0))
    if restitution is not None:
        joint = replace(joint, restitution=restitution)
    if shear_dashpot is not None:
        joint = replace(joint, shear_dashpot=shear_dashpot)
    scene.set_joint(joint)
    return scene


@pytest.fixture(scope="module")
def stack_step():
    """The second Newton iterate call of the 20 x 20 stack (2,400 unknowns: the sparse path,
    in mixed precision where PARDISO is there): its StepProblem, the predictor's increments
    and the iteration budget. The run to it is made without the turned contacts' stick
    branch (``newton.REVERSED_STICK``), as the tests that use it were measured: with it the
    first step ends elsewhere by round-off, and the second's iterate takes another path."""
    from dda.solvers import newton

    captured = []
    original = newton.NewtonRaphson.iterate
    rule = newton.REVERSED_STICK

    def capture(self, problem, d, max_iter=None, contraction=0.0):
        captured.append((problem, d.copy(), max_iter))
        return original(self, problem, d, max_iter, contraction)

    newton.NewtonRaphson.iterate = capture
    newton.REVERSED_STICK = False
    try:
        sim = dda.Simulation(stack_scene(20), dt=1e-3, solver=dda.solvers.NewtonRaphson())
        sim.run(2e-3, progress=False)
    finally:
        newton.NewtonRaphson.iterate = original
        newton.REVERSED_STICK = rule
    return captured[1]
