"""The sweep runner: cases on any executor (processes, threads, Dask), rows, Pareto fronts."""

from __future__ import annotations

import csv
import math
from concurrent.futures import ThreadPoolExecutor

import distributed
import numpy as np
import pytest

import dda
from dda.materials import LinearElastic
from dda.studies.studies import DirectShear, MovingBase
from dda.studies.sweep import (
    Case,
    Study,
    cheapest,
    grid,
    markdown_table,
    pareto_front,
    run_case,
    sweep,
    write_csv,
)

DETERMINISTIC = ("study", "solver", "dt", "penalty", "error", "peak_error", "steps",
                 "iterations", "open_close_passes", "solves", "dt_cuts", "slip_reversals", "status")


def small_grid():
    return grid(MovingBase(duration=0.3), solver=["legacy", "newton"], dt=[1e-2, 5e-3],
                penalty=[2e9])


def test_grid_is_the_product_of_the_axes():
    cases = grid(MovingBase(), solver=["legacy", "newton"], dt=[1e-2, 1e-3, 1e-4],
                 penalty=[2e7, 2e9])
    assert len(cases) == 12
    assert cases[0].settings == {"solver": "legacy", "dt": 1e-2, "penalty": 2e7}
    assert cases[-1].settings == {"solver": "newton", "dt": 1e-4, "penalty": 2e9}
    assert len({tuple(c.settings.values()) for c in cases}) == 12


def test_grid_rejects_a_bare_value():
    with pytest.raises(TypeError, match="axis 'dt' must be a list"):
        grid(MovingBase(), dt=1e-3)


def test_grid_names_a_setting_the_study_does_not_take():
    # (a misspelt axis used to fail only in the sweep's runs, as a TypeError from prepare)
    with pytest.raises(TypeError, match="MovingBase has no setting 'solvr'; its settings: "
                                        "solver, dt, penalty"):
        grid(MovingBase(), solvr=["legacy"], dt=[1e-3])


def test_unknown_solver_is_named():
    with pytest.raises(ValueError, match="unknown solver 'implicit'"):
        run_case(Case(MovingBase(duration=0.2), {"solver": "implicit"}))


def test_sweep_needs_cases():
    with pytest.raises(TypeError, match="case 0 is not a Case"):
        sweep([{"solver": "newton"}], executor=ThreadPoolExecutor(1))


def test_process_pool_and_dask_give_the_same_rows():
    cases = small_grid()
    rows = sweep(cases, progress=False)  # the default: local processes
    assert [(r["solver"], r["dt"]) for r in rows] == [
        (c.settings["solver"], c.settings["dt"]) for c in cases]
    for r in rows:
        assert r["status"] == "ok"
        # a step ended at a slip reversal may add one (dda.slip_events)
        assert round(0.3 / r["dt"]) <= r["steps"] <= round(0.3 / r["dt"]) + r["slip_reversals"]
        assert r["cpu_time"] > 0.0 and r["wall_time"] > 0.0
        assert 0.0 < r["error"] < 1.0
        assert r["solves"] >= r["steps"]
        assert r["contacts_max"] == 2
        parts = sum(r[f"{n}_time"] for n in dda.profiling.SECTIONS)
        assert 0.0 < parts <= r["wall_time"]

    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        dask_rows = sweep(cases, executor=client.get_executor(), progress=False)
    for a, b in zip(rows, dask_rows, strict=True):
        assert {k: a[k] for k in DETERMINISTIC} == {k: b[k] for k in DETERMINISTIC}


def test_the_errors_tell_good_settings_from_bad():
    rows = sweep(grid(MovingBase(duration=0.5), solver=["newton", "legacy"], dt=[1e-3],
                      penalty=[2e9])
                 + grid(DirectShear(), solver=["newton", "legacy"], dt=[0.05],
                        penalty=[1e10]),
                 executor=ThreadPoolExecutor(2), progress=False)
    moving_newton, moving_legacy, shear_newton, shear_legacy = rows
    assert moving_newton["error"] < 0.02 and abs(moving_newton["peak_error"]) < 0.01
    assert moving_legacy["error"] < 0.05
    # direct shear in 20 steps: Newton holds the strength, legacy overshoots by 32%
    # (examples/direct_shear.py)
    assert shear_newton["error"] < 1e-3
    assert shear_legacy["overshoot"] == pytest.approx(0.3209, abs=2e-3)
    assert shear_legacy["error"] == pytest.approx(shear_legacy["overshoot"])


class TooFast(Study):
    """A block allowed to move a billionth of its size per step: every step is cut."""

    name = "too_fast"

    def prepare(self, dt=1e-2):
        scene = dda.Scene()
        scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)],
                        LinearElastic(young=1e9, poisson=0.2, density=1000.0),
                        velocity=(10.0, 0.0))
        sim = dda.Simulation(scene, dt=dt, max_displacement_ratio=1e-9)
        return sim, 0.1, lambda result: 0.0


