"""Sweeps: run many settings of a study on any executor and collect one row per run.

A :class:`Study` turns settings (a dict such as ``{"solver": "newton", "dt": 1e-3,
"penalty": 2e9}``) into a simulation, a duration and a way to measure the error of the result
against the study's reference. A :class:`Case` is one study with one set of settings;
:func:`sweep` runs cases on a :class:`concurrent.futures.Executor` (local processes by default;
a Dask client's ``client.get_executor()`` works unchanged) and returns one row per case, in the
order of the cases, with the settings, the error, the CPU time, the steps, the iterations and
where the time went (:mod:`dda.profiling`).

Studies and settings travel to worker processes by pickling: define a study as a class at
module level (not a lambda or a local function).

Examples
--------
>>> from concurrent.futures import ThreadPoolExecutor
>>> from dda.studies.sweep import grid, sweep
>>> from dda.studies.studies import MovingBase
>>> cases = grid(MovingBase(duration=0.2), solver=["legacy", "newton"], dt=[1e-2],
...              penalty=[2e9])
>>> with ThreadPoolExecutor(2) as pool:
...     rows = sweep(cases, executor=pool, progress=False)
>>> [(r["solver"], r["steps"], r["slip_reversals"], r["status"]) for r in rows]
[('legacy', 21, 1, 'ok'), ('newton', 21, 1, 'ok')]
"""

from __future__ import annotations

import csv
import inspect
import itertools
import math
import pickle
import sys
import threading
import time
import traceback
import warnings
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from dda import registry
from dda.profiling import SECTIONS
from dda.runtime import blas_threads, usable_cores
from dda.simulation import Simulation, SimulationError

# SOLVERS comes from the module's __getattr__ (the registry's solver names)
__all__ = ["Study", "Case", "grid", "run_case", "sweep", "SweepRows", "write_csv",
           "markdown_table", "pareto_front", "cheapest",
           "SOLVERS"]  # noqa: F822


def make_solver(name: str, **settings):
    """The solver called ``name`` with ``settings`` (default: its default settings).

    ``name`` is one of :func:`dda.registry.solver_names` ("legacy", "newton" and any
    registered with :func:`dda.registry.register_solver`) or an import path "module:Class".
    """
    return registry.make_solver(name, **settings)


def __getattr__(name):
    # SOLVERS follows the registry, solvers registered after this import included
    if name == "SOLVERS":
        return registry.solver_names()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class Study(ABC):
    """A scene with a reference answer, to be run at many settings.

    Subclasses set ``name`` and implement :meth:`prepare`.
    """

    name = "study"

    @abstractmethod
    def prepare(self, **settings) -> tuple[Simulation, float, Callable]:
        """The simulation for these settings, its duration (s) and ``error(result)``.

        ``error`` returns the relative error against the study's reference (0.01 is 1%), or
        a dict with that under ``"error"`` and other measures beside it (they become columns
        of the row: numbers as floats; True/False, text and tuples as they are).
        """

    def __repr__(self):
        return f"{type(self).__name__}()"


@dataclass(frozen=True)
class Case:
    """One run of a sweep: a study and its settings."""

    study: Study
    settings: dict = field(default_factory=dict)


def grid(study: Study, **axes: Sequence) -> list[Case]:
    """Every combination of the given settings, as cases (the last axis varies fastest).

    >>> from dda.studies.studies import MovingBase
    >>> [c.settings for c in grid(MovingBase(), solver=["legacy"], dt=[1e-2, 1e-3])]
    [{'solver': 'legacy', 'dt': 0.01}, {'solver': 'legacy', 'dt': 0.001}]
    """
    if not axes:
        return [Case(study, {})]
    known = _settings_of(study)
    unknown = [name for name in axes if known is not None and name not in known]
    if unknown:
        raise TypeError(f"grid: {type(study).__name__} has no setting "
                        f"{', '.join(map(repr, unknown))}; its settings: "
                        f"{', '.join(known) or 'none'}")
    for name, values in axes.items():
        if isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
            raise TypeError(f"grid: axis {name!r} must be a list of values, got {values!r}")
    names = list(axes)
    return [Case(study, dict(zip(names, combo, strict=True)))
            for combo in itertools.product(*(list(axes[n]) for n in names))]


def _settings_of(study) -> list[str] | None:
    """The names ``study.prepare`` takes, or None when it takes any (``**settings``)."""
    try:
        params = inspect.signature(study.prepare).parameters.values()
    except (TypeError, ValueError):
        return None
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
        return None
    return [p.name for p in params
            if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)]


