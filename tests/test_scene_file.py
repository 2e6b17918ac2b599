"""TOML scene files: everything the API says, and errors that name the line and the key."""

import textwrap

import numpy as np
import pytest

import dda
from dda.contact import BartonBandis, StaticDynamicTransition
from dda.io.scene_file import SceneFileError, key_lines, load_scene
from dda.solvers import LegacyPullBack, NewtonRaphson

FULL = """
[scene]
gravity = 9.81

[materials.rock]
young = 1e9
poisson = 0.25
density = 2500.0

[materials.soft]
young = 1e8
poisson = 0.2
density = 2000.0
plane = "strain"

[joints.default]
normal_penalty = 1e9
shear_penalty = 1e9
friction = { law = "coulomb", phi = 30.0 }

[[joints.pair]]
between = ["base", "top"]
normal_penalty = 2e9
shear_penalty = 2e9
friction = { law = "transition", phi_static = 35.0, phi_dynamic = 25.0 }
restitution = 0.2

[[blocks]]
name = "base"
material = "rock"
vertices = [[0, 0], [4, 0], [4, 1], [0, 1]]
fixed = true

[[blocks]]
name = "top"
material = "soft"
vertices = [[1, 1], [2, 1], [2, 2], [1, 2]]
rigid = true
velocity = [0.1, 0.0]

[[cut]]
name = "cut"
material = "rock"
domain = [[2.5, 1], [3.5, 1], [3.5, 2], [2.5, 2]]
min_size = 0.05
joint_sets = [{ dip = 0.0, spacing = 0.5, offset = 0.25 }]

[[shake]]
block = "base"
sine = { amplitude = 2.0, frequency = 2.0, start = 0.01 }

[[load]]
block = "top"
point = [1.5, 2.0]
force = [0.0, -100.0]

[simulation]
dt = 1e-3
duration = 0.02
solver = "legacy"
max_open_close = 20

[output]
prefix = "full"
every = 5
"""


def write(tmp_path, text, name="scene.toml"):
    f = tmp_path / name
    f.write_text(textwrap.dedent(text))
    return f


def test_a_full_scene_builds_what_the_api_would(tmp_path):
    loaded = load_scene(write(tmp_path, FULL))
    scene = loaded.scene
    assert [b.name for b in scene.blocks] == ["base", "top", "cut0", "cut1", "cut2"]
    assert scene.gravity == 9.81
    top = scene._blocks[1]
    assert top.rigid and top.material.plane == "strain" and top.velocity[0] == 0.1
    assert scene._blocks[0].fixed
    pair = scene.joint_for(0, 1)
    assert isinstance(pair.friction, StaticDynamicTransition) and pair.normal_penalty == 2e9
    assert pair.restitution == 0.2 and scene.joint_for(1, 2).restitution == 0.0
    assert scene.joint_for(1, 2).friction.phi == 30.0
    assert isinstance(loaded.solver, LegacyPullBack)
    assert loaded.settings == {"dt": 1e-3, "max_open_close": 20}
    assert loaded.effects == ["gravity", "shaking of block 'base'", "point load on block 'top'"]
    result = loaded.run(out=tmp_path / "out")
    assert len(result.stats) == 20
    assert (tmp_path / "out" / "full.pvd").is_file()
    # the same scene through the API gives the same numbers
    api = dda.Scene(gravity=9.81)
    ids = {}
    for handle, b in zip(scene.blocks, scene._blocks, strict=True):
        ids[handle.name] = api.add_block(b.vertices, b.material, fixed=b.fixed, rigid=b.rigid,
                                         velocity=b.velocity, name=handle.name)
    api.set_joint(scene._joints.default)
    api.set_joint(pair, between=(ids["base"], ids["top"]))
    api.shake(ids["base"], acceleration=lambda t: (  # the sine from rest: half amplitude
        (1.0 if t < 0.01 + 0.25 else 2.0) * np.sin(4.0 * np.pi * (t - 0.01))  # for T/2
        if t >= 0.01 else 0.0, 0.0))
    api.add_point_load(ids["top"], (1.5, 2.0), (0.0, -100.0))
    ref = dda.Simulation(api, dt=1e-3, solver=LegacyPullBack(), max_open_close=20).run(0.02)
    for name in ("top", "cut0", "cut1", "cut2"):
        assert np.abs(result.displacement(name)).max() > 0.0
        np.testing.assert_allclose(result.displacement(name), ref.displacement(name),
                                   rtol=1e-12, atol=1e-15)


