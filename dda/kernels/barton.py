"""Compiled return map of :class:`dda.contact.BartonBandis` (Barton's JRC-JCS law).

The numpy return map solves each slipping contact's equation ``|t_tr| - p_s lambda =
S(|t_n|, kappa + lambda)`` by a safeguarded Newton iteration over arrays, some fifty array
operations an iteration; on the 311-block cut slope of ``examples/jointed_slope.py`` with
Barton joints it was most of a step. :func:`barton_return_map` does the numpy law's arithmetic
contact by contact, in its order (:meth:`dda.contact.BartonBandis.shear_strength`,
``_slip_increment``), so the trial has the same numbers: the same bits where numpy's
``log10``, ``tan`` and the like are the C library's, as the kernel's are, and a few ulp apart
on a machine with AVX-512, where numpy takes vectorized versions of them;
``tests/test_barton_bandis.py`` compares the two. The numpy path stays the reference, and a
subclass of the law takes it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["barton_return_map"]


@njit(cache=True)
def _roughness(pressure, length, jrc, jcs, phi_r, max_angle, mobilized, slip_at_peak,
               block_size, ln10):
    """``(sigma_n, i, d i / d sigma_n, slip at peak)`` of one contact: what its strength
    needs that does not depend on the slip (:meth:`dda.contact.BartonBandis.roughness_angle`,
    ``peak_slip``; the slip at peak 1 when the law is not mobilized)."""
    sigma = pressure / length
    positive = sigma > 0.0
    safe = sigma if positive else 1.0
    raw = jrc * math.log10(jcs / safe) if positive else math.inf
    top = max_angle - phi_r
    i = min(max(raw, 0.0), top)
    di = -jrc / (safe * ln10) if positive and raw > 0.0 and raw < top else 0.0
    peak = 1.0
    if mobilized:
        if slip_at_peak > 0.0:
            peak = slip_at_peak
        else:
            size = block_size if block_size > 0.0 else 2.0 * length
            peak = size / 500.0 * (jrc / size) ** 0.33
    return sigma, i, di, peak


@njit(cache=True)
def _strength(pressure, sigma, i, di, peak, kappa, phi_r, mobilized, knots, ratios, rad):
    """``(S, dS/d|t_n|, dS/d kappa, phi_mob)`` of one contact at the slip ``kappa``
    (:meth:`dda.contact.BartonBandis.shear_strength`, ``mobilized_angle``)."""
    if mobilized:  # Barton's table, linear in r
        r = kappa / peak
        last = knots.shape[0] - 1
        k = np.searchsorted(knots, r, side="right") - 1
        k = min(max(k, 0), last - 1)
        beyond = r >= knots[last]
        w = 1.0 if beyond else (r - knots[k]) / (knots[k + 1] - knots[k])
        at_k = 0.0 if k == 0 else phi_r + ratios[k] * i
        at_k1 = phi_r + ratios[k + 1] * i
        phi = at_k + w * (at_k1 - at_k)
        dphi_di = (0.0 if k == 0 else ratios[k]) * (1.0 - w) + ratios[k + 1] * w
        dphi_dr = 0.0 if beyond else (at_k1 - at_k) / (knots[k + 1] - knots[k])
    else:
        phi, dphi_di, dphi_dr = phi_r + i, 1.0, 0.0
    tan = math.tan(phi * rad)
    sec2 = 1.0 + tan * tan
    ds_dp = tan + sigma * sec2 * rad * dphi_di * di
    ds_dk = pressure * sec2 * rad * dphi_dr / peak
    return pressure * tan, ds_dp, ds_dk, phi


@njit(cache=True)
def barton_return_map(g_se, slip, dilation, delta_g_s, t_n, shear_penalty, length, jrc, jcs,
                      phi_r, max_angle, mobilized, slip_at_peak, block_size, knots, ratios,
                      ln10, rad, tol, max_iter):
    """Barton's return map, contact by contact (:meth:`dda.contact.BartonBandis.return_map`).

    ``dilation`` is the committed dilatancy (empty: the law keeps none); ``slip_at_peak`` and
    ``block_size`` are -1 when not given; ``knots`` and ``ratios`` Barton's table (its first
    ratio 0); ``tol`` and ``max_iter`` the scalar equation's tolerance and iteration limit.

    Returns
    -------
    t_s, slipping, strength, g_se, slip, dilation : the trial
    ds_dp, ds_dk : ``dS/d|t_n|`` and ``dS/d kappa`` at its end (for the tangent)
    unstable : whether a slipping contact softens faster than its shear penalty
    """
    m = delta_g_s.shape[0]
    keeps_dilation = dilation.shape[0] > 0
    t_s = np.empty(m)
    slipping = np.zeros(m, dtype=np.bool_)
    strength = np.empty(m)
    g_se_out = np.empty(m)
    slip_out = np.empty(m)
    dilation_out = np.empty(m if keeps_dilation else 0)
    ds_dp_out = np.empty(m)
    ds_dk_out = np.empty(m)
    unstable = False
    for c in range(m):
        ps = shear_penalty[c]
        t_trial = ps * (g_se[c] + delta_g_s[c])
        pressure = max(-t_n[c], 0.0)
        kappa = slip[c]
        sigma, i, di, peak = _roughness(pressure, length[c], jrc, jcs, phi_r, max_angle,
                                        mobilized, slip_at_peak, block_size, ln10)
        s0, _, ds_dk0, _ = _strength(pressure, sigma, i, di, peak, kappa, phi_r, mobilized,
                                     knots, ratios, rad)
        slides = abs(t_trial) > s0
        if slides and ps + ds_dk0 <= 0.0:
            unstable = True
        lam = 0.0
        if slides:  # the scalar equation (_slip_increment): safeguarded Newton
            a = abs(t_trial)
            lo, hi = 0.0, a / ps
            for _ in range(max_iter):
                s, _, ds_dk, _ = _strength(pressure, sigma, i, di, peak, kappa + lam, phi_r,
                                           mobilized, knots, ratios, rad)
                f = a - ps * lam - s
                if abs(f) <= tol * a:
                    break
                if f > 0.0:
                    lo = lam
                if f < 0.0:
                    hi = lam
                slope = ps + ds_dk
                newton = lam + f / (slope if slope > 0.0 else 1.0)
                lam = newton if slope > 0.0 and newton > lo and newton < hi else 0.5 * (lo + hi)
        s, ds_dp, ds_dk, phi = _strength(pressure, sigma, i, di, peak, kappa + lam, phi_r,
                                         mobilized, knots, ratios, rad)
        if slides and ps + ds_dk <= 0.0:
            unstable = True
        if slides:
            t_s[c] = s * (1.0 if t_trial > 0.0 else -1.0)
        else:
            t_s[c] = t_trial
        slipping[c] = slides
        strength[c] = s if slides else s0
        g_se_out[c] = t_s[c] / ps
        slip_out[c] = kappa + lam
        if keeps_dilation:
            dilation_out[c] = dilation[c] + math.tan(0.5 * (phi - phi_r) * rad) * lam
        ds_dp_out[c] = ds_dp
        ds_dk_out[c] = ds_dk
    return (t_s, slipping, strength, g_se_out, slip_out, dilation_out, ds_dp_out, ds_dk_out,
            unstable)
