"""Contact detection: a broad phase on bounding boxes and a vertex-edge narrow phase.

Everything works on the stacked vertex arrays of :mod:`dda.geometry` and returns arrays.

Conventions
-----------
Edge ``e`` of a block is the counter-clockwise edge from vertex ``e`` to ``next(e)``. A contact
pairs vertex P1 of block j with edge e of block k and uses the edge reversed, P2 = next(e) and
P3 = e, so that the left normal ``n = (1/l) [y2 - y3, x3 - x2]`` of METHOD.md section 3 is the
outward normal of block k and ``g_n < 0`` is penetration.

Rules of the narrow phase (METHOD.md section 3)
-----------------------------------------------
A vertex-edge pair is a contact candidate when
1. the vertex is convex (a reflex vertex cannot touch an edge first);
2. the foot of the perpendicular lies on the edge (0 <= xi <= 1 up to round-off), or the
   vertex lies within the search distance of the edge's end vertex (vertex-vertex);
3. the gap lies in ``[-penetration_limit, search_distance]``, and a negative gap (the vertex
   behind the edge's line) counts only when the vertex is inside the edge's block, no deeper
   behind the line than it is inside the block (its distance to the block's boundary) plus
   ``sunk_depth`` (a vertex sunk into the block deeper than ``sunk_depth`` is exempt); or,
   at a run's first step, when it touches: no farther behind the line and outside the block
   than ``TOUCH_TOLERANCE`` of the pair's smaller block (two voussoirs whose extrados chords fall
   away from a shared corner, built 1e-8 m into each other: each corner lies behind the
   other's joint face and just above its chord, and neither got a contact);
4. the vertex is locally the first point of its block to cross the edge's line: both of its
   edges leave it towards the outside of that line, within ``ENTRANCE_TOLERANCE_DEG``, and
   its outward bisector does not point the way of the edge's outward normal (a sharp wedge
   slid along a floor into a block standing on it lies on that block's bottom edge, its
   edges on and behind the line: the block's side holds it) (a sunk vertex is exempt: the
   edge along which the two blocks overlap least near it holds it, see below).
Of several edges of one block that pass for the same vertex, the nearest are preferred (the
distance from the vertex to the edge as a segment: round a convex corner of a concave block,
the top of a step's riser, the line of the tread below lies beyond a corner resting on the
tread above, and only the riser leads there), of those the one with the largest gap (the least
deep: at a corner where four blocks meet, a vertex sliding along one joint past the corner must
not be taken as deep behind the other joint's line), then one whose foot lies on the edge, then
the one whose outward normal is most opposed to the vertex's outward bisector. For a sunk
vertex "nearest" means the least overlap along the edge's normal, seen from the vertex
(:func:`dda.contact.inside._fan_overlap`: how deep behind the edge's line the vertex and the
stretches of its own two edges inside the block reach, a separating axis test local to the
vertex): its nearest edge can be the wrong one, as for two corners that hit tip to tip and
slid past each other, each nearest the other's side while the overlap runs under the other's
face. For a convex block the nearest edge is the least deep one (outside it the feet of two
edges never both lie on their edges, and in a corner's wedge the two are equally near). At a
reflex (concave) vertex of the block the solid is the union of the two edges' half-planes,
and a vertex in the corner is near both: the edge across a reflex vertex from the chosen one
is kept as well (Shi's rule for a convex vertex entering a concave angle: two vertex-edge
contacts). A vertex-vertex case (the foot at the end of the edge, the two vertices within the
search distance) shows up as two mirrored pairs, P on an edge at Q and Q on an edge at P; only
one is kept: the one whose foot lies on its edge, else the better opposed one; both when the
other's vertex is inside the other block deeper than ``sunk_depth`` (corners sunk into each
other).

The point-inside-block probes (inside or not, how deep, the overlap seen from a sunk vertex)
live in :mod:`dda.contact.inside`, shared with the penetration guard.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numba import njit

from dda.contact.inside import _fan_overlap, _point_in_block, inside_depth
from dda.contact.kinematics import ContactGeometry, contact_geometry
from dda.geometry import _segments_cross, next_vertex_index, polygon_integrals
from dda.kernels.geometry import vertex_turns
from dda.kernels.kinematics import _frame

__all__ = ["VertexTopology", "broad_phase", "narrow_phase", "find_overlaps", "overlap_depths",
           "CandidateContacts", "inside_depth", "keep_closed"]

ENTRANCE_TOLERANCE_DEG = 20.0
# a closed contact's mirror (keep_closed) lies along the same joint: its edge runs against the
# contact's within this angle (two joint sets of a cut slope meet at 20 degrees)
MIRROR_TOLERANCE_DEG = 5.0
_XI_TOL = 1e-9
# gaps to two edges within this fraction of the edge length are a tie (round-off)
_GAP_TIE = 1e-9
#: blocks that overlap by less than this fraction of the smaller one's size (the larger side
#: of its bounding box) touch: the scene accepts them (``dda.scene.OVERLAP_TOLERANCE``), and
#: the narrow phase takes a vertex that far behind an edge's line and that far outside its
#: block for a contact on the edge (rule 3)
TOUCH_TOLERANCE = 1e-6


class Memo:
    """The last few results of pure functions of arrays, by the arrays' bytes.

    A scene's block pairs, and the vertex rows they give, change seldom from one step to the
    next: what is derived from them alone is kept here, in the topology it belongs to. Copies
    and pickles (checkpoints) start empty.
    """

    __slots__ = ("entries", "size")

    def __init__(self, size: int = 8):
        self.entries: dict = {}
        self.size = size

    def __reduce__(self):
        return (Memo, (self.size,))

    def get(self, key, make):
        """The result for ``key``, made by ``make()`` when it is not kept."""
        hit = self.entries.get(key)
        if hit is None:
            if len(self.entries) >= self.size:
                self.entries.pop(next(iter(self.entries)))
            hit = self.entries[key] = make()
        return hit


@dataclass(frozen=True)
class VertexTopology:
    """Per-vertex neighbours, owning block, convexity and outward bisector."""

    offsets: np.ndarray
    block: np.ndarray
    nxt: np.ndarray
    prv: np.ndarray

    @classmethod
    def from_offsets(cls, offsets: np.ndarray) -> VertexTopology:
        counts = np.diff(offsets)
        nxt = next_vertex_index(offsets)
        prv = np.empty_like(nxt)
        prv[nxt] = np.arange(len(nxt))
        block = np.repeat(np.arange(len(counts)), counts)
        return cls(offsets=offsets, block=block, nxt=nxt, prv=prv)

    @cached_property
    def counts(self) -> np.ndarray:
        """(n_blocks,) vertices (and edges) of every block."""
        return np.diff(self.offsets)

    @cached_property
    def memo(self) -> Memo:
        """Results derived from the block pairs alone, kept from step to step."""
        return Memo()

    def straight(self, x: np.ndarray, index=None) -> np.ndarray:
        """Whether each vertex (or each of ``index``) lies on the straight line of its two
        edges (to round-off): a point of a side, not a corner."""
        cross, scale, dot, _ = self.turns(x)
        straight = (np.abs(cross) <= 1e-9 * scale) & (dot < 0.0)
        return straight if index is None else straight[index]

    def reflex(self, x: np.ndarray) -> np.ndarray:
        """Whether each vertex is reflex (its interior angle above 180 degrees by more than
        round-off; a straight vertex between collinear edges is not)."""
        cross, scale, _, _ = self.turns(x)
        return cross > 1e-9 * scale

    def convex_and_bisector(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Convexity of every vertex and its outward unit bisector."""
        cross, _, _, bisector = self.turns(x)
        return cross < 0.0, bisector

    def turns(self, x: np.ndarray):
        """Per vertex: the cross product ``a x b`` of its arms (a to prev, b to next), its
        round-off scale ``|a| |b|``, their dot product and the outward unit bisector, in one
        compiled pass (:func:`dda.kernels.geometry.vertex_turns`)."""
        return vertex_turns(np.ascontiguousarray(x, dtype=np.float64), self.prv, self.nxt)