def test_the_output_table_sets_the_writers_interval_and_names(tmp_path):
    """``[output] interval`` (evenly spaced frames in simulated time) and ``plain_names``
    reach the writer (they were unknown keys); a plausibility warning of the file is given
    once, with its line (``loaded.simulation()`` repeated it without)."""
    import warnings

    text = (FULL.replace("every = 5", "interval = 0.004\nplain_names = false")
            .replace("dt = 1e-3", "dt = 1e-3\nrecord_every = 1"))
    loaded = load_scene(write(tmp_path, text))
    writer = loaded.writer(tmp_path / "out")
    assert (writer.interval, writer.every, writer.plain_names) == (0.004, 1, False)
    loaded.run(out=tmp_path / "out")
    from dda.plot import read_pvd

    times = [t for t, _ in read_pvd(tmp_path / "out" / "full.pvd")]
    np.testing.assert_allclose(times, [0.0, 0.004, 0.008, 0.012, 0.016, 0.02], atol=1e-12)
    long = write(tmp_path, FULL.replace("dt = 1e-3", "dt = 0.5"), "long.toml")
    with pytest.warns(dda.PlausibilityWarning, match=r"long.toml, line \d+, simulation: "
                                                     r"Simulation: dt = 0.5 s is"):
        again = load_scene(long)
    with warnings.catch_warnings():
        warnings.simplefilter("error", dda.PlausibilityWarning)
        again.simulation()


def test_barton_and_newton_settings(tmp_path):
    text = FULL.replace('friction = { law = "coulomb", phi = 30.0 }',
                        'friction = { law = "barton", jrc = 10.0, jcs = 50e6, phi_r = 28.0 }')
    text = text.replace('solver = "legacy"', 'solver = "newton"\ntol = 1e-8\nmax_iter = 9')
    loaded = load_scene(write(tmp_path, text))
    assert isinstance(loaded.scene._joints.default.friction, BartonBandis)
    assert isinstance(loaded.solver, NewtonRaphson)
    assert (loaded.solver.tol, loaded.solver.max_iter) == (1e-8, 9)


def test_recorded_and_file_shaking(tmp_path):
    (tmp_path / "acc.csv").write_text("t,ax,ay\n0,0,0\n1,1,0\n2,0,0\n")
    base = FULL.replace('sine = { amplitude = 2.0, frequency = 2.0, start = 0.01 }',
                        'file = "acc.csv"')
    loaded = load_scene(write(tmp_path, base))
    u, v = loaded.scene._shakes[0].history.state(1.0)
    assert v[0] == pytest.approx(0.5) and u[0] == pytest.approx(1 / 6)
    rec = FULL.replace('sine = { amplitude = 2.0, frequency = 2.0, start = 0.01 }',
                       'times = [0.0, 1.0]\nvalues = [[0.0, 0.0], [2.0, 0.0]]')
    u, v = load_scene(write(tmp_path, rec)).scene._shakes[0].history.state(1.0)
    assert v[0] == pytest.approx(1.0)


def test_prescribed_velocity_frees_the_missing_direction(tmp_path):
    text = FULL.replace('[[load]]', '[[prescribe]]\nblock = "top"\nvelocity = { x = 1e-3 }\n'
                        '\n[[load]]')
    loaded = load_scene(write(tmp_path, text))
    motion = loaded.scene._motions[0]
    assert motion.displacement.mask.tolist() == [True, False]


