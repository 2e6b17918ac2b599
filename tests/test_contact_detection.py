"""Broad and narrow phase: the right vertex-edge pairs, and nothing twice."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dda.contact.detection import (
    CandidateContacts,
    VertexTopology,
    bounding_boxes,
    broad_phase,
    find_overlaps,
    keep_closed,
    narrow_phase,
)
from dda.contact.kinematics import contact_geometry
from tests.conftest import box


def stack(*polys):
    verts = np.concatenate([np.asarray(p, float) for p in polys])
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in polys])])
    return verts, offsets


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(0, 10), st.floats(0, 10), st.floats(0.01, 2),
                          st.floats(0.01, 2)), min_size=0, max_size=30),
       st.floats(0, 0.5))
def test_broad_phase_equals_brute_force(rects, margin):
    boxes = np.array([[x, y, x + w, y + h] for x, y, w, h in rects]).reshape(-1, 4)
    pairs = {tuple(p) for p in broad_phase(boxes, margin).tolist()}
    brute = set()
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            a, b = boxes[i], boxes[j]
            if (a[0] - margin <= b[2] + margin and b[0] - margin <= a[2] + margin
                    and a[1] - margin <= b[3] + margin and b[1] - margin <= a[3] + margin):
                brute.add((i, j))
    assert pairs == brute


def contacts_of(*polys, d0=1e-3, touch=0.0):
    x, offsets = stack(*polys)
    topo = VertexTopology.from_offsets(offsets)
    c = narrow_phase(x, topo, d0, 2 * d0, touch=touch)
    return x, c


def test_narrow_block_on_wide_base_two_contacts():
    x, c = contacts_of(box(0, 0, 1, 0.2), box(0.4, 0.2, 0.2, 0.2))
    assert len(c) == 2
    assert set(c.vertex.tolist()) == {4, 5}  # the top block's two lower corners
    assert set(c.edge.tolist()) == {2}  # on the base's top edge (2 -> 3)


def test_equal_width_stack_two_contacts_not_four():
    x, c = contacts_of(box(0, 0, 1, 0.2), box(0, 0.2, 1, 0.2))
    assert len(c) == 2
    # one contact at each end of the interface, whichever block owns the vertex
    pts = np.sort(x[c.vertex][:, 0])
    np.testing.assert_allclose(pts, [0.0, 1.0])


def test_side_by_side_blocks_touch_along_vertical_edge():
    x, c = contacts_of(box(0, 0, 1, 1), box(1, 0, 1, 1))
    assert len(c) == 2
    np.testing.assert_allclose(np.sort(x[c.vertex][:, 1]), [0.0, 1.0])


def test_far_blocks_have_no_contact():
    x, c = contacts_of(box(0, 0, 1, 1), box(0, 1.01, 1, 1), d0=1e-3)
    assert len(c) == 0


def test_corner_onto_face_picks_the_face():
    # a square rotated 45 degrees with its lowest corner just above a flat base
    s = np.sqrt(0.5) * 0.2
    diamond = [(0.5, 0.2005), (0.5 + s, 0.2005 + s), (0.5, 0.2005 + 2 * s), (0.5 - s, 0.2005 + s)]
    x, c = contacts_of(box(0, 0, 1, 0.2), diamond)
    assert len(c) == 1
    assert c.vertex[0] == 4 and c.edge[0] == 2


def test_vertex_to_vertex_keeps_one_pair():
    # two diamonds corner to corner, one above the other
    s = 0.1
    low = [(0.0, -2 * s), (s, -s), (0.0, 0.0), (-s, -s)]
    high = [(0.0, 0.0005), (s, s + 0.0005), (0.0, 2 * s + 0.0005), (-s, s + 0.0005)]
    x, c = contacts_of(low, high)
    assert len(c) == 1


def test_corner_past_a_four_block_corner_is_not_taken_as_deep():
    # where two joints cross, the upper right block's corner has slid 0.1 mm left along the
    # bedding past the lower left block's corner: 1 micron into the bedding, 0.1 mm behind
    # the line of the cross joint. The contact is on the bedding (a 0.1 mm "penetration"
    # of the cross joint threw face blocks of a cut slope out at metres per second)
    eps, delta = 1e-4, 1e-6
    lower = box(0, 0, 1, 1)
    upper = [(1 - eps, 1 - delta), (2, 1 - delta), (2, 2), (1.3, 2)]
    x, c = contacts_of(lower, upper)
    frame = contact_geometry(x, c.vertex, c.edge, VertexTopology.from_offsets(
        np.array([0, 4, 8])).nxt)
    assert len(c) >= 1
    np.testing.assert_allclose(frame.gap, -delta, atol=1e-12)
    np.testing.assert_allclose(np.abs(frame.normal[:, 1]), 1.0)


def test_find_overlaps():
    x, off = stack(box(0, 0, 1, 1), box(1, 0, 1, 1), box(0.5, 0.5, 1, 1))
    assert find_overlaps(x, off) == [(0, 2), (1, 2)]
    x, off = stack(box(0, 0, 1, 1), box(1, 0, 1, 1))
    assert find_overlaps(x, off) == []


def test_bounding_boxes():
    x, off = stack(box(0, 0, 1, 2), box(3, 1, 1, 1))
    np.testing.assert_allclose(bounding_boxes(x, off), [[0, 0, 1, 2], [3, 1, 4, 2]])


def test_compiled_vertex_turns_are_the_numpy_ones():
    """Cross products, their scale, dot products and outward bisectors of every vertex come
    from one compiled pass: numpy's numbers to the bit, straight vertices included."""
    from dda.contact.detection import VertexTopology

    rng = np.random.default_rng(0)
    offsets, points = [0], []
    for b in range(200):
        k = int(rng.integers(3, 9))
        angle = np.sort(rng.uniform(0, 2 * np.pi, k))
        radius = rng.uniform(0.5, 2.0, k)
        p = np.stack([radius * np.cos(angle), radius * np.sin(angle)], 1)
        p += rng.normal(scale=10.0, size=2)
        if b % 5 == 0:  # a straight vertex: the midpoint of an edge
            p = np.insert(p, 1, 0.5 * (p[0] + p[1]), axis=0)
        points.append(p)
        offsets.append(offsets[-1] + len(p))
    x = np.concatenate(points)
    topo = VertexTopology.from_offsets(np.array(offsets))
    # the numpy formulas the kernel replaced
    a, b = x[topo.prv] - x, x[topo.nxt] - x
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    scale = np.hypot(a[:, 0], a[:, 1]) * np.hypot(b[:, 0], b[:, 1])
    ua = a / np.sqrt(a[:, 0] * a[:, 0] + a[:, 1] * a[:, 1])[:, None]
    ub = b / np.sqrt(b[:, 0] * b[:, 0] + b[:, 1] * b[:, 1])[:, None]
    inward = ua + ub
    norm = np.sqrt(inward[:, 0] * inward[:, 0] + inward[:, 1] * inward[:, 1])
    left = np.stack([-ub[:, 1], ub[:, 0]], axis=1)
    bisector = -np.where((norm < 1e-12)[:, None], left,
                         inward / np.maximum(norm, 1e-300)[:, None])
    got = topo.turns(x)
    for want, have in zip((cross, scale, np.einsum("ij,ij->i", a, b), bisector), got,
                          strict=True):
        np.testing.assert_array_equal(have, want)
    assert topo.straight(x).sum() == 40


