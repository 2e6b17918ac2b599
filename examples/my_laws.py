"""A user's friction law in one file: Coulomb friction whose cohesion breaks at the first slip.

Used by ``examples/user_friction_law.py`` and ``examples/brittle_block.toml``; the guide
``docs/friction_laws.md`` walks through it.
"""

import numpy as np

from dda.contact import CoulombLike


class BrittleCohesion(CoulombLike):
    """Strength ``c l_c + |t_n| tan(phi)`` while intact, ``|t_n| tan(phi)`` once it slipped."""

    name = "brittle"

    def __init__(self, phi: float, cohesion: float):
        self.phi, self.cohesion = float(phi), float(cohesion)
        self.mu = np.tan(np.radians(self.phi))

    def __repr__(self):
        return f"BrittleCohesion(phi={self.phi}, cohesion={self.cohesion})"

    def history_fields(self):
        return {**super().history_fields(), "intact": 1.0}

    def strength(self, t_n, length, history=None):
        return history["intact"] * self.cohesion * length + np.maximum(-t_n, 0.0) * self.mu

    def strength_slope(self, t_n, length, history=None):
        return self.mu

    def updated_history(self, history, slipping):
        return {"intact": np.where(slipping, 0.0, history["intact"])}
