"""Rock bolts (issue 23, item 1): the bolt's terms, equilibrium, breaking, pretension, the
scene file, checkpoints and bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import dda
import dda.step as step_module
from dda.bolts import BoltTable, BoltTerm, moved_points
from dda.contact import CoulombSingle, JointMaterial
from dda.contact.tangent import _TANGENT_TERMS, SPRING_TERMS
from dda.effects import TimeTable
from dda.geometry import t_matrix
from dda.io.scene_data import ArrayStore, scene_from_data, scene_to_data
from dda.io.scene_file import SceneFileError, load_scene
from dda.kernels import small_step
from dda.kernels.pair_stiffness import PairStiffness
from dda.materials import LinearElastic
from dda.solvers import LegacyPullBack, NewtonRaphson, linear
from tests.conftest import box, incline_scene

G = 9.81
SOLVERS = [LegacyPullBack(), NewtonRaphson()]
SOLVER_IDS = ["legacy", "newton"]
SLOPE, PHI = 30.0, 20.0
# the incline block of tests.conftest.incline_scene: 0.5 m square, density 2500
WEIGHT = 2500.0 * 0.25 * G


# ---------------------------------------------------------------------- the bolt's terms
def _energy(d, points, centroid, k, pretension, length0):
    """W(d) = 1/2 k (L - L0)^2 + P L of a bolt whose ends move by T d (dda.bolts)."""
    ta = t_matrix(points[:1], centroid[:1])[0]
    tb = t_matrix(points[1:], centroid[1:])[0]
    xa = points[0] + ta @ d[:6]
    xb = points[1] + tb @ d[6:]
    length = np.hypot(*(xb - xa))
    return 0.5 * k * (length - length0) ** 2 + pretension * length


@pytest.mark.parametrize("stretch", [1.3, 0.6], ids=["tension", "compression"])
def test_bolt_terms_are_the_energy_derivatives(stretch):
    """f_bolt = -dW/dd and K_bolt = d2W/dd2 at the step's start (central differences)."""
    points = np.array([[0.3, 0.2], [1.4, -0.5]])
    centroid = np.array([[0.1, 0.4], [1.2, -0.9]])
    length = np.hypot(*(points[1] - points[0]))
    k, pretension = 2.0e6, 3.0e4
    length0 = length / stretch
    n0 = pretension + k * (length - length0)
    assert (n0 > 0) == (stretch > 1)
    term = BoltTerm.build(np.array([0]), np.array([1]), points[None], centroid,
                          np.array([k]), np.array([n0]))
    args = (points, centroid, k, pretension, length0)
    h = 1e-6
    eye = np.eye(12)
    grad = np.array([(_energy(h * e, *args) - _energy(-h * e, *args)) / (2 * h) for e in eye])
    np.testing.assert_allclose(-term.force[0], grad, rtol=1e-7, atol=1e-6 * abs(n0))
    h = 1e-4
    hess = np.array([[(_energy(h * (ei + ej), *args) - _energy(h * (ei - ej), *args)
                       - _energy(h * (ej - ei), *args) + _energy(-h * (ei + ej), *args))
                      / (4 * h * h) for ej in eye] for ei in eye])
    stiffness = term.stiffness()[0]
    np.testing.assert_allclose(stiffness, hess, rtol=1e-5, atol=1e-6 * k)
    np.testing.assert_allclose(stiffness, stiffness.T, rtol=0, atol=1e-12 * k)  # symmetric
    # the residual is the quadratic model's gradient: K d - f
    d = np.linspace(-1e-3, 1e-3, 12)
    np.testing.assert_allclose(term.residual(d.reshape(2, 6))[0],
                               stiffness @ d - term.force[0], rtol=1e-12)


def test_the_compiled_terms_are_the_numpy_ones():
    """dda.kernels.bolts against BoltTerm.build and moved_points (numpy, the reference)."""
    scene, top, t = bolted_incline(20.0, stiffness=3e7)
    scene.add_bolt(top, 2.5 * t + (0.1, 0.1), "base", 2.5 * t - (0.1, 0.3), stiffness=2e6,
                   pretension=1e4)
    model = dda.Simulation(scene, dt=1e-3).model
    rng = np.random.default_rng(3)
    points = model.bolts.points + rng.normal(scale=1e-3, size=(2, 2, 2))
    centroid = model.centroid_initial + rng.normal(scale=1e-3, size=(2, 2))
    for broken in ([False, False], [True, False]):
        broken = np.array(broken)
        term = model.bolts.term(points, broken, centroid)
        keep = ~broken
        length = np.hypot(*(points[keep, 1] - points[keep, 0]).T)
        n0 = model.bolts.pretension[keep] + model.bolts.stiffness[keep] * (
            length - model.bolts.length[keep])
        ref = BoltTerm.build(model.bolts.blocks[keep, 0], model.bolts.blocks[keep, 1],
                             points[keep], centroid, model.bolts.stiffness[keep], n0)
        for name in ("bj", "bk", "rows", "weights", "force"):
            np.testing.assert_allclose(getattr(term, name), getattr(ref, name), rtol=1e-14,
                                       atol=1e-14 * np.abs(getattr(ref, name)).max())
        np.testing.assert_array_equal(term.index, np.flatnonzero(keep))
    assert model.bolts.term(points, np.array([True, True]), centroid) is None
    d = rng.normal(scale=1e-2, size=(2, 6))
    np.testing.assert_allclose(model.bolts.moved(points, centroid, d),
                               moved_points(points, model.bolts.blocks, centroid, d),
                               rtol=1e-15, atol=1e-15)


@pytest.mark.parametrize("terms, rows", [(SPRING_TERMS, 2), (_TANGENT_TERMS, 5)],
                         ids=["legacy springs", "newton tangent"])