@pytest.mark.parametrize("change, line, key, words", [
    ('material = "soft"', 'material = "sofft"', "blocks[1].material", "no material 'sofft'"),
    ("poisson = 0.2\n", "poisson = 0.7\n", "materials.soft", "poisson"),
    ("rigid = true", "rigid = 1", "blocks[1].rigid", "true or false"),
    ('between = ["base", "top"]', 'between = ["base", "tip"]', "joints.pair[0].between",
     "no block 'tip'"),
    ("phi_static = 35.0", "phi_static = 35.0, mu = 2", "joints.pair[0].friction",
     "unknown key 'mu'"),
    ("dt = 1e-3", "dt = -1e-3", "simulation.dt", "positive"),
    ("every = 5", "evry = 5", "output.evry", "unknown key"),
    ("every = 5", "every = 5\ninterval = 0.01", "output.interval", "not both"),
    ("every = 5", "interval = -0.01", "output.interval", "positive"),
    ("every = 5", "plain_names = 0", "output.plain_names", "true or false"),
    ("spacing = 0.5", "spacing = -0.5", "cut[0].joint_sets[0]", "spacing"),
    ("vertices = [[1, 1], [2, 1], [2, 2], [1, 2]]", "vertices = [[1, 1], [1, 2], [2, 2], [2, 1]]",
     "blocks[1]", "clockwise"),
    ('solver = "legacy"', 'solver = "implicit"', "simulation.solver", "'newton' or 'legacy'"),
    ("[joints.default]", "[joint.default]", "joint", "did you mean 'joints'?"),
    ("[[blocks]]", "[[block]]", "block", "did you mean 'blocks'?"),
    ("every = 5", "evry = 5", "output.evry", "did you mean 'every'?"),
])
def test_errors_name_the_line_and_the_key(tmp_path, change, line, key, words):
    text = FULL.replace(change, line, 1)
    assert text != FULL
    f = write(tmp_path, text)
    with pytest.raises(SceneFileError) as info:
        load_scene(f)
    msg = str(info.value)
    # the line the message names holds the key (or opens its table)
    number = int(msg.split(", line ")[1].split(",")[0])
    shown = text.splitlines()[number - 1]
    last = key.split(".")[-1].split("[")[0]
    assert last in shown or f"[{last}" in shown or f"[[{last}" in shown, (msg, shown)
    assert f", {key}:" in msg and words in msg, msg


def test_a_bracket_in_a_comment_keeps_the_lines_of_the_keys_after_it(tmp_path):
    text = FULL.replace('name = "base"', 'name = "base"  # see "Adachi" [2017, and {', 1)
    text = text.replace("every = 5", "evry = 5")
    with pytest.raises(SceneFileError) as info:
        load_scene(write(tmp_path, text))
    number = text.splitlines().index("evry = 5") + 1
    assert str(info.value).startswith(f"scene.toml, line {number}, output.evry: ")


def test_a_scene_file_without_joints_says_which_table_to_add(tmp_path):
    import re

    text = re.sub(r"\[joints.default\].*?\n\n\[\[joints.pair\]\].*?\n\n", "", FULL,
                  flags=re.S)
    assert "joints" not in text
    with pytest.raises(SceneFileError, match=r"joints: no \[joints.default\], and "
                                             r"\[\[joints.pair\]\] for 0 of the 10 block "
                                             r"pairs.*add \[joints.default\]"):
        load_scene(write(tmp_path, text))


def test_syntax_errors_and_missing_files(tmp_path):
    with pytest.raises(SceneFileError, match="not valid TOML.*line 2"):
        load_scene(write(tmp_path, "[scene]\ngravity = = 1\n"))
    with pytest.raises(SceneFileError, match="no scene file"):
        load_scene(tmp_path / "nothing.toml")
    with pytest.raises(SceneFileError, match="no blocks"):
        load_scene(write(tmp_path, "[scene]\ngravity = 1.0\n"))


def test_key_lines_follow_arrays_of_tables():
    text = '[a]\nx = 1\n[[b]]\ny = [1,\n 2]\nz = 3\n[[b]]\ny = 4\n[c.d]\n"q" = 1\n'
    lines = key_lines(text)
    assert lines[("a", "x")] == 2 and lines[("b", 0, "y")] == 4 and lines[("b", 0, "z")] == 6
    assert lines[("b", 1)] == 7 and lines[("b", 1, "y")] == 8 and lines[("c", "d", "q")] == 10


