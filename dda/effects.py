"""Time histories of the effects a scene can hold: base shaking, prescribed motion, loads.

Each history is evaluated once per step (a handful of user callables per step, never a loop
over blocks or contacts). :class:`TimeTable` is a ready-made history from samples.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right

import numpy as np

from dda.kernels.shaking import gauss_legendre_steps

# 5-point Gauss-Legendre rule on [0, 1]: exact for polynomials up to degree 9
_GL_X, _GL_W = np.polynomial.legendre.leggauss(5)
_GL_X = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W


def _as_xy(value, what: str) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape != (2,):
        raise ValueError(f"{what} must return two numbers (x, y), got {value!r}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what} returned a value that is not finite: {value!r}")
    return a


def _breakpoints(f, name: str) -> np.ndarray:
    """The sorted times of a callable's ``breakpoints`` attribute (none: an empty array)."""
    given = getattr(f, "breakpoints", None)
    if given is None:
        return np.zeros(0)
    try:
        b = np.asarray(given, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: acceleration.breakpoints must be a list of times") from None
    if not np.all(np.isfinite(b)):
        raise ValueError(f"{name}: acceleration.breakpoints contains NaN or inf")
    return np.unique(b[b > 0.0])


class TimeTable:
    """A history ``t -> (x, y)`` from samples: linear between them, held outside them.

    A module-level class rather than a lambda, so that a run using it can be checkpointed.
    Either direction may be left out (None): for ``Scene.prescribe_motion`` that direction is
    free; a point load needs both.

    Parameters
    ----------
    times : (n,) array-like
        Sample times (s), strictly increasing.
    x, y : (n,) array-like, optional
        Values at the samples.

    Examples
    --------
    >>> ramp = TimeTable([0.0, 1.0, 2.0], x=[0.0, 1e-3, 1e-3])  # ramp, then hold; y free
    >>> ramp(0.5), ramp(5.0)
    ((0.0005, None), (0.001, None))
    """

    def __init__(self, times, x=None, y=None, name="time table"):
        self.name = name
        try:
            t = np.asarray(times, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{name}: times must be a list of numbers") from None
        if t.ndim != 1 or len(t) < 1:
            raise ValueError(f"{name}: times must be a 1-D list of at least one time")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise ValueError(f"{name}: times must be finite and increase strictly")
        if x is None and y is None:
            raise ValueError(f"{name}: give the values of x, of y or of both")
        cols = []
        for label, col in (("x", x), ("y", y)):
            if col is None:
                cols.append(None)
                continue
            try:
                c = np.asarray(col, dtype=float)
            except (TypeError, ValueError):
                raise ValueError(f"{name}: {label} must be a list of numbers") from None
            if c.ndim != 1:
                raise ValueError(f"{name}: {label} must be a list of numbers, one per time")
            if c.shape != t.shape:
                raise ValueError(f"{name}: {label} has {c.size} values for {len(t)} times")
            if not np.all(np.isfinite(c)):
                raise ValueError(f"{name}: {label} contains NaN or inf")
            cols.append(c)
        self.times = t
        self.x, self.y = cols

    def __call__(self, t: float):
        return tuple(None if c is None else float(np.interp(t, self.times, c))
                     for c in (self.x, self.y))


def sampling_interval(times) -> float:
    """A record's sampling interval: its length over its samples less one (a jump written
    as two samples a hair apart does not make it a hair); inf for fewer than 2 samples."""
    times = np.asarray(times, dtype=float)
    return float((times[-1] - times[0]) / (len(times) - 1)) if len(times) > 1 else np.inf


class AccelerationHistory:
    """A base acceleration a(t) and its exact integrals v(t) and u(t), starting from rest.

    Either a callable ``t -> (ax, ay)`` (integrated step by step with 5-point Gauss-Legendre,
    exact for polynomials of degree 9 over a step) or a sampled record ``times, values``
    taken as piecewise linear in time and integrated exactly. A record may start after t = 0
    by at most its first sample spacing (a record whose first sample is at its time step):
    it ramps linearly from zero acceleration at t = 0. One that starts later is refused: a
    record in absolute times would otherwise ramp over its whole offset.

    A callable that is smooth only between known times (a wave switched on at ``start``, an
    amplitude that changes at some time) may list them in an attribute ``breakpoints`` (a
    sequence of times): a step across one is integrated piece by piece, split there, so the
    kink or jump does not spoil the rule's accuracy
    (:class:`dda.io.scene_file.SineAcceleration` does this).
    """

    def __init__(self, acceleration, times=None, name="shake"):
        self.name = name
        self._callable = None
        if times is None and callable(acceleration):
            self._callable = acceleration
            _as_xy(acceleration(0.0), f"{name}: acceleration(t)")
            self._breaks = _breakpoints(acceleration, name)
            self._t = 0.0
            self._v = np.zeros(2)
            self._u = np.zeros(2)
            return
        if times is None:
            try:
                times, acceleration = acceleration
            except (TypeError, ValueError):
                raise ValueError(
                    f"{name}: acceleration must be a callable t -> (ax, ay) or a pair "
                    "(times, values)"
                ) from None
        t = np.asarray(times, dtype=float)
        a = np.asarray(acceleration, dtype=float)
        if a.ndim == 1:
            a = np.stack([a, np.zeros_like(a)], axis=1)
        if t.ndim != 1 or len(t) < 2 or a.shape != (len(t), 2):
            raise ValueError(
                f"{name}: times must be a 1-D array of at least 2 samples and the values "
                f"(n,) or (n, 2) with the same n; got times {t.shape} and values {a.shape}"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(a))):
            raise ValueError(f"{name}: the acceleration record contains NaN or inf")
        if np.any(np.diff(t) <= 0):
            raise ValueError(f"{name}: the record's times must increase strictly")
        if t[0] < 0.0:
            raise ValueError(f"{name}: the record must start at t = 0, got {t[0]:g}")
        if t[0] > 0.0 and t[0] > (t[1] - t[0]) * (1.0 + 1e-9):
            raise ValueError(
                f"{name}: the record starts at t = {t[0]:g} s, later than its first sample "
                f"spacing ({t[1] - t[0]:g} s) after t = 0; shift its times to start at 0 (a "
                "run starts at t = 0), or add a sample at t = 0")
        if t[0] > 0.0:
            t = np.concatenate([[0.0], t])
            a = np.concatenate([np.zeros((1, 2)), a])
        self._times = t
        self._acc = a
        h = np.diff(t)[:, None]
        dv = 0.5 * h * (a[:-1] + a[1:])
        self._vel = np.concatenate([np.zeros((1, 2)), np.cumsum(dv, axis=0)])
        du = self._vel[:-1] * h + h * h * (a[:-1] / 3.0 + a[1:] / 6.0)
        self._disp = np.concatenate([np.zeros((1, 2)), np.cumsum(du, axis=0)])

    @property
    def function(self):
        """The callable ``t -> (ax, ay)`` of the history, or None for a record."""
        return self._callable

    @property
    def record(self) -> tuple[np.ndarray, np.ndarray] | None:
        """``(times, values)`` of a recorded history ((n,), (n, 2); starting at t = 0), or
        None for a callable."""
        return None if self._callable is not None else (self._times, self._acc)

    @property
    def end_time(self) -> float:
        """Last time the history covers (inf for a callable)."""
        return np.inf if self._callable is not None else float(self._times[-1])

    @property
    def min_spacing(self) -> float:
        """The finest spacing of a record's samples (s); inf for a callable."""
        return np.inf if self._callable is not None else float(np.diff(self._times).min())

    @property
    def typical_spacing(self) -> float:
        """A record's sampling interval, its length over its samples less one (s); inf for a
        callable. Unlike :attr:`min_spacing` it does not see a jump written as two samples
        a hair apart (nor does it, unlike their median, where every sample is such a pair:
        a square wave's)."""
        if self._callable is not None:
            return np.inf
        return sampling_interval(self._times)

    def sample(self, t: np.ndarray) -> np.ndarray:
        """(n, 2) acceleration at the times ``t`` (a record: linear between its samples)."""
        t = np.asarray(t, dtype=float)
        if self._callable is not None:
            return self._called(t).reshape(-1, 2)
        return np.stack([np.interp(t, self._times, self._acc[:, k]) for k in (0, 1)], axis=1)

    def _called(self, t) -> np.ndarray:
        """(len(t), 2) the callable's accelerations at the times ``t``, checked as a whole and
        one by one (for the message) only when that fails."""
        values = [self._callable(ti) for ti in t.tolist()]  # Python floats: faster to call
        try:
            a = np.array(values, dtype=float)
        except (TypeError, ValueError):
            a = None
        if a is None or a.shape != (len(t), 2) or not np.isfinite(a).all():
            a = np.array([_as_xy(v, f"{self.name}: acceleration(t)") for v in values])
        return a

    def check_covers(self, t_end: float):
        """Raise ValueError when a recorded history ends before ``t_end``."""
        if t_end > self.end_time * (1 + 1e-12):
            raise ValueError(
                f"{self.name}: the acceleration record ends at t = {self.end_time:g} s but the "
                f"run goes to t = {t_end:g} s; extend the record or shorten the run"
            )

    def initial(self):
        """The integrator's state at t = 0: ``(t, v, u)`` for a callable, None for a record
        (whose integrals are exact at any t)."""
        return None if self._callable is None else (0.0, np.zeros(2), np.zeros(2))

    def advance(self, start, t: float):
        """Displacement and velocity at ``t``, and the integrator's state there (pure).

        ``start`` is the integrator's state at an earlier time (:meth:`initial`, or the last
        one returned); nothing of the history changes, so a step that is refused simply
        keeps its ``start``. A callable is integrated from ``start`` to ``t`` exactly::

            u(t) = u0 + v0 h + int_0^h (h - s) a(t0 + s) ds,   v(t) = v0 + int_0^h a(t0 + s) ds

        (:func:`dda.kernels.shaking.gauss_legendre_steps`, the kernel of
        :meth:`advance_many` too).
        """
        if self._callable is None:
            u, v = self._sampled(np.array([t], dtype=float))
            return u[0], v[0], None
        t0, v0, u0 = start
        if t < t0 - 1e-15:
            t0, v0, u0 = 0.0, np.zeros(2), np.zeros(2)
        if t - t0 <= 0.0:
            return u0.copy(), v0.copy(), (t0, v0, u0)
        u, v = self._integrated(t0, v0, u0, np.array([t], dtype=float))
        return u[0].copy(), v[0].copy(), (t, v[0], u[0])

    def advance_many(self, start, times: np.ndarray):
        """:meth:`advance` over a run of steps ending at ``times`` (increasing, each after
        ``start``'s time), to the same bits as a call for each in turn.

        Returns ``(u, v, states)``: (K, 2) displacement and velocity at each time, and
        ``states[k]`` the integrator's state after the k-th (None for a record).
        """
        times = np.asarray(times, dtype=float)
        if self._callable is None:
            u, v = self._sampled(times)
            return u, v, _States(None, u, v)
        t0, v0, u0 = start
        if not (len(times) and times[0] - t0 > 0.0 and np.all(np.diff(times) > 0.0)):
            raise ValueError(f"{self.name}: advance_many needs times after the start's, "
                             "increasing")
        u, v = self._integrated(t0, v0, u0, times)
        return u, v, _States(times, u, v)

    def _integrated(self, t0, v0, u0, times):
        """(K, 2) u and v at ``times`` from ``(t0, v0, u0)``, each step split at the
        breakpoints inside it."""
        b = self.__dict__.get("_break_list")
        if b is None:  # (the breakpoints as a list: bisect on it costs a tenth of searchsorted)
            b = self.__dict__["_break_list"] = self._breaks.tolist()
        t_last = float(times[-1])
        if b and bisect_left(b, t_last) > bisect_right(b, t0):
            begin, end, last = [], [], []
            a0 = t0
            for t in times.tolist():  # (rarely: a step across a breakpoint)
                for a1 in (*b[bisect_right(b, a0):bisect_left(b, t)], t):
                    begin.append(a0)
                    end.append(a1)
                    last.append(a1 == t)
                    a0 = a1
            begin, end = np.array(begin), np.array(end)
            last = np.array(last, dtype=np.bool_)
        else:
            begin = np.empty(len(times))
            begin[0] = t0
            begin[1:] = times[:-1]
            end, last = times, np.ones(len(times), dtype=np.bool_)
        at = begin[:, None] + (end - begin)[:, None] * _GL_X
        a = self._called(at.reshape(-1)).reshape(len(begin), len(_GL_X), 2)
        return gauss_legendre_steps(np.asarray(u0, dtype=float), np.asarray(v0, dtype=float),
                                    begin, end, last, a, _GL_W, _GL_X)

    def state(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Displacement and velocity at time t (callables must be queried in increasing t;
        the simulation uses the pure :meth:`advance`)."""
        if self._callable is None:
            u, v = self._sampled(np.array([t], dtype=float))
            return u[0], v[0]
        u, v, (self._t, self._v, self._u) = self.advance((self._t, self._v, self._u), t)
        return u, v

    def _sampled(self, t: np.ndarray):
        """(K, 2) u and v of a record at the times ``t`` (the same arithmetic for one time
        and for many)."""
        ts = self._times
        i = np.clip(np.searchsorted(ts, t, side="right") - 1, 0, len(ts) - 2)
        s = (t - ts[i])[:, None]
        h = (ts[i + 1] - ts[i])[:, None]
        a0 = self._acc[i]
        slope = (self._acc[i + 1] - a0) / h
        vel = self._vel[i]
        v = vel + a0 * s + 0.5 * slope * s * s
        u = self._disp[i] + vel * s + 0.5 * a0 * s * s + slope * s**3 / 6.0
        return u, v


class _States:
    """The integrator's states after each step of :meth:`AccelerationHistory.advance_many`:
    ``(t, v, u)`` for a callable, None for a record."""

    def __init__(self, times, u, v):
        self.times, self.u, self.v = times, u, v

    def __getitem__(self, k: int):
        if self.times is None:
            return None
        return float(self.times[k]), self.v[k].copy(), self.u[k].copy()


class DisplacementHistory:
    """A prescribed displacement ``t -> (ux or None, uy or None)`` of every vertex of a block."""

    def __init__(self, displacement, name="prescribe_motion"):
        if not callable(displacement):
            raise ValueError(f"{name}: displacement must be a callable t -> (ux, uy)")
        self._f = displacement
        self.name = name
        first = displacement(0.0)
        try:
            items = list(first)
        except TypeError:
            raise ValueError(f"{name}: displacement(t) must return (ux, uy)") from None
        if len(items) != 2:
            raise ValueError(f"{name}: displacement(t) must return (ux, uy), got {first!r}")
        self.mask = np.array([v is not None for v in items])
        if not self.mask.any():
            raise ValueError(f"{name}: displacement(t) leaves both directions free (None, None)")
        u0 = self(0.0)
        if np.any(np.abs(u0) > 0.0):
            raise ValueError(
                f"{name}: displacement(0) must be zero (it is measured from the start), got "
                f"{first!r}"
            )

    @property
    def function(self):
        """The callable ``t -> (ux, uy)``."""
        return self._f

    def __call__(self, t: float) -> np.ndarray:
        items = list(self._f(t))
        mask = np.array([v is not None for v in items])
        if len(items) != 2 or not np.array_equal(mask, self.mask):
            raise ValueError(
                f"{self.name}: displacement(t) must leave the same directions free at every t"
            )
        vals = np.array([0.0 if v is None else float(v) for v in items])
        if not np.all(np.isfinite(vals)):
            raise ValueError(f"{self.name}: displacement({t:g}) is not finite: {items!r}")
        return vals


class LoadHistory:
    """A point load, constant or a callable ``t -> (fx, fy)``."""

    def __init__(self, force, name="point load"):
        self.name = name
        if callable(force):
            self._f = force
            _as_xy(force(0.0), f"{name}: force(t)")
        else:
            value = _as_xy(force, f"{name}: force")
            self._f = None
            self._value = value

    @property
    def constant(self) -> bool:
        return self._f is None

    @property
    def function(self):
        """The callable ``t -> (fx, fy)``, or None for a constant force."""
        return self._f

    @property
    def value(self) -> np.ndarray | None:
        """The constant force, or None for a callable."""
        return None if self._f is not None else self._value

    def __call__(self, t: float) -> np.ndarray:
        if self._f is None:
            return self._value
        return _as_xy(self._f(t), f"{self.name}: force(t) at t = {t:.6g} s")
