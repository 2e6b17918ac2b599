"""``"auto"`` penalties and dt (dda.auto_settings): what the rule chooses, and its text."""

import warnings

import numpy as np
import pytest

import dda
from dda.auto_settings import KAPPA, MASS_STIFFNESS, shaking_frequency
from dda.contact import CoulombSingle, JointMaterial
from dda.effects import AccelerationHistory
from dda.materials import LinearElastic
from dda.penalty_advice import SOFT_DEPTH, TARGET_DEPTH
from dda.solvers import LegacyPullBack, NewtonRaphson
from tests.conftest import box

ROCK = LinearElastic(young=10e9, poisson=0.25, density=2600.0)
G = 9.81


def column(n, joint=None, shake=None):
    """n unit squares stacked on a fixed base."""
    scene = dda.Scene(gravity=G)
    base = scene.add_block([(-1, -1), (2, -1), (2, 0), (-1, 0)], ROCK, fixed=True, name="base")
    for i in range(n):
        scene.add_block([(0, i), (1, i), (1, i + 1), (0, i + 1)], ROCK, name=f"b{i}")
    scene.set_joint(joint or JointMaterial("auto", "auto", CoulombSingle(phi=35.0)))
    if shake is not None:
        scene.shake(base, acceleration=shake)
    return scene


MASS = 2600.0  # kg per m, a unit square
HALF_WIDTH = 0.5  # 2 area / perimeter of a unit square


def test_a_joint_takes_auto_and_names_other_strings():
    assert JointMaterial("auto", 1e9, CoulombSingle(phi=30.0)).auto
    assert not JointMaterial(1e9, 1e9, CoulombSingle(phi=30.0)).auto
    with pytest.raises(ValueError, match="normal_penalty must be a number .* or 'auto', got "
                                         "'automatic'"):
        JointMaterial("automatic", 1e9, CoulombSingle(phi=30.0))
    with pytest.raises(ValueError, match="dt must be a number .* or 'auto', got 'fast'"):
        dda.Simulation(column(1), dt="fast")


@pytest.mark.parametrize("solver, kappa", [(LegacyPullBack(), 3.0), (NewtonRaphson(), 10.0)])
def test_a_given_dt_gets_the_solvers_multiple_of_the_inertia_of_the_lightest_block(solver,
                                                                                  kappa):
    sim = dda.Simulation(column(1), dt=1e-3, solver=solver)
    inertia = 2 * MASS / 1e-6
    assert sim.dt == 1e-3 and solver.auto_kappa == kappa
    np.testing.assert_allclose(sim.model.joints.normal_penalty, kappa * inertia, rtol=1e-12)
    np.testing.assert_allclose(sim.model.joints.shear_penalty, kappa * inertia, rtol=1e-12)
    assert f"{kappa:g} x Newmark's inertia" in sim.choices and "block 'b0'" in sim.choices
    assert "dt:" not in sim.choices  # dt was given
    assert KAPPA == 3.0  # a solver that does not say takes the module's


def test_a_solver_of_ones_own_says_how_stiff_its_springs():
    class Stiff(LegacyPullBack):
        auto_kappa = 30.0

    sim = dda.Simulation(column(1), dt=1e-3, solver=Stiff())
    np.testing.assert_allclose(sim.model.joints.normal_penalty, 30 * 2 * MASS / 1e-6,
                               rtol=1e-12)


def test_without_shaking_dt_lets_a_block_fall_one_percent_of_its_half_width():
    sim = dda.Simulation(column(1), dt="auto")
    dt = np.sqrt(2 * TARGET_DEPTH * HALF_WIDTH / G)
    assert sim.dt == pytest.approx(dt, rel=1e-12)
    # the block comes to rest on its two springs, each sunk by half its weight over the
    # penalty: h / 2,000 (10 x 2 m / dt^2 with dt^2 = 0.02 h / g, Newton's), 0.05% of its
    # half-width (legacy DDA's 3 x: h / 600)
    p = sim.model.joints.normal_penalty[0]
    result = sim.run(40 * sim.dt, progress=False)
    sunk = result.stats["spring_penetration"]
    assert sunk[-1] == pytest.approx(0.5 * MASS * G / p, rel=1e-3)
    assert sunk[-1] == pytest.approx(HALF_WIDTH / 2000.0, rel=1e-3)
    legacy = dda.Simulation(column(1), dt="auto", solver=LegacyPullBack())
    assert legacy.dt == sim.dt
    sunk = legacy.run(40 * sim.dt, progress=False).stats["spring_penetration"]
    assert sunk[-1] == pytest.approx(HALF_WIDTH / 600.0, rel=1e-3)