def test_joined_stiffness_is_the_contacts_then_the_bolts(terms, rows):
    """The bolts' rows join a PairStiffness of either layout (the compiled assembly) and
    give the same 12 x 12 matrices as the arrays joined."""
    rng = np.random.default_rng(1)
    m = 3
    contacts = PairStiffness(rng.normal(size=(m, rows, 12)), terms,
                             rng.normal(size=(m, len(terms))))
    pts = rng.normal(size=(2, 2, 2))
    term = BoltTerm.build(np.array([0, 2]), np.array([1, 0]), pts, rng.normal(size=(3, 2)),
                          np.array([1e6, 2e6]), np.array([5e3, -2e3]))
    f = rng.normal(size=(m, 12))
    joined_k, joined_f = term.joined(contacts, f)
    assert isinstance(joined_k, PairStiffness)
    expected = np.concatenate([contacts.dense(), term.stiffness()])
    np.testing.assert_allclose(joined_k.dense(), expected, rtol=1e-13, atol=1e-9)
    np.testing.assert_array_equal(joined_f, np.concatenate([f, term.force]))
    dense_k, _ = term.joined(contacts.dense(), f)
    np.testing.assert_allclose(dense_k, expected, rtol=1e-13, atol=1e-9)


# ---------------------------------------------------------------------- equilibrium
def bolted_incline(beta_deg, stiffness, strength=None, phi=PHI, length=0.8):
    """The incline of tests.conftest (0.5 m block on a 30 degree slope, phi 20) with one bolt
    from the block's up-slope lower corner to the base, ``beta_deg`` into the slope from the
    up-slope direction. Returns the scene, the block, the slope direction and the bolt's
    direction angle."""
    scene, top, t = incline_scene(phi=phi, slope_deg=SLOPE)
    n = np.array([-t[1], t[0]])
    beta = np.radians(beta_deg)
    # on the block's lower face for a bolt along the slope; a little above it otherwise
    point_a = 2.5 * t + 0.45 * t + (0.0 if beta_deg == 0 else 0.1) * n
    point_b = point_a + length * (np.cos(beta) * t - np.sin(beta) * n)
    scene.add_bolt(top, point_a, "base", point_b, stiffness=stiffness, strength=strength)
    return scene, top, t


def held_tension(beta_deg, phi=PHI):
    """The bolt force that holds the block with the friction fully mobilized up the slope.

    The bolt pulls the block with T along e = cos(beta) t - sin(beta) n (t up the slope, n
    out of it: beta > 0 pulls the block into the joint). The joint carries the normal force
    N = W cos(theta) + T sin(beta) and, the block creeping down, the friction tan(phi) N up
    the slope; along the slope W sin(theta) = T cos(beta) + tan(phi) N, so

        T = W (sin(theta) - cos(theta) tan(phi)) / (cos(beta) + sin(beta) tan(phi)).
    """
    th, ph, b = np.radians(SLOPE), np.radians(phi), np.radians(beta_deg)
    return WEIGHT * (np.sin(th) - np.cos(th) * np.tan(ph)) / (np.cos(b) + np.sin(b) * np.tan(ph))


@pytest.mark.parametrize("beta", [0.0, 20.0])
@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_bolt_holds_the_block_with_the_rigid_block_equilibrium_force(solver, beta):
    """A block on a joint steeper than its friction angle held by one bolt to the fixed
    base: the bolt force is the equilibrium value of :func:`held_tension` within 1%.

    The static analysis (velocity reset every step) makes the state unique: the block creeps
    down until the bolt holds it with the friction fully mobilized (a dynamic run may come
    to rest with the friction anywhere below its limit)."""
    scene, top, t = bolted_incline(beta, stiffness=1e8)
    sim = dda.Simulation(scene, dt=1e-3, solver=solver, analysis="static")
    result = sim.run(0.3)
    force = result.bolt_force(0)
    expected = held_tension(beta)
    assert force[-1] == pytest.approx(expected, rel=1e-3)  # the issue asks 1%; 4e-6 here
    assert abs(force[-1] - force[-20]) < 1e-4 * expected  # at rest
    assert not result.bolt_broken(0).any()
    # it crept down: the bolt stretched by its force over its stiffness
    assert result.displacement(top)[-1] @ t < 0


