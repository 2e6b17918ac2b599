"""A scene as plain data and back (dda.io.scene_data): every kind of input survives, the run
from the scene read back is the same to the bit, and what cannot be named is refused at once
with what to do instead."""

import json

import numpy as np
import pytest

import dda
from dda.contact import BartonBandis, CoulombSingle, JointMaterial, StaticDynamicTransition
from dda.effects import TimeTable
from dda.io.scene_data import (
    ArrayStore,
    SceneDataError,
    resolve_function,
    scene_from_data,
    scene_to_data,
)
from dda.io.scene_file import ConstantVelocity, SineAcceleration
from dda.materials import LinearElastic
from tests import scene_data_helpers as helpers
from tests.conftest import box


def full_scene():
    """Every input a scene takes: fixed, rigid and moving blocks, two materials, a default
    joint and pair joints with the three built-in laws and a law of the tests' own, shaking
    by a function, by a record and by the scene file's sine, prescribed motions by a time
    table, a function (with points) and a constant velocity, constant and varying point loads,
    damping of some blocks."""
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    soft = LinearElastic(young=2e8, poisson=0.3, density=2000.0, plane="strain")
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, -0.5, 3.2, 0.5), rock, fixed=True, name="base")
    a = scene.add_block(box(0.5, 0.0, 0.4, 0.3), rock, name="a", velocity=(0.2, 0.0))
    b = scene.add_block(box(1.5, 0.0, 0.4, 0.3), soft, name="b", angular_velocity=0.5,
                        rigid=True)
    c = scene.add_block(box(2.5, 0.0, 0.4, 0.3), rock, name="c")
    table2 = scene.add_block(box(3.5, -0.2, 0.8, 0.2), rock, fixed=True, name="table2")
    table3 = scene.add_block(box(4.5, -0.2, 0.8, 0.2), rock, fixed=True, name="table3")
    d = scene.add_block(box(3.7, 0.0, 0.3, 0.3), rock, name="d")
    e = scene.add_block(box(4.7, 0.0, 0.3, 0.3), rock, name="e")
    scene.set_joint(JointMaterial(1e9, 5e8, CoulombSingle(phi=30.0, cohesion=10.0),
                                  restitution=0.2))
    scene.set_joint(JointMaterial("auto", "auto", StaticDynamicTransition(40, 30)),
                    between=("base", a))
    scene.set_joint(JointMaterial(2e9, 2e9, BartonBandis(jrc=8, jcs=40e6, phi_r=27,
                                                         block_size=0.4),
                                  shear_dashpot=False), between=(b, "base"))
    scene.set_joint(JointMaterial(1e9, 1e9, helpers.Sticky(phi=25.0, glue=50.0)),
                    between=(c, "base"))
    scene.shake("base", acceleration=helpers.table)
    scene.shake(table2, acceleration=np.array([[0.0, 0.0], [1.0, 0.5], [0.0, 0.0]]),
                times=[0.1, 0.5, 2.0])
    scene.shake(table3, acceleration=SineAcceleration(2.0, 3.0, start=0.05,
                                                      direction=(0.6, 0.8)))
    scene.prescribe_motion(d, TimeTable([0.0, 1.0], x=[0.0, 1e-3]), penalty=1e8)
    scene.prescribe_motion(e, helpers.slide, points=[(4.7, 0.3), (5.0, 0.3)])
    scene.add_block(box(5.4, 0.0, 0.3, 0.3), rock, name="f")
    scene.prescribe_motion("f", ConstantVelocity(0.01, None))
    scene.add_point_load(a, (0.7, 0.3), (0.0, -1e3))
    scene.add_point_load(c, (2.7, 0.3), helpers.push)
    scene.set_damping(mass=0.1)
    scene.set_damping(stiffness=1e-4, blocks=[b, "c"])
    return scene


def round_trip(scene):
    store = ArrayStore()
    data = json.loads(json.dumps(scene_to_data(scene, store)))  # plain JSON all through
    return scene_from_data(data, ArrayStore(store.arrays)), data, store


