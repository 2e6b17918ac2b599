"""Results as data (issue 22, item 5): Result.to_xarray(), StepStats.to_pandas() and sweep
rows as a DataFrame and a rounded table; the NetCDF round trip."""

from __future__ import annotations

import math
import re
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.data import format_rows
from dda.materials import LinearElastic
from dda.result import StepStats, _normal_and_shear
from dda.studies.studies import MovingBase
from dda.studies.sweep import Case, Study, SweepRows, grid, pareto_front, sweep
from tests.conftest import box, incline_scene

xr = pytest.importorskip("xarray")
pd = pytest.importorskip("pandas")

UNITS = {"displacement": "m", "rotation": "rad", "velocity": "m/s", "angular_velocity": "rad/s",
         "strain_rate": "1/s", "stress": "Pa", "initial_centroid": "m", "joint_force": "N/m"}


def drop_scene():
    """A block ("blöck", a non-ASCII name) 0.5 mm above a fixed base, and a third block resting
    on the base beside it: one pair in contact from the start, one that closes mid-run."""
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 2, 0.2), rock, fixed=True, name="base")
    scene.add_block(box(0.2, 0.2005, 0.2, 0.2), rock, name="blöck")
    scene.add_block(box(1.2, 0.2, 0.3, 0.3), rock, name="rest")
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=30.0)))
    return scene


@pytest.fixture(scope="module")
def dropped():
    """The drop scene run for 0.04 s, every second step recorded."""
    sim = dda.Simulation(drop_scene(), dt=1e-3, record_every=2)
    return sim, sim.run(0.04)


@pytest.fixture(scope="module")
def sliding():
    """The block sliding down a 30 degree incline (phi 20), every step recorded."""
    scene, _, _ = incline_scene(20.0)
    return dda.Simulation(scene, dt=1e-3, solver=dda.solvers.LegacyPullBack()).run(0.02)


# ------------------------------------------------------------------------- Result
@pytest.mark.parametrize("case", ["dropped", "sliding"])
def test_the_dataset_holds_what_the_result_methods_give(case, request):
    result = request.getfixturevalue(case)
    result = result[1] if isinstance(result, tuple) else result
    ds = result.to_xarray()
    assert ds.displacement.dims == ("time", "block", "component")
    assert ds.stress.dims == ("time", "block", "tensor_component")
    assert ds.joint_force.dims == ("time", "pair", "force_component")
    np.testing.assert_array_equal(ds.time.values, result.time)
    names = [b.name for b in result.scene.blocks]
    assert ds.block.values.tolist() == names
    assert ds.block_id.values.tolist() == list(range(len(names)))
    assert ds.component.values.tolist() == ["x", "y"]
    assert ds.tensor_component.values.tolist() == ["xx", "yy", "xy"]
    for block in result.scene.blocks:
        at = ds.sel(block=block.name)
        velocity = result.velocity(block)
        np.testing.assert_array_equal(at.displacement.values, result.displacement(block))
        np.testing.assert_array_equal(at.rotation.values, result.rotation(block))
        np.testing.assert_array_equal(at.velocity.values, velocity[:, :2])
        np.testing.assert_array_equal(at.angular_velocity.values, velocity[:, 2])
        np.testing.assert_array_equal(at.strain_rate.values, velocity[:, 3:])
        np.testing.assert_array_equal(at.stress.values, result.stress(block))


@pytest.mark.parametrize("case", ["dropped", "sliding"])
def test_the_joint_forces_are_the_results_pair_by_pair(case, request):
    result = request.getfixturevalue(case)
    result = result[1] if isinstance(result, tuple) else result
    ds = result.to_xarray()
    pairs = result.joint_pairs()
    assert ds.pair.values.tolist() == [f"{a.name}/{b.name}" for a, b in pairs]
    assert ds.block_a.values.tolist() == [a.name for a, _ in pairs]
    assert ds.block_b_id.values.tolist() == [b.index for _, b in pairs]
    assert ds.force_component.values.tolist() == ["normal", "shear"]
    for a, b in pairs:
        np.testing.assert_array_equal(ds.joint_force.sel(pair=f"{a.name}/{b.name}").values,
                                      result.joint_force(a, b))
        assert np.abs(result.joint_force(a, b)).max() > 0.0


