"""Block cutting by joint sets (dda.geometry.cut_blocks)."""

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.contact.detection import find_overlaps
from dda.geometry import JointSet, cut_blocks, signed_areas
from dda.materials import LinearElastic

ROCK = LinearElastic(young=1e9, poisson=0.2, density=2500.0)


def areas(blocks):
    x = np.concatenate([np.asarray(b) for b in blocks])
    offsets = np.concatenate([[0], np.cumsum([len(b) for b in blocks])])
    return signed_areas(x, offsets), x, offsets


def test_two_orthogonal_sets_cut_a_grid():
    blocks = cut_blocks([(0, 0), (3, 0), (3, 2), (0, 2)],
                        [JointSet(dip=0, spacing=1), JointSet(dip=90, spacing=1)])
    assert len(blocks) == 6
    a, _, _ = areas(blocks)
    np.testing.assert_allclose(a, 1.0, rtol=1e-12)  # counter-clockwise unit squares
    assert all(len(b) == 4 for b in blocks)
    assert sorted(blocks[0]) == [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)]


def test_inclined_set_counts_and_dip_convention():
    """Traces at 45 deg, 1 m apart across a 10 m square: 14 traces, 15 strips; a trace
    dipping +30 descends towards +x."""
    blocks = cut_blocks([(0, 0), (10, 0), (10, 10), (0, 10)], [JointSet(dip=45, spacing=1)],
                        min_size=0.0)
    assert len(blocks) == 15
    cut = cut_blocks([(0, 0), (2, 0), (2, 2), (0, 2)],
                     [JointSet(dip=30, spacing=10, offset=np.hypot(1, 1) * np.cos(
                         np.radians(75)))], min_size=0.0)
    assert len(cut) == 2
    shared = set(cut[0]) & set(cut[1])
    (x1, y1), (x2, y2) = sorted(shared)
    assert (y2 - y1) / (x2 - x1) == pytest.approx(-np.tan(np.radians(30)), rel=1e-9)


@pytest.mark.parametrize("persistence", [1.0, 0.6])
def test_blocks_tile_the_domain(persistence):
    """Without sliver dropping the blocks cover the domain exactly, never overlap, and make a
    valid scene; non-persistent traces make fewer, larger blocks."""
    domain = [(0, 0), (12, 0), (12, 6), (5, 6), (0, 2)]
    sets = [JointSet(dip=-25, spacing=0.9),
            JointSet(dip=70, spacing=1.3, persistence=persistence, trace_length=2.0)]
    blocks = cut_blocks(domain, sets, min_size=0.0, seed=3)
    a, x, offsets = areas(blocks)
    assert np.all(a > 0)
    assert a.sum() == pytest.approx(12 * 6 - 0.5 * 5 * 4, rel=1e-9)
    assert find_overlaps(x, offsets) == []
    scene = dda.Scene()
    for b in blocks:
        scene.add_block(b, ROCK)
    scene.set_joint(JointMaterial(1e9, 1e9, CoulombSingle(phi=30)))
    scene.validate()
    persistent = cut_blocks(domain, [sets[0], JointSet(dip=70, spacing=1.3)], min_size=0.0)
    if persistence < 1:
        assert len(blocks) < len(persistent)
    else:
        assert len(blocks) == len(persistent)


@pytest.mark.parametrize("width, height", [(1, 1), (2, 1), (4, 3), (7, 5), (8, 8)])
def test_a_joint_on_the_domain_boundary_loses_no_block(width, height):
    """A grid whose traces fall on the boundary: a trace computed with sin and cos lies
    4e-16 m inside it. Snapped after noding, it overlapped the boundary unnoded and whole
    blocks vanished (a 1 m square cut by a vertical set 1 m apart gave no block; a 4 x 3 m
    rectangle 10 of 12)."""
    rect = [(0, 0), (width, 0), (width, height), (0, height)]
    blocks = cut_blocks(rect, [JointSet(dip=0, spacing=1), JointSet(dip=90, spacing=1)])
    a, _, _ = areas(blocks)
    assert len(blocks) == width * height
    np.testing.assert_allclose(a, 1.0, rtol=1e-12)
    for dip in (90, -90, 180):
        one = cut_blocks([(0, 0), (1, 0), (1, 1), (0, 1)], [JointSet(dip=dip, spacing=1)])
        assert len(one) == 1 and areas(one)[0][0] == pytest.approx(1.0, rel=1e-12)
    ell = [(0, 0), (3, 0), (3, 1), (1, 1), (1, 3), (0, 3)]  # a trace along its inner edge
    a, _, _ = areas(cut_blocks(ell, [JointSet(dip=90, spacing=1)]))
    assert len(a) == 3 and a.sum() == pytest.approx(5.0, rel=1e-12)


