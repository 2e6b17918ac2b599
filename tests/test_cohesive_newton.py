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
    legacy DDA (1 MPa of cohesion holds every block: both well under a millimetre)."""
    sim, result, blocks = _run(monkeypatch, hold=True, dense=dense)
    _, legacy, _ = _run(monkeypatch, hold=True, dense=dense, solver="legacy")
    assert result.time[-1] == pytest.approx(0.06)
    moved = np.array([np.hypot(*result.displacement(b)[-1]) for b in blocks])
    moved_legacy = np.array([np.hypot(*legacy.displacement(b)[-1]) for b in blocks])
    assert moved.max() < 1e-3 and moved_legacy.max() < 1e-3
    assert np.median(moved) == pytest.approx(np.median(moved_legacy), rel=0.3, abs=2e-5)
    assert len(result.stats.cuts) <= 2 * len(legacy.stats.cuts) + 5


def test_both_paths_hold_alike(monkeypatch):
    """The dense kernel takes the composed iterate's holds: the same steps, cuts and end."""
    a, ra, _ = _run(monkeypatch, hold=True, dense=False, duration=0.03)
    b, rb, _ = _run(monkeypatch, hold=True, dense=True, duration=0.03)
    assert len(ra.stats) == len(rb.stats) and len(ra.stats.cuts) == len(rb.stats.cuts)
    np.testing.assert_array_equal(ra.stats["iterations"], rb.stats["iterations"])
    np.testing.assert_allclose(a.state.x, b.state.x, rtol=0, atol=1e-9)


def _held_tension(problem, sol):
    """The held contacts' pull over the iterate's largest normal force: the contacts a
    converged Newton step leaves closed whose gap is open, and the largest normal force."""
    el = problem.element
    closed = sol.contacts.state != OPEN
    force = el.response(sol.d, held=closed).force
    held = closed & ~el.response(sol.d).closed
    return force[held], float(np.max(np.abs(force)))


def test_a_held_contact_pulls_by_at_most_the_cycle_tension(monkeypatch):
    """Every step of the cohesive cut that converged with contacts held: each pulls by at
    most CYCLE_TENSION of the largest normal force (and some steps did hold)."""
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
        assert pull.max() <= CYCLE_TENSION * largest * (1 + 1e-9)


def test_a_contact_held_early_lets_go_when_it_pulls_harder(monkeypatch):
    """From a start 0.1 mm off the predictor (the 3 x 3 stack of tests/test_dense_newton.py,
    without the reversed contacts' stick branch) contacts cycle in the first iterates and
    are held; those that later pull by more than CYCLE_TENSION let go, and both paths
    converge alike (held for good, the iterations did not converge in 25, and the answer's
    held contacts pulled 3.6% of the largest force)."""
    from tests.test_dense_newton import _both, _problem_and_start

    problem, d = _problem_and_start(monkeypatch)
    monkeypatch.setattr(newton, "REVERSED_STICK", False)
    rng = np.random.default_rng(3)
    start = d.copy()
    free = problem.free
    start[free, :2] += 1e-4 * rng.standard_normal((np.count_nonzero(free), 2))
    start[free, 2] += 1e-5 * rng.standard_normal(np.count_nonzero(free))
    a, b = _both(problem, start, monkeypatch)
    assert a.converged and b.converged and a.iterations == b.iterations
    pull, largest = _held_tension(problem, a)
    assert len(pull) and pull.max() <= CYCLE_TENSION * largest * (1 + 1e-9)


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
