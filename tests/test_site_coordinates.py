"""A scene at a site's coordinates (a UTM northing, y = 4e6 m) runs as it does at the origin:
the model computes about the scene's centre (dda.geometry.site_origin), and the frames and
results come back in the scene's coordinates."""

import warnings

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.geometry import site_origin
from dda.materials import LinearElastic
from dda.registry import make_solver

SITE = np.array([5e5, 4e6])
ROCK = LinearElastic(young=5e9, poisson=0.25, density=2600.0)


def three_blocks(at, effects=False):
    """An L and a sliding square on a fixed base (the review's scene); with ``effects`` also a
    water table, a point load, a bolt and a block pushed by springs at two of its points."""
    at = np.asarray(at, dtype=float)

    def moved(points):
        return [tuple(np.asarray(p, dtype=float) + at) for p in points]

    scene = dda.Scene(gravity=9.81)
    scene.add_block(moved([(-1, -0.2), (2, -0.2), (2, 0), (-1, 0)]), ROCK, fixed=True,
                    name="base")
    scene.add_block(moved([(0, 0), (0.8, 0), (0.8, 0.2), (0.2, 0.2), (0.2, 0.6), (0, 0.6)]),
                    ROCK, name="L")
    scene.add_block(moved([(0.3, 0.2), (0.6, 0.2), (0.6, 0.5), (0.3, 0.5)]), ROCK, name="sq",
                    velocity=(0.5, 0.0))
    scene.set_joint(JointMaterial(normal_penalty=5e9, shear_penalty=5e9,
                                  friction=CoulombSingle(phi=25.0)))
    if effects:
        scene.add_block(moved([(1.2, 0), (1.6, 0), (1.6, 0.3), (1.2, 0.3)]), ROCK, name="push")
        scene.set_water_table(moved([(-1.0, 0.1), (2.0, 0.3)]))
        scene.add_point_load("L", moved([(0.1, 0.5)])[0], (200.0, -100.0))
        scene.add_bolt("L", moved([(0.1, 0.3)])[0], "base", moved([(0.1, -0.15)])[0],
                       stiffness=1e7, pretension=1e3)
        scene.prescribe_motion("push", lambda t: (-0.05 * t, None),
                               points=moved([(1.6, 0.1), (1.6, 0.2)]))
    return scene


@pytest.mark.parametrize("solver", ["newton", "legacy"])
@pytest.mark.parametrize("effects", [False, True])
def test_a_scene_at_a_site_runs_as_at_the_origin(solver, effects):
    """Before, Newton-Raphson stopped this scene at t = 0.109 s at (5e5, 4e6) ("did not
    converge in 25 iterations", where it ran through at the origin) and legacy DDA slid the
    square 5e-7 m off; now both match the origin's run to 1e-10 m (a coordinate's own
    rounding at 4e6 m is 5e-10 m)."""
    runs = []
    for at in ((0.0, 0.0), SITE):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dda.PlausibilityWarning)
            sim = dda.Simulation(three_blocks(at, effects), dt=2e-3, solver=make_solver(solver))
        runs.append((sim, sim.run(0.3, progress=False)))
    (near_sim, near), (far_sim, far) = runs
    assert far_sim.model.origin.tolist() == [5e5, 4e6]
    assert not near_sim.model.origin.any()
    assert len(far.stats) == len(near.stats)
    for name in ("L", "sq"):
        np.testing.assert_allclose(far.displacement(name), near.displacement(name),
                                   rtol=0, atol=1e-10)
    # the frames and the initial centroids are in the scene's coordinates
    here, there = near_sim.frame(), far_sim.frame()
    np.testing.assert_allclose(there.vertices, here.vertices + SITE, rtol=0, atol=2e-9)
    np.testing.assert_allclose(there.contact_point, here.contact_point + SITE, rtol=0,
                               atol=2e-9)
    if effects:
        np.testing.assert_allclose(there.bolt_points, here.bolt_points + SITE, rtol=0,
                                   atol=2e-9)
    np.testing.assert_allclose(far.to_xarray()["initial_centroid"].values,
                               near.to_xarray()["initial_centroid"].values + SITE, atol=2e-9)