# ---------------------------------------------------------------------- breaking
@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_bolt_breaks_where_its_force_would_exceed_the_strength(solver):
    """With a strength below the equilibrium force the bolt breaks at the step where an
    unbreakable bolt's force first exceeds it (the runs are the same to the bit before),
    never carries more than its strength, nothing after; the block then slides as an
    unbolted one does, at g (sin(theta) - cos(theta) tan(phi))."""
    strength = 0.5 * held_tension(0.0)
    runs = {}
    for s in (None, strength):
        scene, top, t = bolted_incline(0.0, stiffness=1e6, strength=s)
        runs[s] = dda.Simulation(scene, dt=1e-3, solver=solver).run(0.6)
    whole, broken = runs[None], runs[strength]
    over = np.flatnonzero(whole.bolt_force(0) > strength)
    assert len(over)
    first = int(over[0])
    assert 10 < first < 100
    flags = broken.bolt_broken(0)
    assert not flags[:first].any() and flags[first:].all()
    np.testing.assert_array_equal(broken.bolt_force(0)[:first], whole.bolt_force(0)[:first])
    assert np.all(broken.bolt_force(0)[:first] <= strength)
    assert np.all(broken.bolt_force(0)[first:] == 0.0)
    # after the break: the Coulomb acceleration of a free block (Newmark's beta 0.5 is exact
    # for a constant acceleration: 1e-11 here)
    time = broken.time
    s = broken.displacement(top) @ t
    late = time > time[first] + 0.1
    accel = -2 * np.polyfit(time[late], s[late], 2)[0]
    expected = G * (np.sin(np.radians(SLOPE)) - np.cos(np.radians(SLOPE))
                    * np.tan(np.radians(PHI)))
    assert accel == pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_a_break_lives_in_the_trial_state(solver):
    """The step in which a bolt breaks changes none of its inputs: the broken flag is the
    trial's, stepping again gives the same trial, and a refused step breaks nothing."""
    import copy

    from dda.step import StepSettings, step
    from tests.test_pure_step import _same

    scene, top, t = bolted_incline(0.0, stiffness=1e6, strength=0.5 * held_tension(0.0))
    sim = dda.Simulation(scene, dt=1e-3, solver=solver)
    sim.run(0.026)  # the bolt breaks in step 27
    state = sim.committed
    assert not state.bolt_broken.any()
    before = copy.deepcopy(state)
    trial, report = step(sim.model, state, 1e-3, solver)
    assert report.converged and trial.bolt_broken.tolist() == [True]
    assert trial.bolt_forces(sim.model).tolist() == [0.0]
    _same(vars(state), vars(before))
    again, _ = step(sim.model, state, 1e-3, solver)
    _same(vars(again), vars(trial))
    refused, report = step(sim.model, state, 1e-3, solver,
                           StepSettings(max_displacement_ratio=1e-12))
    assert refused is None
    _same(vars(state), vars(before))


def _series(strengths):
    """A block hung from a middle block, hung from a fixed roof: two bolts in series, 1e6
    N/m each; the static analysis at dt 0.1 s takes the blocks most of the way to their
    equilibrium in the first step (bolt 0 carries both weights, bolt 1 the lower one)."""
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=G)
    scene.add_block(box(0, 2, 1, 0.5), rock, fixed=True, name="roof")
    middle = scene.add_block(box(0.25, 1.2, 0.5, 0.5), rock, name="middle")
    low = scene.add_block(box(0.25, 0.4, 0.5, 0.5), rock, name="low")
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=30.0)))
    scene.add_bolt(middle, (0.5, 1.6), "roof", (0.5, 2.2), stiffness=1e6,
                   strength=strengths[0])
    scene.add_bolt(low, (0.5, 0.8), middle, (0.5, 1.3), stiffness=1e6, strength=strengths[1])
    return scene


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_two_bolts_overloaded_in_one_step_break_one_at_a_time(solver):
    """Both bolts of a series would exceed their strength in the first step: the more
    overloaded (the lower one) breaks, the step is solved again, and the upper one, unloaded
    by the break (it now carries one block), holds."""
    weight = 2500.0 * 0.25 * G
    strengths = (1.5 * weight, 0.7 * weight)
    whole = dda.Simulation(_series((None, None)), dt=0.1, solver=solver,
                           analysis="static").run(0.3)
    ratios = [whole.bolt_force(i)[1] / strengths[i] for i in (0, 1)]
    assert 1.0 < ratios[0] < ratios[1]  # both over in step 1, the lower one more
    result = dda.Simulation(_series(strengths), dt=0.1, solver=solver,
                            analysis="static").run(0.3)
    assert result.bolt_broken(1)[1:].all() and not result.bolt_broken(0).any()
    assert np.all(result.bolt_force(0) <= strengths[0])
    assert result.bolt_force(0)[-1] == pytest.approx(weight, rel=0.05)


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_bolts_between_free_blocks_dense_and_sparse(solver, monkeypatch):
    """The series of two bolts (one between two free blocks) without strengths: the upper
    one ends carrying both blocks, the lower one its block; the sparse assembly
    (``DENSE_LIMIT`` 0) gives the dense one's numbers."""
    weight = 2500.0 * 0.25 * G
    runs = []
    for limit in (linear.DENSE_LIMIT, 0):
        monkeypatch.setattr(linear, "DENSE_LIMIT", limit)
        # (a solver of its own: a solver keeps its last system's layout)
        sim = dda.Simulation(_series((None, None)), dt=0.1, solver=type(solver)(),
                             analysis="static")
        runs.append(sim.run(2.0))
    dense, sparse = runs
    for i, load in ((0, 2 * weight), (1, weight)):
        # (the bolts stretch the blocks, whose weight grows with their area: 1e-5)
        assert dense.bolt_force(i)[-1] == pytest.approx(load, rel=1e-4)
        np.testing.assert_allclose(sparse.bolt_force(i), dense.bolt_force(i), rtol=1e-9)


def test_a_bolt_to_a_moved_block_follows_its_motion():
    """A block hung by a bolt from a roof whose motion is prescribed (a known block: its
    increment goes to the right-hand side): the block follows the roof up by 0.1 m and hangs
    W / k below where it started."""
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=G)
    roof = scene.add_block(box(0, 2, 1, 0.5), rock, name="roof")
    low = scene.add_block(box(0.25, 1.0, 0.5, 0.5), rock, name="low")
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=30.0)))
    scene.prescribe_motion(roof, TimeTable([0.0, 0.5, 10.0], x=[0.0, 0.0, 0.0],
                                           y=[0.0, 0.1, 0.1]))
    k = 1e6
    scene.add_bolt(low, (0.5, 1.25), roof, (0.5, 2.25), stiffness=k)
    result = dda.Simulation(scene, dt=0.02, analysis="static").run(2.0)
    weight = 2500.0 * 0.25 * G
    assert result.bolt_force(0)[-1] == pytest.approx(weight, rel=1e-6)
    assert result.displacement(low)[-1, 1] == pytest.approx(0.1 - weight / k, rel=1e-6)