def test_carrying_the_same_contacts_over_keeps_everything():
    """A detection that finds the very contacts of the last step, in the same order, takes
    the short way; it gives what matching them one by one gives (the same contacts found in
    the reverse order go the long way)."""
    import dda
    from dda.contact.contacts import carry_over
    from dda.contact.detection import CandidateContacts
    from tests.stability import scenes

    sim = dda.Simulation(scenes.shaken_cut_slope()[0], dt=2e-3)
    sim.run(0.02, progress=False)
    old, x, topo = sim.state.contacts.copy(), sim.state.x, sim.model.topo
    assert np.any(old.state == 0) and np.any(old.state != 0)
    old.held_ago = np.arange(len(old)) % 5 + 1  # counts of the cycle rule's memory to carry
    old.t_n[np.flatnonzero(old.state != 0)[::3]] = 0.0  # and contacts that ended it held
    same = CandidateContacts(old.vertex, old.edge, old.bj, old.bk)
    back = np.arange(len(old))[::-1]
    reverse = CandidateContacts(old.vertex[back], old.edge[back], old.bj[back], old.bk[back])
    fast, fresh_fast, _ = carry_over(old, same, x, topo.nxt, topo.prv, sim.model.n_blocks)
    slow, fresh_slow, _ = carry_over(old, reverse, x, topo.nxt, topo.prv, sim.model.n_blocks)
    order = np.argsort(back)
    np.testing.assert_array_equal(fresh_fast, fresh_slow[order])
    for name in ("vertex", "edge", "bj", "bk", "state", "xi0", "t_n", "t_s", "held_ago"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(slow, name)[order])
    assert set(fast.held_ago) > {1}
    assert fast.history.keys() == slow.history.keys()
    for key in fast.history:
        np.testing.assert_array_equal(fast.history[key], slow.history[key][order])


