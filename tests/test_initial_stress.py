"""Initial stress of blocks (METHOD.md section 1: the load -A [sxx, syy, sxy] on the strain
unknowns): a free block relaxes it, a confined one keeps it, scene files and checkpoints
carry it (an underground review: no in-situ stress could be given)."""

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.io.scene_data import ArrayStore, scene_from_data, scene_to_data
from dda.materials import LinearElastic
from dda.solvers import LegacyPullBack, NewtonRaphson
from tests.conftest import box

ROCK = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
SOLVERS = [LegacyPullBack(), NewtonRaphson()]
IDS = ["legacy", "newton"]


@pytest.mark.parametrize("solver", SOLVERS, ids=IDS)
def test_a_free_block_relaxes_its_stress_into_strain(solver):
    """Nothing holds it: the stress goes to zero and the block strains by -D^-1 sigma_0
    (plane stress, E 1 GPa, nu 0.25: 0.5e-3 and 1.75e-3 for -1 and -2 MPa)."""
    scene = dda.Scene(gravity=0.0)
    scene.add_block(box(0, 0, 1, 1), ROCK, stress=(-1e6, -2e6, 0.0), name="b")
    scene.add_block(box(3, 0, 1, 1), ROCK, fixed=True)
    scene.set_joint(JointMaterial(1e10, 1e10, CoulombSingle(phi=30.0)))
    sim = dda.Simulation(scene, dt=0.01, analysis="static", solver=solver)
    np.testing.assert_array_equal(sim.committed.stress[0], [-1e6, -2e6, 0.0])
    sim.run(0.05, progress=False)
    np.testing.assert_allclose(sim.committed.stress[0], 0.0, atol=1e-3)
    strain = -np.linalg.solve(ROCK.elasticity(), [-1e6, -2e6, 0.0])
    x = sim.committed.x[:4]
    # (to the small-strain update's second order: 1.2e-8 here)
    np.testing.assert_allclose(np.ptp(x, axis=0), 1.0 + strain[:2], rtol=1e-7)


@pytest.mark.parametrize("solver", SOLVERS, ids=IDS)
def test_a_block_between_walls_keeps_its_stress_but_the_springs_give(solver):
    """sxx_0 = -1 MPa between two fixed frictionless walls on springs of p = 1e11 N/m (two a
    side): the block expands into them until E eps_x = sigma - sigma_0 and p (eps_x L / 2) x
    2 = -sigma H: sigma = sigma_0 / (1 + E H / (p L)) = -0.990099 MPa (H = L = 1 m); the
    walls carry it.
    (With friction the walls' shear springs hold the block's Poisson expansion: -0.98946.)"""
    scene = dda.Scene(gravity=0.0)
    scene.add_block(box(-1, 0, 1, 1), ROCK, fixed=True, name="left")
    scene.add_block(box(0, 0, 1, 1), ROCK, stress=(-1e6, 0.0, 0.0), name="b")
    scene.add_block(box(1, 0, 1, 1), ROCK, fixed=True, name="right")
    scene.set_joint(JointMaterial(1e11, 1e11, CoulombSingle(phi=0.0)))
    sim = dda.Simulation(scene, dt=0.01, analysis="static", solver=solver)
    result = sim.run(0.1, progress=False)
    expected = -1e6 / (1.0 + 1e9 / 1e11)
    assert sim.committed.stress[1, 0] == pytest.approx(expected, rel=1e-6)
    assert abs(sim.committed.stress[1, 1]) < 1e-6 * 1e6
    # the walls carry it over the block's height, which Poisson shrank by 2.5e-6
    assert result.joint_force("left", "b")[-1, 0] == pytest.approx(
        -expected * (1.0 - 0.25 * 9.9e-6), rel=1e-7)


def test_set_initial_stress_takes_a_field_at_the_centroids():
    """A vertical stress growing with depth below y = 10 m, k0 = 0.5, on every block that is
    neither fixed nor rigid; a rigid block's stress is refused."""
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, -1, 3, 1), ROCK, fixed=True, name="base")
    scene.add_block(box(0, 0, 1, 2), ROCK, name="low")
    scene.add_block(box(0, 2, 1, 2), ROCK, name="high")
    scene.add_block(box(2, 0, 1, 1), ROCK, rigid=True, name="stiff")

    def field(x, y):
        sv = -2500.0 * 9.81 * (10.0 - y)
        return (0.5 * sv, sv, 0.0)

    scene.set_initial_stress(field)
    scene.set_joint(JointMaterial(1e10, 1e10, CoulombSingle(phi=30.0)))
    stress = dda.Simulation(scene, dt=1e-3).committed.stress
    np.testing.assert_allclose(stress[1], field(0.5, 1.0), rtol=1e-12)
    np.testing.assert_allclose(stress[2], field(0.5, 3.0), rtol=1e-12)
    np.testing.assert_array_equal(stress[[0, 3]], 0.0)
    with pytest.raises(ValueError, match="a rigid block carries no stress"):
        scene.set_initial_stress((-1e6, 0, 0), blocks=["stiff"])
    with pytest.raises(ValueError, match="a rigid block carries no stress"):
        scene.add_block(box(5, 0, 1, 1), ROCK, rigid=True, stress=(-1e6, 0, 0))
    with pytest.raises(ValueError, match=r"stress must be \(sxx, syy, sxy\)"):
        scene.add_block(box(5, 0, 1, 1), ROCK, stress=(-1e6, 0))
    with pytest.raises(ValueError, match="stress sxx must be finite"):
        scene.add_block(box(5, 0, 1, 1), ROCK, stress=(float("nan"), 0, 0))


