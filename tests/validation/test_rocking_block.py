"""Housner's rocking block (issue 20, item 3): impacts that do not depend on dt.

A 15 x 45 cm concrete block released from half its critical tilt on a fixed base
(:func:`dda.studies.cases.rocking_block`), 1.3 s: four impacts. With the joint's impact dashpot
at ``restitution=0``, the default (the corner that strikes does not bounce, Housner's
assumption), each impact keeps the share of the rocking amplitude that Housner's coefficient
of restitution gives (:func:`dda.studies.references.housner_rocking`), within 5%, at dt 1e-3
and 1e-4 and under both solvers. Without the dashpot the same block keeps 19-25% more at dt
1e-4 than Housner: the penalty impact alone loses what Newmark's gamma = 1 takes, which
depends on dt.

Measured (amplitude ratio per impact against Housner's, penalty 1e8 N/m):

| solver | dt | impacts 1-4 |
|---|---|---|
| legacy | 1e-3 | -1.2% -2.4% -1.8% -2.8% |
| legacy | 1e-4 | +0.2% -0.1% -0.1% -0.4% |
| Newton | 1e-3 | -1.0% -3.4% -4.1% -2.4% |
| Newton | 1e-4 | +0.5% +0.3% +0.2% -0.1% |
| legacy, no dashpot | 1e-4 | +24.5% +20.6% +19.3% +18.5% |
"""

import numpy as np
import pytest

import dda
from dda.studies.cases import rocking_amplitudes, rocking_block
from dda.studies.references import housner_rocking

WIDTH, HEIGHT = 0.15, 0.45
ALPHA = np.arctan(WIDTH / HEIGHT)
TILT = 0.5 * ALPHA
PENALTY = 1e8  # 5 x the stacked cubes' (A's) 2e7: at 2e7 the block rocks on soft corners
IMPACTS = 4


def rocking_ratios(solver, dt, restitution):
    """The amplitude kept at each of the first IMPACTS impacts, over Housner's."""
    scene, block = rocking_block(TILT, PENALTY, restitution)
    solver = dda.solvers.NewtonRaphson() if solver == "newton" else dda.solvers.LegacyPullBack()
    result = dda.Simulation(scene, dt=dt, solver=solver).run(1.3, progress=False)
    amplitudes = rocking_amplitudes(result.time, result.rotation(block), TILT)
    assert len(amplitudes) >= IMPACTS, amplitudes / ALPHA
    ours = np.concatenate([[TILT], amplitudes[:IMPACTS]])
    housner = housner_rocking(WIDTH, HEIGHT, TILT, IMPACTS)
    return (ours[1:] / ours[:-1]) / (housner[1:] / housner[:-1]), result


@pytest.mark.parametrize("solver", ["legacy", "newton"])
@pytest.mark.parametrize("dt", [1e-3, 1e-4])
def test_by_default_each_impact_keeps_housners_share(solver, dt):
    """The joint's default impact dashpot (restitution 0), at dt 1e-3 and 1e-4 alike."""
    ratios, result = rocking_ratios(solver, dt, restitution=None)
    assert np.all(np.abs(ratios - 1.0) < 0.05), ratios
    assert len(result.stats.cuts) == 0


def test_without_it_the_rocking_depends_on_dt():
    """The negative control: the elastic penalty impact at dt 1e-4 keeps far more (its
    slower decay leaves the fourth swing unfinished at 1.3 s: three impacts)."""
    ratios, _ = rocking_ratios("legacy", 1e-4, restitution=1.0)
    assert np.all(ratios[:3] > 1.15), ratios


def test_the_reference_sequence_is_housners():
    """Independent of the code under test: the first rebound from energy and momentum."""
    r = 1.0 - 1.5 * np.sin(ALPHA) ** 2  # 0.85 for a 1 : 3 block
    assert r == pytest.approx(0.85)
    # the kinetic energy at the first impact, times r^2, lifts the centroid again
    radius = 0.5 * np.hypot(WIDTH, HEIGHT)
    energy = radius * (np.cos(ALPHA - TILT) - np.cos(ALPHA))  # per m g
    lifted = housner_rocking(WIDTH, HEIGHT, TILT, 1)[1]
    assert radius * (np.cos(ALPHA - lifted) - np.cos(ALPHA)) == pytest.approx(r * r * energy)