def test_compiled_boxes_and_broad_phase_are_the_numpy_ones():
    """Bounding boxes and the broad phase's pairs (in their order) are numpy's, from one
    compiled pass each: boxes of any spread, ties in the sort, zero and positive margins."""
    from dda.contact.detection import _sweep, bounding_boxes, broad_phase

    rng = np.random.default_rng(0)
    for trial in range(200):
        n = int(rng.integers(2, 300))
        centre = rng.uniform(0, rng.choice([1.0, 10.0, 100.0]), (n, 2))
        centre[:, 1] *= rng.choice([0.1, 1.0, 10.0])
        if trial % 7 == 0:
            centre = np.round(centre)  # equal lower bounds: the stable sort decides
        half = rng.uniform(0.1, 2.0, (n, 2))
        boxes = np.concatenate([centre - half, centre + half], axis=1)
        margin = float(rng.choice([0.0, 0.01, 0.5]))
        lo, hi = boxes[:, :2] - margin, boxes[:, 2:] + margin
        mid = 0.5 * (lo + hi)
        axis = int(np.argmax(mid.max(axis=0) - mid.min(axis=0)))
        order = np.argsort(lo[:, axis], kind="stable")
        stop = np.searchsorted(lo[order, axis], hi[order, axis], side="right")
        want = _sweep(order, stop, lo[:, 1 - axis].copy(), hi[:, 1 - axis].copy())
        np.testing.assert_array_equal(broad_phase(boxes, margin), want)
        offsets = np.concatenate([[0], np.cumsum(rng.integers(3, 7, n))])
        x = rng.normal(size=(offsets[-1], 2))
        start = offsets[:-1]
        np.testing.assert_array_equal(
            bounding_boxes(x, offsets),
            np.concatenate([np.minimum.reduceat(x, start, axis=0),
                            np.maximum.reduceat(x, start, axis=0)], axis=1))


