"""The penetration guard (issue 17, item 1): every vertex inside another block is found
geometrically, and a step that leaves one untracked is refused."""

import numpy as np
import pytest
import shapely
from hypothesis import example, given, settings
from hypothesis import strategies as st

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.contact.contacts import OPEN, STICK, ContactSet
from dda.contact.detection import VertexTopology
from dda.contact.penetration import untracked_penetrations, vertex_penetrations
from dda.materials import LinearElastic
from tests.conftest import box

ROCK = LinearElastic(young=1e9, poisson=0.25, density=2500.0)


def stack(polys):
    x = np.concatenate([np.asarray(p, float) for p in polys])
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in polys])]).astype(np.int64)
    return x, VertexTopology.from_offsets(offsets)


def star(cx, cy, radii, turn):
    """A star-shaped (generally non-convex) polygon, counter-clockwise."""
    n = len(radii)
    ang = turn + 2 * np.pi * np.arange(n) / n
    return np.stack([cx + np.asarray(radii) * np.cos(ang), cy + np.asarray(radii) * np.sin(ang)],
                    axis=1)


@settings(max_examples=80, deadline=None, derandomize=True)
@example([(0.0, 0.0, [0.375, 1.0, 1.0], 0.375), (0.5, 0.0, [0.375, 1.0, 0.375], 0.375)])
@given(st.lists(st.tuples(st.floats(0, 3), st.floats(0, 3),
                          st.lists(st.floats(0.3, 1.0), min_size=3, max_size=9),
                          st.floats(0, 6.3)), min_size=2, max_size=5))
def test_vertex_penetrations_match_shapely(blocks):
    polys = [star(cx, cy, r, t) for cx, cy, r, t in blocks]
    x, topo = stack(polys)
    pen = vertex_penetrations(x, topo)
    found = {(int(v), int(k)): float(d) for v, k, d in
             zip(pen.vertex, pen.block, pen.depth, strict=True)}
    shapes = [shapely.Polygon(p) for p in polys]
    expected = {}
    for v, p in enumerate(x):
        j = int(topo.block[v])
        for k, s in enumerate(shapes):
            if k == j:
                continue
            pt = shapely.Point(p)
            depth = s.exterior.distance(pt)
            if s.contains(pt) and depth > 1e-9:
                expected[(v, k)] = depth
    # points within round-off of a boundary may go either way; nothing deeper may differ
    assert {key for key, d in expected.items() if d > 1e-7} <= set(found)
    assert {key for key, d in found.items() if d > 1e-7} <= set(expected)
    for key in set(found) & set(expected):
        assert found[key] == pytest.approx(expected[key], rel=1e-9, abs=1e-12)



@settings(max_examples=80, deadline=None, derandomize=True)
@given(st.lists(st.tuples(st.floats(0, 3), st.floats(0, 3),
                          st.lists(st.floats(0.3, 1.0), min_size=3, max_size=9),
                          st.floats(0, 6.3)), min_size=2, max_size=5),
       st.floats(0.0, 0.3))
def test_edge_probes_deeper_than_a_depth_are_those_of_all_probes_deeper_than_it(blocks,
                                                                                 least):
    """The edge probe skips an edge outside the other block's box shrunk by ``min_depth``
    (nothing of a block deeper than that lies outside it): with ``min_depth`` it finds
    exactly the probes deeper than it of a search without."""
    from dda.contact.penetration import edge_penetrations

    x, topo = stack([star(cx, cy, r, t) for cx, cy, r, t in blocks])
    every = edge_penetrations(x, topo)
    deep = edge_penetrations(x, topo, min_depth=least)
    keep = every.depth > least
    assert sorted(zip(deep.vertex.tolist(), deep.block.tolist(), deep.depth.tolist(),
                      strict=True)) == sorted(zip(every.vertex[keep].tolist(),
                                                  every.block[keep].tolist(),
                                                  every.depth[keep].tolist(), strict=True))


def rectangle(cx, cy, length, width, turn):
    """A rectangle, counter-clockwise, its length along the angle ``turn``."""
    c, s = np.cos(turn), np.sin(turn)
    return [(cx + a * c - b * s, cy + a * s + b * c) for a, b in
            ((-length / 2, -width / 2), (length / 2, -width / 2), (length / 2, width / 2),
             (-length / 2, width / 2))]


def boundary_depth_in(p, q, per_edge=400):
    """The deepest point of polygon p's boundary inside polygon q (shapely, sampled): its
    distance to q's boundary, and the sampling step."""
    shape = shapely.Polygon(q)
    p = np.asarray(p, float)
    t = np.linspace(0.0, 1.0, per_edge, endpoint=False)[:, None]
    pts = np.concatenate([a + t * (b - a) for a, b in zip(p, np.roll(p, -1, axis=0),
                                                            strict=True)])
    step = max(np.hypot(*(np.roll(p, -1, axis=0) - p).T)) / per_edge
    inside = shapely.contains_xy(shape, pts[:, 0], pts[:, 1])
    if not inside.any():
        return 0.0, step
    return float(shapely.distance(shape.exterior, shapely.points(pts[inside])).max()), step


