"""Bounded input (issue 21, item 2): polygon validity in O(n log n), limits on vertices and
blocks, cuts refused before they start, scene files that nest or weigh too much, the range
of dt. Each hostile input is built here."""

import time
import tracemalloc

import numpy as np
import pytest

import dda
from dda.geometry import JointSet, _self_intersections_all_pairs, cut_blocks, self_intersections
from dda.io import scene_file
from dda.io.scene_file import SceneFileError, load_scene
from dda.materials import LinearElastic
from tests.conftest import box
from tests.test_scene_file import FULL, write

ROCK = LinearElastic(young=1e9, poisson=0.25, density=2500.0)


def circle(n):
    a = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.column_stack([np.cos(a), np.sin(a)])


def test_the_sweep_finds_what_comparing_every_pair_finds():
    rng = np.random.default_rng(11)
    found = 0
    for trial in range(300):
        n = int(rng.integers(3, 40))
        v = rng.normal(size=(n, 2))
        if trial % 3 == 0:  # a star-shaped, simple polygon
            a = np.sort(rng.uniform(0.0, 2.0 * np.pi, n))
            v = np.column_stack([np.cos(a), np.sin(a)]) * rng.uniform(0.5, 1.5, n)[:, None]
        if trial % 5 == 0 and n > 4:  # a vertex on another edge: touching, not crossing
            v[0] = 0.5 * (v[2] + v[3])
        pairs = self_intersections(v)
        assert pairs == _self_intersections_all_pairs(v)
        found += bool(pairs)
    assert 100 < found < 300  # both kinds of polygon were tried


def test_a_polygon_of_200000_vertices_is_checked_in_linear_memory():
    """Comparing every pair of edges asked numpy for 37 GiB here (issue 21)."""
    v = circle(200_000)
    tracemalloc.start()
    t0 = time.perf_counter()
    assert self_intersections(v) == []
    seconds = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak < 100e6, peak
    assert seconds < 5.0, seconds  # measured 0.02 s
    v[50_000] = v[150_000]  # a vertex on the far side of the circle: two pairs meet
    assert len(self_intersections(v)) >= 2


def test_a_block_past_the_vertex_limit_is_refused_at_once():
    scene = dda.Scene()
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match="200,000 vertices, more than the limit of 100,000"):
        scene.add_block(circle(200_000), ROCK)
    assert time.perf_counter() - t0 < 2.0
    big = dda.Scene(max_vertices=300_000)
    big.add_block(circle(200_000), ROCK)  # a limit of the scene's own takes it
    assert len(big.blocks) == 1


def test_a_block_past_the_block_limit_is_refused():
    scene = dda.Scene(max_blocks=3)
    for i in range(3):
        scene.add_block(box(2.0 * i, 0.0, 1.0, 1.0), ROCK)
    with pytest.raises(ValueError, match="the scene has 3 blocks, its limit"):
        scene.add_block(box(10.0, 0.0, 1.0, 1.0), ROCK)
    with pytest.raises(ValueError, match="max_blocks must be a whole number"):
        dda.Scene(max_blocks=2.5)


def test_a_cut_of_a_billion_blocks_is_refused_before_it_starts():
    sets = [JointSet(dip=0.0, spacing=0.03), JointSet(dip=90.0, spacing=0.03)]
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=r"about 1,111,\d{3},\d{3} blocks, more than the limit"):
        cut_blocks([(0, 0), (1000, 0), (1000, 1000), (0, 1000)], sets)
    assert time.perf_counter() - t0 < 1.0
    grid = cut_blocks([(0, 0), (10, 0), (10, 10), (0, 10)],
                      [JointSet(dip=0.0, spacing=1.0), JointSet(dip=90.0, spacing=1.0)])
    assert len(grid) == 100  # (estimated 121: an estimate, on the safe side)


def test_a_scene_files_cut_takes_the_scenes_limit(tmp_path):
    text = FULL.replace("[scene]", "[scene]\nmax_blocks = 50", 1)
    text += """
[[cut]]
name = "rock"
material = "rock"
domain = [[10.0, 0.0], [20.0, 0.0], [20.0, 10.0], [10.0, 10.0]]
joint_sets = [{ dip = 0.0, spacing = 1.0 }, { dip = 90.0, spacing = 1.0 }]
"""
    with pytest.raises(SceneFileError,
                       match=r"cut\[1\]: .*about 121 blocks, more than the limit of 45"):
        load_scene(write(tmp_path, text))


def test_a_scene_file_that_nests_too_deeply_says_so(tmp_path):
    """50,000 nested arrays gave a bare RecursionError."""
    f = tmp_path / "deep.toml"
    f.write_text("[scene]\ngravity = " + "[" * 50_000 + "]" * 50_000 + "\n")
    with pytest.raises(SceneFileError, match="deep.toml: not a scene file: its arrays or "
                                             "tables nest too deeply"):
        load_scene(f)


def test_a_scene_file_too_large_is_not_read(tmp_path, monkeypatch):
    monkeypatch.setattr(scene_file, "MAX_FILE_BYTES", 1000)
    f = write(tmp_path, FULL + "\n# " + "x" * 2000 + "\n")
    with pytest.raises(SceneFileError, match="bytes, more than a scene file's 1,000"):
        load_scene(f)
    g = tmp_path / "binary.toml"
    g.write_bytes(b"\xff\xfe[scene]")
    with pytest.raises(SceneFileError, match="not UTF-8 text"):
        load_scene(g)


@pytest.mark.parametrize("dt", [1e-300, 1e-10, 1e4, 1e300])
def test_dt_outside_its_range_is_refused(dt):
    """dt 1e-300 passed and the run could never end; 1e300 overflowed in the step."""
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 1, 1), ROCK)
    with pytest.raises(ValueError, match="dt must lie between 1e-09 and 1000 s"):
        dda.Simulation(scene, dt=dt)


def test_a_scene_files_dt_outside_its_range_names_its_line(tmp_path):
    text = FULL.replace("dt = ", "dt = 1e-300 #", 1)
    with pytest.raises(SceneFileError, match=r"line \d+, simulation.*dt must lie between"):
        load_scene(write(tmp_path, text))
