"""Water in the joints (dda.water, Scene.set_water_table): exact edge integrals, the
divergence theorem on a submerged block, and Hoek and Bray's planar slide with a water-filled
tension crack under both solvers."""

import textwrap
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

import dda
from dda import geometry
from dda.contact import CoulombSingle, JointMaterial
from dda.contact.detection import VertexTopology
from dda.materials import LinearElastic
from dda.solvers import LegacyPullBack, NewtonRaphson
from dda.water import WaterTable, water_forces

GAMMA = 9810.0
ROCK = LinearElastic(young=10e9, poisson=0.25, density=2600.0)

# a non-convex polygon (counter-clockwise)
ELL = np.array([(0.0, 0.0), (2.0, 0.0), (2.0, 0.5), (0.7, 0.5), (0.7, 1.5), (0.0, 1.5)])


def _forces(table, vertices):
    offsets = np.array([0, len(vertices)])
    topo = VertexTopology.from_offsets(offsets)
    ints = geometry.polygon_integrals(vertices, offsets, topo.nxt)
    return water_forces(table, vertices, topo.nxt, topo.block, ints.centroid)[0], ints


def _brute_force(table, vertices, centroid, n=20000):
    """The edge integral by the midpoint rule on n pieces an edge (error O(1/n^2))."""
    f = np.zeros(6)
    for p, q in zip(vertices, np.roll(vertices, -1, axis=0), strict=True):
        s = (np.arange(n) + 0.5) / n
        pts = p + s[:, None] * (q - p)
        length = np.hypot(*(q - p))
        pressure = table.unit_weight * np.maximum(table.head(pts[:, 0]) - pts[:, 1], 0.0)
        normal = np.array([q[1] - p[1], p[0] - q[0]]) / length
        t = geometry.t_matrix(pts, np.repeat(centroid[None], n, axis=0))
        f += np.einsum("gij,gi->j", t, -(pressure * length / n)[:, None] * normal)
    return f


def test_a_submerged_block_gets_the_divergence_theorems_forces():
    """Fully below a level h: f = (0, g A, 0, -g A (h - y_c), -g A (h - y_c), 0), the
    buoyancy through the centroid and the mean pressure on the strains, to round-off."""
    h = 3.0
    f, ints = _forces(WaterTable.level(h, GAMMA), ELL)
    area, yc = ints.area[0], ints.centroid[0, 1]
    mean = GAMMA * area * (h - yc)
    np.testing.assert_allclose(f, [0.0, GAMMA * area, 0.0, -mean, -mean, 0.0],
                               rtol=1e-12, atol=1e-9 * mean)


@pytest.mark.parametrize("table", [
    WaterTable.level(0.8, GAMMA),                          # crosses the ell's arm
    WaterTable(np.array([-1.0, 0.5, 1.2, 3.0]), np.array([0.2, 1.3, 0.4, 0.9]), GAMMA),
])
def test_a_block_the_table_crosses_equals_a_fine_sum(table):
    """Split at the table's nodes and crossings, two Gauss points a piece are exact: equal to
    a 20,000-piece midpoint sum to its own error (about 1e-8 relative)."""
    f, ints = _forces(table, ELL)
    ref = _brute_force(table, ELL, ints.centroid[0])
    np.testing.assert_allclose(f, ref, rtol=1e-7, atol=1e-7 * np.abs(ref).max())
    assert np.abs(f).max() > 100.0  # (something is loaded)


def test_a_level_through_a_box_lifts_it_by_the_water_it_displaces():
    """A 2 x 1 m box 0.3 m deep: lifted by the water's weight of 0.6 m^2, straight up
    through its centroid's vertical (no moment), no sideways force."""
    box = np.array([(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 1.0)])
    f, _ = _forces(WaterTable.level(0.3, GAMMA), box)
    np.testing.assert_allclose(f[:3], [0.0, GAMMA * 0.6, 0.0], atol=1e-9)


# ------------------------------------------------------------------ Hoek and Bray
PSI_P, PSI_F, HEIGHT, CRACK, TOE, PHI = 30.0, 60.0, 10.0, 4.0, 20.0, 40.0
_TAN_P = np.tan(np.radians(PSI_P))
Y_CRACK = HEIGHT - CRACK                      # the crack's bottom, on the sliding plane
X_CRACK = TOE - Y_CRACK / _TAN_P
WEDGE = [(X_CRACK, Y_CRACK), (TOE, 0.0), (TOE - HEIGHT / np.tan(np.radians(PSI_F)), HEIGHT),
         (X_CRACK, HEIGHT)]