def test_a_failed_run_is_a_row_with_its_reason():
    rows = sweep([Case(TooFast(), {"dt": 1e-2}),
                  Case(MovingBase(duration=0.2), {"solver": "legacy", "dt": 1e-2})],
                 executor=ThreadPoolExecutor(2), progress=False)
    assert rows[0]["status"].startswith("failed at t = 0 s")
    assert "max_displacement_ratio" in rows[0]["status"]
    assert math.isnan(rows[0]["error"])
    assert rows[0]["steps"] == 0
    assert rows[1]["status"] == "ok"


class NoMeasure(MovingBase):
    """The moving base whose error measure raises (a study's bug met after the run)."""

    name = "no_measure"

    def prepare(self, **settings):
        sim, duration, _ = super().prepare(**settings)

        def error(result):
            raise ValueError("no slip to measure")

        return sim, duration, error


def test_a_case_that_raises_is_a_row_and_the_others_run():
    """A negative penalty, a solver's name mistyped and an error measure that raises: each a
    row that says so with its settings (before, the first stopped the whole sweep and the
    rows already done were lost), the good cases run, and a warning counts them."""
    base = MovingBase(duration=0.2)
    cases = [Case(base, {"solver": "legacy", "dt": 1e-2, "penalty": 2e9}),
             Case(base, {"solver": "legacy", "dt": 1e-2, "penalty": -1.0}),
             Case(base, {"solver": "Legacy", "dt": 1e-2, "penalty": 2e9}),
             Case(NoMeasure(duration=0.2), {"solver": "legacy", "dt": 1e-2, "penalty": 2e9})]
    with pytest.warns(RuntimeWarning, match=r"2 of 4 cases did not run; the first, case 1 "
                                            r"\(solver='legacy', dt=0.01, penalty=-1.0\)"):
        rows = sweep(cases, executor=ThreadPoolExecutor(2), progress=False)
    ok, negative, typo, measure = rows
    assert ok["status"] == "ok" and ok["steps"] == 21
    assert negative["status"].startswith("not run: ValueError: JointMaterial")
    assert negative["penalty"] == -1.0 and math.isnan(negative["error"])
    assert negative["steps"] == 0 and math.isnan(negative["cpu_time"])
    assert typo["status"].startswith("not run:") and "'Legacy'" in typo["status"]
    assert measure["status"] == ("ran, but its error measure raised ValueError: no slip to "
                                 "measure")
    assert measure["steps"] == 21 and math.isnan(measure["error"])
    assert "not run" in str(rows)  # the table prints
    with pytest.raises(ValueError, match="JointMaterial") as info:
        sweep(cases[:2], executor=ThreadPoolExecutor(1), progress=False, on_error="raise")
    assert "sweep: case 1 (solver='legacy', dt=0.01, penalty=-1.0)" in info.value.__notes__
    with pytest.raises(ValueError, match="on_error"):
        sweep(cases, on_error="skip")


class Counted(MovingBase):
    """The moving base, counting its preparations."""

    name = "counted"
    prepared: list = []

    def prepare(self, **settings):
        self.prepared.append(settings["solver"])
        return super().prepare(**settings)


def test_each_process_warms_its_kernels_once_per_study_and_solver(monkeypatch):
    """The first case of each study and solver in a process first runs a few untimed steps,
    so that loading the compiled kernels is not charged to its cpu_time (0.37 s against
    0.006 s for the same case after it, in a fresh worker)."""
    from dda.studies import sweep as sweep_module

    monkeypatch.setattr(sweep_module, "_WARMED", set())
    Counted.prepared.clear()
    study = Counted(duration=0.1)
    sweep([Case(study, {"solver": s, "dt": 1e-2, "penalty": 2e9})
           for s in ("legacy", "legacy", "newton", "legacy", "newton")],
          executor=ThreadPoolExecutor(1), progress=False)
    # the warm-up prepares once more for the first legacy and the first newton case
    assert Counted.prepared == ["legacy", "legacy", "legacy", "newton", "newton", "legacy",
                                "newton"]


class TwoArgError(Exception):
    """An exception that pickles but does not unpickle (its __init__ takes two arguments)."""

    def __init__(self, a, b):
        super().__init__(f"{a} and {b}")


class RaisesTwoArg(MovingBase):
    name = "raises_two_arg"

    def prepare(self, **settings):
        if settings["dt"] == 1e-2:
            raise TwoArgError("first", "second")
        return super().prepare(**settings)


def test_an_exception_that_does_not_unpickle_stays_in_its_case():
    """Raised in a worker process, it broke the pool: every later case became "not run:
    BrokenProcessPool" (3 of 4)."""
    from concurrent.futures import ProcessPoolExecutor

    study = RaisesTwoArg(duration=0.2)
    cases = [Case(study, {"solver": "legacy", "dt": dt, "penalty": 2e9})
             for dt in (5e-3, 1e-2, 5e-3, 5e-3)]
    with ProcessPoolExecutor(1) as pool, pytest.warns(RuntimeWarning, match="1 of 4 cases"):
        rows = sweep(cases, executor=pool, progress=False)
    assert [r["status"] for r in rows] == ["ok", "not run: RuntimeError: TwoArgError: first "
                                           "and second", "ok", "ok"]
    # raised, it keeps its worker's traceback as its cause; in threads it is itself
    with ProcessPoolExecutor(1) as pool, pytest.raises(RuntimeError) as info:
        sweep(cases[:2], executor=pool, progress=False, on_error="raise")
    assert "in prepare" in str(info.value.__cause__) and "TwoArgError" in str(
        info.value.__cause__)
    with pytest.raises(TwoArgError):
        sweep(cases[:2], executor=ThreadPoolExecutor(1), progress=False, on_error="raise")


