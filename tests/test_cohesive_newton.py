"""Newton-Raphson on cohesive joints: a contact that cycles between open and closed is held
closed while it pulls little (dda.solvers.newton.HOLD_CYCLING).

A cohesive joint's shear strength ``c l`` does not need a normal force, and it vanishes when
the contact opens: a contact that carries a shear force near ``c l`` at a normal force near
zero has no consistent state (closed, the iterate opens it; open, its block falls back in),
and Newton's iterates switched it until the step was cut to nothing.
"""

from __future__ import annotations

import numpy as np
import pytest

import dda
from dda.contact import CoulombLike, CoulombSingle, JointMaterial
from dda.contact.contacts import OPEN
from dda.errors import SimulationError
from dda.geometry import JointSet, cut_blocks
from dda.materials import LinearElastic
from dda.solvers import newton
from dda.solvers.open_close import CYCLE_TENSION

ROCK = LinearElastic(young=10e9, poisson=0.25, density=2600.0)


def cut_slope(cohesion: float, height: float = 4.0, law=None):
    """``examples/jointed_slope.py``'s rock mass cut ``height`` high (18 blocks at 4 m), on
    a fixed base against a fixed back wall, under gravity, joints of 5e10 N/m, phi 35 (or
    ``law``)."""
    toe, back = height, 3.0 * height
    mass = [(toe, 0.0), (back, 0.0), (back, height),
            (toe + height / np.tan(np.radians(59.0)), height)]
    sets = [JointSet(dip=-25.0, spacing=1.0, offset=0.3),
            JointSet(dip=70.0, spacing=1.6, persistence=0.8, trace_length=5.0)]
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(0, -3), (back + 4, -3), (back + 4, 0), (0, 0)], ROCK, fixed=True,
                    name="base")
    scene.add_block([(back, 0), (back + 4, 0), (back + 4, height + 2), (back, height + 2)],
                    ROCK, fixed=True, name="back")
    blocks = [scene.add_block(b, ROCK, name=f"rock{i}")
              for i, b in enumerate(cut_blocks(mass, sets, min_size=0.1, seed=0))]
    law = law or CoulombSingle(phi=35.0, cohesion=cohesion)
    scene.set_joint(JointMaterial(5e10, 5e10, law))
    return scene, blocks


def _run(monkeypatch, hold: bool, dense: bool, solver="newton", duration=0.06):
    monkeypatch.setattr(newton, "HOLD_CYCLING", hold)
    monkeypatch.setattr(newton, "DENSE_NEWTON", dense)
    monkeypatch.setattr(newton, "NEWTON_DENSE_STEP", dense)
    scene, blocks = cut_slope(1e6)
    sim = dda.Simulation(scene, dt=2e-3, solver=solver, max_open_close=30)
    result = sim.run(duration, progress=False)
    return sim, result, blocks


@pytest.mark.parametrize("dense", [False, True])
def test_without_the_hold_newton_stalls_on_a_cohesive_cut(monkeypatch, dense):
    """The failure the rule is for (both paths): the run stops within 0.01 s."""
    with pytest.warns(dda.PenaltyWarning), pytest.raises(SimulationError, match="cannot go on"):
        _run(monkeypatch, hold=False, dense=dense)


@pytest.mark.parametrize("dense", [False, True])
def test_held_newton_runs_a_cohesive_cut_as_legacy_dda_does(monkeypatch, dense):
    """With the hold, Newton runs the 0.06 s; the glued blocks move as little under it as under
    legacy DDA (1 MPa of cohesion holds every block: both well under a millimetre). Newton
    cuts more steps here: 15 in 256 steps against legacy DDA's 4 in 66."""
    sim, result, blocks = _run(monkeypatch, hold=True, dense=dense)
    _, legacy, _ = _run(monkeypatch, hold=True, dense=dense, solver="legacy")
    assert result.time[-1] == pytest.approx(0.06)
    moved = np.array([np.hypot(*result.displacement(b)[-1]) for b in blocks])
    moved_legacy = np.array([np.hypot(*legacy.displacement(b)[-1]) for b in blocks])
    assert moved.max() < 1e-3 and moved_legacy.max() < 1e-3
    assert np.median(moved) == pytest.approx(np.median(moved_legacy), rel=0.3, abs=2e-5)
    assert len(result.stats.cuts) <= 25


