"""The penetration guard: find every vertex that lies inside another block, geometrically.

Contact detection decides which vertex-edge pairs get springs; this module does not trust it.
It looks at a configuration as it is (the deformed vertices at the end of a step) and finds,
for every vertex of every block, whether it lies inside another block and how deep:

    depth(P, k) = min over the edges e of block k of dist(P, segment e),   P inside k

with "inside" decided by the crossing number of a ray from P (even-odd rule, so non-convex
blocks are handled exactly). The midpoint of every edge is probed the same way: where blocks
stand corner on corner, a corner that sinks into the block below does so along that block's
side-face line, on its boundary, at depth zero, and only the edge between two such corners is
inside (:func:`edge_penetrations`). An edge that crosses into the other block and out again
between its ends, its midpoint outside (two bars across each other, two corners that passed
each other), is probed as well at the middle of each stretch between the crossings. A vertex
inside another block is *tracked* when a closed contact of that vertex (or, for a
vertex-vertex contact, of the vertex at the end of the contacted edge) against that block
carries a spring penetration ``-t_n / p_n`` at least as deep, give or take the tolerance;
anything else is an untracked penetration, which the simulation refuses.
An open contact that an impact dashpot let go while its vertex was still inside (the spring's
and the dashpot's force summed to zero, :attr:`dda.contact.element.ContactElement.release`)
holds its vertex at its own gap (:func:`released_depth`): the vertex is on its way out, and
the contact closes again if it turns back.

Every operation is on arrays over (vertex, block) pairs from the broad phase.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numba import njit

from dda.contact.contacts import OPEN, STICK
from dda.contact.detection import VertexTopology, _boxes, bounding_boxes, broad_phase
from dda.contact.inside import _corners_inside_kernel
from dda.kernels.geometry import vertex_turns
from dda.kernels.kinematics import _frame
from dda.kernels.sums import run_sum

__all__ = ["GuardReport", "Penetrations", "penetration_guard", "vertex_penetrations",
           "edge_penetrations", "untracked_depth", "untracked_edge_depth",
           "untracked_penetrations", "released_depth", "held_by_contact"]


@dataclass
class Penetrations:
    """Vertices inside another block: vertex index, the block it is in, the depth (m) and the
    edge of that block nearest to it (CCW start index)."""

    vertex: np.ndarray
    block: np.ndarray
    depth: np.ndarray
    edge: np.ndarray

    def __len__(self):
        return len(self.vertex)

    def select(self, mask) -> Penetrations:
        return Penetrations(self.vertex[mask], self.block[mask], self.depth[mask],
                            self.edge[mask])

    @property
    def deepest(self) -> float:
        return float(self.depth.max()) if len(self) else 0.0


def _empty() -> Penetrations:
    z = np.zeros(0, dtype=np.int64)
    return Penetrations(z, z.copy(), np.zeros(0), z.copy())


def vertex_penetrations(x: np.ndarray, topo: VertexTopology, min_depth: float = 0.0,
                        pairs: np.ndarray | None = None, boxes=None) -> Penetrations:
    """Every corner of ``x`` that lies inside another block deeper than ``min_depth`` (m).

    A vertex between collinear edges is not a corner and is left out (as contact detection
    leaves it out): it is a point of a side, which the corners' springs hold.

    Parameters
    ----------
    x : (n_vertices, 2) vertex positions
    topo : the blocks' vertex topology
    min_depth : report only vertices deeper than this
    pairs : block pairs whose boxes overlap (the broad phase at zero margin when None)

    Examples
    --------
    >>> import numpy as np
    >>> from dda.contact.detection import VertexTopology
    >>> x = np.array([[0, 0], [1, 0], [1, 1], [0, 1],            # a unit square and a box
    ...               [0.9, 0.2], [2, 0.2], [2, 0.8], [0.9, 0.8]], float)  # 0.1 into it
    >>> pen = vertex_penetrations(x, VertexTopology.from_offsets(np.array([0, 4, 8])))
    >>> pen.vertex.tolist(), pen.block.tolist(), np.round(pen.depth, 12).tolist()
    ([4, 7], [0, 0], [0.1, 0.1])
    """
    # a vertex between collinear edges is a point of a side, not a corner: where two blocks
    # overlap edge to edge it is inside the other, and the corners' springs hold the overlap
    return _inside(x, topo, min_depth, pairs, boxes, midpoints=False)


def _inside(x, topo, min_depth, pairs, boxes, midpoints) -> Penetrations:
    """The corners (or edge midpoints) of ``x`` inside another block deeper than
    ``min_depth`` (:func:`vertex_penetrations`, :func:`edge_penetrations`)."""
    offsets = topo.offsets
    if len(offsets) < 3:
        return _empty()
    if boxes is None:
        boxes = bounding_boxes(x, offsets)
    if pairs is None:
        pairs = broad_phase(boxes, 0.0)
    if len(pairs) == 0:
        return _empty()
    x = np.ascontiguousarray(x, dtype=np.float64)
    corner = np.ones(len(x), dtype=bool) if midpoints else ~topo.straight(x)
    vertex, kblock, depth, nearest = _corners_inside_kernel(
        x, offsets, topo.nxt, np.ascontiguousarray(pairs, dtype=np.int64), boxes, corner,
        float(min_depth), midpoints)
    return Penetrations(vertex, kblock, depth, nearest)


def edge_penetrations(x: np.ndarray, topo: VertexTopology, min_depth: float = 0.0,
                      pairs: np.ndarray | None = None, boxes=None) -> Penetrations:
    """Every edge of ``x`` that lies inside another block deeper than ``min_depth`` (m) at
    its midpoint or at the middle of a stretch between its crossings with the block's
    boundary (the deepest of those probes): ``vertex`` is the edge's start vertex (the edge
    runs to ``topo.nxt[vertex]``).

    Examples
    --------
    >>> import numpy as np
    >>> from dda.contact.detection import VertexTopology
    >>> x = np.array([[0, 0], [1, 0], [1, 1], [0, 1],              # a unit square and one
    ...               [0, 0.997], [1, 0.997], [1, 2], [0, 2]], float)  # 3 mm into it, aligned
    >>> topo = VertexTopology.from_offsets(np.array([0, 4, 8]))
    >>> len(vertex_penetrations(x, topo, min_depth=1e-9))  # its corners are on the sides
    0
    >>> pen = edge_penetrations(x, topo, min_depth=1e-9)
    >>> pen.vertex.tolist(), pen.block.tolist(), np.round(pen.depth, 12).tolist()
    ([2, 4], [1, 0], [0.003, 0.003])
    """
    return _inside(x, topo, min_depth, pairs, boxes, midpoints=True)


def released_depth(x: np.ndarray, contacts, topo: VertexTopology,
                   dashpot: np.ndarray) -> np.ndarray:
    """(m,) how deep inside the other block each open contact with an impact dashpot leaves
    its vertex: ``max(-g_n, 0)`` with ``g_n`` the vertex's gap to its edge's line at ``x``;
    0 for closed contacts and for those without a dashpot (``dashpot`` False).

    Such a contact was let go where the spring's and the dashpot's force summed to zero,
    before the vertex was out; it holds the vertex at that depth until it is (the guard
    counts it as a closed spring ``-t_n / p_n`` of that depth).
    """
    from dda.contact.kinematics import contact_geometry  # kinematics imports the kernels

    out = np.zeros(len(contacts))
    sel = np.flatnonzero((contacts.state == OPEN) & np.asarray(dashpot, dtype=bool))
    if len(sel):
        gap = contact_geometry(x, contacts.vertex[sel], contacts.edge[sel], topo.nxt).gap
        out[sel] = np.maximum(-gap, 0.0)
    return out


def _holding(contacts, normal_penalty, released):
    """``contacts`` with each contact of ``released`` depth > 0 (:func:`released_depth`)
    shown as a closed spring of that depth, for the guard's accounting only."""
    if released is None or not np.any(released > 0.0):
        return contacts
    hold = released > 0.0
    return replace(contacts, state=np.where(hold, np.int8(STICK), contacts.state),
                   t_n=np.where(hold, -normal_penalty * released, contacts.t_n))


