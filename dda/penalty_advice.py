"""Telling the user when the contact penalty is wrong for the scene and the step size.

A penalty spring is a compromise (METHOD.md sections 4 and 5): too soft, and blocks sink into
each other; too stiff for the step size, and OPEN-CLOSE does not settle, so steps are cut.
:class:`dda.Simulation` checks both as it runs and warns once for each, with a penalty that
would do and why:

- **too soft**: a closed spring sinks deeper than ``SOFT_DEPTH`` (5 %) of the thinner
  block's half-width ``h = 2 area / perimeter``. A resting load ``F`` sinks ``F / p``, so the
  penalty that keeps it within ``TARGET_DEPTH`` (1 %, the penetration guard's tolerance) is
  ``p depth / (TARGET_DEPTH h)``; an impact's depth falls only as ``1 / sqrt(p)``, so it may
  need up to the square of that ratio.
- **too stiff**: ``STIFF_CUTS`` (20) steps or more cut because contacts would not settle, and
  either at least ``STIFF_SHARE`` (10 %) of the steps taken, or steps that average at most
  ``STIFF_HELD`` (1/8) of the dt asked for (the step control waits longer and longer before it
  tries a cut dt doubled again, so a run held at a small dt has few cuts). The spring is
  measured against the inertia of the lightest free block, ``k_m = 2 m / dt^2`` (the mass term
  of Newmark's effective stiffness, METHOD.md section 2): a penalty near ``STIFF_RATIO`` (10) times
  ``k_m``, or a step ``dt = sqrt(2 STIFF_RATIO m / p)``, keeps the spring from dominating.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

__all__ = ["PenaltyAdvisor", "PenaltyWarning", "soft_penalty_advice", "stiff_penalty_advice",
           "contact_cut", "natural_step"]

SOFT_DEPTH = 0.05
TARGET_DEPTH = 0.01
STIFF_CUTS = 20
STIFF_SHARE = 0.1
STIFF_RATIO = 10.0
STIFF_HELD = 1.0 / 8.0

# the reasons of a dt cut that come from the contacts (see Simulation and the solvers)
_CONTACT_REASONS = ("OPEN-CLOSE did not settle", "Newton-Raphson did not converge",
                    "untracked penetration")


class PenaltyWarning(UserWarning):
    """The contact penalty looks wrong for the scene or the step size."""


def _nice(value: float) -> str:
    """A round number near ``value`` (one significant digit, rounded up)."""
    if not math.isfinite(value) or value <= 0:
        return f"{value:g}"
    exp = math.floor(math.log10(value))
    lead = math.ceil(value / 10**exp - 1e-9)
    if lead == 10:
        lead, exp = 1, exp + 1
    return f"{lead}e{exp}"


def contact_cut(reason: str) -> bool:
    """Whether a dt cut's reason comes from the contacts."""
    return reason.startswith(_CONTACT_REASONS)


def soft_penalty_advice(depth: np.ndarray, half_width: np.ndarray, penalty: np.ndarray,
                        names: list[str]) -> str | None:
    """The warning for springs that sink too deep, or None.

    Parameters
    ----------
    depth : (m,) spring penetration ``-t_n / p_n`` of each closed contact (m)
    half_width : (m,) the thinner block's half-width of each contact (m)
    penalty : (m,) each contact's normal penalty (N/m)
    names : (m,) how to name each contact's pair of blocks

    Examples
    --------
    >>> import numpy as np
    >>> print(soft_penalty_advice(np.array([0.01]), np.array([0.1]), np.array([1e6]),
    ...                           ["block 'a' on block 'b'"]))  # doctest: +NORMALIZE_WHITESPACE
    contact springs sink too deep: 0.01 m, 10% of the half-width (2 area / perimeter) of
    block 'a' on block 'b', with a normal penalty of 1e+06 N/m. A penalty of at least 1e7 N/m
    keeps a resting load within 1% (an impact, whose depth falls as 1/sqrt(penalty), may need
    up to 1e8 N/m); a penalty this soft lets blocks sink into each other.
    """
    if len(depth) == 0:
        return None
    ratio = depth / half_width
    i = int(np.argmax(ratio))
    if ratio[i] <= SOFT_DEPTH:
        return None
    factor = ratio[i] / TARGET_DEPTH
    return (f"contact springs sink too deep: {depth[i]:.3g} m, {100 * ratio[i]:.3g}% of the "
            f"half-width (2 area / perimeter) of {names[i]}, with a normal penalty of "
            f"{penalty[i]:.3g} N/m. A penalty of at least {_nice(penalty[i] * factor)} N/m "
            f"keeps a resting load within {100 * TARGET_DEPTH:g}% (an impact, whose depth "
            f"falls as 1/sqrt(penalty), may need up to {_nice(penalty[i] * factor**2)} N/m); "
            "a penalty this soft lets blocks sink into each other.")