def _cpu_clock():
    # in a worker thread (a threaded Dask worker) the process clock counts the other threads
    # too; in a worker process (the default) it also counts BLAS threads, as it should
    if threading.current_thread() is threading.main_thread():
        return time.process_time
    return time.thread_time


def run_case(case: Case) -> dict:
    """Run one case and return its row (see :func:`sweep`); a failed run is a row too.

    The whole case (its preparation, its run and its measures) runs with
    :data:`dda.runtime.BLAS_THREADS` BLAS threads: a sweep's processes, one a core, would
    otherwise each start a thread a core and fight for them."""
    if not isinstance(case, Case):
        raise TypeError(f"run_case: expected a Case, got {case!r}")
    with blas_threads():
        return _run_case(case)


#: steps a process runs of the first case of each study and solver before it times one: the
#: compiled kernels load on their first call (0.37 s of CPU for the first legacy case of a
#: fresh worker against 0.006 s for the same case next), which would be charged to that case
WARM_UP_STEPS = 5
#: (study, solver) pairs this process has run a warm-up for
_WARMED: set = set()


def _warm_up(case: Case) -> None:
    """Run the case's simulation for :data:`WARM_UP_STEPS` steps, once per process for each
    study and solver, untimed; a failure is left to the timed run to report."""
    key = (type(case.study).__qualname__, case.study.name, repr(case.settings.get("solver")))
    if key in _WARMED:
        return
    try:
        sim, duration, _ = case.study.prepare(**case.settings)
        sim.run(min(duration, WARM_UP_STEPS * sim.dt), progress=False)
    except Exception:  # noqa: BLE001 - the timed run meets it again and reports it
        return  # (not warmed: a case with bad settings leaves the next good one to do it)
    _WARMED.add(key)


def _run_case(case: Case) -> dict:
    _warm_up(case)
    sim, duration, error = case.study.prepare(**case.settings)
    clock = _cpu_clock()
    cpu0, wall0 = clock(), time.perf_counter()
    status = "ok"
    try:
        result = sim.run(duration, progress=False)
    except SimulationError as exc:
        result = exc.result
        status = f"failed at t = {sim.committed.time:.4g} s: {exc}"
    cpu = clock() - cpu0
    wall = time.perf_counter() - wall0
    measures = {"error": math.nan}
    if status == "ok":
        try:
            measures = error(result)
        except Exception as exc:  # noqa: BLE001 - the run is kept; the row says what failed
            status = f"ran, but its error measure raised {type(exc).__name__}: {exc}"
    if not isinstance(measures, dict):
        measures = {"error": measures}
    st = result.stats
    row = {"study": case.study.name, **case.settings,
           **{k: _measure(v) for k, v in measures.items()}, "cpu_time": cpu,
           "wall_time": wall, "steps": len(st), "iterations": int(st["iterations"].sum()),
           "open_close_passes": int(st["open_close_passes"].sum()),
           "solves": int(st["solves"].sum()), "dt_cuts": len(st.cuts),
           "slip_reversals": len(st.reversals),
           "contacts_max": int(st["contacts"].max()) if len(st) else 0, "status": status}
    for name in SECTIONS:
        row[f"{name}_time"] = float(st[f"{name}_time"].sum())
    return row


