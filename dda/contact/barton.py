"""Barton's rough-joint law as a friction return map (METHOD.md section 7).

Peak strength of a rough rock joint (Barton 1973; Barton and Choubey 1977)::

    tau_peak = sigma_n tan(phi_r + JRC log10(JCS / sigma_n))

with the mobilization of JRC along the accumulated slip of Barton and Bandis (1982). The law
plugs into the contact element through :class:`dda.contact.friction.FrictionLaw` alone.
"""

from __future__ import annotations

import warnings

import numpy as np

from dda._checks import finite_number
from dda.contact.friction import FrictionLaw, FrictionTrial
from dda.kernels.barton import barton_return_map
from dda.plausibility import check_angle

__all__ = ["BartonBandis", "MOBILIZATION_SLIP", "MOBILIZATION_JRC"]

#: Barton's mobilization table: slip / slip at peak ...
MOBILIZATION_SLIP = np.array([0.0, 0.3, 0.6, 1.0, 2.0, 4.0, 10.0, 100.0])
#: ... against JRC_mob / JRC_peak. The first entry, -phi_r / i, depends on the normal stress
#: (it makes the mobilized angle zero at zero slip) and is filled in per contact.
MOBILIZATION_JRC = np.array([np.nan, 0.0, 0.75, 1.0, 0.85, 0.70, 0.50, 0.0])

#: the table's JRC ratios with the first, per-contact entry as 0 (it enters as a zero angle)
_MOBILIZATION_M = np.nan_to_num(MOBILIZATION_JRC)
_LN10 = np.log(10.0)
_RAD = np.pi / 180.0
#: relative tolerance of the scalar return-map equation (round-off of the shear force)
_RETURN_TOL = 1e-13
_RETURN_MAX_ITER = 100
_NO_DILATION = np.zeros(0)

#: Whether a :class:`BartonBandis` of its own class takes the compiled return map
#: (:mod:`dda.kernels.barton`); False: the numpy one, the reference
COMPILED = True


