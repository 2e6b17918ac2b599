"""The examples run as a user runs them, and reproduce their stored numbers."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("solver", ["newton", "legacy"])
def test_shaking_slope_demo(tmp_path, capsys, solver):
    """The README's demo at its own default length (6 s): the block slides in steps, reaches
    the lip (a concave corner of the lower block) at about 4.8 s and stays on its side of it.
    Before issue 17 it lost its seat at the lip and fell through the lower block (7.77 m)."""
    demo = load("shaking_slope")
    result, slide = demo.main(["--out", str(tmp_path), "--solver", solver])
    out = capsys.readouterr().out
    assert "slide down the joint after 6 s" in out
    # files a user looks at
    assert (tmp_path / "slope.pvd").exists()
    assert len(list(tmp_path.glob("slope_*.vtu"))) >= 301
    png = tmp_path / "slide.png"
    assert png.stat().st_size > 10_000
    image = pytest.importorskip("matplotlib.image").imread(png)
    assert image[..., :3].std() > 0.05  # not blank
    # physics: the slide cannot start before the table passes g tan(phi - 15) and starts
    # within 30 ms of it (cubic growth to the 10 um detection level takes about 14 ms)
    args = type("A", (), {"peak": 670.0, "phi": 31.6, "duration": 3.0})
    t_threshold = demo.threshold_time(args)
    # third amplitude level (3/6 of 670 gal) from t = 2 s: A cos(4 pi t) < -g tan(16.6 deg)
    amplitude = 6.70 * 3 / 6
    expected = 2.0 + np.arccos(-demo.slide_threshold(31.6) / amplitude) / (4 * np.pi)
    assert t_threshold == pytest.approx(expected, abs=2e-4)
    start = demo.slide_start(result, slide)
    assert t_threshold < start < t_threshold + 0.03
    # stored numbers (dt 1e-3): slide after 3 s, 3.5585 mm (Newton) and 3.5522 mm (legacy)
    at_3 = np.interp(3.0, result.time, slide)
    assert at_3 == pytest.approx({"newton": 3.5585e-3, "legacy": 3.5522e-3}[solver], rel=0.005)
    before_lip = (result.time > 0.5) & (result.time < 4.7)
    assert np.all(np.diff(slide[before_lip]) > -1e-6)  # it never slides back up the joint
    # the lip holds it: it gets there (10.5 cm) and never passes it
    assert slide.max() == pytest.approx(demo.STOP, abs=2e-3)
    assert slide.max() <= 0.11 and 0.095 < slide[-1] <= 0.11
    # and nothing passed into anything: the deepest vertex inside the other block is the
    # deepest contact spring's, to the guard's tolerance
    gap = result.stats.penetration - result.stats.spring_penetration
    assert gap.max() < 1e-4


def test_jointed_slope_example(tmp_path, capsys):
    """The cut slope has several hundred blocks covering the rock mass but for the dropped
    slivers, and it runs: a short run writes its files and stays finite."""
    demo = load("jointed_slope")
    scene, base, blocks = demo.build_scene()
    assert 250 <= len(blocks) <= 400
    from dda.geometry import polygon_integrals

    x, offsets = scene.vertex_arrays()
    area = polygon_integrals(x, offsets).area[[b.index for b in blocks]]
    mass = 0.5 * (40 + 28) * 20
    assert 0.98 * mass < area.sum() <= mass * (1 + 1e-9)
    face = demo.face_blocks(scene, blocks)
    assert 20 < len(face) < 80
    result, blocks, moved = demo.main(["--out", str(tmp_path), "--duration", "0.01"])
    assert "blocks cut from the slope" in capsys.readouterr().out
    assert (tmp_path / "slope.pvd").exists()
    assert np.all(np.isfinite(moved)) and moved.max() < 0.05
    result, _, moved = demo.main(["--out", str(tmp_path / "auto"), "--duration", "0.01",
                                  "--auto"])
    assert "auto" in capsys.readouterr().out
    assert np.all(np.isfinite(moved)) and moved.max() < 0.05
    # --dt auto: the joints' 5e10 N/m kept, dt chosen for it (3 x the lightest block's inertia)
    result, _, moved = demo.main(["--out", str(tmp_path / "auto_dt"), "--duration", "0.002",
                                  "--dt", "auto"])
    assert "shortened to 0.000149 s to keep the joints' given normal penalty 5e+10 N/m" in (
        capsys.readouterr().out)
    assert np.all(np.isfinite(moved)) and result.stats["dt"].max() <= 1.5e-4


def test_jointed_slope_other_cuts(tmp_path, capsys):
    """``--seed`` draws the cross joints' traces again (benchmarks/cut_rate.py): another set
    of blocks that covers the same rock mass, and it runs."""
    demo = load("jointed_slope")
    from dda.geometry import polygon_integrals

    counts = {}
    for seed in (0, 1):
        scene, _, blocks = demo.build_scene(seed=seed)
        x, offsets = scene.vertex_arrays()
        area = polygon_integrals(x, offsets).area[[b.index for b in blocks]].sum()
        assert 0.98 * 680.0 < area <= 680.0 * (1 + 1e-9)
        counts[seed] = (len(blocks), round(float(area), 6))
    assert counts[0] != counts[1]  # a different cut, not the same one again
    _, blocks, moved = demo.main(["--out", str(tmp_path), "--duration", "0.004",
                                  "--seed", "1"])
    assert f"{counts[1][0]} blocks cut from the slope" in capsys.readouterr().out
    assert len(blocks) == counts[1][0]
    assert np.all(np.isfinite(moved)) and moved.max() < 0.05


def test_user_friction_law(capsys):
    """docs/friction_laws.md's example at its default length: the user's law passes the check,
    both laws under both solvers land within 1% of the rigid-block formula, and the scene file
    that names the law by import path gives the Newton run's numbers (its coordinates are the
    Python scene's to 10 decimals)."""
    example = load("user_friction_law")
    runs = example.main([])
    out = capsys.readouterr().out
    assert "check_friction_law(BrittleCohesion(phi=30.0, cohesion=5000.0)): passed" in out
    assert len(runs) == 5
    for (name, _), (t, slide) in runs.items():
        expected = example.slide_formula(name, np.asarray(t))[-1]
        assert slide[-1] == pytest.approx(expected, rel=0.01)
    # the cohesion matters: the brittle block slides 24 times as far as the cohesive one
    assert runs[("brittle", "newton")][1][-1] > 20 * runs[("coulomb", "newton")][1][-1]
    np.testing.assert_allclose(runs[("brittle", "scene file")][1],
                               runs[("brittle", "newton")][1], rtol=1e-6, atol=1e-9)


