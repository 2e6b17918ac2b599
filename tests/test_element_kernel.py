"""The contact element from one kernel call (:meth:`dda.contact.ContactElement.compiled`,
:func:`dda.kernels.element.element_arrays`) against the constructor and the numpy dashpots:
every array the solvers read, to the bit."""

from dataclasses import replace

import numpy as np
import pytest

import dda
import dda.step as step_module
from dda.contact import StaticDynamicTransition
from dda.solvers.open_close import round_off_gap
from tests.conftest import stack_scene
from tests.stability import scenes

ARRAYS = ("gap0", "shear0", "length", "e_row", "i_row", "normal_penalty", "shear_penalty",
          "dashpot", "dashpot_reference", "release", "judge_stiffness", "_spring_rows")


def _stack():
    return stack_scene(3), 1e-3


def _shear_off():
    scene = stack_scene(3)
    scene.set_joint(replace(scene.default_joint, shear_dashpot=False, restitution=0.3))
    return scene, 1e-3


def _no_dashpots():
    return stack_scene(3, restitution=1.0), 1e-3


def _faces():
    scene, dt, _, _ = scenes.incline(StaticDynamicTransition(35.0, 25.0))
    return scene, dt


def _cut_slope():
    scene, dt, _, _ = scenes.shaken_cut_slope()
    return scene, dt


def _elements(make, monkeypatch, steps=5):
    """The element of the step after ``steps`` steps, built both ways from the same state."""
    scene, dt = make()
    sim = dda.Simulation(scene, dt=dt)
    sim.run(steps * dt, progress=False)
    model, state = sim.model, sim.committed
    built = []
    for kernels in (True, False):
        monkeypatch.setattr(step_module, "BLOCK_KERNELS", kernels)
        ints, *_ = step_module._plain_start(model, state, dt, 1.0)
        found = step_module._detect(model, state, 0.01, sim.settings.penetration_tolerance)
        built.append(step_module._element(model, state, found, ints, dt))
    return built


@pytest.mark.parametrize("make", [_stack, _shear_off, _no_dashpots, _faces, _cut_slope])
def test_the_compiled_element_has_the_constructors_bits(make, monkeypatch):
    compiled, reference = _elements(make, monkeypatch)
    assert len(compiled) > 0
    for name in ARRAYS:
        a, b = getattr(compiled, name), getattr(reference, name)
        if b is None:
            assert a is None, name
            continue
        assert np.array_equal(np.asarray(a), np.asarray(b)), name
    for a, b in zip(compiled.maps, reference.maps, strict=True):
        assert np.array_equal(a, b)
    assert np.array_equal(compiled.gap_round_off, round_off_gap(reference))
    assert reference.gap_round_off is None
    for k in reference.contacts.history:
        assert np.array_equal(compiled.contacts.history[k], reference.contacts.history[k]), k
    if reference.shear_dashpot is None:
        assert compiled.shear_dashpot is None
    else:
        for a, b in zip(compiled.shear_dashpot, reference.shear_dashpot, strict=True):
            assert np.array_equal(a, b)
    faces = reference.laws.faces
    if faces is not None:
        assert np.array_equal(compiled.laws.faces.index, faces.index)


def test_the_cases_cover_each_dashpot_on_and_off(monkeypatch):
    with_both = _elements(_stack, monkeypatch)[0]
    assert with_both.dashpot is not None and with_both.shear_dashpot is not None
    impact_only = _elements(_shear_off, monkeypatch)[0]
    assert impact_only.dashpot is not None and impact_only.shear_dashpot is None
    neither = _elements(_no_dashpots, monkeypatch)[0]
    assert neither.dashpot is None and neither.shear_dashpot is None
