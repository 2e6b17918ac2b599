"""The compiled OPEN-CLOSE pass (dda.kernels.open_close) against the numpy iteration: the same
return maps, the same decisions, the same bits."""

from __future__ import annotations

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial, StaticDynamicTransition, element
from dda.contact.element import LawGroups
from dda.contact.faces import Faces
from dda.kernels.open_close import law_forces
from dda.materials import LinearElastic
from tests.conftest import box
from tests.stability import scenes as S

LAWS = [CoulombSingle(phi=30.0, cohesion=2e4), StaticDynamicTransition(35.0, 20.0),
        StaticDynamicTransition(30.0, 25.0, onset="contact"), CoulombSingle(phi=10.0)]


def _groups(rng, m):
    law_index = rng.integers(0, len(LAWS), m)
    groups = LawGroups.build(law_index, LAWS)
    return LawGroups(groups.groups, Faces(rng.integers(0, max(m // 3, 1), m)))


@pytest.mark.parametrize("seed", range(8))
def test_law_forces_are_the_laws_return_maps(seed):
    """Every law, a mix of them, faces that span contacts of several laws, a ``where`` mask:
    the kernel's forces and slipping flags are those of the laws' own return maps, to the
    bit."""
    rng = np.random.default_rng(seed)
    m = 40
    laws = _groups(rng, m)
    history = {"g_se": rng.normal(0.0, 1e-4, m), "slip": rng.random(m),
               "sliding": (rng.random(m) < 0.4).astype(float)}
    dgs = rng.normal(0.0, 1e-4, m)
    t_n = -np.abs(rng.normal(0.0, 1e6, m)) * (rng.random(m) < 0.9)
    ps, length = np.full(m, 1e10) * rng.uniform(0.5, 2.0, m), rng.uniform(0.1, 1.0, m)
    where = rng.random(m) < 0.8
    t_s, slipping, _ = laws.return_map(history, dgs, t_n, ps, length, where=where)
    kind, mu_s, mu_d, cohesion, face = laws.kernel_laws(m)
    k_t, k_slip = law_forces(kind, mu_s, mu_d, cohesion, face, history["g_se"],
                             history["sliding"], dgs, t_n, ps, length, where)
    assert 0 < np.count_nonzero(slipping) < np.count_nonzero(where)  # both branches met
    np.testing.assert_array_equal(k_t, t_s)
    np.testing.assert_array_equal(k_slip, slipping)


def test_a_law_without_a_kernel_keeps_the_numpy_iteration():
    class Softer(CoulombSingle):  # a subclass may change any part of the return map
        pass

    assert LawGroups([(Softer(phi=30.0), np.arange(3))]).kernel_laws(3) is None
    assert LawGroups([(CoulombSingle(phi=30.0), np.arange(3))]).kernel_laws(3) is not None


def _two_joints():
    """A block on a block on a base, the joints Coulomb with cohesion but the upper one, the
    static-to-dynamic transition by faces, pushed sideways: both laws in one step."""
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(-2.0, -0.5, 4.0, 0.5), rock, fixed=True)
    low = scene.add_block(box(-0.5, 0.0, 1.0, 0.5), rock, velocity=(0.3, 0.0))
    top = scene.add_block(box(-0.3, 0.5, 0.6, 0.4), rock, velocity=(0.8, 0.0))
    scene.set_joint(JointMaterial(1e9, 1e9, CoulombSingle(phi=25.0, cohesion=1e3)))
    scene.set_joint(JointMaterial(1e9, 1e9, StaticDynamicTransition(30.0, 20.0)),
                    between=(low, top))
    return scene, 1e-3, 0.25


CASES = {
    "incline coulomb": lambda: S.incline(CoulombSingle(phi=20.0))[:2] + (0.3,),
    "incline transition by contact": lambda: S.incline(
        StaticDynamicTransition(35.0, 20.0, onset="contact"))[:2] + (0.3,),
    "resting on faces": lambda: S.incline(StaticDynamicTransition(25.0, 20.0), kick=0.0,
                                          slope=24.0)[:2] + (0.3,),
    "two laws": _two_joints,
    "shaken cut slope": lambda: S.shaken_cut_slope()[:2] + (0.06,),
}


@pytest.mark.parametrize("solver", [dda.solvers.LegacyPullBack, dda.solvers.NewtonRaphson])
@pytest.mark.parametrize("case", CASES)
def test_compiled_passes_give_the_numpy_iterations_bits(case, solver, monkeypatch):
    """The composed compiled passes (a dense system's passes, and its Newton iterations, in
    one kernel call agree with them to round-off: tests/test_dense_passes.py,
    tests/test_dense_newton.py)."""
    from dda.solvers import newton, open_close

    monkeypatch.setattr(open_close, "DENSE_PASSES", False)
    monkeypatch.setattr(newton, "DENSE_NEWTON", False)
    runs = []
    for compiled in (False, True):
        monkeypatch.setattr(element, "KERNEL_LAWS", compiled)
        scene, dt, duration = CASES[case]()
        sim = dda.Simulation(scene, dt=dt, solver=solver())
        result = sim.run(duration, progress=False)
        runs.append((sim.state, result.stats))
    (a, sa), (b, sb) = runs
    assert np.count_nonzero(sa["sliding"]) > 0  # friction decisions were taken
    for name in ("open_close_passes", "iterations", "closed", "sliding", "time"):
        np.testing.assert_array_equal(sa[name], sb[name], err_msg=name)
    for name in ("centroid", "velocity", "stress"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_array_equal(a.contacts.t_s, b.contacts.t_s)
    for key, value in a.contacts.history.items():
        np.testing.assert_array_equal(value, b.contacts.history[key], err_msg=key)


def test_round_off_gaps_are_numpys():
    from dda.kernels.open_close import round_off_gaps

    rng = np.random.default_rng(3)
    p1 = rng.normal(0.0, 1.0, (500, 2)) * 10.0 ** rng.integers(-6, 7, (500, 2))
    p2 = rng.normal(0.0, 1.0, (500, 2)) * 10.0 ** rng.integers(-6, 7, (500, 2))
    length = rng.random(500)
    eps64 = 64.0 * np.finfo(float).eps
    expected = np.maximum(1e-12 * length,
                          eps64 * np.maximum(np.abs(p1).max(axis=1), np.abs(p2).max(axis=1)))
    np.testing.assert_array_equal(round_off_gaps(p1, p2, length, 1e-12, eps64), expected)


def test_kept_patterns_compare_keys_by_value():
    from dda.solvers.sparse_factor import FactorSet

    built = []
    fs = FactorSet()
    key = (np.array([True, False]), np.array([0, 1]), None)
    first = fs.kept("p", key, lambda: built.append(1) or "a")
    assert fs.kept("p", (key[0].copy(), key[1].copy(), None), lambda: "b") == first
    assert fs.kept("p", (key[0], np.array([0, 2]), None), lambda: "c") == "c"
    assert fs.kept("p", (key[0], np.array([0.0, 2.0]), None), lambda: "d") == "c"  # by value
    assert fs.kept("p", (key[0], np.array([0, 2]), np.array([1])), lambda: "e") == "e"


def test_compiled_passes_log_why_they_went_on(monkeypatch):
    """benchmarks/stacks.py reads PASS_LOG: the compiled passes log what the numpy ones do."""
    from dda.solvers import open_close
    from tests.conftest import stack_scene

    logs = []
    for compiled in (False, True):
        monkeypatch.setattr(element, "KERNEL_LAWS", compiled)
        monkeypatch.setattr(open_close, "PASS_LOG", [])
        sim = dda.Simulation(stack_scene(4), dt=1e-3, solver=dda.solvers.LegacyPullBack())
        sim.run(0.02, progress=False)
        logs.append(list(open_close.PASS_LOG))
    assert len(logs[0]) > 20 and any(sum(row) for row in logs[0])
    assert logs[0] == logs[1]
