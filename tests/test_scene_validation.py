"""Bad input gets an error that names the block, joint or argument and says what is wrong."""

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic
from tests.conftest import box

ROCK = LinearElastic(young=1e9, poisson=0.2, density=2000.0)
JOINT = JointMaterial(normal_penalty=1e9, shear_penalty=1e9, friction=CoulombSingle(phi=30))


def test_clockwise_polygon_named():
    scene = dda.Scene()
    with pytest.raises(ValueError, match=r"block 'cw'.*clockwise"):
        scene.add_block(box(0, 0, 1, 1)[::-1], ROCK, name="cw")


def test_self_intersecting_polygon_named():
    scene = dda.Scene()
    with pytest.raises(ValueError, match=r"block 'bow'.*self-intersecting"):
        scene.add_block([(0, 0), (1, 1), (1, 0), (0, 1)], ROCK, name="bow")


@pytest.mark.parametrize("verts, what", [
    ([(0, 0), (1, 0)], "n >= 3"),
    ([(0, 0), (1, 0), (np.nan, 1)], "NaN"),
    ([(0, 0), (1, 0), (2, 0)], "zero area"),
    ([(0, 0), (0, 0), (1, 1)], "coincide"),
])
def test_degenerate_polygons(verts, what):
    with pytest.raises(ValueError, match=what):
        dda.Scene().add_block(verts, ROCK, name="b")


def test_overlapping_blocks_named():
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 1, 1), ROCK, name="a")
    scene.add_block(box(0.5, 0.5, 1, 1), ROCK, name="b")
    scene.set_joint(JOINT)
    with pytest.raises(ValueError, match=r"'a' and .*'b' overlap"):
        dda.Simulation(scene, dt=1e-3)


def test_crossing_without_vertex_inside_is_overlap():
    scene = dda.Scene()
    scene.add_block(box(0, 0.4, 3, 0.2), ROCK, name="bar")
    scene.add_block(box(1.4, 0, 0.2, 1), ROCK, name="post")
    scene.set_joint(JOINT)
    with pytest.raises(ValueError, match="overlap"):
        dda.Simulation(scene, dt=1e-3)


@pytest.mark.parametrize("second", [
    box(0, 0, 1, 1),                            # laid exactly on the first
    box(0, 0, 0.5, 1),                          # inside it along three shared edges
    [(0, 0), (1, 0), (1, 1)],                   # half of it, sharing every vertex
    box(0, 0, 1, 2),                            # covering it, sharing its bottom corners
])
def test_coincident_blocks_are_overlaps(second):
    """No vertex of one lies strictly inside the other and no edges cross properly, yet the
    blocks overlap: such a scene used to pass and run (found by tests/test_api_fuzz.py)."""
    scene = dda.Scene()
    scene.add_block(box(0, 0, 1, 1), ROCK, name="a")
    scene.add_block(second, ROCK, name="b")
    scene.set_joint(JOINT)
    with pytest.raises(ValueError, match=r"'a' and .*'b' overlap"):
        dda.Simulation(scene, dt=1e-3)


def test_touching_blocks_are_fine():
    scene = dda.Scene()
    scene.add_block(box(0, 0, 1, 1), ROCK, name="a")
    scene.add_block(box(1, 0, 1, 1), ROCK, name="b")  # shares an edge
    scene.add_block(box(2, 1, 1, 1), ROCK, name="c")  # shares a corner with b
    scene.set_joint(JOINT)
    dda.Simulation(scene, dt=1e-3)


@pytest.mark.parametrize("kwargs, name", [
    (dict(young=-1.0, poisson=0.2, density=1.0), "young"),
    (dict(young=np.nan, poisson=0.2, density=1.0), "young"),
    (dict(young=1.0, poisson=0.5, density=1.0), "poisson"),
    (dict(young=1.0, poisson=0.2, density=0.0), "density"),
])
def test_bad_material(kwargs, name):
    with pytest.raises(ValueError, match=name):
        LinearElastic(**kwargs)


@pytest.mark.parametrize("kwargs, name", [
    (dict(normal_penalty=-1.0, shear_penalty=1.0), "normal_penalty"),
    (dict(normal_penalty=1.0, shear_penalty=float("nan")), "shear_penalty"),
])
def test_bad_joint(kwargs, name):
    with pytest.raises(ValueError, match=name):
        JointMaterial(friction=CoulombSingle(phi=30), **kwargs)


