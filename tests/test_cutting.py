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
