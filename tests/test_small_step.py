"""A small scene's common step in one kernel call (dda.kernels.small_step, dda.step.SMALL_STEP)
against the composed step: the same runs to the bit, the fast path taken where it should be
and not where it should not."""

from dataclasses import replace

import numpy as np
import pytest

import dda
import dda.step as step_module
from dda.contact import BartonBandis, CoulombSingle, StaticDynamicTransition
from dda.kernels import small_step
from tests.conftest import stack_scene
from tests.stability import scenes


def _incline(law):
    return scenes.incline(law)[0], 1e-3, 0.3


def _no_dashpots():
    scene = stack_scene(3, restitution=1.0)
    return scene, 1e-3, 0.1


def _impact_only():
    scene = stack_scene(3)
    scene.set_joint(replace(scene.default_joint, shear_dashpot=False))
    return scene, 1e-3, 0.1


def _stopper():  # impacts whose steps are cut (moves, OPEN-CLOSE)
    scene, duration = scenes.stopper_impact()
    return scene, 1e-3, duration


def _shaken():  # a shaken base: known motion in the step
    scene, dt, _, _ = scenes.shaken_cut_slope()
    return scene, dt, 0.1


CASES = {
    "coulomb incline": lambda: _incline(CoulombSingle(phi=30.0)),
    "transition, per contact": lambda: _incline(StaticDynamicTransition(35.0, 25.0,
                                                                        onset="contact")),
    "transition, by faces": lambda: _incline(StaticDynamicTransition(35.0, 25.0)),
    "stack without dashpots": _no_dashpots,
    "stack, impact dashpot": _impact_only,
    "stopper": _stopper,
    "shaken cut slope": _shaken,
}


def _run(make, solver, small, monkeypatch, count=None):
    monkeypatch.setattr(step_module, "SMALL_STEP", small)
    scene, dt, duration = make()
    sim = dda.Simulation(scene, dt=dt, solver=solver())
    result = sim.run(duration, progress=False)
    return sim, result


@pytest.mark.parametrize("solver", [dda.solvers.LegacyPullBack, dda.solvers.NewtonRaphson])
@pytest.mark.parametrize("case", list(CASES))
def test_the_one_call_step_runs_as_the_composed_one(case, solver, monkeypatch):
    taken = []
    original = small_step.contact_step

    def counting(*args):
        out = original(*args)
        taken.append(out[0])
        return out

    monkeypatch.setattr(step_module, "contact_step", counting)
    fast, fast_result = _run(CASES[case], solver, True, monkeypatch)
    slow, slow_result = _run(CASES[case], solver, False, monkeypatch)
    # the fast path ran and decided steps itself (of the 31-block slope's, whose contacts
    # change in most steps as it settles and shakes, 24 of 145 under legacy DDA; most steps
    # elsewhere)
    decided = [s for s in taken if s != small_step.FALLBACK]
    assert len(decided) > 0.1 * len(fast_result.stats), (len(decided), len(taken))
    a, b = fast.committed, slow.committed
    for name in ("x", "velocity", "stress", "rotation", "centroid"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), name)
    for name in ("vertex", "edge", "state", "xi0", "t_n", "t_s", "held_ago"):
        np.testing.assert_array_equal(getattr(a.contacts, name), getattr(b.contacts, name))
    assert a.contacts.history.keys() == b.contacts.history.keys()
    for k in a.contacts.history:
        np.testing.assert_array_equal(a.contacts.history[k], b.contacts.history[k])
    for field in ("time", "open_close_passes", "iterations", "solves", "retries", "pairs",
                  "unknowns", "penetration", "spring_penetration"):
        np.testing.assert_array_equal(fast_result.stats[field], slow_result.stats[field],
                                      field)
    assert fast_result.stats.cuts == slow_result.stats.cuts
    for x, y in zip(fast_result.stats.residual_norms, slow_result.stats.residual_norms,
                    strict=True):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("law", [BartonBandis(jrc=8.0, jcs=40e6, phi_r=27.0)])
def test_laws_it_does_not_take_go_the_composed_way(law, monkeypatch):
    taken = []
    monkeypatch.setattr(step_module, "contact_step",
                        lambda *args: taken.append(1) or small_step.contact_step(*args))
    scene, dt, duration = _incline(law)
    dda.Simulation(scene, dt=dt, solver=dda.solvers.LegacyPullBack()).run(0.05)
    assert taken == []


def test_a_static_analysis_goes_the_composed_way(monkeypatch):
    taken = []
    monkeypatch.setattr(step_module, "contact_step",
                        lambda *args: taken.append(1) or small_step.contact_step(*args))
    scene, dt, _ = _incline(CoulombSingle(phi=40.0))
    dda.Simulation(scene, dt=dt, analysis="static").run(0.02)
    assert taken == []