def untracked_edge_depth(pen: Penetrations, contacts, normal_penalty: np.ndarray,
                         topo: VertexTopology, released=None) -> np.ndarray:
    """(len(pen),) how much deeper each edge midpoint of :func:`edge_penetrations` is inside
    its block k than the springs that hold the edge there.

    A straight edge is held by its two end vertices' springs against k
    (:func:`untracked_depth`) and by the springs of k's vertices on the edge; between them
    it is no deeper than the deepest of those, so the midpoint's depth less that deepest
    spring is what no contact accounts for. ``released``: as in :func:`untracked_depth`.
    """
    if len(pen) == 0:
        return np.zeros(0)
    contacts = _holding(contacts, normal_penalty, released)
    zero = np.zeros(len(pen))
    ends = [Penetrations(v, pen.block, zero, pen.edge) for v in (pen.vertex,
                                                                  topo.nxt[pen.vertex])]
    held = np.maximum(*(-untracked_depth(e, contacts, normal_penalty, topo) for e in ends))
    c = contacts
    closed = np.flatnonzero(c.state != OPEN)
    if len(closed):
        nb = len(topo.offsets)
        # k's vertices in contact with the edge: key (edge, the vertex's block)
        keys = np.asarray(c.edge[closed] * nb + c.bj[closed], dtype=np.int64)
        spring = -c.t_n[closed] / normal_penalty[closed]
        want = np.asarray(pen.vertex * nb + pen.block, dtype=np.int64)
        held = np.maximum(held, _gather_kernel(keys, np.ascontiguousarray(spring), want, True))
    return pen.depth - held