def test_a_heavy_load_raises_the_penalty_to_hold_it():
    """One block pressed by 20 of its weights: its two contacts carry 21 weights."""
    scene = column(1)
    weight = MASS * G
    scene.add_point_load(1, (0.5, 1.0), (0.0, -20 * weight))
    need = 0.5 * 21 * weight / (TARGET_DEPTH * HALF_WIDTH)
    sim = dda.Simulation(scene, dt=0.05)  # a long step: a soft penalty by the inertia
    kappa = NewtonRaphson.auto_kappa  # the default solver's
    assert kappa * 2 * MASS / 0.05**2 < need
    np.testing.assert_allclose(sim.model.joints.normal_penalty, need, rtol=1e-9)
    assert "keeps the load under block 'b0'" in sim.choices
    auto = dda.Simulation(scene, dt="auto")  # dt shortened to keep the penalty at kappa x
    assert auto.dt == pytest.approx(np.sqrt(kappa * 2 * MASS / need), rel=1e-9)
    assert "dt shortened" in auto.choices
    # the block settles with its contacts at 1% of its half-width (5 mm); the swing of the
    # settling stays below the 5% at which the penalty advice warns
    result = auto.run(300 * auto.dt, progress=False)
    sunk = result.stats["spring_penetration"]
    assert sunk[-1] == pytest.approx(TARGET_DEPTH * HALF_WIDTH, rel=2e-3)
    assert sunk.max() < SOFT_DEPTH * HALF_WIDTH


def test_blocks_that_carry_blocks_get_joints_twice_as_stiff_as_their_rock():
    """Ten blocks on one: the load would ask for 2.55e7 N/m (10 weights over two contacts at
    1% of the half-width), but joints that soft make the column 400 times softer than its
    rock; the penalty is 2 E, and the column settles by its joints' depths (10 + 9 + ... + 1
    half-weights over the penalty) and the blocks' own strain ((k - 1/2) W / E each) alike."""
    n = 10
    need = 0.5 * n * MASS * G / (TARGET_DEPTH * HALF_WIDTH)
    floor = MASS_STIFFNESS * ROCK.young
    assert need < floor
    sim = dda.Simulation(column(n), dt=0.05)
    np.testing.assert_allclose(sim.model.joints.normal_penalty, floor, rtol=1e-12)
    assert "2 x the Young's modulus 1e+10 Pa of block 'b0', which carries blocks" in sim.choices
    auto = dda.Simulation(column(n), dt="auto")
    kappa = NewtonRaphson.auto_kappa  # the default solver's
    assert auto.dt == pytest.approx(np.sqrt(kappa * 2 * MASS / floor), rel=1e-9)
    legacy = dda.Simulation(column(n), dt="auto", solver=LegacyPullBack())
    assert legacy.dt == pytest.approx(np.sqrt(KAPPA * 2 * MASS / floor), rel=1e-9)
    assert "dt shortened" in auto.choices
    result = auto.run(300 * auto.dt, progress=False)
    weight = MASS * G
    strain = sum(k - 0.5 for k in range(1, n + 1)) * weight / ROCK.young
    joints = 55 * 0.5 * weight / floor
    assert result.displacement(n)[-1, 1] == pytest.approx(-joints - strain, rel=0.02)
    # a single block on its base gets no floor
    single = dda.Simulation(column(1), dt=1e-2).model.joints.normal_penalty[0]
    assert single == pytest.approx(kappa * 2 * MASS / 1e-4, rel=1e-12) and single < floor


