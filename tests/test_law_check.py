"""check_friction_law: passes on every law of the package, fails on each kind of broken law."""

import inspect

import numpy as np
import pytest

import dda.contact as contact
from dda.contact import (
    BartonBandis,
    CoulombLike,
    CoulombSingle,
    FrictionLaw,
    StaticDynamicTransition,
    check_friction_law,
)
from examples.my_laws import BrittleCohesion

PACKAGE_LAWS = [
    CoulombSingle(phi=30.0),
    CoulombSingle(phi=36.4, cohesion=1e4),
    StaticDynamicTransition(phi_static=30.0, phi_dynamic=20.0, onset="contact"),
    StaticDynamicTransition(phi_static=40.0, phi_dynamic=30.0, onset="face"),
    BartonBandis(jrc=10.0, jcs=50e6, phi_r=25.0),
    BartonBandis(jrc=15.0, jcs=100e6, phi_r=30.0, mobilized=False),
    BartonBandis(jrc=8.0, jcs=80e6, phi_r=28.0, dilation=True),
]


@pytest.mark.parametrize("law", PACKAGE_LAWS + [BrittleCohesion(30.0, 5e4)], ids=repr)
def test_every_law_passes(law):
    assert check_friction_law(law) is None


def test_every_law_class_of_the_package_is_checked():
    classes = {obj for _, obj in inspect.getmembers(contact, inspect.isclass)
               if issubclass(obj, FrictionLaw) and not inspect.isabstract(obj)}
    assert classes == {type(law) for law in PACKAGE_LAWS}


class _Broken(CoulombSingle):
    """Coulomb with one defect switched on by ``kind``."""

    def __init__(self, kind):
        super().__init__(phi=30.0)
        self.kind = kind
        if kind == "unpicklable":
            self.hook = lambda x: x

    def __repr__(self):
        return f"_Broken({self.kind!r})"

    def strength_slope(self, t_n, length, history=None):
        return 1.1 * self.mu if self.kind == "slope" else self.mu

    def strength(self, t_n, length, history=None):
        s = super().strength(t_n, length, history)
        if self.kind == "not vectorized":  # the strength of the whole batch's mean pressure
            s = np.full_like(s, np.mean(s))
        if self.kind == "never slips":
            s = s + 1e12
        return s

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length, faces=None):
        trial = super().return_map(committed, delta_g_s, t_n, shear_penalty, length, faces)
        if self.kind == "mutates":
            committed["g_se"] += delta_g_s
        if self.kind == "over strength":  # slips at 1.5 times the strength it reports
            trial.t_s = np.where(trial.slipping, 1.5 * trial.t_s, trial.t_s)
        if self.kind == "pushes the slip":  # a slipping force with the slip, not against it
            trial.t_s = np.where(trial.slipping, -trial.t_s, trial.t_s)
        return trial

    def tangent(self, trial, normal_penalty, shear_penalty):
        k_ss, k_sn = super().tangent(trial, normal_penalty, shear_penalty)
        if self.kind == "over strength":
            k_sn = 1.5 * k_sn
        if self.kind == "pushes the slip":
            k_sn = -k_sn
        return k_ss, k_sn

    def initial_state(self, n):
        state = super().initial_state(n)
        if self.kind == "bool history":
            state["slip"] = np.zeros(n, dtype=bool)
        return state

    def stick(self, committed, delta_g_s, shear_penalty):
        trial = super().stick(committed, delta_g_s, shear_penalty)
        if self.kind == "stick":
            trial.t_s = 2.0 * trial.t_s
        return trial


@pytest.mark.parametrize("kind, message", [
    ("slope", "tangent d t_s / d g_n of a slipping contact"),
    ("mutates", "changed its input committed history"),
    ("not vectorized", "evaluated alone differs"),
    ("never slips", "0 slipped"),
    ("stick", "stick\\(\\) and return_map\\(\\) disagree"),
    ("unpicklable", "cannot be pickled"),
    ("over strength", "more than its trial \\(stick spring\\) force"),
    ("pushes the slip", "friction must resist the slip"),
    ("bool history", "dtype bool; history is carried as float"),
])
def test_each_defect_is_named(kind, message):
    with pytest.raises(AssertionError, match=message):
        check_friction_law(_Broken(kind))
    check_friction_law(_Broken("none"))  # the same class without the defect passes