@settings(max_examples=150, deadline=None, derandomize=True)
@given(st.lists(st.tuples(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.2, 2.0),
                          st.floats(0.01, 1.0), st.floats(0.0, 3.2)), min_size=2, max_size=2),
       st.sampled_from([0.0, 1e-3, 1e-2, 3e-2]))
def test_the_edge_and_corner_probes_see_half_of_a_convex_overlap(bars, least):
    """For two rectangles (bars up to 1:200, crossed, laid along each other, one inside the
    other) the guard's probes, the corners and the edges, find at least half of the depth of
    each one's boundary inside the other whenever that is deeper than twice ``min_depth``,
    and never more than it: along an edge's stretch inside a convex block the depth is
    concave, so the stretch's middle reaches half its deepest (issue: a midpoint at the
    other's side stood for its stretch)."""
    from dda.contact.penetration import edge_penetrations

    polys = [rectangle(*b) for b in bars]
    x, topo = stack(polys)
    pen = [edge_penetrations(x, topo, min_depth=least), vertex_penetrations(x, topo,
                                                                            min_depth=least)]
    for j, k in ((0, 1), (1, 0)):
        true, step = boundary_depth_in(polys[j], polys[k])
        found = max((float(p.depth[(topo.block[p.vertex] == j) & (p.block == k)].max(
            initial=0.0)) for p in pen), default=0.0)
        assert found <= true + step + 1e-12
        if true > 2.0 * least + step:
            assert found >= 0.5 * true - step


def test_a_vertex_in_a_notch_is_inside_the_non_convex_block():
    # a U-shaped block and a small box whose right side is in the U's right arm, 0.05 deep
    u = [(0, 0), (3, 0), (3, 2), (2, 2), (2, 1), (1, 1), (1, 2), (0, 2)]
    sq = box(1.5, 1.5, 0.55, 0.3)  # right corners at (2.05, 1.5) and (2.05, 1.8)
    x, topo = stack([u, sq])
    pen = vertex_penetrations(x, topo)
    assert pen.vertex.tolist() == [9, 10]
    np.testing.assert_allclose(pen.depth, [0.05, 0.05])
    assert pen.edge.tolist() == [3, 3]  # the arm's inner wall, (2, 2) -> (2, 1)
    # in the notch's open space nothing is inside
    x, topo = stack([u, box(1.2, 1.2, 0.5, 0.5)])
    assert len(vertex_penetrations(x, topo)) == 0


def contacts(vertex, edge, bj, bk, state, t_n):
    m = len(vertex)
    a = [np.asarray(v, dtype=np.int64) for v in (vertex, edge, bj, bk)]
    return ContactSet(*a, np.asarray(state, dtype=np.int8), np.zeros(m), np.asarray(t_n, float),
                      np.zeros(m), {})


def test_untracked_penetrations_need_a_closed_contact_as_deep():
    # square 1 sits 0.01 into square 0: its vertices 4 and 5 are inside
    x, topo = stack([box(0, 0, 1, 1), box(0.2, 0.99, 0.5, 0.5)])
    pen = vertex_penetrations(x, topo)
    assert sorted(pen.vertex.tolist()) == [4, 5]
    tol = np.full(len(pen), 1e-3)
    pn = 1e9
    # no contacts at all: both untracked
    none = contacts([], [], [], [], [], [])
    assert untracked_penetrations(pen, none, np.zeros(0), tol, topo).all()
    # both closed at the right depth: tracked
    both = contacts([4, 5], [2, 2], [1, 1], [0, 0], [STICK, STICK], [-0.01 * pn] * 2)
    assert not untracked_penetrations(pen, both, np.full(2, pn), tol, topo).any()
    # one open, one closed but only half as deep as the vertex is: both untracked
    bad = contacts([4, 5], [2, 2], [1, 1], [0, 0], [OPEN, STICK], [0.0, -0.005 * pn])
    assert untracked_penetrations(pen, bad, np.full(2, pn), tol, topo).all()
    # within the tolerance of the spring: tracked
    near = contacts([4, 5], [2, 2], [1, 1], [0, 0], [STICK, STICK], [-0.0095 * pn] * 2)
    assert not untracked_penetrations(pen, near, np.full(2, pn), tol, topo).any()
    # shallower than the tolerance: nothing to track
    assert not untracked_penetrations(pen, none, np.zeros(0), np.full(2, 0.02), topo).any()


