"""Joint material: the penalty springs and the friction law of a block interface."""

from __future__ import annotations

from dataclasses import dataclass

from dda._checks import finite_number
from dda.contact.friction import FrictionLaw


@dataclass(frozen=True, eq=False)
class JointMaterial:
    """Penalty contact with friction between blocks (METHOD.md section 4).

    Parameters
    ----------
    normal_penalty : float
        Normal penalty p_n in N/m (per unit thickness), positive.
    shear_penalty : float
        Shear penalty p_s in N/m, positive.
    friction : FrictionLaw
        The friction law of this joint, for example ``CoulombSingle(phi=30)``.
    """

    normal_penalty: float
    shear_penalty: float
    friction: FrictionLaw

    def __post_init__(self):
        finite_number("normal_penalty", self.normal_penalty, positive=True, where="JointMaterial")
        finite_number("shear_penalty", self.shear_penalty, positive=True, where="JointMaterial")
        if not isinstance(self.friction, FrictionLaw):
            raise TypeError(
                "JointMaterial: friction must be a FrictionLaw such as CoulombSingle(phi=30), "
                f"got {self.friction!r}"
            )