class StickKeepsSliding(StaticDynamicTransition):
    """A law whose stick branch forgets to reset its 'sliding' flag: under legacy DDA it would
    keep the dynamic angle after sticking again."""

    def elastic_update(self, committed, delta_g_s):
        return FrictionLaw.elastic_update(self, committed, delta_g_s)


class NaNAtZeroPressure(CoulombSingle):
    def strength_slope(self, t_n, length, history=None):
        p = np.maximum(-t_n, 0.0)
        return self.mu * p / p


def test_a_stick_branch_that_keeps_a_flag_is_found():
    with pytest.raises(AssertionError, match="history field 'sliding' after stick"):
        check_friction_law(StickKeepsSliding(phi_static=30.0, phi_dynamic=20.0))


def test_a_law_that_breaks_without_normal_force_is_found():
    with pytest.raises(AssertionError, match="t_n = 0 gives a non-finite"):
        with np.errstate(invalid="ignore", divide="ignore"):
            check_friction_law(NaNAtZeroPressure(phi=30.0))


class WrongStick(CoulombSingle):
    def tangent(self, trial, normal_penalty, shear_penalty):
        k_ss, k_sn = super().tangent(trial, normal_penalty, shear_penalty)
        return 0.5 * k_ss, k_sn


def test_a_wrong_stick_tangent_is_found():
    with pytest.raises(AssertionError, match="d t_s / d g_s of a sticking contact"):
        check_friction_law(WrongStick(phi=30.0))


def test_a_non_law_is_refused():
    with pytest.raises(AssertionError, match="not a dda.contact.FrictionLaw"):
        check_friction_law(object())


class Capped(CoulombLike):
    """A strength that saturates: S = 1e5 tanh(|t_n| / 1e5)."""

    def strength(self, t_n, length, history=None):
        return 1e5 * np.tanh(np.maximum(-t_n, 0.0) / 1e5)

    def strength_slope(self, t_n, length, history=None):
        return 1.0 / np.cosh(np.maximum(-t_n, 0.0) / 1e5) ** 2

    def __repr__(self):
        return "Capped()"


class CappedWrongSlope(Capped):
    def strength_slope(self, t_n, length, history=None):
        return np.ones_like(t_n)


def test_coulomb_like_needs_only_the_strength():
    """A law that gives strength and slope inherits the return map and the tangent; a wrong
    slope is caught."""
    check_friction_law(Capped())
    with pytest.raises(AssertionError, match="d t_s / d g_n of a slipping contact"):
        check_friction_law(CappedWrongSlope())


class Forgetful(CoulombLike):
    """A law that keeps mu but not its constructor's ``angle``: no checkpoint can rebuild it."""

    name = "forgetful"

    def __init__(self, angle):
        self.mu = float(np.tan(np.radians(angle)))

    def strength(self, t_n, length, history=None):
        return np.maximum(-t_n, 0.0) * self.mu

    def strength_slope(self, t_n, length, history=None):
        return self.mu


def test_a_law_that_forgets_its_parameters_is_found():
    with pytest.raises(AssertionError, match=r"does not keep its constructor parameter\(s\) "
                                             r"\['angle'\]"):
        check_friction_law(Forgetful(30.0))


class NegativeStick(CoulombSingle):
    """A stick spring that pulls the contact along (its force and tangent of the other sign,
    consistent with each other)."""

    def __repr__(self):
        return "NegativeStick()"

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length, faces=None):
        trial = super().return_map(committed, delta_g_s, t_n, shear_penalty, length, faces)
        trial.t_s = -trial.t_s
        return trial

    def stick(self, committed, delta_g_s, shear_penalty):
        trial = super().stick(committed, delta_g_s, shear_penalty)
        trial.t_s = -trial.t_s
        return trial

    def tangent(self, trial, normal_penalty, shear_penalty):
        k_ss, k_sn = super().tangent(trial, normal_penalty, shear_penalty)
        return -k_ss, -k_sn


def test_a_stick_spring_that_does_not_push_back_is_found():
    """It passed every other check; on a 25 degree slope at phi 30 its block slid 0.42 m in
    0.3 s."""
    with pytest.raises(AssertionError, match="sticking contact's d t_s / d g_s is -1e\\+09"):
        check_friction_law(NegativeStick(phi=30.0))