def test_a_vertex_vertex_contact_covers_its_mirror_vertex():
    # two squares corner to corner, each corner 0.01 inside the other; the contact kept is
    # vertex 0's against block 1's edge that ends at vertex 0's partner
    a = box(0, 0, 1, 1)
    b = box(0.99, 0.99, 1, 1)
    x, topo = stack([a, b])
    pen = vertex_penetrations(x, topo)
    assert sorted(pen.vertex.tolist()) == [2, 4]
    # vertex 2 of block 0 (1, 1) against block 1's bottom edge 4 -> 5: its end vertex 4 is
    # covered as the mirror image
    c = contacts([2], [4], [0], [1], [STICK], [-0.01 * 1e9])
    assert not untracked_penetrations(pen, c, np.array([1e9]), np.full(2, 1e-4), topo).any()


def drop_scene():
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(-1, -0.5, 2, 0.5), ROCK, fixed=True, name="floor")
    scene.add_block(box(-0.1, 0.001, 0.2, 0.2), ROCK, name="brick", velocity=(0.0, -2.0))
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=30.0)))
    return scene


def test_the_guard_stops_a_run_whose_detection_misses_a_contact(monkeypatch, tmp_path):
    """With a contact detector that finds nothing the brick would fall through the floor;
    the guard refuses the step, cuts it, and stops the run with the blocks, vertex, depth and
    time, the steps before kept and written."""
    import dda.step as step
    from dda.contact.detection import CandidateContacts

    def blind(x, topo, d0, limit, pairs=None, sunk_depth=None, boxes=None, touch=0.0):
        return CandidateContacts(*(np.zeros(0, dtype=np.int64) for _ in range(4)))

    monkeypatch.setattr(step, "narrow_phase", blind)
    sim = dda.Simulation(drop_scene(), dt=1e-3)
    writer = dda.io.VTUWriter(tmp_path / "drop")
    with pytest.raises(dda.SimulationError) as info:
        sim.run(0.05, output=writer)
    msg = str(info.value)
    assert "untracked penetration" in msg
    assert "of block 'brick'" in msg and "inside block 'floor'" in msg
    assert "vertex 0" in msg or "vertex 1" in msg
    # it reaches the floor at t = 0.5 ms (1 mm at 2 m/s) and is stopped within a tolerance
    # (0.5 mm) of it, not after falling through
    import re

    t_stop = float(re.search(r"at t = ([0-9.e-]+) s", msg).group(1))
    assert 0.5e-3 < t_stop < 0.5e-3 + 0.6e-3 / 2.0
    depth = float(re.search(r"is ([0-9.e-]+) m inside", msg).group(1))
    assert 0.5e-3 < depth < 2e-3
    result = info.value.result
    assert result is not None and len(result.stats.cuts) > 0
    assert all("untracked penetration" in r for _, _, r in result.stats.cuts)
    assert writer.pvd_path.exists()


def test_the_guard_lets_a_tracked_contact_sink_and_reports_it():
    sim = dda.Simulation(drop_scene(), dt=1e-3)
    result = sim.run(0.05)
    st = result.stats
    assert len(st.cuts) == 0
    # the brick lands: the deepest vertex is the deepest spring, to round-off and the
    # linearization of the last step
    assert st.penetration.max() > 0
    np.testing.assert_allclose(st.penetration, st.spring_penetration, rtol=1e-3, atol=1e-9)
    assert st.guard_time.sum() > 0
    assert "guard" in str(result.profile())


def test_penetration_tolerance_is_checked():
    with pytest.raises(ValueError, match="penetration_tolerance"):
        dda.Simulation(drop_scene(), dt=1e-3, penetration_tolerance=0.0)


