"""Module-level callables and a law of a test's own, importable by path (``tests.
scene_data_helpers:...``), for the scene-as-data tests."""

from __future__ import annotations

import numpy as np

from dda.contact import CoulombLike


def table(t):
    """A base acceleration: 0.3 g at 2 Hz."""
    return (0.3 * 9.81 * np.sin(4.0 * np.pi * t), 0.0)


def push(t):
    """A point load that grows with time."""
    return (1e3 * t, -2e3)


def slide(t):
    """A prescribed displacement along x, y free."""
    return (1e-3 * t, None)


class Sticky(CoulombLike):
    """A Coulomb law with a cohesion in N/m of contact length (a law of a test's own)."""

    name = "sticky"

    def __init__(self, phi: float, glue: float = 0.0):
        self.phi, self.glue = float(phi), float(glue)
        self.mu = float(np.tan(np.radians(self.phi)))

    def strength(self, t_n, length, history=None):
        return self.glue * length + np.maximum(-t_n, 0.0) * self.mu

    def strength_slope(self, t_n, length, history=None):
        return self.mu


class Pulse:
    """A callable object (an instance, not a function): no import path of its own."""

    def __call__(self, t):
        return (0.0, 0.0)


def make_closure():
    """A function defined inside another."""

    def inner(t):
        return (0.0, 0.0)

    return inner
