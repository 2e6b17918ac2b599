"""A single 15 x 45 cm block of the stacked cubes' concrete on a shaken base, against the
rigid-block rocking theory (Housner 1963, integrated in time:
:func:`dda.studies.references.housner_shaken`).

The table is the stacked cubes' ramped sine (:func:`dda.studies.cases.ramped_sine`, 2 s).
At penalty 1e8 N/m with the impact dashpot at restitution 0 (the corner that strikes does not
bounce, Housner's assumption) DDA's peak rotation is within 2.6% of the theory's in these
three cases, under both solvers at dt 1e-3, and the block lifts off at the same time (within
5 ms) to the same side. Over the eight shaking cases of the stacked cubes (4 s) the same
holds within 2.6% wherever the block rocks, and neither theory nor DDA topples it
(``examples/stacked_cubes.py`` has the table).
"""

import numpy as np
import pytest

import dda
from dda.registry import make_solver
from dda.studies.cases import ramped_sine, rocking_block
from dda.studies.references import housner_shaken

WIDTH, HEIGHT, SHAKE, END = 0.15, 0.45, 2.0, 2.5


@pytest.mark.parametrize("solver", ["legacy", "newton"])
@pytest.mark.parametrize("freq, gal", [(3.0, 400.0), (3.0, 700.0), (5.0, 700.0)])
def test_a_shaken_block_rocks_as_the_rigid_block_theory(freq, gal, solver):
    table = ramped_sine(freq, gal, stop=SHAKE)
    theory = housner_shaken(WIDTH, HEIGHT, table, END)
    scene, block = rocking_block(0.0, 1e8, 0.0, WIDTH, HEIGHT, table=table)
    result = dda.Simulation(scene, dt=1e-3, solver=make_solver(solver)).run(END)
    rotation, time = np.asarray(result.rotation(block)), np.asarray(result.time)
    assert not theory.toppled
    assert np.abs(rotation).max() == pytest.approx(theory.peak, rel=0.05)
    lift = np.radians(0.1)
    i = np.flatnonzero(np.abs(rotation) > lift)[0]
    j = np.flatnonzero(np.abs(theory.rotation) > lift)[0]
    assert time[i] == pytest.approx(theory.time[j], abs=0.01)
    assert np.sign(rotation[i]) == np.sign(theory.rotation[j])