def test_a_pair_that_closes_mid_run_carries_nothing_before(dropped):
    _, result = dropped
    force = result.to_xarray().joint_force.sel(pair="base/blöck", force_component="normal")
    weight = 0.2 * 0.2 * 2500.0 * 9.81
    assert float(force[0]) == 0.0 and float(force[5]) == 0.0  # still falling at 10 ms
    assert float(force.max()) > weight  # the impact, then the block rests
    assert set(result.to_xarray().pair.values) == {"base/blöck", "base/rest"}


def test_every_variable_has_its_units_and_a_long_name(dropped):
    ds = dropped[1].to_xarray()
    assert {name: v.attrs["units"] for name, v in ds.data_vars.items()} == UNITS
    for name in list(ds.data_vars) + ["time", "block", "block_id", "pair", "block_a"]:
        assert ds[name].attrs["long_name"], name
    assert ds.time.attrs["units"] == "s"


def test_the_initial_centroid_and_the_displacement_give_the_position_now(dropped):
    sim, result = dropped
    ds = result.to_xarray()
    np.testing.assert_array_equal(ds.initial_centroid.values, sim.model.centroid_initial)
    now = (ds.initial_centroid + ds.displacement.isel(time=-1)).values
    np.testing.assert_allclose(now, sim.committed.centroid, rtol=0, atol=1e-12)


def test_the_attributes_say_what_the_run_was(dropped):
    sim, result = dropped
    attrs = result.to_xarray().attrs
    assert attrs["dt"] == 1e-3 and attrs["record_every"] == 2
    assert attrs["solver"] == repr(sim.solver) and attrs["analysis"] == "dynamic"
    assert attrs["steps"] == len(result.stats) == 40 and attrs["dt_cuts"] == 0
    assert attrs["slip_reversals"] == len(result.stats.reversals)
    assert attrs["gravity"] == 9.81 and attrs["dda_version"] == dda.__version__
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\+00:00", attrs["created"])
    assert "choices" not in attrs  # empty: nothing was "auto"


def test_the_dataset_survives_netcdf(dropped, tmp_path):
    ds = dropped[1].to_xarray()
    ds.to_netcdf(tmp_path / "run.nc")
    with xr.open_dataset(tmp_path / "run.nc") as back:
        back.load()
    xr.testing.assert_identical(back, ds)
    assert back.block.values.tolist() == ["base", "blöck", "rest"]
    assert back.block_id.dtype == np.int32
    assert back.displacement.dtype == np.float64
    assert back.time.dtype == np.float64  # seconds, not decoded as dates or timedeltas
    assert back.joint_force.attrs["units"] == "N/m"


def test_a_scene_without_contacts_has_no_pair_dimension(tmp_path):
    scene = dda.Scene(gravity=9.81)
    b = scene.add_block(box(0, 0, 1, 1), LinearElastic(young=1e9, poisson=0.2, density=1e3))
    ds = dda.Simulation(scene, dt=0.01).run(0.05).to_xarray()
    assert "pair" not in ds.dims and "joint_force" not in ds
    np.testing.assert_allclose(ds.displacement.sel(block=b.name, component="y")[-1],
                               -9.81 * 0.05**2 / 2, rtol=1e-12)
    ds.to_netcdf(tmp_path / "free.nc")
    with xr.open_dataset(tmp_path / "free.nc") as back:
        xr.testing.assert_identical(back.load(), ds)


def test_a_zero_normal_gives_zero_forces():
    force = np.array([[1.0, 2.0], [3.0, 4.0]])
    normal = np.array([[0.0, 0.0], [0.0, 2.0]])
    np.testing.assert_array_equal(_normal_and_shear(force, normal), [[0, 0], [4.0, 3.0]])


# ------------------------------------------------------------------------- StepStats
def test_the_stats_frame_is_the_stats_columns(dropped):
    stats = dropped[1].stats
    frame = stats.to_pandas()
    assert list(frame.columns) == list(StepStats.FIELDS)
    assert frame.index.name == "step" and len(frame) == len(stats) == 40
    assert frame.index[0] == 0
    for key in StepStats.FIELDS:
        np.testing.assert_array_equal(frame[key].to_numpy(), stats[key])
        want = np.int64 if key in StepStats._COUNTS else np.float64
        assert frame[key].dtype == want, key
    assert set(frame.attrs["units"]) == set(StepStats.FIELDS)
    assert frame.attrs["units"]["time"] == "s" and frame.attrs["units"]["penetration"] == "m"
    assert frame.attrs["units"]["closed"] == "1"
    assert frame["time"].iloc[-1] == pytest.approx(0.04)


