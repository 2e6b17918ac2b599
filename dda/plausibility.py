"""Plausibility warnings: inputs that are valid but are most likely a typing mistake.

A careless but expert user types radians for degrees, MPa for Pa, kN/m^3 for kg/m^3, a
gravity pointing up, a shaking direction that is not a unit vector, or a time step far
above the contacts' period; each is valid input, and each runs (sometimes for a long time)
to a wrong answer. The checks here name the input, the value and the likely mistake, as one
:class:`PlausibilityWarning` each; they never stop a run (``warnings.simplefilter("error",
dda.PlausibilityWarning)`` makes them errors, ``"ignore"`` silences them).

The ranges are wide on purpose, orders of magnitude around rock and masonry: a warning is
for a value no real block or joint has, not for an unusual one.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

__all__ = ["PlausibilityWarning", "check_angle", "check_density", "check_direction",
           "check_gravity", "check_rate_laws_static", "check_shaking_resolution",
           "check_time_step", "check_unit_weight",
           "check_young", "YOUNG_RANGE", "DENSITY_RANGE"]

#: Young's moduli (Pa) between which no warning is given: soft soil to diamond
YOUNG_RANGE = (1e5, 1e13)
#: densities (kg/m^3) between which no warning is given: light foams to the densest metals
DENSITY_RANGE = (100.0, 25_000.0)
#: a step this many times the shortest contact period gets a warning (the implicit step is
#: stable at any dt, and Newton's cheapest accurate moving base takes 25 periods a step: the
#: warning is for a step that skips a hundred)
DT_PERIODS = 100.0
#: a step that resolves the fastest bolt's vibration in fewer steps a period gets a warning:
#: Newmark's gamma = 1 then takes over 10% off the peak force of a bolt let go from rest
#: (0.892 of it at 20 steps; dda.auto_settings, rule 8)
BOLT_STEPS = 20.0


class PlausibilityWarning(UserWarning):
    """An input that is valid but most likely a mistake (the message says which and why)."""


def _warn(message: str, stacklevel: int = 3) -> None:
    warnings.warn(message, PlausibilityWarning, stacklevel=stacklevel + 1)


def check_angle(name: str, value: float, where: str) -> None:
    """A friction angle (degrees) between 0 and pi/2 looks like radians.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     check_angle("phi", 0.52, "CoulombSingle")
    >>> print(caught[0].message)  # doctest: +NORMALIZE_WHITESPACE
    CoulombSingle: phi = 0.52 degrees looks like radians (0.52 rad = 29.8 degrees);
    angles are in degrees
    """
    if 0.0 < value < 0.5 * math.pi:
        _warn(f"{where}: {name} = {value:g} degrees looks like radians ({value:g} rad = "
              f"{math.degrees(value):.1f} degrees); angles are in degrees")


def check_young(value: float, where: str) -> None:
    """A Young's modulus orders of magnitude outside rock and masonry (MPa or GPa typed as
    Pa, or Pa typed as kPa)."""
    low, high = YOUNG_RANGE
    if value < low:
        _warn(f"{where}: young = {value:g} Pa is orders of magnitude below rock and masonry "
              f"(1e9 to 1e11 Pa); it is in Pa (MPa typed as Pa? {value:g} MPa = "
              f"{value * 1e6:g} Pa)")
    elif value > high:
        _warn(f"{where}: young = {value:g} Pa is orders of magnitude above any rock "
              "(1e9 to 1e11 Pa); it is in Pa")


def check_density(value: float, where: str) -> None:
    """A density orders of magnitude outside rock and masonry (a unit weight in kN/m^3, or
    g/cm^3, typed for kg/m^3)."""
    low, high = DENSITY_RANGE
    if value < low:
        _warn(f"{where}: density = {value:g} kg/m^3 is far below rock and masonry (2,000 to "
              f"3,000 kg/m^3): a unit weight in kN/m^3 ({value:g} kN/m^3 is "
              f"{value * 1e3 / 9.81:,.0f} kg/m^3) or g/cm^3?")
    elif value > high:
        _warn(f"{where}: density = {value:g} kg/m^3 is far above any rock (2,000 to "
              "3,000 kg/m^3); it is in kg/m^3")


def check_gravity(value: float) -> None:
    """Gravity pointing up, or orders of magnitude off Earth's."""
    if value < 0.0:
        _warn(f"Scene: gravity = {value:g} m/s^2 points up: gravity acts in -y, give its "
              "size (9.81)")
    elif value > 0.0 and not 0.1 <= value <= 100.0:
        _warn(f"Scene: gravity = {value:g} m/s^2 is orders of magnitude off Earth's 9.81 "
              "(in mm/s^2 or g?)")