def untracked_depth(pen: Penetrations, contacts, normal_penalty: np.ndarray,
                    topo: VertexTopology, released=None) -> np.ndarray:
    """(len(pen),) how much deeper each penetration is than the closed spring that holds it.

    A penetration of vertex P into block k at depth delta is held by a closed contact of P
    against an edge of k, or (vertex-vertex) by a closed contact between the same two blocks
    whose contacted edge ends at P; the result is ``delta`` less the spring penetration
    ``-t_n / p_n`` of those contacts (``delta`` itself when there is none). P's own springs
    against k add as ``sqrt(sum s^2)``: in a reflex corner of k, P is held by both edges and
    is deepest from the corner point, ``sqrt(s1^2 + s2^2)`` for a square corner.

    Parameters
    ----------
    pen : the penetrations found by :func:`vertex_penetrations`
    contacts : the step's trial :class:`dda.contact.ContactSet`
    normal_penalty : (m,) normal penalty of each contact
    topo : the blocks' vertex topology
    released : (m,) optional, the depth at which open contacts an impact dashpot let go
        hold their vertices (:func:`released_depth`)
    """
    if len(pen) == 0:
        return np.zeros(0)
    c = _holding(contacts, normal_penalty, released)
    if not np.any(c.state != OPEN):
        return pen.depth.copy()
    ints = [np.asarray(a, dtype=np.int64) for a in (pen.vertex, pen.block, c.vertex, c.edge,
                                                      c.bj, c.bk, topo.nxt)]
    return _untracked_kernel(np.asarray(c.state, dtype=np.int8),
                             np.ascontiguousarray(c.t_n, dtype=np.float64),
                             np.ascontiguousarray(normal_penalty, dtype=np.float64),
                             np.ascontiguousarray(pen.depth, dtype=np.float64), *ints,
                             len(topo.offsets))