def test_recorded_shaking_example(tmp_path, capsys, monkeypatch):
    """The jointed slope shaken by a record: without --record the example writes its
    synthetic .AT2 (0.3 g, ends at rest) and says so; with a K-NET file of one's own it reads
    that, scaled and baseline corrected. Short runs: they write their files and stay finite."""
    example = load("recorded_shaking")
    result, record, moved = example.main(["--out", str(tmp_path), "--duration", "0.05"])
    out = capsys.readouterr().out
    assert "no --record given: wrote a synthetic record" in out
    assert "62 blocks cut from the 8 m slope" in out
    from dda.io.records import read_at2

    synthetic = read_at2(tmp_path / "synthetic.AT2")
    assert synthetic.peak == pytest.approx(0.3 * 9.80665, rel=1e-6)
    assert synthetic.dt == 0.01 and synthetic.duration == pytest.approx(4.0)
    assert abs(synthetic.end_motion()[0]) < 1e-6  # the table ends at rest
    assert (tmp_path / "slope.pvd").exists() and (tmp_path / "record.png").stat().st_size > 10_000
    assert np.all(np.isfinite(moved)) and moved.max() < 0.01
    from dda.effects import AccelerationHistory

    table = AccelerationHistory(record.acceleration, record.times)  # the base follows it
    np.testing.assert_allclose(result.displacement("base")[:, 0],
                               [table.state(t)[0][0] for t in result.time], atol=1e-12)
    # a K-NET record of one's own (the synthetic motion in counts), halved, corrected
    t, a = example.synthetic_record(duration=0.5)
    counts = np.round(a * 100 / (3920 / 6182761)).astype(int)
    rows = [" ".join(f"{c:8d}" for c in counts[k:k + 8]) for k in range(0, len(counts), 8)]
    from tests.test_records import knet_header

    knet = tmp_path / "own.EW"
    knet.write_text(knet_header(counts, direction="E-W") + "\n".join(rows))
    drawn = []
    real_plot = example.plot

    def plot(*args, **kwargs):
        drawn.append(real_plot(*args, **kwargs))
        return drawn[-1]

    monkeypatch.setattr(example, "plot", plot)
    result, record, moved = example.main(["--out", str(tmp_path / "knet"), "--record",
                                          str(knet), "--duration", "0.03", "--scale", "0.5",
                                          "--baseline", "quadratic"])
    out = capsys.readouterr().out
    assert "record own.EW (knet, MYG004, E-W): 51 samples at dt 0.01 s" in out
    from dda.io.records import read_knet

    own = read_knet(knet)  # the counts' mean taken away moves the peak a little: 0.148 g
    assert f"peak {0.5 * own.peak / 9.80665:.3f} g" in out and "quadratic baseline" in out
    # the picture draws the record as scaled (it drew the file's, twice the peak printed)
    assert drawn == [pytest.approx(0.5 * record.peak / 9.80665, rel=1e-12)]
    assert own.peak == pytest.approx(0.3 * 9.80665, rel=0.02)
    assert record.baseline == "quadratic" and abs(record.end_motion()[0]) < 1e-12
    assert np.all(np.isfinite(moved))


def test_bolted_slope_example(tmp_path, capsys):
    """The factor of safety of the 8 m cut slope (issue 23, item 4), at a coarse tolerance:
    dry, the bedding's tan 35 / tan 25 = 1.5016; wet, below 1.3; wet and bolted, above 1.3
    again; the report's pictures and table written."""
    example = load("bolted_slope")
    rows = example.main(["--out", str(tmp_path), "--tolerance", "0.05", "--workers", "2"])
    factors = {r["case"]: r["factor"] for r in rows}
    assert factors["dry"] == pytest.approx(np.tan(np.radians(35)) / np.tan(np.radians(25)),
                                           rel=0.03)
    assert factors["wet"] < 1.3 < factors["bolted"]
    assert rows[2]["bolts"] >= 8
    for name in ("slope.png", "fos_dry.png", "fos_wet.png", "fos_bolted.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    assert len((tmp_path / "factors.csv").read_text().splitlines()) == 4
    assert "bolted: StrengthReduction: F = " in capsys.readouterr().out


def test_shaking_slope_demo_shorter_than_its_settling(tmp_path, capsys):
    """A demo run shorter than the 0.5 s of elastic settling the slide is measured from has no
    slide start to report: it says so (nan) instead of failing at the end of the run."""
    demo = load("shaking_slope")
    result, slide = demo.main(["--out", str(tmp_path), "--duration", "0.1"])
    assert result.time[-1] == pytest.approx(0.1)
    assert np.isnan(demo.slide_start(result, slide))
    assert "it has not started by the end of the run" in capsys.readouterr().out