@pytest.mark.parametrize("solver, steps", [(NewtonRaphson(), 167), (LegacyPullBack(), 400)])
def test_dt_resolves_the_shaking_by_the_solver(solver, steps):
    shake = lambda t: (0.3 * G * np.sin(2 * np.pi * 5.0 * t), 0.0)  # noqa: E731
    sim = dda.Simulation(column(1, shake=shake), dt="auto", solver=solver)
    assert sim.dt == pytest.approx(1.0 / (steps * 5.0), rel=0.01)
    assert f"{steps} steps" in sim.choices and "5 Hz" in sim.choices


def test_the_laws_say_how_much_strength_they_lose_at_the_onset_of_slip():
    from dda.contact import BartonBandis, FrictionLaw, StaticDynamicTransition

    assert CoulombSingle(phi=35.0).onset_drop() == 0.0
    assert BartonBandis(jrc=10.0, jcs=50e6, phi_r=30.0).onset_drop() == 0.0
    law = StaticDynamicTransition(40.5, 31.6)
    assert law.onset_drop() == pytest.approx(
        1.0 - np.tan(np.radians(31.6)) / np.tan(np.radians(40.5)), rel=1e-12)
    assert StaticDynamicTransition(30.0, 30.0).onset_drop() == 0.0
    assert StaticDynamicTransition(0.0, 0.0).onset_drop() == 0.0
    assert FrictionLaw.onset_drop(law) == 0.0  # a law of one's own: no drop unless it says


def _drop(phi_static, phi_dynamic):
    return 1.0 - np.tan(np.radians(phi_dynamic)) / np.tan(np.radians(phi_static))


@pytest.mark.parametrize("solver, phi_dynamic, steps", [
    (LegacyPullBack(), 20.0, 400 + int(np.ceil(4100.0 * _drop(35.0, 20.0)))),  # 2,369
    # a drop of 3.7%: 151 more
    (LegacyPullBack(), 34.0, 400 + int(np.ceil(4100.0 * _drop(35.0, 34.0)))),
    (LegacyPullBack(), 35.0, 400),  # no drop
    (NewtonRaphson(), 20.0, 167 + int(np.ceil(475.0 * _drop(35.0, 20.0)))),  # 372
    (NewtonRaphson(), 35.0, 167)])
def test_the_steps_a_period_grow_with_the_strength_lost_at_onset(solver, phi_dynamic, steps):
    from dda.contact import StaticDynamicTransition

    shake = lambda t: (0.3 * G * np.sin(2 * np.pi * 5.0 * t), 0.0)  # noqa: E731
    law = StaticDynamicTransition(35.0, phi_dynamic)
    sim = dda.Simulation(column(1, JointMaterial("auto", "auto", law), shake=shake),
                         dt="auto", solver=solver)
    assert sim.dt == pytest.approx(1.0 / (steps * 5.0), rel=1e-9)
    assert f"{steps} steps" in sim.choices
    # the reason is shown where it applies
    assert ("loses" in sim.choices) == (phi_dynamic < 35.0)