def check_unit_weight(value: float) -> None:
    """A water unit weight orders of magnitude off 9810 N/m^3 (kN/m^3 typed, or a density)."""
    if not 5e3 <= value <= 2e4:
        _warn(f"Scene.set_water_table: unit_weight = {value:g} N/m^3 is far from water's 9810 "
              "(in kN/m^3, or a density in kg/m^3?)")


#: the deepest water on Earth (m): a table higher than this above every block is a typing
#: mistake (the wrong unit, a coordinate for a height)
DEEPEST_WATER = 11_000.0


def check_water_table(model) -> None:
    """A water table more than :data:`DEEPEST_WATER` above the top of the scene."""
    water = getattr(model, "water", None)
    if water is None or not model.n_blocks:
        return
    above = float(water.y.min()) - float(model.x_initial[:, 1].max())
    if above > DEEPEST_WATER:
        _warn(f"Scene.set_water_table: the table lies {above:.3g} m above the scene's top, "
              f"deeper than any water on Earth ({DEEPEST_WATER:g} m): a height in mm, or a "
              "coordinate given for a height?", stacklevel=4)


def check_direction(name: str, vector, where: str) -> None:
    """A direction that is not a unit vector (it scales the amplitude it carries)."""
    v = np.asarray(vector, dtype=float)
    size = float(np.hypot(*v)) if v.shape == (2,) else float(np.linalg.norm(v))
    if size > 0.0 and abs(size - 1.0) > 1e-6:
        _warn(f"{where}: {name} = {v.tolist()} has length {size:g}, not 1: it multiplies the "
              f"amplitude by {size:g}; give a unit vector ({(v / size).round(6).tolist()})")


def check_time_step(model, dt: float) -> None:
    """A step far above the shortest contact period ``2 pi sqrt(m / p)`` (the lightest free
    block on the stiffest joint): its contacts cannot settle, and most steps would be cut.
    Dynamic analysis only: a static step carries no velocity and solves for equilibrium (the
    direct shear of ``examples/direct_shear.py`` runs at 159 such periods without a cut)."""
    free = model.free
    if not free.any() or model.n_blocks < 2:
        return
    _check_bolt_step(model, dt)
    mass = model.density * model.size ** 2
    light = int(np.flatnonzero(free)[np.argmin(mass[free])])
    penalties = model.joints.normal_penalty
    finite = penalties[np.isfinite(penalties)]
    if len(finite) == 0:
        return
    period = 2.0 * math.pi * math.sqrt(mass[light] / float(finite.max()))
    if dt > DT_PERIODS * period:
        _warn(f"Simulation: dt = {dt:g} s is {dt / period:.0f} times the period of "
              f"{model.block_label(light)} on its stiffest joint ({period:.3g} s, "
              f"2 pi sqrt(m / p) with p = {finite.max():g} N/m): its contacts cannot settle "
              f"in a step and most steps would be cut; take dt near {period:.3g} s, a softer "
              "penalty, or dt='auto'", stacklevel=4)


