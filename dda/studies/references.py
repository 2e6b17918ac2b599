"""Reference solutions the paper cases are checked against (METHOD.md section 9).

:func:`sliding_block` is a rigid block on a plane that translates with a shaking table: the
analytical stick-slip solution of a block on a moving table (A appendix) when the plane is
horizontal, and Newmark's rigid-block sliding computation when it dips, both with a static and
a dynamic friction coefficient. :func:`housner_rocking` is a rigid rectangular block rocking
on a rigid base, each impact taking out the energy Housner's coefficient of restitution says;
:func:`housner_shaken` is the same block on a base that shakes horizontally.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from dda._checks import finite_number

_ROOT_TOL = 4 * np.finfo(float).eps  # the event search's tolerance in scipy's solve_ivp

__all__ = ["SlidingHistory", "sliding_block", "housner_restitution", "housner_rocking",
           "RockingHistory", "housner_shaken"]


@dataclass
class SlidingHistory:
    """Slide of a rigid block relative to its table, sampled at the requested times.

    Attributes
    ----------
    time : (n,) s
    slip : (n,) displacement of the block relative to the table along the plane (m), positive
        down the dip (along +x for a horizontal plane)
    velocity : (n,) its rate (m/s)
    sliding : (n,) True while the block slides
    events : list of (time, what) for every start and stop of sliding
    """

    time: np.ndarray
    slip: np.ndarray
    velocity: np.ndarray
    sliding: np.ndarray
    events: list[tuple[float, str]]

    def start_time(self) -> float:
        """The first time the block starts to slide (nan if it never does)."""
        starts = [t for t, what in self.events if what.startswith("slide")]
        return starts[0] if starts else float("nan")


def sliding_block(
    table_acceleration: Callable[[float], Sequence[float]],
    times: np.ndarray,
    mu_static: float,
    mu_dynamic: float | None = None,
    dip: float = 0.0,
    gravity: float = 9.81,
    max_step: float = 1e-3,
    breakpoints: Sequence[float] = (),
    rtol: float = 1e-10,
) -> SlidingHistory:
    r"""Stick-slip of a rigid block on a plane fixed to a translating table.

    In the table's frame the block feels gravity and the inertial force ``-m a(t)``. Along the
    plane (dipping ``dip`` degrees towards +x; the unit vector down the dip is
    ``(cos b, -sin b)``), per unit mass::

        D(t) = (g + a_y) sin b - a_x cos b          driving acceleration down the dip
        N(t) = (g + a_y) cos b + a_x sin b          normal pressure (must stay positive)

    - stuck (``s' = 0``): the block stays while ``|D| <= mu_s N``; beyond that it starts to
      slide in the direction of ``D``;
    - sliding: ``s'' = D - mu_d N sgn(s')``, until ``s'`` returns to zero; there it sticks if
      ``|D| <= mu_s N`` (the static coefficient again, as in METHOD.md section 6), otherwise it
      slides on, in the direction of ``D``.

    With a horizontal plane this is the A appendix's solution of a block on a moving table:
    ``a_2 = a_1`` while stuck, ``a_2 = mu g sgn(v_1 - v_2)`` while sliding. A sliding phase is
    integrated with an adaptive Runge-Kutta method (DOP853) and its end located as an event
    (a root of ``s'``); a stuck phase needs no integration: ``|D| - mu_s N`` is read every
    ``max_step`` and its root located by Brent's method. The switching instants are exact to
    round-off, the slip to ``rtol``.

    Parameters
    ----------
    table_acceleration : callable
        ``t -> (a_x, a_y)`` of the table, m/s^2.
    times : (n,) array
        Increasing output times, starting at the first time of the run (the block is at rest
        relative to the table then).
    mu_static, mu_dynamic : float
        Friction coefficients; ``mu_dynamic`` defaults to ``mu_static`` (one coefficient).
    dip : float
        Dip of the plane in degrees, in [0, 90).
    gravity : float
        g, m/s^2.
    max_step : float
        Largest integration step, and the spacing at which a stuck phase reads the static
        strength (s): the search for a phase's end looks for sign changes from one step to
        the next, so it must be shorter than the shortest stick or slip phase of interest.
    breakpoints : sequence of float
        Times where the table acceleration jumps; phases are split there.
    rtol : float
        Relative tolerance of the integration.

    Returns
    -------
    SlidingHistory

    Examples
    --------
    A table accelerating at 0.5 g under a block with mu 0.3 leaves it behind at 0.2 g:

    >>> import numpy as np
    >>> h = sliding_block(lambda t: (0.5 * 9.81, 0.0), np.array([0.0, 1.0]), mu_static=0.3)
    >>> round(float(h.slip[-1]), 6), round(-0.5 * 0.2 * 9.81, 6)
    (-0.981, -0.981)
    """
    where = "sliding_block"
    mu_s = finite_number("mu_static", mu_static, nonnegative=True, where=where)
    mu_d = mu_s if mu_dynamic is None else finite_number("mu_dynamic", mu_dynamic,
                                                         nonnegative=True, where=where)
    if mu_d > mu_s:
        raise ValueError(f"{where}: mu_dynamic ({mu_d}) must not exceed mu_static ({mu_s})")
    b = np.radians(finite_number("dip", dip, nonnegative=True, where=where))
    if b >= np.pi / 2:
        raise ValueError(f"{where}: dip is in degrees and must be below 90, got {dip}")
    g = finite_number("gravity", gravity, positive=True, where=where)
    max_step = finite_number("max_step", max_step, positive=True, where=where)
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or len(times) < 2 or np.any(np.diff(times) <= 0):
        raise ValueError(f"{where}: times must be an increasing 1-D array of 2 or more times")
    cos_b, sin_b = np.cos(b), np.sin(b)

    def drive_and_pressure(t):
        ax, ay = table_acceleration(t)
        d = (g + ay) * sin_b - ax * cos_b
        n = (g + ay) * cos_b + ax * sin_b
        if n <= 0.0:
            raise ValueError(f"{where}: the block lifts off the plane at t = {t:.6g} s "
                             "(normal pressure <= 0); this reference covers sliding only")
        return d, n

    t_end = times[-1]
    cuts = sorted({float(t) for t in breakpoints if times[0] < t < t_end})
    slip = np.full(len(times), np.nan)
    vel = np.full(len(times), np.nan)
    sliding = np.zeros(len(times), dtype=bool)
    events: list[tuple[float, str]] = []
    opts = {"method": "DOP853", "rtol": rtol, "atol": 1e-14, "max_step": max_step,
            "dense_output": True}

    def fill(sol, t0, t1, moving):
        sel = (times >= t0) & (times <= t1)
        if sel.any():
            y = sol.sol(times[sel])
            slip[sel], vel[sel] = y[0], y[1]
            sliding[sel] = moving

    def segment_end(t):
        later = [c for c in cuts if c > t + 1e-12]
        return later[0] if later else t_end

    def beyond(tt):
        """How far the drive is beyond the static strength, down and up the dip (m/s^2)."""
        d, n = drive_and_pressure(tt)
        return d - mu_s * n, -d - mu_s * n

    def stuck_until(t0, stop):
        """The end of a stuck phase that starts at ``t0`` (at most ``stop``) and the direction
        of the slide that ends it (0.0: none before ``stop``). The static strength is checked
        every ``max_step`` and a crossing located by Brent's method, as an ODE solver's event
        search would do, without integrating the block's rest."""
        a, g_a = t0, beyond(t0)
        k = 1
        while a < stop:
            b = min(t0 + k * max_step, stop)
            g_b = beyond(b)
            roots = [(brentq(lambda tt, i=i: beyond(tt)[i], a, b, xtol=_ROOT_TOL,
                             rtol=_ROOT_TOL), 1.0 - 2.0 * i)
                     for i in (0, 1) if g_a[i] <= 0.0 <= g_b[i]]
            if roots:
                return min(roots)
            a, g_a = b, g_b
            k += 1
        return stop, 0.0

    t, s, v = float(times[0]), 0.0, 0.0
    direction = 0.0  # 0: stuck, +-1: sliding down / up the dip
    while t < t_end - 1e-12:
        stop = segment_end(t)
        if direction == 0.0:
            d0, n0 = drive_and_pressure(t)
            if abs(d0) > mu_s * n0:  # already beyond the static strength
                direction = float(np.sign(d0))
                events.append((t, "slide " + ("+" if direction > 0 else "-")))
                continue
            t1, direction = stuck_until(t, stop)
            sel = (times >= t) & (times <= t1)
            slip[sel], vel[sel], sliding[sel] = s, 0.0, False
            t, v = t1, 0.0
            if direction:
                events.append((t, "slide " + ("+" if direction > 0 else "-")))
        else:
            sign = direction

            def rhs(tt, y, sign=sign):
                d, n = drive_and_pressure(tt)
                return [y[1], d - mu_d * n * sign]

            def halts(tt, y):
                return y[1]

            halts.terminal, halts.direction = True, -sign
            sol = solve_ivp(rhs, (t, stop), [s, v], events=halts, **opts)
            t1 = float(sol.t[-1])
            fill(sol, t, t1, True)
            t, s, v = t1, float(sol.y[0, -1]), float(sol.y[1, -1])
            if sol.status == 1:
                v = 0.0
                d, n = drive_and_pressure(t)
                if abs(d) <= mu_s * n:
                    direction = 0.0
                    events.append((t, "stick"))
                else:
                    direction = float(np.sign(d))
                    events.append((t, "slide " + ("+" if direction > 0 else "-")))
    at_end = np.isnan(slip)
    slip[at_end], vel[at_end] = s, v
    return SlidingHistory(times, slip, vel, sliding, events)


def housner_restitution(width: float, height: float) -> float:
    """Housner's (1963) coefficient of restitution of a rigid rectangular block's rocking:
    the ratio of the angular velocities after and before an impact,

        r = 1 - (3/2) sin^2 alpha,   alpha = atan(width / height)

    from the conservation of angular momentum about the corner that strikes, which sticks
    and does not bounce (a perfectly inelastic impact); the kinetic energy falls by r^2.

    Examples
    --------
    >>> round(housner_restitution(0.15, 0.45), 4)
    0.85
    """
    finite_number("width", width, positive=True, where="housner_restitution")
    finite_number("height", height, positive=True, where="housner_restitution")
    alpha = np.arctan2(width, height)
    return float(1.0 - 1.5 * np.sin(alpha) ** 2)


def housner_rocking(width: float, height: float, tilt: float, impacts: int) -> np.ndarray:
    """Rocking amplitudes of a rigid ``width`` x ``height`` block released from rest at
    ``tilt`` radians on one corner (below its critical angle ``alpha = atan(width /
    height)``): ``impacts + 1`` amplitudes, the release tilt then the largest tilt after each
    impact.

    Between impacts the block swings about one corner without loss; its centroid, at
    ``R = sqrt(width^2 + height^2) / 2`` from that corner, stands ``R cos(alpha - theta)``
    above the base at tilt theta, so the kinetic energy at an impact is ``m g R (cos(alpha
    - theta_k) - cos alpha)``. The impact keeps ``r^2`` of it (:func:`housner_restitution`),
    and the block rises to

        cos(alpha - theta_(k+1)) = cos alpha + r^2 (cos(alpha - theta_k) - cos alpha)

    Examples
    --------
    >>> a = np.arctan(0.15 / 0.45)
    >>> np.round(housner_rocking(0.15, 0.45, 0.5 * a, 3) / a, 3).tolist()
    [0.5, 0.324, 0.221, 0.154]
    """
    alpha = float(np.arctan2(width, height))
    tilt = finite_number("tilt", tilt, positive=True, where="housner_rocking")
    if tilt >= alpha:
        raise ValueError(f"housner_rocking: a tilt of {tilt:g} rad topples the block (its "
                         f"critical angle is {alpha:g} rad)")
    r2 = housner_restitution(width, height) ** 2
    out = [tilt]
    for _ in range(int(impacts)):
        rise = np.cos(alpha) + r2 * (np.cos(alpha - out[-1]) - np.cos(alpha))
        out.append(alpha - float(np.arccos(rise)))
    return np.array(out)


@dataclass(frozen=True)
class RockingHistory:
    """Rocking of a rigid block on a shaken base (:func:`housner_shaken`).

    Attributes
    ----------
    time : (n,) s, the integrator's own points (denser where the block rocks)
    rotation : (n,) rad, counterclockwise positive (pivoting on the left corner), as
        ``result.rotation`` of a DDA block
    toppled : whether the block fell over (its rotation reached 90 degrees)
    impacts : how many times it came down on its base
    """

    time: np.ndarray
    rotation: np.ndarray
    toppled: bool
    impacts: int

    @property
    def peak(self) -> float:
        """The largest rotation from upright (rad)."""
        return float(np.abs(self.rotation).max(initial=0.0))


def housner_shaken(width: float, height: float, acceleration: Callable, duration: float,
                   restitution: float | None = None, gravity: float = 9.81,
                   rest_speed: float = 1e-4) -> RockingHistory:
    """A rigid ``width`` x ``height`` block standing on a base that shakes horizontally with
    ``acceleration`` (``t -> (a_x, a_y)``, m/s^2; ``a_y`` is ignored): Housner's (1963)
    rocking block under base excitation, integrated in time.

    The block stands still until ``|a_x| > g tan(alpha)`` (``alpha = atan(width / height)``)
    and then rocks about one base corner. With ``R`` the centroid's distance from that
    corner and ``p^2 = 3 g / (4 R)`` (a rectangle's inertia about its corner, ``4 m R^2 /
    3``), counterclockwise ``theta`` (the left corner as pivot for ``theta > 0``):

        theta'' = -p^2 (sgn(theta) sin(alpha - |theta|) - (a_x / g) cos(alpha - |theta|))

    Each time it comes down (``theta = 0``) the angular velocity is multiplied by the
    coefficient of restitution, Housner's :func:`housner_restitution` unless
    ``restitution`` is given; under ``rest_speed`` rad/s it stands still again. The block
    has toppled when its rotation reaches 90 degrees. There is no sliding, no bouncing and no
    second impact corner: the rigid-block theory the stacked cubes and a rocking DDA block are
    judged by.

    Examples
    --------
    >>> still = housner_shaken(0.15, 0.45, lambda t: (3.0, 0.0), 1.0)  # below g/3
    >>> still.peak, still.impacts
    (0.0, 0)
    """
    width = finite_number("width", width, positive=True, where="housner_shaken")
    height = finite_number("height", height, positive=True, where="housner_shaken")
    duration = finite_number("duration", duration, positive=True, where="housner_shaken")
    g = finite_number("gravity", gravity, positive=True, where="housner_shaken")
    alpha = float(np.arctan2(width, height))
    r = housner_restitution(width, height) if restitution is None else finite_number(
        "restitution", restitution, where="housner_shaken")
    if not 0.0 <= r <= 1.0:
        raise ValueError(f"housner_shaken: restitution must be between 0 and 1, got {r!r}")
    p2 = 3.0 * g / (2.0 * np.hypot(width, height))  # 3 g / (4 R), R the half-diagonal

    def a_x(t):
        return float(acceleration(t)[0])

    uplift = g * np.tan(alpha)
    t, theta, omega, side = 0.0, 0.0, 0.0, 0
    times, rotations = [0.0], [0.0]
    toppled, impacts = False, 0
    scan = 2e-4  # the step the standing block's uplift is looked for with (s)
    while t < duration and not toppled:
        if side == 0:  # standing: wait for the base to throw it
            grid = np.arange(t, duration + scan, scan)
            a = np.array([a_x(s) for s in np.minimum(grid, duration)])
            over = np.flatnonzero(np.abs(a) > uplift)
            if not len(over):
                times.append(duration)
                rotations.append(0.0)
                break
            i = int(over[0])
            side = 1 if a[i] > 0 else -1
            if i > 0:  # the crossing itself, between two scan points
                t = brentq(lambda s: abs(a_x(s)) - uplift, grid[i - 1], grid[i])
            else:
                t = float(grid[0])
            theta, omega = 0.0, 0.0
            times.append(t)
            rotations.append(0.0)
        s = side

        def rhs(tt, y, s=s):
            arm = alpha - s * y[0]
            return [y[1], -p2 * (s * np.sin(arm) - a_x(tt) / g * np.cos(arm))]

        def lands(tt, y, s=s):
            return y[0] - s * 1e-12

        lands.terminal, lands.direction = True, -s

        def falls(tt, y):
            return abs(y[0]) - 0.5 * np.pi

        falls.terminal = True
        sol = solve_ivp(rhs, (t, duration), [theta if theta else s * 2e-12, omega],
                        events=(lands, falls), max_step=1e-3, rtol=1e-9, atol=1e-12)
        times.extend(sol.t[1:])
        rotations.extend(sol.y[0][1:])
        t = float(sol.t[-1])
        if sol.t_events[1].size:
            toppled = True
        elif sol.t_events[0].size:
            impacts += 1
            omega = r * float(sol.y_events[0][0][1])
            theta = 0.0
            side = 0 if abs(omega) < rest_speed else (1 if omega > 0 else -1)
            if side == 0:
                omega = 0.0
    return RockingHistory(np.array(times), np.array(rotations), toppled, impacts)
