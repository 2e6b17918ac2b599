"""A law whose force depends on the slip rate (FrictionLaw.uses_dt): Coulomb friction plus a
viscous term, checked and run against a block's terminal velocity on a slope."""

import warnings

import numpy as np
import pytest

import dda
from dda.contact import FrictionLaw, FrictionTrial, JointMaterial, check_friction_law
from dda.materials import LinearElastic
from dda.registry import make_solver


class ViscousCoulomb(FrictionLaw):
    """``|t_s| = mu |t_n| + eta |slip rate|`` while slipping (eta in N s/m per m of joint):
    backward Euler over the step, the slip increment ``lam`` of a slipping contact solving
    ``|t_trial| - p_s lam = mu N + eta lam / dt``."""

    uses_dt = True

    def __init__(self, phi, eta):
        self.phi, self.eta = float(phi), float(eta)
        self.mu = float(np.tan(np.radians(phi)))

    def __repr__(self):
        return f"ViscousCoulomb(phi={self.phi}, eta={self.eta})"

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length, dt=None):
        ps = shear_penalty
        trial = ps * (committed["g_se"] + delta_g_s)
        n = np.maximum(-t_n, 0.0)
        static = self.mu * n
        slipping = np.abs(trial) > static
        c = self.eta / dt
        lam = np.where(slipping, (np.abs(trial) - static) / (ps + c), 0.0)
        t_s = trial - np.sign(trial) * ps * lam
        state = {"g_se": t_s / ps, "slip": committed["slip"] + lam}
        return FrictionTrial(t_s, slipping, static + c * lam, state,
                             {"c": np.full(len(t_s), c)})

    def tangent(self, trial, normal_penalty, shear_penalty):
        ps, c, sign = shear_penalty, trial.extra["c"], np.sign(trial.t_s)
        k_ss = np.where(trial.slipping, ps * c / (ps + c), ps)
        k_sn = np.where(trial.slipping, -sign * ps * self.mu * normal_penalty / (ps + c), 0.0)
        return k_ss, k_sn


def test_the_rate_law_passes_the_check():
    check_friction_law(ViscousCoulomb(phi=25.0, eta=1e4))


@pytest.mark.parametrize("solver", ["legacy", "newton"])
def test_a_block_reaches_the_terminal_velocity_of_its_viscous_joint(solver):
    """A 1 x 0.5 m block on a 38 degree slope at phi 25, on two vertex contacts of eta 5,000
    N s/m each: ``W (sin - tan(phi) cos) = 2 eta v`` gives v = 0.3044 m/s, reached with the
    time constant m / (2 eta) = 0.125 s. After 1 s (8 of them) within 0.5%."""
    th = np.radians(38.0)
    t, n = np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])
    rock = LinearElastic(young=10e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(0, 0), (6, 0), (6, 6 * np.tan(th))], rock, fixed=True)
    foot = 4.5 * t + 1e-6 * n
    block = scene.add_block([tuple(p) for p in (foot, foot + t, foot + t + 0.5 * n,
                                                foot + 0.5 * n)], rock)
    eta = 5e3
    scene.set_joint(JointMaterial(1e10, 1e10, friction=ViscousCoulomb(phi=25.0, eta=eta),
                                  restitution=1.0))
    result = dda.Simulation(scene, dt=1e-3, solver=make_solver(solver)).run(
        1.0, progress=False)
    slide = -result.displacement(block) @ t
    v = (slide[-1] - slide[-11]) / (result.time[-1] - result.time[-11])
    weight = 2500 * 0.5 * 9.81
    terminal = weight * (np.sin(th) - np.tan(np.radians(25.0)) * np.cos(th)) / (2 * eta)
    assert terminal == pytest.approx(0.3044, abs=1e-4)
    assert v == pytest.approx(terminal, rel=5e-3)
    assert np.count_nonzero(result.stats["sliding"]) > 0.9 * len(result.stats)


def test_a_static_analysis_warns_that_a_rate_law_gets_the_pseudo_time_step():
    """A static analysis's dt is a pseudo time: a rate law's force would depend on how the
    loading was divided into steps. Warned once, at the simulation's start; a dynamic one,
    or a static one with rate-free laws, is not."""
    rock = LinearElastic(young=10e9, poisson=0.25, density=2500.0)

    def scene_with(law):
        scene = dda.Scene(gravity=9.81)
        scene.add_block([(0, 0), (2, 0), (2, 1), (0, 1)], rock, fixed=True)
        scene.add_block([(0.5, 1), (1.5, 1), (1.5, 1.5), (0.5, 1.5)], rock)
        scene.set_joint(JointMaterial(1e10, 1e10, friction=law))
        return scene

    viscous = scene_with(ViscousCoulomb(phi=25.0, eta=5e3))
    with pytest.warns(dda.PlausibilityWarning, match=r"ViscousCoulomb.*pseudo time step dt = 0.01"):
        dda.Simulation(viscous, dt=1e-2, analysis="static")
    with warnings.catch_warnings():
        warnings.simplefilter("error", dda.PlausibilityWarning)
        dda.Simulation(viscous, dt=1e-3, analysis="dynamic")
        dda.Simulation(scene_with(dda.contact.CoulombSingle(phi=25.0)), dt=1e-2,
                       analysis="static")


class ReportsYield(ViscousCoulomb):
    """The same forces, reporting as its strength the yield check's, mu |t_n| (the
    viscous part slides above it): a check against the reported strength refused it."""

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length, dt=None):
        trial = super().return_map(committed, delta_g_s, t_n, shear_penalty, length, dt=dt)
        trial.strength = self.mu * np.maximum(-t_n, 0.0)
        return trial


def test_a_law_that_slides_above_its_yield_strength_passes_the_check():
    check_friction_law(ReportsYield(phi=25.0, eta=1e4))


class NaNOnShortSteps(ViscousCoulomb):
    """A defect only a step shorter than the run's dt meets (the located reversal's)."""

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length, dt=None):
        trial = super().return_map(committed, delta_g_s, t_n, shear_penalty, length, dt=dt)
        if dt < 1.9e-3:
            trial.t_s[:] = np.nan
        return trial


def test_a_law_defect_met_in_a_located_reversal_names_the_time():
    from tests.conftest import shaken_block_scene

    scene, _, _ = shaken_block_scene(phi=30, amplitude=6.0)
    scene.set_joint(JointMaterial(1e9, 1e9, friction=NaNOnShortSteps(phi=30, eta=1e3),
                                  restitution=1.0))
    sim = dda.Simulation(scene, dt=2e-3, solver="newton", locate_reversals=True)
    with pytest.raises(dda.FrictionLawError, match=r"^the run cannot go on at t = 0\.\d+ s "
                                                   r"\(a step of 0\.002 s\): friction law"):
        sim.run(0.6, progress=False)