class BartonBandis(FrictionLaw):
    r"""Barton's JRC-JCS joint strength, peak or mobilized with the accumulated slip.

    Strength of a closed contact with compressive force ``|t_n|`` and tributary length ``l_c``
    (METHOD.md section 7)::

        sigma_n = |t_n| / l_c
        i       = JRC log10(JCS / sigma_n)                     (roughness angle, degrees)
        S       = |t_n| tan(phi_mob),   phi_peak = phi_r + i

    ``l_c`` is the contact element's tributary length
    (:func:`dda.contact.kinematics.tributary_length`): half the shorter of the contacted edge
    and the vertex's own edge along it, so the two vertex contacts of a face lying on an edge
    share the face's length and ``sigma_n`` is the face's mean normal stress.

    **Mobilization** (``mobilized=True``, Barton and Bandis 1982). With the accumulated slip
    kappa (the plastic part of the shear displacement, history field ``slip``) and
    ``r = kappa / slip_at_peak``, the mobilized angle is ``phi_mob = phi_r + i m(r)``, where
    ``m`` interpolates Barton's table linearly:

    ====================  =========  ===  ====  ===  ====  ====  ===  ===
    r = slip / slip_peak  0          0.3  0.6   1    2     4     10   100
    JRC_mob / JRC_peak    -phi_r/i   0    0.75  1    0.85  0.70  0.5  0
    ====================  =========  ===  ====  ===  ====  ====  ===  ===

    So the strength is zero at zero slip, reaches ``sigma_n tan(phi_r)`` at 0.3 slip_at_peak,
    peaks at ``slip_at_peak`` and softens to the residual ``sigma_n tan(phi_r)`` at 100
    slip_at_peak and beyond. As in every friction law here the elastic shear displacement
    ``t_s / p_s`` comes on top of the slip; with a stiff penalty it is small.

    With ``mobilized=False`` the strength is the peak strength at every slip (a plain
    Coulomb law whose angle depends on the normal stress).

    **Limits where the logarithm misbehaves** (Barton and Choubey 1977):

    - the peak angle ``phi_r + i`` is capped at ``max_angle`` (70 degrees by default), which
      also covers ``sigma_n -> 0`` where ``i`` grows without bound; at ``sigma_n = 0`` the
      strength is zero;
    - ``i`` is floored at zero: at ``sigma_n >= JCS`` the asperities are sheared off and the
      strength is ``sigma_n tan(phi_r)``.

    In both limits ``d i / d sigma_n = 0`` and the tangent follows.

    **Return map** (backward Euler). A trial ``t_tr = p_s (g_se + delta g_s)`` above the
    strength ``S(|t_n|, kappa_n)`` slips by ``lambda >= 0`` solving

    .. math:: |t_{tr}| - p_s \lambda = S(|t_n|, \kappa_n + \lambda),

    (safeguarded Newton, bracketed on ``[0, |t_tr| / p_s]``), then
    ``t_s = S sgn(t_tr)``. Its consistent tangent, with ``h = dS/d kappa`` (negative when the
    joint softens) and ``d|t_n|/d g_n = -p_n``::

        d t_s / d g_s = p_s h / (p_s + h)
        d t_s / d g_n = -p_n sgn(t_s) (dS/d|t_n|) p_s / (p_s + h)
        dS/d|t_n|     = tan(phi) + sigma_n sec^2(phi) (d phi / d i)(d i / d sigma_n)

    The return map is unique while the softening slope stays below the shear penalty,
    ``p_s + h > 0``. With realistic penalties it holds by orders of magnitude; the law warns
    once when it does not (raise the shear penalty, or the slip at peak): the slip then
    jumps to a root farther along the softening branch.

    **Dilation** (``dilation=True``): the law also keeps the normal dilatancy the joint would
    show under zero normal stiffness, ``v = sum tan(d_mob) lambda`` with Barton's mobilized
    dilation angle ``d_mob = JRC_mob log10(JCS/sigma_n) / 2 = (phi_mob - phi_r) / 2``, as the
    history field ``dilation`` (m). It is recorded, not fed back into the normal gap: the
    contact element owns the gap, and the friction-law interface returns shear forces only.

    Parameters
    ----------
    jrc : float
        Joint roughness coefficient, 0 to 20. A smooth joint (0) has nothing to mobilize: its
        strength is ``sigma_n tan(phi_r)`` at every slip.
    jcs : float
        Joint wall compressive strength, Pa.
    phi_r : float
        Residual friction angle, degrees, in [0, max_angle).
    mobilized : bool
        Mobilize JRC with the accumulated slip (True) or use the peak strength throughout.
    slip_at_peak : float, optional
        Accumulated slip at the peak strength, m. By default Barton and Bandis' size rule
        ``slip_at_peak = (L / 500) (JRC / L)^0.33`` (L in metres) with ``L = block_size``, or,
        when that is not given, ``L = 2 l_c`` of each contact (the length of the face it
        belongs to).
    block_size : float, optional
        Joint length L between cross joints (m) for the size rule.
    dilation : bool
        Keep the dilatancy history field ``dilation``.
    max_angle : float
        Cap of the peak angle ``phi_r + i``, degrees, in (0, 90).

    Examples
    --------
    >>> import numpy as np
    >>> law = BartonBandis(jrc=10, jcs=100e6, phi_r=30, mobilized=False)
    >>> law.peak_angle(np.array([1e6]))            # 30 + 10 log10(100)
    array([50.])
    >>> law.peak_angle(np.array([1e3, 200e6]))     # capped at 70, floored at phi_r
    array([70., 30.])
    >>> trial = law.return_map(law.initial_state(1), np.array([1.0]), np.array([-1e5]),
    ...                        np.array([1e8]), np.array([0.1]))
    >>> float(trial.t_s[0] / 1e5 / np.tan(np.radians(50.0))).__round__(12)
    1.0
    """

    name = "barton"

    def __init__(self, jrc: float, jcs: float, phi_r: float, mobilized: bool = True,
                 slip_at_peak: float | None = None, block_size: float | None = None,
                 dilation: bool = False, max_angle: float = 70.0):
        where = "BartonBandis"
        self.jrc = finite_number("jrc", jrc, nonnegative=True, where=where)
        if self.jrc > 20.0:
            raise ValueError(f"{where}: jrc runs from 0 (smooth) to 20 (very rough), got {jrc}")
        self.jcs = finite_number("jcs", jcs, positive=True, where=where)
        self.max_angle = finite_number("max_angle", max_angle, positive=True, where=where)
        if self.max_angle >= 90.0:
            raise ValueError(f"{where}: max_angle is in degrees and must be below 90, "
                             f"got {max_angle}")
        self.phi_r = finite_number("phi_r", phi_r, nonnegative=True, where=where)
        check_angle("phi_r", self.phi_r, where)
        if self.phi_r >= self.max_angle:
            raise ValueError(f"{where}: phi_r ({phi_r}) must lie below max_angle "
                             f"({self.max_angle}) degrees")
        self.slip_at_peak = (None if slip_at_peak is None else
                             finite_number("slip_at_peak", slip_at_peak, positive=True,
                                           where=where))
        self.block_size = (None if block_size is None else
                           finite_number("block_size", block_size, positive=True, where=where))
        self.mobilized = bool(mobilized) and self.jrc > 0.0
        self.dilation = bool(dilation)
        self._warned_snap_back = False

    def __repr__(self):
        return (f"BartonBandis(jrc={self.jrc}, jcs={self.jcs}, phi_r={self.phi_r}, "
                f"mobilized={self.mobilized}, slip_at_peak={self.slip_at_peak}, "
                f"block_size={self.block_size}, dilation={self.dilation}, "
                f"max_angle={self.max_angle})")

    def history_fields(self) -> dict[str, float]:
        fields = super().history_fields()
        if self.dilation:
            fields["dilation"] = 0.0
        return fields

    # --- strength ---------------------------------------------------------------------------

    def roughness_angle(self, sigma_n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``i = JRC log10(JCS / sigma_n)`` within its limits, and ``d i / d sigma_n`` (deg/Pa).

        ``i`` is clipped to ``[0, max_angle - phi_r]``; the derivative is zero where it is
        clipped and at ``sigma_n = 0``.
        """
        sigma_n = np.asarray(sigma_n, dtype=float)
        positive = sigma_n > 0.0
        safe = np.where(positive, sigma_n, 1.0)
        raw = np.where(positive, self.jrc * np.log10(self.jcs / safe), np.inf)
        top = self.max_angle - self.phi_r
        i = np.minimum(np.maximum(raw, 0.0), top)  # (np.clip: the same, 6 us slower)
        inside = positive & (raw > 0.0) & (raw < top)
        di = np.where(inside, -self.jrc / (safe * _LN10), 0.0)
        return i, di

    def peak_angle(self, sigma_n: np.ndarray) -> np.ndarray:
        """Peak friction angle ``phi_r + i`` (degrees) at normal stress ``sigma_n`` (Pa)."""
        return self.phi_r + self.roughness_angle(sigma_n)[0]

    def peak_slip(self, length: np.ndarray) -> np.ndarray:
        """Accumulated slip at the peak strength of contacts of tributary length ``length``."""
        if self.slip_at_peak is not None:
            return np.full(np.shape(length), self.slip_at_peak)
        size = (np.full(np.shape(length), self.block_size) if self.block_size is not None
                else 2.0 * np.asarray(length, dtype=float))
        return size / 500.0 * (self.jrc / size) ** 0.33

    def mobilized_angle(self, i: np.ndarray, r: np.ndarray):
        """Mobilized angle ``phi_mob`` (deg) at roughness angle ``i`` and slip ratio ``r``.

        Returns ``(phi_mob, d phi_mob / d i, d phi_mob / d r)``; linear interpolation of
        Barton's table in ``r``, held at the residual ``phi_r`` beyond its last entry.
        """
        knots = MOBILIZATION_SLIP
        k = np.minimum(np.maximum(np.searchsorted(knots, r, side="right") - 1, 0), len(knots) - 2)
        beyond = r >= knots[-1]
        w = np.where(beyond, 1.0, (r - knots[k]) / (knots[k + 1] - knots[k]))
        # angle at the knots: phi_r + m_k i, except 0 at r = 0 (m_0 = -phi_r / i)
        m = _MOBILIZATION_M  # m_0 enters through the zero angle below
        at_k = np.where(k == 0, 0.0, self.phi_r + m[k] * i)
        at_k1 = self.phi_r + m[k + 1] * i
        phi = at_k + w * (at_k1 - at_k)
        dphi_di = np.where(k == 0, 0.0, m[k]) * (1.0 - w) + m[k + 1] * w
        dphi_dr = np.where(beyond, 0.0, (at_k1 - at_k) / (knots[k + 1] - knots[k]))
        return phi, dphi_di, dphi_dr

    def shear_strength(self, pressure: np.ndarray, length: np.ndarray, slip: np.ndarray):
        """Shear strength ``S = |t_n| tan(phi_mob)`` (N/m) and its two derivatives.

        Parameters
        ----------
        pressure : compressive normal force ``|t_n|`` (N/m), >= 0
        length : tributary length l_c (m)
        slip : accumulated slip kappa (m)

        Returns
        -------
        S, dS/d|t_n|, dS/d kappa, phi_mob (degrees)
        """
        sigma = pressure / length
        i, di = self.roughness_angle(sigma)
        if self.mobilized:
            peak = self.peak_slip(length)
            phi, dphi_di, dphi_dr = self.mobilized_angle(i, slip / peak)
        else:
            peak, phi, dphi_di, dphi_dr = 1.0, self.phi_r + i, 1.0, 0.0
        tan = np.tan(phi * _RAD)
        sec2 = 1.0 + tan * tan
        ds_dp = tan + sigma * sec2 * _RAD * dphi_di * di
        ds_dk = pressure * sec2 * _RAD * dphi_dr / peak
        return pressure * tan, ds_dp, ds_dk, phi

    # --- the FrictionLaw interface ------------------------------------------------------------

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length):
        if COMPILED and type(self) is BartonBandis:
            return self._compiled_return_map(committed, delta_g_s, t_n, shear_penalty, length)
        return self._numpy_return_map(committed, delta_g_s, t_n, shear_penalty, length)

    def _compiled_return_map(self, committed, delta_g_s, t_n, shear_penalty, length):
        """The trial of :meth:`_numpy_return_map` from :func:`dda.kernels.barton.
        barton_return_map` (the same numbers, contact by contact)."""
        arrays = [np.asarray(a, dtype=np.float64) for a in (
            committed["g_se"], committed["slip"],
            committed["dilation"] if self.dilation else _NO_DILATION, delta_g_s, t_n,
            shear_penalty, length)]
        (t_s, slipping, strength, g_se, slip, dilation, ds_dp, ds_dk,
         unstable) = barton_return_map(
            *arrays, self.jrc, self.jcs, self.phi_r, self.max_angle, self.mobilized,
            -1.0 if self.slip_at_peak is None else self.slip_at_peak,
            -1.0 if self.block_size is None else self.block_size, MOBILIZATION_SLIP,
            _MOBILIZATION_M, _LN10, _RAD, _RETURN_TOL, _RETURN_MAX_ITER)
        self._warn_if_snap_back(unstable)
        state = {"g_se": g_se, "slip": slip}
        if self.dilation:
            state["dilation"] = dilation
        return FrictionTrial(t_s=t_s, slipping=slipping, strength=strength, state=state,
                             extra={"ds_dp": ds_dp, "ds_dk": ds_dk})

    def _numpy_return_map(self, committed, delta_g_s, t_n, shear_penalty, length):
        """The return map in numpy, from :meth:`shear_strength` (the reference)."""
        t_trial = shear_penalty * (committed["g_se"] + delta_g_s)
        pressure = np.maximum(-t_n, 0.0)
        kappa = committed["slip"]
        s0, _, ds_dk0, _ = self.shear_strength(pressure, length, kappa)
        slipping = np.abs(t_trial) > s0
        self._warn_if_snap_back(slipping & (shear_penalty + ds_dk0 <= 0.0))
        lam = np.zeros_like(t_trial)
        if slipping.any():
            lam[slipping] = self._slip_increment(
                np.abs(t_trial[slipping]), pressure[slipping], length[slipping],
                kappa[slipping], shear_penalty[slipping])
        s, ds_dp, ds_dk, phi = self.shear_strength(pressure, length, kappa + lam)
        self._warn_if_snap_back(slipping & (shear_penalty + ds_dk <= 0.0))
        t_s = np.where(slipping, s * np.sign(t_trial), t_trial)
        state = {"g_se": t_s / shear_penalty, "slip": kappa + lam}
        if self.dilation:
            state["dilation"] = (committed["dilation"]
                                 + np.tan(0.5 * (phi - self.phi_r) * _RAD) * lam)
        return FrictionTrial(t_s=t_s, slipping=slipping, strength=np.where(slipping, s, s0),
                             state=state, extra={"ds_dp": ds_dp, "ds_dk": ds_dk})

    def _slip_increment(self, a, pressure, length, kappa, penalty):
        """Solve ``a - p_s lambda - S(kappa + lambda) = 0`` for lambda in [0, a / p_s].

        Safeguarded Newton: a Newton step that leaves the bracket (or a non-decreasing
        residual slope) is replaced by bisection; the bracket shrinks by the residual's sign.
        """
        lo, hi = np.zeros_like(a), a / penalty
        lam = lo.copy()
        # each iteration works on the contacts not yet converged (``active``): one contact
        # bisecting at a kink of the table took all of a call's thousand contacts through 45
        # iterations; each contact's numbers are its own, so they are the same either way
        active = np.arange(len(a))
        for _ in range(_RETURN_MAX_ITER):
            lam_a, a_a, p_a = lam[active], a[active], penalty[active]
            s, _, ds_dk, _ = self.shear_strength(pressure[active], length[active],
                                                 kappa[active] + lam_a)
            f = a_a - p_a * lam_a - s
            going = ~(np.abs(f) <= _RETURN_TOL * a_a)  # (a NaN goes on, as it did)
            if not going.any():
                return lam
            lo_a = np.where(f > 0.0, lam_a, lo[active])
            hi_a = np.where(f < 0.0, lam_a, hi[active])
            slope = p_a + ds_dk
            newton = lam_a + f / np.where(slope > 0.0, slope, 1.0)
            good = (slope > 0.0) & (newton > lo_a) & (newton < hi_a)
            active = active[going]
            lam[active] = np.where(good, newton, 0.5 * (lo_a + hi_a))[going]
            lo[active], hi[active] = lo_a[going], hi_a[going]
        return lam

    def _warn_if_snap_back(self, unstable):
        if not self._warned_snap_back and np.any(unstable):
            self._warned_snap_back = True
            warnings.warn("BartonBandis: the joint softens faster than the shear penalty "
                          "(p_s + dS/dslip <= 0), so the return map is not unique and the "
                          "slip may jump. Raise the shear penalty or slip_at_peak.",
                          RuntimeWarning, stacklevel=3)

    def tangent(self, trial, normal_penalty, shear_penalty):
        h = trial.extra["ds_dk"]
        slope = shear_penalty + h
        ratio = shear_penalty / np.where(slope > 0.0, slope, shear_penalty)
        dts_dgs = np.where(trial.slipping, h * ratio, shear_penalty)
        dts_dgn = np.where(trial.slipping,
                           -normal_penalty * np.sign(trial.t_s) * trial.extra["ds_dp"] * ratio,
                           0.0)
        return dts_dgs, dts_dgn