def test_empty_stats_give_an_empty_frame_with_the_columns():
    frame = StepStats().to_pandas()
    assert len(frame) == 0 and list(frame.columns) == list(StepStats.FIELDS)


# ------------------------------------------------------------------------- sweep rows
class Stops(Study):
    """A run that fails at once: its row has NaN error and a long status."""

    name = "stops"

    def prepare(self, dt=1e-2):
        scene = dda.Scene()
        scene.add_block(box(0, 0, 1, 1), LinearElastic(young=1e9, poisson=0.2, density=1e3),
                        velocity=(10.0, 0.0))
        return dda.Simulation(scene, dt=dt, max_displacement_ratio=1e-9), 0.1, lambda r: 0.0


@pytest.fixture(scope="module")
def rows():
    cases = grid(MovingBase(duration=0.1), solver=["legacy", "newton"], dt=[1e-2],
                 penalty=[2e9]) + [Case(Stops(), {"dt": 1e-2})]
    with ThreadPoolExecutor(1) as pool:
        return sweep(cases, executor=pool, progress=False)


def test_sweep_rows_stay_a_list_of_dicts(rows):
    assert isinstance(rows, SweepRows) and isinstance(rows, list)
    assert [r["solver"] for r in rows[:2]] == ["legacy", "newton"]
    assert all(isinstance(r, dict) for r in rows)
    assert rows == [dict(r) for r in rows]


def test_the_sweep_frame_is_the_rows(rows):
    frame = rows.to_pandas()
    assert list(frame.columns) == list(dict.fromkeys(k for r in rows for k in r))
    assert len(frame) == len(rows) == 3
    for i, row in enumerate(rows):
        for key, value in row.items():
            got = frame[key].iloc[i]
            if isinstance(value, float) and math.isnan(value):
                assert math.isnan(got), key
            else:
                assert got == value, key
    assert math.isnan(frame.loc[2, "solver"])  # the failing study has no solver setting
    assert frame["steps"].dtype == np.int64 and frame["cpu_time"].dtype == np.float64
    assert frame.attrs["units"]["cpu_time"] == "s" and frame.attrs["units"]["dt"] == "s"


def test_printed_rows_are_rounded(rows):
    text = str(rows)
    assert repr(rows) == text
    header, *lines = text.splitlines()
    assert header.split()[:4] == ["study", "solver", "dt", "penalty"]
    assert "detection_time" not in header  # the parts' seconds: to_pandas()
    assert len(lines) == 3
    numbers = re.findall(r"\d+\.\d+(?:e[-+]\d+)?", text)
    assert numbers and all(len(n.split("e")[0].replace(".", "").lstrip("0")) <= 4
                           for n in numbers), numbers
    assert f"{rows[0]['cpu_time']!r}" not in text  # not the unrounded float
    assert "failed at t = 0 s" in lines[2] and lines[2].rstrip().endswith("...")
    assert " nan " in lines[2]
    assert "detection_time" in rows.table(columns=["solver", "detection_time"])


def test_the_pareto_front_prints_rounded_too(rows):
    front = pareto_front(rows)
    assert isinstance(front, SweepRows) and len(front) >= 1
    assert str(front).splitlines()[1:] == str(SweepRows(front)).splitlines()[1:]
    assert f"{front[0]['error']!r}" not in str(front)


def test_format_rows_rounds_to_the_digits_asked():
    rows = [{"a": 1 / 3, "b": 12345.678, "c": "x"}, {"a": math.nan, "b": 2}]
    assert format_rows(rows, digits=3) == ("    a         b  c\n"
                                           "0.333  1.23e+04  x\n"
                                           "  nan         2")
    assert str(SweepRows()) == "SweepRows([])"


# ------------------------------------------------------------------------- the extra
@pytest.mark.parametrize("module", ["xarray", "pandas"])
def test_a_missing_package_names_the_extra(module, monkeypatch, sliding):
    monkeypatch.setitem(sys.modules, module, None)  # import fails as if not installed
    call = sliding.to_xarray if module == "xarray" else sliding.stats.to_pandas
    with pytest.raises(ImportError, match=re.escape("pip install 'dda[data]'")):
        call()


def test_import_dda_does_not_import_xarray_or_pandas():
    import subprocess

    code = ("import sys, dda, dda.studies.sweep; "
            "print(sorted(m for m in ('xarray', 'pandas') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"
