r"""Recorded accelerograms: PEER NGA ``.AT2`` and K-NET / KiK-net ASCII files, and their
baseline correction.

:func:`read_at2` and :func:`read_knet` (or :func:`read_record`, which tells the format from
the file's suffix) return a :class:`Record`: sample times from 0 (s) and one component of
acceleration (m/s^2), ready for :meth:`dda.Scene.shake`::

    rec = read_record("RSN6_IMPVALL.I_I-ELC180.AT2")
    scene.shake(base, acceleration=rec.acceleration, times=rec.times)       # along x
    scene.shake(base, acceleration=rec.along((0.6, 0.8)), times=rec.times)  # along a direction

The scene format reads the same files (``[[shake]] file = "x.AT2"``, :mod:`dda.io.scene_file`).
A record is taken as piecewise linear between its samples, as :class:`dda.effects.
AccelerationHistory` integrates it (exactly):

.. math::

    v_{i+1} = v_i + \tfrac{h}{2}(a_i + a_{i+1}), \qquad
    u_{i+1} = u_i + h v_i + h^2\bigl(\tfrac{a_i}{3} + \tfrac{a_{i+1}}{6}\bigr),

from rest (:math:`u_0 = v_0 = 0`). A record whose velocity does not come back to zero moves
the shaken block on for ever: :meth:`Record.end_motion` tells, and :func:`baseline_correct`
(``baseline=`` of the readers) removes a mean or a polynomial trend.
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from dda.effects import sampling_interval

__all__ = ["BASELINES", "G", "Record", "RecordError", "baseline_correct", "guess_format",
           "integrate", "on_common_times", "read_at2", "read_knet", "read_record",
           "write_at2"]

#: standard gravity (m/s^2): PEER's records are in units of g
G = 9.80665

#: the baseline corrections of :func:`baseline_correct`
BASELINES = ("none", "mean", "linear", "quadratic")

#: a file's suffix (upper case) -> its format
SUFFIXES = {".AT2": "at2", ".CSV": "csv",
            **{f".{c}{k}": "knet" for c in ("EW", "NS", "UD") for k in ("", "1", "2")}}

#: the largest record file read (bytes); a long record at 200 Hz is a few MB
MAX_FILE_BYTES = 256 * 2**20

# a Fortran real: 1.5, -.1234E-02, 12, 1.0D+01; "stuck" values (1.2E-02-3.4E-02) split apart
_REAL = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[Ee][-+]?\d+)?")
_EXP_D = re.compile(r"(?<=[\d.])[Dd](?=[-+]?\d)")  # Fortran's double exponent 1.0D+01


class RecordError(ValueError):
    """A record file that is not what it claims: ``file, line N: what is wrong``."""


def _error(path, line, message) -> RecordError:
    where = f"{Path(path).name}, line {line}" if line else f"{Path(path).name}"
    return RecordError(f"{where}: {message}")


@dataclass(frozen=True, eq=False)
class Record:
    """One component of a recorded accelerogram.

    Attributes
    ----------
    times : (n,) ndarray
        Sample times (s), ``dt`` apart from 0.
    acceleration : (n,) ndarray
        Acceleration at the samples, in ``units`` (m/s^2).
    dt : float
        Sampling interval (s).
    format : str
        ``"at2"`` or ``"knet"``.
    path : str
        The file read.
    units : str
        ``"m/s^2"``.
    station, direction : str
        The station (K-NET's station code; PEER's second header line) and the component as the
        file names it (K-NET ``"N-S"``, ``"E-W"``, ``"U-D"``, KiK-net ``"1"`` to ``"6"``
        or as written; PEER: the last two items of its second line, e.g. ``"El Centro Array
        #9"`` and ``"180"``).
    scale_factor : float
        What one unit of the file's numbers is in m/s^2: ``g`` for PEER, ``numerator /
        denominator / 100`` for K-NET (its ``3920(gal)/6182761`` per count).
    baseline : str
        The correction applied (:func:`baseline_correct`).
    header : dict
        The header's fields as read (strings), by name.
    """

    times: np.ndarray
    acceleration: np.ndarray
    dt: float
    format: str
    path: str
    units: str = "m/s^2"
    station: str = ""
    direction: str = ""
    scale_factor: float = 1.0
    baseline: str = "none"
    header: dict = field(default_factory=dict)

    @property
    def duration(self) -> float:
        """Time of the last sample (s)."""
        return float(self.times[-1])

    @property
    def peak(self) -> float:
        """Peak absolute acceleration (m/s^2)."""
        return float(np.abs(self.acceleration).max())

    def end_motion(self) -> tuple[float, float]:
        """Velocity (m/s) and displacement (m) at the record's end of a block that follows it
        from rest (:func:`integrate`): what a baseline correction would take away."""
        v, u = integrate(self.times, self.acceleration)
        return float(v[-1]), float(u[-1])

    def along(self, direction=(1.0, 0.0)) -> np.ndarray:
        """(n, 2) acceleration along ``direction`` (not normalized: ``(0, 2)`` doubles it)."""
        d = np.asarray(direction, dtype=float)
        if d.shape != (2,) or not np.all(np.isfinite(d)):
            raise ValueError(f"direction must be two numbers (x, y), got {direction!r}")
        return self.acceleration[:, None] * d[None, :]

    def corrected(self, baseline: str) -> Record:
        """This record after :func:`baseline_correct` (``"none"``: itself)."""
        if baseline == "none":
            return self
        return replace(self, acceleration=baseline_correct(self.times, self.acceleration,
                                                            baseline),
                       baseline=baseline if self.baseline == "none"
                       else f"{self.baseline}, {baseline}")


# ---------------------------------------------------------------------- integrals, baseline
def integrate(times, acceleration) -> tuple[np.ndarray, np.ndarray]:
    """Velocity and displacement at the samples of a piecewise linear acceleration, from rest
    (module docstring; the integrals :class:`dda.effects.AccelerationHistory` uses).

    Parameters
    ----------
    times : (n,) array-like
    acceleration : (n,) or (n, k) array-like

    Returns
    -------
    v, u : ndarrays shaped as ``acceleration``
    """
    t = np.asarray(times, dtype=float)
    a = np.asarray(acceleration, dtype=float)
    h = np.diff(t).reshape(-1, *([1] * (a.ndim - 1)))
    v = np.concatenate([np.zeros_like(a[:1]), np.cumsum(0.5 * h * (a[:-1] + a[1:]), axis=0)])
    du = v[:-1] * h + h * h * (a[:-1] / 3.0 + a[1:] / 6.0)
    u = np.concatenate([np.zeros_like(a[:1]), np.cumsum(du, axis=0)])
    return v, u


def baseline_correct(times, acceleration, method: str = "quadratic") -> np.ndarray:
    r"""The acceleration with a baseline taken away, so that a block following it from rest
    comes to rest at its end instead of drifting on.

    With :math:`v(t)` the record's velocity from rest (:func:`integrate`), :math:`T` its last
    time and :math:`s = t/T`, a polynomial :math:`p` through the origin and through
    :math:`v(T)` is fitted to the velocity at the samples by least squares, and its
    derivative taken away from the acceleration:

    .. math::

        p(t) = v(T)\,s + \sum_{k=2}^{K} c_k (s^k - s), \qquad
        \min_c \sum_i igl(v(t_i) - p(t_i)igr)^2, \qquad a_c = a - p'(t).

    - ``"none"``: the record as it is.
    - ``"mean"`` (:math:`K = 1`): the time average :math:`v(T)/T` (the trapezoid rule's).
    - ``"linear"`` (:math:`K = 2`): a linear trend :math:`c_0 + c_1 t`, as an instrument's
      offset that drifts.
    - ``"quadratic"`` (:math:`K = 3`): a quadratic trend :math:`c_0 + c_1 t + c_2 t^2`.

    The corrected record ends at rest (its velocity at :math:`T` is zero to round-off); where
    the block ends is not fixed (it is what the fit leaves). The correction is linear and
    takes away exactly the trends it fits: a record plus ``c + d t`` comes out of ``"linear"``
    as the record alone would, to round-off. A motion that is already clean (its velocity
    wavers about zero and ends near it) is changed little.

    Parameters
    ----------
    times : (n,) array-like
        Increasing sample times (s) from 0.
    acceleration : (n,) or (n, k) array-like
        The record (each column corrected on its own).
    method : {"none", "mean", "linear", "quadratic"}

    Returns
    -------
    ndarray shaped as ``acceleration``

    Examples
    --------
    >>> t = np.linspace(0.0, 10.0, 1001)
    >>> a = np.cos(2 * np.pi * t) + 0.05 + 0.01 * t      # a wave on an offset and a trend
    >>> round(float(integrate(t, a)[0][-1]), 9)            # it would move on at 1 m/s
    1.0
    >>> v, u = integrate(t, baseline_correct(t, a, "linear"))
    >>> bool(abs(v[-1]) < 1e-12)
    True
    """
    if method not in BASELINES:
        raise ValueError(f"baseline must be {', '.join(map(repr, BASELINES))}, got {method!r}")
    t = np.asarray(times, dtype=float)
    a = np.asarray(acceleration, dtype=float)
    if method == "none":
        return a.copy()
    if t.ndim != 1 or len(t) < 2 or a.shape[0] != len(t) or np.any(np.diff(t) <= 0):
        raise ValueError("baseline_correct: times must increase and match the acceleration's "
                         f"rows, got {t.shape} and {a.shape}")
    v, _ = integrate(t, a)
    v = v.reshape(len(t), -1)
    s = ((t - t[0]) / (t[-1] - t[0]))[:, None]  # scaled time: a well-conditioned fit
    q = s ** np.arange(BASELINES.index(method))[None, :]  # the trends: 1, s, s^2 (n, K)
    vq, _ = integrate(t, q)  # their velocities, integrated as the record is: exact
    # c = v(T) e_0 / T + N z: every c with vq(T) c = v(T); z by least squares
    end = vq[-1]
    null = np.vstack([-end[None, 1:] / end[0], np.eye(len(end) - 1)])  # (K, K - 1)
    c = np.zeros((len(end), v.shape[1]))
    c[0] = v[-1] / end[0]
    if null.shape[1]:
        z, *_ = np.linalg.lstsq(vq @ null, v - vq @ c, rcond=None)
        c += null @ z
    return a - (q @ c).reshape(a.shape)


def on_common_times(times_a, values_a, times_b, values_b):
    """Two records sampled at different times, both at the union of their sample times.

    Each is piecewise linear, so at the union of their samples both are exact; the result
    covers the time both cover (it ends with the shorter record). A time of ``times_b``
    within ``1e-9`` of the finer sampling interval (a record's length over its samples) of
    one of ``times_a`` is taken as that time, unless it is one of a jump's two samples in
    ``times_b``: 0.005 k and k / 100 differ in the last bit at every other shared instant, and the
    union's spacings of 5.6e-17 s were no sampling (the automatic dt measured the shaking at
    them).

    Parameters
    ----------
    times_a, times_b : (n,) and (m,) arrays
    values_a, values_b : (n, ...) and (m, ...) arrays

    Returns
    -------
    times (k,), values_a (k, ...), values_b (k, ...)
    """
    ta, tb = np.asarray(times_a, dtype=float), np.asarray(times_b, dtype=float)
    va, vb = np.asarray(values_a, dtype=float), np.asarray(values_b, dtype=float)
    if len(ta) == len(tb) and np.array_equal(ta, tb):
        return ta, va.copy(), vb.copy()
    end = min(ta[-1], tb[-1])
    ta_in, tb_in = ta[ta <= end], tb[tb <= end]
    spacing = min(sampling_interval(ts) for ts in (ta, tb))
    if np.isfinite(spacing) and len(ta_in) and len(tb_in):
        tol = 1e-9 * spacing
        at = np.searchsorted(ta_in, tb_in)
        left = ta_in[np.clip(at - 1, 0, len(ta_in) - 1)]
        right = ta_in[np.clip(at, 0, len(ta_in) - 1)]
        near = np.minimum(np.abs(tb_in - left), np.abs(tb_in - right)) <= tol
        # ... but the two samples of a jump of b's own stay (b's value jumps there)
        gaps = np.diff(tb_in)
        jump = np.zeros(len(tb_in), dtype=bool)
        jump[1:] |= gaps <= tol
        jump[:-1] |= gaps <= tol
        tb_in = tb_in[~near | jump]
    t = np.union1d(ta_in, tb_in)

    def at(ts, v):
        flat = v.reshape(len(ts), -1)
        out = np.stack([np.interp(t, ts, flat[:, k]) for k in range(flat.shape[1])], axis=1)
        return out.reshape(len(t), *v.shape[1:])

    return t, at(ta, va), at(tb, vb)


# ---------------------------------------------------------------------- reading
def guess_format(path) -> str | None:
    """``"at2"``, ``"knet"`` or ``"csv"`` from the file's suffix (case ignored): ``.AT2``;
    K-NET ``.EW .NS .UD``, KiK-net ``.EW1 .NS1 .UD1 .EW2 .NS2 .UD2``; ``.csv``. None when the
    suffix says nothing."""
    return SUFFIXES.get(Path(path).suffix.upper())


def read_record(path, format: str | None = None, baseline: str = "none") -> Record:
    """A PEER NGA or K-NET / KiK-net record, its format told by its suffix
    (:func:`guess_format`) unless given: :func:`read_at2` or :func:`read_knet`."""
    fmt = format or guess_format(path)
    if fmt not in ("at2", "knet"):
        raise RecordError(
            f"{Path(path).name}: cannot tell the record's format from its suffix; give format "
            '"at2" (PEER NGA) or "knet" (K-NET / KiK-net ASCII)' if fmt is None
            else f"{Path(path).name}: format must be 'at2' or 'knet', got {fmt!r}")
    return (read_at2 if fmt == "at2" else read_knet)(path, baseline=baseline)


def _lines(path) -> list[str]:
    p = Path(path)
    if not p.is_file():
        raise RecordError(f"no record file {p}")
    if p.stat().st_size > MAX_FILE_BYTES:
        raise RecordError(f"{p.name}: larger than {MAX_FILE_BYTES // 2**20} MB, not a record")
    return p.read_text(encoding="latin-1").splitlines()


def _numbers(path, lines, first: int) -> np.ndarray:
    """All numbers of ``lines`` (the file's line ``first`` on), Fortran style; an error names
    the first line that holds anything else."""
    text = _EXP_D.sub("E", " ".join(lines))
    try:
        return np.array(text.split(), dtype=float)
    except ValueError:
        pass
    out = []
    for k, line in enumerate(lines):
        line = _EXP_D.sub("E", line)
        found = _REAL.findall(line)
        if _REAL.sub(" ", line).strip(" \t,"):
            raise _error(path, first + k, f"not a number in {line.strip()[:60]!r}")
        out.extend(found)
    return np.array(out, dtype=float)


_NPTS_WEST2 = re.compile(r"NPTS\s*=\s*(\d+)\s*,?\s*DT\s*=\s*([-+0-9.Ee]+)", re.I)
_NPTS_OLD = re.compile(r"^\s*(\d+)\s+([-+0-9.Ee]+)\s+NPTS\s*,\s*DT\b", re.I)


def read_at2(path, baseline: str = "none") -> Record:
    """A PEER NGA ``.AT2`` acceleration record (values in g), in m/s^2.

    The file has a header of four lines, then the values, several on a line::

        PEER NGA STRONG MOTION DATABASE RECORD
        Imperial Valley-02, 5/19/1940, El Centro Array #9, 180
        ACCELERATION TIME SERIES IN UNITS OF G
        NPTS=  4000, DT=   .0100 SEC                    (NGA-West2; older: 4000 .0100 NPTS, DT)
          .2669800E-02  .2560000E-02  ...

    Acceleration = value x g (g = 9.80665 m/s^2); times ``k dt`` from 0. PEER's records are
    processed (filtered and baseline corrected) already, hence ``baseline="none"`` by default.

    Raises
    ------
    RecordError
        When the third line is not an acceleration in g, the fourth gives no NPTS and DT (or
        a DT that is not a positive number), a value is not a number, or the number of values
        is not NPTS; the message names the file and the line.

    Examples
    --------
    >>> import tempfile, dda
    >>> folder = Path(tempfile.mkdtemp())
    >>> write_at2(folder / "pulse.AT2", [0.0, 0.1, 0.0, -0.1, 0.0], dt=0.01)
    >>> rec = read_at2(folder / "pulse.AT2")
    >>> rec.dt, float(rec.times[-1]), float(rec.acceleration[1])   # 0.1 g in m/s^2
    (0.01, 0.04, 0.980665)
    >>> scene = dda.Scene(gravity=9.81)
    >>> rock = dda.materials.LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    >>> base = scene.add_block([(0, 0), (1, 0), (1, 0.2), (0, 0.2)], rock, fixed=True)
    >>> scene.shake(base, acceleration=rec.acceleration, times=rec.times)
    """
    lines = _lines(path)
    if len(lines) < 5:
        raise _error(path, None, f"a PEER .AT2 file has 4 header lines and then values; this "
                                 f"one has {len(lines)} lines")
    units = lines[2]
    if not re.search(r"\bACCELERATION\b", units, re.I):
        raise _error(path, 3, f"expected 'ACCELERATION TIME SERIES IN UNITS OF G', got "
                              f"{units.strip()[:60]!r} (is it a velocity .VT2 or displacement "
                              ".DT2 file?)")
    if not re.search(r"\bUNITS\s+OF\s+G\b|\(G'?S?\)|\bIN\s+G\b", units, re.I):
        raise _error(path, 3, f"expected acceleration in units of G, got {units.strip()[:60]!r}")
    m = _NPTS_WEST2.search(lines[3]) or _NPTS_OLD.search(lines[3])
    if m is None:
        raise _error(path, 4, "expected 'NPTS= 5000, DT= .0050 SEC' (or the older '5000 .0050 "
                              f"NPTS, DT'), got {lines[3].strip()[:60]!r}")
    npts = int(m.group(1))
    try:
        dt = float(m.group(2))
    except ValueError:
        dt = math.nan
    if not (math.isfinite(dt) and dt > 0):
        raise _error(path, 4, f"DT must be a positive number of seconds, got {m.group(2)!r}")
    values = _numbers(path, lines[4:], 5)
    if len(values) != npts:
        raise _error(path, 4, f"NPTS = {npts} but the file holds {len(values)} values (lines "
                              f"5 to {len(lines)})")
    if npts < 2:
        raise _error(path, 4, f"NPTS = {npts}: a record needs 2 samples or more")
    if not np.all(np.isfinite(values)):
        raise _error(path, None, "a value is not finite")
    parts = [p.strip() for p in lines[1].split(",")]
    rec = Record(times=np.arange(npts) * dt, acceleration=values * G, dt=dt, format="at2",
                 path=str(path), station=parts[-2] if len(parts) > 1 else "",
                 direction=parts[-1] if len(parts) > 1 else "", scale_factor=G,
                 header={"title": lines[0].strip(), "event": lines[1].strip(),
                         "units": units.strip(), "npts": str(npts), "dt": m.group(2)})
    return rec.corrected(baseline)


_KNET_LABELS = ("Origin Time", "Lat.", "Long.", "Depth. (km)", "Mag.", "Station Code",
                "Station Lat.", "Station Long.", "Station Height(m)", "Record Time",
                "Sampling Freq(Hz)", "Duration Time(s)", "Dir.", "Scale Factor",
                "Max. Acc. (gal)", "Last Correction", "Memo.")


def read_knet(path, baseline: str = "none") -> Record:
    """A K-NET or KiK-net ASCII record (one component), in m/s^2.

    The file has 17 header lines, a label in the first 18 columns and its value after it::

        Origin Time       2011/03/11 14:46:00
        ...
        Station Code      MYG004
        ...
        Sampling Freq(Hz) 100Hz
        Duration Time(s)  300
        Dir.              N-S
        Scale Factor      3920(gal)/6182761
        Max. Acc. (gal)   2700.044
        Last Correction   2011/03/11 14:46:29
        Memo.

    then whole counts, 8 on a line. Acceleration (gal) = counts x 3920 / 6182761 (the scale
    factor), less the record's mean, as NIED advises (the counts carry the instrument's
    offset); m/s^2 = gal / 100. Times ``k / frequency`` from 0 (the header's record time is
    the first sample's). K-NET records are not otherwise corrected: a block that follows one
    may drift (:meth:`Record.end_motion`); ``baseline="linear"`` or ``"quadratic"`` takes a
    trend away.

    Raises
    ------
    RecordError
        When a header line is not the label it should be, the sampling frequency is not like
        ``100Hz``, the scale factor not like ``3920(gal)/6182761`` (positive numbers, gal),
        a value is not a number, or there are fewer than 2; the message names the file and
        the line.
    """
    lines = _lines(path)
    if len(lines) < 18:
        raise _error(path, None, f"a K-NET file has 17 header lines and then values; this one "
                                 f"has {len(lines)} lines")
    header = {}
    for k, label in enumerate(_KNET_LABELS):
        if not lines[k].startswith(label):
            raise _error(path, k + 1, f"expected the K-NET header line {label!r}, got "
                                      f"{lines[k].strip()[:60]!r}")
        header[label] = lines[k][len(label):].strip()
    m = re.fullmatch(r"(\d+(?:\.\d*)?)\s*Hz", header["Sampling Freq(Hz)"], re.I)
    freq = float(m.group(1)) if m else 0.0
    if not freq > 0:
        raise _error(path, 11, "Sampling Freq(Hz) must read like '100Hz', got "
                               f"{header['Sampling Freq(Hz)']!r}")
    m = re.fullmatch(r"(\d+(?:\.\d*)?(?:[Ee][-+]?\d+)?)\s*\(gal\)\s*/\s*"
                     r"(\d+(?:\.\d*)?(?:[Ee][-+]?\d+)?)", header["Scale Factor"])
    num, den = (float(m.group(1)), float(m.group(2))) if m else (0.0, 0.0)
    if not (num > 0 and den > 0 and math.isfinite(num) and math.isfinite(den)):
        raise _error(path, 14, "Scale Factor must read like '3920(gal)/6182761' (positive "
                               f"numbers, in gal), got {header['Scale Factor']!r}")
    counts = _numbers(path, lines[17:], 18)
    if len(counts) < 2:
        raise _error(path, 18, f"a record needs 2 samples or more, this one has {len(counts)}")
    if not np.all(np.isfinite(counts)):
        raise _error(path, None, "a value is not finite")
    gal = counts * (num / den)
    gal -= gal.mean()
    _check_peak(path, header["Max. Acc. (gal)"], float(np.abs(gal).max()))
    rec = Record(times=np.arange(len(counts)) / freq, acceleration=gal / 100.0, dt=1.0 / freq,
                 format="knet", path=str(path), station=header["Station Code"],
                 direction=header["Dir."], scale_factor=num / den / 100.0, header=header)
    return rec.corrected(baseline)


def _check_peak(path, stated: str, peak: float) -> None:
    """A PlausibilityWarning when a K-NET header's ``Max. Acc. (gal)`` (``stated``) is not
    the peak of its counts times its scale factor less their mean (``peak``, gal) to 1%: a
    scale factor pasted from another file (KiK-net's 7845(gal)/8223790 on K-NET counts)
    would scale the whole record wrongly, and nothing else shows it. Nothing when the header
    gives no number."""
    try:
        header = float(stated)
    except ValueError:
        return
    if not (math.isfinite(header) and header > 0.0):
        return
    if abs(peak - header) > 0.01 * header + 0.001:
        from dda.plausibility import PlausibilityWarning  # noqa: PLC0415

        warnings.warn(f"{Path(path).name}, line 15: Max. Acc. {header:g} gal, but the counts "
                      f"times the Scale Factor, less their mean, peak at {peak:.4g} gal "
                      f"({peak / header:.3g} times it): is the Scale Factor the file's own?",
                      PlausibilityWarning, stacklevel=4)


# ---------------------------------------------------------------------- writing
def write_at2(path, acceleration_g, dt: float, title: str = "PEER NGA STRONG MOTION DATABASE "
              "RECORD (written by dda)", event: str = "synthetic, 0/0/0, dda, 000",
              style: str = "west2") -> None:
    """Write an acceleration (in g) as a PEER ``.AT2`` file, five values a line (E15.7).

    ``style="west2"`` writes ``NPTS=  n, DT=   dt SEC``, ``"old"`` the older ``n dt NPTS, DT``.
    For tests and examples: a record of one's own, in the format users have.
    """
    a = np.asarray(acceleration_g, dtype=float).reshape(-1)
    if style == "west2":
        line4 = f"NPTS= {len(a):6d}, DT= {dt:9.7g} SEC"
    elif style == "old":
        line4 = f"{len(a):6d} {dt:9.7g}    NPTS, DT"
    else:
        raise ValueError(f"style must be 'west2' or 'old', got {style!r}")
    rows = [" ".join(f"{v:15.7E}" for v in a[k:k + 5]) for k in range(0, len(a), 5)]
    Path(path).write_text("\n".join([title, event, "ACCELERATION TIME SERIES IN UNITS OF G",
                                     line4, *rows]) + "\n")