@pytest.mark.parametrize("phi", [-1.0, 90.0, float("nan")])
def test_bad_friction_angle(phi):
    with pytest.raises(ValueError, match="phi"):
        CoulombSingle(phi=phi)


def test_joint_needs_a_law():
    with pytest.raises(TypeError, match="friction"):
        JointMaterial(normal_penalty=1.0, shear_penalty=1.0, friction=0.6)


def test_bad_simulation_arguments():
    scene = dda.Scene()
    scene.add_block(box(0, 0, 1, 1), ROCK)
    for kwargs, name in [(dict(dt=0.0), "dt"), (dict(dt=-1e-3), "dt"),
                         (dict(dt=1e-3, analysis="quasi"), "analysis"),
                         (dict(dt=1e-3, velocity_carry=1.5), "velocity_carry")]:
        with pytest.raises(ValueError, match=name):
            dda.Simulation(scene, **kwargs)
    with pytest.raises(ValueError, match="duration"):
        dda.Simulation(scene, dt=1e-3).run(duration=np.nan)


def test_record_that_does_not_cover_the_run():
    scene = dda.Scene(gravity=9.81)
    base = scene.add_block(box(0, 0, 1, 0.2), ROCK, name="table")
    scene.add_block(box(0.4, 0.2, 0.2, 0.2), ROCK)
    scene.set_joint(JOINT)
    t = np.linspace(0, 0.5, 51)
    scene.shake(base, acceleration=np.sin(t), times=t)
    sim = dda.Simulation(scene, dt=1e-2)
    with pytest.raises(ValueError, match=r"table.*ends at t = 0.5"):
        sim.run(duration=1.0)


def test_missing_default_joint():
    scene = dda.Scene()
    scene.add_block(box(0, 0, 1, 1), ROCK)
    scene.add_block(box(0, 1, 1, 1), ROCK)
    with pytest.raises(ValueError, match="default joint"):
        dda.Simulation(scene, dt=1e-3)


def test_blocks_are_found_by_name_in_a_scene_of_any_age():
    """Names are kept in an index as blocks are added (a search of the list made adding
    20,000 blocks take 9.6 s, now 1.6); a scene pickled before the index builds it; a name
    with a control character is refused (a zero byte ends a name in the VTU files)."""
    import pickle

    scene = dda.Scene()
    for i in range(5):
        scene.add_block(box(2 * i, 0, 1, 1), ROCK, name=f"b{i}")
    assert scene.block("b3").index == 3 and scene.block(4).name == "b4"
    old = pickle.loads(pickle.dumps(scene))
    del old.__dict__["_names"]  # as a checkpoint of before keeps it
    assert old.block("b2").index == 2
    with pytest.raises(ValueError, match="unique"):
        old.add_block(box(20, 0, 1, 1), ROCK, name="b0")
    assert old.add_block(box(20, 0, 1, 1), ROCK, name="b5").index == 5
    assert old.block("b5").index == 5
    with pytest.raises(ValueError, match="no block named"):
        old.block(["b5"])
    with pytest.raises(ValueError, match="control characters"):
        scene.add_block(box(30, 0, 1, 1), ROCK, name="a\0b")


def test_effect_conflicts_and_unknown_blocks():
    scene = dda.Scene()
    fixed = scene.add_block(box(0, 0, 1, 1), ROCK, fixed=True, name="f")
    with pytest.raises(ValueError, match="'f' is fixed"):
        scene.prescribe_motion(fixed, displacement=lambda t: (t, None))
    scene.shake(fixed, acceleration=lambda t: (1.0, 0.0))  # a fixed block may be a table
    with pytest.raises(ValueError, match="'f' has a prescribed motion"):
        scene.shake(fixed, acceleration=lambda t: (1.0, 0.0))
    with pytest.raises(ValueError, match="no block named"):
        scene.add_point_load("nope", point=(0, 0), force=(1, 0))
    with pytest.raises(ValueError, match="unique"):
        scene.add_block(box(2, 0, 1, 1), ROCK, name="f")
    with pytest.raises(ValueError, match="displacement"):
        scene.prescribe_motion(scene.add_block(box(4, 0, 1, 1), ROCK),
                               displacement=lambda t: (1.0 + t, None))