@njit(cache=True)
def _untracked_kernel(state, t_n, normal_penalty, depth, pen_vertex, pen_block, vertex, edge,
                      bj, bk, nxt, nb):
    """:func:`untracked_depth` in one compiled pass, the numpy version's arithmetic."""
    closed = np.flatnonzero(state != 0)
    n = closed.shape[0]
    spring = np.empty(n)
    spring_sq = np.empty(n)
    own = np.empty(n, dtype=np.int64)
    mirrored = np.empty(2 * n, dtype=np.int64)
    twice = np.empty(2 * n)
    for k in range(n):
        c = closed[k]
        spring[k] = -t_n[c] / normal_penalty[c]
        spring_sq[k] = spring[k] ** 2
        # the vertex's own springs against that block: one for a convex block; two at a
        # reflex corner, where the vertex is deepest from the corner point itself and the
        # two lines' gaps add up to it as the sides of a right triangle (exact for a
        # square corner)
        own[k] = vertex[c] * nb + bk[c]
        # the mirror image of a vertex-vertex contact: a closed contact between the same
        # blocks whose contacted edge ends at the vertex
        mirrored[k] = edge[c] * nb + bj[c]
        mirrored[n + k] = nxt[edge[c]] * nb + bj[c]
        twice[k] = spring[k]
        twice[n + k] = spring[k]
    want = pen_vertex * nb + pen_block
    held_own = np.sqrt(_gather_kernel(own, spring_sq, want, np.bool_(False)))
    held_mirror = _gather_kernel(mirrored, twice, want, np.bool_(True))
    out = np.empty(want.shape[0])
    for w in range(want.shape[0]):
        out[w] = depth[w] - max(held_own[w], held_mirror[w])
    return out


@njit(cache=True)
def _gather_kernel(keys, values, want, use_max):
    """For each of ``want``, the sum (or with ``use_max`` the largest) of the values whose key
    it is, 0 where none is: the values sorted by key (stable) and reduced run by run as
    ``numpy.add.reduceat`` / ``numpy.maximum.reduceat`` of the sorted runs do (the sum in
    numpy's order: the first value plus the pairwise sum of the others), to the bit."""
    order = _stable_order(keys)
    n = keys.shape[0]
    ranked = np.empty(n, dtype=np.int64)
    for i in range(n):
        ranked[i] = keys[order[i]]
    out = np.zeros(want.shape[0])
    for w in range(want.shape[0]):
        key = want[w]
        lo = np.searchsorted(ranked, key)  # the first sorted position not below ``key``
        if lo == n or ranked[lo] != key:
            continue
        end = lo + 1
        while end < n and ranked[end] == key:
            end += 1
        if use_max:
            acc = values[order[lo]]
            for j in range(lo + 1, end):
                acc = max(acc, values[order[j]])
        else:
            acc = run_sum(values, order, lo, end)
        out[w] = acc
    return out


# the radix sort's fixed cost (zeroing and summing 4,097 counts a 12-bit digit) against numba's
# merge sort, in a compiled loop on the guard's kind of keys: 128 keys 5 against 2.9 us, 256
# keys 5.7 against 7.4 us, 512 keys 6.3 against 17.8 us
RADIX_FROM = 200


@njit(cache=True)
def _stable_order(keys):
    """``numpy.argsort(keys, kind="mergesort")`` (stable) of int64 keys: a least-significant
    digit radix sort of 12-bit digits when there are ``RADIX_FROM`` keys or more and none is
    negative (the guard's keys are ``vertex * blocks + block``), else numba's merge sort. On
    the 60 x 60 stack's 42,000 mirrored keys 0.36 ms against 1.94 ms; on a few keys the
    radix sort's two passes over 4,097 counts cost more than the keys (8 keys: 3 us against
    0.08 us)."""
    n = keys.shape[0]
    if n < RADIX_FROM or keys.min() < 0:
        return np.argsort(keys, kind="mergesort")
    order = np.arange(n)
    spare = np.empty(n, dtype=np.int64)
    count = np.empty(4097, dtype=np.int64)
    top = keys.max()
    shift = 0
    while True:
        count[:] = 0
        for i in range(n):
            count[((keys[order[i]] >> shift) & 4095) + 1] += 1
        for d in range(4096):
            count[d + 1] += count[d]
        for i in range(n):
            digit = (keys[order[i]] >> shift) & 4095
            spare[count[digit]] = order[i]
            count[digit] += 1
        order, spare = spare, order
        shift += 12
        if shift >= 63 or (top >> shift) == 0:
            return order