def stiff_penalty_advice(cuts: int, steps: int, penalty: float, mass: float, dt: float,
                         name: str, mean_dt: float | None = None, floor: float = 0.0,
                         floor_reason: str = "") -> str | None:
    """The warning for a penalty too stiff for the step size, or None.

    Parameters
    ----------
    cuts : steps cut so far because the contacts would not settle
    steps : steps taken so far
    penalty : the stiffest normal penalty in play (N/m)
    mass : the lightest free block's mass (kg per m)
    dt : the step size asked for (s)
    name : that block's name
    mean_dt : the mean size of the steps taken (s), if known
    floor : the least penalty the scene takes (N/m; :func:`dda.auto_settings.penalty_floor`),
        and ``floor_reason`` why. Where ``STIFF_RATIO`` times the inertia at ``dt`` is below
        it, the penalty advised is the floor, at the dt that keeps it at ``STIFF_RATIO``
        times the inertia: a softer one would sink the resting loads or soften the mass
        (the cut slope of ``examples/jointed_slope.py`` was advised 1e9 N/m at its 2e-3 s,
        where joints of 2.2e9 N/m move its face twice as far as joints of 2e10)

    Examples
    --------
    >>> print(stiff_penalty_advice(40, 100, 1e13, 100.0, 1e-3, "block 'b'"))
    ... # doctest: +NORMALIZE_WHITESPACE
    the step was cut 40 times in 100 steps because the contacts would not settle: the normal
    penalty 1e+13 N/m is 5e+04 times the inertia 2 m / dt^2 = 2e+08 N/m of block 'b' (the
    lightest free block). A penalty of about 2e9 N/m at dt = 0.001 s, or dt = 1.41e-05 s at
    this penalty, keeps the springs from dominating the step.

    Where the scene takes no softer penalty than that (a floor of 1e10 N/m):

    >>> print(stiff_penalty_advice(40, 100, 1e13, 100.0, 1e-3, "block 'b'", floor=1e10,
    ...       floor_reason="the reason"))  # doctest: +NORMALIZE_WHITESPACE
    the step was cut 40 times in 100 steps because the contacts would not settle: the normal
    penalty 1e+13 N/m is 5e+04 times the inertia 2 m / dt^2 = 2e+08 N/m of block 'b' (the
    lightest free block). A penalty of about 1e10 N/m at dt = 0.000447 s (the least this
    scene takes, 1e+10 N/m: the reason), or dt = 1.41e-05 s at this penalty, keeps the
    springs from dominating the step.
    """
    held = mean_dt is not None and mean_dt <= STIFF_HELD * dt
    if cuts < STIFF_CUTS or (cuts < STIFF_SHARE * steps and not held):
        return None
    inertia = 2.0 * mass / dt**2
    ratio = penalty / inertia
    # (with round-off to spare: the fully implicit method's "auto" penalty is STIFF_RATIO
    # times the inertia, dda.auto_settings, and is not to be called too stiff)
    if ratio <= STIFF_RATIO * (1.0 + 1e-9):
        return None
    dt_ok = math.sqrt(2.0 * STIFF_RATIO * mass / penalty)
    mean = f" (they average dt = {mean_dt:.3g} s)" if held else ""
    if STIFF_RATIO * inertia >= floor:
        softer = f"{_nice(STIFF_RATIO * inertia)} N/m at dt = {dt:g} s"
    else:
        p_floor = _nice(floor)
        dt_floor = math.sqrt(2.0 * STIFF_RATIO * mass / float(p_floor))
        softer = (f"{p_floor} N/m at dt = {dt_floor:.3g} s (the least this scene takes, "
                  f"{floor:.3g} N/m: {floor_reason})")
    return (f"the step was cut {cuts} times in {steps} steps{mean} because the contacts would "
            f"not settle: the normal penalty {penalty:.3g} N/m is {ratio:.2g} times the inertia "
            f"2 m / dt^2 = {inertia:.3g} N/m of {name} (the lightest free block). A penalty of "
            f"about {softer}, or dt = {dt_ok:.3g} s at this penalty, keeps the springs from "
            "dominating the step.")


