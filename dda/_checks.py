"""Input checks shared by the public API: every error names the argument and says what is wrong."""

from __future__ import annotations

import math

import numpy as np


def finite_number(name: str, value, *, positive=False, nonnegative=False, where: str = "") -> float:
    """Return ``value`` as a float, or raise ValueError naming ``name`` (and ``where``)."""
    label = f"{where}: {name}" if where else name
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{label} must be a number, got the text {value!r} (give it without "
                         "quotes)")
    if isinstance(value, (bool, np.bool_)):  # float(True) is 1.0: a flag where a number goes
        raise ValueError(f"{label} must be a number, got {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{label} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{label} must be finite, got {x}")
    if positive and x <= 0.0:
        raise ValueError(f"{label} must be positive, got {x}")
    if nonnegative and x < 0.0:
        raise ValueError(f"{label} must not be negative, got {x}")
    return x


def finite_vector(name: str, value, size: int = 2, where: str = "", allow_none=False):
    """Return ``value`` as a float array of ``size`` entries (None kept where allowed)."""
    label = f"{where}: {name}" if where else name
    try:
        items = list(value)
    except TypeError:
        raise ValueError(f"{label} must be a sequence of {size} numbers, got {value!r}") from None
    if len(items) != size:
        raise ValueError(f"{label} must have {size} entries, got {len(items)}")
    out = []
    for i, v in enumerate(items):
        if v is None and allow_none:
            out.append(None)
        else:
            out.append(finite_number(f"{name}[{i}]", v, where=where))
    if allow_none:
        return out
    return np.array(out, dtype=float)