def test_both_paths_hold_alike(monkeypatch):
    """The dense kernel takes the composed iterate's holds: the same steps, cuts and end."""
    a, ra, _ = _run(monkeypatch, hold=True, dense=False, duration=0.03)
    b, rb, _ = _run(monkeypatch, hold=True, dense=True, duration=0.03)
    assert len(ra.stats) == len(rb.stats) and len(ra.stats.cuts) == len(rb.stats.cuts)
    np.testing.assert_array_equal(ra.stats["iterations"], rb.stats["iterations"])
    np.testing.assert_allclose(a.state.x, b.state.x, rtol=0, atol=1e-9)


def _held_tension(problem, sol):
    """The held contacts' pull and what it is measured against: the contacts a converged
    Newton step leaves closed whose gap is open, and the largest contact force (normal and
    shear) on their own blocks, the smaller of the two (free blocks only)."""
    el = problem.element
    closed = sol.contacts.state != OPEN
    resp = el.response(sol.d, held=closed)
    held = closed & ~el.response(sol.d).closed
    size = np.hypot(resp.force, resp.t_s)
    largest = np.zeros(len(problem.free))
    np.maximum.at(largest, el.bj, size)
    np.maximum.at(largest, el.bk, size)
    largest[~problem.free] = np.inf
    return resp.force[held], np.minimum(largest[el.bj], largest[el.bk])[held]


def test_a_held_contact_pulls_by_at_most_the_cycle_tension(monkeypatch):
    """Every step of the cohesive cut that converged with contacts held: each pulls by at
    most CYCLE_TENSION of the largest contact force on its own blocks (and some steps did
    hold). A held contact that pulls harder is let go: held for good, some pulled more."""
    captured = []
    original = newton.NewtonRaphson.iterate

    def capture(self, problem, d, max_iter=None, contraction=0.0):
        sol = original(self, problem, d, max_iter, contraction)
        if sol.converged:
            captured.append(_held_tension(problem, sol))
        return sol

    monkeypatch.setattr(newton.NewtonRaphson, "iterate", capture)
    _run(monkeypatch, hold=True, dense=False, duration=0.03)
    pulls = [(pull, largest) for pull, largest in captured if len(pull)]
    assert len(pulls) >= 3
    for pull, largest in pulls:
        assert np.all(pull <= CYCLE_TENSION * largest * (1 + 1e-9))


def test_both_paths_hold_alike_from_a_perturbed_start(monkeypatch):
    """From a start 0.1 mm off the predictor (the 3 x 3 stack of tests/test_dense_newton.py,
    without the reversed contacts' stick branch) contacts cycle in the first iterates and
    are held and let go: both paths take the same iterations to the same |R| (both end the
    25 at 175 N; without the hold they converged at the 25th)."""
    from tests.test_dense_newton import _both, _problem_and_start, perturbed_start

    problem, d = _problem_and_start(monkeypatch)
    monkeypatch.setattr(newton, "REVERSED_STICK", False)
    a, b = _both(problem, perturbed_start(problem, d), monkeypatch)
    assert a.converged == b.converged and a.iterations == b.iterations
    np.testing.assert_allclose(a.residual_norms, b.residual_norms, rtol=1e-6,
                               atol=1e-9 * max(a.residual_norms))


def test_a_held_response_is_the_same_through_a_law_written_in_numpy(monkeypatch):
    """The compiled response and the laws' numpy path hold alike: open contacts of the
    cohesive cut held closed pull by ``p_n g_n``, have the law's strength at zero normal force and
    no normal-shear coupling, and keep no tension as their normal force (the cut's joints
    have the default impact dashpot: its force and the spring's together pull)."""
    from tests.test_dense_newton import _problem_and_start

    scene, _ = cut_slope(1e4)
    problem, d = _problem_and_start(monkeypatch, scene=scene, step=2)
    el = problem.element
    rng = np.random.default_rng(5)
    d = d.copy()
    d[problem.free, :2] += 2e-6 * rng.standard_normal((np.count_nonzero(problem.free), 2))
    base = el.response(d)
    held = ~base.closed & (rng.random(len(el)) < 0.5)
    assert held.sum() >= 3
    compiled = el.response(d, held)
    el.__dict__["kernel_laws"] = None
    numpy_path = el.response(d, held)
    for a, b in ((compiled.closed, numpy_path.closed), (compiled.slipping, numpy_path.slipping)):
        np.testing.assert_array_equal(a, b)
    for a, b in ((compiled.force, numpy_path.force), (compiled.t_n, numpy_path.t_n),
                 (compiled.t_s, numpy_path.t_s), (compiled.residual, numpy_path.residual),
                 (np.asarray(compiled.stiffness), np.asarray(numpy_path.stiffness))):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-9)
    assert compiled.closed[held].all() and (compiled.force[held] > 0).all()
    assert (compiled.t_n[held] <= 0.0).all()  # the spring's own force (with the dashpot's)