def test_a_face_shared_corner_on_corner_at_both_ends_keeps_both_contacts():
    """Two blocks of the 311-block cut slope (Newton, automatic penalty, t = 0.337 s) share a
    face with a corner on a corner at each end, their sides collinear. The face is held by
    the lower block's top corner on the upper block's face and the upper block's bottom
    corner on the lower block's face. The top corner went past the other block's side while
    0.87 mm behind the face: the narrow phase no longer takes it (behind the line, not inside
    the block), and keep_closed took the bottom contact for its mirror (an end of the edge
    with a candidate against an edge at the vertex), so the face sank in untracked until the
    guard stopped the run (the positions here, 5.5 mm deep). Only the end nearer the vertex's
    foot can hold a mirror."""
    lower = [(32.49085, -0.00061), (33.89117, 0.64929), (33.54944, 1.59313),
             (32.09269, 0.91704), (32.42489, -0.00049)]
    upper = [(34.12766, 0.00237), (33.88913, 0.65446), (32.49098, -0.00028)]
    x, offsets = stack(lower, upper)
    topo = VertexTopology.from_offsets(offsets)
    d0, limit = 1e-3, 0.02
    cand = narrow_phase(x, topo, d0, limit)
    found = set(zip(cand.vertex.tolist(), cand.edge.tolist(), strict=True))
    assert (7, 0) in found  # the bottom corner on the face
    assert not {(1, 6), (6, 0), (6, 1)} & found  # neither top corner is seen
    kept = keep_closed(cand, np.array([1, 7]), np.array([6, 0]), x, topo, d0, limit, 2)
    assert {(1, 6), (7, 0)} <= set(zip(kept.vertex.tolist(), kept.edge.tolist(),
                                            strict=True))
    frame = contact_geometry(x, np.array([1]), np.array([6]), topo.nxt)
    assert frame.gap[0] == pytest.approx(-5.55e-3, abs=1e-5)


def test_a_sunk_corner_keeps_the_face_it_is_held_by_against_a_side_as_deep():
    """The cut slope (Newton, automatic penalty, t = 0.33 s): a block's corner under another
    block's face, at the corner of that face, 0.888 mm behind the face and 0.875 mm behind
    the side (the two blocks' sides on one joint), deeper than the pair's sunk depth
    (0.863 mm). The narrow phase held a sunk vertex by the edge it is least deep behind:
    the side, whose spring cannot hold the face; the contact flipped between face and side on
    round-off and the face sank in (the guard stopped the run 4.8 mm deep at 1.93 s). It now
    takes the face: the corner's own top edge runs under the face the whole face long, so a
    spring on the side would have to push the block a metre to clear it
    (``_fan_overlap``). And a closed contact keeps its edge unless the new one is shallower
    by more than the sunk depth."""
    lower = box(0.0, 0.0, 1.0, 1.0)
    upper = box(-0.875e-3, 1.0 - 0.888e-3, 1.0, 1.0)
    x, offsets = stack(lower, upper)
    topo = VertexTopology.from_offsets(offsets)
    corner = int(np.flatnonzero((x[:4, 0] == 0.0) & (x[:4, 1] == 1.0))[0])
    u = x[4:]
    bottom = 4 + int(np.flatnonzero(u[:, 1] == u[:, 1].min())[np.argmin(
        u[u[:, 1] == u[:, 1].min(), 0])])  # the upper block's edge from its bottom left
    side = int(topo.prv[bottom])  # ... and the edge that ends there: its left side
    d0, limit, sunk = 1e-4, 0.01, 0.863e-3
    cand = narrow_phase(x, topo, d0, limit, sunk_depth=sunk)
    mine = (cand.vertex == corner) & (cand.bk == 1)
    assert list(cand.edge[mine]) == [bottom]
    assert cand.geometry.gap[mine][0] == pytest.approx(-0.888e-3, rel=1e-6)
    # a closed contact on the face against a side found instead (the narrow phase of before)
    closed_v, closed_e = np.array([corner]), np.array([bottom])
    on_side = CandidateContacts(np.array([corner]), np.array([side]), np.array([0]),
                                np.array([1]))
    kept = keep_closed(on_side, closed_v, closed_e, x, topo, d0, limit, 2, sunk)
    assert list(kept.edge[(kept.vertex == corner) & (kept.bk == 1)]) == [bottom]
    # without the hysteresis (sunk depth 0) it moves on to the side
    moved = keep_closed(on_side, closed_v, closed_e, x, topo, d0, limit, 2, 0.0)
    assert list(moved.edge[(moved.vertex == corner) & (moved.bk == 1)]) == [side]
    # 2 mm under the face, 0.875 mm behind the side: still the face
    upper = box(-0.875e-3, 1.0 - 2.0e-3, 1.0, 1.0)
    x, offsets = stack(lower, upper)
    cand = narrow_phase(x, topo, d0, limit, sunk_depth=sunk)
    assert list(cand.edge[(cand.vertex == corner) & (cand.bk == 1)]) == [bottom]
    kept = keep_closed(on_side, closed_v, closed_e, x, topo, d0, limit, 2, sunk)
    assert list(kept.edge[(kept.vertex == corner) & (kept.bk == 1)]) == [bottom]
    # held by the side instead, 4 mm deep behind it and 2 mm behind the bottom, which its
    # own side crosses: it moves on to the bottom
    upper = box(-4e-3, 1.0 - 2.0e-3, 1.0, 1.0)
    x, offsets = stack(lower, upper)
    cand = narrow_phase(x, topo, d0, limit, sunk_depth=sunk)
    assert list(cand.edge[(cand.vertex == corner) & (cand.bk == 1)]) == [bottom]
    kept = keep_closed(cand, closed_v, np.array([side]), x, topo, d0, limit, 2, sunk)
    assert list(kept.edge[(kept.vertex == corner) & (kept.bk == 1)]) == [bottom]