def _split_reference(domain, sets, seed):
    """The blocks by splitting the domain along every trace until none splits a piece more
    (shapely's split; no noding or polygonizing), sliver-free: what cut_blocks must give."""
    from shapely.geometry import LineString, Polygon
    from shapely.ops import split

    dom = Polygon(domain)
    rng = np.random.default_rng(seed)
    lines = [LineString(seg) for js in sets for seg in js.traces(dom.bounds, rng)]
    pieces, changed = [dom], True
    while changed:  # a trace ending inside a piece may cross one of its later parts
        changed, new = False, []
        for piece in pieces:
            parts = [piece]
            for line in lines:  # a split along an edge leaves slivers of 1e-20 m^2
                parts = [q for p in parts for q in (split(p, line).geoms
                                                    if line.crosses(p) else [p])
                         if q.area > 1e-12]
            changed |= len(parts) > 1
            new.extend(parts)
        pieces = new
    return sorted(p.area for p in pieces)


@pytest.mark.parametrize("seed", [1, 3])
def test_non_persistent_sets_match_splitting_trace_by_trace(seed):
    """The example's cut slope (examples/jointed_slope.py) at seeds 1 and 3: every block of
    splitting the mass trace by trace, no joint lost (before the fix, 306 of 315 and 318 of
    330 blocks: faces beside a trace left unnoded were merged)."""
    mass = [(20.0, 0.0), (60.0, 0.0), (60.0, 20.0), (32.0, 20.0)]
    sets = [JointSet(dip=-25.0, spacing=1.0, offset=0.3),
            JointSet(dip=70.0, spacing=1.6, persistence=0.8, trace_length=5.0)]
    a, x, offsets = areas(cut_blocks(mass, sets, min_size=0.0, seed=seed))
    reference = _split_reference(mass, sets, seed)
    assert len(a) == len(reference)
    np.testing.assert_allclose(np.sort(a), reference, rtol=1e-7, atol=1e-9)
    assert find_overlaps(x, offsets) == []


def test_traces_that_reach_no_joint_cut_nothing():
    blocks = cut_blocks([(0, 0), (10, 0), (10, 1), (0, 1)],
                        [JointSet(dip=0, spacing=0.5, offset=0.25, persistence=0.5,
                                  trace_length=1.0)])
    assert len(blocks) == 1


def test_slivers_are_dropped():
    """Traces at x = 0.02, 1.02, 2.02 across a 3 x 1 domain: the 2 cm strip goes."""
    sets = [JointSet(dip=90, spacing=1.0, offset=0.02)]
    blocks = cut_blocks([(0, 0), (3, 0), (3, 1), (0, 1)], sets)
    a, _, _ = areas(blocks)
    np.testing.assert_allclose(sorted(a), [0.98, 1.0, 1.0], rtol=1e-9)
    assert len(cut_blocks([(0, 0), (3, 0), (3, 1), (0, 1)], sets, min_size=0.0)) == 4


def test_slivers_over_a_percent_of_the_area_are_reported():
    """A 5 cm strip of a 1 m square, 5% of its area, went with no word (a review's two sets
    1 degree apart lost 18 of 27 pieces, 3.5% of the area); now a warning says how many and
    how much; a 0.7% strip is not worth one. One JointSet is taken as a list of one."""
    square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    with pytest.warns(dda.PlausibilityWarning, match=r"cut_blocks: 1 slivers thinner than "
                                                     r"min_size = 0.1 m were dropped, 5% of"):
        blocks = cut_blocks(square, JointSet(dip=90, spacing=1.0, offset=0.05), min_size=0.1)
    assert len(blocks) == 1 and areas(blocks)[0][0] == pytest.approx(0.95, rel=1e-12)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", dda.PlausibilityWarning)
        cut_blocks([(0, 0), (3, 0), (3, 1), (0, 1)], [JointSet(dip=90, spacing=1.0,
                                                               offset=0.02)])  # 0.7%