def _moved_roof_scene():
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=G)
    roof = scene.add_block(box(0, 2, 1, 0.5), rock, name="roof")
    low = scene.add_block(box(0.25, 1.0, 0.5, 0.5), rock, name="low")
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=30.0)))
    scene.prescribe_motion(roof, TimeTable([0.0, 0.5, 10.0], x=[0.0, 0.02, 0.02],
                                           y=[0.0, 0.1, 0.1]))
    scene.add_bolt(low, (0.4, 1.25), roof, (0.6, 2.25), stiffness=1e6, pretension=500.0)
    return scene


@pytest.mark.parametrize("make", [lambda: bolted_incline(20.0, stiffness=1e8)[0],
                                  _moved_roof_scene], ids=["fixed anchor", "moved anchor"])
@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_anchored_bolts_fold_into_their_block_as_the_coupling_would(make, solver,
                                                                    monkeypatch):
    """A bolt anchored in a known block, folded into its free block's matrix and forces
    (dda.kernels.bolts.fold_anchored), runs as the same bolt coupled through the system's
    pattern with the known block's increment on the right-hand side."""
    runs = []
    for fold in (True, False):
        if not fold:
            monkeypatch.setattr(BoltTable, "system",
                                lambda self, points, broken, centroid, free, k, f, dk:
                                (k, f, self.term(points, broken, centroid)))
        sim = dda.Simulation(make(), dt=1e-3, solver=type(solver)())
        runs.append((sim.run(0.1), sim.state))
    (folded, a), (coupled, b) = runs
    np.testing.assert_allclose(folded.bolt_force(0), coupled.bolt_force(0), rtol=1e-7,
                               atol=1e-9 * np.abs(coupled.bolt_force(0)).max())
    np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-10)


@pytest.mark.parametrize("strength", [None, 150.0], ids=["holds", "breaks"])
@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_a_bolt_to_a_shaken_table_in_the_compiled_step(solver, strength, monkeypatch):
    """A block bolted to a shaken table (the anchor's increment folded into the block's
    forces) runs the same in the compiled small step as in the composed one, to the bit; a
    bolt that breaks does so in the same step either way (the compiled step's trial goes to
    the composed one)."""
    from tests.conftest import shaken_block_scene

    taken = []
    monkeypatch.setattr(step_module, "contact_step",
                        lambda *args: taken.append(1) or small_step.contact_step(*args))
    runs = []
    for small in (True, False):
        monkeypatch.setattr(step_module, "SMALL_STEP", small)
        scene, table, top = shaken_block_scene(phi=20, amplitude=6.0)
        scene.add_bolt(top, (1.0, 0.3), table, (1.5, 0.1), stiffness=1e6, strength=strength)
        sim = dda.Simulation(scene, dt=1e-3, solver=type(solver)())
        runs.append((sim.run(0.3), sim.state))
    (fast, a), (slow, b) = runs
    assert len(taken) > 0.5 * len(fast.stats)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(fast.bolt_force(0), slow.bolt_force(0))
    np.testing.assert_array_equal(fast.bolt_broken(0), slow.bolt_broken(0))
    assert fast.bolt_broken(0)[-1] == (strength is not None)
    assert np.abs(fast.bolt_force(0)).max() > 100.0


def test_bolt_energy_is_its_elastic_energy():
    """A pretensioned bolt holds N^2 / (2 k) of energy from the start (dda.energy)."""
    scene, top, t = bolted_incline(20.0, stiffness=1e7)
    scene.add_bolt(top, 2.5 * t + (0.1, 0.1), "base", 2.5 * t - (0.1, 0.3), stiffness=2e6,
                   pretension=1e4)
    sim = dda.Simulation(scene, dt=1e-3)
    assert sim.energy().bolt == pytest.approx(0.5 * 1e4**2 / 2e6, rel=1e-12)


# ---------------------------------------------------------------------- pretension
@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_pretension_presses_the_block_on_its_base(solver):
    """A pretensioned bolt from a block resting on a flat base to the base, at 36.9 degrees
    from the horizontal through the block's centroid: the base's normal force rises by the
    bolt force's normal component (3/5 of it), the shear takes its horizontal 4/5, and the
    bolt keeps its pretension but for the joint's give (k / p_n of it)."""
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=G)
    base = scene.add_block(box(-1, -1, 4, 1), rock, fixed=True, name="base")
    top = scene.add_block(box(0, 0, 1, 0.5), rock, name="top")
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=40.0)))
    weight = 2500.0 * 0.5 * G
    pretension = weight
    scene.add_bolt(top, (0.5, 0.25), base, (0.5 + 1.0, 0.25 - 0.75), stiffness=1e6,
                   pretension=pretension)
    result = dda.Simulation(scene, dt=1e-3, solver=solver, analysis="static").run(0.1)
    force = result.bolt_force(0)
    assert force[0] == pretension  # applied at the start
    assert force[-1] == pytest.approx(pretension, rel=1e-2)
    joint = result.joint_force(base, top)[-1]
    assert joint[0] == pytest.approx(weight + 0.6 * force[-1], rel=1e-4)
    assert abs(joint[1]) == pytest.approx(0.8 * force[-1], rel=1e-4)


# ---------------------------------------------------------------------- the scene file
SCENE_FILE = """
[scene]
gravity = 9.81
[materials.rock]
young = 1e9
poisson = 0.25
density = 2500.0
[joints.default]
normal_penalty = 1e9
shear_penalty = 1e9
friction = { law = "coulomb", phi = 30.0 }
[[blocks]]
name = "base"
material = "rock"
vertices = [[-1, -1], [3, -1], [3, 0], [-1, 0]]
fixed = true
[[blocks]]
name = "top"
material = "rock"
vertices = [[0, 0], [1, 0], [1, 0.5], [0, 0.5]]
[[bolt]]
block_a = "top"
point_a = [0.5, 0.4]
block_b = "base"
point_b = [0.5, -0.6]
stiffness = STIFFNESS
pretension = 2000.0
strength = 1e6
[simulation]
dt = 1e-3
duration = 0.01
solver = "legacy"
"""


