"""The contact element's consistent tangent against finite differences of its residual."""

import numpy as np
import pytest

import dda
import dda.contact.element as element_module
from dda.contact import CoulombSingle, JointMaterial, StaticDynamicTransition
from dda.kernels import PairStiffness
from tests.conftest import box, capture_step_problem, wedge_scene

LAWS = {
    "coulomb": lambda: CoulombSingle(phi=20.0),
    "static-dynamic": lambda: StaticDynamicTransition(phi_static=20.0, phi_dynamic=15.0,
                                                       onset="contact"),
    "static-dynamic-face": lambda: StaticDynamicTransition(phi_static=20.0, phi_dynamic=15.0,
                                                           onset="face"),
}


def capture_problem(scene, duration, dt=1e-3):
    """Run a scene with Newton-Raphson, then return the StepProblem of the next step."""
    sim = dda.Simulation(scene, dt=dt, solver=dda.solvers.NewtonRaphson())
    sim.run(duration)
    return capture_step_problem(sim, dt)


def sliding_problem(law, restitution=1.0):
    """A block sliding down a free wedge (moving contact edge, soft penalty)."""
    scene, _, _ = wedge_scene(penalty=1e7, law=law, restitution=restitution)
    return capture_problem(scene, 0.05)


def resting_problem(law, restitution=1.0):
    rock = dda.materials.LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(-1, -0.2, 3, 0.2), rock, fixed=True)
    scene.add_block(box(0, 0, 1, 0.2), rock)  # a free slab under a block
    scene.add_block(box(0.3, 0.2, 0.3, 0.2), rock)
    scene.set_joint(JointMaterial(normal_penalty=1e7, shear_penalty=1e7, friction=law,
                                  restitution=restitution))
    return capture_problem(scene, 0.05)


def tangent_mismatch(problem, rng):
    """Largest |K v - FD(r) v| over the contacts, relative to |K| |v|, near the solution."""
    el = problem.element
    d = dda.solvers.NewtonRaphson().solve_step(problem).d
    d[problem.free] += 1e-9 * rng.normal(size=(problem.free.sum(), 6))
    resp = el.response(d)
    v = np.zeros_like(d)
    v[problem.free] = rng.normal(size=(problem.free.sum(), 6))
    dv = el.pair_increments(v)
    h = 1e-8  # displacements are ~1e-4 per step: round-off dominates below ~1e-9
    fd = (el.response(d + h * v).residual - el.response(d - h * v).residual) / (2 * h)
    an = np.einsum("mij,mj->mi", resp.stiffness, dv)
    scale = np.abs(resp.stiffness).max() * np.abs(dv).max()
    return resp, np.abs(an - fd).max() / scale


@pytest.mark.parametrize("law_name", sorted(LAWS))
@pytest.mark.parametrize("case, expect_slip", [(sliding_problem, True),
                                               (resting_problem, False)],
                         ids=["slip", "stick"])
@pytest.mark.parametrize("restitution", [1.0, 0.0, 0.4], ids=["elastic", "e0", "e0.4"])
def test_contact_tangent_matches_finite_differences(case, expect_slip, law_name, restitution):
    """(With an impact dashpot too: its force on the exact gap's change and its share of
    the normal force in the geometric terms.)"""
    problem = case(LAWS[law_name](), restitution)
    if restitution < 1.0:
        assert problem.element.dashpot is not None and np.all(problem.element.dashpot > 0)
    resp, mismatch = tangent_mismatch(problem, np.random.default_rng(0))
    closed = resp.closed
    assert closed.sum() >= 2
    if expect_slip:
        assert resp.slipping[closed].any()
    else:
        assert not resp.slipping[closed].any()
    assert mismatch < 1e-6


def test_the_check_sees_a_missing_geometric_term(monkeypatch):
    """Negative control: without the second variations the tangent no longer matches."""
    problem = sliding_problem(CoulombSingle(phi=20.0))
    original = element_module.consistent_tangent

    def without_geometric_terms(*args, **kwargs):
        k = original(*args, **kwargs)  # terms 2 and 3: B^T H + H^T B, the second variations
        return PairStiffness(k.rows, k.terms[:2], k.weights[:, :2])

    monkeypatch.setattr(element_module, "consistent_tangent", without_geometric_terms)
    _, mismatch = tangent_mismatch(problem, np.random.default_rng(0))
    assert mismatch > 1e-5
