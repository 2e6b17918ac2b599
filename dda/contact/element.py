"""The generic vertex-edge contact element, vectorized over every contact of a step.

It owns the kinematics of the step's contacts (METHOD.md section 3), asks each friction law for
forces and tangents of its contacts (section 4), and returns stiffness and force contributions
for one sparse assembly: the stiffness as rank-one terms (:class:`dda.kernels.PairStiffness`,
an (m, 12, 12) array on request), the forces as an (m, 12) array.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from dda.contact.contacts import OPEN, SLIP, STICK, ContactSet
from dda.contact.faces import Faces, contact_faces
from dda.contact.friction import FrictionLaw
from dda.contact.kinematics import (
    ContactGeometry,
    contact_geometry,
    pair_maps,
    trial_kinematics,
    tributary_length,
)
from dda.contact.tangent import SPRING_TERMS, consistent_tangent
from dda.errors import FrictionLawError
from dda.kernels.dashpot import add_dashpot
from dda.kernels.element import element_arrays
from dda.kernels.kinematics import pair_increments as _pair_increments
from dda.kernels.open_close import (
    as_float64,
    contact_response,
    kernel_history,
    kernel_history_dict,
)
from dda.kernels.pair_stiffness import PairStiffness, legacy_springs
from dda.profiling import section

__all__ = ["ContactElement", "LawGroups", "KERNEL_LAWS"]

_NO_DAMPING = np.zeros(0)

#: the built-in laws take the compiled paths of :mod:`dda.kernels.open_close` (OPEN-CLOSE's
#: passes, legacy DDA's step end, the fully implicit method's contact response); False: the
#: numpy paths every law takes, the reference the compiled ones are tested against
KERNEL_LAWS = True


_LAST_ONE_LAW = (None, None, -1, None)


def _one_law_arrays(law, numbers, m):
    """``(kind, mu_static, mu_dynamic, cohesion, no face)`` of ``m`` contacts of one law: the
    arrays of the last call when it was for the same law, numbers and ``m`` (a scene with
    one law asks for the same ones every step; the kernels only read them)."""
    global _LAST_ONE_LAW
    last_law, last_numbers, last_m, arrays = _LAST_ONE_LAW
    if last_law is law and last_m == m and last_numbers == numbers:
        return arrays
    arrays = (np.full(m, numbers[0], dtype=np.int64),
              *(np.full(m, float(v)) for v in numbers[1:]), np.full(m, -1, dtype=np.int64))
    _LAST_ONE_LAW = (law, numbers, m, arrays)
    return arrays


@dataclass
class LawGroups:
    """Contacts grouped by the friction law they share: ``[(law, indices), ...]``.

    ``faces`` says which contacts form one face; it is only needed (and only set, by
    :class:`ContactElement`) when a law judges faces as a whole (``law.uses_faces``).
    """

    groups: list[tuple[FrictionLaw, np.ndarray]]
    faces: Faces | None = None
    #: the step's size (s), given to the return map of a law that asks for it
    #: (``FrictionLaw.uses_dt``); None: not known (a law that needs it raises)
    dt: float | None = None

    @property
    def uses_faces(self) -> bool:
        return any(law.uses_faces for law, _ in self.groups)

    @classmethod
    def build(cls, law_index: np.ndarray, laws: list[FrictionLaw]) -> LawGroups:
        groups = []
        for i in np.unique(law_index):
            groups.append((laws[int(i)], np.flatnonzero(law_index == i)))
        return cls(groups)

    def initial_history(self, history: dict[str, np.ndarray], mask: np.ndarray,
                        new: np.ndarray | None = None) -> None:
        """Give the contacts in ``mask`` (open ones) the initial history of their law, in
        place: all of it to those in ``new`` (found anew), and to the others the fields their
        law does not keep while open (:meth:`dda.contact.FrictionLaw.kept_when_open`).
        ``new`` None: no contact is new."""
        for law, idx in self.groups:
            sel = idx[mask[idx]]
            if len(sel) == 0:
                continue
            kept = law.kept_when_open()
            for k, v in law.initial_state(len(sel)).items():
                out = history.setdefault(k, np.zeros(len(mask)))
                if k not in kept:
                    out[sel] = v
                elif new is not None:
                    fresh = new[sel]
                    out[sel[fresh]] = np.asarray(v)[fresh]

    def kernel_laws(self, m: int):
        """The laws as per-contact numbers for the compiled OPEN-CLOSE pass
        (:mod:`dda.kernels.open_close`): ``(kind, mu_static, mu_dynamic, cohesion, face)``,
        or None when a law has none (a law written in numpy, a subclass of a built-in one).
        ``face`` keys a face-judged contact's face within its law (-1 elsewhere)."""
        if len(self.groups) == 1:  # one law: no scatter
            law = self.groups[0][0]
            numbers = law._kernel_parameters()
            if numbers is None:
                return None
            kind, mu_s, mu_d, cohesion, no_face = _one_law_arrays(law, numbers, m)
            face = (np.asarray(self.faces.index, dtype=np.int64) if law.uses_faces
                    else no_face)
            return kind, mu_s, mu_d, cohesion, face
        kind = np.zeros(m, dtype=np.int64)
        mu_s, mu_d, cohesion = np.zeros(m), np.zeros(m), np.zeros(m)
        face = np.full(m, -1, dtype=np.int64)
        for g, (law, idx) in enumerate(self.groups):
            numbers = law._kernel_parameters()
            if numbers is None:
                return None
            kind[idx], mu_s[idx], mu_d[idx], cohesion[idx] = numbers
            if law.uses_faces:
                face[idx] = self.faces.index[idx] * len(self.groups) + g
        return kind, mu_s, mu_d, cohesion, face

    def _select(self, history, law, idx):
        return {k: history[k][idx] for k in law.history_fields()}

    def return_map(self, history, delta_g_s, t_n, shear_penalty, length, where=None,
                   normal_penalty=None):
        """Return map of every contact (or those in ``where``) through its own law.

        Returns shear force, slipping flag and the trial history as full-length arrays; with
        ``normal_penalty`` given, also the consistent tangent (d t_s/d g_s, d t_s/d g_n).
        """
        with section("return_map"):
            return self._return_map(history, delta_g_s, t_n, shear_penalty, length, where,
                                    normal_penalty)

    def _return_map(self, history, delta_g_s, t_n, shear_penalty, length, where,
                    normal_penalty):
        m = len(delta_g_s)
        t_s = np.zeros(m)
        slipping = np.zeros(m, dtype=bool)
        dts_dgs = np.zeros(m)
        dts_dgn = np.zeros(m)
        trial_history = {k: v.copy() for k, v in history.items()}
        for law, idx in self.groups:
            if where is not None:
                idx = idx[where[idx]]
            if len(idx) == 0:
                continue
            args = (self._select(history, law, idx), delta_g_s[idx], t_n[idx],
                    shear_penalty[idx], length[idx])
            kw = {}
            if law.uses_faces:
                kw["faces"] = self.faces.subset(idx) if self.faces is not None else None
            if law.uses_dt:
                if self.dt is None:
                    raise FrictionLawError(f"friction law {law!r} needs the step's dt, which "
                                           "this call does not know")
                kw["dt"] = self.dt
            trial = law.return_map(*args, **kw)
            t_s[idx] = trial.t_s
            _check_finite(law, "return_map", "shear force", t_s[idx], args)
            slipping[idx] = trial.slipping
            for k, v in law.trial_history(trial).items():
                trial_history[k][idx] = v
            if normal_penalty is not None:
                dts_dgs[idx], dts_dgn[idx] = law.tangent(trial, normal_penalty[idx],
                                                         shear_penalty[idx])
                _check_finite(law, "tangent", "tangent", dts_dgs[idx] + dts_dgn[idx], args)
        if normal_penalty is not None:
            return t_s, slipping, trial_history, (dts_dgs, dts_dgn)
        return t_s, slipping, trial_history

    def stick(self, history, delta_g_s, shear_penalty, where):
        """Every contact in ``where`` locked on its elastic branch through its own law.

        Returns the shear force (zero outside ``where``) and the history (a copy; the
        contacts outside ``where`` keep theirs).
        """
        with section("return_map"):
            t_s = np.zeros(len(delta_g_s))
            out = {k: v.copy() for k, v in history.items()}
            for law, idx in self.groups:
                idx = idx[where[idx]]
                if len(idx) == 0:
                    continue
                committed, dgs, ps = (self._select(history, law, idx), delta_g_s[idx],
                                      shear_penalty[idx])
                trial = law.stick(committed, dgs, ps)
                t_s[idx] = trial.t_s
                _check_finite(law, "stick", "shear force", t_s[idx],
                              (committed, dgs, None, ps, None))
                for k, v in law.trial_history(trial).items():
                    out[k][idx] = v
            return t_s, out