def bounding_boxes(x: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(n_blocks, 4) boxes [xmin, ymin, xmax, ymax]."""
    return _boxes(np.ascontiguousarray(x, dtype=np.float64), offsets)


@njit(cache=True)
def _boxes(x, offsets):
    n = offsets.shape[0] - 1
    out = np.empty((n, 4))
    for b in range(n):
        start = offsets[b]
        out[b, 0], out[b, 1] = x[start, 0], x[start, 1]
        out[b, 2], out[b, 3] = x[start, 0], x[start, 1]
        for v in range(start + 1, offsets[b + 1]):
            out[b, 0] = min(out[b, 0], x[v, 0])
            out[b, 1] = min(out[b, 1], x[v, 1])
            out[b, 2] = max(out[b, 2], x[v, 0])
            out[b, 3] = max(out[b, 3], x[v, 1])
    return out


def broad_phase(boxes: np.ndarray, margin: float) -> np.ndarray:
    """Pairs (i < j) of blocks whose boxes, grown by ``margin``, overlap (sort and sweep).

    The sweep runs along the axis of larger spread of the box centres: a sort and a
    searchsorted in numpy, then a compiled loop over the boxes each box's interval reaches,
    so the cost is O(N log N + candidate pairs).
    """
    if len(boxes) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    return _broad_phase(np.ascontiguousarray(boxes, dtype=np.float64), float(margin))


def pairs_with_free_block(pairs: np.ndarray, free: np.ndarray) -> np.ndarray:
    """The rows of ``pairs`` (k, 2) with at least one block that is ``free`` (in order)."""
    return _pairs_with_free_block(pairs, np.asarray(free, dtype=np.bool_))


@njit(cache=True)
def _pairs_with_free_block(pairs, free):
    keep = np.empty(pairs.shape[0], dtype=np.bool_)
    for i in range(pairs.shape[0]):
        keep[i] = free[pairs[i, 0]] or free[pairs[i, 1]]
    return pairs[keep]


@njit(cache=True)
def _broad_phase(boxes, margin):
    """:func:`broad_phase` compiled: the grown boxes, the axis of larger spread of their
    centres (the first on a tie), a stable sort along it, each box's reach in the sorted
    order (``searchsorted`` to the right), then :func:`_sweep`."""
    n = boxes.shape[0]
    lo = np.empty((n, 2))
    hi = np.empty((n, 2))
    spread = np.empty(2)
    for a in range(2):
        cmin, cmax = np.inf, -np.inf
        for b in range(n):
            lo[b, a] = boxes[b, a] - margin
            hi[b, a] = boxes[b, 2 + a] + margin
            c = 0.5 * (lo[b, a] + hi[b, a])
            cmin = min(cmin, c)
            cmax = max(cmax, c)
        spread[a] = cmax - cmin
    axis = 0 if spread[0] >= spread[1] else 1
    other = 1 - axis
    # a contiguous copy: numba's argsort would compile again for a strided column
    order = np.argsort(lo[:, axis].copy(), kind="mergesort")
    lo_sorted = lo[order, axis]
    stop = np.searchsorted(lo_sorted, hi[order, axis], side="right")
    return _sweep(order, stop, lo[:, other].copy(), hi[:, other].copy())


@njit(cache=True)
def _sweep(order, stop, lo, hi):
    """The pairs (min, max) of sorted positions s < t < stop[s] whose intervals [lo, hi] on
    the other axis overlap, s by s and t by t (the order of the numpy sweep)."""
    n = order.shape[0]
    total = 0
    for s in range(n):
        total += max(stop[s] - s - 1, 0)
    out = np.empty((total, 2), dtype=np.int64)
    m = 0
    for s in range(n):
        i = order[s]
        for t in range(s + 1, stop[s]):
            j = order[t]
            if lo[i] <= hi[j] and lo[j] <= hi[i]:
                out[m, 0] = min(i, j)
                out[m, 1] = max(i, j)
                m += 1
    return out[:m].copy()


@dataclass
class CandidateContacts:
    """Vertex-edge pairs found by the narrow phase (edge = start vertex of the CCW edge).

    ``geometry`` is their :class:`dda.contact.kinematics.ContactGeometry` at the positions
    the narrow phase looked at, when it has it (:func:`dda.contact.contacts.carry_over`
    takes it from there instead of computing it again).
    """

    vertex: np.ndarray
    edge: np.ndarray
    bj: np.ndarray
    bk: np.ndarray
    pairs: int = 0  # block pairs the broad phase handed to the narrow phase
    geometry: ContactGeometry | None = None

    def __len__(self):
        return len(self.vertex)


def keep_closed(cand: CandidateContacts, closed_vertex, closed_edge, x, topo,
                search_distance: float, penetration_limit: float, n_blocks: int,
                sunk_depth: float | np.ndarray = 0.0) -> CandidateContacts:
    """The candidates with the closed contacts of the last step that the narrow phase lost
    or moved to the next edge too early put back.

    The narrow phase's rules pick the edge a vertex *enters* by; once a contact is closed, its
    vertex may sink where those rules no longer see it, or see another edge. Two cases:

    - *Lost*: no candidate of the vertex against the edge's block. Where blocks stand corner
      on corner (a column, a wall's bond) a loaded corner sinks into the block below exactly
      along its side face's line: it is no distance inside that block, so the rule against
      far edges ("no deeper behind the edge's line than inside the block") dropped its
      contact, and the block fell through (``tests/stability/test_hard_cases.py``). The
      contact is put back when its vertex lies over its edge (foot parameter in [0, 1] up to
      round-off) or past its end by no more than it is deep behind the edge's line plus the
      search distance, and its gap is within ``[-penetration_limit, search_distance]``; not
      when the corner at the end of its edge nearer the vertex's foot has a candidate against
      an edge at the vertex (the mirrored vertex-vertex pair that the narrow phase kept
      instead). Only that end: two blocks that share a face corner on corner at both ends hold
      it by one vertex at each end, and the far end's contact is no mirror of the near end's
      (the 311-block cut slope lost a face's upper contact that way under Newton and the
      automatic penalty, and the face sank 6 mm in). And where the vertex's own block shares
      the face (an edge at the vertex runs against the contact's edge, within
      ``MIRROR_TOLERANCE_DEG``, over a length), a candidate at that end is a mirror only if
      its edge runs against the contact's edge too: a sliver that slid down a face had its
      corner taken on the other block's side, 20 degrees off, and the face lost its contact.
      Corners that only touch across a junction (a stack's diagonal neighbours) keep the
      plain rule.
    - *Turned the corner early*: the narrow phase chose the edge next to the contact's across
      a convex corner of the block for a sunk vertex (deeper behind the new edge than
      ``sunk_depth``, of the pair's thinner block) that still lies over its own edge and is
      not shallower behind the new edge by more than ``sunk_depth``.
      A vertex sunk into a block near its corner is held by the edge it is least deep behind;
      on a face shared corner on corner with collinear sides (two joint sets cutting a slope)
      the corner of one block sits under the other's face and as deep behind its side: the
      choice flipped between face and side on round-off, ended on the side, whose spring cannot
      hold the face, and the face sank in (the cut slope, Newton, t = 0.33 s: 0.888 mm behind
      the face, 0.875 mm behind the side; stopped by the guard 4.8 mm deep at 1.93 s). The
      contact keeps its edge; a vertex that slides round the corner leaves its edge's span
      and moves on to the next edge as before (:func:`dda.contact.contacts.carry_over`), and
      one that rotates round it deep inside the block (a block tipping over a stopper's
      corner 2 cm deep on a soft penalty) moves on once the new edge is the shallower by more
      than the sunk depth, unless the vertex's own edges still cross the contact's edge and
      not the new one: then the overlap of the two blocks is bounded by the contact's edge,
      and the new edge's depth is another contact's doing (a step's corner pressed 2.3 mm
      into an L's side at the floor's level sits 1.8 mm under the L's bottom, as far as the
      L sinks into the floor; moved to the bottom, it let the L's side cross the step 3.3 mm
      deep untracked, ``tests/stability/test_impacts.py``). ``sunk_depth`` 0 turns this off.
    """
    if len(closed_vertex) == 0:
        return cand
    blk = topo.block
    closed_vertex = np.asarray(closed_vertex, dtype=np.int64)
    closed_edge = np.asarray(closed_edge, dtype=np.int64)
    lost, turned, turned_row = _stale_closed(
        np.asarray(cand.vertex, dtype=np.int64), np.asarray(cand.edge, dtype=np.int64),
        np.asarray(cand.bk, dtype=np.int64), closed_vertex, closed_edge, blk, topo.nxt,
        topo.prv, n_blocks, np.ascontiguousarray(x, dtype=np.float64))
    if len(turned):
        sunk = _per_block(sunk_depth, n_blocks)
        # only across a convex corner of the block (a reflex one keeps both edges already)
        e, f = closed_edge[turned], cand.edge[turned_row]
        corner = np.where(f == topo.nxt[e], topo.nxt[e], e)
        hysteresis = np.minimum(sunk[blk[closed_vertex[turned]]], sunk[blk[e]])
        keep_turn = (~topo.reflex(x)[corner]) & (hysteresis > 0.0)
        turned, turned_row = turned[keep_turn], turned_row[keep_turn]
        hysteresis = hysteresis[keep_turn]
    if len(lost) == 0 and len(turned) == 0:
        return cand
    back = np.concatenate([lost, turned])
    frame = contact_geometry(x, closed_vertex[back], closed_edge[back], topo.nxt)
    over = (frame.xi >= -_XI_TOL) & (frame.xi <= 1.0 + _XI_TOL)
    # a corner on a corner: both sink together, the foot drifts past the end by round-off
    # and strain, by no more than the vertex is deep behind the line plus the search distance
    past = np.maximum(-frame.xi, frame.xi - 1.0) * frame.length
    near = over | (past <= search_distance + np.maximum(-frame.gap, 0.0))
    keep = (frame.gap <= search_distance) & (frame.gap >= -penetration_limit)
    keep[:len(lost)] &= near[:len(lost)]
    if len(turned):
        t = slice(len(lost), None)
        new_gap = (cand.geometry.gap[turned_row] if cand.geometry is not None else
                   contact_geometry(x, cand.vertex[turned_row], cand.edge[turned_row],
                                    topo.nxt).gap)
        # only a sunk vertex (deeper behind the new edge, its least deep, than the sunk
        # depth): the narrow phase's entrance rule judges the others
        # ... and however much shallower the new edge, while the vertex's own edges cross the
        # contact's edge and not the new one (the docstring's L on a step)
        v, f = closed_vertex[back[t]], cand.edge[turned_row]
        entered = (_edges_at_cross(x, v, closed_edge[back[t]], topo)
                   & ~_edges_at_cross(x, v, f, topo))
        keep[t] &= (over[t] & (-new_gap > hysteresis)
                    & ((new_gap - frame.gap[t] <= hysteresis) | entered))
    if not keep.any():
        return cand
    drop = turned_row[keep[len(lost):]]
    back = back[keep]
    stay = np.ones(len(cand), dtype=bool)
    stay[drop] = False
    vertex = np.concatenate([cand.vertex[stay], closed_vertex[back]])
    edge = np.concatenate([cand.edge[stay], closed_edge[back]])
    bk = np.concatenate([cand.bk[stay], blk[closed_edge[back]]])
    order = np.argsort(vertex * n_blocks + bk, kind="stable")
    geometry = None
    if cand.geometry is not None or len(cand) == 0:
        fields = ContactGeometry.__dataclass_fields__
        new = ContactGeometry(*(getattr(frame, name)[keep] for name in fields))
        parts = [new] if cand.geometry is None else [
            ContactGeometry(*(getattr(cand.geometry, name)[stay] for name in fields)), new]
        geometry = ContactGeometry(*(np.concatenate([getattr(g, name) for g in parts])[order]
                                     for name in fields))
    return CandidateContacts(vertex=vertex[order], edge=edge[order], bj=blk[vertex[order]],
                             bk=bk[order], pairs=cand.pairs, geometry=geometry)


def _edges_at_cross(x, vertex, edge, topo) -> np.ndarray:
    """(k,) whether either edge at each ``vertex`` properly crosses its ``edge`` (of
    another block)."""
    c, d, p = x[edge], x[topo.nxt[edge]], x[vertex]
    return (_segments_cross(p, x[topo.prv[vertex]], c, d, 0.0)
            | _segments_cross(p, x[topo.nxt[vertex]], c, d, 0.0))


@njit(cache=True)
def _stale_closed(cand_vertex, cand_edge, cand_block, closed_vertex, closed_edge, block, nxt,
                  prv, n_blocks, x):
    """The closed contacts :func:`keep_closed` may put back.

    Returns the indices of the lost ones (their vertex has no candidate against the edge's
    block, and the end of their edge nearer the vertex's foot has none against either edge
    at the vertex: its mirror), of the turned ones (the vertex's candidates against the block
    do not include the edge but include an edge next to it) and, for each turned one, the row
    of that candidate.
    """
    n_vertices = x.shape[0]
    n_cand = cand_vertex.shape[0]
    cos_tol = np.cos(np.radians(MIRROR_TOLERANCE_DEG))
    keys = cand_vertex * n_blocks + cand_block
    by_key = np.argsort(keys, kind="mergesort")
    sorted_keys = keys[by_key]
    pair_keys = np.sort(cand_vertex * n_vertices + cand_edge)
    n = closed_vertex.shape[0]
    lost = np.empty(n, dtype=np.int64)
    turned = np.empty(n, dtype=np.int64)
    turned_row = np.empty(n, dtype=np.int64)
    n_lost = 0
    n_turned = 0
    for i in range(n):
        v, e = closed_vertex[i], closed_edge[i]
        key = v * n_blocks + block[e]
        at = np.searchsorted(sorted_keys, key)
        if at < n_cand and sorted_keys[at] == key:
            same = False
            row = -1
            while at < n_cand and sorted_keys[at] == key:
                r = by_key[at]
                f = cand_edge[r]
                if f == e:
                    same = True
                elif row < 0 and (f == nxt[e] or f == prv[e]):
                    row = r
                at += 1
            if not same and row >= 0:
                turned[n_turned] = i
                turned_row[n_turned] = row
                n_turned += 1
            continue
        # the end nearer the foot: xi from P2 = nxt[e] towards P3 = e
        ex, ey = x[e, 0] - x[nxt[e], 0], x[e, 1] - x[nxt[e], 1]
        xi = ((x[v, 0] - x[nxt[e], 0]) * ex + (x[v, 1] - x[nxt[e], 1]) * ey) / (ex * ex
                                                                                + ey * ey)
        q = nxt[e] if xi < 0.5 else e
        found = False
        shares = -1  # whether the vertex's block shares the face: asked only on a hit
        for f in (v, prv[v]):  # the edges of the vertex's block that end at it
            pk = q * n_vertices + f
            at = np.searchsorted(pair_keys, pk)
            if found or not (at < pair_keys.shape[0] and pair_keys[at] == pk):
                continue
            if shares < 0:
                shares = 1 if _shares_face(v, e, xi, x, nxt, prv, cos_tol) else 0
            if shares == 0:
                found = True
            else:
                # a face shared with k (not corners touching across a junction): a pair at
                # its end across another joint is no mirror unless it holds this joint, its
                # edge running against this one
                gx, gy = x[nxt[f], 0] - x[f, 0], x[nxt[f], 1] - x[f, 1]
                found = ex * gx + ey * gy >= cos_tol * np.sqrt(
                    (ex * ex + ey * ey) * (gx * gx + gy * gy))
        if not found:
            lost[n_lost] = i
            n_lost += 1
    return lost[:n_lost].copy(), turned[:n_turned].copy(), turned_row[:n_turned].copy()


@njit(cache=True)
def _shares_face(v, e, xi, x, nxt, prv, cos_tol):
    """Whether vertex v, whose foot on edge e is at ``xi`` (from P2 = nxt[e] towards
    P3 = e), has an edge of its own block running against e (within ``acos(cos_tol)``) that
    overlaps it over a length: the two blocks share that face."""
    ex, ey = x[e, 0] - x[nxt[e], 0], x[e, 1] - x[nxt[e], 1]
    ee = ex * ex + ey * ey
    for far, g0 in ((nxt[v], v), (prv[v], prv[v])):
        gx, gy = x[nxt[g0], 0] - x[g0, 0], x[nxt[g0], 1] - x[g0, 1]
        if ex * gx + ey * gy < cos_tol * np.sqrt(ee * (gx * gx + gy * gy)):
            continue
        xi_far = ((x[far, 0] - x[nxt[e], 0]) * ex + (x[far, 1] - x[nxt[e], 1]) * ey) / ee
        lo = max(0.0, min(xi, xi_far))
        hi = min(1.0, max(xi, xi_far))
        if hi - lo > 1e-6:
            return True
    return False


def _empty_candidates(pairs: int) -> CandidateContacts:
    z = np.zeros(0, dtype=np.int64)
    return CandidateContacts(z, z, z, z, pairs)


def _vertex_block_rows(pairs, topo):
    """Every (vertex of j, block k) for both orders of each pair (a function of the pairs
    alone: kept in ``topo.memo``)."""
    def make():
        j = np.concatenate([pairs[:, 0], pairs[:, 1]])
        k = np.concatenate([pairs[:, 1], pairs[:, 0]])
        counts = topo.counts[j]
        pid = np.repeat(np.arange(len(j)), counts)
        run_start = np.repeat(np.cumsum(counts) - counts, counts)
        vertex = topo.offsets[j][pid] + (np.arange(int(counts.sum())) - run_start)
        return vertex, k[pid]

    return topo.memo.get(("vertex-block", pairs.tobytes()), make)


def _in_boxes(p, box, margin):
    """Whether each point lies in its box [xmin, ymin, xmax, ymax] grown by ``margin``."""
    return (
        (p[:, 0] >= box[:, 0] - margin)
        & (p[:, 0] <= box[:, 2] + margin)
        & (p[:, 1] >= box[:, 1] - margin)
        & (p[:, 1] <= box[:, 3] + margin)
    )


def _directed_vertex_block_pairs(pairs, topo, x, boxes, margin):
    """Every (vertex of j, block k) for both orders of each pair, vertex inside k's box."""
    vertex, kk = _vertex_block_rows(pairs, topo)
    inside = _in_boxes(x[vertex], boxes[kk], margin)
    return vertex[inside], kk[inside]


def _edge_runs(kblock, offsets):
    """Every edge of each block of ``kblock``, block after block: the row each edge belongs
    to, the edge (CCW start index), and each run's length and start."""
    counts = np.diff(offsets)[kblock]
    starts = np.cumsum(counts) - counts
    pid = np.repeat(np.arange(len(kblock)), counts)
    edge = offsets[kblock][pid] + (np.arange(len(pid)) - starts[pid])
    return pid, edge, counts, starts


def _expand_to_edges(vertex, kblock, offsets):
    pid, edge, _, _ = _edge_runs(kblock, offsets)
    return vertex[pid], edge


def _per_block(value, n_blocks) -> np.ndarray:
    """A number or an (n_blocks,) array as (n_blocks,) float64 (no copy of one that is)."""
    value = np.asarray(value, dtype=np.float64)
    if value.ndim == 0:
        return np.full(n_blocks, float(value))
    if value.shape != (n_blocks,):
        raise ValueError(f"expected a number or {n_blocks} values per block, got shape "
                         f"{value.shape}")
    return np.ascontiguousarray(value)


def narrow_phase(
    x: np.ndarray,
    topo: VertexTopology,
    search_distance: float,
    penetration_limit: float,
    pairs: np.ndarray | None = None,
    sunk_depth: float | np.ndarray = np.inf,
    boxes: np.ndarray | None = None,
    touch: float = 0.0,
) -> CandidateContacts:
    """Vertex-edge contact candidates of the current configuration (rules in the module doc).

    Parameters
    ----------
    x : (n_vertices, 2) current vertex positions
    topo : VertexTopology
    search_distance : largest gap at which a pair is kept (open contacts are tracked)
    penetration_limit : deepest penetration at which a pair is still recognised
    pairs : block pairs of the broad phase (computed here when None)
    sunk_depth : a vertex inside the other block deeper than this (its distance to that
        block's boundary) is sunk: the entrance test no longer judges its edges (the one
        along which the blocks overlap least holds it), and of a vertex-vertex case's two
        mirrored pairs the sunk one is kept too (two corners sunk into each other: one
        spring holds one corner, and the other, sliding round it, would go on sinking
        untracked). Near a corner a shallow vertex is
        nearer the side than the face it came through, so this must stay well above
        round-off and elastic strain: the simulation passes a quarter of the guard's
        tolerance. Infinite (the default) turns both off. A (n_blocks,) array gives each
        block its own; a pair takes the smaller of its two blocks' (a sliver elsewhere in the
        scene must not make the large blocks' resting depth "sunk").
    boxes : the blocks' bounding boxes at ``x`` (:func:`bounding_boxes`), when at hand
    touch : rule 3's touching tolerance, a fraction of the pair's smaller block (0: none).
        The simulation gives ``TOUCH_TOLERANCE`` at a run's first step only, where blocks
        were built touching: later, a corner just past another block's corner by round-off
        is the other rules' (taken throughout, it changed a strength-reduction trial of the
        bolted slope of ``examples/bolted_slope.py`` from stable to failed: F 1.502 ->
        1.355, not monotonic in F)
    """
    if boxes is None:
        boxes = bounding_boxes(x, topo.offsets)
    margin = max(search_distance, penetration_limit)
    if pairs is None:
        pairs = broad_phase(boxes, margin)
    if len(pairs) == 0:
        return _empty_candidates(len(pairs))
    x = np.ascontiguousarray(x, dtype=np.float64)
    if NARROW_KERNEL:
        (vertex, edge, bj, bk, p1, p2, p3, length, tau, normal, gap,
         xi) = _narrow_phase_kernel(x, topo.offsets, topo.nxt, topo.prv, topo.block,
                                    np.ascontiguousarray(pairs, dtype=np.int64), boxes, margin,
                                    search_distance, penetration_limit,
                                    _per_block(sunk_depth, len(topo.offsets) - 1),
                                    float(touch))
        if len(vertex) == 0:
            return _empty_candidates(len(pairs))
        return CandidateContacts(vertex=vertex, edge=edge, bj=bj, bk=bk, pairs=len(pairs),
                                 geometry=ContactGeometry(p1, p2, p3, length, tau, normal, gap,
                                                          xi))
    cross, scale, _, bisector = topo.turns(x)
    vertex, edge, kblock, on_edge, sunk = _narrow_kernel(
        x, topo.offsets, topo.nxt, topo.prv, np.ascontiguousarray(pairs, dtype=np.int64),
        boxes, margin, cross < 0.0, cross > 1e-9 * scale, bisector,
        search_distance, penetration_limit,
        _per_block(sunk_depth, len(topo.offsets) - 1), float(touch))
    if len(vertex) == 0:
        return _empty_candidates(len(pairs))
    # the kernel gives each (vertex, block)'s edges in the order they were chosen in;
    # the candidates go by vertex, then block
    order = np.argsort(vertex * len(topo.offsets) + kblock, kind="stable")
    vertex, edge, kblock = vertex[order], edge[order], kblock[order]
    frame = contact_geometry(x, vertex, edge, topo.nxt)
    score = -np.einsum("ij,ij->i", frame.normal, bisector[vertex])
    c = _Candidates(vertex, edge, frame.xi, kblock, score, frame.p1, on_edge[order],
                    sunk[order], np.arange(len(vertex)))
    c = _drop_mirrored(c, x, topo, margin)
    r = c.row
    geometry = frame if len(r) == len(vertex) else ContactGeometry(  # (none dropped)
        frame.p1[r], frame.p2[r], frame.p3[r], frame.length[r], frame.tau[r],
        frame.normal[r], frame.gap[r], frame.xi[r])
    return CandidateContacts(vertex=c.vertex, edge=c.edge, bj=topo.block[c.vertex],
                             bk=c.kblock, pairs=len(pairs), geometry=geometry)


NARROW_KERNEL = True
"""Whether :func:`narrow_phase` runs as one compiled pass (:func:`_narrow_phase_kernel`); False
composes it of :func:`_narrow_kernel`, numpy and :func:`_mirrored_kernel` (the same
candidates, to the bit)."""


@njit(cache=True)
def _narrow_phase_kernel(x, offsets, nxt, prv, block, pairs, boxes, margin, search_distance,
                         penetration_limit, sunk_depths, touch_tolerance):
    """:func:`narrow_phase` after the broad phase in one compiled pass: the vertices' turns,
    :func:`_narrow_kernel`, the candidates sorted by vertex then block (stably), their frames
    (:func:`dda.kernels.kinematics.frames`' arithmetic) and scores, and the mirrored
    vertex-vertex pairs dropped (:func:`_mirrored_kernel`). Returns vertex, edge, the two
    blocks and the frame (p1, p2, p3, length, tau, normal, gap, xi) of each candidate."""
    cross, scale, _, bisector = vertex_turns(x, prv, nxt)
    vertex, edge, kblock, on_edge, sunk = _narrow_kernel(
        x, offsets, nxt, prv, pairs, boxes, margin, cross < 0.0, cross > 1e-9 * scale,
        bisector, search_distance, penetration_limit, sunk_depths, touch_tolerance)
    n = vertex.shape[0]
    order = np.argsort(vertex * offsets.shape[0] + kblock, kind="mergesort")
    p1 = np.empty((n, 2))
    p2 = np.empty((n, 2))
    p3 = np.empty((n, 2))
    length = np.empty(n)
    tau = np.empty((n, 2))
    normal = np.empty((n, 2))
    gap = np.empty(n)
    xi = np.empty(n)
    score = np.empty(n)
    v_s = np.empty(n, dtype=np.int64)
    e_s = np.empty(n, dtype=np.int64)
    k_s = np.empty(n, dtype=np.int64)
    on_s = np.empty(n, dtype=np.bool_)
    sunk_s = np.empty(n, dtype=np.bool_)
    for r in range(n):
        i = order[r]
        v, e = vertex[i], edge[i]
        f = nxt[e]
        v_s[r], e_s[r], k_s[r], on_s[r], sunk_s[r] = v, e, kblock[i], on_edge[i], sunk[i]
        p1[r, 0], p1[r, 1] = x[v, 0], x[v, 1]
        p2[r, 0], p2[r, 1] = x[f, 0], x[f, 1]
        p3[r, 0], p3[r, 1] = x[e, 0], x[e, 1]
        ln, t0, t1, n0, n1, g, xr = _frame(x[v, 0], x[v, 1], x[f, 0], x[f, 1], x[e, 0],
                                           x[e, 1])
        length[r], tau[r, 0], tau[r, 1], normal[r, 0], normal[r, 1] = ln, t0, t1, n0, n1
        gap[r], xi[r] = g, xr
        score[r] = -((0.0 + n0 * bisector[v, 0]) + n1 * bisector[v, 1])
    drop = _mirrored_kernel(v_s, e_s, xi, p1, score, on_s, sunk_s, x, nxt, margin)
    keep = np.flatnonzero(~drop)
    if keep.shape[0] == n:
        return (v_s, e_s, block[v_s], k_s, p1, p2, p3, length, tau, normal, gap, xi)
    v_k = v_s[keep]
    return (v_k, e_s[keep], block[v_k], k_s[keep], p1[keep], p2[keep], p3[keep],
            length[keep], tau[keep], normal[keep], gap[keep], xi[keep])


@dataclass
class _Candidates:
    """Vertex-edge candidates on their way through :func:`narrow_phase`: vertex, edge, foot
    parameter xi, the edge's block, the score (how well the edge opposes the vertex), the
    vertex's position, foot on the edge, sunk, and the row of the narrow phase's frame."""

    vertex: np.ndarray
    edge: np.ndarray
    xi: np.ndarray
    kblock: np.ndarray
    score: np.ndarray
    p1: np.ndarray
    on_edge: np.ndarray
    sunk: np.ndarray
    row: np.ndarray

    def take(self, index) -> _Candidates:
        return _Candidates(*(a[index] for a in (self.vertex, self.edge, self.xi, self.kblock,
                                                self.score, self.p1, self.on_edge, self.sunk,
                                                self.row)))


_SIN_TOL = np.sin(np.radians(ENTRANCE_TOLERANCE_DEG))
# a vertex whose outward bisector points along an edge's outward normal by more than this
# (a cosine: round-off, not an angle) does not enter the edge
_BISECTOR_OUT = 1e-9


@njit(cache=True)
def _edge_order_before(i, j, least_deep, on_edge, neg_score):
    """Whether survivor i goes before survivor j (of one vertex and block): the least deep
    first, then the foot on the edge, then the best opposed, then the block's edge order."""
    if least_deep[i] != least_deep[j]:
        return least_deep[i]
    if on_edge[i] != on_edge[j]:
        return on_edge[i]
    if neg_score[i] != neg_score[j]:
        return neg_score[i] < neg_score[j]
    return i < j


@njit(cache=True)
def _narrow_kernel(x, offsets, nxt, prv, pairs, boxes, margin, convex, reflex, bisector,
                   search_distance, penetration_limit, sunk_depths, touch_tolerance):
    """The rules of :func:`narrow_phase` for every convex vertex of one block of a pair in the
    other's box grown by ``margin`` (both orders of every pair) against every edge of the
    other block: the gap range, the inside test behind an edge's line, the reach past the
    edge's end, the entrance test, then one edge per (vertex, block) and the edges across a
    reflex corner of the chosen one.

    Returns vertex, edge, block, foot on the edge and sunk of every candidate, each
    (vertex, block)'s in the order they are chosen in (the expressions are those of the numpy
    version: :func:`dda.contact.kinematics.contact_frame`, an einsum of two terms as
    ``(0 + a0 b0) + a1 b1``).
    """
    n_pairs = pairs.shape[0]
    cap = 0
    most = 0
    for q in range(n_pairs):
        for s in range(2):
            m = offsets[pairs[q, s] + 1] - offsets[pairs[q, s]]
            cap += 3 * m  # a vertex keeps at most one edge and the two across a corner
            most = max(most, m)
    out_v = np.empty(cap, dtype=np.int64)
    out_e = np.empty(cap, dtype=np.int64)
    out_k = np.empty(cap, dtype=np.int64)
    out_on = np.empty(cap, dtype=np.bool_)
    out_sunk = np.empty(cap, dtype=np.bool_)
    # the survivors of one (vertex, block)
    s_edge = np.empty(most, dtype=np.int64)
    s_gap = np.empty(most)
    s_len = np.empty(most)
    s_on = np.empty(most, dtype=np.bool_)
    s_sunk = np.empty(most, dtype=np.bool_)
    s_neg = np.empty(most)
    s_dist = np.empty(most)
    s_least = np.empty(most, dtype=np.bool_)
    s_near = np.empty(most, dtype=np.bool_)
    s_order = np.empty(most, dtype=np.int64)
    gap_tie = 1e-9
    xi_tol = 1e-9
    sin_tol = _SIN_TOL
    n_out = 0
    for s in range(2):
        for q in range(n_pairs):
            j = pairs[q, s]
            k = pairs[q, 1 - s]
            sunk_depth = min(sunk_depths[j], sunk_depths[k])
            touch = touch_tolerance * min(
                max(boxes[j, 2] - boxes[j, 0], boxes[j, 3] - boxes[j, 1]),
                max(boxes[k, 2] - boxes[k, 0], boxes[k, 3] - boxes[k, 1]))
            xmin = boxes[k, 0] - margin
            ymin = boxes[k, 1] - margin
            xmax = boxes[k, 2] + margin
            ymax = boxes[k, 3] + margin
            for v in range(offsets[j], offsets[j + 1]):
                px, py = x[v, 0], x[v, 1]
                if not (px >= xmin and px <= xmax and py >= ymin and py <= ymax):
                    continue
                if not convex[v]:
                    continue
                known = False  # inside test of v and k done
                inside = False
                depth = 0.0
                n_s = 0
                for e in range(offsets[k], offsets[k + 1]):
                    f = nxt[e]
                    p2x, p2y = x[f, 0], x[f, 1]
                    p3x, p3y = x[e, 0], x[e, 1]
                    dx, dy = p3x - p2x, p3y - p2y
                    length = np.hypot(dx, dy)
                    tx, ty = dx / length, dy / length
                    nx, ny = -ty, tx
                    rx, ry = px - p2x, py - p2y
                    gap = (0.0 + rx * nx) + ry * ny
                    if not (gap <= search_distance and gap >= -penetration_limit):
                        continue
                    xi = ((0.0 + rx * tx) + ry * ty) / length
                    on_edge = xi >= -xi_tol and xi <= 1.0 + xi_tol
                    reach = search_distance
                    sunk = False
                    near = True  # no deeper behind the line than inside the block
                    if gap < -gap_tie * length:
                        # behind the edge's line: only a vertex inside the block, and no
                        # deeper behind the line than inside the block (plus sunk_depth)
                        if not known:
                            inside, depth, _ = _point_in_block(px, py, k, x, offsets, nxt)
                            known = True
                        deep = inside and depth > sunk_depth
                        if deep:
                            sunk = True
                            reach = search_distance + depth
                        if not inside and not (depth <= gap_tie * length
                                               or depth <= touch and -gap <= touch):
                            continue
                        if -gap > depth + sunk_depth:
                            if not sunk:
                                continue
                            near = False
                    dist = abs(gap)  # from the vertex to the edge (the segment)
                    if not on_edge:
                        if xi < 0.5:
                            ex, ey = p2x, p2y
                        else:
                            ex, ey = p3x, p3y
                        dist = np.hypot(px - ex, py - ey)
                        if not dist <= reach:
                            continue
                    if sunk:
                        # a sunk vertex: the edge whose spring clears the least overlap
                        # (:func:`_fan_overlap`) counts as the nearest
                        dist = max(dist, _fan_overlap(v, gap, nx, ny, k, x, offsets, nxt, prv))
                    else:
                        # both edges at v leave it towards the outside of the line (within
                        # the tolerance), and v's outward bisector does not point the way
                        # the edge's normal does: a sharp wedge whose edges lie on and
                        # behind the line (its corner slid along a floor into a block that
                        # stands on the same floor, whose bottom edge it then lies on) is
                        # not entering that edge
                        out = (0.0 + nx * bisector[v, 0]) + ny * bisector[v, 1]
                        entering = out <= _BISECTOR_OUT
                        for nb in (prv[v], nxt[v]):
                            ax, ay = x[nb, 0] - px, x[nb, 1] - py
                            arm_len = np.hypot(ax, ay)
                            if not ((0.0 + ax * nx) + ay * ny) >= -sin_tol * arm_len:
                                entering = False
                        if not entering:
                            continue
                    s_edge[n_s] = e
                    s_gap[n_s] = gap
                    s_len[n_s] = length
                    s_on[n_s] = on_edge
                    s_sunk[n_s] = sunk
                    s_neg[n_s] = (0.0 + nx * bisector[v, 0]) + ny * bisector[v, 1]
                    s_dist[n_s] = dist
                    s_near[n_s] = near
                    n_s += 1
                if n_s == 0:
                    continue
                # one edge: of the nearest, the least deep, then foot on the edge, then the
                # best opposed. The nearest first: round a concave block's convex corner
                # (a step's riser top), a farther edge's line may lie beyond the vertex
                # (the tread below the riser), and the least deep of all would be that
                # edge while the vertex rests on the nearer one
                nearest = np.inf
                for i in range(n_s):
                    nearest = min(nearest, s_dist[i])
                best = -np.inf
                for i in range(n_s):
                    s_least[i] = s_dist[i] <= nearest + gap_tie * s_len[i]
                    if s_least[i]:
                        best = max(best, s_gap[i])
                for i in range(n_s):
                    s_least[i] = s_least[i] and s_gap[i] >= best - gap_tie * s_len[i]
                    s_order[i] = i
                for i in range(1, n_s):  # insertion sort (a handful of edges)
                    cur = s_order[i]
                    t = i
                    while t > 0 and _edge_order_before(cur, s_order[t - 1], s_least, s_on,
                                                       s_neg):
                        s_order[t] = s_order[t - 1]
                        t -= 1
                    s_order[t] = cur
                chosen = s_edge[s_order[0]]
                # and the edges across a reflex corner of the chosen one
                for t in range(n_s):
                    i = s_order[t]
                    e = s_edge[i]
                    if t == 0 or s_near[i] and (e == nxt[chosen] and reflex[nxt[chosen]] or
                                                e == prv[chosen] and reflex[chosen]):
                        out_v[n_out] = v
                        out_e[n_out] = e
                        out_k[n_out] = k
                        out_on[n_out] = s_on[i]
                        out_sunk[n_out] = s_sunk[i]
                        n_out += 1
    return (out_v[:n_out].copy(), out_e[:n_out].copy(), out_k[:n_out].copy(),
            out_on[:n_out].copy(), out_sunk[:n_out].copy())


def _groups(keys):
    """Runs of equal keys: the distinct keys (sorted), the first index of each, and the run
    of every key (``np.unique(keys, return_index=True, return_inverse=True)``)."""
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    head = np.empty(len(keys), dtype=bool)
    head[:1] = True
    np.not_equal(sorted_keys[1:], sorted_keys[:-1], out=head[1:])
    inverse = np.empty(len(keys), dtype=np.int64)
    inverse[order] = np.cumsum(head) - 1
    return sorted_keys[head], order[head], inverse


def _drop_mirrored(c: _Candidates, x, topo, reach) -> _Candidates:
    """Vertex-vertex: keep one of the mirrored pairs (P on an edge at Q, Q on an edge at P)."""
    drop = _mirrored_kernel(c.vertex, c.edge, c.xi, c.p1, c.score, c.on_edge, c.sunk, x,
                            topo.nxt, float(reach))
    return c.take(~drop) if drop.any() else c


@njit(cache=True)
def _mirrored_kernel(vertex, edge, xi, p1, score, on_edge, sunk, x, nxt, reach):
    """Which candidates :func:`_drop_mirrored` drops: of the vertex-vertex cases (P within
    ``reach`` of the edge's end Q nearer its foot) with the same two vertices, the first by
    (foot on the edge, best opposed, lower vertex, order) is kept, and of the others those
    of the other vertex that are not sunk go."""
    n = vertex.shape[0]
    n_vertices = x.shape[0]
    drop = np.zeros(n, dtype=np.bool_)
    idx = np.empty(n, dtype=np.int64)
    key = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):
        q = nxt[edge[i]] if xi[i] < 0.5 else edge[i]
        dx = p1[i, 0] - x[q, 0]
        dy = p1[i, 1] - x[q, 1]
        if np.sqrt(dx * dx + dy * dy) <= reach:
            idx[m] = i
            key[m] = min(vertex[i], q) * n_vertices + max(vertex[i], q)
            m += 1
    if m == 0:
        return drop
    idx = idx[:m]
    key = key[:m]
    order = np.argsort(key, kind="mergesort")
    start = 0
    while start < m:
        stop = start + 1
        while stop < m and key[order[stop]] == key[order[start]]:
            stop += 1
        if stop - start > 1:
            head = idx[order[start]]
            for t in range(start + 1, stop):
                i = idx[order[t]]
                if on_edge[i] != on_edge[head]:
                    better = on_edge[i]
                elif score[i] != score[head]:
                    better = score[i] > score[head]
                else:
                    better = vertex[i] < vertex[head]
                if better:
                    head = i
            for t in range(start, stop):
                i = idx[order[t]]
                # only the mirror image goes: the same vertex in a reflex corner keeps both
                # edges; a sunk vertex keeps its own spring
                if i != head and vertex[i] != vertex[head] and not sunk[i]:
                    drop[i] = True
        start = stop
    return drop


def find_overlaps(x: np.ndarray, offsets: np.ndarray, rel_tol: float = 1e-6) -> list:
    """Pairs of blocks whose interiors overlap (touching along edges or at corners is fine):
    the pairs of :func:`overlap_depths`, sorted."""
    return [(a, b) for a, b, _ in overlap_depths(x, offsets, rel_tol)]


def overlap_depths(x: np.ndarray, offsets: np.ndarray, rel_tol: float = 1e-6) -> list:
    """Pairs of blocks whose interiors overlap, and how deep.

    Two simple polygons overlap when a vertex, an edge midpoint or the centroid of one lies
    inside the other, or two of their edges cross. (Vertices and crossings alone miss a block
    laid exactly on another, or inside it along shared edges.) A pair overlaps only deeper
    than ``rel_tol`` times the smaller block's size (the larger side of its bounding box), so
    coordinates typed with 6 decimals that leave blocks 1e-7 m into each other count as
    touching: the contacts take such an overlap up at the first step.

    The depth of a pair is that of its deepest point inside the other block: a vertex or edge
    midpoint's distance to the other block's boundary, or for two crossing edges the smaller
    distance of an edge's end past the other edge's line, :math:`\\min(|d_1|, |d_2|) / |q|`
    with :math:`d` the cross products of the orientation test. Used once, to check a scene
    before a run.

    Returns
    -------
    list of (int, int, float)
        ``(a, b, depth)`` with a < b, sorted by pair; depth in the coordinates' unit.
    """
    topo = VertexTopology.from_offsets(offsets)
    boxes = bounding_boxes(x, offsets)
    pairs = broad_phase(boxes, 0.0)
    if len(pairs) == 0:
        return []
    size = np.max(boxes[:, 2:] - boxes[:, :2], axis=1)  # each block's size
    deepest: dict = {}

    def mark(block_a, block_b, depth):
        tol = rel_tol * np.minimum(size[block_a], size[block_b])
        keep = depth > tol
        for a, b, d in zip(block_a[keep].tolist(), block_b[keep].tolist(),
                           depth[keep].tolist(), strict=True):
            key = (min(a, b), max(a, b))
            deepest[key] = max(deepest.get(key, 0.0), d)

    # vertices and edge midpoints of j inside k
    vertex, kblock = _directed_vertex_block_pairs(pairs, topo, x, boxes, 0.0)
    for points in (x[vertex], 0.5 * (x[vertex] + x[topo.nxt[vertex]])):
        inside, depth, _ = inside_depth(points, kblock, x, offsets, topo.nxt)
        mark(topo.block[vertex[inside]], kblock[inside], depth[inside])
    # a block's centroid (when it lies inside the block) inside the other block
    centroid = polygon_integrals(x, offsets, topo.nxt).centroid
    j = np.concatenate([pairs[:, 0], pairs[:, 1]])
    k = np.concatenate([pairs[:, 1], pairs[:, 0]])
    own, _, _ = inside_depth(centroid[j], j, x, offsets, topo.nxt)
    inside, depth, _ = inside_depth(centroid[j], k, x, offsets, topo.nxt)
    inside &= own
    mark(j[inside], k[inside], depth[inside])
    # edge crossings between the two blocks of a pair: every edge of one block against every
    # edge of the other (no box filter: an edge may cross a box whose corners all lie outside)
    e1, blk2 = _directed_vertex_block_pairs(pairs, topo, x, boxes, np.inf)
    e1, e2 = _expand_to_edges(e1, blk2, offsets)
    p1, p2 = x[e1], x[topo.nxt[e1]]
    q1, q2 = x[e2], x[topo.nxt[e2]]

    def orient(u, v, w):
        return (v[:, 0] - u[:, 0]) * (w[:, 1] - u[:, 1]) - (v[:, 1] - u[:, 1]) * (w[:, 0] - u[:, 0])

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    proper = (d1 * d2 < 0) & (d3 * d4 < 0)
    lp = np.hypot(*(p2 - p1).T)
    lq = np.hypot(*(q2 - q1).T)
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = np.minimum(np.minimum(np.abs(d1), np.abs(d2)) / lq,
                           np.minimum(np.abs(d3), np.abs(d4)) / lp)
    mark(topo.block[e1[proper]], topo.block[e2[proper]], depth[proper])
    return [(a, b, deepest[(a, b)]) for a, b in sorted(deepest)]