def _measure(value):
    """A measure as a row keeps it: a number as a float; True/False, text and tuples (of
    names, say) as they are."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (str, tuple)):
        return value
    return float(value)


class SweepRows(list):
    """A sweep's rows: a list of dicts, one a case, that prints as a rounded table.

    It is a list (iterate, index, sort, filter, pickle it as one); ``print(rows)`` and the
    interpreter show :meth:`table`, and :meth:`to_pandas` gives a DataFrame.

    Examples
    --------
    >>> rows = SweepRows([{"solver": "legacy", "dt": 0.01, "error": 0.031415926,
    ...                    "cpu_time": 0.123456, "steps": 20, "status": "ok"}])
    >>> rows[0]["solver"], len(rows)
    ('legacy', 1)
    >>> print(rows)
    solver    dt    error  cpu_time  steps  status
    legacy  0.01  0.03142    0.1235     20  ok
    """

    def table(self, columns: Sequence[str] | None = None, digits: int = 4) -> str:
        """The rows as a text table, floats to ``digits`` significant digits.

        ``columns`` defaults to every column but the seconds per part of the step
        (``detection_time`` ...: :meth:`to_pandas` has them).
        """
        from dda.data import format_rows

        if columns is None:
            parts = {f"{name}_time" for name in SECTIONS}
            columns = [c for c in dict.fromkeys(k for r in self for k in r) if c not in parts]
        return format_rows(self, columns, digits)

    def to_pandas(self):
        """The rows as a :class:`pandas.DataFrame` (needs ``pip install 'dda[data]'``; see
        :func:`dda.data.rows_frame`)."""
        from dda.data import rows_frame

        return rows_frame(self)

    def __str__(self) -> str:
        return self.table() if self else "SweepRows([])"

    def __repr__(self) -> str:
        return self.__str__()


def sweep(cases: Sequence[Case], executor: Executor | None = None,
          progress: bool | None = None, on_error: str = "row") -> SweepRows:
    """Run every case on ``executor`` and return their rows in the order of ``cases``.

    Parameters
    ----------
    cases : sequence of Case
    executor : concurrent.futures.Executor, optional
        Where the runs go. Default: a process pool with one worker per core this process may
        use (its CPU affinity: a batch job's allocation). A Dask distributed client's
        executor (``client.get_executor()``) runs them on its cluster.
    progress : bool, optional
        A progress bar on stderr (cases done, the last one, elapsed and remaining time). By
        default on when stderr is a terminal.
    on_error : {"row", "raise"}
        What a case that raises (bad settings, a study's bug; a run that stops with
        :class:`~dda.SimulationError` is a row either way) does: "row", the default, makes it
        a row whose ``status`` starts "not run:" with the exception, the other cases go on,
        and a warning at the end counts them; "raise" stops the sweep with the exception,
        noted with the case's settings.

    Returns
    -------
    SweepRows
        A list of dicts (it prints as a rounded table; ``rows.to_pandas()`` is a DataFrame).
        Per case: ``study``, the settings, ``error`` (relative, NaN for a failed run),
        ``cpu_time`` and ``wall_time`` (s, of the run alone: each worker first runs
        :data:`WARM_UP_STEPS` untimed steps of its first case of each study and solver, so
        that loading the compiled kernels is not charged to it; that calls the study's
        ``prepare`` once more), ``steps``, ``iterations``,
        ``open_close_passes``, ``solves``, ``dt_cuts``, ``slip_reversals`` (steps ended at a
        slip reversal, :mod:`dda.slip_events`), ``contacts_max``, ``status`` ("ok" or
        why it stopped) and the seconds per part of the step (``detection_time`` ...).
    """
    cases = list(cases)
    for i, c in enumerate(cases):
        if not isinstance(c, Case):
            raise TypeError(f"sweep: case {i} is not a Case: {c!r}")
    if on_error not in ("row", "raise"):
        raise ValueError(f"sweep: on_error must be 'row' or 'raise', got {on_error!r}")
    if progress is None:
        progress = sys.stderr.isatty()
    own = executor is None
    if own:
        executor = ProcessPoolExecutor(max_workers=min(len(cases), usable_cores()) or 1)
    rows: list[dict | None] = [None] * len(cases)
    not_run: list[int] = []
    bar = tqdm(total=len(cases), unit="case", file=sys.stderr, disable=not progress,
               mininterval=0.0, miniters=1)  # (each case shown: they are few and slow)
    try:
        # threads share this process: a case's exception comes back as it is; elsewhere
        # (processes, a Dask cluster) it comes back as a value with its worker's traceback
        task = run_case if isinstance(executor, ThreadPoolExecutor) else _run_case_or_error
        futures = {executor.submit(task, c): i for i, c in enumerate(cases)}
        for fut in as_completed(futures):
            i = futures[fut]
            try:
                rows[i] = fut.result()
                if isinstance(rows[i], _CaseRaised):
                    raised = rows[i]
                    raise raised.exception from _WorkerTraceback(raised.traceback)
            except Exception as exc:
                where = f"sweep: case {i} ({_settings_text(cases[i])})"
                if on_error == "raise":
                    if hasattr(exc, "add_note"):
                        exc.add_note(where)
                    raise
                rows[i] = _not_run_row(cases[i], exc)
                not_run.append(i)
            bar.set_postfix_str(_label(rows[i]), refresh=False)
            bar.update(1)
    finally:
        bar.close()
        if own:
            executor.shutdown(cancel_futures=True)
    if not_run:
        first = min(not_run)
        warnings.warn(f"sweep: {len(not_run)} of {len(cases)} cases did not run; the first, "
                      f"case {first} ({_settings_text(cases[first])}): "
                      f"{rows[first]['status'][len('not run: '):]}", RuntimeWarning,
                      stacklevel=2)
    return SweepRows(rows)


@dataclass
class _CaseRaised:
    """What a case raised in a worker, sent back as a value with its traceback's text: an
    exception that does not unpickle, raised there, broke the pool and every case after
    it."""

    exception: BaseException
    traceback: str


class _WorkerTraceback(Exception):
    """The traceback of a case's exception in its worker (the raised exception's cause)."""

    def __str__(self):
        return "\n" + (self.args[0] if self.args else "")


def _run_case_or_error(case: Case):
    """:func:`run_case`, or a :class:`_CaseRaised` with what it raised, made safe to send
    back (an exception that does not survive pickling becomes a RuntimeError with its
    type's name and message)."""
    try:
        return run_case(case)
    except Exception as exc:  # noqa: BLE001 - every case's failure is the caller's to judge
        text = "".join(traceback.format_exception(exc))
        try:
            pickle.loads(pickle.dumps(exc))
        except Exception:  # noqa: BLE001 - any failure to pickle or unpickle
            exc = RuntimeError(f"{type(exc).__name__}: {exc}")
        return _CaseRaised(exc, text)


def _settings_text(case: Case) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in case.settings.items()) or "no settings"