def test_every_input_survives_the_round_trip():
    scene = full_scene()
    back, _, _ = round_trip(scene)
    assert [h.name for h in back.blocks] == [h.name for h in scene.blocks]
    for x, y in zip(scene.block_inputs, back.block_inputs, strict=True):
        np.testing.assert_array_equal(x.vertices, y.vertices)
        np.testing.assert_array_equal(x.velocity, y.velocity)
        assert (x.material, x.fixed, x.angular_velocity, x.rigid) == (
            y.material, y.fixed, y.angular_velocity, y.rigid)
    joints = [scene.default_joint, *scene.pair_joints.values()]
    read = [back.default_joint, *back.pair_joints.values()]
    assert back.pair_joints.keys() == scene.pair_joints.keys()
    for j, r in zip(joints, read, strict=True):  # (laws have no __eq__: their attributes)
        assert type(r.friction) is type(j.friction)
        assert vars(r.friction) == vars(j.friction)
        assert (r.normal_penalty, r.shear_penalty, r.restitution, r.shear_dashpot) == (
            j.normal_penalty, j.shear_penalty, j.restitution, j.shear_dashpot)
    assert back.damping_settings == scene.damping_settings
    t = np.linspace(0.0, 1.9, 37)
    for s, r in zip(scene.shakes, back.shakes, strict=True):
        np.testing.assert_array_equal(s.history.sample(t), r.history.sample(t))
    for s, r in zip(scene.motions, back.motions, strict=True):
        assert all(np.array_equal(s.displacement(ti), r.displacement(ti)) for ti in t)
        assert s.penalty == r.penalty
    for s, r in zip(scene.point_loads, back.point_loads, strict=True):
        assert all(np.array_equal(s.force(ti), r.force(ti)) for ti in t)
    assert back.shakes[0].history.function is helpers.table  # named, not copied


def test_the_scene_read_back_runs_the_same_steps():
    scene = full_scene()
    back, _, _ = round_trip(scene)
    runs = [dda.Simulation(s, dt=1e-3, solver=dda.solvers.LegacyPullBack()).run(
        0.05, progress=False) for s in (scene, back)]
    for name in ("a", "b", "c", "d", "e", "f"):
        np.testing.assert_array_equal(runs[0].displacement(name), runs[1].displacement(name))
    np.testing.assert_array_equal(runs[0].stats["open_close_passes"],
                                  runs[1].stats["open_close_passes"])


@pytest.mark.parametrize("make, message", [
    (lambda: (lambda t: (0.0, 0.0)), "no import path"),   # a lambda
    (helpers.make_closure, "no import path"),             # a function inside another
    (helpers.Pulse, "not a plain function"),              # a callable object
])
def test_a_history_without_an_import_path_is_refused_with_what_to_do(make, message):
    scene = dda.Scene()
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene.add_block(box(0, 0, 1, 1), rock, fixed=True, name="table")
    scene.shake("table", acceleration=make())
    with pytest.raises(SceneDataError, match=message) as info:
        scene_to_data(scene, ArrayStore())
    assert "shaking of block 'table'" in str(info.value)
    assert "TimeTable" in str(info.value)


def test_a_function_of_the_script_run_as_a_program_is_refused():
    def accel(t):
        return (0.0, 0.0)

    accel.__module__, accel.__qualname__ = "__main__", "accel"
    scene = dda.Scene()
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene.add_block(box(0, 0, 1, 1), rock, fixed=True, name="table")
    scene.shake("table", acceleration=accel)
    with pytest.raises(SceneDataError, match="__main__.accel has no import path"):
        scene_to_data(scene, ArrayStore())


def test_a_law_defined_in_main_is_refused():
    law = type("Local", (CoulombSingle,), {"__module__": "__main__"})(phi=30.0)
    scene = dda.Scene()
    scene.set_joint(JointMaterial(1e9, 1e9, law))
    with pytest.raises(SceneDataError, match="import path"):
        scene_to_data(scene, ArrayStore())


@pytest.mark.parametrize("path, message", [
    ("os:system", "names no function"),       # a builtin, not a plain function
    ("builtins:eval", "names no function"),
    ("tests.scene_data_helpers:Sticky", "names no function"),  # a class
    ("json:nope", "names no function"),
    ("no_such_module_x:f", "cannot import"),
    ("os.path:join; import os", "import path"),
    ("__import__('os')", "import path"),
])
def test_function_paths_name_plain_functions_only(path, message):
    with pytest.raises(SceneDataError, match=message):
        resolve_function(path, "here")


def test_data_that_is_not_a_scene_says_where():
    _, data, store = round_trip(full_scene())
    bad = json.loads(json.dumps(data))
    bad["blocks"]["material"][1] = 7
    with pytest.raises(SceneDataError, match=r"scene.blocks.material\[1\]"):
        scene_from_data(bad, store)
    bad = json.loads(json.dumps(data))
    bad["joints"]["default"]["friction"]["law"] = "os:system"
    with pytest.raises(SceneDataError, match="not a subclass"):
        scene_from_data(bad, store)
    with pytest.raises(SceneDataError, match="unknown keys"):
        scene_from_data({**data, "extra": 1}, store)