def test_scene_file_bolt_round_trip(tmp_path):
    path = tmp_path / "bolted.toml"
    path.write_text(SCENE_FILE.replace("STIFFNESS", "1e7"))
    loaded = load_scene(path)
    (bolt,) = loaded.scene.bolts
    assert (bolt.block_a, bolt.block_b) == (1, 0)
    np.testing.assert_array_equal(bolt.point_a, [0.5, 0.4])
    np.testing.assert_array_equal(bolt.point_b, [0.5, -0.6])
    assert (bolt.stiffness, bolt.pretension, bolt.strength) == (1e7, 2000.0, 1e6)
    assert any(e.startswith("bolt 0") for e in loaded.effects)
    # the scene as data (checkpoints) keeps it too
    store = ArrayStore()
    back = scene_from_data(scene_to_data(loaded.scene, store), store)
    assert len(back.bolts) == 1
    assert back.bolts[0].__dict__.keys() == bolt.__dict__.keys()
    for key, value in bolt.__dict__.items():
        np.testing.assert_array_equal(getattr(back.bolts[0], key), value)
    result = loaded.run()
    assert result.bolt_force(0)[0] == 2000.0


def test_dda_info_lists_the_bolts(tmp_path):
    from dda.cli import describe

    path = tmp_path / "bolted.toml"
    path.write_text(SCENE_FILE.replace("STIFFNESS", "1e7"))
    text = describe(load_scene(path), budget=0.05)
    assert ("effects    gravity, bolt 0 from block 'top' to block 'base' (1e+07 N/m, "
            "pretension 2000 N/m, strength 1e+06 N/m)") in text


def test_scene_file_bolt_errors_name_the_line(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(SCENE_FILE.replace("STIFFNESS", "-1e7"))
    line = SCENE_FILE.splitlines().index("[[bolt]]") + 1
    with pytest.raises(SceneFileError, match=rf"line {line}, bolt\[0\]: .*stiffness must be "
                                             "positive"):
        load_scene(path)
    path.write_text(SCENE_FILE.replace("STIFFNESS", "1e7").replace('block_b = "base"',
                                                                  'block_b = "bass"'))
    with pytest.raises(SceneFileError, match=r"bolt\[0\]\.block_b: no block 'bass'"):
        load_scene(path)
    path.write_text(SCENE_FILE.replace("STIFFNESS", "1e7").replace("strength", "strenth"))
    with pytest.raises(SceneFileError, match=r"bolt\[0\]\.strenth: unknown key"):
        load_scene(path)


# ---------------------------------------------------------------------- checkpoints
def _two_bolt_scene():
    """The incline's block held by a weak bolt (it breaks in the first 0.05 s) and a strong
    one (it holds)."""
    scene, top, t = bolted_incline(0.0, stiffness=1e6, strength=300.0)
    n = np.array([-t[1], t[0]])
    a = 2.5 * t + 0.45 * t + 0.1 * n
    scene.add_bolt(top, a, "base", a + 0.8 * (np.cos(0.3) * t - np.sin(0.3) * n),
                   stiffness=1e6, strength=1e5)
    return scene


def test_checkpoint_resumes_bolts_with_the_same_numbers(tmp_path):
    ref = dda.Simulation(_two_bolt_scene(), dt=1e-3, solver=NewtonRaphson())
    ref.run(0.05)
    tail_ref = ref.run(0.05)
    sim = dda.Simulation(_two_bolt_scene(), dt=1e-3, solver=NewtonRaphson())
    head = sim.run(0.05)
    assert head.bolt_broken(0)[-1] and not head.bolt_broken(1)[-1]
    path = tmp_path / "bolts.ckpt"
    sim.save_checkpoint(path, end=0.1)
    resumed = dda.Simulation.resume(path)
    np.testing.assert_array_equal(resumed.state.bolt_broken, [True, False])
    np.testing.assert_array_equal(resumed.state.bolt_points, sim.state.bolt_points)
    tail = resumed.run()
    for i in (0, 1):
        np.testing.assert_array_equal(tail.bolt_force(i), tail_ref.bolt_force(i))
        np.testing.assert_array_equal(tail.bolt_broken(i), tail_ref.bolt_broken(i))
    np.testing.assert_array_equal(resumed.state.x, ref.state.x)
    assert tail.bolt_force(1)[-1] > 0


# ---------------------------------------------------------------------- VTU
def test_the_vtu_series_carries_bolts_as_lines(tmp_path):
    """Every frame has the bolts as line cells (kind 2) from end a to end b with their force
    and state; a scene without bolts gets no bolt fields."""
    import meshio

    from dda.io import VTUWriter

    scene = _two_bolt_scene()
    writer = VTUWriter(tmp_path / "bolted")
    sim = dda.Simulation(scene, dt=1e-3, solver=NewtonRaphson(), output=writer)
    result = sim.run(0.05)
    files = writer.files
    assert len(files) == len(result.time)
    for k in (0, len(files) - 1):
        mesh = meshio.read(files[k])
        (i,) = [j for j, c in enumerate(mesh.cells) if c.type == "line"]
        lines = mesh.cells[i].data
        assert len(lines) == 2
        np.testing.assert_allclose(mesh.points[lines][:, :, :2], sim.state.bolt_points
                                   if k else sim.model.bolts.points, rtol=1e-12)
        force = mesh.cell_data["bolt_force [N/m]"]
        np.testing.assert_array_equal(force[i], [result.bolt_force(0)[k],
                                                 result.bolt_force(1)[k]])
        np.testing.assert_array_equal(mesh.cell_data["bolt_state"][i],
                                      [result.bolt_broken(0)[k], result.bolt_broken(1)[k]])
        np.testing.assert_array_equal(mesh.cell_data["kind"][i], [2, 2])
        assert np.isnan(force[0]).all()  # the blocks
    assert mesh.cell_data["bolt_state"][i].tolist() == [1, 0]  # bolt 0 broke
    plain = tmp_path / "plain"
    dda.Simulation(incline_scene(phi=PHI)[0], dt=1e-3, output=VTUWriter(plain)).run(0.002)
    mesh = meshio.read(tmp_path / "plain_00000.vtu")
    assert all(c.type != "line" for c in mesh.cells)
    assert "bolt_force [N/m]" not in mesh.cell_data


# ---------------------------------------------------------------------- bad input
@pytest.fixture
def two_blocks():
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=G)
    base = scene.add_block(box(-1, -1, 4, 1), rock, fixed=True, name="base")
    top = scene.add_block(box(0, 0, 1, 0.5), rock, name="top")
    return scene, base, top, rock


