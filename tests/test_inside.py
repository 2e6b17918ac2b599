"""The point-inside-block probes of :mod:`dda.contact.inside`: a touch of a reflex corner, and
the thin overlap with which the guard's edge probe skips a pair.

A segment that runs through a reflex vertex of block k from inside crosses the lines of both
of its edges there, one each way, without leaving k. A review's search on integer grids found
both probes misreading it (38 of 6,662 cases of ``_fan_overlap``, 23 of 30,000 segments of the
stretch probe).
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dda.contact.detection import VertexTopology
from dda.contact.inside import _fan_overlap, _thin_overlap
from tests.test_penetration_guard import boundary_depth_in, star


def stack(polys):
    x = np.concatenate([np.asarray(p, float) for p in polys])
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in polys])]).astype(np.int64)
    return x, offsets, VertexTopology.from_offsets(offsets)


def test_an_edge_that_touches_a_reflex_corner_from_inside_has_not_left_the_block():
    """Vertex (3, 3) of a triangle sits 1 behind the top edge of a block with a reflex
    corner at (3, 2); its edge to (3, 1) touches that corner and stays inside, so the overlap
    along the top edge's normal reaches (3, 1): 3, not the 2 of the touch (taken for the
    edge's exit before)."""
    k = [(0, 0), (4, 0), (3, 2), (4, 4), (0, 4)]
    j = [(3, 3), (2.5, 2), (3, 1)]
    x, offsets, topo = stack([j, k])
    over = _fan_overlap(0, -1.0, 0.0, 1.0, 1, x, offsets, topo.nxt, topo.prv)
    assert over == pytest.approx(3.0, rel=1e-12)
    # an edge that does leave is still cut where it leaves: from (3.5, 3.5), 0.5 behind the
    # line, the edge down to (3.5, 0.5) leaves k at (3.5, 3) (and enters again at (3.5, 1)),
    # 1 behind the line; the other, to (2.5, 2), stays inside, 2 behind: 2, not 3.5
    j = [(3.5, 3.5), (2.5, 2), (3.5, 0.5)]
    x, offsets, topo = stack([j, k])
    over = _fan_overlap(0, -0.5, 0.0, 1.0, 1, x, offsets, topo.nxt, topo.prv)
    assert over == pytest.approx(2.0, rel=1e-12)


def test_the_stretch_before_a_touch_of_a_reflex_corner_is_probed():
    """An edge from (1.5, 1.5) to (0.5, 2.5) runs inside a block through its reflex corner
    at (1, 2) (its midpoint) and leaves it at t = 0.7: both stretches are inside, the first
    0.25 deep at its middle. Its crossings at the corner came sorted entry first, so the
    first stretch looked as if it ended by entering and was skipped (0.10 found)."""
    from dda.contact.penetration import edge_penetrations

    k = [(1, 1), (4, 3), (0, 2), (1, 2)]
    j = [(1.5, 1.5), (0.5, 2.5), (0.0, 0.0)]
    x, offsets, topo = stack([j, k])
    pen = edge_penetrations(x, topo, min_depth=0.0)
    depth = pen.depth[(pen.vertex == 0) & (pen.block == 1)]
    assert depth == pytest.approx([0.25], rel=1e-12)


@settings(max_examples=100, deadline=None, derandomize=True)
@given(st.lists(st.tuples(st.floats(0, 2), st.floats(0, 2),
                          st.lists(st.floats(0.3, 1.0), min_size=3, max_size=9),
                          st.floats(0, 6.3)), min_size=2, max_size=2),
       st.floats(0.0, 0.5))
def test_a_thin_overlap_bounds_the_depth_of_every_point(blocks, depth):
    """Where two blocks overlap by at most ``depth`` across one of their edge normals
    (``_thin_overlap``, with which the guard's edge probe skips a pair), no point of either
    boundary lies deeper than that inside the other (shapely, sampled), convex or not."""
    polys = [star(cx, cy, r, t) for cx, cy, r, t in blocks]
    x, offsets, topo = stack(polys)
    if not _thin_overlap(0, 1, x, offsets, topo.nxt, depth):
        return
    for j, k in ((0, 1), (1, 0)):
        true, step = boundary_depth_in(polys[j], polys[k])
        assert true <= depth + step


def test_blocks_pressed_along_a_slanted_joint_are_thin():
    """Two squares pressed 10 um into each other along a joint at 30 degrees: their boxes
    reach far into each other, and the overlap across the joint's normal is 10 um."""
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    rot = np.array([[c, -s], [s, c]])
    lower = np.array([(0, -1), (1, -1), (1, 0), (0, 0)], float) @ rot.T
    upper = (np.array([(0, 0), (1, 0), (1, 1), (0, 1)], float) - [0, 1e-5]) @ rot.T
    x, offsets, topo = stack([lower, upper])
    assert _thin_overlap(0, 1, x, offsets, topo.nxt, 2e-5)
    assert not _thin_overlap(0, 1, x, offsets, topo.nxt, 0.5e-5)