# the rock behind the crack and below the plane; below the plane's daylight point the
# face goes on down, so the wedge can slide out
BASE = [(-2.0, -8.0), (30.0, -8.0), (30.0, -5.0), (TOE + 5.0 / np.tan(np.radians(PSI_F)), -5.0),
        (TOE, 0.0), (X_CRACK, Y_CRACK), (X_CRACK, HEIGHT), (-2.0, HEIGHT)]
PLANE = (TOE - X_CRACK) / np.cos(np.radians(PSI_P))   # A, the sliding plane's length


def _weight():
    offsets = np.array([0, 4])
    return 2600.0 * 9.81 * geometry.polygon_integrals(np.array(WEDGE), offsets).area[0]


def hoek_bray(zw):
    """Hoek and Bray's planar slide with a tension crack filled to zw (no cohesion):
    U = g zw A / 2 on the plane, V = g zw^2 / 2 in the crack, and
    F = (W cos psi - U - V sin psi) tan phi / (W sin psi + V cos psi); returns F, N', T."""
    w, s, c = _weight(), np.sin(np.radians(PSI_P)), np.cos(np.radians(PSI_P))
    u, v = 0.5 * GAMMA * zw * PLANE, 0.5 * GAMMA * zw ** 2
    normal, shear = w * c - u - v * s, w * s + v * c
    return normal * np.tan(np.radians(PHI)) / shear, normal, shear


def slope(zw):
    """The wedge on its plane, the water table level with the crack's water behind it and
    falling straight to the plane's daylight point (Hoek and Bray's pressure: zw at the
    crack's foot, linear to zero at the toe)."""
    scene = dda.Scene(gravity=9.81)
    scene.add_block(BASE, ROCK, fixed=True, name="base")
    scene.add_block(WEDGE, ROCK, name="wedge", rigid=True)
    scene.set_joint(JointMaterial(normal_penalty=1e11, shear_penalty=1e11,
                                  friction=CoulombSingle(phi=PHI)))
    scene.set_water_table([(-2.0, Y_CRACK + zw), (X_CRACK, Y_CRACK + zw), (TOE, 0.0),
                           (30.0, -5.0)])
    return scene


CRITICAL = brentq(lambda z: hoek_bray(z)[0] - 1.0, 0.0, CRACK)  # 3.538 m