def test_the_largest_drop_of_the_scene_s_laws_sets_legacy_s_steps():
    """A Coulomb default and a transition joint on one pair: the transition's drop counts; a
    law of one's own says its drop by ``onset_drop``, which must be a share, 0 to 1."""
    from dda.auto_settings import largest_onset_drop
    from dda.contact import StaticDynamicTransition

    class Softening(CoulombSingle):
        def __init__(self, phi, drop):
            super().__init__(phi=phi)
            self.drop = drop

        def onset_drop(self):
            return self.drop

    shake = lambda t: (0.3 * G * np.sin(2 * np.pi * 5.0 * t), 0.0)  # noqa: E731
    scene = column(2, shake=shake)
    transition = StaticDynamicTransition(35.0, 20.0)
    scene.set_joint(JointMaterial("auto", "auto", transition), between=("b0", "b1"))
    sim = dda.Simulation(scene, dt="auto", solver=LegacyPullBack())
    drop, law = largest_onset_drop(sim.model)
    assert law is transition and drop == pytest.approx(transition.onset_drop())
    assert sim.dt == pytest.approx(1.0 / ((400 + np.ceil(4100.0 * drop)) * 5.0), rel=1e-9)
    scene.set_joint(JointMaterial("auto", "auto", Softening(35.0, 0.5)))
    sim = dda.Simulation(scene, dt="auto", solver=LegacyPullBack())
    assert sim.dt == pytest.approx(1.0 / (2450 * 5.0), rel=1e-9)  # 0.5 beats 0.43
    for bad in (1.5, -0.1, float("nan")):
        scene.set_joint(JointMaterial("auto", "auto", Softening(35.0, bad)))
        with pytest.raises(ValueError, match="onset_drop"):
            dda.Simulation(scene, dt="auto", solver=LegacyPullBack())


def test_the_shaking_frequency_of_records_and_callables():
    t = np.arange(0.0, 10.0, 0.005)
    record = AccelerationHistory(np.sin(2 * np.pi * 3.0 * t), t)
    assert shaking_frequency([record]) == pytest.approx(3.0, abs=0.1)
    two = AccelerationHistory(lambda s: (np.sin(2 * np.pi * 2.0 * s),
                                         0.5 * np.sin(2 * np.pi * 8.0 * s)))
    assert shaking_frequency([two], duration=10.0) == pytest.approx(8.0, abs=0.1)
    assert shaking_frequency([]) is None
    assert shaking_frequency([AccelerationHistory(lambda s: (1.0, 0.0))]) is None
    # a jump written as two samples 1e-12 s apart is probed at the record's sampling
    # interval, not at 1e-12 s (36.4 TiB asked for); its frequency is the 3 Hz sine's
    jump = np.concatenate([t[:400], [t[399] + 1e-12], t[400:]])
    values = np.sin(2 * np.pi * 3.0 * jump)
    values[400:] += 0.01
    assert shaking_frequency([AccelerationHistory(values, jump)]) == pytest.approx(3.0, abs=0.1)


def test_a_given_penalty_stays_and_a_lone_auto_shear_follows_it():
    sim = dda.Simulation(column(1, JointMaterial(2e9, "auto", CoulombSingle(phi=35.0))),
                         dt=1e-3)
    assert sim.model.joints.normal_penalty.tolist() == [2e9]
    assert sim.model.joints.shear_penalty.tolist() == [2e9]
    given = dda.Simulation(column(1, JointMaterial(2e9, 1e8, CoulombSingle(phi=35.0))),
                           dt=1e-3)
    assert given.choices == ""
    assert given.model.joints.shear_penalty.tolist() == [1e8]


def _pebble(joint):
    """A 5 cm square (6.25 kg/m) resting on a fixed slab."""
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=G)
    scene.add_block(box(0, -0.5, 2, 0.5), rock, fixed=True)
    scene.add_block(box(0.5, 0.0, 0.05, 0.05), rock, name="pebble")
    scene.set_joint(joint)
    return scene


@pytest.mark.parametrize("solver, kappa", [(LegacyPullBack(), 3.0), (NewtonRaphson(), 10.0)])
def test_a_given_stiff_penalty_shortens_an_auto_dt(solver, kappa):
    """Joints given as 1e11 N/m under a pebble: the fall's dt (7.1e-3 s) would be 144 times
    its contact period, which the plausibility check warns of, naming dt="auto" as the
    remedy. An "auto" dt keeps the given penalty at kappa times the pebble's inertia
    2 m / dt^2 (rule 6), and the pebble rests without a cut step."""
    mass = 2500.0 * 0.05**2
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning of a step too long for its contacts
        sim = dda.Simulation(_pebble(JointMaterial(1e11, 1e11, CoulombSingle(phi=30.0))),
                             dt="auto", solver=solver)
    assert sim.dt == pytest.approx(np.sqrt(kappa * 2 * mass / 1e11), rel=1e-12)
    assert sim.model.joints.normal_penalty.tolist() == [1e11]
    assert ("dt: shortened to" in sim.choices and "given normal penalty 1e+11 N/m at "
            f"{kappa:g} x Newmark's inertia" in sim.choices and "block 'pebble'" in sim.choices)
    result = sim.run(200 * sim.dt, progress=False)
    assert result.stats.cuts == []


