"""Studies: sweeps, analytical reference solutions, and the factor of safety by strength
reduction (:func:`strength_reduction`, :mod:`dda.studies.factor_of_safety`)."""

from dda.studies.factor_of_safety import Criterion, StrengthReduction, strength_reduction

__all__ = ["Criterion", "StrengthReduction", "strength_reduction"]
