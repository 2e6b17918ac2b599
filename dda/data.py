"""Results as data: a run's history as an xarray Dataset, its statistics and a sweep's rows as
pandas DataFrames.

xarray and pandas are the optional extra ``dda[data]`` (``pip install 'dda[data]'``): they are
imported here, when a conversion is asked for, never by ``import dda``.

:meth:`dda.Result.to_xarray` (:func:`result_dataset`) gives these variables, each with its
``units`` (SI) and ``long_name``:

==================  ==============================  =======  =================================
variable            dimensions                      units    meaning
==================  ==============================  =======  =================================
displacement        time, block, component          m        centroid displacement from the
                                                             start (:meth:`Result.displacement`)
rotation            time, block                     rad      rigid rotation from the start,
                                                             counter-clockwise positive
velocity            time, block, component          m/s      centroid velocity
angular_velocity    time, block                     rad/s    rate of the rigid rotation
strain_rate         time, block, tensor_component   1/s      rate of the block's uniform
                                                             strain (xy: engineering shear)
stress              time, block, tensor_component   Pa       the block's uniform stress,
                                                             tension positive
initial_centroid    block, component                m        the centroid at the start
joint_force         time, pair, force_component     N/m      total normal (compression
                                                             positive) and shear force of the
                                                             pair (:meth:`Result.joint_force`)
==================  ==============================  =======  =================================

``velocity``, ``angular_velocity`` and ``strain_rate`` are :meth:`Result.velocity`'s six
columns [u0, v0, r0, ex, ey, gxy]; ``stress`` is :meth:`Result.stress` [sx, sy, txy].

Examples
--------
>>> rows = [{"solver": "newton", "dt": 0.001, "error": 0.0123456789, "steps": 300}]
>>> print(format_rows(rows))
solver     dt    error  steps
newton  0.001  0.01235    300
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Sequence
from datetime import datetime, timezone

import numpy as np

__all__ = ["result_dataset", "stats_frame", "rows_frame", "format_rows", "STATS_UNITS",
           "ROW_UNITS"]

_EXTRA = "pip install 'dda[data]'"

# per block: (name, dims after time and block, units, long_name, source, columns)
_BLOCK_VARIABLES = (
    ("displacement", ("component",), "m", "centroid displacement from the start", "disp",
     slice(0, 2)),
    ("rotation", (), "rad", "rigid rotation from the start, counter-clockwise positive",
     "rot", None),
    ("velocity", ("component",), "m/s", "centroid velocity", "vel", slice(0, 2)),
    ("angular_velocity", (), "rad/s", "rate of the rigid rotation, counter-clockwise positive",
     "vel", 2),
    ("strain_rate", ("tensor_component",), "1/s",
     "rate of the uniform strain (xy: engineering shear strain rate)", "vel", slice(3, 6)),
    ("stress", ("tensor_component",), "Pa", "uniform stress, tension positive", "stress",
     slice(0, 3)),
)

#: Units of the :class:`dda.result.StepStats` columns ("1": a count).
STATS_UNITS = {"time": "s", "dt": "s", "iterations": "1", "open_close_passes": "1",
               "contacts": "1", "closed": "1", "sliding": "1", "retries": "1",
               "wall_time": "s", "solves": "1", "unknowns": "1", "pairs": "1",
               "penetration": "m", "spring_penetration": "m"}

#: Units of a sweep row's outcome columns (:func:`dda.studies.sweep.sweep`; "1": a count or a
#: ratio). The settings' columns are the study's own.
ROW_UNITS = {"error": "1", "cpu_time": "s", "wall_time": "s", "steps": "1", "iterations": "1",
             "open_close_passes": "1", "solves": "1", "dt_cuts": "1", "slip_reversals": "1",
             "contacts_max": "1",
             "dt": "s", "penalty": "N/m"}


def _require(name: str):
    """Import the optional module ``name``, or say how to install it."""
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        raise ImportError(f"{name} is needed for results as data; install it with {_EXTRA}"
                          ) from exc


def _units_of_stats() -> dict:
    from dda.profiling import SECTIONS

    return {**STATS_UNITS, **{f"{name}_time": "s" for name in SECTIONS}}


# ------------------------------------------------------------------------------ Result
def result_dataset(result):
    """The history ``result`` recorded, as an :class:`xarray.Dataset` (see the module).

    Parameters
    ----------
    result : dda.Result

    Returns
    -------
    xarray.Dataset
        Coordinates ``time`` (s), ``block`` (names) with ``block_id`` (int32 index),
        ``component`` (x, y), ``tensor_component`` (xx, yy, xy), ``pair`` ("a/b" labels,
        with ``block_a``, ``block_b``, ``block_a_id``, ``block_b_id``) and
        ``force_component`` (normal, shear). Its attributes: :func:`_run_attributes`.
    """
    xr = _require("xarray")
    names = list(result._names)
    coords = {
        "time": ("time", result.time.astype(np.float64),
                 {"units": "s", "long_name": "time of the recorded step"}),
        "block": ("block", np.array(names, dtype=str), {"long_name": "block name"}),
        "block_id": ("block", np.arange(len(names), dtype=np.int32),
                     {"long_name": "block index in the scene"}),
        "component": ("component", np.array(["x", "y"]), {"long_name": "vector component"}),
        "tensor_component": ("tensor_component", np.array(["xx", "yy", "xy"]),
                             {"long_name": "component of a symmetric 2D tensor"}),
    }
    variables = _block_variables(result)
    if result._centroid0 is not None:
        variables["initial_centroid"] = (("block", "component"), result._centroid0,
                                         {"units": "m", "long_name": "centroid at the start"})
    pair_coords, pair_variables = _pair_data(result, names)
    coords.update(pair_coords)
    variables.update(pair_variables)
    bolt_coords, bolt_variables = _bolt_data(result)
    coords.update(bolt_coords)
    variables.update(bolt_variables)
    return xr.Dataset(variables, coords=coords, attrs=_run_attributes(result))


def _bolt_data(result) -> tuple[dict, dict]:
    """The ``bolt`` coordinate and ``bolt_force``, ``bolt_broken`` (time x bolt); nothing in
    a scene without bolts."""
    rows = result._bolt_rows
    if not rows or not len(rows[0][0]):
        return {}, {}
    force = np.stack([r[0] for r in rows]).astype(np.float64)
    broken = np.stack([r[1] for r in rows]).astype(np.int8)  # (NetCDF3 has no booleans)
    coords = {"bolt": ("bolt", np.arange(force.shape[1], dtype=np.int32),
                       {"long_name": "bolt index (Scene.add_bolt's return)"})}
    variables = {
        "bolt_force": (("time", "bolt"), force,
                       {"units": "N/m", "long_name": "bolt axial force per m of thickness, "
                                                     "tension positive (0 once broken)"}),
        "bolt_broken": (("time", "bolt"), broken,
                        {"units": "1", "long_name": "1 once the bolt has broken"}),
    }
    return coords, variables


def _block_variables(result) -> dict:
    """The per-block variables of :data:`_BLOCK_VARIABLES`, as (dims, values, attrs)."""
    sources = {"disp": result._history(result._disp, (2,)),
               "rot": result._history(result._rot, ()),
               "vel": result._history(result._vel, (6,)),
               "stress": result._history(result._stress, (3,))}
    out = {}
    for name, dims, units, long_name, source, columns in _BLOCK_VARIABLES:
        values = sources[source] if columns is None else sources[source][:, :, columns]
        out[name] = (("time", "block", *dims), np.ascontiguousarray(values, dtype=np.float64),
                     {"units": units, "long_name": long_name})
    return out


def _pair_data(result, names) -> tuple[dict, dict]:
    """The ``pair`` coordinates and ``joint_force``; nothing when no pair carried a force
    (a zero-length dimension would be NetCDF3's unlimited one)."""
    keys, forces = result._joint_forces()
    if len(keys) == 0:
        return {}, {}
    n = len(names)
    a, b = (keys // n).astype(np.int32), (keys % n).astype(np.int32)
    name_a = np.array([names[i] for i in a], dtype=str)
    name_b = np.array([names[i] for i in b], dtype=str)
    coords = {
        "pair": ("pair", np.char.add(np.char.add(name_a, "/"), name_b),
                 {"long_name": "block pair, lower index first"}),
        "block_a": ("pair", name_a, {"long_name": "the pair's block of lower index"}),
        "block_b": ("pair", name_b, {"long_name": "the pair's block of higher index"}),
        "block_a_id": ("pair", a, {"long_name": "index of block_a"}),
        "block_b_id": ("pair", b, {"long_name": "index of block_b"}),
        "force_component": ("force_component", np.array(["normal", "shear"]),
                            {"long_name": "normal (compression positive) or shear"}),
    }
    variables = {"joint_force": (
        ("time", "pair", "force_component"), forces,
        {"units": "N/m", "long_name": "total force the pair carries, per m of thickness "
                                      "(normal: compression positive; shear: along the "
                                      "normal from a into b turned clockwise, on b)"})}
    return coords, variables


def _run_attributes(result) -> dict:
    """What the run was, as NetCDF attributes (numbers and strings only)."""
    from dda import __version__

    stats = result.stats
    attrs = {"title": "dda run", "dda_version": __version__,
             "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
             "gravity": float(result.scene.gravity), "steps": len(stats),
             "dt_cuts": len(stats.cuts), "slip_reversals": len(stats.reversals)}
    attrs.update({k: v for k, v in result._settings.items()
                  if isinstance(v, (int, float, str)) and v != ""})
    return attrs


# ------------------------------------------------------------------------------ StepStats
def stats_frame(stats):
    """The per-step statistics as a :class:`pandas.DataFrame` (see
    :meth:`dda.result.StepStats.to_pandas`)."""
    pd = _require("pandas")
    columns = {k: stats[k] for k in stats.FIELDS}
    frame = pd.DataFrame(columns, index=pd.RangeIndex(len(stats), name="step"))
    units = _units_of_stats()
    frame.attrs["units"] = {k: units[k] for k in stats.FIELDS}
    frame.attrs["timing_every"] = stats.timing_every
    return frame


# ------------------------------------------------------------------------------ sweep rows
def _columns(rows: Sequence[dict]) -> list:
    """Every key of the rows, in the order they first appear."""
    return list(dict.fromkeys(k for r in rows for k in r))


def rows_frame(rows: Sequence[dict]):
    """Sweep rows (or any list of dicts) as a :class:`pandas.DataFrame`, one row each.

    The columns are the rows' keys in the order they first appear (a key a row lacks is
    missing there: NaN); ``frame.attrs["units"]`` gives the units of the columns
    :data:`ROW_UNITS` knows.

    Examples
    --------
    >>> frame = rows_frame([{"solver": "legacy", "error": 0.02}, {"solver": "newton"}])
    >>> list(frame.columns), frame["error"].isna().tolist()
    (['solver', 'error'], [False, True])
    """
    pd = _require("pandas")
    columns = _columns(rows)
    frame = pd.DataFrame.from_records(list(rows), columns=columns)
    frame.attrs["units"] = {k: ROW_UNITS[k] for k in columns if k in ROW_UNITS}
    return frame


def _cell(value, digits: int, width: int) -> str:
    """One table cell: floats to ``digits`` significant digits, text cut to ``width``."""
    if isinstance(value, (bool, np.bool_)):
        return str(value)
    if isinstance(value, (float, np.floating)):
        return "nan" if math.isnan(value) else f"{value:.{digits}g}"
    text = str(value)
    return text if len(text) <= width else text[:width - 3] + "..."


def format_rows(rows: Sequence[dict], columns: Sequence[str] | None = None,
                digits: int = 4, width: int = 40) -> str:
    """A plain text table of rows, numbers rounded to ``digits`` significant digits.

    Parameters
    ----------
    rows : sequence of dict
    columns : sequence of str, optional
        Default: every key, in the order they first appear.
    digits : int
        Significant digits of a float.
    width : int
        Longest cell; longer text (a failed run's status) is cut.

    Returns
    -------
    str
        A header line and a line a row; numbers right-aligned, text left-aligned.
    """
    columns = _columns(rows) if columns is None else list(columns)
    cells = [[_cell(r.get(c, ""), digits, width) for c in columns] for r in rows]
    numeric = [all(isinstance(r.get(c), (int, float, np.number)) for r in rows if c in r)
               for c in columns]
    widths = [max([len(c)] + [len(line[j]) for line in cells]) for j, c in enumerate(columns)]

    def line(values):
        return "  ".join(v.rjust(w) if num else v.ljust(w)
                         for v, w, num in zip(values, widths, numeric, strict=True)).rstrip()

    return "\n".join([line(columns)] + [line(v) for v in cells])