def test_a_case_that_fails_leaves_the_warm_up_to_the_next(monkeypatch):
    """A case with bad settings used up its solver's warm-up: the next good case's cpu_time
    carried the kernels' loading again (0.39 s against 0.005 s)."""
    from dda.studies import sweep as sweep_module

    monkeypatch.setattr(sweep_module, "_WARMED", set())
    Counted.prepared.clear()
    study = Counted(duration=0.1)
    with pytest.warns(RuntimeWarning, match="1 of 3 cases"):
        rows = sweep([Case(study, {"solver": "legacy", "dt": dt, "penalty": 2e9})
                      for dt in (-1.0, 1e-2, 1e-2)], executor=ThreadPoolExecutor(1),
                     progress=False)
    assert [r["status"] for r in rows][1:] == ["ok", "ok"]
    # the bad case: its warm-up and its run; the first good one: a warm-up and its run
    assert len(Counted.prepared) == 5


def test_the_default_pool_uses_the_cores_the_process_may_use(monkeypatch):
    from dda.runtime import usable_cores

    monkeypatch.setattr("os.sched_getaffinity", lambda pid: {1}, raising=False)
    monkeypatch.setattr("os.cpu_count", lambda: 64)
    assert usable_cores() == 1


def test_progress_bar_counts_the_cases(capsys):
    sweep(grid(MovingBase(duration=0.2), solver=["legacy"], dt=[1e-2, 2e-2]),
          executor=ThreadPoolExecutor(1), progress=True)
    err = capsys.readouterr().err
    assert "1/2" in err and "2/2" in err


def rows_for_fronts():
    return [
        {"solver": "a", "cpu_time": 1.0, "error": 0.5},
        {"solver": "a", "cpu_time": 2.0, "error": 0.05},
        {"solver": "a", "cpu_time": 3.0, "error": 0.08},  # dominated
        {"solver": "a", "cpu_time": 4.0, "error": -0.005},
        {"solver": "a", "cpu_time": 0.5, "error": math.nan},  # failed
    ]


def test_fronts_pass_over_rows_without_the_measure():
    """A failed or not-run row has no study measures beyond "error": a front by another
    measure raised KeyError on it."""
    rows = [{"cpu_time": 1.0, "error": 0.2, "peak": 0.1},
            {"cpu_time": 0.5, "error": math.nan, "status": "not run: ValueError: x"},
            {"cpu_time": 2.0, "error": 0.01, "peak": 0.005}]
    assert [r["cpu_time"] for r in pareto_front(rows, error="peak")] == [1.0, 2.0]
    assert cheapest(rows, 0.01, error="peak")["cpu_time"] == 2.0


def test_pareto_front_and_cheapest():
    rows = rows_for_fronts()
    assert [r["cpu_time"] for r in pareto_front(rows)] == [1.0, 2.0, 4.0]
    assert cheapest(rows, 0.01)["cpu_time"] == 4.0
    assert cheapest(rows, 0.1)["cpu_time"] == 2.0
    assert cheapest(rows, 1e-4) is None


def test_csv_and_markdown(tmp_path):
    rows = rows_for_fronts()
    path = write_csv(rows, tmp_path / "rows.csv")
    with open(path) as f:
        back = list(csv.DictReader(f))
    assert [float(r["cpu_time"]) for r in back] == [r["cpu_time"] for r in rows]
    table = markdown_table(rows[:2], ["solver", "cpu_time", "error"],
                           {"cpu_time": ".2f", "error": ".1%"})
    assert table.splitlines()[2] == "| a | 1.00 | 50.0% |"
    assert np.isnan(float(back[-1]["error"]))


def _blas_threads() -> int:
    from threadpoolctl import threadpool_info

    return max((p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"),
               default=1)


class CountsBlasThreads(MovingBase):
    """The moving base, recording the BLAS threads it sees while prepared and measured."""

    def prepare(self, **settings):
        seen = _blas_threads()
        sim, duration, error = super().prepare(**settings)

        def measured(result):
            out = error(result)
            out = out if isinstance(out, dict) else {"error": out}
            return {**out, "blas_prepare": seen, "blas_measure": _blas_threads()}

        return sim, duration, measured


def test_a_sweeps_cases_run_on_one_blas_thread():
    """Issue 22, item 7: a case's preparation, run and measures on one BLAS thread (a sweep
    on two cores must not start four BLAS threads)."""
    rows = sweep(grid(CountsBlasThreads(duration=0.3), solver=["legacy"], dt=[1e-2]))
    assert rows[0]["blas_prepare"] == 1 and rows[0]["blas_measure"] == 1