def test_a_given_soft_penalty_leaves_an_auto_dt_alone():
    """1e7 N/m is below 10 x 2 m / dt^2 = 5.1e7 N/m of the fall's dt: that dt stays."""
    auto = dda.Simulation(column(1), dt="auto")
    soft = dda.Simulation(column(1, JointMaterial(1e7, 1e7, CoulombSingle(phi=35.0))),
                          dt="auto")
    assert soft.dt == auto.dt == pytest.approx(np.sqrt(2 * TARGET_DEPTH * HALF_WIDTH / G))
    assert "shortened" not in soft.choices


def test_beside_a_given_stiff_joint_the_auto_penalty_follows_the_shorter_dt():
    """One joint given as 1e11 N/m, the other "auto": dt is set by the given one, and the
    auto one is kappa times the inertia at that dt, the same 1e11 N/m."""
    scene = column(2)
    scene.set_joint(JointMaterial(1e11, 1e11, CoulombSingle(phi=35.0)), between=("b0", "b1"))
    sim = dda.Simulation(scene, dt="auto")
    kappa = NewtonRaphson.auto_kappa
    assert sim.dt == pytest.approx(np.sqrt(kappa * 2 * MASS / 1e11), rel=1e-12)
    np.testing.assert_allclose(sim.model.joints.normal_penalty, 1e11, rtol=1e-9)


def test_nothing_sets_a_time_scale_without_gravity_or_shaking():
    scene = dda.Scene()
    scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)], ROCK)
    with pytest.raises(ValueError, match="nothing in the scene sets a time scale"):
        dda.Simulation(scene, dt="auto")


def test_a_solver_of_ones_own_says_how_many_steps_a_period():
    class Careful(NewtonRaphson):
        auto_steps_per_period = 1000

    shake = lambda t: (0.3 * G * np.sin(2 * np.pi * 5.0 * t), 0.0)  # noqa: E731
    sim = dda.Simulation(column(1, shake=shake), dt="auto", solver=Careful())
    assert sim.dt == pytest.approx(1.0 / 5000.0, rel=0.01)

    class Blunt(LegacyPullBack):  # adds no steps for a drop
        auto_steps_per_drop = 0.0

    from dda.contact import StaticDynamicTransition

    law = JointMaterial("auto", "auto", StaticDynamicTransition(35.0, 20.0))
    sim = dda.Simulation(column(1, law, shake=shake), dt="auto", solver=Blunt())
    assert sim.dt == pytest.approx(1.0 / 2000.0, rel=1e-9)
    assert "loses" not in sim.choices


SCENE = """
[scene]
gravity = 9.81

[simulation]
dt = "auto"
duration = 0.1

[materials.rock]
young = 10e9
poisson = 0.25
density = 2600.0

[joints.default]
normal_penalty = "auto"
shear_penalty = "auto"
friction = { law = "coulomb", phi = 35.0 }

[[blocks]]
name = "base"
material = "rock"
vertices = [[0, 0], [4, 0], [4, 1], [0, 1]]
fixed = true

[[blocks]]
name = "top"
material = "rock"
vertices = [[1, 1], [2, 1], [2, 2], [1, 2]]
"""