def _not_run_row(case: Case, exc: BaseException) -> dict:
    """The row of a case that raised before its run ended: its settings, NaN measures and
    times, no steps, and the exception as its status."""
    row = {"study": getattr(case.study, "name", type(case.study).__name__), **case.settings,
           "error": math.nan, "cpu_time": math.nan, "wall_time": math.nan, "steps": 0,
           "iterations": 0, "open_close_passes": 0, "solves": 0, "dt_cuts": 0,
           "slip_reversals": 0, "contacts_max": 0,
           "status": f"not run: {type(exc).__name__}: {exc}"}
    for name in SECTIONS:
        row[f"{name}_time"] = math.nan
    return row


def _label(row) -> str:
    """The settings of a case's row, short (the progress bar's last case)."""
    label = ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                      for k, v in row.items() if k not in _OUTCOME and k != "study")
    return label[:60]


_OUTCOME = {"error", "cpu_time", "wall_time", "steps", "iterations", "open_close_passes",
            "solves", "dt_cuts", "slip_reversals", "contacts_max", "status"} | {
                f"{n}_time" for n in SECTIONS}


def write_csv(rows: Sequence[dict], path) -> Path:
    """Write rows to a CSV file (columns in the order of the first row)."""
    path = Path(path)
    columns = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns)
        w.writeheader()
        w.writerows(rows)
    return path


def markdown_table(rows: Sequence[dict], columns: Sequence[str],
                   formats: dict | None = None) -> str:
    """A markdown table of the given columns; ``formats`` maps a column to a format spec."""
    formats = formats or {}
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        cells = []
        for c in columns:
            v = r.get(c, "")
            spec = formats.get(c)
            cells.append(format(v, spec) if spec and isinstance(v, (int, float)) else str(v))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def pareto_front(rows: Sequence[dict], cost: str = "cpu_time",
                 error: str = "error") -> SweepRows:
    """The rows no other row beats in both cost and error, cheapest first.

    Rows with a NaN error (failed runs) are left out. A :class:`SweepRows` (a list).

    >>> rows = [{"cpu_time": 1, "error": 0.1}, {"cpu_time": 2, "error": 0.2},
    ...         {"cpu_time": 3, "error": 0.01}]
    >>> [r["cpu_time"] for r in pareto_front(rows)]
    [1, 3]
    """
    ok = [r for r in rows if np.isfinite(r.get(error, math.nan))]  # (failed: no measures)
    ok.sort(key=lambda r: (r[cost], abs(r[error])))
    front, best = [], math.inf
    for r in ok:
        if abs(r[error]) < best:
            front.append(r)
            best = abs(r[error])
    return SweepRows(front)


def cheapest(rows: Sequence[dict], tolerance: float, cost: str = "cpu_time",
             error: str = "error") -> dict | None:
    """The cheapest row whose ``|error|`` is at most ``tolerance`` (None if there is none)."""
    ok = [r for r in rows if np.isfinite(r.get(error, math.nan)) and abs(r[error]) <= tolerance]
    return min(ok, key=lambda r: r[cost]) if ok else None
