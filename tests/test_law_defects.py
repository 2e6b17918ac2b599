"""A defective friction law stops a run with an error that names it, under both solvers,
instead of cutting dt without end (the helper's review: a law that gave NaN on its slip branch
took Newton-Raphson to steps of 7e-15 s, 33,593 of them in 29 s, for ever)."""

from dataclasses import replace

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.registry import make_solver
from tests.conftest import incline_scene

SOLVERS = ["legacy", "newton"]


class NaNOnSlip(CoulombSingle):
    """Coulomb whose slip branch gives NaN (a law with a division by zero, say)."""

    def __repr__(self):
        return "NaNOnSlip()"

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length, faces=None):
        trial = super().return_map(committed, delta_g_s, t_n, shear_penalty, length, faces)
        trial.t_s = np.where(trial.slipping, np.nan, trial.t_s)
        return trial


class OverStrength(CoulombSingle):
    """Coulomb whose slip branch carries 1.5 times the strength it reports, with the
    matching tangent: Newton-Raphson converges only where nothing slips."""

    def __repr__(self):
        return "OverStrength()"

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length, faces=None):
        trial = super().return_map(committed, delta_g_s, t_n, shear_penalty, length, faces)
        trial.t_s = np.where(trial.slipping, 1.5 * trial.t_s, trial.t_s)
        return trial

    def tangent(self, trial, normal_penalty, shear_penalty):
        k_ss, k_sn = super().tangent(trial, normal_penalty, shear_penalty)
        return k_ss, 1.5 * k_sn


def _sliding(law):
    """A block on a 35 degree slope at phi 30: it slides from the first step."""
    scene, _, _ = incline_scene(30.0, slope_deg=35.0)
    scene.set_joint(replace(scene.default_joint, friction=law))
    return scene


@pytest.mark.parametrize("solver", SOLVERS)
def test_a_law_that_gives_nan_stops_the_run_and_is_named(solver):
    sim = dda.Simulation(_sliding(NaNOnSlip(phi=30.0)), dt=1e-3, solver=make_solver(solver))
    with pytest.raises(dda.FrictionLawError,
                       match=r"at t = 0 s \(a step of 0\.001 s\): friction law NaNOnSlip\(\): "
                             r"return_map\(\) returned a non-finite shear force \(nan\)"):
        sim.run(0.05, progress=False)
    assert sim.control.steps == 0  # no step was taken, and no dt was cut for it


def test_a_law_newton_converges_with_only_where_nothing_slips_stops_the_run():
    """Its steps were accepted at ever smaller dt between failed tries above; a try that fails
    below dt / 2^cut_limit ends the run."""
    sim = dda.Simulation(_sliding(OverStrength(phi=30.0)), dt=1e-3,
                         solver=make_solver("newton"))
    floor = sim.control.dt * 2.0 ** -sim.control.cut_limit()
    with pytest.raises(dda.SimulationError,
                       match=r"failed, below the smallest a step is cut to, .* dt / 2\^12") as e:
        sim.run(0.05, progress=False)
    cuts = [dt for _, dt, _ in e.value.result.stats.cuts]
    assert cuts[-1] < floor <= min(cuts[:-1])  # the first try below the floor ends it
    assert sim.committed.time < 0.01


def test_a_law_with_a_flag_for_history_is_refused_at_the_joint():
    class Flagged(CoulombSingle):
        def history_fields(self):
            return {"g_se": 0.0, "slip": 0.0, "broken": False}

    with pytest.raises(TypeError, match=r"history field\(s\) \['broken'\] .*keep a flag as "
                                        r"0\.0 / 1\.0"):
        JointMaterial(1e9, 1e9, friction=Flagged(phi=30.0))


def test_a_history_field_given_as_a_0d_array_is_a_number():
    class ZeroD(CoulombSingle):
        def history_fields(self):
            return {"g_se": 0.0, "slip": np.asarray(0.0)}

    JointMaterial(1e9, 1e9, friction=ZeroD(phi=30.0))


def test_a_short_last_step_is_cut_as_ever_below_the_floor():
    """A run's last step shortened to what is left (1e-8 s, below dt / 2^12) that fails is
    cut and tried again, as before the floor; a working size below it ends the run."""
    from types import SimpleNamespace

    from dda.step_control import StepControl

    report = SimpleNamespace(untracked=0.0, reason="OPEN-CLOSE did not settle in 12 passes",
                             untracked_held=False)
    start = SimpleNamespace(time=0.01, untracked=0.0)
    control = StepControl(dt=1e-3)
    control.check_can_go_on(report, 1, 1e-8, start, short_step=True)  # no error
    with pytest.raises(dda.SimulationError, match="below the smallest a step is cut to"):
        control.check_can_go_on(report, 1, 1e-8, start)