def test_a_scene_file_run_can_be_checkpointed(tmp_path):
    loaded = load_scene(write(tmp_path, FULL))
    sim = loaded.simulation()
    sim.run(0.005, checkpoint=tmp_path / "run.ckpt")
    resumed = dda.Simulation.resume(tmp_path / "run.ckpt")
    assert resumed.state.time == pytest.approx(0.005)


TABLES = """
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
vertices = [[0, 0], [4, 0], [4, 1], [0, 1]]
fixed = true
[[blocks]]
name = "top"
material = "rock"
vertices = [[1, 1], [2, 1], [2, 2], [1, 2]]
[[blocks]]
name = "platen"
material = "rock"
vertices = [[3, 1], [3.5, 1], [3.5, 1.5], [3, 1.5]]
[[prescribe]]
block = "platen"
displacement = { times = [0.0, 0.01, 0.03], x = [0.0, 1e-4, 1e-4] }
[[load]]
block = "top"
point = [2.0, 1.5]
force = { times = [0.0, 0.02], x = [0.0, 3e4] }
[[damping]]
mass = 2.0
[[damping]]
stiffness = 1e-4
blocks = ["top"]
[simulation]
dt = 1e-3
duration = 0.03
solver = "newton"
[output]
prefix = "tables"
checkpoint = "tables.ckpt"
checkpoint_every = 10
"""


def test_time_tables_and_damping_equal_the_api(tmp_path):
    from dda.effects import TimeTable

    loaded = load_scene(write(tmp_path, TABLES))
    assert loaded.effects == ["gravity", "prescribed motion of block 'platen'",
                              "point load on block 'top'", "damping"]
    alpha, beta = loaded.scene.damping_coefficients()
    # a later table overrides both coefficients of the blocks it names (as set_damping does)
    assert alpha.tolist() == [2.0, 0.0, 2.0] and beta.tolist() == [0.0, 1e-4, 0.0]
    result = loaded.run(out=tmp_path / "out")
    assert (tmp_path / "out" / "tables.ckpt").is_file()
    # the same scene through the API, with plain functions for the histories
    api = dda.Scene(gravity=9.81)
    for handle, b in zip(loaded.scene.blocks, loaded.scene._blocks, strict=True):
        api.add_block(b.vertices, b.material, fixed=b.fixed, name=handle.name)
    api.set_joint(loaded.scene._joints.default)
    api.prescribe_motion("platen", lambda t: (float(np.interp(t, [0, 0.01], [0, 1e-4])), None))
    api.add_point_load("top", (2.0, 1.5), lambda t: (float(np.interp(t, [0, 0.02], [0, 3e4])),
                                                     0.0))
    api.set_damping(mass=2.0)
    api.set_damping(stiffness=1e-4, blocks=["top"])
    ref = dda.Simulation(api, dt=1e-3, solver=NewtonRaphson()).run(0.03)
    for name in ("top", "platen"):
        assert np.abs(result.displacement(name)).max() > 1e-6
        np.testing.assert_allclose(result.displacement(name), ref.displacement(name),
                                   rtol=1e-10, atol=1e-14)
    # the platen's x follows the table through penalty springs; its y is free: it settles
    # into its joint with the base under its weight (p_n = 1e9 N/m over two contacts), between
    # none and twice the static sink (a weight applied at once), held at zero if y were fixed
    u = result.displacement("platen")
    assert u[-1, 0] == pytest.approx(1e-4, rel=1e-3)
    assert 0.2 < -u[-1, 1] / (2500.0 * 9.81 * 0.25 / 2e9) < 2.0
    # TimeTable holds the last value and leaves a missing direction free
    table = TimeTable([0.0, 1.0], x=[0.0, 2.0])
    assert table(0.25) == (0.5, None) and table(9.0) == (2.0, None)


