"""Joint material: the penalty springs, the impact dashpot and the friction law of a block
interface."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda._checks import finite_number
from dda.contact.friction import FrictionLaw


@dataclass(frozen=True, eq=False)
class JointMaterial:
    """Penalty contact with friction between blocks (METHOD.md section 4).

    Parameters
    ----------
    normal_penalty : float or "auto"
        Normal penalty p_n in N/m (per unit thickness), positive; ``"auto"``: chosen by the
        simulation from the scene and its step (:mod:`dda.auto_settings`; ``sim.choices``
        says what and why).
    shear_penalty : float or "auto"
        Shear penalty p_s in N/m, positive; ``"auto"``: the normal penalty.
    friction : FrictionLaw
        The friction law of this joint, for example ``CoulombSingle(phi=30)``.
    restitution : float, optional
        Coefficient of restitution ``e`` of a normal impact at one of the joint's contacts,
        0 to 1: a dashpot beside each closed contact's normal spring takes the energy out
        (:mod:`dda.contact.dashpot`). 0 (the default): a critically damped spring, an
        impact that does not bounce, as Housner's rocking block assumes (``dda.studies.
        references.housner_rocking``): a 15 x 45 cm block rocks down as Housner's sequence
        at dt 1e-3 and 1e-4 alike. 1: no dashpot, the penalty impact of original DDA (and of
        Berkeley's C code), whose loss comes from Newmark's gamma = 1 and so depends on dt
        and the penalty: the same block keeps 0.75-0.77 of its rocking amplitude an impact
        at dt 1e-3 and 0.86-0.88 at dt 1e-4 (penalties 2e7 and 2e8 N/m, issue 20).
    shear_dashpot : bool, optional
        Damp the closed contacts' shear springs too, with the damping ratio of
        ``restitution`` (:mod:`dda.contact.dashpot`; no effect at ``restitution`` 1). On by
        default: without it a block at rest on soft shear springs vibrates with no loss but
        Newmark's, which depends on dt. The 16 s rock slope of ``examples/rock_slope.py``
        (ks 10 MN/m, face onset, Newton) follows the rigid block within 0.70% at dt 1e-3 and
        0.30% at dt 1e-4 with it, 0.69% and 10.95% without (legacy DDA at dt 1e-4: 5.2%
        and 61.7%). False gives the joints of original DDA and of the papers; the per-contact
        onset of :class:`dda.contact.StaticDynamicTransition` reproduces the papers only
        without it (with it the rock slope's block starts sliding a level early).

    Examples
    --------
    >>> from dda.contact import CoulombSingle, JointMaterial
    >>> JointMaterial("auto", "auto", CoulombSingle(phi=30.0)).auto
    True
    """

    normal_penalty: float | str
    shear_penalty: float | str
    friction: FrictionLaw
    restitution: float = 0.0
    shear_dashpot: bool = True

    def __post_init__(self):
        for name in ("normal_penalty", "shear_penalty"):
            value = getattr(self, name)
            if isinstance(value, str):
                if value != "auto":
                    raise ValueError(f"JointMaterial: {name} must be a number (N/m) or "
                                     f"'auto', got {value!r}")
                continue
            finite_number(name, value, positive=True, where="JointMaterial")
        finite_number("restitution", self.restitution, where="JointMaterial")
        if not 0.0 <= self.restitution <= 1.0:
            raise ValueError("JointMaterial: restitution must be between 0 (an impact that "
                             f"does not bounce) and 1 (no dashpot), got {self.restitution!r}")
        if not isinstance(self.shear_dashpot, bool):
            raise TypeError("JointMaterial: shear_dashpot must be True or False, got "
                            f"{self.shear_dashpot!r}")
        if not isinstance(self.friction, FrictionLaw):
            raise TypeError(
                "JointMaterial: friction must be a FrictionLaw such as CoulombSingle(phi=30), "
                f"got {self.friction!r}"
            )
        flags = [k for k, v in self.friction.history_fields().items()
                 if np.asarray(v).dtype.kind not in "iuf" or np.asarray(v).ndim != 0]
        if flags:
            raise TypeError(
                f"JointMaterial: friction law {self.friction!r} has the history field(s) "
                f"{flags} whose initial value is not a number; history is carried as float "
                "arrays (keep a flag as 0.0 / 1.0)")

    @property
    def auto(self) -> bool:
        """Whether either penalty is left to the simulation ("auto")."""
        return "auto" in (self.normal_penalty, self.shear_penalty)