def test_a_sunk_corner_pressed_into_a_side_keeps_it_where_it_is_shallower_under_the_bottom():
    """The L on a step of tests/stability (E/1e4, dt 1e-3, restitution 0): the step's corner
    at the floor's level, pressed 2.3 mm into the L's leg through its side, sits 1.8 mm under
    the leg's bottom as the L sinks into the floor. The narrow phase took the bottom, the
    shallower by more than the sunk depth, and the side crossed the step 3.3 mm deep
    untracked. It now takes the side: the step's own side runs up inside the leg, 30 cm
    behind the bottom's line (``_fan_overlap``). A closed contact on the side against the
    bottom found instead keeps the side: the step's own bottom edge crosses the leg's side and
    neither of its edges the leg's bottom."""
    step = box(0.0, 0.0, 0.3, 0.3)
    leg = box(-0.0977, -1.8e-3, 0.1, 0.3)
    x, offsets = stack(step, leg)
    topo = VertexTopology.from_offsets(offsets)
    corner = 0  # the step's (0, 0)
    bottom, side = 4, 5  # the leg's edges from its lower left and lower right corners
    d0, limit, sunk = 1e-4, 0.01, 0.22e-3
    cand = narrow_phase(x, topo, d0, limit, sunk_depth=sunk)
    held = (cand.vertex == corner) & (cand.bk == 1)
    assert list(cand.edge[held]) == [side]
    assert cand.geometry.gap[held][0] == pytest.approx(-2.3e-3, rel=1e-6)
    on_bottom = CandidateContacts(np.array([corner]), np.array([bottom]), np.array([0]),
                                  np.array([1]))
    kept = keep_closed(on_bottom, np.array([corner]), np.array([side]), x, topo, d0, limit, 2,
                       sunk)
    assert list(kept.edge[(kept.vertex == corner) & (kept.bk == 1)]) == [side]


def test_two_corners_that_hit_tip_to_tip_and_crossed_are_held_along_the_overlap():
    """tests/stability's corner-on-corner impact (E/1e4, legacy, restitution 0) at t = 0.209 s
    as the narrow phase of before left it: the box's corner had slid past the anvil's tip and
    was held 1.46 mm behind the anvil's left face, the tip 0.35 mm behind the box's side,
    while the box's bottom edge lay inside the anvil under its right face, 6.4 mm deep at the
    corner (7.9e-5 m2 of overlap, untracked). The overlap along each of the anvil's and the
    box's normals (the separating axis test) is least along the right face's: the corner is
    held there, as deep as the overlap."""
    anvil = [(0.0, -0.5), (0.21213, -0.28787), (0.0, -0.07574), (-0.21213, -0.28787)]
    box_ = [(-0.00353, -0.08133), (0.25824, -0.22787), (0.40478, 0.0339), (0.14301, 0.18045)]
    x, offsets = stack(anvil, box_)
    topo = VertexTopology.from_offsets(offsets)
    cand = narrow_phase(x, topo, 1e-4, 0.02, sunk_depth=0.375e-3)
    held = (cand.vertex == 4) & (cand.bk == 0)
    assert list(cand.edge[held]) == [1]  # the anvil's right face, not its left (2)

    def axis_overlap(n):
        a, b = np.asarray(anvil) @ n, np.asarray(box_) @ n
        return min(a.max(), b.max()) - max(a.min(), b.min())

    normals = [np.array([d[1], -d[0]]) / np.hypot(*d) for p in (anvil, box_)
               for d in np.roll(np.asarray(p), -1, axis=0) - np.asarray(p)]
    least = min(axis_overlap(n) for n in normals)
    assert -cand.geometry.gap[held][0] == pytest.approx(least, rel=1e-9)
    assert least > 6e-3


