"""The dda command (run, demo, render, info) and the pictures: files that are not blank."""

import os
import subprocess
import sys

import numpy as np
import pytest

import dda
from dda import plot
from dda.cli import main

SCENE = """
[scene]
gravity = 9.81
[materials.rock]
young = 1e9
poisson = 0.25
density = 2500.0
[joints.default]
normal_penalty = 1e9
shear_penalty = 1e9
friction = { law = "coulomb", phi = 20.0 }
[[blocks]]
name = "base"
material = "rock"
vertices = [[0, 0], [3, 0], [3, 0.5], [0, 0.5]]
fixed = true
[[blocks]]
name = "top"
material = "rock"
vertices = [[1, 0.5], [1.5, 0.5], [1.5, 1.0], [1, 1.0]]
[[shake]]
block = "base"
sine = { amplitude = 6.0, frequency = 5.0, form = "sine" }  # full amplitude at once: slips
[simulation]
dt = 2e-3
duration = 0.1
solver = "legacy"
[output]
prefix = "slide"
every = 5
"""


def png_pixels(path):
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"), dtype=float)


def not_blank(pixels):
    """More than a background: many colours and a real spread."""
    colours = len(np.unique(pixels.reshape(-1, 3), axis=0))
    return colours > 20 and pixels.std() > 10.0