@pytest.mark.parametrize("kwargs, message", [
    ({"point_a": (0.5, 0.9)}, r"bolt 0 \(block 'top' to block 'base'\): point_a \(0.5, 0.9\) "
                              r"is outside block 'top', 0.4 m from it"),
    ({"point_b": (3.5, -0.5)}, r"point_b \(3.5, -0.5\) is outside block 'base', 0.5 m"),
    ({"block_b": "top"}, r"bolt 0 .*: block_a and block_b are the same block"),
    ({"stiffness": -1e6}, r"bolt 0 .*: stiffness must be positive, got -1000000"),
    ({"stiffness": float("nan")}, r"bolt 0 .*: stiffness must be finite, got nan"),
    ({"stiffness": True}, r"bolt 0 .*: stiffness must be a number, got True"),  # was 1 N/m
    ({"strength": -5.0}, r"bolt 0 .*: strength must be positive, got -5"),
    ({"pretension": -1.0}, r"bolt 0 .*: pretension must not be negative"),
    ({"pretension": 2e3, "strength": 1e3}, r"pretension 2000 N/m exceeds the strength 1000"),
    ({"point_a": (0.5, 0.0), "point_b": (0.5, 0.0)}, r"point_a and point_b coincide"),
    ({"point_a": (0.5, float("inf"))}, r"point_a\[1\] must be finite"),
])
def test_bad_bolts_are_refused_with_a_message_naming_the_bolt(two_blocks, kwargs, message):
    scene, base, top, _ = two_blocks
    args = {"block_a": top, "point_a": (0.5, 0.25), "block_b": base, "point_b": (0.5, -0.5),
            "stiffness": 1e6}
    if "block_b" in kwargs:
        kwargs = {**kwargs, "point_b": (0.6, 0.3)}
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        scene.add_bolt(**args)
    assert scene.bolts == ()


def test_a_bolt_between_two_blocks_of_known_motion_is_refused(two_blocks):
    scene, base, top, rock = two_blocks
    other = scene.add_block(box(-1, -3, 4, 1), rock, fixed=True, name="deep")
    with pytest.raises(ValueError, match=r"bolt 0 .*: both blocks are fixed"):
        scene.add_bolt(base, (0, -0.5), other, (0, -2.5), stiffness=1e6)
    # a block shaken after the bolt was added: the simulation says so
    scene.add_bolt(top, (0.5, 0.25), other, (0, -2.5), stiffness=1e6)
    scene.prescribe_motion(top, lambda t: (0.0, 0.0))
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=30.0)))
    with pytest.raises(ValueError, match=r"bolt 0 \(block 'top' to block 'deep'\): both its "
                                         "blocks have a known motion"):
        dda.Simulation(scene, dt=1e-3)


def test_bolt_force_of_a_bolt_the_scene_does_not_have(two_blocks):
    scene, base, top, _ = two_blocks
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=30.0)))
    result = dda.Simulation(scene, dt=1e-3).run(0.002)
    with pytest.raises(ValueError, match=r"no bolt 0 \(the scene has 0\)"):
        result.bolt_force(0)


# ---------------------------------------------------------------------- no bolts: no cost
# the incline of tests.conftest.incline_scene(phi=20) after 0.05 s at dt 1e-3: its block's
# centroid displacement (x, y) and rotation, computed by the code before bolts existed
# (commit 4adfedc); the dynamic runs take the compiled small step, the static ones the
# composed step's dense kernels
BEFORE_BOLTS = {
    ("legacy", "dynamic"): (-0.0019618061656769825, -0.0011371969796756254,
                            6.28104652107268e-06),
    ("legacy", "static"): (-3.853993610247741e-05, -2.6798698762542372e-05,
                           6.281054214666382e-06),
    ("newton", "dynamic"): (-0.001961701723502962, -0.0011371366799859395,
                            6.281044587480852e-06),
    ("newton", "static"): (-3.852080588728768e-05, -2.678765392771787e-05,
                           6.281054221645518e-06),
}


@pytest.mark.parametrize("analysis", ["dynamic", "static"])
@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_a_scene_without_bolts_runs_as_before(solver, analysis, monkeypatch):
    taken = []
    monkeypatch.setattr(step_module, "contact_step",
                        lambda *args: taken.append(1) or small_step.contact_step(*args))
    scene, top, _ = incline_scene(phi=PHI)
    result = dda.Simulation(scene, dt=1e-3, solver=solver, analysis=analysis).run(0.05)
    got = (*result.displacement(top)[-1], result.rotation(top)[-1])
    expected = BEFORE_BOLTS[(solver.name, analysis)]
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0)
    assert (len(taken) > 40) == (analysis == "dynamic")  # the small step where it was