def test_only_a_scene_far_from_the_origin_moves():
    """Scenes near the origin keep their coordinates (their runs are the same to the bit);
    a far one is moved by its centre, rounded below its extent."""
    square = np.array([(0, 0), (1, 0), (1, 1), (0, 1)], dtype=float)
    assert not site_origin(square).any()
    assert not site_origin(square + 99.0).any()  # 99.5 m from a 1 m block: left
    assert site_origin(square + 1000.3).tolist() == [1001.0, 1001.0]
    assert site_origin(square * 40 + [20.0, 4.1e6]).tolist() == [40.0, 4100020.0]
    assert not site_origin(np.zeros((0, 2))).any()


def test_a_checkpoint_of_before_the_origin_resumes_in_place(tmp_path):
    """A checkpoint written before models had an origin holds the scene's coordinates; it
    resumes where it stopped (read as the model's, every block sat 4e6 m off: a displacement
    of (5e5, 4e6) m for a block that had moved 1 mm)."""
    import json

    path = tmp_path / "run.ckpt"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", dda.PlausibilityWarning)
        sim = dda.Simulation(three_blocks(SITE), dt=2e-3)
        sim.run(0.02, progress=False, checkpoint=path)
        reference = dda.Simulation(three_blocks(SITE), dt=2e-3)
        reference.run(0.04, progress=False)
    with np.load(path) as f:  # the layout of before: no origin, positions as the scene's
        arrays = dict(f)
    header = json.loads(arrays["header"].tobytes().decode())
    assert header["state"].pop("origin") == SITE.tolist()
    for name in ("x", "centroid"):
        arrays[f"a/state/{name}"] = arrays[f"a/state/{name}"] + SITE
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    old = tmp_path / "old.ckpt"
    with open(old, "wb") as f:
        np.savez(f, **arrays)
    resumed = dda.Simulation.resume(old)
    np.testing.assert_allclose(resumed.frame().vertices, sim.frame().vertices, rtol=0,
                               atol=1e-9)
    result = resumed.run(0.02, progress=False)
    assert np.abs(result.displacement("sq")[-1]).max() < 0.05
    np.testing.assert_allclose(resumed.frame().vertices, reference.frame().vertices, rtol=0,
                               atol=1e-9)


def test_the_potential_energy_is_measured_from_the_scenes_y_0():
    """A 1 m block of 1000 kg/m^3 under g = 10 at y = 101 (the model's origin at 102) has
    rho g A y_c = 1.015e6 J/m, as at y = 99 with none (it read -5000 J/m)."""
    rock = LinearElastic(young=5e9, poisson=0.25, density=1000.0)
    for y in (99.0, 101.0, 5e6):
        scene = dda.Scene(gravity=10.0)
        scene.add_block([(0, y), (1, y), (1, y + 1), (0, y + 1)], rock)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dda.PlausibilityWarning)
            sim = dda.Simulation(scene, dt=1e-3)
        assert sim.energy().potential == pytest.approx(1e4 * (y + 0.5), rel=1e-12)


def test_a_far_scenes_energy_changes_as_at_the_origin():
    """Over 0.1 s the three blocks' total energy changes by -29.04 J/m at the origin; at the
    site it read -35,039 J/m (the blocks' strained areas times the origin's 4e6 m)."""
    changes = []
    for at in ((0.0, 0.0), SITE):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dda.PlausibilityWarning)
            sim = dda.Simulation(three_blocks(at), dt=2e-3)
        before = sim.energy()
        sim.run(0.1, progress=False)
        after = sim.energy()
        changes.append((after.total - before.total, after.potential - before.potential))
    (total0, potential0), (total1, potential1) = changes
    assert total0 == pytest.approx(-29.04, abs=0.01)
    assert total1 == pytest.approx(total0, abs=0.01)
    assert potential1 == pytest.approx(potential0, abs=1e-3)
