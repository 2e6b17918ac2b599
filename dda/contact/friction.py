"""Friction laws as return maps (METHOD.md sections 4 and 6).

A law is vectorized over every contact that shares it and owns its history fields. It is asked
for a trial built from the committed history every time (so a reverted step costs nothing) and
for the consistent tangent of that trial. It never touches the global system.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from dda._checks import finite_number
from dda.kernels.friction import coulomb_return_map, transition_return_map
from dda.kernels.open_close import COULOMB, TRANSITION, TRANSITION_FACE
from dda.plausibility import check_angle

__all__ = ["FrictionLaw", "FrictionTrial", "CoulombLike", "CoulombSingle",
           "StaticDynamicTransition"]


@dataclass
class FrictionTrial:
    """The outcome of one return map, per contact.

    Attributes
    ----------
    t_s : shear force (N per m of thickness), the same sign convention as g_s
    slipping : True where the trial force was returned to the yield surface
    strength : the shear strength used in the yield check (N per m)
    state : the trial history, committed as it is when the step converges
    """

    t_s: np.ndarray
    slipping: np.ndarray
    strength: np.ndarray
    state: dict[str, np.ndarray]
    extra: dict[str, np.ndarray] = field(default_factory=dict)


class FrictionLaw(ABC):
    """Base class of the friction laws: one subclass per law, vectorized over contacts.

    A law owns its history fields (:meth:`history_fields`); no one else reads them. The
    defaults of this base keep the elastic shear displacement ``g_se`` (so ``t_s = p_s g_se``
    on the stick branch, :meth:`stick`) and the accumulated slip ``slip``; a law that keeps
    other fields overrides :meth:`history_fields`, :meth:`stick` and :meth:`elastic_update`.

    A law that judges a face-to-face contact as a whole sets ``uses_faces`` to True; its
    :meth:`return_map` then also gets ``faces=`` (:class:`dda.contact.faces.Faces`: which of
    its contacts form one face).
    """

    #: the law's name in scene files, sweeps and the CLI (the registry's key)
    name: str = "law"
    uses_faces: bool = False
    #: a law whose force depends on the slip rate sets this: its ``return_map`` then also
    #: gets ``dt=`` (the step's size, s; the slip increment over it is the rate)
    uses_dt: bool = False

    def history_fields(self) -> dict[str, float]:
        """Names of the history fields and their value for a contact that has just closed."""
        return {"g_se": 0.0, "slip": 0.0}

    def initial_state(self, n: int) -> dict[str, np.ndarray]:
        """History of ``n`` contacts that have just closed."""
        return {k: np.full(n, v, dtype=float) for k, v in self.history_fields().items()}

    def kept_when_open(self) -> tuple[str, ...]:
        """The history fields a contact keeps while it is open (its vertex and edge still
        found, and closing again), where the others start again from
        :meth:`history_fields`: what belongs to the joint's surface rather than to the
        spring, such as a slip-weakening law's accumulated slip. Default: none, every field
        starts again (a slip-weakening law was back at its peak after a block's one-step
        hop, 215 mm of slip forgotten). A contact found anew starts from
        :meth:`history_fields` whatever this says; the elastic shear ``g_se`` is best not
        kept (an open contact carries no force)."""
        return ()

    @abstractmethod
    def return_map(
        self,
        committed: dict[str, np.ndarray],
        delta_g_s: np.ndarray,
        t_n: np.ndarray,
        shear_penalty: np.ndarray,
        length: np.ndarray,
    ) -> FrictionTrial:
        """Backward-Euler return map of one step (METHOD.md section 4, H9).

        Parameters
        ----------
        committed : history at the start of the step (never modified)
        delta_g_s : shear displacement increment since the committed state
        t_n : normal force (negative in compression)
        shear_penalty : p_s of each contact
        length : tributary contact length l_c of each contact (turns stresses into forces)
        """

    @abstractmethod
    def tangent(
        self, trial: FrictionTrial, normal_penalty: np.ndarray, shear_penalty: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Consistent tangent ``(d t_s / d g_s, d t_s / d g_n)`` of a trial, per contact."""

    def elastic_update(
        self, committed: dict[str, np.ndarray], delta_g_s: np.ndarray
    ) -> dict[str, np.ndarray]:
        """History after a step taken on the elastic (stick) branch without a return map.

        This is legacy DDA's way: a locked contact keeps its spring force even when it lies
        above the strength, until it is pulled back at the start of the next step. The
        default keeps the elastic shear displacement in ``g_se``; a law that keeps it
        elsewhere overrides this and :meth:`stick`.
        """
        state = {k: v.copy() for k, v in committed.items()}
        state["g_se"] = committed["g_se"] + delta_g_s
        return state

    def stick(self, committed: dict[str, np.ndarray], delta_g_s: np.ndarray,
              shear_penalty: np.ndarray) -> FrictionTrial:
        """The trial of a contact locked on its elastic branch (no yield check).

        Legacy DDA's stick spring: ``t_s = p_s (g_se + delta_g_s)`` with the history of
        :meth:`elastic_update`. With ``delta_g_s = 0`` it is the shear force the spring
        starts the step with. The solvers reach it through the contact element only.
        """
        state = self.elastic_update(committed, delta_g_s)
        t_s = shear_penalty * state["g_se"]
        return FrictionTrial(t_s=t_s, slipping=np.zeros(len(t_s), dtype=bool),
                             strength=np.full(len(t_s), np.inf), state=state)

    def onset_drop(self) -> float:
        """The share of its strength a contact loses at once when it starts to slide: 0 for a
        strength that does not drop (the default), ``1 - mu_dynamic / mu_static`` for a drop
        from static to dynamic friction.

        ``dt="auto"`` takes more steps a period the larger it is (:mod:`dda.auto_settings`,
        rule 1: a slip starts only at the end of the step in which it is due, legacy DDA's up
        to a step late): a law whose strength drops at onset overrides it.
        """
        return 0.0

    def _kernel_parameters(self):
        """``(kind, mu_static, mu_dynamic, cohesion)`` for the compiled OPEN-CLOSE pass
        (:mod:`dda.kernels.open_close`), or None: only a built-in law of its own class has
        them (a subclass or a law written in numpy takes the numpy iteration)."""
        return None

    def trial_history(self, trial: FrictionTrial) -> dict[str, np.ndarray]:
        """The history a trial leaves: what the contact carries into the next step if the
        step that made the trial is accepted (the element asks for it on every trial)."""
        if type(self).commit is not FrictionLaw.commit:  # a law written for the old name
            return self.commit(trial)
        return trial.state

    def commit(self, trial: FrictionTrial) -> dict[str, np.ndarray]:
        """Old name of :meth:`trial_history` (it commits nothing); a law that overrides it
        is still asked through it."""
        return trial.state


