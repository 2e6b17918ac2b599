"""Newton's cycles through more than two contact patterns (``dda.solvers.newton.CYCLE_LENGTH``).

With the joints' impact dashpot a resting contact lets go close to its own gap and its friction
sees the dashpot's force, and on a pile of blocks settling Newton's full steps went round
three and four contact patterns (|R| 293, 220, 270, 135 N, 293, ...) until the step was cut.
Halving a step that comes back to any of the last ``CYCLE_LENGTH`` patterns, not only to the
one two steps back, took the cut steps of three such piles (0.2 s) from 67 / 65 / 58 to
30 / 32 / 40. That was without the joints' shear dashpot (``JointMaterial.shear_dashpot``, on
by default since), which the pile here keeps off: with it the pile below cuts 27 steps with
cycles of two and 22 with cycles of up to eight, the dashpot having damped most of the cycles.

Both measured without the turned contacts' stick branch (``newton.REVERSED_STICK``), which came
after: with it the pile takes no cut for Newton at either cycle length (0.2 s: 1,716 steps and
36 cuts, all OPEN-CLOSE, 20 s of CPU; without it 2,324 steps, 70 cuts, 34 of them Newton's,
31 s with cycles of two, and 1,778 steps, 32 cuts, 3 Newton's, 25 s with cycles of up to eight).
"""

import warnings
from dataclasses import replace

import pytest

import dda
from dda.registry import make_solver
from tests.stability import scenes


def _cuts(monkeypatch, cycle_length, reversed_stick=False):
    """The pile's cut steps over 0.2 s: (all, Newton's)."""
    from dda.solvers import newton

    monkeypatch.setattr(newton, "CYCLE_LENGTH", cycle_length)
    monkeypatch.setattr(newton, "REVERSED_STICK", reversed_stick)
    scene, dt, _, _ = scenes.pile(1000, columns=24)
    scene.set_joint(replace(scene.default_joint, shear_dashpot=False))
    sim = dda.Simulation(scene, dt=dt, solver=make_solver("newton"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", dda.PenaltyWarning)
        result = sim.run(0.2, progress=False)
    cuts = result.stats.cuts
    return len(cuts), sum("Newton" in c[2] for c in cuts)


@pytest.mark.slow
def test_newton_halves_steps_that_cycle_through_several_patterns(monkeypatch):
    two = _cuts(monkeypatch, 2)[0]
    longer = _cuts(monkeypatch, 8)[0]
    assert longer <= 0.6 * two, (two, longer)


@pytest.mark.slow
def test_the_stick_branch_leaves_the_pile_no_newton_cut(monkeypatch):
    cuts, newton_cuts = _cuts(monkeypatch, 8, reversed_stick=True)
    assert newton_cuts == 0, cuts
