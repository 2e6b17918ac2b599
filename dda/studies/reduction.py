"""Strength reduction of joints: every friction law's strength divided by a factor F.

The factor of safety by strength reduction (:func:`dda.studies.strength_reduction`) runs a
scene whose joints are weakened by a trial factor ``F``; this module makes that scene.
Every joint keeps its penalties, its dashpots and everything else; its friction law is
replaced by the same law with the strength divided by ``F`` (Duncan's definition: ``F`` is the
ratio of the strength the joint has to the strength equilibrium needs)::

    tan(phi_F) = tan(phi) / F          c_F = c / F

so the Coulomb strength ``c l_c + |t_n| tan(phi)`` becomes that strength divided by ``F`` at
every normal force. Per law (:func:`reduce_friction`):

- :class:`~dda.contact.CoulombSingle` ``(phi, cohesion)``: ``phi_F = atan(tan(phi) / F)``,
  ``c_F = c / F``.
- :class:`~dda.contact.StaticDynamicTransition` ``(phi_static, phi_dynamic)``: both angles as
  above (``phi_dynamic_F <= phi_static_F`` still holds), the onset rule kept.
- :class:`~dda.contact.BartonBandis`: Barton's strength ``|t_n| tan(phi_r + JRC log10(JCS /
  sigma_n))`` (peak or mobilized) divided by ``F`` at every normal stress and slip, which is
  ``tan(phi_mob, F) = tan(phi_mob) / F``: the law :class:`ReducedBartonBandis`. No change of
  ``JRC`` and ``phi_r`` alone does this (reducing ``phi_r`` and ``JRC`` in proportion gives
  ``tan(phi_mob / F)``, a different, normal-stress dependent reduction), so the reduced law
  keeps the parameters and divides the strength and its derivatives. The dilation history
  (``dilation=True``) keeps the unreduced angles: it is the joint's geometry, not its strength.
- a law with a method ``reduced(factor)`` (a law of your own, or a subclass of one above):
  whatever that method returns, which must be a :class:`~dda.contact.FrictionLaw` whose
  strength is the law's divided by ``factor``.
- any other law: :class:`TypeError` naming the law and saying how to give it a reduction.

The scene's water, bolts, loads and other effects are not touched: only the joints' friction.
"""

from __future__ import annotations

import contextlib
import copy
import math
import warnings

from dda.contact.barton import BartonBandis
from dda.contact.friction import CoulombSingle, FrictionLaw, StaticDynamicTransition
from dda.contact.joint import JointMaterial
from dda.plausibility import PlausibilityWarning

__all__ = ["ReducedBartonBandis", "reduce_friction", "reduced_joint", "reduced_scene"]


def _reduced_angle(phi: float, factor: float) -> float:
    """``atan(tan(phi) / factor)`` in degrees."""
    return math.degrees(math.atan(math.tan(math.radians(phi)) / factor))


@contextlib.contextmanager
def _meant(*angles):
    """Silence the plausibility check for weak reduced angles (below 1.57 degrees they look
    like radians to it; they are meant), and only for them: ``warnings.catch_warnings``
    changes the process's filters, which threads share."""
    if not any(0.0 < a < 0.5 * math.pi for a in angles):
        yield
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityWarning)
        yield


def _check_factor(factor) -> float:
    try:
        f = float(factor)
    except (TypeError, ValueError):
        raise TypeError(
            f"strength reduction: the factor must be a number, got {factor!r}") from None
    if not (math.isfinite(f) and f > 0.0):
        raise ValueError(f"strength reduction: the factor must be finite and positive, got {f!r}")
    return f


class ReducedBartonBandis(BartonBandis):
    """Barton's joint (:class:`~dda.contact.BartonBandis`) with its strength divided by
    ``factor``.

    The strength at every normal force ``|t_n|`` and accumulated slip ``kappa`` is
    ``S_F = S / F`` (so ``tan(phi_mob, F) = tan(phi_mob) / F``), and its derivatives
    ``dS_F/d|t_n|`` and ``dS_F/d kappa`` are those of ``S`` over ``F``: the return map and
    the consistent tangent of the base class follow unchanged.

    Parameters
    ----------
    jrc, jcs, phi_r, mobilized, slip_at_peak, block_size, dilation, max_angle
        As :class:`~dda.contact.BartonBandis`.
    factor : float
        The strength reduction factor ``F`` (positive; 1 is the law itself).

    Examples
    --------
    >>> import numpy as np
    >>> law = ReducedBartonBandis(jrc=10, jcs=100e6, phi_r=30, mobilized=False, factor=2.0)
    >>> s, _, _, phi = law.shear_strength(np.array([1e6]), np.array([1.0]), np.zeros(1))
    >>> round(float(s[0] / 1e6), 6), float(phi[0])   # tan(50 deg) / 2 at 1 MPa
    (0.595877, 50.0)
    """

    #: not registered: a scene as data names it by its import path
    name = "reduced_barton"

    def __init__(self, jrc: float, jcs: float, phi_r: float, mobilized: bool = True,
                 slip_at_peak: float | None = None, block_size: float | None = None,
                 dilation: bool = False, max_angle: float = 70.0, factor: float = 1.0):
        super().__init__(jrc, jcs, phi_r, mobilized=mobilized, slip_at_peak=slip_at_peak,
                         block_size=block_size, dilation=dilation, max_angle=max_angle)
        self.factor = _check_factor(factor)

    def __repr__(self):
        return super().__repr__()[:-1].replace("BartonBandis(", "ReducedBartonBandis(", 1) + \
            f", factor={self.factor})"

    def shear_strength(self, pressure, length, slip):
        s, ds_dp, ds_dk, phi = super().shear_strength(pressure, length, slip)
        f = self.factor
        return s / f, ds_dp / f, ds_dk / f, phi

    def reduced(self, factor: float) -> ReducedBartonBandis:
        """The same joint with its strength divided by ``factor`` once more."""
        return ReducedBartonBandis(**_barton_parameters(self),
                                   factor=self.factor * _check_factor(factor))