def untracked_penetrations(pen: Penetrations, contacts, normal_penalty: np.ndarray,
                           tolerance: np.ndarray, topo: VertexTopology,
                           released=None) -> np.ndarray:
    """Which of ``pen`` no closed contact accounts for (boolean mask over ``pen``): those
    deeper than their spring (:func:`untracked_depth`) by more than ``tolerance``."""
    return untracked_depth(pen, contacts, normal_penalty, topo, released) > tolerance


@dataclass(frozen=True)
class GuardReport:
    """What the penetration guard found on a step's trial.

    ``reason`` is empty when every vertex inside another block is held by a closed contact
    at its depth (give or take the tolerance), else why the step is refused. ``deepest`` is
    the deepest vertex inside another block (m), ``spring_deepest`` the deepest closed spring
    (m), ``untracked`` the deepest untracked penetration in tolerances; ``held`` whether the refused
    one's vertex has a closed contact against that block (:func:`held_by_contact`).
    """

    reason: str = ""
    deepest: float = 0.0
    spring_deepest: float = 0.0
    untracked: float = 0.0
    # the refused penetration's vertex (or an end of its edge) has a closed contact against
    # that block: a held contact whose linear gap fell short, not one detection missed
    held: bool = False


GUARD_KERNEL = True
"""Whether :func:`penetration_guard` runs as one compiled pass (:func:`_guard_kernel`); False
composes it from the functions above (the same numbers, to the bit)."""


def penetration_guard(model, x_new, contacts, normal_penalty, pairs,
                      tolerance: float, released=None, dashpot=None) -> GuardReport:
    """The penetration guard on a trial configuration ``x_new`` of ``model``'s blocks.

    ``contacts`` are the trial's contacts, ``normal_penalty`` their p_n, ``pairs`` the block
    pairs whose boxes may overlap; ``tolerance`` is a fraction of the thinner block's
    half-width (:attr:`dda.model.Model.thickness`); ``released`` the depths at which open
    contacts an impact dashpot let go hold their vertices (:func:`released_depth`), or
    ``dashpot``, each contact's impact dashpot (``c / dt``, or None: none), from which the
    guard finds them itself.
    """
    if model.n_blocks < 2:
        return GuardReport()
    topo = model.topo
    if GUARD_KERNEL and released is None:
        c = contacts
        m = len(c)
        has_dashpot = dashpot is not None
        ints = [np.ascontiguousarray(a, dtype=np.int64)
                for a in (c.vertex, c.edge, c.bj, c.bk, pairs)]
        (deepest, spring, untracked, on_edge, v, k, depth,
         tol) = _guard_kernel(np.ascontiguousarray(x_new, dtype=np.float64), model.offsets,
                              topo.nxt, topo.prv, topo.block, model.thickness,
                              float(tolerance), float(model.min_thickness),
                              np.ascontiguousarray(c.state, dtype=np.int8),
                              np.ascontiguousarray(c.t_n, dtype=np.float64),
                              np.ascontiguousarray(normal_penalty, dtype=np.float64),
                              (np.ascontiguousarray(dashpot, dtype=np.float64) if has_dashpot
                               else np.zeros(m)), has_dashpot, *ints)
        if not untracked > 1.0:
            return GuardReport("", deepest, spring, untracked)
        return GuardReport(_untracked_reason(model, x_new, on_edge, v, k, depth, tol),
                           deepest, spring, untracked,
                           held_by_contact(contacts, topo, int(v), int(k), bool(on_edge)))
    if released is None and dashpot is not None:
        released = released_depth(x_new, contacts, topo, np.asarray(dashpot) > 0.0)
    contacts = _holding(contacts, normal_penalty, released)
    boxes = bounding_boxes(x_new, topo.offsets)
    pen = vertex_penetrations(x_new, topo, pairs=pairs, boxes=boxes)
    # an edge shallower than a quarter of the smallest tolerance is untracked by less than
    # that: below the half tolerance at which the step control calls a penetration already
    # there at a step's start (resting contacts sink far less; they cost no edge check)
    edges = edge_penetrations(x_new, topo, 0.25 * tolerance * float(np.min(model.thickness)),
                              pairs, boxes)
    closed = contacts.state != OPEN
    spring = float(np.maximum.reduce(-contacts.t_n[closed] / normal_penalty[closed],
                                      initial=0.0))
    deepest = max(pen.deepest, edges.deepest)
    if len(pen) == 0 and len(edges) == 0:
        return GuardReport("", deepest, spring)

    def tolerances(p):
        return tolerance * np.minimum(model.thickness[topo.block[p.vertex]],
                                      model.thickness[p.block])

    tol = tolerances(pen)
    ratio = untracked_depth(pen, contacts, normal_penalty, topo) / tol
    worst, worst_e = float(ratio.max(initial=-np.inf)), -np.inf
    if len(edges):
        tol_e = tolerances(edges)
        ratio_e = untracked_edge_depth(edges, contacts, normal_penalty, topo) / tol_e
        worst_e = float(ratio_e.max())
    untracked = max(worst, worst_e)
    if not untracked > 1.0:
        return GuardReport("", deepest, spring, untracked)
    on_edge = worst_e > worst
    p, r, t = (edges, ratio_e, tol_e) if on_edge else (pen, ratio, tol)
    i = int(np.argmax(r))
    reason = _untracked_reason(model, x_new, on_edge, int(p.vertex[i]), int(p.block[i]),
                               float(p.depth[i]), float(t[i]))
    return GuardReport(reason, deepest, spring, untracked,
                       held_by_contact(contacts, topo, int(p.vertex[i]), int(p.block[i]),
                                       on_edge))