def test_scene_files_take_auto_and_dda_info_says_what_it_chose(tmp_path, capsys):
    from dda.cli import describe, main
    from dda.io.scene_file import SceneFileError, load_scene

    path = tmp_path / "auto.toml"
    path.write_text(SCENE)
    loaded = load_scene(path)
    sim = loaded.simulation()
    assert sim.dt == pytest.approx(np.sqrt(2 * TARGET_DEPTH * HALF_WIDTH / G), rel=1e-12)
    info = describe(loaded)
    assert "auto       dt: a block starting from rest moves at most 1%" in info
    assert "normal penalty: 10 x Newmark's inertia" in info  # the default solver's
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    assert "  auto: shear penalty: the normal penalty" in capsys.readouterr().out
    path.write_text(SCENE.replace('normal_penalty = "auto"', 'normal_penalty = "stiff"'))
    with pytest.raises(SceneFileError, match='normal_penalty: must be a positive number or '
                                             '"auto", got \'stiff\''):
        load_scene(path)


def test_a_choice_without_a_solver_takes_the_default_multiple():
    """dda.studies.factor_of_safety asks ``choose`` for the penalty with no solver: the
    module's ``KAPPA`` (3) times the inertia, and 300 steps a period."""
    from dda.auto_settings import choose

    sim = dda.Simulation(column(1), dt=1e-3)
    auto = choose(sim.model, None, 1e-3)
    assert auto.normal_penalty == pytest.approx(KAPPA * 2 * MASS / 1e-6, rel=1e-12)
    assert "3 x Newmark's inertia" in auto.text


def thrown(velocity=(-20.0, 0.0), spin=0.0):
    """A 10 x 5 cm block thrown at a wall 1 mm away (12.5 kg/m, half-width 1/30 m)."""
    scene = dda.Scene(gravity=G)
    scene.add_block([(-0.5, -0.5), (0.0, -0.5), (0.0, 0.5), (-0.5, 0.5)], ROCK, fixed=True,
                    name="wall")
    scene.add_block([(0.001, 0.0), (0.101, 0.0), (0.101, 0.05), (0.001, 0.05)],
                    LinearElastic(young=10e9, poisson=0.25, density=2500.0), name="block",
                    velocity=velocity, angular_velocity=spin)
    scene.set_joint(JointMaterial("auto", "auto", CoulombSingle(phi=30.0)))
    return scene


@pytest.mark.parametrize("solver", ["legacy", "newton"])
def test_a_thrown_block_gets_springs_that_stop_it_within_one_percent_of_its_half_width(solver):
    """Rule 7. Before it a block thrown at 20 m/s got the fall's dt (8 ms) and springs of
    3 x its inertia there, 1.1e6 N/m, and sank 30-47% of its half-width into the wall in its
    first step (a hunt's thrown L-blocks then passed their inner corner into the wall)."""
    mass, half, speed = 2500.0 * 0.1 * 0.05, 2 * 0.005 / 0.3, 20.0
    sim = dda.Simulation(thrown(), dt="auto", solver=solver)
    need = mass * speed**2 / (TARGET_DEPTH * half) ** 2
    np.testing.assert_allclose(sim.model.joints.normal_penalty, need, rtol=1e-9)
    kappa = sim.solver.auto_kappa if hasattr(sim.solver, "auto_kappa") else KAPPA
    assert sim.dt == pytest.approx(np.sqrt(kappa * 2 * mass / need), rel=1e-9)
    assert "keeps an impact of block 'block' at its starting speed (20 m/s" in sim.choices
    result = sim.run(0.002, progress=False)
    assert result.velocity("block")[-1, 0] > 0.0  # it hit the wall and came off it
    sunk = result.stats["spring_penetration"]
    assert 0.0 < sunk.max() <= TARGET_DEPTH * half


def test_a_spin_counts_at_the_farthest_vertex_and_a_static_analysis_starts_at_rest():
    sim = dda.Simulation(thrown(velocity=(3.0, 4.0), spin=10.0), dt="auto")
    reach = np.hypot(0.05, 0.025)  # centroid to corner
    np.testing.assert_allclose(sim.model.initial_speeds(), [0.0, 5.0 + 10.0 * reach],
                               rtol=1e-12)
    static = dda.Simulation(thrown(), dt="auto", analysis="static")
    assert "impact" not in static.choices