def test_compiled_gather_matches_numpy():
    """The guard's compiled gather (the springs that hold a penetration) reduces the values of
    each key as numpy's sort and reduceat do: runs of 1 to about 130 values, keys absent."""
    from dda.contact import penetration

    rng = np.random.default_rng(0)
    for _ in range(200):
        n = int(rng.integers(1, 400))
        n_keys = int(rng.choice([3, 15, 200]))
        keys = rng.integers(0, n_keys, n)
        values = rng.normal(size=n)
        want = rng.integers(0, n_keys + 3, int(rng.integers(1, 20)))
        order = np.argsort(keys, kind="stable")
        k, v = keys[order], values[order]
        start = np.flatnonzero(np.concatenate([[True], k[1:] != k[:-1]]))
        pos = np.minimum(np.searchsorted(k[start], want), len(start) - 1)
        for reduce in (np.add, np.maximum):
            expected = np.where(k[start][pos] == want, reduce.reduceat(v, start)[pos], 0.0)
            got = penetration._gather_kernel(keys, values, want, reduce is np.maximum)
            np.testing.assert_allclose(got, expected, rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("high", [3, 4096, 2**30, 2**62])
def test_the_gathers_order_is_numpys_stable_sort(high):
    """The gather's radix sort orders keys (with many equal ones, over one to six 12-bit
    digits) as numpy's stable sort does, index for index; negative keys, and fewer keys than
    ``RADIX_FROM``, take numba's merge sort, to the same order."""
    from dda.contact import penetration

    rng = np.random.default_rng(high % 1000)
    radix = penetration.RADIX_FROM
    for n in (0, 1, 7, radix - 1, radix, 5000):
        keys = rng.integers(0, high, n) if high > 3 else rng.integers(0, high, n) * 3
        np.testing.assert_array_equal(penetration._stable_order(keys),
                                      np.argsort(keys, kind="stable"))
        if n:
            keys[::3] *= -1
            np.testing.assert_array_equal(penetration._stable_order(keys),
                                          np.argsort(keys, kind="stable"))


def test_compiled_untracked_depth_is_the_numpy_one():
    """How much deeper each penetration is than the springs holding it comes from one
    compiled pass: the numpy version's numbers to the bit, on a shaken jointed slope."""
    import dda
    from dda.contact.penetration import untracked_depth, vertex_penetrations
    from tests.stability import scenes

    sim = dda.Simulation(scenes.shaken_cut_slope()[0], dt=2e-3)
    sim.run(0.05, progress=False)
    c, topo = sim.state.contacts, sim.model.topo
    pen = vertex_penetrations(sim.state.x, topo)
    p_n = np.full(len(c), 1e9)
    closed = (c.state != 0).nonzero()[0]
    assert len(pen) > 10 and len(closed) > 10
    spring = -c.t_n[closed] / p_n[closed]
    nb = len(topo.offsets)
    want = pen.vertex * nb + pen.block

    def gather(keys, values, reduce):  # the numpy version the kernel replaced
        order = np.argsort(keys, kind="stable")
        k, v = keys[order], values[order]
        start = np.flatnonzero(np.concatenate([[True], k[1:] != k[:-1]]))
        pos = np.minimum(np.searchsorted(k[start], want), len(start) - 1)
        return np.where(k[start][pos] == want, reduce.reduceat(v, start)[pos], 0.0)

    held_own = np.sqrt(gather(c.vertex[closed] * nb + c.bk[closed], spring**2, np.add))
    edge_end = np.concatenate([c.edge[closed], topo.nxt[c.edge[closed]]])
    held_mirror = gather(edge_end * nb + np.concatenate([c.bj[closed], c.bj[closed]]),
                         np.concatenate([spring, spring]), np.maximum)
    np.testing.assert_array_equal(untracked_depth(pen, c, p_n, topo),
                                  pen.depth - np.maximum(held_own, held_mirror))


def test_an_edge_between_two_corners_on_the_sides_is_tracked_by_their_springs():
    """Two unit squares corner on corner, the upper 3 mm into the lower: its corners lie on
    the lower block's side lines (no distance inside it), only its bottom edge is inside."""
    from dda.contact.penetration import edge_penetrations, untracked_edge_depth

    x, topo = stack([box(0, 0, 1, 1), box(0, 0.997, 1, 1)])
    assert len(vertex_penetrations(x, topo, min_depth=1e-9)) == 0
    pen = edge_penetrations(x, topo, min_depth=1e-9)
    lower = pen.select(pen.vertex == 4)  # the upper block's bottom edge, in the lower one
    assert lower.depth.tolist() == pytest.approx([0.003])
    pn = 1e9
    none = contacts([], [], [], [], [], [])
    assert untracked_edge_depth(lower, none, np.zeros(0), topo) == pytest.approx([0.003])
    # its two corners on the lower block's top edge (edge 2), each spring 3 mm deep: held
    held = contacts([4, 5], [2, 2], [1, 1], [0, 0], [STICK, STICK], [-0.003 * pn] * 2)
    assert untracked_edge_depth(lower, held, np.full(2, pn), topo) == pytest.approx([0.0])
    # one corner's spring only 1 mm deep, the other's 3 mm: the edge is held by the deeper
    one = contacts([4, 5], [2, 2], [1, 1], [0, 0], [OPEN, STICK], [0.0, -0.003 * pn])
    assert untracked_edge_depth(lower, one, np.full(2, pn), topo) == pytest.approx([0.0])
    # the lower block's corners on the upper block's bottom edge (edge 4) hold it too
    mirror = contacts([2, 3], [4, 4], [0, 0], [1, 1], [STICK, STICK], [-0.003 * pn] * 2)
    assert untracked_edge_depth(lower, mirror, np.full(2, pn), topo) == pytest.approx([0.0])
    # springs only 1 mm deep: 2 mm untracked
    shallow = contacts([4, 5], [2, 2], [1, 1], [0, 0], [STICK, STICK], [-0.001 * pn] * 2)
    assert untracked_edge_depth(lower, shallow, np.full(2, pn), topo) == pytest.approx([0.002])


def test_the_guard_stops_a_column_whose_contacts_are_lost(monkeypatch):
    """Before detection kept closed contacts, a column of unit squares on soft springs lost
    them and its blocks fell through each other, their corners on the side lines where the
    guard saw them at depth zero. With the contacts lost on purpose the guard now stops it."""
    import dda.step as step

    monkeypatch.setattr(step, "keep_closed", lambda cand, *args: cand)
    scene = dda.Scene(gravity=9.81)
    rock = LinearElastic(young=10e9, poisson=0.25, density=2600.0)
    scene.add_block([(-1, -1), (2, -1), (2, 0), (-1, 0)], rock, fixed=True, name="base")
    for i in range(3):
        scene.add_block([(0, i), (1, i), (1, i + 1), (0, i + 1)], rock, name=f"b{i}")
    scene.set_joint(JointMaterial(2.55e7, 2.55e7, CoulombSingle(phi=35.0)))
    sim = dda.Simulation(scene, dt=0.005)
    with pytest.raises(dda.SimulationError, match=r"untracked penetration: the edge from "
                                                  r"vertex \d to \d of block 'b\d' .* is "
                                                  r"0.00\d+ m inside block 'b\d'"):
        sim.run(0.3, progress=False)
    assert sim.committed.time < 0.1  # stopped at the first sinking, not metres later


def test_a_bolted_triangle_pulled_under_an_l_in_static_steps_is_refused_or_kept_out():
    """A triangle and an L on an incline, bolted with a pretension of 79 kN/m, static steps
    of 0.1 s (Newton): the bolt pulls the triangle's acute corner 6 cm under the L along the
    incline's line; the two overlapped by 5.5% of the triangle's area with no contact between
    them, and no corner or edge midpoint more than 4e-5 m inside the other (a strict xfail
    from a hunt of 2026-12-06). Since the narrow phase holds a sunk corner by the edge along
    which the overlap is least (``dda.contact.inside._fan_overlap``), the L's corner is
    held by the triangle's edge and the two stay apart (overlap 8e-8 of the area)."""
    from dda.contact import StaticDynamicTransition

    rock = LinearElastic(young=1e10, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(0.0, -0.5), (2.844426, -0.5), (2.844426, 1.889832), (0.0, 0.0)], rock,
                    fixed=True, name="base")
    tri = scene.add_block([(0.184443, 0.122784), (0.494871, 0.379648), (0.209887, 0.337625)],
                          rock, name="tri")
    ell = scene.add_block([(0.518285, 0.344588), (0.751071, 0.499251), (0.699629, 0.576677),
                           (0.544269, 0.473456), (0.428082, 0.648332), (0.350655, 0.59689)],
                          rock, name="ell")
    scene.add_bolt(tri, (0.2557143, 0.23020429), ell, (0.64767015, 0.48635332), 1.0379879e6,
                   pretension=79049.519)
    scene.set_joint(JointMaterial(14829756.76, 14829756.76,
                                  StaticDynamicTransition(9.7, 9.7 * 0.8)))
    sim = dda.Simulation(scene, dt=0.1, solver="newton", analysis="static")
    o = sim.model.offsets
    worst = [0.0]

    def overlap(state, report):
        p = shapely.Polygon(state.x[o[tri.index]:o[tri.index + 1]])
        q = shapely.Polygon(state.x[o[ell.index]:o[ell.index + 1]])
        worst[0] = max(worst[0], p.intersection(q).area / p.area)

    try:
        sim.run(2.2, progress=False, callback=overlap)
    except dda.SimulationError as exc:  # refused: what the guard is for
        assert "untracked penetration" in str(exc)
        return
    assert worst[0] < 1e-3