class AbsoluteCoulomb(CoulombLike):
    """Coulomb friction written with ``|t_n|``, as a user may write it (no cohesion)."""

    def __init__(self, phi):
        self.mu = np.tan(np.radians(phi))

    def strength(self, t_n, length, history=None):
        return np.abs(t_n) * self.mu

    def strength_slope(self, t_n, length, history=None):
        return self.mu


def incline_with_a_far_block(far: bool):
    """A 0.5 x 1 m block on a 30 degree fixed incline (phi 20, cohesion 4 kPa: it slides and
    tips), and with ``far`` a 6 x 6 m block resting on its own fixed floor 20 m away."""
    th = np.radians(30.0)
    t = np.array([np.cos(th), np.sin(th)])
    n = np.array([-t[1], t[0]])
    scene = dda.Scene(gravity=9.81)
    scene.add_block([tuple(-4 * t), (4 * t[0], -4 * t[1]), tuple(4 * t)], ROCK, fixed=True)
    small = scene.add_block([tuple(p) for p in (-.25 * t, .25 * t, .25 * t + n, -.25 * t + n)],
                            ROCK)
    if far:
        scene.add_block([(20, -10), (30, -10), (30, -9), (20, -9)], ROCK, fixed=True)
        scene.add_block([(22, -9), (28, -9), (28, -3), (22, -3)],
                        LinearElastic(10e9, 0.25, 1000.0))
    scene.set_joint(JointMaterial(1e10, 1e10, CoulombSingle(phi=20.0, cohesion=4000.0)))
    return scene, small


@pytest.mark.parametrize("dense", [False, True])
def test_a_block_far_away_does_not_hold_a_contact(monkeypatch, dense):
    """A held contact's pull is measured against the forces on its own blocks: a heavy block
    20 m away, touching nothing of the incline, leaves the sliding block's 0.5 s as it is
    (measured against the scene's largest force, its contact was held at up to 1.04 kN/m,
    8% of the block's weight, in 496 of 500 steps and stopped it tipping: 8.6 mm of motion
    against 87.3 mm; a review, 2026-12-07)."""
    monkeypatch.setattr(newton, "DENSE_NEWTON", dense)
    monkeypatch.setattr(newton, "NEWTON_DENSE_STEP", dense)
    moved = []
    for far in (False, True):
        scene, small = incline_with_a_far_block(far)
        sim = dda.Simulation(scene, dt=1e-3, solver="newton", max_open_close=30)
        result = sim.run(0.5, progress=False)
        moved.append(np.hypot(*result.displacement(small)[-1]))
    assert moved[0] > 0.05
    assert moved[1] == pytest.approx(moved[0], rel=1e-6)


def test_a_held_contacts_pull_is_no_compression_to_a_users_law(monkeypatch):
    """A law written with ``|t_n|`` gets a held contact's normal force as zero, not as its
    pull: without cohesion a held contact carries no shear force."""
    from tests.test_dense_newton import _problem_and_start

    scene, _ = cut_slope(0.0, law=AbsoluteCoulomb(35.0))
    problem, d = _problem_and_start(monkeypatch, scene=scene, step=2)
    el = problem.element
    assert el.kernel_laws is None
    rng = np.random.default_rng(5)
    d = d.copy()
    d[problem.free] += 2e-6 * rng.standard_normal((np.count_nonzero(problem.free), 6))
    held = ~el.response(d).closed
    resp = el.response(d, held)
    assert (resp.force[held] > 0).sum() >= 3
    np.testing.assert_array_equal(resp.t_s[held & (resp.force > 0)], 0.0)
