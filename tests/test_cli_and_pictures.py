"""The dda command (run, demo, render, info) and the pictures: files that are not blank."""

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
    with pytest.raises(ValueError, match="no block field 'strain'"):
        _blocks_mesh(pv, last, "strain")
    with pytest.raises(ValueError, match="no block with block_id 7"):
        _blocks_mesh(pv, last, "velocity", relative_to=7)


def test_info_describes_the_scene(series, capsys):
    scene, pvd = series
    assert main(["info", str(scene)]) == 0
    out = capsys.readouterr().out
    assert "blocks     2 (1 free of which 0 rigid, 1 fixed or moved)" in out
    assert "unknowns   6" in out
    assert "contacts   2 vertex-edge pairs touching" in out
    assert "effects    gravity, shaking of block 'base'" in out
    assert "50 steps" in out
    # the estimate leaves out the first steps (the kernels load) and adds the frames written
    assert "timed on steps 4 to " in out and "VTU frames" in out


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


def test_demo_and_the_console_entry_point(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "dda", "demo", "--out", str(tmp_path),
                           "--duration", "0.05", "--no-progress"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "wrote 3 VTU files" in proc.stdout
    assert (tmp_path / "demo.pvd").is_file()
