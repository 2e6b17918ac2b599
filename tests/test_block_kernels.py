"""The compiled block parts of a step (dda.kernels.blocks) against the numpy path: the same
integrals, effective system, vertex moves and Newmark update, to the bit."""

from __future__ import annotations

import numpy as np
import pytest

import dda
from dda import geometry, step
from dda.kernels.blocks import step_end, step_start, step_start_at
from dda.kernels.geometry import edge_sums, edge_terms
from dda.solvers.newmark import effective_system, updated_velocity
from tests.stability import scenes as S


def _blocks(rng, nb):
    """``nb`` random convex polygons (3 to 9 vertices) far from the origin."""
    xs, offsets = [], [0]
    for _ in range(nb):
        n = int(rng.integers(3, 10))
        angles = np.sort(rng.uniform(0.0, 2 * np.pi, n))
        r = rng.uniform(0.2, 2.0)
        c = rng.uniform(-50.0, 50.0, 2)
        xs.append(c + r * np.stack([np.cos(angles), np.sin(angles)], axis=1))
        offsets.append(offsets[-1] + n)
    return np.concatenate(xs), np.array(offsets, dtype=np.int64)


@pytest.mark.parametrize("counts", [(3, 4, 7), (8, 9, 15, 16, 17), (100, 128, 129, 130),
                                    (250, 300, 5)])