def _incline_block(slope_deg, phi=30.0):
    """A 1 m square block on a fixed plane of ``slope_deg`` (friction ``phi``), "auto"."""
    rock = LinearElastic(young=1e10, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    th = np.radians(slope_deg)
    c, s = np.cos(th), np.sin(th)
    scene.add_block([(0, 0), (6 * c, 0), (6 * c, 6 * s)], rock, fixed=True)
    p0, t, n = np.array([2 * c, 2 * s]), np.array([c, s]), np.array([-s, c])
    scene.add_block([p0, p0 + t, p0 + t + n, p0 + n], rock, name="block")
    scene.set_joint(JointMaterial("auto", "auto", CoulombSingle(phi=phi)))
    return scene


@pytest.mark.parametrize("solver", [LegacyPullBack(), NewtonRaphson()], ids=["legacy", "newton"])
def test_a_static_auto_step_shows_a_mechanism(solver):
    """Rule 9: 40 static steps move a block under an unbalanced 1e-3 g by 1% of its size.
    On a plane 0.5 degrees steeper than its friction (an unbalanced 0.01 g) the block slides
    0.2 m in 40 steps; 0.5 degrees flatter it settles on its springs (under 1%). At the
    fall's dynamic step (0.032 s), which static analysis took before, the sliding block
    moved 2 mm in 40 steps and could not be told from the standing one."""
    from dda.auto_settings import STATIC_STEPS

    moved = {}
    for slope in (29.5, 30.5):
        sim = dda.Simulation(_incline_block(slope), dt="auto", analysis="static",
                             solver=solver)
        assert "a static step" in sim.choices
        # d = 4 x 1% x 1 m / (40 x 1e-3 g): 0.319 s
        assert sim.dt == pytest.approx(np.sqrt(4 * 0.01 / (40 * 1e-3 * 9.81)), rel=1e-12)
        result = sim.run(STATIC_STEPS * sim.dt, progress=False)
        moved[slope] = float(np.hypot(*result.displacement("block")[-1]))
    assert moved[29.5] < 0.01
    # N steps of a dt^2 / 2, a = g (sin 30.5 - cos 30.5 tan 30) = 0.0991 m/s^2: 0.202 m
    a = 9.81 * (np.sin(np.radians(30.5)) - np.cos(np.radians(30.5)) * np.tan(np.radians(30)))
    assert moved[30.5] == pytest.approx(STATIC_STEPS * a * sim.dt**2 / 2, rel=0.05)


def test_a_static_auto_step_is_capped_by_a_stiff_given_penalty():
    """50 contact periods of the lightest block on the stiffest joint, as the factor of
    safety's static trials are capped."""
    scene = _incline_block(20.0)
    scene.set_joint(JointMaterial(1e12, 1e12, CoulombSingle(phi=30.0)))
    sim = dda.Simulation(scene, dt="auto", analysis="static")
    assert sim.dt == pytest.approx(50 * 2 * np.pi * np.sqrt(2500.0 / 1e12), rel=1e-12)
    assert "capped at 50 contact periods" in sim.choices


def test_a_square_wave_of_jump_pairs_is_probed_at_its_sampling_interval():
    """Every switch written as two samples 1e-9 s apart: their median spacing is the hair,
    and probing at it asked for 73.8 GiB, even with a given dt (a review of the fix that
    took the median)."""
    switch = np.arange(0.0, 10.0, 0.1)
    t = np.sort(np.concatenate([switch, switch + 1e-9]))
    level = np.where(np.arange(len(t)) % 4 < 2, -1.0, 1.0)
    level[0] = 0.0
    history = AccelerationHistory(0.3 * G * level, t)
    assert history.typical_spacing == pytest.approx(9.9 / 199, rel=1e-6)  # not 1e-9
    f = shaking_frequency([history])
    assert f is not None and 5.0 < f < 100.0  # a 5 Hz square wave's harmonics
    scene = column(1, shake=(t, np.column_stack([0.3 * G * level, 0 * t])))
    dda.Simulation(scene, dt=1e-3)
    dda.Simulation(scene, dt="auto")