def test_a_scene_file_checkpoint_resumes_through_the_command(tmp_path, capsys):
    from dda.cli import main

    f = write(tmp_path, TABLES)
    assert main(["run", str(f), "--out", str(tmp_path / "out"), "--duration", "0.01",
                 "--no-progress"]) == 0
    ckpt = tmp_path / "out" / "tables.ckpt"
    assert ckpt.is_file() and f"checkpoint {ckpt}" in capsys.readouterr().out
    assert main(["run", str(ckpt), "--duration", "0.01", "--no-progress"]) == 0
    assert "resuming at t = 0.01 s" in capsys.readouterr().out
    assert dda.Simulation.resume(ckpt).state.time == pytest.approx(0.02)


def test_the_file_format_covers_every_api_setting():
    """A setting added to the API must get a key in the file format (this test says which)."""
    import inspect

    from dda.io import scene_file

    source = inspect.getsource(scene_file.load_scene)
    scene_methods = {"add_block": "scene.add_block", "set_joint": "scene.set_joint",
                     "shake": "scene.shake", "prescribe_motion": "scene.prescribe_motion",
                     "add_point_load": "scene.add_point_load",
                     "set_damping": "scene.set_damping",
                     "set_water_table": "scene.set_water_table", "add_bolt": "scene.add_bolt",
                     "set_initial_stress": "scene.set_initial_stress"}
    public = {n for n, v in vars(dda.Scene).items() if callable(v) and not n.startswith("_")}
    readers = {"block", "joint_for", "validate", "vertex_arrays", "damping_coefficients"}
    assert public - readers == set(scene_methods), "a new Scene method needs a table"
    for call in scene_methods.values():
        assert call in source
    for name in inspect.signature(dda.Simulation.__init__).parameters:
        if name not in ("self", "scene", "solver", "output"):
            assert f'"{name}"' in source, f"[simulation] has no key {name!r}"
    for name in ("checkpoint", "checkpoint_every"):
        assert f'"{name}"' in source, f"[output] has no key {name!r}"
    for name in inspect.signature(dda.io.VTUWriter.__init__).parameters:
        if name not in ("self", "prefix"):
            assert f'"{name}"' in source, f"[output] has no key {name!r} (VTUWriter's)"
    for name in inspect.signature(dda.Scene.add_block).parameters:
        if name not in ("self", "vertices"):
            assert f'"{name}"' in source, f"[[blocks]] has no key {name!r}"
    reader = inspect.getsource(scene_file._read_scene)
    for name in inspect.signature(dda.Scene.__init__).parameters:
        if name != "self":
            assert f'"{name}"' in reader, f"[scene] has no key {name!r}"


@pytest.mark.parametrize("change, line, key, words", [
    ("displacement = { times = [0.0, 0.01, 0.03], x = [0.0, 1e-4, 1e-4] }",
     "displacement = { times = [0.0, 0.01, 0.03], x = [0.0, 1e-4] }",
     "prescribe[0].displacement", "x has 2 values for 3 times"),
    ("displacement = { times = [0.0, 0.01, 0.03], x = [0.0, 1e-4, 1e-4] }",
     "displacement = { times = [0.0, 0.01, 0.03], x = [1e-5, 1e-4, 1e-4] }",
     "prescribe[0]", "displacement(0) must be zero"),
    ("displacement = { times", "velocity = { x = 1.0 }\ndisplacement = { times",
     "prescribe[0]", "give one of velocity"),
    ("force = { times = [0.0, 0.02], x = [0.0, 3e4] }",
     "force = { times = [0.02, 0.0], x = [0.0, 3e4] }", "load[0].force", "increase strictly"),
    ('blocks = ["top"]', 'blocks = ["tip"]', "damping[1].blocks", "no block 'tip'"),
    ("mass = 2.0", "mass = -2.0", "damping[0]", "mass must not be negative"),
    ("checkpoint_every = 10", "checkpoint_every = 0", "output.checkpoint_every",
     "at least 1"),
    ("force = { times = [0.0, 0.02], x = [0.0, 3e4] }", "force = { times = 5, x = [0.0] }",
     "load[0].force", "times must be a 1-D list"),
    ("force = { times = [0.0, 0.02], x = [0.0, 3e4] }", "force = { times = [0.0], x = 5 }",
     "load[0].force", "x must be a list of numbers"),
])
def test_table_errors_name_the_line_and_the_key(tmp_path, change, line, key, words):
    text = TABLES.replace(change, line, 1)
    assert text != TABLES
    with pytest.raises(SceneFileError) as info:
        load_scene(write(tmp_path, text))
    msg = str(info.value)
    assert f", {key}:" in msg and words in msg, msg
    number = int(msg.split(", line ")[1].split(",")[0])
    shown = text.splitlines()[number - 1]
    last = key.split(".")[-1].split("[")[0]
    assert last in shown, (msg, shown)