def test_two_bars_across_each_other_are_seen_between_their_corners():
    """Two bars across each other, 10 cm wide: no corner of either is inside the other and no
    edge's midpoint either (the crossing is 0.6 m from the horizontal bar's middle and 0.45 m
    from the slanted one's). The guard probes the middle of each stretch between an edge's
    crossings with the other block: each long edge lies in the other bar over a stretch
    whose middle is 5 cm (half the other's width) inside it."""
    from dda.contact.penetration import edge_penetrations

    c, s = np.cos(np.radians(80.0)), np.sin(np.radians(80.0))
    axis, across = np.array([c, s]), np.array([-s, c])
    mid = np.array([0.6, 0.05]) + 0.45 * axis  # the slanted bar's centre
    slanted = [tuple(mid + a * axis + b * across) for a, b in
               ((-1.0, -0.05), (1.0, -0.05), (1.0, 0.05), (-1.0, 0.05))]
    x, topo = stack([box(-1.0, 0.0, 2.0, 0.1), slanted])
    assert len(vertex_penetrations(x, topo, min_depth=1e-9)) == 0
    pen = edge_penetrations(x, topo, min_depth=1e-9)
    assert sorted(zip(pen.vertex.tolist(), pen.block.tolist(), strict=True)) == [
        (0, 1), (2, 1), (4, 0), (6, 0)]  # the four long edges, each in the other bar
    # the middle of a stretch across the other bar lies on that bar's centre line, half its
    # width from either of its sides
    assert pen.depth == pytest.approx([0.05] * 4, rel=1e-9)


