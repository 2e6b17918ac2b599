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
   ``sunk_depth``;
4. the vertex is locally the first point of its block to cross the edge's line: both of its
   edges leave it towards the outside of that line, within ``ENTRANCE_TOLERANCE_DEG`` (a
   vertex sunk into the block deeper than ``sunk_depth`` is exempt: the nearest edge holds
   it).
Of several edges of one block that pass for the same vertex, the one with the largest gap is
preferred (the least deep: at a corner where four blocks meet, a vertex sliding along one
joint past the corner must not be taken as deep behind the other joint's line), then one whose
foot lies on the edge, then the one whose outward normal is most opposed to the vertex's
outward bisector. That choice is right where the block is convex; at a reflex (concave)
vertex of the block the solid is the union of the two edges' half-planes, and a vertex in the
corner is near both: the edge across a reflex vertex from the chosen one is kept as well (Shi's
rule for a convex vertex entering a concave angle: two vertex-edge contacts). A vertex-vertex
case (the foot at the end of the edge, the two vertices within the search distance) shows up
as two mirrored pairs, P on an edge at Q and Q on an edge at P; only one is kept: the one whose
foot lies on its edge, else the better opposed one; both when the other's vertex is inside the
other block deeper than ``sunk_depth`` (corners sunk into each other).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from dda.contact.kinematics import ContactGeometry, contact_geometry
from dda.geometry import next_vertex_index, polygon_integrals

__all__ = ["VertexTopology", "broad_phase", "narrow_phase", "find_overlaps", "CandidateContacts",
           "inside_depth"]

ENTRANCE_TOLERANCE_DEG = 20.0
_XI_TOL = 1e-9
# gaps to two edges within this fraction of the edge length are a tie (round-off)
_GAP_TIE = 1e-9


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

    def _turn(self, x: np.ndarray, index=None):
        """The arms a = prev - v and b = next - v of every vertex (or of ``index``), the
        cross product a x b and its round-off scale |a| |b|."""
        v = slice(None) if index is None else index
        p = x if index is None else x[index]
        a = x[self.prv[v]] - p
        b = x[self.nxt[v]] - p
        cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        return a, b, cross, np.hypot(a[:, 0], a[:, 1]) * np.hypot(b[:, 0], b[:, 1])

    def straight(self, x: np.ndarray, index=None) -> np.ndarray:
        """Whether each vertex (or each of ``index``) lies on the straight line of its two
        edges (to round-off): a point of a side, not a corner."""
        a, b, cross, scale = self._turn(x, index)
        return (np.abs(cross) <= 1e-9 * scale) & (np.einsum("ij,ij->i", a, b) < 0.0)

    def reflex(self, x: np.ndarray) -> np.ndarray:
        """Whether each vertex is reflex (its interior angle above 180 degrees by more than
        round-off; a straight vertex between collinear edges is not)."""
        _, _, cross, scale = self._turn(x)
        return cross > 1e-9 * scale

    def convex_and_bisector(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Convexity of every vertex and its outward unit bisector."""
        a, b, cross, _ = self._turn(x)
        return cross < 0.0, _outward_bisector(a, b)


def _norm(v):
    """Row norms of (n, 2) ``v``: ``np.linalg.norm(v, axis=1)`` to the bit, without its
    overhead."""
    return np.sqrt(v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1])


def _outward_bisector(a, b):
    """The outward unit bisector of vertices with arms a (to prev) and b (to next)."""
    ua = a / _norm(a)[:, None]
    ub = b / _norm(b)[:, None]
    inward = ua + ub
    norm = _norm(inward)
    # a straight vertex has no bisector; its inward normal is the left normal of prev->next
    straight = norm < 1e-12
    if straight.any():
        left = np.stack([-ub[:, 1], ub[:, 0]], axis=1)
        inward = np.where(straight[:, None], left, inward / np.maximum(norm, 1e-300)[:, None])
    else:
        inward = inward / np.maximum(norm, 1e-300)[:, None]
    return -inward


def bounding_boxes(x: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(n_blocks, 4) boxes [xmin, ymin, xmax, ymax]."""
    starts = offsets[:-1]
    lo = np.minimum.reduceat(x, starts, axis=0)
    hi = np.maximum.reduceat(x, starts, axis=0)
    return np.concatenate([lo, hi], axis=1)


def broad_phase(boxes: np.ndarray, margin: float) -> np.ndarray:
    """Pairs (i < j) of blocks whose boxes, grown by ``margin``, overlap (sort and sweep).

    The sweep runs along the axis of larger spread of the box centres; every step is a numpy
    operation (sort, searchsorted, repeat), so the cost is O(N log N + candidate pairs).
    """
    n = len(boxes)
    if n < 2:
        return np.zeros((0, 2), dtype=np.int64)
    lo = boxes[:, :2] - margin
    hi = boxes[:, 2:] + margin
    centres = 0.5 * (lo + hi)
    axis = int(np.argmax(centres.max(axis=0) - centres.min(axis=0)))
    other = 1 - axis
    order = np.argsort(lo[:, axis], kind="stable")
    lo_sorted = lo[order, axis]
    stop = np.searchsorted(lo_sorted, hi[order, axis], side="right")
    first = np.arange(1, n + 1)
    counts = np.maximum(stop - first, 0)
    total = int(counts.sum())
    if total == 0:
        return np.zeros((0, 2), dtype=np.int64)
    i_sorted = np.repeat(np.arange(n), counts)
    run_start = np.repeat(np.cumsum(counts) - counts, counts)
    j_sorted = np.repeat(first, counts) + (np.arange(total) - run_start)
    i, j = order[i_sorted], order[j_sorted]
    keep = (lo[i, other] <= hi[j, other]) & (lo[j, other] <= hi[i, other])
    i, j = i[keep], j[keep]
    out = np.empty((len(i), 2), dtype=np.int64)
    np.minimum(i, j, out=out[:, 0])
    np.maximum(i, j, out=out[:, 1])
    return out


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


def _edge_runs(kblock, offsets, counts=None):
    """Every edge of each block of ``kblock``, block after block: the row each edge belongs
    to, the edge (CCW start index), and each run's length and start."""
    counts = np.diff(offsets)[kblock] if counts is None else counts[kblock]
    starts = np.cumsum(counts) - counts
    pid = np.repeat(np.arange(len(kblock)), counts)
    edge = offsets[kblock][pid] + (np.arange(len(pid)) - starts[pid])
    return pid, edge, counts, starts


def _expand_to_edges(vertex, kblock, offsets):
    pid, edge, _, _ = _edge_runs(kblock, offsets)
    return vertex[pid], edge


def _vertex_edge_rows(vertex, kblock, topo):
    """Every edge of block k for each (vertex, k) (kept in ``topo.memo``: the rows are the
    same from step to step while the blocks stay near each other)."""
    def make():
        pid, edge, _, _ = _edge_runs(kblock, topo.offsets, topo.counts)
        return vertex[pid], edge

    return topo.memo.get(("vertex-edge", vertex.tobytes(), kblock.tobytes()), make)


def narrow_phase(
    x: np.ndarray,
    topo: VertexTopology,
    search_distance: float,
    penetration_limit: float,
    pairs: np.ndarray | None = None,
    sunk_depth: float = np.inf,
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
        block's boundary) is sunk: the entrance test no longer judges its edges (the nearest
        holds it), and of a vertex-vertex case's two mirrored pairs the sunk one is kept too
        (two corners sunk into each other: one spring holds one corner, and the other,
        sliding round it, would go on sinking untracked). Near a corner a shallow vertex is
        nearer the side than the face it came through, so this must stay well above
        round-off and elastic strain: the simulation passes a quarter of the guard's
        tolerance. Infinite (the default) turns both off.
    """
    boxes = bounding_boxes(x, topo.offsets)
    margin = max(search_distance, penetration_limit)
    if pairs is None:
        pairs = broad_phase(boxes, margin)
    if len(pairs) == 0:
        return _empty_candidates(len(pairs))
    vertex, kblock = _directed_vertex_block_pairs(pairs, topo, x, boxes, margin)
    a, b, cross, scale = topo._turn(x)
    keep = cross[vertex] < 0.0  # convex (counter-clockwise: prev -> v -> next turns left)
    vertex, kblock = vertex[keep], kblock[keep]
    if len(vertex) == 0:
        return _empty_candidates(len(pairs))
    vertex, edge = _vertex_edge_rows(vertex, kblock, topo)
    frame = contact_geometry(x, vertex, edge, topo.nxt)
    on_edge = (frame.xi >= -_XI_TOL) & (frame.xi <= 1.0 + _XI_TOL)
    ok, sunk = _within_reach(x, topo, vertex, edge, frame, on_edge, search_distance,
                             penetration_limit, sunk_depth)
    row = ok.nonzero()[0]
    if len(row) == 0:
        return _empty_candidates(len(pairs))
    v = vertex[row]
    c = _Candidates(v, edge[row], frame.xi[row], topo.block[edge[row]],
                    -np.einsum("ij,ij->i", frame.normal[row], _outward_bisector(a[v], b[v])),
                    frame.p1[row], on_edge[row], sunk[row], row)
    c = _one_edge_per_block(c, topo, frame.gap[row], frame.length[row],
                            cross > 1e-9 * scale)
    c = _drop_mirrored(c, x, topo, max(search_distance, penetration_limit))
    r = c.row
    geometry = ContactGeometry(frame.p1[r], frame.p2[r], frame.p3[r], frame.length[r],
                               frame.tau[r], frame.normal[r], frame.gap[r], frame.xi[r])
    return CandidateContacts(vertex=c.vertex, edge=c.edge, bj=topo.block[c.vertex],
                             bk=c.kblock, pairs=len(pairs), geometry=geometry)


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


def _within_reach(x, topo, vertex, edge, frame, on_edge, search_distance, penetration_limit,
                  sunk_depth):
    """Which vertex-edge pairs may be contacts (gap, inside test, end reach, entrance), and
    which vertices are sunk (the rules of :func:`narrow_phase`)."""
    p1, p2, p3 = frame.p1, frame.p2, frame.p3
    normal, gap, xi = frame.normal, frame.gap, frame.xi
    # past the end of the edge only in a vertex-vertex case: P near the edge's end vertex
    end = np.where((xi < 0.5)[:, None], p2, p3)
    end_distance = np.hypot(*(p1 - end).T)
    ok = (gap <= search_distance) & (gap >= -penetration_limit)
    sunk, reach = _behind_lines(x, topo, vertex, edge, frame, ok, search_distance, sunk_depth)
    # past the end of the edge only in a vertex-vertex case: P near the edge's end vertex
    near_end = end_distance <= reach
    ok &= on_edge | near_end
    # entrance test: both edges at the vertex leave towards the outside of the edge's line.
    # It says which edge a vertex comes through; a vertex already inside the block (a soft
    # penalty, a deep impact) is held by the edge it is least deep behind whatever its
    # arms do: a box corner sunk 1.2 cm into an anvil's apex and turning failed the test on
    # the near face and was taken 3.5 cm deep behind the other, 500 J/m of spring at once
    for nb in (topo.prv[vertex], topo.nxt[vertex]):
        arm = x[nb] - p1
        arm_len = np.hypot(arm[:, 0], arm[:, 1])
        ok &= sunk | (np.einsum("ij,ij->i", arm, normal) >= -_SIN_TOL * arm_len)
    return ok, sunk


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


def _behind_lines(x, topo, vertex, edge, frame, ok, search_distance, sunk_depth):
    """The inside test of vertices behind an edge's line (``ok`` is updated in place).

    Returns the sunk flags and how far past an edge's end each pair still reaches.
    """
    gap = frame.gap
    # a vertex behind an edge's line is in contact with it only when it is inside the
    # block: beyond a thin block's far side it is behind the near edge's line too (gaps
    # within round-off of zero are left alone: touching is neither inside nor out)
    behind = (ok & (gap < -_GAP_TIE * frame.length)).nonzero()[0]
    sunk = np.zeros(len(ok), dtype=bool)
    reach = np.full(len(ok), search_distance)
    if len(behind) == 0:
        return sunk, reach
    # once per (vertex, block), not per edge
    nb = len(topo.offsets)
    key, first, back = _groups(vertex[behind] * nb + topo.block[edge[behind]])
    inside, depth, _ = _inside_depth(frame.p1[behind[first]], key % nb, x, topo,
                                     nearest=False)
    inside, depth = inside[back], depth[back]
    # on the boundary (within round-off of an edge) is neither in nor out: a corner of a
    # block sitting on an equal-width one lies on the lower block's side line
    on_boundary = depth <= _GAP_TIE * frame.length[behind]
    ok[behind[~inside & ~on_boundary]] = False
    # nor deeper behind that line than the vertex is inside the block, give or take
    # sunk_depth: a corner that has just entered a box through its top face is 3.8 cm
    # behind the line of the box's side face, and a spring there throws the box off
    too_deep = -gap[behind] > depth + sunk_depth
    ok[behind[too_deep]] = False
    deep = inside & (depth > sunk_depth)
    sunk[behind[deep]] = True
    # a vertex sunk into a block's reflex corner is nearest to the corner itself, past
    # the end of both its edges: it reaches them as far as it is deep
    reach[behind[deep]] += depth[deep]
    return sunk, reach


def _one_edge_per_block(c: _Candidates, topo, gap, length, reflex) -> _Candidates:
    """One edge per (vertex, block): the one the vertex is least deep behind (the signed
    distance to a convex block is the largest of the gaps to its edges' lines), then one
    whose foot is on it, then the best opposed; and across a reflex corner the other edge.
    ``reflex`` says which vertices are reflex (:meth:`VertexTopology.reflex`). The result is
    sorted by vertex, then block."""
    key = c.vertex * len(topo.offsets) + c.kblock
    uniq, first_of, group = _groups(key)
    if len(uniq) == len(key):  # one edge each already: nothing to choose, only the order
        return c.take(first_of)
    best = np.full(len(first_of), -np.inf)
    np.maximum.at(best, group, gap)
    least_deep = gap >= best[group] - _GAP_TIE * length
    c = c.take(np.lexsort((-c.score, ~c.on_edge, ~least_deep, c.kblock, c.vertex)))
    first = np.ones(len(c.vertex), dtype=bool)
    first[1:] = (c.vertex[1:] != c.vertex[:-1]) | (c.kblock[1:] != c.kblock[:-1])
    # at a reflex vertex of block k the solid is the union of its two edges' half-planes, so
    # a vertex near that corner is near both edges at once: keep the edge across the corner
    # from the chosen one too (a block sliding into a notch would otherwise lose its seat on
    # the face as soon as the notch's wall becomes the least deep edge)
    chosen = c.edge[first][np.cumsum(first) - 1]
    keep = first | ((c.edge == topo.nxt[chosen]) & reflex[topo.nxt[chosen]]) | (
        (c.edge == topo.prv[chosen]) & reflex[chosen])
    return c.take(keep)


def _drop_mirrored(c: _Candidates, x, topo, reach) -> _Candidates:
    """Vertex-vertex: keep one of the mirrored pairs (P on an edge at Q, Q on an edge at P)."""
    vertex = c.vertex
    near_end = np.where(c.xi < 0.5, topo.nxt[c.edge], c.edge)
    vv = _norm(c.p1 - x[near_end]) <= reach
    if not vv.any():
        return c
    idx = vv.nonzero()[0]
    a = np.minimum(vertex[idx], near_end[idx])
    b = np.maximum(vertex[idx], near_end[idx])
    order = np.lexsort((vertex[idx], -c.score[idx], ~c.on_edge[idx], b, a))
    a, b, idx = a[order], b[order], idx[order]
    head = np.ones(len(idx), dtype=bool)
    head[1:] = (a[1:] != a[:-1]) | (b[1:] != b[:-1])
    kept_vertex = vertex[idx][head][np.cumsum(head) - 1]
    # only the mirror image goes: the same vertex in a reflex corner keeps both edges
    dup = ~head & (vertex[idx] != kept_vertex)
    dup &= ~c.sunk[idx]  # a sunk vertex keeps its own spring
    drop = np.zeros(len(vertex), dtype=bool)
    drop[idx[dup]] = True
    return c.take(~drop)


def inside_depth(p: np.ndarray, kblock: np.ndarray, x: np.ndarray, offsets: np.ndarray,
                 nxt: np.ndarray, nearest: bool = True):
    """Whether each point ``p`` (n, 2) lies inside block ``kblock`` (n,), its distance to the
    block's boundary and the nearest edge (CCW start index; None unless ``nearest``), all
    points at once.

    Inside is the even-odd rule on a ray towards +x (half-open in y, so a ray through a
    vertex counts once): exact for non-convex blocks. The distance is the least distance to
    an edge segment.
    """
    if len(p) == 0:
        z = np.zeros(0, dtype=np.int64)
        return np.zeros(0, dtype=bool), np.zeros(0), z
    pid, edge, _, starts = _edge_runs(kblock, offsets)
    return _inside_depth_of_runs(p, x, pid, edge, nxt[edge], starts, nearest)


def _inside_depth(p, kblock, x, topo: VertexTopology, nearest: bool = True):
    """:func:`inside_depth` with the edge runs of ``kblock`` kept in ``topo.memo``."""
    if len(p) == 0:
        return inside_depth(p, kblock, x, topo.offsets, topo.nxt, nearest)

    def make():
        pid, edge, _, starts = _edge_runs(kblock, topo.offsets, topo.counts)
        return pid, edge, topo.nxt[edge], starts

    runs = topo.memo.get(("edge-runs", kblock.tobytes()), make)
    return _inside_depth_of_runs(p, x, *runs, nearest)


def _inside_depth_of_runs(p, x, pid, edge, edge_end, starts, nearest):
    q = p[pid]
    a = x[edge]
    b = x[edge_end]
    ab = b - a
    qa = q - a
    # compare the end points themselves: a + (b - a) need not be b in floating point, and a
    # ray through a vertex would then count it twice or not at all
    straddles = (a[:, 1] > q[:, 1]) != (b[:, 1] > q[:, 1])
    dy = np.where(straddles, ab[:, 1], 1.0)
    crossing = straddles & (q[:, 0] < a[:, 0] + qa[:, 1] * ab[:, 0] / dy)
    len2 = np.einsum("ij,ij->i", ab, ab)
    t = np.minimum(np.maximum(np.einsum("ij,ij->i", qa, ab) / np.maximum(len2, 1e-300), 0.0),
                   1.0)
    dist = np.hypot(*(q - (a + t[:, None] * ab)).T)
    inside = np.bitwise_xor.reduceat(crossing, starts)  # an odd number of crossings
    depth = np.minimum.reduceat(dist, starts)
    if not nearest:
        return inside, depth, None
    # the nearest edge: the first of its run at the run's least distance
    idx = (dist == depth[pid]).nonzero()[0]
    first = np.ones(len(idx), dtype=bool)
    first[1:] = pid[idx[1:]] != pid[idx[:-1]]
    near = np.empty(len(p), dtype=np.int64)
    near[pid[idx[first]]] = edge[idx[first]]
    return inside, depth, near


def _strictly_inside(p, kblock, x, offsets, nxt, tol):
    """Whether each point p (n, 2) lies inside block kblock (n,) farther than tol from its
    boundary."""
    inside, depth, _ = inside_depth(p, kblock, x, offsets, nxt)
    return inside & (depth > tol)


def find_overlaps(x: np.ndarray, offsets: np.ndarray, rel_tol: float = 1e-9) -> list:
    """Pairs of blocks whose interiors overlap (touching along edges or at corners is fine).

    Two simple polygons overlap when a vertex, an edge midpoint or the centroid of one lies
    strictly inside the other, or two of their edges cross properly. (Vertices and crossings
    alone miss a block laid exactly on another, or inside it along shared edges.) Used once,
    to check a scene before a run.
    """
    topo = VertexTopology.from_offsets(offsets)
    boxes = bounding_boxes(x, offsets)
    pairs = broad_phase(boxes, 0.0)
    if len(pairs) == 0:
        return []
    size = np.max(boxes[:, 2:] - boxes[:, :2])
    tol = rel_tol * size
    bad = set()

    def mark(block_a, block_b):
        for a, b in zip(block_a.tolist(), block_b.tolist(), strict=True):
            bad.add((min(a, b), max(a, b)))

    # vertices and edge midpoints of j strictly inside k
    vertex, kblock = _directed_vertex_block_pairs(pairs, topo, x, boxes, 0.0)
    for points in (x[vertex], 0.5 * (x[vertex] + x[topo.nxt[vertex]])):
        inside = _strictly_inside(points, kblock, x, offsets, topo.nxt, tol)
        mark(topo.block[vertex[inside]], kblock[inside])
    # a block's centroid (when it lies inside the block) strictly inside the other block
    centroid = polygon_integrals(x, offsets, topo.nxt).centroid
    j = np.concatenate([pairs[:, 0], pairs[:, 1]])
    k = np.concatenate([pairs[:, 1], pairs[:, 0]])
    own = _strictly_inside(centroid[j], j, x, offsets, topo.nxt, tol)
    inside = own & _strictly_inside(centroid[j], k, x, offsets, topo.nxt, tol)
    mark(j[inside], k[inside])
    # proper edge crossings between the two blocks of a pair
    # every edge of one block against every edge of the other (no box filter: an edge may
    # cross a box whose corners all lie outside it)
    e1, blk2 = _directed_vertex_block_pairs(pairs, topo, x, boxes, np.inf)
    e1, e2 = _expand_to_edges(e1, blk2, offsets)
    p1, p2 = x[e1], x[topo.nxt[e1]]
    q1, q2 = x[e2], x[topo.nxt[e2]]

    def orient(u, v, w):
        return (v[:, 0] - u[:, 0]) * (w[:, 1] - u[:, 1]) - (v[:, 1] - u[:, 1]) * (w[:, 0] - u[:, 0])

    area_tol = tol * size
    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    proper = (d1 * d2 < 0) & (d3 * d4 < 0)
    proper &= (np.minimum(np.abs(d1), np.abs(d2)) > area_tol) & (
        np.minimum(np.abs(d3), np.abs(d4)) > area_tol
    )
    for v1, v2 in zip(e1[proper].tolist(), e2[proper].tolist(), strict=True):
        ba, bb = int(topo.block[v1]), int(topo.block[v2])
        bad.add((min(ba, bb), max(ba, bb)))
    return sorted(bad)