def _barton_parameters(law: BartonBandis) -> dict:
    return {"jrc": law.jrc, "jcs": law.jcs, "phi_r": law.phi_r, "mobilized": law.mobilized,
            "slip_at_peak": law.slip_at_peak, "block_size": law.block_size,
            "dilation": law.dilation, "max_angle": law.max_angle}


def reduce_friction(law: FrictionLaw, factor: float) -> FrictionLaw:
    """The friction law ``law`` with its strength divided by ``factor`` (module docstring).

    Parameters
    ----------
    law : FrictionLaw
    factor : float
        ``F > 0``: ``tan(phi_F) = tan(phi) / F``, ``c_F = c / F``.

    Returns
    -------
    FrictionLaw
        A new law; ``law`` is not changed.

    Raises
    ------
    TypeError
        For a law this module does not know and that has no ``reduced(factor)`` method.

    Examples
    --------
    >>> from dda.contact import CoulombSingle, StaticDynamicTransition
    >>> reduce_friction(CoulombSingle(phi=45.0, cohesion=1e4), 2.0)  # atan(1 / 2)
    CoulombSingle(phi=26.56505117707799, cohesion=5000.0)
    >>> law = reduce_friction(StaticDynamicTransition(40.5, 31.6), 1.25)
    >>> round(law.mu_static, 6), round(law.mu_dynamic, 6)  # tan(40.5) / 1.25, tan(31.6) / 1.25
    (0.683265, 0.492163)
    """
    f = _check_factor(factor)
    reduced = getattr(law, "reduced", None)
    if callable(reduced):
        out = reduced(f)
        if not isinstance(out, FrictionLaw):
            raise TypeError(f"{type(law).__name__}.reduced({f:g}) returned {out!r}, not a "
                            "FrictionLaw")
        return out
    kind = type(law)
    if kind is CoulombSingle:
        phi = _reduced_angle(law.phi, f)
        with _meant(phi):
            return CoulombSingle(phi=phi, cohesion=law.cohesion / f)
    if kind is StaticDynamicTransition:
        phi_s, phi_d = _reduced_angle(law.phi_static, f), _reduced_angle(law.phi_dynamic, f)
        with _meant(phi_s, phi_d):
            return StaticDynamicTransition(phi_s, phi_d, onset=law.onset)
    if kind is BartonBandis:
        return ReducedBartonBandis(**_barton_parameters(law), factor=f)
    raise TypeError(
        f"strength reduction does not know how to weaken the friction law {law!r} "
        f"({kind.__module__}.{kind.__qualname__}); give its class a method "
        "reduced(self, factor) that returns the law with its shear strength divided by factor "
        "(tan(phi) / factor and cohesion / factor for a Coulomb-type law)")


def reduced_joint(joint: JointMaterial, factor: float) -> JointMaterial:
    """``joint`` with its friction law reduced by ``factor`` (penalties, dashpots kept)."""
    return JointMaterial(joint.normal_penalty, joint.shear_penalty,
                         reduce_friction(joint.friction, factor),
                         restitution=joint.restitution, shear_dashpot=joint.shear_dashpot)


def reduced_scene(scene, factor: float):
    """A copy of ``scene`` whose every joint (the default and each pair's) is reduced by
    ``factor``; the scene itself is not changed.

    Raises
    ------
    TypeError
        Naming the joint whose friction law has no reduction (:func:`reduce_friction`).
    """
    f = _check_factor(factor)
    names = [b.name for b in scene.blocks]
    joints = []  # (between, reduced joint), checked before the scene is copied
    if scene.default_joint is not None:
        joints.append((None, _reduced(scene.default_joint, f, "the default joint")))
    for (a, b), joint in scene.pair_joints.items():
        where = f"the joint between {names[a]!r} and {names[b]!r}"
        joints.append(((a, b), _reduced(joint, f, where)))
    out = copy.deepcopy(scene)
    for between, joint in joints:
        out.set_joint(joint, between=between)
    return out


def _reduced(joint, factor, where):
    try:
        return reduced_joint(joint, factor)
    except TypeError as exc:
        raise TypeError(f"{where}: {exc}") from None
