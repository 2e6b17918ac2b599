"""Which points of a block lie inside another block, and how deep: the geometric probes shared
by contact detection (a sunk vertex, :mod:`dda.contact.detection`), the penetration guard
(:mod:`dda.contact.penetration`) and the scene's overlap check.

Inside is the even-odd rule on a ray towards +x (exact for non-convex blocks); the depth of a
point is its least distance to the block's boundary. Blocks are given as the stacked vertex
arrays of :mod:`dda.geometry` (``x``, ``offsets``, ``nxt``; edge ``e`` runs counter-clockwise
from vertex ``e`` to ``nxt[e]``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["inside_depth"]


def inside_depth(p: np.ndarray, kblock: np.ndarray, x: np.ndarray, offsets: np.ndarray,
                 nxt: np.ndarray, nearest: bool = True):
    """Whether each point ``p`` (n, 2) lies inside block ``kblock`` (n,), its distance to the
    block's boundary and the nearest edge (CCW start index; None unless ``nearest``), all
    points at once.

    Inside is the even-odd rule on a ray towards +x (half-open in y, so a ray through a
    vertex counts once): exact for non-convex blocks. The distance is the least distance to
    an edge segment; the nearest edge is the first (in the block's order) at that distance.
    """
    if len(p) == 0:
        z = np.zeros(0, dtype=np.int64)
        return np.zeros(0, dtype=bool), np.zeros(0), z
    inside, depth, near = _inside_depth_kernel(
        np.ascontiguousarray(p, dtype=np.float64), np.ascontiguousarray(kblock, dtype=np.int64),
        np.ascontiguousarray(x, dtype=np.float64), np.ascontiguousarray(offsets, dtype=np.int64),
        np.ascontiguousarray(nxt, dtype=np.int64))
    return inside, depth, (near if nearest else None)


@njit(cache=True)
def _segment_distance(px, py, e, x, nxt):
    """The distance from (px, py) to edge e (from vertex e to ``nxt[e]``) as a segment."""
    ax, ay = x[e, 0], x[e, 1]
    abx, aby = x[nxt[e], 0] - ax, x[nxt[e], 1] - ay
    len2 = (0.0 + abx * abx) + aby * aby
    t = ((0.0 + (px - ax) * abx) + (py - ay) * aby) / max(len2, 1e-300)
    t = min(max(t, 0.0), 1.0)
    return np.hypot(px - (ax + t * abx), py - (ay + t * aby))


@njit(cache=True)
def _point_in_block(qx, qy, k, x, offsets, nxt):
    """Inside (even-odd), depth (least distance to an edge segment) and nearest edge of the
    point (qx, qy) and block k, each edge evaluated as the numpy expressions did (an einsum
    of two terms is ``(0 + a0 b0) + a1 b1``)."""
    inside = False
    depth = np.inf
    near = -1
    for e in range(offsets[k], offsets[k + 1]):
        f = nxt[e]
        ax, ay = x[e, 0], x[e, 1]
        bx, by = x[f, 0], x[f, 1]
        abx, aby = bx - ax, by - ay
        qay = qy - ay
        # compare the end points themselves: a + (b - a) need not be b in floating point,
        # and a ray through a vertex would then count it twice or not at all
        if (ay > qy) != (by > qy):
            if qx < ax + qay * abx / aby:
                inside = not inside
        dist = _segment_distance(qx, qy, e, x, nxt)
        if near < 0 or dist < depth:
            depth = dist
            near = e
    return inside, depth, near


@njit(cache=True)
def _crossings(ax, ay, dx, dy, k, x, offsets, nxt, cuts, enters):
    """Where the segment from (ax, ay) along (dx, dy) crosses block k's edges strictly
    between its ends: the parameters t in (0, 1) and whether it enters k there (crosses a
    CCW edge from its right to its left), written to ``cuts[:n]`` and ``enters[:n]`` in
    k's edge order; returns n. The segment's ends must lie strictly on either side of the
    edge's line, and the edge's ends on either side of the segment's line or on it: where
    the segment runs through a vertex of k both of its edges count, so a segment that only
    touches a reflex vertex from inside crosses there twice, once each way."""
    n = 0
    for e in range(offsets[k], offsets[k + 1]):
        f = nxt[e]
        px, py = x[e, 0], x[e, 1]
        ex, ey = x[f, 0] - px, x[f, 1] - py
        sa = ex * (ay - py) - ey * (ax - px)  # > 0: the start on k's side of the line
        den = dx * ey - dy * ex
        sb = sa - den  # ... and the end
        if not ((sa < 0.0 < sb) or (sb < 0.0 < sa)):
            continue
        sp = dx * (py - ay) - dy * (px - ax)
        sq = dx * (x[f, 1] - ay) - dy * (x[f, 0] - ax)
        if (sp > 0.0 and sq > 0.0) or (sp < 0.0 and sq < 0.0):
            continue
        cuts[n] = sa / den
        enters[n] = sa < 0.0
        n += 1
    return n


@njit(cache=True)
def _fan_overlap(v, gap, nx, ny, k, x, offsets, nxt, prv):
    """How deep behind an edge's line (outward normal (nx, ny); the vertex ``gap`` from it,
    negative behind) the part of vertex v's block near v that lies inside block k reaches:
    the larger of ``-gap`` and, for each edge at v that heads behind the line, the depth of
    the point where it leaves k (its other end when it does not; a touch of a reflex corner
    of k from inside is no exit).

    It is how far the edge's spring must push v's block out along (nx, ny) to clear k
    there: the overlap of the two blocks along that normal, seen from v (the separating
    axis test, local to v's two edges). For a corner sunk into a block's corner the nearest
    edge can be the wrong one: two corners that hit each other tip to tip and slid past
    each other are each nearest the other's side, while the overlap runs along the side's
    other edge, whose spring alone pushes them apart.
    """
    px, py = x[v, 0], x[v, 1]
    over = -gap
    m = offsets[k + 1] - offsets[k]
    cuts, enters = np.empty(m), np.empty(m, dtype=np.bool_)
    for nb in (prv[v], nxt[v]):
        ax, ay = x[nb, 0] - px, x[nb, 1] - py
        a_n = (0.0 + ax * nx) + ay * ny
        if a_n >= 0.0:
            continue
        t_exit = 1.0
        n = _crossings(px, py, ax, ay, k, x, offsets, nxt, cuts, enters)
        for i in range(n):
            if enters[i] or not (cuts[i] > 1e-12 and cuts[i] < t_exit):
                continue
            # a leave matched by an entry at the same place is a touch of a reflex corner
            # of k from inside (its two edges are crossed there, one each way), no exit
            touch = False
            for q in range(n):
                if enters[q] and abs(cuts[q] - cuts[i]) <= 1e-12:
                    touch = True
            if not touch:
                t_exit = cuts[i]
        over = max(over, -gap - t_exit * a_n)
    return over


@njit(cache=True)
def _deepest_stretch(v, w, k, x, offsets, nxt, inside, depth, near, min_depth, cuts,
                     enters, xmin, ymin, xmax, ymax, shape, pile):
    """The deepest inside block k of edge v -> w's midpoint (``inside`` k at ``depth``,
    ``near`` its nearest edge, as :func:`_point_in_block` gives them; ``near`` -1: not
    probed) and the middles of the edge's stretches between its crossings with k's
    boundary, as ``(inside, depth, near)``.

    An edge that crosses into k and out again between its ends can lie inside k over a
    stretch that neither its ends nor its midpoint reach (two blocks whose corners passed
    each other, a bar across another); the middle of each stretch inside is probed. For a
    convex k a point's depth is concave along the stretch and zero at its ends, so the
    middle reaches at least half the stretch's deepest, ``M``. A stretch is skipped where an
    upper bound of ``M`` is at most ``min_depth``: half its length (its ends are on k's
    boundary); the largest distance of its points to a side of k's box (a point's depth
    is at most its distance to the box's boundary, as k lies in its box), which skips the
    stretch of an edge resting along another block's edge; and, for the stretch through a
    probed midpoint, the larger distance of its ends to the midpoint's nearest edge (a
    point's depth is at most its distance to any edge, and that distance is convex along
    the stretch). Where the midpoint is already at least half that bound deep, it stands
    for its stretch. (A midpoint that stood for its stretch by lying in k's box alone hid a
    bar laid across another with its midpoint at the other's side, 5 cm deep.)
    Inside a concave k (one with a reflex corner) the depth along a stretch need not be
    concave: a bar laid through an L's inner corner is 0.5 m deep in both arms and 1 cm at
    the corner, its stretch's middle. There the stretch is searched instead
    (:func:`_search_stretch`), and so is an edge that lies inside it whole, without a
    crossing (a notch above its midpoint). Where round-off breaks the alternation of
    entries and leaves (an edge along k's collinear edges), every stretch is probed.
    ``cuts`` and ``enters``: scratch of at least k's size; ``shape``: the blocks' shapes
    known so far (:func:`_is_concave`); ``pile``: the search's scratch
    (:data:`SEARCH_PROBES`); k's box is ``xmin`` to ``xmax`` and ``ymin`` to ``ymax``."""
    ax, ay = x[v, 0], x[v, 1]
    dx, dy = x[w, 0] - ax, x[w, 1] - ay
    n = _crossings(ax, ay, dx, dy, k, x, offsets, nxt, cuts, enters)
    if n == 0:
        # no crossing: the edge lies inside k or outside it, whole. Inside a concave k its
        # midpoint may lie by a notch while the rest runs deep: search it
        if (near >= 0 and not inside) or not _is_concave(k, x, offsets, nxt, shape):
            return inside, depth, near
        if near < 0:
            if min(max(ax, ax + dx) - xmin, max(ay, ay + dy) - ymin, xmax - min(ax, ax + dx),
                   ymax - min(ay, ay + dy)) <= min_depth:
                return inside, depth, near  # no deeper than its box bound
            ins, dep, ne = _point_in_block(ax + 0.5 * dx, ay + 0.5 * dy, k, x, offsets, nxt)
            if ins:
                inside, depth, near = True, dep, ne
        if not inside:
            return inside, depth, near
    for i in range(1, n):  # by t, a leave before an entry at the same t (insertion: a handful)
        t, en = cuts[i], enters[i]
        j = i
        while j > 0 and (cuts[j - 1] > t + 1e-12 or (abs(cuts[j - 1] - t) <= 1e-12
                                                     and enters[j - 1] and not en)):
            cuts[j], enters[j] = cuts[j - 1], enters[j - 1]
            j -= 1
        cuts[j], enters[j] = t, en
    # entries and leaves alternate along the edge; where round-off broke that (an edge
    # collinear with k's edges to 1e-13 degrees crossed them at meaningless places and
    # missed a real crossing), every stretch may be inside, and the probes decide
    tangled = False
    for i in range(1, n):
        tangled = tangled or enters[i] == enters[i - 1]
    length = np.hypot(dx, dy)
    mid_near = near
    mid_inside, mid_depth = inside, depth
    for i in range(n + 1):
        # the stretch from crossing i - 1 (the edge's start for i = 0) to crossing i (its
        # end for i = n): inside k when it starts by entering or ends by leaving
        t0 = 0.0 if i == 0 else cuts[i - 1]
        t1 = 1.0 if i == n else cuts[i]
        if not (n == 0 or tangled or (i > 0 and enters[i - 1]) or (i < n and not enters[i])):
            continue
        # a point's depth is at most its distance along the edge to a crossing (on k's
        # boundary): half the stretch between two crossings, the whole of one that runs to
        # the edge's end (a vertex inside k, at any depth), nothing of a whole edge
        ends = (i > 0) + (i < n)
        if ends == 2 and (t1 - t0) * length <= max(2.0 * min_depth, 1e-12 * length):
            continue
        if ends == 1 and (t1 - t0) * length <= min_depth:
            continue
        x0, y0 = ax + t0 * dx, ay + t0 * dy
        x1, y1 = ax + t1 * dx, ay + t1 * dy
        bound = min(max(x0, x1) - xmin, max(y0, y1) - ymin, xmax - min(x0, x1),
                    ymax - min(y0, y1))
        if t0 <= 0.5 <= t1 and mid_near >= 0:
            bound = min(bound, max(_segment_distance(x0, y0, mid_near, x, nxt),
                                   _segment_distance(x1, y1, mid_near, x, nxt)))
            if mid_inside and 2.0 * mid_depth >= bound:
                continue
        if bound <= min_depth:
            continue
        if _is_concave(k, x, offsets, nxt, shape):
            inside, depth, near = _search_stretch(ax, ay, dx, dy, length, t0, t1, k, x,
                                                  offsets, nxt, inside, depth, near, bound,
                                                  pile)
            continue
        t = 0.5 * (t0 + t1)
        ins, dep, ne = _point_in_block(ax + t * dx, ay + t * dy, k, x, offsets, nxt)
        if ins and (not inside or dep > depth):
            inside, depth, near = True, dep, ne
    return inside, depth, near


#: the most points :func:`_search_stretch` probes along one stretch
SEARCH_PROBES = 48


@njit(cache=True)
def _search_stretch(ax, ay, dx, dy, length, t0, t1, k, x, offsets, nxt, inside, depth, near,
                    bound, pile):
    """The deepest point inside block k (any shape) of the stretch ``t0 .. t1`` of the
    segment from (ax, ay) along (dx, dy) (``length`` long) that lies inside k, found to
    within half its depth, where deeper than ``(inside, depth, near)`` found so far: as
    ``(inside, depth, near)``; ``bound`` is an upper bound of the stretch's depth.

    Branch and bound on the stretch's pieces. A piece from ``a`` to ``b`` (depths ``d_a``,
    ``d_b``, nearest edges ``e_a``, ``e_b``) is no deeper than ``(d_a + d_b + |ab|) / 2``
    (a point's depth changes no faster than the point moves), nor than ``max(d_a,
    dist(b, e_a))`` and ``max(dist(a, e_b), d_b)`` (a point's distance to an edge is convex
    along the segment and at least its depth). The piece of the largest bound is halved at
    a probe until no bound is above twice the deepest point probed (depth first, a saw of
    short edges spent the probes far from a chamber: 0.034 m found of 0.50). A stretch's
    ends are probed where they are the segment's ends, for the bounds only: the deepest
    point is looked for between them (a vertex is the corner probe's to report, but for a
    vertex between collinear edges, which no probe reports: counted as found, it hid a
    stretch 0.5 m deep); a crossing is on k's boundary, at depth 0. The search knows nothing
    of the least depth of interest. At most :data:`SEARCH_PROBES` probes; ``pile``: (2
    ``SEARCH_PROBES`` + 2, 7) scratch, a row a piece with its bound."""
    for side in range(2):  # the whole stretch: its ends in pile[0, :3] and pile[0, 3:6]
        t = t0 if side == 0 else t1
        d, e = 0.0, -1
        if t <= 0.0 or t >= 1.0:
            ins, d, e = _point_in_block(ax + t * dx, ay + t * dy, k, x, offsets, nxt)
            if not ins:
                d = 0.0
        pile[0, 3 * side], pile[0, 3 * side + 1], pile[0, 3 * side + 2] = t, d, e
    pile[0, 6] = _piece_bound(ax, ay, dx, dy, length, pile[0], bound, x, nxt)
    rows = 1
    best = 0.0  # the deepest point probed inside the stretch
    for _ in range(SEARCH_PROBES):
        top = 0
        for r in range(1, rows):
            if pile[r, 6] > pile[top, 6]:
                top = r
        if pile[top, 6] <= 2.0 * best:
            break
        tb, db, eb = pile[top, 3], pile[top, 4], pile[top, 5]
        tm = 0.5 * (pile[top, 0] + tb)
        ins, dm, em = _point_in_block(ax + tm * dx, ay + tm * dy, k, x, offsets, nxt)
        if not ins:  # (round-off: the stretch lies inside k)
            dm = 0.0
        else:
            best = max(best, dm)
            if not inside or dm > depth:
                inside, depth, near = True, dm, em
        # the piece's halves: one in its row, one in a new row
        pile[top, 3], pile[top, 4], pile[top, 5] = tm, dm, em
        pile[rows, 0], pile[rows, 1], pile[rows, 2] = tm, dm, em
        pile[rows, 3], pile[rows, 4], pile[rows, 5] = tb, db, eb
        pile[top, 6] = _piece_bound(ax, ay, dx, dy, length, pile[top], bound, x, nxt)
        pile[rows, 6] = _piece_bound(ax, ay, dx, dy, length, pile[rows], bound, x, nxt)
        rows += 1
    return inside, depth, near


@njit(cache=True)
def _piece_bound(ax, ay, dx, dy, length, piece, bound, x, nxt):
    """The upper bound of the depth of a piece, a row of :func:`_search_stretch`'s pile."""
    ta, da, ea = piece[0], piece[1], int(piece[2])
    tb, db, eb = piece[3], piece[4], int(piece[5])
    upper = min(bound, 0.5 * (da + db + (tb - ta) * length))
    if ea >= 0:
        upper = min(upper, max(da, _segment_distance(ax + tb * dx, ay + tb * dy, ea, x, nxt)))
    if eb >= 0:
        upper = min(upper, max(_segment_distance(ax + ta * dx, ay + ta * dy, eb, x, nxt), db))
    return upper


@njit(cache=True)
def _is_concave(k, x, offsets, nxt, shape):
    """Whether block k has a reflex corner (two edges that turn clockwise by more than
    round-off, ``1e-12`` of their lengths' product), kept in ``shape[k]`` (0: not yet
    known, 1: convex, 2: concave) for the next call."""
    if shape[k] == 0:
        shape[k] = 1
        for v in range(offsets[k], offsets[k + 1]):
            w = nxt[v]
            u = nxt[w]
            ex, ey = x[w, 0] - x[v, 0], x[w, 1] - x[v, 1]
            fx, fy = x[u, 0] - x[w, 0], x[u, 1] - x[w, 1]
            if ex * fy - ey * fx < -1e-12 * np.hypot(ex, ey) * np.hypot(fx, fy):
                shape[k] = 2
                break
    return shape[k] == 2


@njit(cache=True)
def _inside_depth_kernel(p, kblock, x, offsets, nxt):
    """:func:`inside_depth` of every point p[i] and block kblock[i]."""
    n = p.shape[0]
    inside = np.empty(n, dtype=np.bool_)
    depth = np.empty(n)
    near = np.empty(n, dtype=np.int64)
    for i in range(n):
        inside[i], depth[i], near[i] = _point_in_block(p[i, 0], p[i, 1], kblock[i], x, offsets,
                                                       nxt)
    return inside, depth, near


@njit(cache=True)
def _thin_overlap(a, b, x, offsets, nxt, depth):
    """Whether blocks a and b overlap no deeper than ``depth`` across one of their edge
    normals: their projections on it overlap by at most ``depth`` (or not at all).

    The two blocks' common part then lies in a slab that wide across the axis, so no point of
    either lies deeper than ``depth`` inside the other: moving it along the axis out of the
    slab takes it out of the other block (any axis bounds it, for convex blocks or not)."""
    for blk in (a, b):
        for e in range(offsets[blk], offsets[blk + 1]):
            f = nxt[e]
            nx, ny = x[f, 1] - x[e, 1], x[e, 0] - x[f, 0]  # not normalized: depth scales
            amin, amax = np.inf, -np.inf
            for v in range(offsets[a], offsets[a + 1]):
                p = x[v, 0] * nx + x[v, 1] * ny
                amin, amax = min(amin, p), max(amax, p)
            bmin, bmax = np.inf, -np.inf
            for v in range(offsets[b], offsets[b + 1]):
                p = x[v, 0] * nx + x[v, 1] * ny
                bmin, bmax = min(bmin, p), max(bmax, p)
            if min(amax - bmin, bmax - amin) <= depth * np.hypot(nx, ny):
                return True
    return False


@njit(cache=True)
def _corners_inside_kernel(x, offsets, nxt, pairs, boxes, corner, min_depth, midpoints=False):
    """Every corner (``corner[v]``) of one block of a pair in the other's box inside that
    block deeper than ``min_depth``: vertex, block, depth and nearest edge, the pairs in the
    order (j, k) first, then (k, j) (the guard's :func:`vertex_penetrations`; kept in this
    file with :func:`_point_in_block`, whose cache it shares). With ``midpoints`` the point of
    vertex v is the deepest of its edge's (to ``nxt[v]``, every edge's) midpoint and the
    middles of the edge's stretches inside the block between its crossings with the block's
    boundary (:func:`_deepest_stretch`) (``corner`` unused; the guard's
    :func:`dda.contact.penetration.edge_penetrations`)."""
    n_pairs = pairs.shape[0]
    cap = 0
    for q in range(n_pairs):
        for s in range(2):
            cap += offsets[pairs[q, s] + 1] - offsets[pairs[q, s]]
    out_v = np.empty(cap, dtype=np.int64)
    out_k = np.empty(cap, dtype=np.int64)
    out_d = np.empty(cap)
    out_e = np.empty(cap, dtype=np.int64)
    most = 0
    for b in range(offsets.shape[0] - 1):
        most = max(most, offsets[b + 1] - offsets[b])
    cuts = np.empty(most)  # _deepest_stretch's scratch
    enters = np.empty(most, dtype=np.bool_)
    pile = np.empty((2 * SEARCH_PROBES + 2, 7))
    shape = np.zeros(offsets.shape[0] - 1, dtype=np.int8)  # _deepest_stretch's (_is_concave)
    # the edges' probes report nothing of a pair that overlaps no deeper than min_depth
    # across one of its edge normals (:func:`_thin_overlap`): two blocks pressed together
    # along a joint at an angle to the axes, whose boxes reach far into each other. Tested
    # once a pair has an edge in the other's shrunk box (0 not yet, 1 thin, 2 not)
    thin = np.zeros(n_pairs, dtype=np.int8)
    test_thin = midpoints and min_depth > 0.0
    n_out = 0
    for s in range(2):
        for q in range(n_pairs):
            if thin[q] == 1:
                continue
            j = pairs[q, s]
            k = pairs[q, 1 - s]
            xmin, ymin, xmax, ymax = boxes[k, 0], boxes[k, 1], boxes[k, 2], boxes[k, 3]
            sxmin, symin = xmin + min_depth, ymin + min_depth
            sxmax, symax = xmax - min_depth, ymax - min_depth
            for v in range(offsets[j], offsets[j + 1]):
                if midpoints:
                    # a point of k deeper than min_depth lies in k's box shrunk by it (a ray
                    # from it along an axis leaves k within the box): nothing of an edge
                    # outside that box can be deeper
                    w = nxt[v]
                    if not (max(x[v, 0], x[w, 0]) >= sxmin and min(x[v, 0], x[w, 0]) <= sxmax
                            and max(x[v, 1], x[w, 1]) >= symin
                            and min(x[v, 1], x[w, 1]) <= symax):
                        continue
                    if test_thin and thin[q] == 0:
                        thin[q] = 1 if _thin_overlap(j, k, x, offsets, nxt, min_depth) else 2
                        if thin[q] == 1:
                            break
                    px, py = 0.5 * (x[v, 0] + x[w, 0]), 0.5 * (x[v, 1] + x[w, 1])
                    if px >= sxmin and px <= sxmax and py >= symin and py <= symax:
                        inside, depth, near = _point_in_block(px, py, k, x, offsets, nxt)
                    else:
                        inside, depth, near = False, np.inf, -1
                    inside, depth, near = _deepest_stretch(v, w, k, x, offsets, nxt, inside,
                                                           depth, near, min_depth, cuts,
                                                           enters, xmin, ymin, xmax, ymax,
                                                           shape, pile)
                else:
                    px, py = x[v, 0], x[v, 1]
                    if not (px >= xmin and px <= xmax and py >= ymin and py <= ymax):
                        continue
                    if not corner[v]:
                        continue
                    inside, depth, near = _point_in_block(px, py, k, x, offsets, nxt)
                if inside and depth > min_depth:
                    out_v[n_out] = v
                    out_k[n_out] = k
                    out_d[n_out] = depth
                    out_e[n_out] = near
                    n_out += 1
    return out_v[:n_out].copy(), out_k[:n_out].copy(), out_d[:n_out].copy(), out_e[:n_out].copy()
