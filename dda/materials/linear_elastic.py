"""Linear elastic block material, plane stress or plane strain (METHOD.md section 1)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda._checks import finite_number
from dda.plausibility import check_density, check_young


@dataclass(frozen=True)
class LinearElastic:
    """Isotropic linear elasticity for a DDA block (per unit thickness).

    Parameters
    ----------
    young : float
        Young's modulus E in Pa (positive).
    poisson : float
        Poisson's ratio nu, in [0, 0.5) (plane strain needs nu < 0.5).
    density : float
        Mass density rho in kg/m^3 (positive).
    plane : {"stress", "strain"}
        Plane stress (default) or plane strain.

    Examples
    --------
    >>> rock = LinearElastic(young=14.9e9, poisson=0.2, density=2198.0)
    >>> bool(rock.elasticity()[0, 0] == 14.9e9 / (1 - 0.2**2))
    True
    """

    young: float
    poisson: float
    density: float
    plane: str = "stress"

    def __post_init__(self):
        young = finite_number("young", self.young, positive=True, where="LinearElastic")
        nu = finite_number("poisson", self.poisson, where="LinearElastic")
        if not -1.0 < nu < 0.5:
            raise ValueError(f"LinearElastic: poisson must lie in (-1, 0.5), got {nu}")
        density = finite_number("density", self.density, positive=True, where="LinearElastic")
        for name, value in (("young", young), ("poisson", nu), ("density", density)):
            object.__setattr__(self, name, value)  # (frozen: the numbers as floats)
        check_young(young, "LinearElastic")
        check_density(density, "LinearElastic")
        if self.plane not in ("stress", "strain"):
            raise ValueError(
                f"LinearElastic: plane must be 'stress' or 'strain', got {self.plane!r}"
            )

    def elasticity(self) -> np.ndarray:
        """The 3x3 matrix D with [sx, sy, txy] = D [ex, ey, gxy] (engineering shear strain).

        Plane stress: ``E / (1 - nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]]``;
        plane strain: ``E / ((1 + nu)(1 - 2 nu)) [[1 - nu, nu, 0], [nu, 1 - nu, 0],
        [0, 0, (1 - 2 nu) / 2]]``.
        """
        e, nu = float(self.young), float(self.poisson)
        if self.plane == "stress":
            f = e / (1.0 - nu * nu)
            return f * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, 0.5 * (1.0 - nu)]])
        f = e / ((1.0 + nu) * (1.0 - 2.0 * nu))
        return f * np.array(
            [[1.0 - nu, nu, 0.0], [nu, 1.0 - nu, 0.0], [0.0, 0.0, 0.5 * (1.0 - 2.0 * nu)]]
        )
