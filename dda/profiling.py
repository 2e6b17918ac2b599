"""Where a step's time goes: exclusive timers around the parts of a step.

A :class:`StepProfile` is made active for one step (``with profile.active():``); the code of
the step marks its parts with ``with section("assembly"):``. Time spent in a section nested
inside another is counted only once, in the inner one, so the sections add up to at most the
step's wall time. Without an active profile a section costs one context-variable lookup.

The active profile lives in a :class:`contextvars.ContextVar`, so runs in threads (a Dask
worker with threads) keep their own.

Sections
--------
detection
    broad and narrow phase, carrying contacts over from the last step
contact_element
    contact kinematics and linearization (E, I rows, gaps, geometric stiffness), faces
return_map
    the friction laws' return maps and tangents
assembly
    building the global matrix and right-hand side (and residual vectors)
solve
    factorization and solution of the linear system; on a scene solved dense with the
    built-in friction laws, the whole OPEN-CLOSE iteration (with legacy DDA's pull-back and
    step end) and the whole Newton-Raphson iteration (their kinematics, return maps and
    assembly too: one kernel call each, :mod:`dda.kernels.dense_passes`,
    :mod:`dda.kernels.dense_newton`); and a small scene's common step from its detection to
    its guard, in one kernel call (:mod:`dda.kernels.small_step`: its detection,
    contact_element and guard read 0)
guard
    the penetration guard: every vertex inside another block at the end of the step, found
    geometrically and checked against the closed contacts (:mod:`dda.contact.penetration`)
"""

from __future__ import annotations

from contextvars import ContextVar
from time import perf_counter

__all__ = ["SECTIONS", "StepProfile", "section"]

SECTIONS = ("detection", "contact_element", "return_map", "assembly", "solve", "guard")

_active: ContextVar[StepProfile | None] = ContextVar("dda_step_profile", default=None)


class StepProfile:
    """Seconds per section and the number of linear solves of one step (retries included)."""

    __slots__ = ("seconds", "solves", "_nested", "_starts")

    def __init__(self):
        self.seconds = dict.fromkeys(SECTIONS, 0.0)
        self.solves = 0
        self._nested: list[float] = []  # per open section: the time of the sections in it
        self._starts: list[float] = []  # per open section: when it started

    def active(self):
        """Context manager that makes this profile the one sections report to."""
        return _Activation(self)


class _Activation:
    __slots__ = ("profile", "token")

    def __init__(self, profile):
        self.profile = profile

    def __enter__(self):
        self.token = _active.set(self.profile)
        return self.profile

    def __exit__(self, *exc):
        _active.reset(self.token)
        return False


class _Section:
    """One per section name, shared: what an open section needs lives in the profile."""

    __slots__ = ("name",)

    def __init__(self, name):
        self.name = name

    def __enter__(self):
        p = _active.get()
        if p is not None:
            p._nested.append(0.0)
            p._starts.append(perf_counter())
        return self

    def __exit__(self, *exc):
        p = _active.get()
        if p is not None and p._starts:  # (not when the profile came in within the section)
            elapsed = perf_counter() - p._starts.pop()
            inner = p._nested.pop()
            p.seconds[self.name] += elapsed - inner
            if p._nested:
                p._nested[-1] += elapsed
        return False


def section(name: str) -> _Section:
    """Time the enclosed block as part ``name`` of the active step profile (if any).

    Examples
    --------
    >>> from dda.profiling import StepProfile, section
    >>> p = StepProfile()
    >>> with p.active():
    ...     with section("assembly"):
    ...         with section("solve"):
    ...             pass
    >>> p.seconds["assembly"] >= 0.0 and p.seconds["solve"] >= 0.0
    True
    """
    try:
        return _SECTION_OF[name]
    except KeyError:
        raise ValueError(f"section: unknown section {name!r}; there are "
                         f"{', '.join(SECTIONS)}") from None


def count_solve(n: int = 1) -> None:
    """Count ``n`` linear solves in the active profile."""
    p = _active.get()
    if p is not None:
        p.solves += n


_SECTION_OF = {name: _Section(name) for name in SECTIONS}