def test_a_restitution_outside_0_to_1_names_its_line(tmp_path):
    text = FULL.replace("restitution = 0.2", "restitution = 1.5")
    with pytest.raises(SceneFileError, match=r"joints\.pair\[0\].*restitution must be between"):
        load_scene(write(tmp_path, text))


@pytest.mark.parametrize("line, message", [
    ('dir = "../../escaped"', "goes up out of the folder with '..'"),
    ('dir = "/tmp/dda-escaped"', "is an absolute path"),
    ('dir = "out/../../escaped"', "goes up out of the folder"),
    ('prefix = "../../escaped/x"', "must be a file name"),
    ('prefix = "sub/x"', "must be a file name"),
    ('checkpoint = "../run.ckpt"', "must be a file name"),
    ('checkpoint = ".."', "must be a file name"),
])
def test_a_scene_files_output_stays_in_its_folder(tmp_path, line, message):
    """A scene file from someone else writes nowhere but in its own folder (issue 21)."""
    key = line.split(" =")[0]
    text = FULL.replace('prefix = "full"', line if key == "prefix" else
                        f'prefix = "full"\n{line}')
    with pytest.raises(SceneFileError, match=message) as info:
        load_scene(write(tmp_path, text))
    assert f"output.{key}" in str(info.value)
    if key == "dir":
        assert "--allow-outside-output" in str(info.value)