def _lightest(model) -> tuple[float, int]:
    """The lightest free block's mass at the start (kg per m) and its index."""
    mass = model.density * model.size**2
    light = int(np.flatnonzero(model.free)[np.argmin(mass[model.free])])
    return float(mass[light]), light


def natural_step(model) -> float:
    """The step size at which the stiffest joint's normal penalty equals the lightest free
    block's inertia: ``dt_n = sqrt(2 m / p)`` (``p = 2 m / dt_n^2``, the mass term of
    Newmark's effective stiffness). 0 when the scene has no free block with mass.

    Above it the springs dominate the step; a step far above it (a static analysis at 1 s a
    step) may have to be cut many times before its contacts settle
    (:class:`dda.step_control.StepControl`).
    """
    if not model.free.any():
        return 0.0
    mass, _ = _lightest(model)
    pn = model.joints.normal_penalty
    penalty = float(np.nanmax(pn)) if len(pn) and not np.isnan(pn).all() else 0.0
    if mass <= 0.0 or not penalty > 0.0:
        return 0.0
    return math.sqrt(2.0 * mass / penalty)


class PenaltyAdvisor:
    """Watches the committed steps of a run and warns (once each) when the penalty is wrong.

    Parameters
    ----------
    model : dda.model.Model
    dt : the step size asked for (s)
    """

    def __init__(self, model, dt: float):
        self.model = model
        self.dt = dt
        self.warned: set[str] = set()

    def observe(self, state, steps: int, contact_cuts: int) -> None:
        """Look at a committed :class:`dda.step.StepState` after ``steps`` steps, of which
        ``contact_cuts`` were cut because the contacts would not settle."""
        if "soft" not in self.warned:
            self._check_soft(state)
        if ("stiff" not in self.warned and contact_cuts >= STIFF_CUTS
                and self.model.free.any()):
            self._check_stiff(steps, contact_cuts, state.time / max(steps, 1))

    def soft_advice(self, state) -> str | None:
        """:func:`soft_penalty_advice` for the closed contacts of ``state`` (None when no
        spring sinks ``SOFT_DEPTH`` of its thinner block's half-width), warned or not."""
        model, c = self.model, state.contacts
        if not len(c.t_n):
            return None
        closed, depth, pn = model.spring_depths(c)
        if len(closed) == 0:
            return None
        half = np.minimum(model.thickness[c.bj[closed]], model.thickness[c.bk[closed]])
        if not np.any(depth > SOFT_DEPTH * half):
            return None
        names = [f"{model.block_label(j)} on {model.block_label(k)}"
                 for j, k in zip(c.bj[closed], c.bk[closed], strict=True)]
        return soft_penalty_advice(depth, half, pn, names)

    def _check_soft(self, state):
        model, c = self.model, state.contacts
        # no spring can sink SOFT_DEPTH of a block's half-width when the largest normal force
        # would not sink it so on the softest joint and the thinnest block (a test of two
        # array reductions: the full check costs ten times more, every step)
        if not len(c.t_n) or (-float(c.t_n.min()) <= SOFT_DEPTH * model.min_thickness
                              * float(model.joints.normal_penalty.min())):
            return
        message = self.soft_advice(state)
        if message:
            self.warned.add("soft")
            warnings.warn(message, PenaltyWarning, stacklevel=6)

    def _check_stiff(self, steps, contact_cuts, mean_dt):
        model = self.model
        mass, light = _lightest(model)
        from dda.auto_settings import penalty_floor  # noqa: PLC0415 (it imports this module)

        floor, why = penalty_floor(model)
        message = stiff_penalty_advice(contact_cuts, steps,
                                       float(model.joints.normal_penalty.max()),
                                       mass, self.dt, model.block_label(light),
                                       mean_dt, floor, why)
        if message:
            self.warned.add("stiff")
            warnings.warn(message, PenaltyWarning, stacklevel=6)