def _check_bolt_step(model, dt: float) -> None:
    """A step that resolves the fastest bolt's vibration (:func:`dda.bolts.shortest_period`)
    in fewer than ``BOLT_STEPS`` steps: the bolts' dynamic forces come out low."""
    from dda.auto_settings import BOLT_STEPS_PER_PERIOD  # noqa: PLC0415 (imports this)
    from dda.bolts import released_peak, shortest_period  # noqa: PLC0415 (the kernels)

    period, bolt = shortest_period(model)
    steps = period / dt
    if steps < BOLT_STEPS:
        low = 100.0 * (1.0 - released_peak(steps))
        _warn(f"Simulation: dt = {dt:g} s resolves the vibration of {bolt} (period "
              f"{period:.3g} s) in {steps:.2g} steps a period: Newmark's damping takes "
              f"{low:.2g}% off the peak force of a bolt let go from rest, so a bolt may "
              f"survive that would break; take dt at most "
              f"{period / BOLT_STEPS_PER_PERIOD:.3g} s (1% off), or dt='auto'", stacklevel=5)


#: a given dt that resolves the shaking's 99%-energy frequency in fewer than this share of
#: the solver's own auto_steps_per_period gets a warning (Newton: 8, legacy DDA: 20 steps)
SHAKING_STEPS_SHARE = 1.0 / 20.0
#: a given penalty whose contact frequency sqrt(p / m) / (2 pi) (_softest_contact) is below
#: this multiple of the shaking's frequency gets a warning
SHAKING_CONTACT_RATIO = 3.0
#: a callable shaking is sampled this often (s) for these warnings (4,000 calls over the
#: auto rule's 20 s; its frequencies up to 100 Hz)
CALLABLE_STEP = 5e-3


def check_shaking_resolution(model, dt: float, solver, shakes, dt_given: bool,
                             penalty_given: bool) -> None:
    """A given dt or penalty that cannot follow the shaking (dynamic analysis with shaking).

    - **dt**: fewer steps a period of the frequency below which 99% of the shaking's
      spectral energy lies (:func:`dda.auto_settings.shaking_frequency`) than
      ``SHAKING_STEPS_SHARE`` of the solver's ``auto_steps_per_period`` (the number
      ``dt="auto"`` takes). A block on a 25 degree plane (phi 30) under a 0.4 g broadband
      record (99% below 11.9 Hz) slid 258.6 mm in Newmark's rigid-block integration; at dt
      0.02 s (4 steps a period) Newton erred +2.4% and legacy DDA -18 to -28%, at 0.05 s
      +32% and -78 to -98%, with no word said (an earthquake engineer's review, 2026-12-07).
    - **penalty**: a contact frequency ``sqrt(p / m) / (2 pi)`` (:func:`_softest_contact`:
      a joint given for a pair with the pair's reduced mass, the default joint with the
      heaviest free block) below ``SHAKING_CONTACT_RATIO`` times that frequency: the block
      rides the shaking on its springs. The same block at 1e6 / 3e6 / 1e7 / 3e7 N/m
      (contact frequencies 6.4 / 11 / 20 / 35 Hz) erred +15 / +10 / +5 / +1.8% (Newton) and
      -26 / -12 / -5 / -1.8% (legacy DDA), while it sank at most 1.9% of its half-width, below
      the penalty advice's 5%.
    """
    from dda.auto_settings import (  # noqa: PLC0415 (it imports this module)
        PROBE_SECONDS,
        _frequency,
        shaking_frequency,
    )

    if not shakes or not model.free.any() or not (dt_given or penalty_given):
        return
    # a record is sampled cheaply; a Python callable at 1 kHz over PROBE_SECONDS is 20,000
    # calls (33.7 s at 1 ms a call), so a callable is sampled every CALLABLE_STEP over them
    # (over its first 2 s instead, a shaking that began at 3 s went unseen)
    recorded = [h for h in shakes if h.function is None]
    called = [h for h in shakes if h.function is not None]
    t = np.arange(0.0, PROBE_SECONDS, CALLABLE_STEP)
    found = [x for x in (shaking_frequency(recorded) if recorded else None,
                         _frequency([(CALLABLE_STEP, h.sample(t)) for h in called])
                         if called else None) if x is not None]
    if not found:
        return
    f = max(found)
    if dt_given:
        auto = int(getattr(solver, "auto_steps_per_period", 300))
        steps = 1.0 / (dt * f)
        if steps < SHAKING_STEPS_SHARE * auto:
            _warn(f"Simulation: dt = {dt:g} s takes {steps:.2g} steps a period of the "
                  f"shaking's {f:.3g} Hz (below which 99% of its spectral energy lies), where "
                  f"dt='auto' takes {auto} for {getattr(solver, 'name', 'this solver')}: the "
                  "slip it drives may err by tens of percent (a block under a 12 Hz record "
                  "at 4 steps a period: Newton +2.4%, legacy DDA -18 to -28%); take "
                  f"dt at most {1.0 / (SHAKING_STEPS_SHARE * auto * f):.3g} s, or dt='auto'",
                  stacklevel=4)
    if penalty_given:
        worst = _softest_contact(model)
        if worst is None:
            return
        contact, p, m, block = worst
        if contact < SHAKING_CONTACT_RATIO * f:
            _warn(f"Simulation: a penalty of {p:g} N/m lets {model.block_label(block)} "
                  f"({m:.3g} kg/m on it) ride the shaking on its springs: its contact "
                  f"frequency, {contact:.3g} Hz, is within {SHAKING_CONTACT_RATIO:g} times the "
                  f"shaking's {f:.3g} Hz (below which 99% of its spectral energy lies), and "
                  "a block's slip errs by percents (at 1.7 times: 5%); take at least "
                  f"{(2 * math.pi * SHAKING_CONTACT_RATIO * f) ** 2 * m:.3g} N/m, or "
                  '"auto"', stacklevel=4)