class CoulombLike(FrictionLaw):
    """A law defined by its shear strength alone: it inherits the return map and the tangent.

    A trial ``t_tr = p_s (g_se + delta_g_s)`` above the strength ``S`` (:meth:`strength`)
    slips, and is returned radially to the sliding strength ``S_d`` (:meth:`sliding_strength`,
    ``S`` unless the law says otherwise)::

        t_s = t_tr                    if |t_tr| <= S      (stick)
        t_s = S_d sign(t_tr)          otherwise           (slip)

    The history keeps the elastic shear displacement ``g_se = t_s / p_s`` and the accumulated
    slip ``slip += |t_tr - t_s| / p_s``; :meth:`updated_history` adds a law's own fields. The
    consistent tangent follows from the strength's slope ``dS_d / d|t_n|``
    (:meth:`sliding_slope`): with ``t_n = p_n g_n`` in contact,

        d t_s / d g_s = p_s (stick), 0 (slip)
        d t_s / d g_n = 0 (stick), -p_n (dS_d / d|t_n|) sign(t_s) (slip)

    A subclass gives :meth:`strength` and :meth:`strength_slope` (both vectorized over its
    contacts; ``history`` is the committed history of those contacts), and optionally
    :meth:`history_fields` and :meth:`updated_history`. Check it with
    :func:`dda.contact.check_friction_law`.
    """

    @abstractmethod
    def strength(self, t_n: np.ndarray, length: np.ndarray,
                 history: dict[str, np.ndarray] | None = None) -> np.ndarray:
        """Shear strength S a trial force is checked against (N per m), per contact."""

    @abstractmethod
    def strength_slope(self, t_n: np.ndarray, length: np.ndarray,
                       history: dict[str, np.ndarray] | None = None):
        """``dS / d|t_n|`` per contact (an array or a number)."""

    def sliding_strength(self, t_n, length, history=None) -> np.ndarray:
        """The strength a slipping trial is returned to (default: :meth:`strength`)."""
        return self.strength(t_n, length, history)

    def sliding_slope(self, t_n, length, history=None):
        """``dS_d / d|t_n|`` of :meth:`sliding_strength` (default: :meth:`strength_slope`)."""
        return self.strength_slope(t_n, length, history)

    def slides(self, t_trial, strength, t_n, length, history, faces=None) -> np.ndarray:
        """Which trials slip (default: ``|t_tr| > S`` contact by contact)."""
        return np.abs(t_trial) > strength

    def updated_history(self, history: dict[str, np.ndarray],
                        slipping: np.ndarray) -> dict[str, np.ndarray]:
        """The law's own history fields after a trial (``slipping`` all False on the stick
        branch); ``g_se`` and ``slip`` are kept by the base. Default: none."""
        return {}

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length, faces=None):
        trial = self._compiled_return_map(committed, delta_g_s, t_n, shear_penalty, length,
                                          faces)
        if trial is not None:
            return trial
        return self._numpy_return_map(committed, delta_g_s, t_n, shear_penalty, length, faces)

    def _compiled_return_map(self, committed, delta_g_s, t_n, shear_penalty, length, faces):
        """The same trial from a compiled kernel (:mod:`dda.kernels.friction`), or None:
        a built-in law offers one for its own class only, so a subclass that overrides a part
        of the return map gets the numpy path that calls that part."""
        return None

    def _numpy_return_map(self, committed, delta_g_s, t_n, shear_penalty, length, faces=None):
        """The return map in numpy, from :meth:`strength`, :meth:`slides`,
        :meth:`sliding_strength` and :meth:`updated_history` (the reference)."""
        t_trial = shear_penalty * (committed["g_se"] + delta_g_s)
        check = self.strength(t_n, length, committed)
        slipping = self.slides(t_trial, check, t_n, length, committed, faces)
        t_s = np.where(slipping, self.sliding_strength(t_n, length, committed)
                       * np.sign(t_trial), t_trial)
        state = {"g_se": t_s / shear_penalty,
                 "slip": committed["slip"] + np.abs(t_trial - t_s) / shear_penalty}
        state.update(self.updated_history(committed, slipping))
        slope = self.sliding_slope(t_n, length, committed)
        return FrictionTrial(t_s=t_s, slipping=slipping, strength=check, state=state,
                             extra={"slope": slope})

    def tangent(self, trial, normal_penalty, shear_penalty):
        # t_n = p_n g_n < 0 in contact, so d|t_n|/d g_n = -p_n
        dts_dgs = np.where(trial.slipping, 0.0, shear_penalty)
        dts_dgn = np.where(trial.slipping,
                           -normal_penalty * trial.extra["slope"] * np.sign(trial.t_s), 0.0)
        return dts_dgs, dts_dgn

    def elastic_update(self, committed, delta_g_s):
        state = super().elastic_update(committed, delta_g_s)
        state.update(self.updated_history(committed,
                                          np.zeros(len(state["g_se"]), dtype=bool)))
        return state


