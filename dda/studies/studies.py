"""Paper cases as sweepable studies: settings in, simulation and error against the reference out.

Both take the settings ``solver`` ("legacy" or "newton"), ``dt`` (s) and ``penalty`` (N/m, the
normal and the shear penalty), so one grid covers both (``benchmarks/accuracy_cost.py``).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from dda.simulation import Simulation
from dda.studies.cases import G, moving_base, relative_slip, shear_box, shear_stress
from dda.studies.references import sliding_block
from dda.studies.sweep import Study, make_solver

__all__ = ["MovingBase", "DirectShear"]


@lru_cache(maxsize=8)
def _moving_base_reference(duration, phi, amplitude, freq, samples=20_001):
    omega = 2 * np.pi * freq
    times = np.linspace(0.0, duration, samples)
    ref = sliding_block(lambda t: (amplitude * np.sin(omega * t), 0.0), times,
                        np.tan(np.radians(phi)))
    return times, ref.slip


class MovingBase(Study):
    """The block on a shaken base (H 3(2), A 4(1); :func:`dda.studies.cases.moving_base`).

    Error: the largest gap between the DDA slip history and the analytical stick-slip
    solution (:func:`dda.studies.references.sliding_block`), divided by the analytical peak
    slip (20.43 mm for the default 1 s). ``peak_error`` is the peak slip's relative error.

    Parameters
    ----------
    duration : float
        Shaking time (s).
    phi, amplitude, freq : float
        Friction angle (degrees), table acceleration amplitude (m/s^2) and frequency (Hz).
    """

    name = "moving_base"

    def __init__(self, duration: float = 1.0, phi: float = 36.4, amplitude: float = G,
                 freq: float = 2.0):
        self.duration, self.phi, self.amplitude, self.freq = duration, phi, amplitude, freq

    def __repr__(self):
        return (f"MovingBase(duration={self.duration:g}, phi={self.phi:g}, "
                f"amplitude={self.amplitude:g}, freq={self.freq:g})")

    def prepare(self, solver="newton", dt=1e-3, penalty=2e9):
        scene, base, block = moving_base(penalty, self.phi, self.amplitude, self.freq)
        sim = Simulation(scene, dt=dt, solver=make_solver(solver))

        def error(result):
            times, ref = _moving_base_reference(self.duration, self.phi, self.amplitude,
                                                self.freq)
            slip = relative_slip(result, base, block)
            peak = np.abs(ref).max()
            if peak == 0.0:
                raise ValueError(f"MovingBase: the block does not slip in {self.duration:g} s "
                                 "of shaking; the relative error has no scale")
            gap = np.abs(slip - np.interp(result.time, times, ref)).max()
            return {"error": gap / peak, "peak_error": np.abs(slip).max() / peak - 1.0}

        return sim, self.duration, error


class DirectShear(Study):
    """Direct shear of two blocks under a normal stress (H 3(1); :func:`shear_box`).

    Static analysis with ``n = round(1 / dt)`` shear steps after one consolidation step.
    Error: the largest relative gap between the shear stress and the strength
    ``normal_stress tan(phi)`` once the joint has yielded in the reference sense: the peak's
    overshoot or the end value's shortfall, whichever is larger.

    Parameters
    ----------
    normal_stress : float
        Pa.
    shear : float
        Shear displacement imposed at the loading springs over the run (m).
    phi : float
        Friction angle (degrees).
    """

    name = "direct_shear"

    def __init__(self, normal_stress: float = 1e6, shear: float = 2e-3, phi: float = 30.0):
        self.normal_stress, self.shear, self.phi = normal_stress, shear, phi

    def __repr__(self):
        return (f"DirectShear(normal_stress={self.normal_stress:g}, shear={self.shear:g}, "
                f"phi={self.phi:g})")

    def prepare(self, solver="newton", dt=1e-2, penalty=1e10):
        from dda.contact import CoulombSingle

        scene, lower, upper = shear_box(self.shear, friction=CoulombSingle(phi=self.phi),
                                        normal_stress=self.normal_stress, penalty=penalty,
                                        consolidation=dt)
        sim = Simulation(scene, dt=dt, solver=make_solver(solver), analysis="static")
        strength = self.normal_stress * np.tan(np.radians(self.phi))

        def error(result):
            tau = shear_stress(result, lower, upper)
            over = tau.max() / strength - 1.0
            end = tau[-1] / strength - 1.0
            return {"error": max(abs(over), abs(end)), "overshoot": over, "end_error": end}

        return sim, 1.0 + dt, error