def held_by_contact(contacts, topo: VertexTopology, v: int, k: int, on_edge: bool) -> bool:
    """Whether a closed contact holds vertex ``v`` (with ``on_edge``, either end of its edge
    to ``nxt[v]``) against block ``k``: one of the vertex against an edge of k, or a vertex
    of k against an edge of the vertex's block at the vertex (its vertex-vertex mirror).

    An untracked penetration so held is a spring whose linear gap fell short of the step's
    turning and sliding, which a smaller step shrinks; one not held is a contact detection
    missed (:meth:`dda.step_control.StepControl.check_can_go_on`)."""
    c = contacts
    nxt = topo.nxt
    ends = [v, int(nxt[v])] if on_edge else [v]
    j = int(topo.block[v])
    closed = c.state != OPEN
    own = np.isin(c.vertex, ends) & (c.bk == k)
    mirror = (c.bj == k) & (c.bk == j) & (np.isin(c.edge, ends) | np.isin(nxt[c.edge], ends))
    return bool(np.any(closed & (own | mirror)))


def _untracked_reason(model, x_new, on_edge, v, k, depth, tol) -> str:
    """Why the guard refuses a step: the worst untracked penetration, vertex (or, with
    ``on_edge``, the edge from) ``v`` at ``depth`` inside block ``k``."""
    topo = model.topo
    j = int(topo.block[v])
    local = v - int(model.offsets[j])
    if on_edge:
        w = int(topo.nxt[v])
        mid = 0.5 * (x_new[v] + x_new[w])
        what = (f"the edge from vertex {local} to {w - int(model.offsets[j])} of "
                f"{model.block_label(j)} (its midpoint at {mid[0]:.6g}, {mid[1]:.6g})")
    else:
        what = (f"vertex {local} of {model.block_label(j)} (at {x_new[v, 0]:.6g}, "
                f"{x_new[v, 1]:.6g})")
    return (f"untracked penetration: {what} is {depth:.3g} m inside "
            f"{model.block_label(k)}, and no closed contact holds it "
            f"(tolerance {tol:.3g} m)")