@pytest.mark.parametrize("kwargs, match", [
    ({"dip": 0, "spacing": 0}, "spacing must be positive"),
    ({"dip": np.nan, "spacing": 1}, "dip must be finite"),
    ({"dip": 0, "spacing": 1, "persistence": 1.5}, "persistence"),
    ({"dip": 0, "spacing": 1, "persistence": 0.5}, "trace_length"),
    ({"dip": 0, "spacing": 1, "persistence": 0.0}, "persistence must be positive"),
])
def test_bad_joint_sets(kwargs, match):
    with pytest.raises(ValueError, match=match):
        JointSet(**kwargs)


def test_bad_domains_and_sets():
    with pytest.raises(ValueError, match="simple polygon"):
        cut_blocks([(0, 0), (1, 1), (1, 0), (0, 1)], [JointSet(dip=0, spacing=1)])
    with pytest.raises(ValueError, match="corners"):
        cut_blocks([(0, 0), (1, 1)], [JointSet(dip=0, spacing=1)])
    with pytest.raises(TypeError, match=r"joint_sets\[0\]"):
        cut_blocks([(0, 0), (1, 0), (1, 1)], [(0, 1)])


def _circle(cx, cy, r, n=48):
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t)])


def test_an_opening_is_taken_out_before_the_cut():
    """A tunnel in a jointed mass (an underground review: a shapely polygon with a hole was
    refused as 'not (n, 2) corners', and dropping the blocks whose centroid lay in the tunnel
    left 16 blocks over 4.19 of its 19.55 m^2). The blocks tile the domain less the opening,
    none reaches into it, and the same cut comes from a shapely polygon with the hole."""
    from shapely.geometry import Point, Polygon

    domain = [(0, 0), (16, 0), (16, 16), (0, 16)]
    tunnel = _circle(8.0, 8.0, 2.5)
    sets = [JointSet(dip=60, spacing=1.0), JointSet(dip=120, spacing=1.0)]
    blocks = cut_blocks(domain, sets, min_size=0.0, openings=[tunnel])
    a, x, offsets = areas(blocks)
    hole = Polygon(tunnel)
    assert np.all(a > 0) and a.sum() == pytest.approx(256.0 - hole.area, rel=1e-9)
    assert find_overlaps(x, offsets) == []
    # (the noding grid is 1e-8 m here)
    assert all(Polygon(b).intersection(hole).area < 1e-7 for b in blocks)
    # corners on the outline: the blocks around it end there
    on_outline = [p for b in blocks for p in b if abs(Point(p).distance(hole.exterior)) < 1e-7]
    assert len(on_outline) > len(tunnel)
    with_hole = cut_blocks(Polygon(domain, holes=[tunnel]), sets, min_size=0.0)
    assert sorted(map(sorted, with_hole)) == sorted(map(sorted, blocks))
    # the slivers the outline leaves go as any other (with those at the domain's sides)
    kept = cut_blocks(domain, sets, min_size=0.25, openings=[tunnel])
    dropped = {tuple(sorted(b)) for b in blocks} - {tuple(sorted(b)) for b in kept}
    assert len(kept) + len(dropped) == len(blocks)
    assert sum(Polygon(b).distance(hole) < 1e-7 for b in dropped) >= 4


def test_an_opening_across_the_boundary_and_bad_openings():
    domain = [(0, 0), (10, 0), (10, 6), (0, 6)]
    sets = [JointSet(dip=0, spacing=1.0), JointSet(dip=90, spacing=1.0)]
    portal = [(4.0, 4.5), (6.0, 4.5), (6.0, 7.0), (4.0, 7.0)]  # a cutting from the top
    blocks = cut_blocks(domain, sets, min_size=0.0, openings=[portal])
    a, _, _ = areas(blocks)
    assert a.sum() == pytest.approx(60.0 - 2.0 * 1.5, rel=1e-9)
    with pytest.raises(ValueError, match=r"openings\[0\] lies inside one block"):
        cut_blocks(domain, [JointSet(dip=0, spacing=5.0)], openings=[_circle(5, 3, 0.5)])
    with pytest.raises(ValueError, match=r"openings\[0\] lies outside the domain"):
        cut_blocks(domain, sets, openings=[_circle(20, 3, 0.5)])
    with pytest.raises(ValueError, match=r"openings\[0\] must be a simple polygon"):
        cut_blocks(domain, sets, openings=[[(1, 1), (3, 3), (3, 1), (1, 3)]])
    with pytest.raises(ValueError, match="take the whole domain"):
        cut_blocks(domain, sets, openings=[[(-1, -1), (11, -1), (11, 7), (-1, 7)]])