def test_edge_sums_are_numpys_reduceat_to_the_bit(counts):
    """Blocks of 3 to 300 vertices (numpy's pairwise summation: under 8 terms one by one, up
    to 128 in eight running sums, halves above): the compiled sums have reduceat's bits, and
    the step's start from the vertices is the step's start from those sums."""
    rng = np.random.default_rng(sum(counts))
    xs, offsets = [], [0]
    for n in counts:
        angles = np.sort(rng.uniform(0.0, 2 * np.pi, n))
        xs.append(rng.uniform(-50, 50, 2) + rng.uniform(0.2, 2.0) * np.stack(
            [np.cos(angles), np.sin(angles)], axis=1))
        offsets.append(offsets[-1] + n)
    x, offsets = np.concatenate(xs), np.array(offsets, dtype=np.int64)
    nxt = geometry.next_vertex_index(offsets)
    s = np.add.reduceat(edge_terms(x, offsets, nxt), offsets[:-1], axis=0)
    np.testing.assert_array_equal(edge_sums(x, offsets, nxt), s)
    nb = len(counts)
    block = np.repeat(np.arange(nb), np.diff(offsets))
    args = (rng.uniform(1e3, 3e3, nb), rng.normal(0.0, 1e9, (nb, 3, 3)), 9.81,
            rng.normal(0.0, 1e6, (nb, 3)))
    rest = (x, block, rng.normal(0.0, 1.0, (nb, 6)), 0.9, 2e6, 2e3, True)
    for a, b in zip(step_start_at(x, offsets, nxt, *args, *rest[1:]),
                    step_start(s, x[offsets[:-1]], *args, *rest), strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("carry", [1.0, 0.5, 0.0])
def test_step_start_is_the_numpy_block_system(seed, carry):
    rng = np.random.default_rng(seed)
    nb = int(rng.integers(1, 12))
    x, offsets = _blocks(rng, nb)
    nxt = geometry.next_vertex_index(offsets)
    block = np.repeat(np.arange(nb), np.diff(offsets))
    density = rng.uniform(1e3, 3e3, nb)
    elasticity = rng.normal(0.0, 1e9, (nb, 3, 3))
    stress = rng.normal(0.0, 1e6, (nb, 3))
    velocity = rng.normal(0.0, 1.0, (nb, 6)) * 10.0 ** rng.uniform(-6, 0, (nb, 6))
    gravity, dt = 9.81 * (seed % 2), 10.0 ** rng.uniform(-5, -2)

    ints = geometry.polygon_integrals(x, offsets, nxt)
    k = geometry.stiffness_matrices(ints.area, elasticity)
    m = geometry.mass_matrices(ints, density)
    f = np.zeros((nb, 6))
    if gravity:
        f[:, 1] -= gravity * density * ints.area
    f[:, 3:] -= ints.area[:, None] * stress
    v = velocity * carry if carry else None
    k_eff, f_eff = effective_system(k, m, f, v, dt)
    t = geometry.t_matrix(x, ints.centroid[block])
    vv = np.einsum("vij,vj->vi", t, velocity[block] * carry)
    speed = np.hypot(vv[:, 0], vv[:, 1]).max()

    s = np.add.reduceat(edge_terms(x, offsets, nxt), offsets[:-1], axis=0)
    got = step_start(s, x[offsets[:-1]], density, elasticity, gravity, stress, x, block,
                     velocity, carry, 2.0 / dt**2, 2.0 / dt, bool(carry))
    for name, a, b in zip(("area", "centroid", "sxx", "syy", "sxy", "k_eff", "f_eff"),
                          (ints.area, ints.centroid, ints.sxx, ints.syy, ints.sxy, k_eff,
                           f_eff), got[:7], strict=True):
        np.testing.assert_array_equal(b, a, err_msg=name)
    assert got[8] == speed

    # the end of a step: moves, the checks' numbers and the Newmark update
    d = rng.normal(0.0, 1e-3, (nb, 6))
    free = rng.random(nb) < 0.7
    size = np.sqrt(ints.area)
    rotation = rng.normal(0.0, 1.0, nb)
    move = geometry.vertex_displacements(x, ints.centroid[block], d[block])
    distance = np.hypot(move[:, 0], move[:, 1])
    per_block = np.maximum.reduceat(distance, offsets[:-1])
    ratio = np.where(free, per_block / size, 0.0)
    vel = np.where(free[:, None], updated_velocity(d, v, dt), 0.0)
    grown = stress + np.where(free[:, None], np.einsum("bij,bj->bi", elasticity, d[:, 3:]),
                              0.0)
    (move_k, x_new, largest, worst, worst_move, vel_k, stress_k, rotation_k,
     centroid_k) = step_end(x, block, offsets, ints.centroid, d, free, size,
                            velocity if v is None else v, v is not None, 2.0 / dt,
                            elasticity, stress, rotation)
    np.testing.assert_array_equal(move_k, move)
    np.testing.assert_array_equal(x_new, x + move)
    assert largest == distance.max()
    assert worst == int(np.argmax(ratio)) and worst_move == per_block[worst]
    np.testing.assert_array_equal(vel_k, vel)
    np.testing.assert_array_equal(stress_k, grown)
    np.testing.assert_array_equal(rotation_k, rotation + d[:, 2])
    np.testing.assert_array_equal(centroid_k, ints.centroid + d[:, :2])


CASES = {
    "incline": lambda: (S.incline(dda.contact.CoulombSingle(phi=20.0))[0], {}, 1e-3, 0.2),
    "tower": lambda: (S.tower(6)[0], {}, 1e-3, 0.1),
    "tower, static": lambda: (S.tower(6)[0], {"analysis": "static"}, 1e-3, 0.03),
    "tower, carry 0.5": lambda: (S.tower(6)[0], {"velocity_carry": 0.5}, 1e-3, 0.05),
    "shaken cut slope": lambda: (S.shaken_cut_slope()[0], {}, 2e-3, 0.04),
}


@pytest.mark.parametrize("solver", ["legacy", "newton"])
@pytest.mark.parametrize("case", CASES)
def test_block_kernels_give_the_numpy_steps_bits(case, solver, monkeypatch):
    runs = []
    for compiled in (False, True):
        monkeypatch.setattr(step, "BLOCK_KERNELS", compiled)
        scene, kw, dt, duration = CASES[case]()
        assert dda.model.Model(scene).plain_blocks  # the kernels are taken
        sim = dda.Simulation(scene, dt=dt, solver=dda.registry.make_solver(solver), **kw)
        result = sim.run(duration, progress=False)
        runs.append((sim.state, result.stats))
    (a, sa), (b, sb) = runs
    for name in ("open_close_passes", "iterations", "closed", "time"):
        np.testing.assert_array_equal(sa[name], sb[name], err_msg=name)
    for name in ("x", "centroid", "velocity", "stress", "rotation"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_array_equal(a.contacts.t_n, b.contacts.t_n)


def test_a_scene_with_damping_loads_or_springs_keeps_the_numpy_path():
    scene = S.tower(3)[0]
    assert dda.model.Model(scene).plain_blocks
    scene.set_damping(mass=1.0)
    assert not dda.model.Model(scene).plain_blocks


@pytest.mark.parametrize("seed", range(4))
def test_dashpot_kernel_is_the_numpy_contact_mass_and_dashpot(seed):
    """Contacts between free blocks and with a block whose motion is known (infinite mass):
    :func:`dda.kernels.dashpot.dashpot_stiffnesses` gives
    :func:`dda.contact.dashpot.dashpot_stiffness` of :func:`contact_mass`, to the bit."""
    from dda.contact.dashpot import contact_mass, dashpot_stiffness
    from dda.kernels.dashpot import dashpot_stiffnesses

    rng = np.random.default_rng(seed)
    nb, m = 5, 30
    centroid = rng.uniform(-10.0, 10.0, (nb, 2))
    density, area = rng.uniform(1e3, 3e3, nb), rng.uniform(0.01, 4.0, nb)
    sxx, syy = rng.uniform(1e-4, 2.0, nb), rng.uniform(1e-4, 2.0, nb)
    free = np.array([False, True, True, True, False])
    bj, bk = rng.integers(1, 4, m), rng.integers(0, nb, m)
    point = centroid[bj] + rng.normal(0.0, 0.5, (m, 2))
    angle = rng.uniform(0.0, 2 * np.pi, m)
    normal = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    zeta, pn, dt = rng.uniform(0.0, 1.0, m), 10.0 ** rng.uniform(6, 11, m), 1e-3

    mass = np.where(free, density * area, np.inf)
    inertia = np.where(free, density * (sxx + syy), np.inf)
    expected = dashpot_stiffness(zeta, pn, contact_mass(
        point, normal, centroid[bj], centroid[bk], mass[bj], mass[bk], inertia[bj],
        inertia[bk]), dt)
    got = dashpot_stiffnesses(zeta, pn, point, normal, bj, bk, centroid, free, density, area,
                              sxx, syy, dt)
    np.testing.assert_array_equal(got, expected)
    assert np.all(np.isfinite(got)) and np.all(got >= 0.0)