def _incline_scene(digits=None, shift=0.0):
    """A 1 m block on a 30 degree incline, its corners typed with ``digits`` decimals (or
    exact) and pushed ``shift`` m into the incline along its normal."""
    t = np.radians(30.0)
    along, normal = np.array([np.cos(t), np.sin(t)]), np.array([-np.sin(t), np.cos(t)])
    foot = 1.0 * along - shift * normal
    top = [foot, foot + along, foot + along + normal, foot + normal]
    if digits is not None:
        top = np.round(top, digits)
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(0, 0), (4 * np.cos(t), 0), (4 * np.cos(t), 4 * np.sin(t))], ROCK,
                    fixed=True, name="incline")
    scene.add_block([tuple(p) for p in top], ROCK, name="block")
    scene.set_joint(JOINT)
    return scene


def test_geometry_typed_with_six_decimals_runs():
    """Corners typed with 6 decimals leave the block 4e-7 m into the incline (under 1e-6 of
    its 1 m): the scene runs and the contact takes the overlap up, as a block set down exactly
    does. (With the tolerance at 1e-9 of the model's size this scene was refused.)"""
    typed = _incline_scene(digits=6, shift=4e-7)
    exact = _incline_scene()
    moved = []
    for scene in (typed, exact):
        result = dda.Simulation(scene, dt=1e-3).run(0.05)
        moved.append(result.displacement(scene.block("block"))[-1])
    # phi 30 on 30 degrees: the block creeps; the typed one as the exact one, to the overlap
    np.testing.assert_allclose(moved[0], moved[1], atol=2e-6)


def test_overlap_message_gives_the_depth_and_the_smaller_blocks_share():
    """2 mm into the incline; the tilted block's size is its bounding box's side, 1.366 m."""
    scene = _incline_scene(shift=2e-3)
    with pytest.raises(dda.OverlapError,
                       match=r"'incline' and .*'block' overlap at the start by 0.002 m, "
                             r"0.146% of the smaller block's size") as info:
        dda.Simulation(scene, dt=1e-3)
    assert info.value.depth == pytest.approx(2e-3, rel=1e-9)
    assert [b.name for b in info.value.blocks] == ["incline", "block"]


def test_the_tolerance_follows_the_smaller_block():
    """A pebble of 1 cm 1e-7 m into a 100 m base overlaps (1e-5 of its size); a 1 m block as
    deep does not (1e-7 of its size)."""
    for size, refused in ((0.01, True), (1.0, False)):
        scene = dda.Scene()
        scene.add_block(box(0, 0, 100, 10), ROCK, name="base", fixed=True)
        scene.add_block(box(50, 10 - 1e-7, size, size), ROCK, name="stone")
        scene.set_joint(JOINT)
        if refused:
            with pytest.raises(ValueError, match=r"overlap at the start by 1e-07 m, 0.001%"):
                dda.Simulation(scene, dt=1e-3)
        else:
            dda.Simulation(scene, dt=1e-3)


def test_a_block_inside_another_is_measured_against_its_size_in_percent():
    """A 0.2 m square wholly inside a 2 m one, 0.5 m from its nearest side: 250% of the
    smaller block's size (given as a bare ratio, 2.5 read as a share)."""
    scene = dda.Scene(gravity=9.81)
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene.add_block([(0, 0), (2, 0), (2, 2), (0, 2)], rock, fixed=True, name="big")
    scene.add_block([(0.5, 0.9), (0.7, 0.9), (0.7, 1.1), (0.5, 1.1)], rock, name="small")
    scene.set_joint(JointMaterial(1e9, 1e9, friction=CoulombSingle(phi=30.0)))
    with pytest.raises(dda.OverlapError, match=r"by 0\.\d+ m, \d+% of the smaller block's size"):
        dda.Simulation(scene, dt=1e-3)


def test_no_default_joint_says_how_many_pairs_have_one():
    scene = dda.Scene(gravity=9.81)
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    a = scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)], rock, fixed=True)
    b = scene.add_block([(0, 1), (1, 1), (1, 2), (0, 2)], rock)
    scene.add_block([(3, 0), (4, 0), (4, 1), (3, 1)], rock)
    scene.set_joint(JointMaterial(1e9, 1e9, friction=CoulombSingle(phi=30.0)), between=(a, b))
    with pytest.raises(ValueError, match=r"no default joint, and joints for 1 of its 3 block "
                                         r"pairs: any two blocks may come into contact"):
        dda.Simulation(scene, dt=1e-3)