@pytest.mark.parametrize("least", [0.0, 1e-4, 2.4e-4])
def test_two_bars_across_each_other_with_their_midpoints_at_the_others_side(least):
    """Two bars crossed like a plus sign whose long edges' midpoints lie 0.1 mm inside the
    other bar, at its side: the midpoint stood for its stretch because it lies in the other's
    box, and the 5 cm deep middle of the stretch went unprobed at every least depth, so the
    guard let a 1 cm^2 overlap through (a review's random search: 64 of 14,820 pairs missed
    by more than 3 least depths, all but 3 of them fixed here; those 3 have a concave other
    block). The midpoint now stands for its stretch only when it is at least half as deep as
    a bound of the stretch's depth (its ends' distance to the midpoint's nearest edge)."""
    from dda.contact.penetration import edge_penetrations

    x, topo = stack([[(-0.9, 0.0), (0.9002, 0.0), (0.9002, 0.1), (-0.9, 0.1)],
                     [(0.0, -0.9), (0.1, -0.9), (0.1, 0.9002), (0.0, 0.9002)]])
    assert len(vertex_penetrations(x, topo, min_depth=least)) == 0
    pen = edge_penetrations(x, topo, min_depth=least)
    assert sorted(zip(pen.vertex.tolist(), pen.block.tolist(), strict=True)) == [
        (0, 1), (2, 1), (5, 0), (7, 0)]  # the four long edges, each in the other bar
    assert pen.depth == pytest.approx([0.05] * 4, rel=1e-9)


def ell(a, b, t, turn=0.0, at=(0.0, 0.0)):
    """An L, counter-clockwise: arms ``a`` along x and ``b`` along y, ``t`` thick, its outer
    corner at ``at``, turned by ``turn`` about it."""
    p = np.array([(0, 0), (a, 0), (a, t), (t, t), (t, b), (0, b)], float)
    c, s = np.cos(turn), np.sin(turn)
    return p @ np.array([[c, s], [-s, c]]) + at


@pytest.mark.parametrize("least", [0.0, 1e-3, 1e-2])
def test_a_bar_past_an_ells_inner_corner_is_seen_in_both_arms(least):
    """A 5 cm bar laid across a 1 m thick L past its inner corner, its upper long edge 1.4 cm
    from that corner inside the L, its corners outside: along the edge the depth rises to
    0.5 m in either arm and falls to 1.4 cm at the corner, the edge's midpoint. The middle
    of a stretch stood for it (the depth along a stretch is concave inside a convex block,
    not inside an L): the guard found 6.4 cm (the lower edge's middle) of 0.50 m. A stretch
    inside a concave block is now searched (its pieces bounded by their ends' depths and
    nearest edges): 0.495 m."""
    from dda.contact.penetration import edge_penetrations

    d = np.array([1.0, -1.0]) / np.sqrt(2.0)  # along the bar
    up = np.array([1.0, 1.0]) / np.sqrt(2.0)
    on = up * 1.98 / np.sqrt(2.0)  # the point of the line x + y = 1.98 nearest the origin
    bar = [tuple(on + a * d + b * up) for a, b in ((-1.8, -0.05), (1.8, -0.05), (1.8, 0.0),
                                                    (-1.8, 0.0))]
    x, topo = stack([ell(3.0, 3.0, 1.0), bar])
    assert len(vertex_penetrations(x, topo, min_depth=least)) == 0
    pen = edge_penetrations(x, topo, min_depth=least)
    found = pen.depth[pen.block == 0].max(initial=0.0)
    true, step = boundary_depth_in(bar, ell(3.0, 3.0, 1.0), per_edge=2000)
    assert true == pytest.approx(0.5, abs=2e-3)
    assert 0.5 * true <= found <= true + step


