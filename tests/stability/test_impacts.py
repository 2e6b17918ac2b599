"""Impacts (issue 17): no vertex passes into another block untracked, and no impact ends with
more energy than it started with, for penalties from E/1e4 to 1000 E and dt from 1e-4 to
1e-2 s, under both solvers; concave corners (a lip, a notch, an L-shaped block) included.

Each case runs through ``watch``: after every step the energy (kinetic, potential, strain and
springs) must not exceed the start by more than 1 % of what the scene can set free, and the
deepest vertex inside another block, found geometrically, must be no deeper than the deepest
closed spring, give or take the guard's tolerance. dt 1e-4 is marked slow.
"""

import warnings
from dataclasses import replace

import pytest

import dda
from dda.registry import make_solver
from tests.stability import scenes
from tests.stability.watch import assert_tracked, watch

SOLVERS = ("newton", "legacy")  # run in this order; classes from dda.registry
E = scenes.IMPACT_E
PENALTIES = {"E/1e4": E / 1e4, "E/100": E / 100, "E": E, "1000 E": 1000 * E}
MATRIX = ["stopper", "block on block", "corner on corner", "notch"]
CONCAVE = ["lip", "L on a step", "low stopper"]
DTS = [pytest.param(1e-4, marks=pytest.mark.slow), 1e-3, 1e-2]


def run_impact(name, penalty, dt, solver, restitution=None):
    scene, duration = scenes.IMPACTS[name](penalty)
    if restitution is not None:
        scene.set_joint(replace(scene.default_joint, restitution=restitution))
    sim = dda.Simulation(scene, dt=dt, solver=make_solver(solver))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        w = watch(sim, duration, chunk=1)
    assert w.sim.state.time == pytest.approx(duration)
    return w, [str(c.message) for c in caught]


def assert_no_energy_gain(w):
    assert w.energy_gain <= 0.01, (
        f"energy rose by {w.energy_peak - w.energy0:.4g} J/m ({100 * w.energy_gain:.2f} % of "
        f"{w.scale:.4g})")


@pytest.mark.parametrize("solver", sorted(SOLVERS))
@pytest.mark.parametrize("dt", DTS)
@pytest.mark.parametrize("penalty", list(PENALTIES))
@pytest.mark.parametrize("name", MATRIX)
def test_impact_matrix(name, penalty, dt, solver):
    w, _ = run_impact(name, PENALTIES[penalty], dt, solver)
    assert_no_energy_gain(w)
    assert_tracked(w)


@pytest.mark.parametrize("solver", sorted(SOLVERS))
@pytest.mark.parametrize("dt", DTS)
@pytest.mark.parametrize("penalty", ["E/1e4", "E", "1000 E"])
@pytest.mark.parametrize("name", CONCAVE)
def test_impacts_into_concave_corners(name, penalty, dt, solver, request):
    if (name, penalty) == ("low stopper", "E/1e4") and dt != 1e-3:
        # the guard's edge probes (issue 20's session) see what the vertex guard did not:
        # the block tips over the stopper's top corner and its bottom-right corner region
        # hooks into the stopper's (its corner 4 mm past the stopper's side face, the
        # stopper's corner 0.4 mm past the block's side face, each held by that face), while
        # its bottom face crosses the stopper's top 23 mm deep over 12 cm, which no
        # vertex-edge pair holds; the run now stops there instead of finishing through it
        request.applymarker(pytest.mark.xfail(
            strict=True, raises=dda.SimulationError,
            reason="edge-edge overlap of two hooked corners: no vertex-edge contact holds it"))
    w, _ = run_impact(name, PENALTIES[penalty], dt, solver)
    assert_no_energy_gain(w)
    assert_tracked(w)


@pytest.mark.parametrize("solver", sorted(SOLVERS))
@pytest.mark.parametrize("name", MATRIX)
def test_impacts_with_a_dashpot_stay_tracked(name, solver):
    """With an impact dashpot that takes all of it (restitution 0) a rebounding contact lets
    go where its spring's and its dashpot's force cancel, its vertex still inside the other
    block (4.5 mm at E/1e4 in the stopper). The guard counts that open contact as holding
    the vertex at its gap (``dda.contact.penetration.released_depth``): before it did, the
    stopper, block-on-block and corner-on-corner impacts stopped with "untracked
    penetration" after 13 cuts. The watch checks it geometrically on its own."""
    w, _ = run_impact(name, PENALTIES["E/1e4"], 1e-3, solver, restitution=0.0)
    assert_no_energy_gain(w)
    assert_tracked(w)