def test_a_vertex_vertex_pair_across_another_joint_is_no_mirror():
    """The cut slope (Newton, automatic penalty, t = 0.053 s): a sliver slid 6 mm down the
    face it shares with a larger block, whose sides are on one joint with the sliver's. The
    larger block's corner was held closed on the sliver's face; the narrow phase found
    instead the sliver's corner on the larger block's side, and keep_closed took that for
    the closed contact's mirror: the face lost its lower contact and sank in 1.1 mm (the
    guard stopped the run at 0.197 s; these are the positions there). A mirror holds the same
    joint: its edge runs against the contact's edge.

    The narrow phase no longer finds the sliver's corner on the larger block's side: the
    corner's wedge lies along the face, its outward bisector pointing out of the side (the
    side's normal and the bisector at 80 degrees, one of its edges 19.8 degrees behind the
    side's line, inside the entrance tolerance of 20). keep_closed's rule is checked with
    that candidate given by hand."""
    big = [(60.01417, 17.5896), (59.77061, 18.25836), (58.31512, 17.5793),
           (58.65863, 16.63609), (60.01424, 17.26855)]
    sliver = [(60.0164, 18.36555), (59.77266, 18.25272), (60.01421, 17.58323)]
    x, offsets = stack(big, sliver)
    topo = VertexTopology.from_offsets(offsets)
    d0, limit, sunk = 1e-3, 0.01, 0.25 * 0.01 * 0.108  # the sliver's quarter tolerance
    cand = narrow_phase(x, topo, d0, limit, sunk_depth=sunk)
    found = set(zip(cand.vertex.tolist(), cand.edge.tolist(), strict=True))
    assert (7, 4) not in found  # the sliver's corner is not on the big block's side
    assert not any(v == 0 for v, _ in found)  # the big block's corner is not seen
    on_side = CandidateContacts(np.array([7]), np.array([4]), np.array([1]), np.array([0]))
    kept = keep_closed(on_side, np.array([0]), np.array([6]), x, topo, d0, limit, 2, sunk)
    assert (0, 6) in set(zip(kept.vertex.tolist(), kept.edge.tolist(), strict=True))


@pytest.mark.parametrize("into", [1e-6, 5e-6])
def test_a_sharp_wedge_slid_along_a_floor_into_a_block_is_held_by_its_side(into):
    """A triangle whose corner is a 6.8 degree wedge slides along the floor into a block that
    stands on the same floor (a hunt's shaken U, Newton, t = 0.34 s): its tip lies on the
    block's bottom edge, its edges on and behind that edge's line, within the entrance
    tolerance. The tip is held by the block's side it pushes into, not by the bottom edge
    (whose normal its outward bisector follows). Held by the bottom, or by nothing, the tip
    slid 0.96 mm into the block and the guard stopped the run."""
    from dda.contact.detection import VertexTopology as Topology

    block = [(1.175311, -0.027005), (1.364135, -0.027005), (1.364135, -0.002217),
             (1.175311, -0.002217)]
    dx = 1.175311 + into - 1.176214
    wedge = [(1.176214 + dx, -0.027005), (1.063506 + dx, -0.013617),
             (1.076334 + dx, -0.027005)]
    x = np.array(wedge + block, float)
    topo = Topology.from_offsets(np.array([0, 3, 7]))
    c = narrow_phase(x, topo, 1e-3, 1e-3, sunk_depth=1.44e-5)
    held = set(zip(c.vertex.tolist(), c.edge.tolist(), strict=True))
    assert (0, 6) in held  # the tip on the block's left side, (1.175, -0.0022) -> (1.175, -0.027)
    assert (0, 3) not in held  # not on its bottom