@settings(max_examples=150, deadline=None, derandomize=True)
@given(st.tuples(st.floats(0.35, 2.0), st.floats(0.35, 2.0), st.floats(0.02, 0.3),
                 st.floats(0.0, 6.3), st.floats(-0.5, 0.5), st.floats(-0.5, 0.5)),
       st.tuples(st.floats(-0.5, 1.0), st.floats(-0.5, 1.0), st.floats(0.2, 2.5),
                 st.floats(0.01, 0.5), st.floats(0.0, 3.2)),
       st.sampled_from([0.0, 1e-3, 1e-2]))
def test_the_edge_and_corner_probes_see_half_of_an_overlap_with_an_ell(el, bar, least):
    """A rectangle and an L (arms 0.35-2 m, 2-30 cm thick, turned anyhow): the guard's probes
    find at least half of the depth of the rectangle's boundary inside the L whenever that
    is deeper than twice ``min_depth``, and never more than it. (A random search, 40,000
    such pairs and stars: 55 found less than half, 2 of them nothing of 4.8 and 9.0 cm; none
    since the stretch search.)"""
    from dda.contact.penetration import edge_penetrations

    a, b, t, turn, cx, cy = el
    k = ell(a, b, t, turn, (cx, cy))
    j = rectangle(*bar)
    x, topo = stack([j, k])
    found = max(float(p.depth[(topo.block[p.vertex] == 0) & (p.block == 1)].max(initial=0.0))
                for p in (edge_penetrations(x, topo, min_depth=least),
                          vertex_penetrations(x, topo, min_depth=least)))
    true, step = boundary_depth_in(j, k)
    assert found <= true + step + 1e-12
    if true > 2.0 * least + step:
        assert found >= 0.5 * true - step


def _deepest_found(polys, least, j=0, k=1):
    """The deepest point of block j inside block k the guard's probes (edges and corners)
    report at least depth ``least``."""
    from dda.contact.penetration import edge_penetrations

    x, topo = stack(polys)
    return max(float(p.depth[(topo.block[p.vertex] == j) & (p.block == k)].max(initial=0.0))
               for p in (edge_penetrations(x, topo, min_depth=least),
                         vertex_penetrations(x, topo, min_depth=least)))


def _saw_slab(chamber=(3.0, 4.0)):
    """A 10 m slab whose ceiling, 1 cm up, is a saw of 2 cm teeth 5 mm high but over a 1 m
    chamber 0.6 m high."""
    top = []
    for i, xx in enumerate(np.arange(10.0, -1e-12, -0.02)):
        if chamber[0] < xx < chamber[1]:
            continue
        top.append((xx, 0.01 + (0.005 if i % 2 else 0.0)))
        if xx > chamber[1] and xx - 0.02 < chamber[1]:
            top += [(chamber[1], 0.01), (chamber[1], 0.6), (chamber[0], 0.6), (chamber[0], 0.01)]
    return [(0.0, -1.0), (10.0, -1.0)] + top


# (a review's random and hand-made search, 180,000 pairs against shapely: four ways the
# concave search found less than half, each fixed; these fail on the code before)
@pytest.mark.parametrize("least", [0.0, 1e-3, 1e-2])
@pytest.mark.parametrize("case", ["inside, no crossing", "straight vertex", "saw", "tangled"])
def test_the_stretch_search_sees_half_in_a_concave_blocks_hard_cases(case, least):
    """- an edge wholly inside a slab with a notch above its midpoint: no crossing, so only
      its midpoint was probed (0.15 of 1.0 m);
    - a vertex between collinear edges 0.5 m inside an L, ending the stretch: counted as
      found but reported by no probe, it pruned the whole stretch (0 of 0.5 m);
    - a bar under a slab whose ceiling is a saw of short edges but over a chamber: the
      depth-first search spent its 48 probes far from the chamber (0.034 of 0.50 m); the
      piece of the largest bound is now halved first;
    - a T's edge along an L's inner wall to 1e-13 degrees: k's two collinear edges were
      crossed at meaningless places and the crossing at the reflex corner missed, so entry
      and leave no longer alternated and a stretch 2.04 m deep was taken for outside (older
      than the search; 0.50 found): every stretch of such an edge is now probed."""
    if case == "inside, no crossing":
        k = [(0, 0), (10, 0), (10, 2), (5.05, 2), (5.05, 1.1), (4.95, 1.1), (4.95, 2), (0, 2)]
        j = [(0.1, 0.95), (9.9, 0.95), (9.9, 1.0), (0.1, 1.0)]
    elif case == "straight vertex":
        k = ell(3.0, 3.0, 1.0)
        j = [(2, -5), (2, 0.5), (2, 5), (-10, 5), (-10, -5)]
    elif case == "saw":
        k = _saw_slab()
        j = [(-1.0, -0.02), (11.0, -0.02), (11.0, 0.0), (-1.0, 0.0)]
    else:
        j = [(222.06911504828759, 109.89846599749092), (276.082686689263, 152.70946066408567),
             (273.36340813695574, 156.14030706325676), (281.68353657306, 162.73481587432067),
             (259.39996814577995, 190.84944224628504), (188.74613963259588, 134.84942995756242),
             (211.02970805987596, 106.73480358559807), (219.34983649598027, 113.329312396662)]
        k = [(270.4394159864529, 159.02068400730863), (274.80243781752887, 153.5159674250553),
             (277.9948542401181, 156.0462670939877), (276.16213207797455, 158.3585672536518),
             (277.52347235500787, 159.43756146878872), (281.12008909700984, 162.28822909697465),
             (278.58978942807744, 165.4806455195639)]
    true, step = boundary_depth_in(j, k, per_edge=20000)
    found = _deepest_found([j, k], least)
    assert true > 0.4
    assert 0.5 * true - step <= found <= true + step


