"""The contacts of a scene as a structure of arrays, carried from step to step.

A contact is identified by its (vertex, edge) pair. Its history (state, shear reference point,
forces and the friction law's fields) follows it while the pair persists, and moves with the
vertex when it slides onto an adjacent edge of the same block; a contact that opens loses its
forces and its law's fields but those its law keeps (:meth:`dda.contact.FrictionLaw.
kept_when_open`), which start again from the law's initial values when it closes
(``docs/friction_laws.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda.contact.detection import CandidateContacts
from dda.contact.kinematics import ContactGeometry, contact_geometry
from dda.kernels.open_close import HELD_NEVER, own_measures

__all__ = ["OPEN", "STICK", "SLIP", "HELD_NEVER", "ContactSet", "carry_over", "held_ago",
           "pair_key"]

OPEN, STICK, SLIP = 0, 1, 2
STATE_NAMES = ("open", "stick", "slip")


def pair_key(a, b, n_blocks: int):
    """One integer per unordered block pair: ``min(a, b) n_blocks + max(a, b)``.

    Sorting by it groups a pair's contacts; the joint table and the results look pairs up
    by it.
    """
    return np.minimum(a, b) * n_blocks + np.maximum(a, b)


@dataclass
class ContactSet:
    """Contacts as arrays (length m), with the committed state of each.

    Attributes
    ----------
    vertex, edge : vertex index and CCW edge start index (stacked vertex numbering)
    bj, bk : the vertex's block and the edge's block
    state : OPEN, STICK or SLIP at the end of the last committed step
    xi0 : edge parameter of the shear reference point x0' (METHOD.md section 3)
    t_n, t_s : committed normal (negative in compression) and shear force, N per m
    history : the friction laws' history fields, each an (m,) array
    held_ago : (m,) int64, as of the start of the step that made this set: how many steps
        before it the contact last ended a step closed at zero normal force (1: the step
        just before; :data:`HELD_NEVER` for never, and for a contact found anew), which is
        how a contact that OPEN-CLOSE's cycle rule held ends its step. Legacy DDA measures
        the cycle rule's limit of a contact held within its last ``cycle_memory`` steps on
        its own blocks (:mod:`dda.solvers.open_close`). None (the default): never held.
    """

    vertex: np.ndarray
    edge: np.ndarray
    bj: np.ndarray
    bk: np.ndarray
    state: np.ndarray
    xi0: np.ndarray
    t_n: np.ndarray
    t_s: np.ndarray
    history: dict[str, np.ndarray]
    held_ago: np.ndarray | None = None

    def __post_init__(self):
        if self.held_ago is None:
            self.held_ago = np.full(len(self.vertex), HELD_NEVER, dtype=np.int64)

    def __len__(self):
        return len(self.vertex)

    @classmethod
    def empty(cls, fields) -> ContactSet:
        z = np.zeros(0)
        zi = np.zeros(0, dtype=np.int64)
        return cls(zi, zi, zi, zi, np.zeros(0, dtype=np.int8), z, z, z,
                   {k: z.copy() for k in fields})

    def copy(self) -> ContactSet:
        return ContactSet(
            self.vertex.copy(), self.edge.copy(), self.bj.copy(), self.bk.copy(),
            self.state.copy(), self.xi0.copy(), self.t_n.copy(), self.t_s.copy(),
            {k: v.copy() for k, v in self.history.items()}, self.held_ago.copy(),
        )


def held_ago(contacts: ContactSet) -> np.ndarray:
    """(m,) each contact's ``held_ago`` for the step after ``contacts`` (a committed set):
    1 where it ended its step closed at zero normal force (held by the cycle rule, or closed
    at a gap of round-off), else one more than it had (up to :data:`HELD_NEVER`)."""
    return own_measures(np.asarray(contacts.state, dtype=np.int8),
                        np.asarray(contacts.t_n, dtype=np.float64),
                        np.asarray(contacts.held_ago, dtype=np.int64), 0)[1]


def _to_adjacent_edges(old, new, hit, src, xi0, x, nxt, prv, n_blocks, geom):
    """A closed contact whose vertex is now found on the adjacent edge of the same block
    moves there: its source row goes into ``src`` and its shear reference into ``xi0`` (in
    place), placed so that g_s is the same on the new edge as on the old."""
    closed_old = (old.state != OPEN).nonzero()[0]
    miss = (~hit).nonzero()[0]
    if not (len(closed_old) and len(miss)):
        return
    key2 = old.vertex[closed_old] * n_blocks + old.bk[closed_old]
    o2 = np.argsort(key2)
    want = new.vertex[miss] * n_blocks + new.bk[miss]
    p2 = np.minimum(np.searchsorted(key2[o2], want), len(o2) - 1)
    found = key2[o2][p2] == want
    cand = closed_old[o2[p2]]
    adjacent = (nxt[old.edge[cand]] == new.edge[miss]) | (prv[old.edge[cand]] == new.edge[miss])
    # the old pair must be gone from the new detection
    taken = np.zeros(len(old), dtype=bool)
    taken[src[src >= 0]] = True
    ok = found & adjacent & ~taken[cand]
    moved = miss[ok]
    from_old = cand[ok]
    if len(moved):
        og = contact_geometry(x, old.vertex[from_old], old.edge[from_old], nxt)
        g_s = og.shear_gap(old.xi0[from_old])
        src[moved] = from_old
        # keep g_s: xi0 on the new edge is the foot minus the old shear gap
        xi0[moved] = geom.xi[moved] - g_s / geom.length[moved]


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """``numpy.array_equal`` of two index arrays (by their bytes when of one dtype: the
    cheap test of a small scene's every step)."""
    if a.dtype == b.dtype and a.shape == b.shape:
        return a.tobytes() == b.tobytes()
    return bool(np.array_equal(a, b))


def _carried_whole(old, new, x, nxt):
    geom = new.geometry
    if geom is None:
        geom = contact_geometry(x, new.vertex, new.edge, nxt)
    state = old.state.astype(np.int8, copy=True)
    xi0, t_n, t_s = old.xi0.copy(), old.t_n.copy(), old.t_s.copy()
    history = {k: np.array(v, dtype=float) for k, v in old.history.items()}
    fresh = state == OPEN
    if fresh.any():
        xi0[fresh] = geom.xi[fresh]
        t_n[fresh] = 0.0
        t_s[fresh] = 0.0
    contacts = ContactSet(new.vertex, new.edge, new.bj, new.bk, state, xi0, t_n, t_s, history,
                          held_ago(old))
    return contacts, fresh, geom


def carry_over(
    old: ContactSet, new: CandidateContacts, x: np.ndarray, nxt: np.ndarray, prv: np.ndarray,
    n_blocks: int, with_new: bool = False,
) -> tuple[ContactSet, np.ndarray, ContactGeometry]:
    """Build the contact set of the new detection, with the history of the old one.

    Returns the set, a boolean mask of the contacts that carry no history (new or open):
    the caller gives those the initial history of their friction law, and the contacts'
    geometry at ``x`` (for :class:`dda.contact.ContactElement`); ``with_new``: also a mask of
    the contacts found anew (not carried), whose law history is all its initial one
    (:meth:`dda.contact.FrictionLaw.kept_when_open`).

    A pair found again keeps everything. A vertex that was in contact with an edge and is now
    found on the adjacent edge of the same block keeps its state and history, and its shear
    reference point is placed so that g_s is the same on the new edge as on the old.
    """
    m = len(new)
    n_v = len(x)
    if m and len(old) == m and _same(old.vertex, new.vertex) and _same(old.edge, new.edge):
        # the same contacts in the same order (a scene at rest, a slow slide): each keeps all
        # it had, as the matching below would give it
        whole = _carried_whole(old, new, x, nxt)
        return (*whole, np.zeros(m, dtype=bool)) if with_new else whole
    state = np.zeros(m, dtype=np.int8)
    xi0 = np.zeros(m)
    t_n = np.zeros(m)
    t_s = np.zeros(m)
    history = {k: np.zeros(m) for k in old.history}
    ago = np.full(m, HELD_NEVER, dtype=np.int64)
    found_anew = np.ones(m, dtype=bool)
    geom = new.geometry
    if geom is None:
        geom = contact_geometry(x, new.vertex, new.edge, nxt)
    if len(old) and m:
        old_key = old.vertex * n_v + old.edge
        order = np.argsort(old_key)
        sorted_key = old_key[order]
        new_key = new.vertex * n_v + new.edge
        pos = np.minimum(np.searchsorted(sorted_key, new_key), len(old) - 1)
        hit = sorted_key[pos] == new_key
        src = np.where(hit, order[pos], -1)
        _to_adjacent_edges(old, new, hit, src, xi0, x, nxt, prv, n_blocks, geom)
        carried = (src >= 0).nonzero()[0]
        found_anew[carried] = False
        from_old = src[carried]
        state[carried] = old.state[from_old]
        t_n[carried] = old.t_n[from_old]
        t_s[carried] = old.t_s[from_old]
        same = carried[old.edge[from_old] == new.edge[carried]]
        xi0[same] = old.xi0[src[same]]
        for k in history:
            history[k][carried] = old.history[k][from_old]
        ago[carried] = held_ago(old)[from_old]
    fresh = state == OPEN
    # an open contact's shear reference follows the foot until it closes
    xi0[fresh] = geom.xi[fresh]
    t_n[fresh] = 0.0
    t_s[fresh] = 0.0
    contacts = ContactSet(new.vertex, new.edge, new.bj, new.bk, state, xi0, t_n, t_s, history,
                          ago)
    return (contacts, fresh, geom, found_anew) if with_new else (contacts, fresh, geom)