def _softest_contact(model):
    """``(frequency, penalty, mass, block)`` of the lowest contact frequency ``sqrt(p / m) /
    (2 pi)`` among the scene's given joints, or None: a joint of one pair with the pair's
    reduced mass (a block whose motion is known counts as infinitely heavy), the default
    joint with the heaviest free block."""
    joints = model.joints
    penalties = np.asarray(joints.normal_penalty, dtype=float)
    mass = model.density * model.size ** 2
    free_mass = np.where(model.free, mass, np.inf)
    nb = model.n_blocks
    cands = []
    keys = np.asarray(joints.pair_keys, dtype=np.int64)
    if len(keys):
        a, b = keys // nb, keys % nb
        p = penalties[np.asarray(joints.pair_joint, dtype=np.int64)]
        ma, mb = free_mass[a], free_mass[b]
        both = np.isfinite(ma) & np.isfinite(mb)
        m = np.where(both, ma * mb / np.where(both, ma + mb, 1.0), np.minimum(ma, mb))
        ok = np.isfinite(p) & np.isfinite(m)
        for i in np.flatnonzero(ok):  # one per joint given for a pair: a handful
            light = int(a[i]) if ma[i] <= mb[i] else int(b[i])
            cands.append((math.sqrt(p[i] / m[i]) / (2 * math.pi), float(p[i]), float(m[i]),
                          light))
    if joints.default >= 0 and np.isfinite(penalties[joints.default]):
        heavy = int(np.flatnonzero(model.free)[np.argmax(mass[model.free])])
        p = float(penalties[joints.default])
        cands.append((math.sqrt(p / mass[heavy]) / (2 * math.pi), p, float(mass[heavy]),
                      heavy))
    return min(cands) if cands else None


def check_rate_laws_static(laws, dt: float) -> None:
    """A rate-dependent friction law (``FrictionLaw.uses_dt``) in a static analysis: its
    ``dt`` is the analysis's pseudo time step, so a slip "rate" and the force it gives
    depend on how the loading was divided into steps, not on a physical time."""
    rated = [type(law).__name__ for law in laws if getattr(law, "uses_dt", False)]
    if rated:
        _warn(f"Simulation: a static analysis with a rate-dependent friction law "
              f"({', '.join(sorted(set(rated)))}, uses_dt): its return map gets the pseudo time "
              f"step dt = {dt:g} s, so its rate term acts on slip per pseudo step, not per "
              "second; use analysis='dynamic' for a physical rate", stacklevel=4)