@njit(cache=True)
def _guard_kernel(x, offsets, nxt, prv, block_of, thickness, tolerance, min_thickness, state,
                  t_n, normal_penalty, dashpot, has_dashpot, vertex, edge, bj, bk, pairs):
    """:func:`penetration_guard` in one compiled pass, the composed version's arithmetic:
    the released depths (:func:`released_depth`) held as closed springs (:func:`_holding`),
    the corners and edge midpoints inside another block, and each one's untracked depth
    over its tolerance. Returns the deepest penetration, the deepest spring, the worst
    ratio (-inf when nothing is inside) and, for the worst, whether it is an edge, its
    vertex, block, depth and tolerance."""
    m = state.shape[0]
    st = state.copy()
    tn = t_n.copy()
    if has_dashpot:
        for c in range(m):
            if state[c] == 0 and dashpot[c] > 0.0:
                v, e = vertex[c], edge[c]
                f = nxt[e]
                g = _frame(x[v, 0], x[v, 1], x[f, 0], x[f, 1], x[e, 0], x[e, 1])[5]
                released = max(-g, 0.0)
                if released > 0.0:
                    st[c] = 1
                    tn[c] = -normal_penalty[c] * released
    spring = 0.0
    for c in range(m):
        if st[c] != 0:
            s = -tn[c] / normal_penalty[c]
            if not spring >= s:
                spring = s
    boxes = _boxes(x, offsets)
    cross, scale, dot, _ = vertex_turns(x, prv, nxt)
    corner = ~((np.abs(cross) <= 1e-9 * scale) & (dot < 0.0))
    nb = offsets.shape[0] - 1
    if pairs.shape[0] == 0:
        return 0.0, spring, 0.0, False, -1, -1, 0.0, 0.0
    pv, pk, pd, _ = _corners_inside_kernel(x, offsets, nxt, pairs, boxes, corner, 0.0,
                                           np.bool_(False))
    ev, ek, ed, _ = _corners_inside_kernel(x, offsets, nxt, pairs, boxes, corner,
                                           0.25 * tolerance * min_thickness, np.bool_(True))
    deepest = 0.0
    if pd.shape[0]:
        deepest = pd.max()
    if ed.shape[0]:
        e_deepest = ed.max()
        if e_deepest > deepest:
            deepest = e_deepest
    if pd.shape[0] == 0 and ed.shape[0] == 0:
        return deepest, spring, 0.0, False, -1, -1, 0.0, 0.0
    worst, wi = -np.inf, -1
    if pd.shape[0]:
        left = _untracked_kernel(st, tn, normal_penalty, pd, pv, pk, vertex, edge, bj, bk,
                                 nxt, nb + 1)
        for i in range(pd.shape[0]):
            r = left[i] / (tolerance * min(thickness[block_of[pv[i]]], thickness[pk[i]]))
            if r > worst or wi < 0:
                worst, wi = r, i
    worst_e, we = -np.inf, -1
    if ed.shape[0]:
        zero = np.zeros(ed.shape[0])
        held = np.maximum(-_untracked_kernel(st, tn, normal_penalty, zero, ev, ek, vertex, edge,
                                             bj, bk, nxt, nb + 1),
                          -_untracked_kernel(st, tn, normal_penalty, zero, nxt[ev], ek, vertex,
                                             edge, bj, bk, nxt, nb + 1))
        n_closed = 0
        for c in range(m):
            if st[c] != 0:
                n_closed += 1
        if n_closed:
            keys = np.empty(n_closed, dtype=np.int64)
            springs = np.empty(n_closed)
            q = 0
            for c in range(m):
                if st[c] != 0:
                    keys[q] = edge[c] * (nb + 1) + bj[c]
                    springs[q] = -tn[c] / normal_penalty[c]
                    q += 1
            held = np.maximum(
                held, _gather_kernel(keys, springs, ev * (nb + 1) + ek, np.bool_(True))
            )
        for i in range(ed.shape[0]):
            r = (ed[i] - held[i]) / (tolerance * min(thickness[block_of[ev[i]]],
                                                     thickness[ek[i]]))
            if r > worst_e or we < 0:
                worst_e, we = r, i
    if worst_e > worst:
        return (deepest, spring, worst_e, True, ev[we], ek[we], ed[we],
                tolerance * min(thickness[block_of[ev[we]]], thickness[ek[we]]))
    return (deepest, spring, worst, False, pv[wi], pk[wi], pd[wi],
            tolerance * min(thickness[block_of[pv[wi]]], thickness[pk[wi]]))