def _check_finite(law, method: str, what: str, values: np.ndarray, args) -> None:
    """Raise :class:`dda.errors.FrictionLawError` when ``law.method`` gave a non-finite
    ``values`` for a contact whose inputs ``args`` (history, shear increment, normal force,
    shear penalty, length; None where not given) are all finite: the law's defect, which a
    smaller dt would only hide (under Newton-Raphson a law that gave NaN on its slip branch
    took steps of 7e-15 s, where nothing slips, for ever)."""
    bad = ~np.isfinite(values)
    if not bad.any():
        return
    history, dgs, t_n, ps, length = args
    inputs = [dgs, ps, *history.values()] + [a for a in (t_n, length) if a is not None]
    ok = np.ones(len(values), dtype=bool)
    for a in inputs:
        ok &= np.isfinite(np.asarray(a, dtype=float))
    blamed = np.flatnonzero(bad & ok)
    if len(blamed) == 0:
        return  # non-finite inputs: the step fails and is cut as any other
    i = int(blamed[0])
    state = ", ".join(f"{k} = {float(v[i]):.6g}" for k, v in history.items())
    normal = f"t_n = {float(t_n[i]):.6g} N/m, " if t_n is not None else ""
    name = repr(law) if repr(law).startswith(type(law).__name__) else (
        f"{type(law).__name__} ({law!r})")
    raise FrictionLawError(
        f"friction law {name}: {method}() returned a non-finite {what} ({values[i]}) for "
        f"{len(blamed)} of {len(values)} contacts from finite inputs; the first: "
        f"{normal}shear increment {float(dgs[i]):.6g} m, shear penalty {float(ps[i]):.6g} "
        f"N/m, history {{{state}}} (dda.contact.check_friction_law tests a law)")