def test_a_stretch_that_runs_to_its_edges_end_is_not_bounded_by_half_its_length():
    """An L's edge enters a star and ends inside it, 0.64 m deep at its end, over a stretch
    0.85 m long. The stretch was skipped at a least depth above half its length (0.43 m),
    a bound that holds only between two crossings, where both ends are on the star's
    boundary: the probes with that least depth missed the edge that those without it found
    (a review's search for the exactness below, 25 of 3,900 pairs, since the whole-edge
    search; the bound itself was older)."""
    from dda.contact.penetration import edge_penetrations

    star_ = [(17.45859292962612, 66.68890667991808), (38.57827906495654, 15.30549293443508),
             (84.45457797934577, 24.284536080627753), (113.32078554486415, 47.760866193511376),
             (93.51513733987761, 78.12700808636714), (69.60127151890137, 67.83959437294982)]
    ell_ = [(39.51793179663286, 66.32532031346997), (69.60127151890137, 66.32532031346997),
            (69.60127151890137, 67.83959437294982), (41.032205856112704, 67.83959437294982),
            (41.032205856112704, 97.2419347960504), (39.51793179663286, 97.2419347960504)]
    x, topo = stack([star_, ell_])
    least = 0.43137505490117534
    every = edge_penetrations(x, topo)
    deep = edge_penetrations(x, topo, min_depth=least)
    keep = every.depth > least
    assert (11, 0) in set(zip(every.vertex[keep].tolist(), every.block[keep].tolist(),
                              strict=True))
    assert sorted(zip(deep.vertex.tolist(), deep.block.tolist(), deep.depth.tolist(),
                      strict=True)) == sorted(zip(every.vertex[keep].tolist(),
                                                  every.block[keep].tolist(),
                                                  every.depth[keep].tolist(), strict=True))


def test_the_guard_stops_a_bar_that_passed_through_a_plate_between_its_corners(monkeypatch):
    """With a contact detector that finds nothing, a slanted bar thrown down at 10 m/s onto a
    fixed 2 cm plate passes its lower corner through the plate within one step (5 cm at dt
    5 ms): after it no corner and no edge midpoint of either is inside the other, only the
    stretches of the bar's long edges across the plate. The guard refuses that step (its
    cuts then find the corner inside, which detection, blind, does not hold)."""
    import dda.step as step
    from dda.contact.detection import CandidateContacts

    def blind(x, topo, d0, limit, pairs=None, sunk_depth=None, boxes=None, touch=0.0):
        return CandidateContacts(*(np.zeros(0, dtype=np.int64) for _ in range(4)))

    monkeypatch.setattr(step, "narrow_phase", blind)
    rock = LinearElastic(young=10e9, poisson=0.25, density=2600.0)
    scene = dda.Scene(gravity=0.0)
    scene.add_block([(-1.0, -0.02), (1.0, -0.02), (1.0, 0.0), (-1.0, 0.0)], rock, fixed=True,
                    name="plate")
    c, s = np.cos(np.radians(70.0)), np.sin(np.radians(70.0))
    axis, across = np.array([c, s]), np.array([-s, c])
    low = np.array([0.3, 0.01])  # the bar's lower end, 1 cm above the plate
    scene.add_block([tuple(low + a * axis + b * across) for a, b in
                     ((0.0, -0.02), (1.0, -0.02), (1.0, 0.02), (0.0, 0.02))], rock, name="bar",
                    velocity=(0.0, -10.0))
    scene.set_joint(JointMaterial(1e9, 1e9, CoulombSingle(phi=30.0)))
    sim = dda.Simulation(scene, dt=5e-3)
    with pytest.raises(dda.SimulationError, match=r"untracked penetration: .* of block 'bar' "
                                                  r".* inside block 'plate'"):
        sim.run(0.02, progress=False)
    # its first step was refused (cut down until its corner is seen inside the plate), not
    # taken through
    assert sim.committed.time < 5e-3
