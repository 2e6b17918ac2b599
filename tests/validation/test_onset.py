"""The onset of sliding under static-to-dynamic friction (issue 20, item 1).

``StaticDynamicTransition`` starts a face sliding when the face's shear force reaches its static
strength (``onset="face"``, the default), as a rigid block does; the papers' per-contact rule
(``onset="contact"``) lets the lightly pressed end of a face that carries a moment yield first,
and the face unzips below its strength. Each case is checked against its rigid-block reference.
"""

import numpy as np
import pytest

import dda
from dda.contact import StaticDynamicTransition
from dda.registry import make_solver
from dda.studies.cases import relative_slip, shaken_incline, shear_box, shear_stress
from dda.studies.references import sliding_block

PHI_S, PHI_D = 40.0, 30.0
AMPLITUDE, FREQ, DIP = 0.5 * 9.81, 2.0, 20.0


def table(t):
    return (AMPLITUDE * np.sin(2 * np.pi * FREQ * t), 0.0)


def incline_slip(law, solver):
    """Final slide of the block down the shaken 20 deg incline after 2 s, the largest gap to
    the rigid block's slide over its final slide, and that rigid slide."""
    scene, lower, block, down = shaken_incline(law, table, dip=DIP)
    result = dda.Simulation(scene, dt=1e-3, solver=make_solver(solver)).run(2.0,
                                                                            progress=False)
    slip = relative_slip(result, lower, block, down)
    rigid = sliding_block(table, np.asarray(result.time), np.tan(np.radians(PHI_S)),
                          np.tan(np.radians(PHI_D)), dip=DIP).slip
    return slip[-1], np.abs(slip - rigid).max() / rigid[-1], rigid[-1]


@pytest.mark.parametrize("solver", ["newton", "legacy"])
def test_the_default_onset_slides_as_the_rigid_block(solver):
    slide, gap, rigid = incline_slip(StaticDynamicTransition(PHI_S, PHI_D), solver)
    assert rigid > 0.2  # a slide of 25 cm is compared
    # measured: Newton -0.10 %, legacy -0.80 % at the end; the largest gap is the end's
    assert slide == pytest.approx(rigid, rel=0.01)
    assert gap < 0.01


@pytest.mark.parametrize("solver", ["newton", "legacy"])
def test_the_per_contact_onset_slides_farther(solver):
    """The papers' rule, kept as an option: the block's rocking moment unzips its base early
    (measured: Newton +8.7 %, legacy +7.8 %)."""
    slide, _, rigid = incline_slip(StaticDynamicTransition(PHI_S, PHI_D, onset="contact"),
                                   solver)
    assert slide > 1.03 * rigid


def simple_shear_peak(law, solver):
    """METHOD.md's simple shear (phi 30 / 20, 1e11 N/m, nu 0, 0.3 mm in 150 steps after one
    consolidation step) with the upper block driven at its four corners through 1.5e8 N/m
    springs: the shear stress's peak and its last value (Pa)."""
    n = 150
    scene, lower, upper = shear_box(0.3e-3, friction=law, poisson=0.0, penalty=1e11,
                                    consolidation=1.0 / n, loading_stiffness=1.5e8,
                                    driven="corners")
    result = dda.Simulation(scene, dt=1.0 / n, solver=make_solver(solver),
                            analysis="static").run(1.0 + 1.0 / n, progress=False)
    tau = shear_stress(result, lower, upper)
    return tau.max(), tau[-1]


STATIC = 1e6 * np.tan(np.radians(30.0))  # 577.35 kPa
DYNAMIC = 1e6 * np.tan(np.radians(20.0))  # 363.97 kPa


@pytest.mark.parametrize("solver", ["newton", "legacy"])
def test_a_joint_under_a_moment_yields_at_its_static_strength(solver):
    peak, end = simple_shear_peak(StaticDynamicTransition(30.0, 20.0), solver)
    # measured -0.73 % (Newton), +0.95 % (legacy, which holds a sticking contact's spring for
    # the whole step: it overshoots by up to a step's 4 kPa of load, as in direct shear)
    assert peak == pytest.approx(STATIC, rel=0.01 if solver == "newton" else 0.015)
    assert end == pytest.approx(DYNAMIC, rel=0.005)
    peak, end = simple_shear_peak(StaticDynamicTransition(30.0, 20.0, onset="contact"), solver)
    assert peak < 0.95 * STATIC  # measured 512.4 kPa (Newton), 521.0 kPa (legacy)
    assert end == pytest.approx(DYNAMIC, rel=0.005)
