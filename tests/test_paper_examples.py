"""The paper-case examples run as a user runs them and write what they promise."""

import csv

import numpy as np
import pytest

from tests.test_examples import load


def picture_is_not_blank(path):
    assert path.stat().st_size > 20_000
    image = pytest.importorskip("matplotlib.image").imread(path)
    assert image[..., :3].std() > 0.05


def csv_rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_direct_shear_example(tmp_path, capsys):
    runs = load("direct_shear").main(["--out", str(tmp_path)])
    assert "overshoot" in capsys.readouterr().out
    picture_is_not_blank(tmp_path / "direct_shear.png")
    assert len(csv_rows(tmp_path / "direct_shear.csv")) == sum(len(r["tau"]) for r in runs)
    assert len(list(tmp_path.glob("direct_shear_*.vtu"))) == 22  # 20 steps, start, consolidation
    over = {(r["solver"], r["steps"]): r["overshoot"] for r in runs}
    assert over["legacy", 20] > over["legacy", 50] > over["legacy", 200] > 0.01
    assert max(abs(over["newton", n]) for n in (20, 50, 200)) < 0.005


def test_simple_shear_example(tmp_path, capsys):
    runs = load("simple_shear").main(["--out", str(tmp_path)])
    assert "after the drop" in capsys.readouterr().out
    picture_is_not_blank(tmp_path / "simple_shear.png")
    assert (tmp_path / "simple_shear.pvd").exists()
    newton = runs[0]
    assert newton["peak"] == pytest.approx(577.35e3, rel=0.005)
    assert newton["after_drop"] == pytest.approx(363.97e3, rel=0.005)


def test_moving_base_example(tmp_path, capsys):
    runs = load("moving_base").main(["--out", str(tmp_path), "--duration", "0.3"])
    out = capsys.readouterr().out
    assert "worst peak error" in out and "| legacy | 0.01 |" in out
    picture_is_not_blank(tmp_path / "moving_base.png")
    table = csv_rows(tmp_path / "moving_base_table.csv")
    assert len(table) == 16
    assert (tmp_path / "moving_base_table.md").read_text().count("\n") == 18
    assert (tmp_path / "moving_base.pvd").exists()
    for r in runs:
        if r["solver"] == "newton":
            assert abs(r["peak_error"]) < (0.05 if r["dt"] == 1e-3 else 0.10)


def test_rock_slope_example(tmp_path, capsys):
    runs = load("rock_slope").main(["--out", str(tmp_path), "--hold", "0.5",
                                    "--joints", "single,face"])
    assert "start rigid" in capsys.readouterr().out
    picture_is_not_blank(tmp_path / "rock_slope.png")
    rows = csv_rows(tmp_path / "rock_slope.csv")
    assert len(rows) == len(runs[0]["time"])
    # every 20 recorded steps: one per 20 ms, more where dt was cut at the stopper
    assert len(list(tmp_path.glob("rock_slope_*.vtu"))) >= 201
    single, face = runs
    assert (single["joint"], face["joint"]) == ("single", "face")
    assert abs(single["start"] - single["rigid_start"]) < 0.05
    assert abs(face["start"] - face["rigid_start"]) < 0.05
    # the transition makes the block slide farther than one angle does
    def at(run, t):
        return run["slide"][np.searchsorted(run["time"], t)]

    assert at(face, 3.0) > 5 * at(single, 3.0)


def test_rock_slope_csv_takes_runs_recorded_at_other_times(tmp_path):
    """A run whose steps were cut has more records than the others (the 16 s default run
    failed with an IndexError): its slide is interpolated onto the first run's times."""
    t1, t2 = np.linspace(0.0, 1.0, 5), np.array([0.0, 0.25, 0.3, 0.5, 0.6, 0.75, 1.0])
    runs = [{"joint": "single", "time": t1, "slide": t1 * 1e-3, "rigid": t1 * 2e-3},
            {"joint": "face", "time": t2, "slide": t2 * 3e-3, "rigid": t2 * 4e-3}]
    load("rock_slope").write_csv(runs, lambda t: (0.5, 0.0), tmp_path / "r.csv")
    rows = csv_rows(tmp_path / "r.csv")
    assert [float(r["time_s"]) for r in rows] == pytest.approx(t1)
    assert [float(r["face_dda_mm"]) for r in rows] == pytest.approx(3.0 * t1)
    assert [float(r["face_rigid_mm"]) for r in rows] == pytest.approx(4.0 * t1)
    assert float(rows[2]["table_gal"]) == 50.0


def test_rock_slope_example_names_unknown_joints(tmp_path):
    with pytest.raises(SystemExit):
        load("rock_slope").main(["--out", str(tmp_path), "--joints", "single,glue"])


def test_stacked_cubes_example(tmp_path, capsys):
    runs = load("stacked_cubes").main(["--out", str(tmp_path), "--duration", "1",
                                       "--cases", "3:300,3:700"])
    out = capsys.readouterr().out
    assert "outcomes agree with the test" in out
    picture_is_not_blank(tmp_path / "stacked_cubes.png")
    rows = csv_rows(tmp_path / "stacked_cubes.csv")
    assert [(r["freq_Hz"], r["amplitude_gal"], r["test_outcome"]) for r in rows] == [
        ("3.0", "300.0", "stable"), ("3.0", "700.0", "toppled")]
    assert (tmp_path / "stacked_cubes.pvd").exists()
    assert runs[0]["outcome"] == "stable"


def test_stacked_cubes_example_runs_akaos_own_settings(tmp_path, capsys):
    """--akao: A's DDA settings (legacy, no dashpot, the table driven by a displacement sine
    from t = 0) on the four cases of A's table 5, next to A's own DDA outcomes."""
    runs = load("stacked_cubes").main(["--out", str(tmp_path), "--duration", "0.3", "--akao",
                                       "--cases", "5:400"])
    out = capsys.readouterr().out
    assert "A's DDA settings: legacy DDA" in out and "restitution 1," in out
    assert "of 1 agree with A's own DDA" in out
    assert [r["akao_dda"] for r in runs] == ["moved"]
    rows = csv_rows(tmp_path / "stacked_cubes.csv")
    assert rows[0]["akao_dda_outcome"] == "moved"
    assert runs[0]["status"] == "ok"


def test_stacked_cubes_example_refuses_unknown_cases(tmp_path):
    with pytest.raises(SystemExit):
        load("stacked_cubes").main(["--out", str(tmp_path), "--cases", "4:300"])