def test_which_bolted_scenes_take_the_compiled_step(monkeypatch):
    """A bolt anchored in a fixed block is folded into its free block's matrix and forces:
    the scene keeps the compiled small step. A bolt between two free blocks couples them,
    which the compiled step does not know: the composed step takes the scene, until that
    bolt breaks."""
    taken = []
    monkeypatch.setattr(step_module, "contact_step",
                        lambda *args: taken.append(1) or small_step.contact_step(*args))
    scene, top, t = bolted_incline(0.0, stiffness=1e8)
    result = dda.Simulation(scene, dt=1e-3).run(0.05)
    assert len(taken) >= 0.8 * len(result.stats)
    n = np.array([-t[1], t[0]])
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    p0 = 1.9 * t
    low = scene.add_block([p0, p0 + 0.5 * t, p0 + 0.5 * t + 0.5 * n, p0 + 0.5 * n], rock,
                          name="low")
    scene.add_bolt(low, p0 + 0.25 * t + 0.25 * n, top, 2.75 * t + 0.25 * n, stiffness=1e6,
                   strength=300.0)
    sim = dda.Simulation(scene, dt=1e-3)
    taken.clear()
    sim.run(0.005)
    assert taken == [] and not sim.state.bolt_broken[1]
    result = sim.run(0.1)
    broken_at = int(np.flatnonzero(result.bolt_broken(1))[0])
    assert not result.bolt_broken(0).any()
    assert len(taken) >= 0.8 * (len(result.stats) - broken_at)


def test_points_move_with_their_blocks():
    """The bolts' ends are material points: moved as the vertices are."""
    points = np.array([[[0.0, 0.0], [1.0, 1.0]]])
    centroid = np.array([[0.5, 0.0], [1.0, 0.5]])
    d = np.zeros((2, 6))
    d[0, 2] = np.pi / 2  # a quarter turn of block 0 about (0.5, 0)
    d[1, :2] = (0.1, -0.2)
    moved = moved_points(points, np.array([[0, 1]]), centroid, d)
    np.testing.assert_allclose(moved[0], [[0.5, -0.5], [1.1, 0.8]], atol=1e-15)


def test_the_dataset_carries_the_bolts(tmp_path):
    """Result.to_xarray: bolt_force and bolt_broken over time x bolt, equal to the result's
    own, and through NetCDF."""
    xr = pytest.importorskip("xarray")
    strength = 0.5 * held_tension(0.0)
    scene, top, t = bolted_incline(0.0, stiffness=1e6, strength=strength)
    result = dda.Simulation(scene, dt=1e-3).run(0.1)
    ds = result.to_xarray()
    np.testing.assert_array_equal(ds.bolt_force.sel(bolt=0).values, result.bolt_force(0))
    np.testing.assert_array_equal(ds.bolt_broken.sel(bolt=0).values.astype(bool),
                                  result.bolt_broken(0))
    assert result.bolt_broken(0).any() and ds.bolt_force.attrs["units"] == "N/m"
    ds.to_netcdf(tmp_path / "run.nc")
    back = xr.open_dataset(tmp_path / "run.nc")
    np.testing.assert_array_equal(back.bolt_force.values, ds.bolt_force.values)
    back.close()


# ------------------------------------------------------- the bolts' vibration and the step
def _hung(stiffness=2.2e7, point=(0.5, 0.5), anchor=(0.5, 2.5), strength=None, size=1.0):
    """A free square of ``size`` hung from a fixed roof by one bolt, nothing else touching."""
    rock = LinearElastic(young=10e9, poisson=0.25, density=2600.0)
    scene = dda.Scene(gravity=G)
    roof = scene.add_block(box(-1.0, 2.0, 5.0, 1.0), rock, fixed=True, name="roof")
    block = scene.add_block(box(0.0, 0.0, size, size), rock, name="block")
    scene.set_joint(JointMaterial(normal_penalty="auto", shear_penalty="auto",
                                  friction=CoulombSingle(phi=PHI)))
    scene.add_bolt(block, point, roof, anchor, stiffness=stiffness, strength=strength)
    return scene, 2600.0 * size**2 * G


def test_released_peak_follows_the_one_mass_newmark_step():
    from dda.bolts import released_peak

    # gamma = 1 damps a half period by exp(-pi omega dt / 4): 1 - pi^2 / (4 N) for many N
    for n in (200.0, 1000.0, 5000.0):
        deficit = 1.0 - released_peak(n)
        assert deficit == pytest.approx(np.pi**2 / (4.0 * n), rel=0.015)
    assert released_peak(2e4) == pytest.approx(1.0 - np.pi**2 / 8e4, rel=1e-12)
    peaks = [released_peak(n) for n in (3, 10, 30, 100, 300)]
    assert np.all(np.diff(peaks) > 0.0) and peaks[-1] < 1.0
    with pytest.raises(ValueError, match="positive"):
        released_peak(0.0)


