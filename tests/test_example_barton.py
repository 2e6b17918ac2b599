"""The Barton direct-shear example runs as a user runs it and shows the law's curve."""

import csv

import pytest

from tests.test_examples import load


def test_barton_direct_shear_example(tmp_path, capsys):
    example = load("barton_direct_shear")
    rows = example.main(["--out", str(tmp_path), "--steps", "100"])
    assert "slip at peak" in capsys.readouterr().out
    # files a user looks at
    png = tmp_path / "barton_shear.png"
    assert png.stat().st_size > 20_000
    image = pytest.importorskip("matplotlib.image").imread(png)
    assert image[..., :3].std() > 0.05  # not blank
    with open(tmp_path / "barton_shear.csv") as f:
        table = list(csv.DictReader(f))
    assert len(table) == 3 * 2 * 100
    assert (tmp_path / "barton_1MPa.pvd").exists()
    assert len(list(tmp_path.glob("barton_1MPa_*.vtu"))) == 100
    # physics: three normal stresses under both solvers; Newton follows Barton
    assert {(r["sigma_n"], r["solver"]) for r in rows} == {
        (s, solver) for s in (0.5e6, 1e6, 2e6) for solver in ("newton", "legacy")}
    step_slip = example.SHEAR / 100
    for r in rows:
        assert abs(r["slip_at_peak"] - r["expected_slip_at_peak"]) <= step_slip
        if r["solver"] == "newton":
            assert abs(r["peak_error"]) < 0.01
            assert r["curve_error"] < 0.01