@pytest.mark.parametrize("solver", [LegacyPullBack(), NewtonRaphson()], ids=["legacy", "newton"])
def test_the_planar_slide_starts_at_hoek_and_brays_critical_water_level(solver):
    """2% below the critical level (F = 1.011) the wedge stays and its joint carries Hoek
    and Bray's effective normal force and shear force; 2% above (F = 0.989) it slides."""
    moved = {}
    for share in (0.98, 1.02):
        scene = slope(share * CRITICAL)
        result = dda.Simulation(scene, dt=1e-3, solver=solver).run(0.5)
        d = np.hypot(*result.displacement(scene.block("wedge")).T)
        moved[share] = (d[len(d) // 2], d[-1])
        if share < 1.0:
            _, normal, shear = hoek_bray(share * CRITICAL)
            force = result.joint_force(scene.block("base"), scene.block("wedge"))[-1]
            np.testing.assert_allclose(np.abs(force), [normal, shear], rtol=1e-4)
    assert moved[0.98][1] < 1e-5 and moved[0.98][1] == pytest.approx(moved[0.98][0], rel=1e-3)
    assert moved[1.02][1] > 3e-3 and moved[1.02][1] > 3.0 * moved[1.02][0]  # accelerating


def test_a_dry_scene_takes_the_plain_block_path():
    scene = slope(1.0)
    assert not dda.Simulation(scene, dt=1e-3).model.plain_blocks
    dry = dda.Scene(gravity=9.81)
    dry.add_block(BASE, ROCK, fixed=True)
    dry.add_block(WEDGE, ROCK)
    dry.set_joint(JointMaterial(normal_penalty=1e11, shear_penalty=1e11,
                                friction=CoulombSingle(phi=PHI)))
    assert dry.water is None and dda.Simulation(dry, dt=1e-3).model.plain_blocks


# ------------------------------------------------------------------ input, files
def test_bad_water_tables_are_refused_with_what_is_wrong():
    scene = slope(1.0)
    scene.set_water_table([(0.0, 5.0), (25.0, 0.0)])
    with pytest.raises(ValueError, match=r"spans x = 0 to 25 m, not the scene's width, "
                                         r"-2 to 30 m"):
        dda.Simulation(scene, dt=1e-3)
    with pytest.raises(ValueError, match="x must increase strictly"):
        scene.set_water_table([(0.0, 5.0), (0.0, 6.0)])
    with pytest.raises(ValueError, match="at least 2"):
        scene.set_water_table([(0.0, 5.0)])
    with pytest.raises(ValueError, match="unit_weight must be positive"):
        scene.set_water_table(2.0, unit_weight=-9810.0)
    with pytest.raises(ValueError, match="NaN"):
        scene.set_water_table([(0.0, np.nan), (1.0, 2.0)])


def test_a_unit_weight_in_kn_is_flagged():
    with pytest.warns(dda.PlausibilityWarning, match="unit_weight = 9.81 N/m.3 is far from"):
        dda.Scene().set_water_table(1.0, unit_weight=9.81)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        dda.Scene().set_water_table(1.0, unit_weight=10050.0)  # sea water: no warning


def test_the_scene_file_and_a_checkpoint_keep_the_water(tmp_path):
    text = textwrap.dedent(f"""
        [scene]
        gravity = 9.81
        [materials.rock]
        young = 10e9
        poisson = 0.25
        density = 2600.0
        [joints.default]
        normal_penalty = 1e11
        shear_penalty = 1e11
        friction = {{ law = "coulomb", phi = {PHI} }}
        [[blocks]]
        name = "base"
        material = "rock"
        vertices = {[[float(c) for c in p] for p in BASE]}
        fixed = true
        [[blocks]]
        name = "wedge"
        material = "rock"
        vertices = {[[float(c) for c in p] for p in WEDGE]}
        rigid = true
        [water]
        table = [[-2.0, {Y_CRACK + 3.0}], [{float(X_CRACK)}, {Y_CRACK + 3.0}], [{TOE}, 0.0],
                 [30.0, -5.0]]
        [simulation]
        dt = 1e-3
        duration = 0.01
        [output]
        checkpoint = "run.ckpt"
        """)
    path = tmp_path / "wet.toml"
    path.write_text(text)
    loaded = dda.load_scene(path)
    assert "water table" in loaded.effects
    water = loaded.scene.water
    np.testing.assert_array_equal(water.y, [Y_CRACK + 3.0, Y_CRACK + 3.0, 0.0, -5.0])
    assert water.unit_weight == GAMMA
    api = slope(3.0)
    a = loaded.run(out=tmp_path / "out")
    b = dda.Simulation(api, dt=1e-3).run(0.01)
    np.testing.assert_array_equal(a.displacement(loaded.blocks["wedge"]),
                                  b.displacement(api.block("wedge")))
    resumed = dda.Simulation.resume(tmp_path / "out" / "run.ckpt")
    np.testing.assert_array_equal(resumed.scene.water.x, water.x)
    bad = path.read_text().replace("[water]\n", "[water]\nunit_weight = -1.0\n")
    path.write_text(bad)
    with pytest.raises(dda.io.scene_file.SceneFileError,
                       match=r"wet.toml, line \d+, water.unit_weight: must be positive"):
        dda.load_scene(path)


@pytest.mark.parametrize("zw", [0.0, 2.0, 3.0])
def test_the_factor_of_safety_of_the_wet_planar_slide_is_hoek_and_brays(zw):
    """Strength reduction (issue 23, item 3) of the planar slide with its crack filled to zw:
    F within 2% of Hoek and Bray's (1.4534, 1.2249, 1.0816; measured -0.16%, +0.68%,
    +0.29%)."""
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(2) as pool:
        fos = dda.studies.strength_reduction(slope(zw), executor=pool)
    assert fos.factor == pytest.approx(hoek_bray(zw)[0], rel=0.02)


# ---------------------------------------------------------------------- energy and stiffness
_SLOPED = WaterTable(np.array([0.0, 2.0]), np.array([0.9, 1.5]))
_QUAD = np.array([[0.2, 0.1], [1.7, 0.3], [1.2, 1.6], [0.1, 0.9]])  # the table crosses it
_NXT = np.array([1, 2, 3, 0])


def _potential(d):
    """water_energy of _QUAD moved by T d about its vertex mean."""
    from dda.water import water_energy

    t = geometry.t_matrix(_QUAD, np.repeat(_QUAD.mean(0)[None], 4, axis=0))
    return water_energy(_SLOPED, _QUAD + np.einsum("nij,j->ni", t, d), _NXT)


def test_the_water_energy_is_the_pressure_integrated_over_the_block():
    from dda.water import water_energy

    cube = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert water_energy(WaterTable.level(2.0), cube, _NXT) == pytest.approx(9810.0 * 1.5)
    # a fine midpoint sum of gamma max(h(x) - y, 0) over the quadrilateral
    n = 1200
    xs = (np.arange(n) + 0.5) * 2.0 / n
    gx, gy = np.meshgrid(xs, xs)
    from matplotlib.path import Path
    inside = Path(_QUAD).contains_points(np.column_stack([gx.ravel(), gy.ravel()]))
    p = 9810.0 * np.maximum(_SLOPED.head(gx.ravel()) - gy.ravel(), 0.0)
    assert water_energy(_SLOPED, _QUAD, _NXT) == pytest.approx(
        float(np.sum(p[inside])) * (2.0 / n) ** 2, rel=2e-4)


def test_the_water_forces_are_minus_the_gradient_of_its_energy():
    """The pressure is a fixed field: its work is the fall of water_energy (energy() counts
    it), by central differences on all six unknowns."""
    f = water_forces(_SLOPED, _QUAD, _NXT, np.zeros(4, int), _QUAD.mean(0)[None])[0]
    h = 1e-6
    grad = np.array([(_potential(h * e) - _potential(-h * e)) / (2 * h) for e in np.eye(6)])
    np.testing.assert_allclose(f, -grad, rtol=1e-7, atol=1e-6 * np.abs(f).max())


def test_the_water_stiffness_is_the_hessian_of_its_energy():
    from dda.water import water_stiffness

    k = water_stiffness(_SLOPED, _QUAD, _NXT, np.zeros(4, int), _QUAD.mean(0)[None])[0]
    h = 1e-4
    e = np.eye(6) * h
    hess = np.array([[(_potential(e[i] + e[j]) - _potential(e[i] - e[j])
                       - _potential(-e[i] + e[j]) + _potential(-e[i] - e[j])) / (4 * h * h)
                      for j in range(6)] for i in range(6)])
    np.testing.assert_allclose(k, hess, atol=1e-6 * np.abs(hess).max())
    # a floating unit cube, half under: its heave stiffness is gamma times its waterline
    cube = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    kc = water_stiffness(WaterTable.level(0.5), cube, _NXT, np.zeros(4, int),
                         np.array([[0.5, 0.5]]))[0]
    assert kc[1, 1] == pytest.approx(9810.0)


@pytest.mark.parametrize("solver", [LegacyPullBack(), NewtonRaphson()], ids=["legacy", "newton"])
def test_a_floating_block_bobs_without_gaining_energy(solver):
    """A 1 m cube of density 500 let go with 0.7 m under water bobs between 0 and 0.4 m up.
    With the pressure taken at each step's start alone it gained energy every period (its
    highest point 0.514 m after 10 s at dt 0.01 s; energy() did not count the water and its
    total rose by 2.0 kJ/m in 0.7 s); with the pressure's stiffness it stays at or below its
    start, and energy() counts the water's potential."""
    wood = LinearElastic(young=1e9, poisson=0.2, density=500.0)
    scene = dda.Scene(gravity=9.81)
    b = scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)], wood, name="float")
    scene.set_water_table(0.7)
    sim = dda.Simulation(scene, dt=0.01, solver=solver)
    e0 = sim.energy().total
    totals, highest = [], []
    for _ in range(20):
        highest.append(sim.run(0.5).displacement(b)[:, 1].max())
        totals.append(sim.energy().total - e0)
    assert max(totals) <= 1e-6 * e0
    assert max(highest) <= 0.4
    assert sim.energy().water > 0.0