class CoulombSingle(CoulombLike):
    """Coulomb friction with one angle and optional cohesion (METHOD.md section 4).

    Yield function ``f = |t_s| - (c l_c + |t_n| tan(phi))``; a trial above it is returned to
    the surface in the direction of the trial force.

    Parameters
    ----------
    phi : float
        Friction angle in degrees, in [0, 90).
    cohesion : float
        Cohesion c in Pa, applied over the contact's tributary length l_c.

    Examples
    --------
    >>> import numpy as np
    >>> law = CoulombSingle(phi=45.0)
    >>> trial = law.return_map(law.initial_state(2), np.array([1e-3, -1e-5]),
    ...                        np.array([-100.0, -100.0]), np.array([1e6, 1e6]), np.ones(2))
    >>> trial.t_s.round(6).tolist(), trial.slipping.tolist()
    ([100.0, -10.0], [True, False])
    """

    name = "coulomb"

    def __init__(self, phi: float, cohesion: float = 0.0):
        phi = finite_number("phi", phi, nonnegative=True, where="CoulombSingle")
        if phi >= 90.0:
            raise ValueError(f"CoulombSingle: phi is in degrees and must be below 90, got {phi}")
        self.phi = phi
        self.cohesion = finite_number("cohesion", cohesion, nonnegative=True, where="CoulombSingle")
        check_angle("phi", phi, "CoulombSingle")
        self.mu = float(np.tan(np.radians(phi)))

    def __repr__(self):
        return f"CoulombSingle(phi={self.phi}, cohesion={self.cohesion})"

    def strength(self, t_n, length, history=None):
        """Shear strength ``c l_c + |t_n| tan(phi)`` for compressive t_n (zero force when open)."""
        return self.cohesion * length + np.maximum(-t_n, 0.0) * self.mu

    def strength_slope(self, t_n, length, history=None):
        return self.mu

    def _kernel_parameters(self):
        if type(self) is not CoulombSingle:
            return None
        return COULOMB, self.mu, self.mu, self.cohesion

    def _compiled_return_map(self, committed, delta_g_s, t_n, shear_penalty, length, faces):
        if type(self) is not CoulombSingle:
            return None
        t_s, slipping, strength, g_se, slip = coulomb_return_map(
            *_float_arrays(committed["g_se"], committed["slip"], delta_g_s, t_n,
                           shear_penalty, length), self.mu, self.cohesion)
        return FrictionTrial(t_s=t_s, slipping=slipping, strength=strength,
                             state={"g_se": g_se, "slip": slip}, extra={"slope": self.mu})