@dataclass
class ContactResponse:
    """Forces, states and the linearization of every contact at one trial state.

    ``stiffness`` (the consistent tangent, a :class:`PairStiffness`: (m, 12, 12) on request by
    ``np.asarray``) is built when first asked for: a Newton iterate that has converged never
    needs it. ``tangent`` is what builds it (or the stiffness itself)."""

    closed: np.ndarray
    slipping: np.ndarray
    t_n: np.ndarray
    t_s: np.ndarray
    history: dict[str, np.ndarray]
    residual: np.ndarray
    tangent: object  # a callable () -> PairStiffness, or the PairStiffness
    #: the normal force that decides closed (with an impact dashpot, the spring's and the
    #: dashpot's; ``t_n`` is the spring's alone), None where not given
    force: np.ndarray | None = None

    @cached_property
    def stiffness(self) -> PairStiffness:
        return self.tangent() if callable(self.tangent) else self.tangent

    #: a callable ``stick -> (PairStiffness, residual rows)``: the contacts of the mask
    #: ``stick`` on their stick branch (:meth:`stick_branch`), None where not given
    stick: object = None

    def stick_branch(self, stick: np.ndarray) -> tuple[PairStiffness, np.ndarray]:
        """The tangent and the residual rows with the closed contacts of the mask ``stick``
        (m,) on the elastic branch of their law, whatever the return map gave them:

            t_s = p_s (g_se + dg_s),   dt_s/dg_s = p_s,   dt_s/dg_n = 0

        (their law's :meth:`~dda.contact.FrictionLaw.stick`, from the committed history);
        their normal force, the other contacts and the geometric terms are the response's.
        A Newton step from them is the step of the branch on which those contacts stick
        (:data:`dda.solvers.newton.REVERSED_STICK`)."""
        if self.stick is None:
            raise TypeError("ContactResponse: this response has no stick branch")
        return self.stick(stick)