@pytest.fixture(scope="module")
def series(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cli")
    scene = tmp / "slide.toml"
    scene.write_text(SCENE)
    assert main(["run", str(scene), "--out", str(tmp / "out"), "--no-progress"]) == 0
    return scene, tmp / "out" / "slide.pvd"


def test_run_writes_the_series(series):
    scene, pvd = series
    entries = plot.read_pvd(pvd)
    assert len(entries) == 11  # 50 steps, every 5th, and the start
    assert entries[-1][0] == pytest.approx(0.1)


def test_render_png_and_gif(series, tmp_path):
    scene, pvd = series
    png, gif = tmp_path / "last.png", tmp_path / "run.gif"
    assert main(["render", str(pvd), "--png", str(png), "--gif", str(gif)]) == 0
    assert not_blank(png_pixels(png))
    from PIL import Image

    with Image.open(gif) as im:
        assert im.n_frames == 11
        im.seek(5)
        assert not_blank(np.asarray(im.convert("RGB"), dtype=float))


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="an X display's warning")
def test_render_without_a_display_prints_no_vtk_warning(series, tmp_path):
    """Headless, VTK's X window logged "bad X server connection" in colour on stderr at every
    render before rendering off screen anyway."""
    scene, pvd = series
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    proc = subprocess.run([sys.executable, "-m", "dda", "render", str(pvd), "--png",
                           str(tmp_path / "a.png")], capture_output=True, text=True, env=env,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "WARN" not in proc.stderr and "X server" not in proc.stderr, proc.stderr
    assert not_blank(png_pixels(tmp_path / "a.png"))


def test_render_mp4(series, tmp_path):
    import imageio.v3 as iio

    scene, pvd = series
    mp4 = tmp_path / "run.mp4"
    assert main(["render", str(pvd), "--mp4", str(mp4)]) == 0
    frames = list(iio.imiter(mp4, plugin="FFMPEG"))
    assert len(frames) == 11
    assert frames[0].shape == (608, 800, 3)  # 600 rounded up to whole 16-pixel blocks
    assert not_blank(np.asarray(frames[-1], dtype=float))
    # the blocks move between the first and the last frame (lossy codec: a real difference)
    assert np.abs(frames[-1].astype(float) - frames[0].astype(float)).mean() > 1.0


def test_animate_refuses_other_formats(series, tmp_path):
    with pytest.raises(ValueError, match="write a .gif or an .mp4"):
        plot.animate(series[1], tmp_path / "run.avi")


def test_history_plot_is_drawn(series, tmp_path):
    scene, pvd = series
    result = dda.load_scene(scene).run(duration=0.05)
    out = plot.history(result, path=tmp_path / "history.png", title="slide")
    assert out is not None
    pixels = png_pixels(tmp_path / "history.png")
    assert not_blank(pixels)
    # the three panels hold lines: every panel's middle column crosses some non-white pixel
    assert (pixels < 200).any(axis=2).sum() > 2000


def test_history_plots_the_slide_on_the_table_and_the_contact_states(series):
    scene, pvd = series
    result = dda.load_scene(scene).run(duration=0.1)
    fig = plot.history(result)
    disp, forces, states = fig.axes
    # on a shaken base the blocks' displacement is measured from the table's
    assert disp.get_ylabel() == "displacement relative\nto base (mm)"
    (line,) = disp.lines
    slide = result.displacement("top") - result.displacement("base")
    np.testing.assert_allclose(line.get_ydata(), 1e3 * np.hypot(*slide.T))
    assert 0.1 < line.get_ydata()[-1] < 0.9 * 1e3 * np.hypot(*result.displacement("top")[-1])
    absolute = plot.history(result, relative_to=None).axes[0]
    assert absolute.get_ylabel() == "displacement (mm)" and len(absolute.lines) == 2
    # 6 m/s2 on phi 20 (tan 20 g = 3.6 m/s2): the block's two contacts slip, then stick
    stick, slip, opened = (ln.get_ydata() for ln in states.lines)
    st = result.stats
    np.testing.assert_array_equal(np.asarray(stick) + slip, st.closed)
    np.testing.assert_array_equal(opened, st.contacts - st.closed)
    assert st.sliding.max() == 2 and (st.sliding == 0).any()
    import matplotlib.pyplot as plt

    plt.close("all")


def test_frames_relative_to_a_block(series):
    from dda.plot import _blocks_mesh, _pyvista

    scene, pvd = series
    last = plot.read_pvd(pvd)[-1][1]
    pv = _pyvista()
    mesh = _blocks_mesh(pv, last, "displacement", relative_to=0)
    u = np.asarray(mesh.cell_data["displacement"])
    ids = np.asarray(mesh.cell_data["block_id"]).astype(int)
    shown = np.asarray(mesh.cell_data["shown"])
    np.testing.assert_allclose(shown, np.linalg.norm(u - u[ids == 0][0], axis=1))
    assert shown[ids == 0][0] == 0.0 and shown[ids == 1][0] > 0.0
    with pytest.raises(ValueError, match="relative_to goes with"):
        _blocks_mesh(pv, last, "stress", relative_to=0)
    with pytest.raises(ValueError, match="no block field 'strain'") as info:
        _blocks_mesh(pv, last, "strain")
    listed = str(info.value).split("there are: ")[1]
    assert "displacement" in listed and "stress" in listed
    assert "normal_force" not in listed and "contact_state" not in listed  # contacts' fields
    with pytest.raises(ValueError, match="no block field 'normal_force'"):
        _blocks_mesh(pv, last, "normal_force")
    with pytest.raises(ValueError, match="no block with block_id 7"):
        _blocks_mesh(pv, last, "velocity", relative_to=7)


def info_of(path, capsys) -> str:
    """What ``dda info PATH`` prints (it must succeed)."""
    assert main(["info", str(path)]) == 0
    return capsys.readouterr().out


def test_info_describes_the_scene(series, capsys):
    scene, pvd = series
    assert main(["info", str(scene)]) == 0
    out = capsys.readouterr().out
    assert "blocks     2 (1 free of which 0 rigid, 1 fixed or moved)" in out
    assert "unknowns   6" in out
    assert "contacts   2 vertex-edge pairs touching" in out
    assert "effects    gravity, shaking of block 'base'" in out
    assert "50 steps" in out
    # the first steps load the kernels (the start-up); a short run is timed whole; the frames
    assert " s to start, " in out and "(timed on all of them)" in out and "11 VTU frames" in out


def test_info_counts_the_frames_of_an_interval_and_no_pairs_of_fixed_blocks(tmp_path, capsys):
    """``[output] interval`` writes a frame each interval of simulated time: 0.1 s at 0.02 s
    is 6 frames, not one a step (an earthquake engineer's review: 29,894 frames estimated
    where 151 were written). A second fixed block touching the base adds no block pair
    (their contacts act on no unknown, and the run makes none)."""
    text = SCENE.replace('every = 5', 'interval = 0.02').replace('[[shake]]', """[[blocks]]
name = "wall"
material = "rock"
vertices = [[3, 0], [3.5, 0], [3.5, 1.0], [3, 1.0]]
fixed = true
[[shake]]""")
    scene = tmp_path / "interval.toml"
    scene.write_text(text)
    out = info_of(scene, capsys)
    assert "for each of 6 VTU frames" in out
    assert "contacts   2 vertex-edge pairs touching at the start (1 block pair)" in out
    # an interval shorter than the step: a frame a step (it counted ten a step), and one
    # that is not a whole number of steps: each frame at the first step past the interval,
    # and the last step's
    for interval, frames in (("0.0002", 51), ("0.005", 18)):
        scene.write_text(text.replace("interval = 0.02", f"interval = {interval}"))
        assert main(["info", str(scene)]) == 0
        assert f"for each of {frames} VTU frames" in capsys.readouterr().out


def test_info_refuses_a_record_that_ends_before_the_run(tmp_path, capsys):
    """As 'dda run' does, at once: it printed a cost, or failed naming a time that was
    neither the record's end nor the run's (where its timing steps crossed the end)."""
    text = SCENE.replace('sine = { amplitude = 6.0, frequency = 5.0, form = "sine" }  '
                         '# full amplitude at once: slips',
                         'times = [0.0, 0.02, 0.05]\nvalues = [0.0, 3.0, -3.0]')
    scene = tmp_path / "short.toml"
    scene.write_text(text)
    assert main(["info", str(scene)]) != 0
    err = capsys.readouterr().err
    assert "ends at t = 0.05 s but the run goes to t = 0.1 s" in err


SCRIPT = """
from pathlib import Path

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.io.vtu import VTUWriter
from dda.materials import LinearElastic

here = Path(__file__).parent
rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
scene = dda.Scene(gravity=9.81)
base = scene.add_block([(0, 0), (3, 0), (3, 0.5), (0, 0.5)], rock, fixed=True, name="base")
scene.add_block([(1, 0.5), (1.5, 0.5), (1.5, 1.0), (1, 1.0)], rock, name="top")
scene.set_joint(JointMaterial(1e9, 1e9, CoulombSingle(phi=20.0)))
scene.shake(base, acceleration=lambda t: (6.0, 0.0))
try:
    dda.Simulation(scene, dt=2e-3).run(0.1, output=VTUWriter(here / "out" / "s", every=5))
except Exception:
    pass
(here / "ran").write_text("the script went on past its first run")
"""


def test_info_describes_a_scripts_first_simulation(tmp_path, capsys):
    """``dda info SCRIPT.py`` runs the script up to its first Simulation.run, describes that
    simulation and stops the script there (an ``except Exception`` in it does not go on)."""
    script = tmp_path / "script.py"
    script.write_text(SCRIPT)
    out = info_of(script, capsys)
    assert "script.py (the first simulation it runs)" in out
    assert "blocks     2 (1 free of which 0 rigid, 1 fixed or moved)" in out
    assert "effects    gravity, shaking of base" in out
    assert "50 steps" in out and "11 VTU frames" in out
    assert not (tmp_path / "ran").exists() and not list(tmp_path.glob("out/*.vtu"))
    lib = tmp_path / "lib.py"
    lib.write_text("x = 1\n")
    assert main(["info", str(lib)]) == 2
    assert "ran to its end without running a dda.Simulation" in capsys.readouterr().err


def test_errors_are_one_line_with_exit_code_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENE.replace('material = "rock"\nvertices = [[1', 'material = "rok"\n'
                                 'vertices = [[1'))
    assert main(["info", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.toml, line 19, blocks[1].material: no material 'rok'" in err
    assert main(["render", str(tmp_path / "none.pvd")]) == 2


def test_run_a_script_passes_out(tmp_path):
    script = tmp_path / "script.py"
    script.write_text("import sys\nopen(sys.argv[sys.argv.index('--out') + 1], 'w')"
                      ".write('ran')\n")
    assert main(["run", str(script), "--out", str(tmp_path / "flag")]) == 0
    assert (tmp_path / "flag").read_text() == "ran"


def test_run_a_script_refuses_the_options_it_would_drop(tmp_path, capsys):
    # (a script reads its own arguments: --duration and --no-progress used to be ignored)
    script = tmp_path / "script.py"
    script.write_text("open(__file__ + '.ran', 'w').write('ran')\n")
    for extra in (["--duration", "1"], ["--no-progress"]):
        with pytest.raises(SystemExit, match=f"dda run: {extra[0]} applies to a scene file"):
            main(["run", str(script), *extra])
    assert not (tmp_path / "script.py.ran").exists()


def test_render_names_a_frame_the_series_does_not_have(series, tmp_path, capsys):
    _, pvd = series
    assert main(["render", str(pvd), "--png", str(tmp_path / "x.png"), "--frame", "999"]) == 2
    assert "frame 999 is not in" in capsys.readouterr().err


def test_demo_and_the_console_entry_point(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "dda", "demo", "--out", str(tmp_path),
                           "--duration", "0.05", "--no-progress"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "wrote 4 VTU files" in proc.stdout  # steps 0, 10, 20 and the last, 25
    assert (tmp_path / "demo.pvd").is_file()


def test_frames_default_relative_to_the_shaken_base(series):
    """The files mark the shaken block: by default the colours are the blocks' displacement
    relative to it, and the colour bar says so, with the unit."""
    from dda.plot import _blocks_mesh, _Frames, _pyvista

    scene, pvd = series
    last = plot.read_pvd(pvd)[-1][1]
    pv = _pyvista()
    raw = pv.read(str(last))
    blocks = np.flatnonzero(raw.cell_data["kind"] == 0)
    u = raw.cell_data["displacement [m]"][blocks]
    ids = raw.cell_data["block_id"][blocks]
    assert list(ids[raw.cell_data["shaken"][blocks] == 1]) == [0]  # the base
    want = np.linalg.norm(u - u[ids == 0][0], axis=1)
    assert want[ids == 1][0] > 1e-3  # the top block slid on the table
    np.testing.assert_allclose(_blocks_mesh(pv, last, "displacement", "auto")
                               .cell_data["shown"], want)
    frames = _Frames([last, last], "displacement", (640, 480))  # the default: "auto"
    assert frames.title == "|displacement| relative to base [mm]"
    np.testing.assert_allclose(frames.mesh(last).cell_data["shown"], 1e3 * want)
    absolute = _Frames([last, last], "displacement", (640, 480), relative_to="none")
    assert absolute.title == "|displacement| [mm]"
    np.testing.assert_allclose(absolute.mesh(last).cell_data["shown"],
                               1e3 * np.linalg.norm(u, axis=1))
    assert _Frames([last, last], "stress", (640, 480)).title == "|stress| [kPa]"
    assert _Frames([last, last], "rotation [rad]", (640, 480)).title.startswith(
        "rotation relative to base [")


def test_the_cli_renders_relative_to_the_shaken_base_by_default(series, tmp_path, monkeypatch):
    seen = []
    monkeypatch.setattr(plot, "render_frame", lambda *a, **k: seen.append(k) or a[1])
    scene, pvd = series
    assert main(["render", str(pvd), "--png", str(tmp_path / "a.png")]) == 0
    assert main(["render", str(pvd), "--png", str(tmp_path / "a.png"), "--relative-to",
                 "top"]) == 0
    assert [k["relative_to"] for k in seen] == ["auto", "top"]


def test_the_png_has_axes_in_metres(series, tmp_path):
    """The PNG has the size asked for, and the picture of the blocks spans on its axes the
    metres the blocks span."""
    from PIL import Image

    from dda.plot import _Frames, _nice_length, _pyvista

    scene, pvd = series
    png = plot.render_frame(pvd, tmp_path / "f.png", size=(640, 480), frame=2)
    with Image.open(png) as im:
        assert im.size == (640, 480)
    assert not_blank(png_pixels(png))
    last = plot.read_pvd(pvd)[2][1]
    frames = _Frames([last, last], "displacement", (640, 480))
    picture = frames.scene(last)
    assert picture.shape[:2] == frames.pixels[::-1]
    x0, x1, y0, y1 = frames.extent
    filled = (picture < 200).any(axis=2)
    cols, rows = np.flatnonzero(filled.any(axis=0)), np.flatnonzero(filled.any(axis=1))
    px = (x1 - x0) / picture.shape[1]
    bounds = _pyvista().read(str(last)).bounds
    np.testing.assert_allclose([x0 + cols[0] * px, x0 + (cols[-1] + 1) * px],
                               [bounds[0], bounds[1]], atol=2 * px)
    np.testing.assert_allclose([y1 - (rows[-1] + 1) * px, y1 - rows[0] * px],
                               [bounds[2], bounds[3]], atol=2 * px)
    assert [_nice_length(s) for s in (0.37, 1.0, 7.0, 0.02)] == [0.2, 1.0, 5.0, 0.02]


def test_an_animation_keeps_a_block_that_flies_out_in_the_middle_in_the_picture(series,
                                                                                 tmp_path):
    """The camera and colour range cover every frame, not the first and last only: a
    block 10 m away in the middle frame (and back at the end) is in the picture."""
    import meshio

    from dda.plot import _Frames

    _, pvd = series
    first = plot.read_pvd(pvd)[0][1]
    mesh = meshio.read(first)
    far = tmp_path / "far.vtu"
    moved = mesh.points.copy()
    moved[:, 0] += 10.0
    meshio.write(far, meshio.Mesh(moved, mesh.cells, point_data=mesh.point_data,
                                  cell_data=mesh.cell_data, field_data=mesh.field_data))
    frames = _Frames([first, far, first], "displacement", (640, 480))
    x0, x1, _, _ = frames.extent
    assert x0 <= mesh.points[:, 0].min() and x1 >= moved[:, 0].max()
    assert x1 - x0 < 1.2 * (moved[:, 0].max() - mesh.points[:, 0].min())


@pytest.fixture(scope="module")
def named_files(tmp_path_factory):
    """A file whose blocks are named "7" (block_id 0), "table" (1, shaken) and "top" (2),
    with the fields under their unit-bearing names only."""
    from dda.contact import CoulombSingle, JointMaterial
    from dda.io.vtu import VTUWriter
    from dda.materials import LinearElastic

    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    s = dda.Scene(gravity=9.81)
    s.add_block([(0, -1), (1, -1), (1, -0.5), (0, -0.5)], rock, fixed=True, name="7")
    table = s.add_block([(0, 0), (3, 0), (3, 0.5), (0, 0.5)], rock, fixed=True, name="table")
    s.add_block([(1, 0.5), (1.5, 0.5), (1.5, 1.0), (1, 1.0)], rock, name="top")
    s.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                              friction=CoulombSingle(phi=20)))
    s.shake(table, acceleration=lambda t: (6.0 * np.sin(10 * np.pi * t), 0.0))
    writer = VTUWriter(tmp_path_factory.mktemp("named") / "case", plain_names=False)
    dda.Simulation(s, dt=2e-3).run(duration=0.02, output=writer)
    return writer.pvd_path, writer.files[-1]


def test_blocks_by_name_or_id(named_files):
    from dda.plot import _blocks_of, _file_reference, _pyvista

    pvd, last = named_files
    mesh, names = _blocks_of(_pyvista(), last)
    assert names == ["7", "table", "top"]
    for key, want in (("top", 2), ("table", 1), ("2", 2), (2, 2), (np.int64(1), 1),
                      ("7", 0),  # a block's name first: the block named "7"
                      (" top ", 2), ("auto", 1), ("none", None), ("None", None), (None, None)):
        assert _file_reference(mesh, names, key) == want, key
    with pytest.raises(ValueError, match=r"no block named 'tabel' in .*; the blocks are: "
                                         r"7 \(0\), table \(1\), top \(2\)"):
        _file_reference(mesh, names, "tabel")
    with pytest.raises(ValueError, match="no block with block_id 7 .*top \\(2\\)"):
        _file_reference(mesh, names, 7)


def test_the_cli_takes_block_names(named_files, tmp_path, capsys):
    pvd, last = named_files
    png = tmp_path / "top.png"
    assert main(["render", str(pvd), "--png", str(png), "--relative-to", "top"]) == 0
    assert png.is_file()
    assert main(["render", str(pvd), "--png", str(png), "--relative-to", "tabel"]) == 2
    err = capsys.readouterr().err
    assert "no block named 'tabel'" in err and "table (1)" in err
    assert main(["render", str(pvd), "--png", str(png), "--relative-to", "top",
                 "--field", "stress"]) == 2
    assert "relative_to goes with displacement" in capsys.readouterr().err


def test_fields_by_their_short_names():
    from dda.plot import _display_unit, _field_key

    both = ["kind", "displacement [m]", "displacement", "stress [Pa]"]
    assert _field_key(both, "displacement", "f") == "displacement [m]"
    assert _field_key(both, "displacement [m]", "f") == "displacement [m]"
    assert _field_key(["displacement"], "displacement", "f") == "displacement"  # old files
    assert _field_key(both, "stress", "f") == "stress [Pa]"
    with pytest.raises(ValueError, match=r"no block field 'strain' \(there are: "
                                         r"displacement, stress\)"):
        _field_key(both, "strain", "f")
    assert _display_unit("m", 4.5e-3) == ("mm", 1e-3)
    assert _display_unit("m", 2.0) == ("m", 1.0)
    assert _display_unit("m", 6.3e-8) == ("µm", 1e-6)  # a "1e-5" over "[mm]" before
    assert _display_unit("rad", 4.5e-6) == ("µrad", 1e-6)
    assert _display_unit("Pa", 6.5e3) == ("kPa", 1e3)
    assert _display_unit("N/m", 2e7) == ("MN/m", 1e6)
    assert _display_unit(None, 3.0) == (None, 1.0)


def _block_pixels(frames, picture, mesh):
    """The picture's colour at each block cell's centre (the blocks here are convex)."""
    x0, _, _, y1 = frames.extent
    px = (frames.extent[1] - x0) / picture.shape[1]
    centres = np.asarray(mesh.cell_centers().points)
    cols = ((centres[:, 0] - x0) / px).astype(int)
    rows = ((y1 - centres[:, 1]) / px).astype(int)
    return picture[rows, cols].astype(float)


@pytest.mark.parametrize("field", ["displacement", "rotation"])
def test_a_blocks_colour_is_the_colour_bars_at_its_value(series, field, tmp_path):
    """Each block is drawn in the colour the colour bar gives its value (drawn lit, the
    blocks came out about 20% darker than the bar); a signed field (rotation, here turned
    clockwise) on a map centred on 0 (on a range from 0 up, every clockwise rotation was
    drawn as the fixed base's 0)."""
    import meshio
    from matplotlib import colormaps

    from dda.plot import _blocks_mesh, _Frames, _pyvista

    _, pvd = series
    last = plot.read_pvd(pvd)[-1][1]
    if field == "rotation":
        mesh = meshio.read(last)
        for name in ("rotation [rad]", "rotation"):
            mesh.cell_data[name] = [-np.asarray(a) for a in mesh.cell_data[name]]
        last = tmp_path / "clockwise.vtu"
        meshio.write(last, mesh)
    frames = _Frames([last, last], field, (640, 480))
    mesh = _blocks_mesh(_pyvista(), last, field, "none" if field == "rotation" else "auto")
    values = np.asarray(mesh.cell_data["shown"]) / frames.scale
    if field == "rotation":
        assert values.min() < 0.0  # the sliding block turns clockwise here
        assert frames.clim[0] == -frames.clim[1] and frames.clim[1] >= np.abs(values).max()
    norm = (values - frames.clim[0]) / (frames.clim[1] - frames.clim[0])
    expected = 255.0 * np.asarray(colormaps[getattr(frames, "cmap", "viridis")](norm))[:, :3]
    drawn = _block_pixels(frames, frames.scene(last), mesh)
    np.testing.assert_allclose(drawn, expected, atol=4.0)


def test_a_scene_at_site_coordinates_draws_as_at_the_origin(series, tmp_path):
    """The same frame moved by (5e5, 4e6) m, a site's coordinates, is the same picture
    (VTK draws in single precision: there the outlines sat up to 5 cm off their faces)."""
    import meshio

    from dda.plot import _Frames

    _, pvd = series
    last = plot.read_pvd(pvd)[-1][1]
    mesh = meshio.read(last)
    far = tmp_path / "far.vtu"
    meshio.write(far, meshio.Mesh(mesh.points + np.array([5e5, 4e6, 0.0]), mesh.cells,
                                  point_data=mesh.point_data, cell_data=mesh.cell_data))
    here = _Frames([last, last], "displacement", (640, 480)).scene(last).astype(float)
    there = _Frames([far, far], "displacement", (640, 480)).scene(far).astype(float)
    differ = np.abs(here - there).max(axis=2) > 30
    assert differ.mean() < 1e-4, differ.mean()  # 0 now; 2.8e-3 before


def test_a_run_that_cannot_go_on_is_one_line_with_exit_code_1(tmp_path, capsys):
    """A run stopped by SimulationError: one line naming the time and the reason, exit code
    1, the frames so far written (a 29-line traceback before)."""
    scene = tmp_path / "stuck.toml"
    scene.write_text(SCENE.replace('solver = "legacy"', 'solver = "newton"\nmax_iter = 1\n'
                                   'tol = 1e-15').replace("normal_penalty = 1e9",
                                                          "normal_penalty = 2e12"))
    with pytest.warns(dda.PenaltyWarning):
        code = main(["run", str(scene), "--out", str(tmp_path / "out"), "--no-progress"])
    assert code == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("dda run: the run stopped: the run cannot go on at t = ")
    assert plot.read_pvd(tmp_path / "out" / "slide.pvd")


def test_output_path_errors_are_one_line(series, tmp_path, capsys):
    scene, pvd = series
    (tmp_path / "afile").write_text("")
    assert main(["run", str(scene), "--out", str(tmp_path / "afile"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("dda run: ") and "afile" in err and "Traceback" not in err
    assert main(["render", str(pvd), "--png", str(tmp_path / "noext")]) == 2
    assert "needs a picture's extension" in capsys.readouterr().err


def test_render_refuses_bad_animation_settings_before_drawing(series, tmp_path, capsys):
    _, pvd = series
    for option in (["--fps", "0"], ["--fps", "-1"], ["--max-frames", "0"]):
        assert main(["render", str(pvd), "--gif", str(tmp_path / "a.gif"), *option]) == 2
        assert "animate: " in capsys.readouterr().err
    assert not (tmp_path / "a.gif").exists()
    assert main(["render", str(pvd), "--gif", str(tmp_path / "a.mp4")]) == 2
    assert "--gif" in capsys.readouterr().err and not (tmp_path / "a.mp4").exists()


def test_render_draws_a_gif_and_an_mp4_of_the_frames_asked_for(series, tmp_path, monkeypatch):
    """--max-frames N takes N frames evenly spread, first and last among them; a GIF and an
    MP4 asked for together are drawn from one drawing of each frame."""
    import imageio.v3 as iio
    from PIL import Image

    from dda.plot import _Frames

    drawn = []
    image = _Frames.image
    monkeypatch.setattr(_Frames, "image", lambda self, f, t: drawn.append(t) or image(self, f, t))
    _, pvd = series
    gif, mp4 = tmp_path / "a.gif", tmp_path / "a.mp4"
    assert main(["render", str(pvd), "--gif", str(gif), "--mp4", str(mp4),
                 "--max-frames", "4"]) == 0
    times = [t for t, _ in plot.read_pvd(pvd)]
    assert drawn == [times[0], times[3], times[7], times[10]]
    with Image.open(gif) as im:
        assert im.n_frames == 4
    assert len(list(iio.imiter(mp4, plugin="FFMPEG"))) == 4


def test_a_series_whose_files_are_missing_is_named(series, tmp_path):
    import shutil

    _, pvd = series
    copy = tmp_path / "moved.pvd"
    shutil.copy(pvd, copy)  # the index without its files
    with pytest.raises(ValueError, match=r"moved.pvd lists 11 of its 11 files that are not "
                                         r"there, the first .*slide_00000.vtu"):
        plot.read_pvd(copy)


def test_the_blocks_outlines_are_drawn_whole(tmp_path, rock):
    """Each block's outline is black along its whole side: drawn in the faces' plane, the
    edges lost the depth test to the faces in patches (two 0.2 x 1.2 m columns lost about
    half of their sides)."""
    from dda.contact import CoulombSingle, JointMaterial
    from dda.plot import _blocks_mesh, _Frames, _pyvista

    scene = dda.Scene(gravity=9.81)
    scene.add_block([(-2, -0.5), (4, -0.5), (4, 0), (-2, 0)], rock, fixed=True)
    for x in (0.0, 1.0):
        scene.add_block([(x, 0), (x + 0.2, 0), (x + 0.2, 1.2), (x, 1.2)], rock)
    scene.add_block([(2, 0), (3, 0), (3, 0.2), (2.3, 0.2), (2.3, 0.7), (2, 0.7)], rock)
    scene.set_joint(JointMaterial(5e9, 5e9, CoulombSingle(phi=40.0)))
    writer = dda.io.VTUWriter(tmp_path / "cols")
    dda.Simulation(scene, dt=2e-3).run(0.004, output=writer, progress=False)
    last = writer.files[-1]
    frames = _Frames([last, last], "displacement", (1024, 768))
    picture = frames.scene(last).astype(float)
    x0, x1, _, y1 = frames.extent
    px = (x1 - x0) / picture.shape[1]
    mesh = _blocks_mesh(_pyvista(), last, "displacement")
    for block in (1, 2):
        (xa, xb, ya, yb, _, _) = mesh.extract_cells([block]).bounds
        rows = np.arange(int((y1 - yb) / px) + 3, int((y1 - ya) / px) - 2)
        face = picture[rows[len(rows) // 2], int(((xa + xb) / 2 - x0) / px)].sum()
        for x in (xa, xb):
            col = int(round((x - x0) / px))
            darkest = picture[rows][:, col - 1:col + 2].sum(axis=2).min(axis=1)
            drawn = np.mean(darkest < face - 50.0)  # darker than the face, and the white
            assert drawn > 0.95, (block, x, drawn)


def test_an_animation_cut_short_leaves_the_last_good_files(series, tmp_path, monkeypatch):
    """Cut short while drawing (Ctrl-C, an error), the MP4 it was writing replaced the last
    good one with a valid 2-frame file; now the files are written whole or not at all."""
    import imageio.v3 as iio
    from PIL import Image

    from dda.plot import _Frames

    _, pvd = series
    gif, mp4 = tmp_path / "a.gif", tmp_path / "a.mp4"
    plot.animate_to([gif, mp4], pvd)
    (tmp_path / "a.part.mp4").write_bytes(b"the user's")  # not the animation's to touch
    image, calls = _Frames.image, []

    def fails_at_the_third(self, f, t):
        calls.append(t)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return image(self, f, t)

    monkeypatch.setattr(_Frames, "image", fails_at_the_third)
    with pytest.raises(KeyboardInterrupt):
        plot.animate_to([gif, mp4], pvd)
    assert len(list(iio.imiter(mp4, plugin="FFMPEG"))) == 11
    with Image.open(gif) as im:
        assert im.n_frames == 11
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif", "a.mp4", "a.part.mp4"]
    assert (tmp_path / "a.part.mp4").read_bytes() == b"the user's"


def test_a_part_of_a_field_is_shown_by_name(series):
    """``stress:s1`` and the other parts: the values the files hold, combined as named (the
    norm of [sx, sy, txy] was the only stress picture); ``displacement:x`` relative to the
    table; an unknown part lists the known ones."""
    import meshio

    from dda.plot import _blocks_mesh, _Frames, _pyvista

    _, pvd = series
    last = plot.read_pvd(pvd)[-1][1]
    mesh = meshio.read(last)
    kind = np.concatenate(mesh.cell_data["kind"])
    stress = np.concatenate(mesh.cell_data["stress [Pa]"])[kind == 0]
    sx, sy, txy = stress.T
    radius = np.hypot((sx - sy) / 2, txy)
    expected = {"sx": sx, "sy": sy, "txy": txy, "mean": (sx + sy) / 2,
                "s1": (sx + sy) / 2 + radius, "s2": (sx + sy) / 2 - radius, "tmax": radius}
    for part, values in expected.items():
        shown = _blocks_mesh(_pyvista(), last, f"stress:{part}").cell_data["shown"]
        np.testing.assert_allclose(shown, values, rtol=1e-12, atol=1e-9)
    frames = _Frames([last, last], "stress:s1", (640, 480))
    assert frames.title.startswith("stress s1 [")
    x = _blocks_mesh(_pyvista(), last, "displacement:x", "auto").cell_data["shown"]
    both = _blocks_mesh(_pyvista(), last, "displacement", "auto").cell_data["shown"]
    assert np.all(np.abs(x) <= both + 1e-15) and np.abs(x).max() > 0.5 * both.max()
    with pytest.raises(ValueError, match=r"'stress' has no part 's3' \(its parts: sx, sy"):
        _blocks_mesh(_pyvista(), last, "stress:s3")
    with pytest.raises(ValueError, match="'rotation' has no part 'x' .it has no parts"):
        _blocks_mesh(_pyvista(), last, "rotation:x")


def test_dda_plot_is_there_after_import_dda_alone():
    """The README's ``dda.plot.history(...)`` after ``import dda``: an AttributeError until
    dda.plot was imported by name; ``import dda`` still loads no plotting library."""
    code = ("import sys, dda\n"
            "assert 'matplotlib' not in sys.modules\n"
            "assert callable(dda.plot.history) and callable(dda.plot.render_frame)\n")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