class StaticDynamicTransition(CoulombLike):
    """Coulomb friction that drops from a static to a dynamic angle (METHOD.md section 6).

    - A sticking contact yields when ``|t_s^tr| > |t_n| tan(phi_static)``; the trial is then
      returned to the dynamic strength ``|t_n| tan(phi_dynamic)`` at once (S figure 1).
    - While it keeps sliding, the yield check uses ``phi_dynamic``.
    - A contact that sticks again must exceed ``phi_static`` to slide once more.

    The history field ``sliding`` (1.0 or 0.0) records whether the contact was sliding at the
    end of the last committed step.

    ``onset`` says what must exceed the static strength for sliding to start:

    - ``"face"`` (the default): the contacts of one face (:mod:`dda.contact.faces`) start
      sliding together, when the face's shear force exceeds its strength:
      ``|sum t_s| > sum |t_n| tan(phi)`` (``phi_static`` for the sticking contacts,
      ``phi_dynamic`` for the sliding ones, their force capped at the dynamic strength). This
      is a rigid block's rule, and a single vertex contact's: a corner contact is a face of its
      own, judged alone. Contacts that slide are checked one by one with ``phi_dynamic``.
    - ``"contact"`` (the papers' rule, Sasaki et al.): each vertex-edge contact on its own. The
      two contacts at the ends of a face share its shear force about equally, but any moment
      on the block (rocking, a load above the joint) presses one end more than the other, so
      the lightly pressed end yields first. Its force drops to the dynamic strength, the other
      end takes the difference and yields in turn: the face starts sliding before its total
      shear force reaches ``tan(phi_static)`` times its total normal force (a progressive
      failure that a rigid block does not have).

    What the per-contact rule costs where a face carries a moment (``tests/validation/
    test_onset.py`` runs the first two; the joints' default shear dashpot,
    :attr:`dda.contact.JointMaterial.shear_dashpot`, on where it acts):

    ========================================================  ===========  =========
    case                                                      ``contact``  ``face``
    ========================================================  ===========  =========
    block on a 20 deg slope, 0.5 g 2 Hz, 40/30 deg, 2 s:      +8.7 %       -0.1 %
    slide against Newmark's rigid block (Newton, dt 1e-3;     (+9.2 %)     (-0.1 %)
    without the shear dashpot in brackets)
    the same, legacy DDA                                      +7.8 %       -0.8 %
                                                              (+5.7 %)     (-0.8 %)
    simple shear of METHOD.md (30/20 deg), the upper block    512.4 kPa    573.1 kPa
    driven at its four corners: peak against 577.35 kPa       (-11 %)      (-0.7 %)
    (Newton)
    the same, legacy DDA (which overshoots by up to a step)   521.0 kPa    582.8 kPa
                                                              (-9.8 %)     (+0.9 %)
    rock slope of ``examples/rock_slope.py``, 16 s: largest   69 %         0.7 %
    gap to the rigid block's slide (Newton, dt 1e-3)          (16.5 %)     (0.7 %)
    ========================================================  ===========  =========

    Where the face carries no moment (the simple shear driven at the joint's level) the two
    rules agree. On the rock slope the shear dashpot moves the per-contact rule's start a
    whole level early (8.25 s against the rigid block's 10.22 s): the two ends of the base
    share its shear force by their history (at 1.9 s in the 4 s version, -22 N and 169 N
    with the dashpot, 3 N and 130 N without), so the lightly pressed end reaches
    ``tan(phi_static)`` at the level before. To reproduce the papers' per-contact results,
    use their joints: ``JointMaterial(..., shear_dashpot=False)``.

    Parameters
    ----------
    phi_static, phi_dynamic : float
        Friction angles in degrees, 0 <= phi_dynamic <= phi_static < 90.
    onset : {"face", "contact"}
        What must yield for sliding to start (see above); ``"face"`` by default.

    Examples
    --------
    >>> import numpy as np
    >>> law = StaticDynamicTransition(phi_static=30.0, phi_dynamic=20.0)
    >>> state = law.initial_state(1)
    >>> yielded = law.return_map(state, np.array([1.0]), np.array([-1.0]), np.array([1.0]),
    ...                          np.ones(1))
    >>> round(float(yielded.t_s[0]), 4), bool(yielded.slipping[0])  # tan(20 deg)
    (0.364, True)
    """

    name = "transition"
    ONSETS = ("face", "contact")

    def __init__(self, phi_static: float, phi_dynamic: float, onset: str = "face"):
        where = "StaticDynamicTransition"
        phi_s = finite_number("phi_static", phi_static, nonnegative=True, where=where)
        phi_d = finite_number("phi_dynamic", phi_dynamic, nonnegative=True, where=where)
        if phi_s >= 90.0:
            raise ValueError(f"{where}: phi_static is in degrees and must be below 90, got {phi_s}")
        if phi_d > phi_s:
            raise ValueError(
                f"{where}: phi_dynamic ({phi_d}) must not exceed phi_static ({phi_s})")
        if onset not in self.ONSETS:
            raise ValueError(f"{where}: onset must be one of {self.ONSETS}, got {onset!r}")
        self.phi_static, self.phi_dynamic = phi_s, phi_d
        self.onset = onset
        check_angle("phi_static", phi_s, where)
        check_angle("phi_dynamic", phi_d, where)
        self.mu_static = float(np.tan(np.radians(phi_s)))
        self.mu_dynamic = float(np.tan(np.radians(phi_d)))

    @property
    def uses_faces(self) -> bool:
        return self.onset == "face"

    def __repr__(self):
        onset = "" if self.onset == "face" else f", onset={self.onset!r}"
        return (f"StaticDynamicTransition(phi_static={self.phi_static}, "
                f"phi_dynamic={self.phi_dynamic}{onset})")

    def history_fields(self) -> dict[str, float]:
        return {"g_se": 0.0, "slip": 0.0, "sliding": 0.0}

    def onset_drop(self) -> float:
        """``1 - tan(phi_dynamic) / tan(phi_static)``: the strength lost at the onset of slip."""
        return 0.0 if self.mu_static == 0.0 else 1.0 - self.mu_dynamic / self.mu_static

    def strength(self, t_n, length, history=None):
        """``|t_n| tan(phi_dynamic)`` on contacts sliding at the step's start, else
        ``|t_n| tan(phi_static)``."""
        pressure = np.maximum(-t_n, 0.0)
        return np.where(history["sliding"] > 0.5, pressure * self.mu_dynamic,
                        pressure * self.mu_static)

    def strength_slope(self, t_n, length, history=None):
        return np.where(history["sliding"] > 0.5, self.mu_dynamic, self.mu_static)

    def sliding_strength(self, t_n, length, history=None):
        return np.maximum(-t_n, 0.0) * self.mu_dynamic

    def sliding_slope(self, t_n, length, history=None):
        return self.mu_dynamic

    def slides(self, t_trial, strength, t_n, length, history, faces=None):
        if faces is None:
            return np.abs(t_trial) > strength
        sliding = history["sliding"] > 0.5
        dynamic = self.sliding_strength(t_n, length)
        carried = np.where(sliding, np.clip(t_trial, -dynamic, dynamic), t_trial)
        face_yields = np.abs(faces.total(carried)) > faces.total(strength)
        return np.where(sliding, np.abs(t_trial) > dynamic, face_yields)

    def updated_history(self, history, slipping):
        return {"sliding": slipping.astype(float)}

    def _kernel_parameters(self):
        if type(self) is not StaticDynamicTransition:
            return None
        kind = TRANSITION_FACE if self.uses_faces else TRANSITION
        return kind, self.mu_static, self.mu_dynamic, 0.0

    def _compiled_return_map(self, committed, delta_g_s, t_n, shear_penalty, length, faces):
        if type(self) is not StaticDynamicTransition:
            return None
        face = _NO_FACES if faces is None else np.asarray(faces.index, dtype=np.int64)
        g_se, slip, sliding, dgs, tn, ps = _float_arrays(
            committed["g_se"], committed["slip"], committed["sliding"], delta_g_s, t_n,
            shear_penalty)
        t_s, slipping, strength, g_out, slip_out = transition_return_map(
            g_se, slip, sliding, dgs, tn, ps, self.mu_static, self.mu_dynamic, face)
        return FrictionTrial(
            t_s=t_s, slipping=slipping, strength=strength,
            state={"g_se": g_out, "slip": slip_out, "sliding": slipping.astype(float)},
            extra={"slope": self.mu_dynamic})


_NO_FACES = np.zeros(0, dtype=np.int64)


def _float_arrays(*arrays):
    """The arrays as the kernels take them (float64; a view when they already are)."""
    return tuple(np.asarray(a, dtype=np.float64) for a in arrays)
