"""The fully implicit method's predictor settles once its open and closed states stand
(``dda.solvers.open_close.LAG_PATIENCE``), whatever its friction does.

The 1,000-brick running-bond wall of ``benchmarks/scaling.py`` settling from a touching start:
at t = 9 ms one step's predictor had its open and closed states from pass 4 on, then switched
one contact between stick and slip and found 10 to 17 sliding contacts' lagged normal forces
off in every pass until the limit of 30 cut the step. That was without the joints' shear
dashpot (``JointMaterial.shear_dashpot``, on by default since), which the wall here keeps off:
with it the same step settles in time without the rule.

That cycle went through a sliding contact whose lagged normal force was zero: Shi's rule (a
slip whose trial force turns against the pass's friction load sticks) read the zero load as a
reversal. With a zero load left to the law, the step settles in 8 passes without the rule too;
the rule stays, for cycles of the lagged forces themselves.
"""

import sys
from pathlib import Path

import dda
import dda.solvers.open_close as oc
from dda.contact import CoulombSingle, JointMaterial
from dda.solvers import NewtonRaphson

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from scaling import wall  # noqa: E402

STEPS = 10


class PlainCoulomb(CoulombSingle):
    """The built-in law as a user's own: no compiled kernel, the numpy passes."""


def _run(law=None):
    scene = wall(1000)
    law = law if law is not None else scene.default_joint.friction
    scene.set_joint(JointMaterial(normal_penalty=1e10, shear_penalty=1e10, friction=law,
                                  shear_dashpot=False))
    sim = dda.Simulation(scene, dt=1e-3, solver=NewtonRaphson(), max_open_close=30)
    return sim.run(STEPS * 1e-3, progress=False)


def test_the_wall_settles_without_a_cut_step():
    result = _run()
    assert result.stats.cuts == []
    assert len(result.stats) == STEPS


def test_the_numpy_passes_follow_the_same_rule():
    result = _run(PlainCoulomb(phi=35.0))
    assert result.stats.cuts == []


def test_without_the_rule_the_step_settles_too(monkeypatch):
    """(It was cut at 9 ms: see the module docstring.)"""
    with_rule = _run()
    monkeypatch.setattr(oc, "LAG_PATIENCE", 10**6)
    without = _run()
    assert without.stats.cuts == []
    assert list(without.stats["open_close_passes"]) == list(with_rule.stats["open_close_passes"])
    assert max(without.stats["open_close_passes"]) <= 8