def test_a_table_deeper_than_any_sea_is_flagged_and_none_removes_the_table():
    """A level of 1e6 m (a height in mm) ran without a word; set_water_table(None) raised
    "table must be a number" where a user meant to drain the scene."""
    scene = slope(1.0)
    scene.set_water_table(1e6)
    with pytest.warns(dda.PlausibilityWarning, match="deeper than any water on Earth"):
        dda.Simulation(scene, dt=1e-3)
    scene.set_water_table(200.0)  # a deep reservoir over the slope: no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error", dda.PlausibilityWarning)
        dda.Simulation(scene, dt=1e-3)
    scene.set_water_table(None)
    assert scene.water is None
    assert dda.Simulation(scene, dt=1e-3).model.water is None


def test_the_steps_water_loads_are_the_forces_and_the_stiffness():
    """A step takes both from one pass over the edges' pieces (dda.water.water_loads): the
    forces from each edge's end forces through J = [T(p); T(q)], as T is affine."""
    from dda.water import water_loads, water_stiffness

    table = WaterTable(np.array([0.0, 0.8, 1.4]), np.array([0.9, 1.5, 1.1]))  # kinked, ends
    x = np.vstack([_QUAD, [[2.0, 0.0], [3.0, 0.2], [2.5, 3.0]]])
    nxt, blocks = np.array([1, 2, 3, 0, 5, 6, 4]), np.array([0, 0, 0, 0, 1, 1, 1])
    centroid = np.array([x[:4].mean(0), x[4:].mean(0)])
    f, k = water_loads(table, x, nxt, blocks, centroid)
    np.testing.assert_allclose(f, water_forces(table, x, nxt, blocks, centroid),
                               rtol=0, atol=1e-12 * np.abs(f).max())
    np.testing.assert_array_equal(k, water_stiffness(table, x, nxt, blocks, centroid))