def test_a_link_that_leads_out_is_refused_and_the_option_allows_it(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    scene_dir = tmp_path / "scene"
    scene_dir.mkdir()
    (scene_dir / "link").symlink_to(outside, target_is_directory=True)
    text = FULL.replace('prefix = "full"', 'prefix = "full"\ndir = "link/out"')
    path = write(scene_dir, text)
    with pytest.raises(SceneFileError, match="leads out of the scene file's folder"):
        load_scene(path)
    assert load_scene(path, allow_outside_output=True).output_dir == scene_dir / "link/out"
    inside = load_scene(write(scene_dir, FULL.replace('prefix = "full"',
                                                      'prefix = "full"\ndir = "a/b"')))
    assert inside.output_dir == scene_dir / "a/b"


def test_the_command_needs_the_option_to_write_outside(tmp_path, capsys):
    from dda.cli import main

    text = TABLES.replace('prefix = "tables"', 'prefix = "tables"\ndir = "../elsewhere"')
    scene_dir = tmp_path / "scene"
    scene_dir.mkdir()
    f = write(scene_dir, text)
    assert main(["run", str(f), "--duration", "0.002", "--no-progress"]) == 2
    assert "goes up out of the folder" in capsys.readouterr().err
    assert not (tmp_path / "elsewhere").exists()
    assert main(["run", str(f), "--duration", "0.002", "--no-progress",
                 "--allow-outside-output"]) == 0
    assert (tmp_path / "elsewhere" / "tables.pvd").is_file()


def test_an_overlap_points_at_the_blocks_lines(tmp_path):
    """Blocks that overlap at the start: the error is at the second block's table, names the
    first one's line, and says how deep (it used to point at [simulation])."""
    text = FULL.replace("vertices = [[1, 1], [2, 1], [2, 2], [1, 2]]",
                        "vertices = [[1, 0.99], [2, 0.99], [2, 2], [1, 2]]")
    f = write(tmp_path, text)
    base = text.splitlines().index('name = "base"') + 1   # dedent keeps the lines
    top = text.splitlines().index('name = "top"') + 1
    with pytest.raises(SceneFileError, match=rf"scene.toml, line {top - 1}, blocks\[1\]: "
                       rf"block 'base' and block 'top' overlap at the start by 0.01 m.*"
                       rf"\('base' is at line {base - 1}\)"):
        load_scene(f)


def test_a_loaded_scene_given_to_simulation_says_what_to_pass(tmp_path):
    loaded = dda.load_scene(write(tmp_path, FULL))
    with pytest.raises(TypeError, match=r"LoadedScene: pass its \.scene, or call its "
                                        r"\.simulation\(\)"):
        dda.Simulation(loaded, dt=1e-3)


@pytest.mark.parametrize("value", [
    '"top [v2"',
    "'''it's [v2'''",
    '"""\\\n  top [v2\n  # [ not a comment\n"""',
    "'''\n[simulation]\n'''",
    '"a \\" [ b"',
])
def test_keys_after_a_string_with_brackets_keep_their_lines(value):
    """Brackets, quotes and table headers inside strings, one-line or multi-line, basic or
    literal, open nothing (a triple-quoted one still cost every later key its line)."""
    import tomllib

    text = f'[[blocks]]\nname = {value}\nmaterial = "stone"\n\n[simulation]\ndt = 2e-3\n'
    tomllib.loads(text)  # valid TOML
    lines = key_lines(text)
    rows = text.splitlines()
    assert lines[("simulation",)] == len(rows) - 1 and lines[("simulation", "dt")] == len(rows)
    assert lines[("blocks", 0, "material")] == len(rows) - 3


@pytest.mark.parametrize("value", ['["""x""""]', "['''x''''']", '["""x\ny""""]'])
def test_a_multi_line_string_ends_at_the_last_three_of_its_quotes(value):
    """Four or five quotes end a multi-line string at the last three (the string then holds
    one or two of them): closed at the first three, the fourth opened a string that took the
    array's ']' and every later key lost its line."""
    import tomllib

    text = f"a = {value}\nb = 1\n[t]\nc = 2\n"
    tomllib.loads(text)  # valid TOML
    rows = len(text.splitlines())
    assert key_lines(text) == {("a",): 1, ("b",): rows - 2, ("t",): rows - 1,
                               ("t", "c"): rows}


def test_a_cut_with_an_opening(tmp_path):
    """[[cut]] openings: outlines taken out of the domain before it is cut, as
    dda.geometry.cut_blocks(..., openings=...) takes them; a bad outline names its line."""
    from dda.geometry import JointSet, cut_blocks

    opening = "openings = [[[2.9, 1.6], [3.1, 1.6], [3.1, 1.9], [2.9, 1.9]]]\n"
    text = FULL.replace("min_size = 0.05\n", "min_size = 0.05\n" + opening)
    loaded = load_scene(write(tmp_path, text))
    cut = [inp for h, inp in zip(loaded.scene.blocks, loaded.scene.block_inputs, strict=True)
           if h.name.startswith("cut")]
    expected = cut_blocks([(2.5, 1), (3.5, 1), (3.5, 2), (2.5, 2)],
                          [JointSet(dip=0.0, spacing=0.5, offset=0.25)], min_size=0.05,
                          openings=[[(2.9, 1.6), (3.1, 1.6), (3.1, 1.9), (2.9, 1.9)]])
    assert len(cut) == len(expected) == 3  # three strips, two notched by the opening
    area = sum(0.5 * abs(np.cross(np.roll(v, -1, 0), v).sum())
               for v in (np.asarray(b.vertices) for b in cut))
    assert area == pytest.approx(1.0 - 0.06, rel=1e-9)
    bad = FULL.replace("min_size = 0.05\n", "min_size = 0.05\nopenings = [[[2.9, 1.6]]]\n")
    with pytest.raises(SceneFileError, match=r"line \d+, cut\[0\]: cut_blocks: openings\[0\] "
                                             r"must be \(n, 2\) corners, n >= 3"):
        load_scene(write(tmp_path, bad, "bad.toml"))