STEP = [(-0.5, -0.5), (2.0, -0.5), (2.0, 0.1), (1.5, 0.1), (1.0, 0.1), (1.0, 0.0), (0.0, 0.0),
        (-0.5, 0.0)]  # a fixed block with a step: tread (3 -> 4) at 0.1, riser 4 -> 5, tread 5 -> 6


@pytest.mark.parametrize("u0, v0", [(1.0 + 1e-5, 0.1 - 2e-6), (1.0 + 1e-5, 0.101),
                                    (1.2, 0.1 - 2e-6), (1.2, 0.15)])
def test_a_corner_at_a_steps_edge_is_held_by_the_tread_it_rests_on_not_the_one_below(u0, v0):
    # a column's corner at the top of a step's riser, on the tread or just above it, with a
    # search distance larger than the riser (a static analysis at a large dt). The lower
    # tread's line lies below the corner (its gap the largest), but the corner would reach it
    # only down the riser: the nearest edge, the tread under it, holds it (the lower tread
    # held it, and the column sank 6 mm into the step untracked in a strength-reduction trial)
    column = [(u0, v0), (u0 + 0.5, v0), (u0 + 0.5, v0 + 3.0), (u0, v0 + 3.0)]
    x, offsets = stack(STEP, column)
    topo = VertexTopology.from_offsets(offsets)
    c = narrow_phase(x, topo, 0.3, 0.3, sunk_depth=1e-3)
    held = {(int(v), int(e)) for v, e in zip(c.vertex, c.edge, strict=True)}
    assert (8, 3) in held  # the column's lower left corner on the tread under it
    assert (9, 2) in held  # and its lower right corner on the same (straight) tread
    assert not any(v == 8 and e == 5 for v, e in held)


def _ridge(delta):
    """Two blocks sharing the face x = 0 whose tops fall away from the shared corner (0, 1)
    (two voussoirs' extrados chords), the right one built ``delta`` into the left."""
    right = [(0.0, 0.0), (1.0, 0.0), (1.0, 0.8), (0.0, 1.0)]
    left = [(-1.0 + delta, 0.0), (delta, 0.0), (delta, 1.0), (-1.0 + delta, 0.8)]
    return right, left


@pytest.mark.parametrize("delta", [1e-8, 1e-7, 9e-7])
def test_blocks_built_a_hair_into_each_other_touch_at_their_corners(delta):
    """Each top corner lies ``delta`` behind the other block's face and 0.2 ``delta`` above its
    falling top: under the scene's touching tolerance (1e-6 of the size) it is taken on the
    face, as at ``delta`` 0; it had no contact at all (an arch of voussoirs turned by 1e-7
    degrees stopped on an untracked penetration)."""
    from dda.contact.detection import TOUCH_TOLERANCE

    _, touching = contacts_of(*_ridge(0.0))
    _, c = contacts_of(*_ridge(delta), touch=TOUCH_TOLERANCE)

    def pairs(cand):
        return sorted(zip(cand.vertex.tolist(), cand.edge.tolist(), strict=True))

    # the right block's two corners on the left block's face (edge 5: (delta, 0) to
    # (delta, 1)); the left block's mirrored ones dropped
    assert pairs(c) == pairs(touching) == [(0, 5), (3, 5)]
    # a corner 2e-6 of the size behind the face is an overlap (the scene refuses it), not
    # a touch
    _, far = contacts_of(*_ridge(2e-6), touch=TOUCH_TOLERANCE)
    assert pairs(far) == [(0, 5)]
    # after a run's first step the rule is off (a simulation's later steps): one contact
    _, later = contacts_of(*_ridge(delta))
    assert pairs(later) == [(0, 5)]