def test_shortest_period_sees_the_blocks_rigid_mass_at_the_bolts_point():
    from dda.bolts import shortest_period
    from dda.model import Model

    m, polar = 2600.0, 2600.0 / 6.0  # a 1 m square: m, and m (1 + 1) / 12 about its centroid
    k = 2.2e7
    # through the centroid along its axis: the block's mass alone
    period, what = shortest_period(Model(_hung(k)[0]))
    assert period == pytest.approx(2.0 * np.pi * np.sqrt(m / k), rel=1e-12)
    assert "block 'block'" in what
    # at a corner, pulled at right angles to the arm (0.5, -0.5) along (1, 1) / sqrt 2:
    # the inverse mass 1 / m + (r x n)^2 / I
    scene, _ = _hung(k, point=(1.0, 0.0), anchor=(3.5, 2.5))
    inverse = 1.0 / m + 0.5 / polar
    assert shortest_period(Model(scene))[0] == pytest.approx(
        2.0 * np.pi / np.sqrt(k * inverse), rel=1e-12)
    # two equal free blocks joined by a bolt along the line of their centroids: 2 k / m
    rock = LinearElastic(young=10e9, poisson=0.25, density=2600.0)
    scene = dda.Scene(gravity=G)
    a = scene.add_block(box(0.0, 0.0, 1.0, 1.0), rock)
    b = scene.add_block(box(2.0, 0.0, 1.0, 1.0), rock)
    scene.set_joint(JointMaterial(normal_penalty=1e10, shear_penalty=1e10,
                                  friction=CoulombSingle(phi=PHI)))
    scene.add_bolt(a, (0.5, 0.5), b, (2.5, 0.5), stiffness=k)
    assert shortest_period(Model(scene))[0] == pytest.approx(
        2.0 * np.pi * np.sqrt(m / (2.0 * k)), rel=1e-12)
    # two bolts along the line of two equal free blocks' centroids: 2 k (2 / m) (each bolt
    # alone, as it was taken: 41% longer)
    scene.add_bolt(a, (0.5, 0.5), b, (2.5, 0.5), stiffness=k)
    assert shortest_period(Model(scene))[0] == pytest.approx(
        2.0 * np.pi * np.sqrt(m / (4.0 * k)), rel=1e-9)
    # two vertical bolts 0.25 m either side of the centroid: together 2 k / m (the block's
    # rise), each alone k (1 / m + 0.25^2 / I) = 1.375 k / m, their rocking 0.75 k / m
    scene, _ = _hung(k, point=(0.25, 0.5), anchor=(0.25, 2.5))
    scene.add_bolt(scene.blocks[1], (0.75, 0.5), scene.blocks[0], (0.75, 2.5), stiffness=k)
    period, what = shortest_period(Model(scene))
    assert period == pytest.approx(2.0 * np.pi * np.sqrt(m / (2.0 * k)), rel=1e-12)
    assert what == "the bolts on block 'block'"
    no_bolts = dda.Scene(gravity=G)
    no_bolts.add_block(box(0.0, 0.0, 1.0, 1.0), rock)
    no_bolts.set_joint(JointMaterial(normal_penalty=1e10, shear_penalty=1e10,
                                     friction=CoulombSingle(phi=PHI)))
    assert shortest_period(Model(no_bolts)) == (float("inf"), "")


@pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
def test_auto_dt_resolves_a_bolts_vibration(solver):
    """A block let go from rest on a bolt swings it to twice its weight (less Newmark's
    damping): under dt="auto" its peak is within 1% of 2 W, and a bolt of 1.5 W breaks.
    (The fall's dt of 0.032 s alone resolved the 82 ms period in 2.6 steps: 1.31 W.)"""
    scene, weight = _hung()
    sim = dda.Simulation(scene, dt="auto", solver=solver)
    assert "bolt's vibration" in sim.choices
    result = sim.run(0.1)
    peak = float(result.bolt_force(0).max())
    assert peak == pytest.approx(2.0 * weight, rel=0.01)
    scene, weight = _hung(strength=1.5 * 2600.0 * G)
    result = dda.Simulation(scene, dt="auto", solver=solver).run(0.1)
    assert result.bolt_broken(0)[-1]


def test_static_auto_dt_has_no_bolt_vibration():
    scene, _ = _hung()
    sim = dda.Simulation(scene, dt="auto", analysis="static")
    assert "bolt" not in sim.choices


def test_a_step_that_skips_a_bolts_vibration_is_warned_of():
    from dda.plausibility import PlausibilityWarning

    period = 2.0 * np.pi * np.sqrt(2600.0 / 2.2e7)  # 82 ms
    with pytest.warns(PlausibilityWarning, match=r"bolt 0 .*34% off the peak force"):
        dda.Simulation(_hung()[0], dt=period / 2.6)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        dda.Simulation(_hung()[0], dt=period / 25.0)


def test_a_bolt_shortens_the_auto_step_but_leaves_the_joints_penalty():
    """Rule 8 shortens dt for the bolt's vibration; the joints' penalty is still kappa times
    the inertia at the step the joints need (it followed the bolt's step: a bolted 0.2 m
    block got 2.1e11 N/m, 70 times its rock's E, for 23 times the steps)."""
    def scene(bolt):
        rock = LinearElastic(young=10e9, poisson=0.25, density=2600.0)
        s = dda.Scene(gravity=G)
        table = s.add_block(box(-1.0, -0.5, 3.0, 0.5), rock, fixed=True, name="table")
        block = s.add_block(box(0.0, 0.0, 0.2, 0.2), rock, name="block")
        roof = s.add_block(box(-1.0, 1.0, 3.0, 0.5), rock, fixed=True, name="roof")
        s.set_joint(JointMaterial("auto", "auto", CoulombSingle(phi=PHI)))
        s.shake(table, acceleration=lambda t: (3.0 * np.sin(4 * np.pi * t), 0.0))
        if bolt:
            s.add_bolt(block, (0.1, 0.1), roof, (0.1, 1.2), stiffness=2.2e7)
        return s

    for solver in SOLVERS:
        plain = dda.Simulation(scene(False), dt="auto", solver=solver)
        bolted = dda.Simulation(scene(True), dt="auto", solver=solver)
        assert bolted.dt < plain.dt / 10
        np.testing.assert_allclose(bolted.model.joints.normal_penalty,
                                   plain.model.joints.normal_penalty, rtol=1e-12)