class ContactElement:
    """Vertex-edge penalty contacts of one step.

    Legacy DDA uses the rows linearized at the step's start (:meth:`linear_gaps`,
    :meth:`legacy_contributions`); the fully implicit method evaluates the contacts exactly at
    every trial state with the consistent tangent (:meth:`response`).

    Parameters
    ----------
    contacts : ContactSet
        The step's contacts with their committed history.
    x : (n_vertices, 2) vertex positions at the start of the step
    centroids : (n_blocks, 2) block centroids at the start of the step
    nxt, prv : vertex neighbours (see :class:`dda.contact.detection.VertexTopology`)
    normal_penalty, shear_penalty : (m,) penalties of each contact's joint
    laws : LawGroups
    geometry : ContactGeometry, optional
        The contacts' geometry at ``x`` when it is at hand (computed otherwise).
    dashpot : (m,) array, optional
        Each contact's impact dashpot as a stiffness on the step's change of its normal gap,
        ``c / dt`` (:mod:`dda.contact.dashpot`); None: no dashpot.

    Attributes
    ----------
    shear_dashpot : tuple or None
        Set by the step when the contacts' shear dashpots are in ``shear_penalty`` (which is
        then ``p_s + c_s / dt``) and in the history's ``g_se``: ``(p_s, c_s / dt, g_se0)``,
        what :func:`dda.contact.dashpot.shear_dashpot_end` needs at the step's end.
    gap_round_off : (m,) array or None
        The round-off of each contact's linearized gap, when :meth:`compiled` computed it
        (:func:`dda.solvers.open_close.round_off_gap`).
    """

    shear_dashpot = None
    gap_round_off = None

    def __init__(self, contacts: ContactSet, x, centroids, nxt, prv, normal_penalty,
                 shear_penalty, laws: LawGroups, geometry: ContactGeometry | None = None,
                 dashpot: np.ndarray | None = None):
        self.dashpot = dashpot
        if len(contacts) == 0:  # a step without contacts does no contact work
            self._build_empty(contacts, normal_penalty, shear_penalty, laws)
            return
        with section("contact_element"):
            self._build(contacts, x, centroids, nxt, prv, normal_penalty, shear_penalty, laws,
                        geometry)

    @classmethod
    def compiled(cls, contacts: ContactSet, x, centroids, nxt, prv, normal_penalty,
                 shear_penalty, laws: LawGroups, geometry: ContactGeometry | None, blocks,
                 dt: float, round_off: tuple[float, float], zeta=None,
                 zeta_s=None) -> ContactElement:
        """The element of a step with every law-independent array from one kernel call
        (:func:`dda.kernels.element.element_arrays`): the same arrays as the constructor's,
        and, where ``zeta`` / ``zeta_s`` give the contacts' impact / shear dashpot damping
        ratios, the dashpots the step adds (:mod:`dda.contact.dashpot`; the shear one into
        ``shear_penalty``, the history's ``g_se`` and :attr:`shear_dashpot`).

        ``blocks`` is ``(free, density, area, sxx, syy)`` of the blocks at the step's start
        (the contact masses); ``dt`` the step (s); ``round_off`` the relative and absolute
        round-off of a linearized gap (:func:`dda.solvers.open_close.round_off_gap`, kept as
        :attr:`gap_round_off`).
        """
        if len(contacts) == 0:
            return cls(contacts, x, centroids, nxt, prv, normal_penalty, shear_penalty, laws,
                       geometry)
        self = cls.__new__(cls)
        with section("contact_element"):
            if geometry is None:
                geometry = contact_geometry(x, contacts.vertex, contacts.edge, nxt)
            if laws.uses_faces:
                laws = LawGroups(laws.groups, contact_faces(x, contacts.vertex, contacts.edge,
                                                            nxt, prv))
            g = geometry
            pn, ps = as_float64(normal_penalty), as_float64(shear_penalty)
            g_se = contacts.history.get("g_se") if zeta_s is not None else None
            if g_se is None:
                zeta_s = None
            no = _NO_DAMPING
            (length, maps, shear0, e_row, i_row, rows, gap_tol, dashpot, reference, release,
             judge, shear_dashpot, ps_eff, g_se_scaled) = element_arrays(
                as_float64(x), as_float64(centroids), nxt, prv, contacts.vertex, contacts.edge,
                contacts.bj, contacts.bk, as_float64(contacts.xi0), as_float64(g.p1),
                as_float64(g.p2), as_float64(g.p3), as_float64(g.length), as_float64(g.tau),
                as_float64(g.normal), as_float64(g.gap), pn, ps,
                no if g_se is None else as_float64(g_se),
                no if zeta is None else as_float64(zeta),
                no if zeta_s is None else as_float64(zeta_s), *blocks, float(dt),
                float(round_off[0]), float(round_off[1]))
        self.contacts, self.bj, self.bk = contacts, contacts.bj, contacts.bk
        self.normal_penalty, self.shear_penalty = normal_penalty, shear_penalty
        self.laws, self.geometry = laws, g
        self.gap0, self.shear0, self.length = g.gap, shear0, length
        self.maps = (maps[0], maps[1], maps[2])
        self.e_row, self.i_row = e_row, i_row
        self.gap_round_off = gap_tol
        # the lazily computed properties, computed
        self.__dict__.update(_spring_rows=rows, dashpot_reference=reference)
        self.dashpot = None
        if zeta is not None:
            self.dashpot = dashpot
            self.__dict__.update(release=release, judge_stiffness=judge)
        if zeta_s is not None:
            g_se0 = np.array(g_se, dtype=float)
            self.shear_penalty = ps_eff
            contacts.history["g_se"] = g_se_scaled
            self.shear_dashpot = (ps, shear_dashpot, g_se0)
        return self

    def _build_empty(self, contacts, normal_penalty, shear_penalty, laws):
        self.contacts = contacts
        self.bj, self.bk = contacts.bj, contacts.bk
        self.normal_penalty, self.shear_penalty = normal_penalty, shear_penalty
        self.laws = laws
        z, z2 = np.zeros(0), np.zeros((0, 2))
        self.geometry = ContactGeometry(z2, z2, z2, z, z2, z2, z, z)
        self.gap0 = self.shear0 = self.length = z
        self.maps = tuple(np.zeros((0, 2, 12)) for _ in range(3))
        self.e_row = self.i_row = np.zeros((0, 12))

    def _build(self, contacts, x, centroids, nxt, prv, normal_penalty, shear_penalty, laws,
               geom):
        self.contacts = contacts
        self.bj = contacts.bj
        self.bk = contacts.bk
        self.normal_penalty = normal_penalty
        self.shear_penalty = shear_penalty
        if laws.uses_faces:
            faces = contact_faces(x, contacts.vertex, contacts.edge, nxt, prv)
            laws = LawGroups(laws.groups, faces)
        self.laws = laws
        if geom is None:
            geom = contact_geometry(x, contacts.vertex, contacts.edge, nxt)
        self.geometry = geom
        self.gap0 = geom.gap
        self.shear0 = geom.shear_gap(contacts.xi0)
        self.length = tributary_length(x, contacts.vertex, geom, prv, nxt)
        self.maps = pair_maps(x, contacts.vertex, contacts.edge, nxt, centroids[contacts.bj],
                              centroids[contacts.bk])
        start = trial_kinematics(geom.p1, geom.p2, geom.p3, contacts.xi0, self.maps,
                                 second=False)
        self.e_row, self.i_row = start.e_row, start.i_row

    def __len__(self):
        return len(self.bj)

    # -- the door to the friction laws: solvers ask the element, never a law or its history
    def friction(self, history, delta_g_s, t_n, where):
        """Return map of the contacts in ``where`` from ``history`` through their own laws.

        Returns ``(t_s, slipping, trial_history)``, full length (zero force elsewhere).
        """
        return self.laws.return_map(history, delta_g_s, t_n, self.shear_penalty, self.length,
                                    where=where)

    def stick(self, history, delta_g_s, where):
        """Shear force and history of the contacts in ``where`` locked on their elastic
        branch (:meth:`dda.contact.FrictionLaw.stick`): legacy DDA's stick spring."""
        return self.laws.stick(history, delta_g_s, self.shear_penalty, where)

    @cached_property
    def kernel_laws(self):
        """The contacts' laws for the compiled OPEN-CLOSE pass (:meth:`LawGroups.kernel_laws`),
        or None: a law without a kernel, or history fields the kernels do not keep."""
        if not KERNEL_LAWS:
            return None
        fields = set(self.contacts.history)
        if not ({"g_se", "slip"} <= fields <= {"g_se", "slip", "sliding"}):
            return None
        laws = self.laws.kernel_laws(len(self))
        if laws is not None and "sliding" not in fields and np.any(laws[0] != 0):
            return None
        return laws

    @cached_property
    def dashpot_reference(self) -> np.ndarray:
        """(m,) the gap an impact dashpot's rate is measured from: the gap at the step's
        start, or 0 for a contact that starts the step open (a dashpot acts on the
        penetration only, never across a gap): ``t_d = (c / dt)(g_n - min(g_n0, 0))``."""
        return np.minimum(self.gap0, 0.0)

    @cached_property
    def release(self) -> np.ndarray:
        """(m,) the gap below which each contact is closed: 0 without an impact dashpot
        (:mod:`dda.contact.dashpot`); with one, the gap at which the spring's and the
        dashpot's forces cancel, ``p_n g + (c / dt)(g - g_ref) = 0`` (:attr:`dashpot_reference`),
        at or below 0. A contact that opens lets go as its force reaches zero, without the
        pull of a dashpot that resists its opening, and the normal force is continuous."""
        if self.dashpot is None:
            return np.zeros(len(self))
        return self.dashpot * self.dashpot_reference / (self.normal_penalty + self.dashpot)

    @cached_property
    def judge_stiffness(self) -> np.ndarray:
        """(m,) the normal force's stiffness on the gap measured from :attr:`release`:
        ``p_n``, or ``p_n + c / dt`` with an impact dashpot, whose normal force (the spring's
        and the dashpot's) is ``(p_n + c / dt)(g_n - release)``."""
        if self.dashpot is None:
            return self.normal_penalty
        return self.normal_penalty + self.dashpot

    def spring_force(self, closed: np.ndarray, gap: np.ndarray, t_n: np.ndarray) -> np.ndarray:
        """The normal force a contact keeps at the step's end: its spring's ``p_n g_n`` where
        ``closed`` (``t_n``, the normal force with ``gap``, itself without a dashpot)."""
        if self.dashpot is None:
            return np.minimum(t_n, 0.0)
        return np.where(closed, np.minimum(self.normal_penalty * gap, 0.0), 0.0)

    def judged_gap(self, gap: np.ndarray) -> np.ndarray:
        """The gaps OPEN-CLOSE judges a contact by: ``gap`` less :attr:`release` (``gap``
        itself without a dashpot), so that the contact is closed where it is negative and
        :attr:`judge_stiffness` times it is the normal force the friction law sees."""
        return gap if self.dashpot is None else gap - self.release

    def legacy_trial(self, history, delta_g_s, t_n, state):
        """Legacy DDA's end of a step: sticking contacts keep their spring (no yield check:
        the pull-back of the next step cuts any excess), sliding ones are returned to the
        strength. Returns the shear force and the history (a copy)."""
        stick, slip = state == STICK, state == SLIP
        t_stick, history_out = self.stick(history, delta_g_s, where=stick)
        t_slip, _, slip_history = self.friction(history, delta_g_s, t_n, where=state != OPEN)
        for key, v in slip_history.items():
            history_out[key][slip] = v[slip]
        return np.where(stick, t_stick, 0.0) + np.where(slip, t_slip, 0.0), history_out

    def trial_contacts(self, state, t_n, t_s, history) -> ContactSet:
        """The step's trial contact set; open contacts get their law's initial history
        (written into ``history``, which the set takes over)."""
        self.laws.initial_history(history, state == OPEN)
        c = self.contacts
        return ContactSet(c.vertex, c.edge, c.bj, c.bk, state, c.xi0.copy(), t_n, t_s, history,
                          c.held_ago)

    def pair_increments(self, d: np.ndarray) -> np.ndarray:
        """(m, 12) increments [d_j; d_k] of each contact's two blocks from (n_blocks, 6) d."""
        return _pair_increments(as_float64(d), np.asarray(self.bj, dtype=np.int64),
                                np.asarray(self.bk, dtype=np.int64))

    def linear_gaps(self, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Normal gap and shear increment linearized at the step's start: g_n0 + E d, I d."""
        with section("contact_element"):
            dd = self.pair_increments(d)
            gap = self.gap0 + np.einsum("mi,mi->m", self.e_row, dd)
            dgs = np.einsum("mi,mi->m", self.i_row, dd)
            return gap, dgs

    def legacy_contributions(self, state, t_stick, t_s_slip):
        """Stiffness and force of original DDA's springs (METHOD.md section 4, legacy terms).

        Closed contacts: normal spring ``p_n E^T E`` with force ``-p_n g_n0 E^T`` (and the
        impact dashpot's ``(c / dt) E^T E``, :meth:`with_dashpot`); stick: shear spring
        ``p_s I^T I`` with force ``-t_stick I^T`` (``t_stick``: the spring's force at the
        step's start, :meth:`stick` with no increment); slip: the friction force ``-t_s I^T``
        as a load.

        Returns
        -------
        k : PairStiffness, the (m, 12, 12) stiffness as rank-one terms
        f : (m, 12)
        """
        with section("contact_element"):
            return self._legacy_contributions(state, t_stick, t_s_slip)

    def _legacy_contributions(self, state, t_stick, t_s_slip):
        f64 = np.float64
        weights, f = legacy_springs(
            np.asarray(state, dtype=np.int8), *(np.ascontiguousarray(a, dtype=f64) for a in (
                self.gap0, self.normal_penalty, self.shear_penalty, t_stick, t_s_slip,
                self.e_row, self.i_row)))
        self.with_dashpot(weights, f, state)
        return PairStiffness.checked_by_caller(self._spring_rows, SPRING_TERMS, weights), f

    def with_dashpot(self, weights: np.ndarray, force: np.ndarray, state: np.ndarray):
        """Legacy DDA's spring weights ``(k_n, k_s)`` and forces with each closed contact's
        impact dashpot (:mod:`dda.contact.dashpot`), in place: ``c / dt`` added to ``k_n``
        and ``-(c / dt)(g_n0 - g_ref) E^T`` to the force, the dashpot's
        ``(c / dt)(g_n0 + E d - g_ref)`` on the linearized gap (``g_ref``:
        :attr:`dashpot_reference`; the force term only on a contact that starts open)."""
        if self.dashpot is None:
            return
        if KERNEL_LAWS:
            add_dashpot(weights, force, np.asarray(state, dtype=np.int8),
                        as_float64(self.dashpot), as_float64(self.gap0),
                        self.dashpot_reference, as_float64(self.e_row))
            return
        cd = np.where(state != OPEN, self.dashpot, 0.0)
        weights[:, 0] += cd
        force -= (cd * (self.gap0 - self.dashpot_reference))[:, None] * self.e_row

    @cached_property
    def _spring_rows(self) -> np.ndarray:
        """(m, 2, 12) the rows E and I of legacy DDA's springs (fixed within the step)."""
        rows = np.empty((len(self.e_row), 2, 12))
        rows[:, 0] = self.e_row
        rows[:, 1] = self.i_row
        return rows

    def response(self, d: np.ndarray, held: np.ndarray | None = None) -> ContactResponse:
        """Contact forces and consistent tangent at the trial increments d (METHOD.md s. 3-4).

        The trial positions are ``X + T(X) d``. Per closed contact (g_n < 0), with the law's
        return map giving t_s and its tangent (k_ss, k_sn):

            r = t_n E^T + t_s I^T
            K = p_n E^T E + t_n (Delta delta g_n) + I^T (k_ss I + k_sn E) + t_s (Delta delta g_s)

        k_sn couples the normal and the shear gap on a slipping contact (unsymmetric K).
        With an impact dashpot (:mod:`dda.contact.dashpot`) ``t_n`` (in ``r``, in the
        geometric term and for the law) is the spring's and the dashpot's,
        ``p_n g_n + (c / dt)(g_n - g_ref)`` (:attr:`dashpot_reference`), ``p_n`` in the first
        term and in the law's tangent is ``p_n + c / dt``, and a contact is closed while that
        force is compressive (``g_n`` below :attr:`release`); the returned ``t_n`` is the
        spring's alone (what the next step starts from, the guard measures depth by and the
        energy counts).
        The contacts of the mask ``held`` (m,) are closed whatever their gap (Newton's hold
        of a contact that cycles, :data:`dda.solvers.newton.HOLD_CYCLING`): where the gap is
        open their spring pulls, ``t_n = p_n g_n > 0``, their strength is the law's at zero
        normal force (``k_sn = 0``), and the normal force they keep is ``min(p_n g_n, 0)``.
        Every trial starts from the committed history, so nothing here needs undoing.
        """
        with section("contact_element"):
            return self._response(d, held)

    def _response(self, d: np.ndarray, held: np.ndarray | None = None) -> ContactResponse:
        dd = self.pair_increments(d)
        a1, a2, a3 = self.maps
        g = self.geometry
        p1 = g.p1 + np.einsum("mij,mj->mi", a1, dd)
        p2 = g.p2 + np.einsum("mij,mj->mi", a2, dd)
        p3 = g.p3 + np.einsum("mij,mj->mi", a3, dd)
        kin = trial_kinematics(p1, p2, p3, self.contacts.xi0, self.maps, second=False)
        ps, kn = self.shear_penalty, self.judge_stiffness
        xi0 = self.contacts.xi0
        if self.kernel_laws is not None:
            with section("return_map"):
                (closed, slipping, spring, t_s, g_se, slip, sliding, kss, ksn, t_n,
                 residual) = contact_response(
                    *self.kernel_laws, *kernel_history(self.contacts.history, len(self)),
                    kin.gap, kin.shear, as_float64(self.shear0), as_float64(self.release),
                    self.dashpot is not None, as_float64(kn), as_float64(self.normal_penalty),
                    as_float64(ps), as_float64(self.length), kin.e_row, kin.i_row,
                    np.zeros(len(self), dtype=bool) if held is None else held)
            history = kernel_history_dict(self.contacts.history, g_se, slip, sliding)
        else:
            # the normal force (with an impact dashpot, the spring's and the dashpot's) on the
            # exact gap
            judged = self.judged_gap(kin.gap)
            closed = judged < 0.0
            if held is not None:
                closed = closed | held
            t_n = np.where(closed, kn * judged, 0.0)
            dgs = kin.shear - self.shear0
            # a held contact's pull is no compression to its law (a law written with |t_n|
            # would read it as one), and its strength does not change with g_n
            t_s, slipping, history, (kss, ksn) = self.laws.return_map(  # with the tangent
                self.contacts.history, dgs, np.minimum(t_n, 0.0), ps, self.length,
                where=closed, normal_penalty=kn)
            ksn = np.where(t_n > 0.0, 0.0, ksn)
            slipping = slipping & closed
            residual = t_n[:, None] * kin.e_row + t_s[:, None] * kin.i_row
            spring = self.spring_force(closed, kin.gap, t_n)

        def tangent(stick=None):
            k_ss, k_sn = kss, ksn
            if stick is not None:  # these contacts on their stick branch
                k_ss = np.where(stick, ps, kss)
                k_sn = np.where(stick, 0.0, ksn)
            with section("contact_element"):
                return consistent_tangent(kin, self.maps, xi0, np.where(closed, kn, 0.0), k_ss,
                                          k_sn, t_n, t_s, closed)

        def stick_branch(stick):
            stick = stick & closed
            t_stick = self.laws.stick(self.contacts.history, kin.shear - self.shear0, ps,
                                      stick)[0]
            rows = residual + np.where(stick, t_stick - t_s, 0.0)[:, None] * kin.i_row
            return tangent(stick), rows

        return ContactResponse(closed, slipping, spring, t_s, history, residual, tangent, t_n,
                               stick_branch)