def test_initial_stress_in_scene_files_and_checkpoints(tmp_path):
    from dda.io.scene_file import SceneFileError, load_scene
    from tests.test_scene_file import FULL, write

    text = FULL.replace('vertices = [[1, 1], [2, 1], [2, 2], [1, 2]]\nrigid = true',
                        'vertices = [[1, 1], [2, 1], [2, 2], [1, 2]]\nstress = [-1e5, -2e5, 3e4]')
    text = text.replace("min_size = 0.05\n", "min_size = 0.05\nstress = [-4e5, 0, 0]\n")
    loaded = load_scene(write(tmp_path, text))
    inputs = dict(zip([b.name for b in loaded.scene.blocks], loaded.scene.block_inputs,
                      strict=True))
    np.testing.assert_array_equal(inputs["top"].stress, [-1e5, -2e5, 3e4])
    assert all(np.array_equal(b.stress, [-4e5, 0, 0]) for n, b in inputs.items()
               if n.startswith("cut"))
    store = ArrayStore()
    back = scene_from_data(scene_to_data(loaded.scene, store), ArrayStore(store.arrays))
    for a, b in zip(loaded.scene.block_inputs, back.block_inputs, strict=True):
        np.testing.assert_array_equal(a.stress, b.stress)
    # [initial_stress]: 0.5 and 1 times 26 kPa a metre below y = 3, on the cut's blocks
    field = text.replace("[[shake]]", "[initial_stress]\nper_depth = [-13000, -26000, 0]\n"
                         "top = 3.0\nblocks = [\"cut0\", \"cut1\"]\n\n[[shake]]", 1)
    scene = load_scene(write(tmp_path, field, "field.toml")).scene
    sim = dda.Simulation(scene, dt=1e-3)
    for name in ("cut0", "cut1"):
        i = scene.block(name).index
        depth = 3.0 - sim.model.centroid_initial[i, 1] - sim.model.origin[1]
        np.testing.assert_allclose(sim.committed.stress[i], [-13000 * depth, -26000 * depth, 0],
                                   rtol=1e-9)
    with pytest.raises(SceneFileError, match="per_depth and top go together"):
        load_scene(write(tmp_path, field.replace("top = 3.0\n", ""), "half.toml"))
    bad = text.replace("stress = [-1e5, -2e5, 3e4]", "stress = [-1e5, -2e5]")
    with pytest.raises(SceneFileError, match=r"blocks\[1\]\.stress: must be \[sxx, syy, sxy\]"):
        load_scene(write(tmp_path, bad, "bad.toml"))


def test_a_block_whose_motion_is_known_drops_its_stress():
    """A fixed or fully moved block has no unknowns for a stress to act on: its stress was
    kept and counted 25 kJ/m of strain energy in energy(free_only=True) beside 45 J/m of the
    free blocks' (a review)."""
    from dda.energy import energy

    scene = dda.Scene(gravity=0.0)
    scene.add_block(box(0, 0, 1, 1), ROCK, fixed=True, stress=(-1e6, 0, 0), name="base")
    moved = scene.add_block(box(2, 0, 1, 1), ROCK, name="moved")
    scene.add_block(box(0, 1, 1, 1), ROCK, name="free")
    scene.prescribe_motion(moved, displacement=lambda t: (1e-3 * t, 0.0))
    scene.set_initial_stress((-2e5, -1e5, 0.0))
    scene.set_joint(JointMaterial(1e10, 1e10, CoulombSingle(phi=30.0)))
    sim = dda.Simulation(scene, dt=1e-3)
    np.testing.assert_array_equal(sim.committed.stress[[0, 1]], 0.0)
    np.testing.assert_array_equal(sim.committed.stress[2], [-2e5, -1e5, 0.0])
    s = np.array([-2e5, -1e5, 0.0])
    alone = 0.5 * s @ np.linalg.solve(ROCK.elasticity(), s)  # the free block's, area 1
    assert energy(sim, free_only=True).strain == pytest.approx(alone, rel=1e-12)


def test_a_field_that_grows_below_top_warns_of_blocks_above_it(tmp_path):
    from dda.io.scene_file import load_scene
    from dda.plausibility import PlausibilityWarning
    from tests.test_scene_file import FULL, write

    field = FULL.replace("[[shake]]", "[initial_stress]\nper_depth = [-13000, -26000, 0]\n"
                         "top = 1.2\n\n[[shake]]", 1)
    with pytest.warns(PlausibilityWarning, match=r"initial_stress\.top: \d+ block\(s\) have "
                      r"their centroid above top = 1.2 m .*tension for a compressive field"):
        load_scene(write(tmp_path, field))
