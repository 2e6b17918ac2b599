"""The contact side of a step compiled, against the versions composed of numpy and smaller
kernels: the penetration guard as one pass (``penetration._guard_kernel``, ``GUARD_KERNEL``),
the narrow phase as one pass (``detection._narrow_phase_kernel``, ``NARROW_KERNEL``) and a
Newton iterate's out-of-balance vectors (``newton_residuals``, ``RESIDUAL_KERNEL``). The
same reports and candidates, to the bit, on random overlapping blocks with random contacts
(released dashpot contacts included), on stacks whose corners meet, and on whole runs."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import dda
from dda.contact import detection, penetration
from dda.contact.contacts import ContactSet
from dda.contact.detection import VertexTopology, bounding_boxes, broad_phase, narrow_phase
from dda.contact.penetration import GuardReport, penetration_guard
from dda.registry import make_solver
from tests.stability import scenes as S


def _polygon(rng, cx, cy):
    """A star-shaped polygon (often non-convex), or a square with a vertex on a side."""
    if rng.random() < 0.25:
        s = rng.uniform(0.3, 1.0)
        return np.array([(cx, cy), (cx + s / 2, cy), (cx + s, cy), (cx + s, cy + s),
                         (cx, cy + s)])
    n = int(rng.integers(3, 9))
    ang = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.arange(n) / n
    r = rng.uniform(0.3, 1.0, n)
    return np.stack([cx + r * np.cos(ang), cy + r * np.sin(ang)], axis=1)


def _model(polys):
    x = np.concatenate(polys)
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in polys])]).astype(np.int64)
    topo = VertexTopology.from_offsets(offsets)
    ints = dda.geometry.polygon_integrals(x, offsets, topo.nxt)
    perimeter = np.add.reduceat(np.hypot(*(x[topo.nxt] - x).T), offsets[:-1])
    thickness = 2.0 * ints.area / perimeter
    return x, SimpleNamespace(n_blocks=len(polys), topo=topo, offsets=offsets,
                              thickness=thickness, min_thickness=float(np.min(thickness)),
                              block_label=lambda j: f"block {j}")


def _contacts(rng, x, topo, pairs, depth_scale):
    """Random vertex-edge contacts between the blocks of ``pairs``, either way round."""
    rows = []
    for a, b in pairs:
        for _ in range(int(rng.integers(0, 6))):
            j, k = (a, b) if rng.random() < 0.5 else (b, a)
            v = int(rng.integers(topo.offsets[j], topo.offsets[j + 1]))
            e = int(rng.integers(topo.offsets[k], topo.offsets[k + 1]))
            rows.append((v, e, j, k))
    m = len(rows)
    r = np.array(rows, dtype=np.int64).reshape(m, 4)
    state = rng.integers(0, 3, m).astype(np.int8)
    p_n = 10.0 ** rng.uniform(6, 10, m)
    t_n = np.where(state != 0, -p_n * rng.uniform(0, depth_scale, m), 0.0)
    if m:
        t_n[rng.random(m) < 0.1] = -0.0
    z = np.zeros(m)
    c = ContactSet(r[:, 0].copy(), r[:, 1].copy(), r[:, 2].copy(), r[:, 3].copy(), state, z,
                   t_n, z.copy(), {})
    dashpot = np.where(rng.random(m) < 0.5, 10.0 ** rng.uniform(5, 9, m), 0.0)
    return c, p_n, dashpot


def _same(a: GuardReport, b: GuardReport):
    assert a.reason == b.reason
    for name in ("deepest", "spring_deepest", "untracked"):
        x, y = getattr(a, name), getattr(b, name)
        assert np.array_equal(np.float64(x), np.float64(y)), (name, x, y)


def _both(model, x, contacts, p_n, pairs, tol, dashpot):
    penetration.GUARD_KERNEL = True
    try:
        got = penetration_guard(model, x, contacts, p_n, pairs, tol, dashpot=dashpot)
        penetration.GUARD_KERNEL = False
        want = penetration_guard(model, x, contacts, p_n, pairs, tol, dashpot=dashpot)
    finally:
        penetration.GUARD_KERNEL = True
    return got, want


def _guard_case(seed):
    """A random guard case: blocks, model, pairs, contacts, penalties, dashpots, tolerance."""
    rng = np.random.default_rng(seed)
    x, model = _random_blocks(rng)
    pairs = broad_phase(bounding_boxes(x, model.offsets), 0.0)
    contacts, p_n, dashpot = _contacts(rng, x, model.topo, pairs, rng.uniform(0.0, 0.5))
    return x, model, pairs, contacts, p_n, dashpot, float(10.0 ** rng.uniform(-3, 0))


def _random_blocks(rng):
    """2 to 8 random polygons scattered over a square of 1 to 4 m (overlapping often)."""
    nb = int(rng.integers(2, 9))
    spread = rng.uniform(1.0, 4.0)
    return _model([_polygon(rng, *rng.uniform(0, spread, 2)) for _ in range(nb)])


@pytest.mark.parametrize("seed", range(40))
def test_guard_kernel_is_the_composed_guard(seed):
    x, model, pairs, contacts, p_n, dashpot, tol = _guard_case(seed)
    for dp in (None, dashpot):
        got, want = _both(model, x, contacts, p_n, pairs, tol, dp)
        _same(got, want)


def test_the_random_cases_reach_every_branch():
    """Refused and passed steps, edges and corners as the worst, released dashpot contacts
    that change the verdict: the random set above is not all one case."""
    seen = set()
    for seed in range(40):
        x, model, pairs, contacts, p_n, dashpot, tol = _guard_case(seed)
        plain = penetration_guard(model, x, contacts, p_n, pairs, tol)
        damped = penetration_guard(model, x, contacts, p_n, pairs, tol, dashpot=dashpot)
        seen.add("refused" if plain.reason else "passed")
        if plain.reason:
            seen.add("edge" if "the edge from" in plain.reason else "corner")
        if damped.untracked != plain.untracked:
            seen.add("released")
    assert seen == {"refused", "passed", "edge", "corner", "released"}


@pytest.mark.parametrize("solver", ["legacy", "newton"])
def test_runs_give_the_same_bits_with_either_guard(solver):
    """An impact with a dashpot that lets contacts go while their vertices are inside: the
    guard's kernel and its composed version take the same steps to the same numbers."""
    from dataclasses import replace

    def run():
        scene = S.stopper_impact()[0]
        j = scene.default_joint
        scene.set_joint(replace(j, normal_penalty=j.normal_penalty / 1e4,
                                shear_penalty=j.shear_penalty / 1e4, restitution=0.0))
        sim = dda.Simulation(scene, dt=1e-3, solver=make_solver(solver))
        r = sim.run(0.12, progress=False)
        return sim.committed, r.stats

    try:
        penetration.GUARD_KERNEL = False
        c0, s0 = run()
    finally:
        penetration.GUARD_KERNEL = True
    c1, s1 = run()
    assert np.array_equal(c0.x, c1.x) and np.array_equal(c0.velocity, c1.velocity)
    for col in ("penetration", "spring_penetration"):
        assert np.array_equal(np.asarray(s0[col]), np.asarray(s1[col]))
    assert np.max(np.asarray(s1["penetration"])) > 0.0


def _narrow_both(x, topo, d0, limit, pairs, sunk):
    detection.NARROW_KERNEL = False
    try:
        want = narrow_phase(x, topo, d0, limit, pairs, sunk)
    finally:
        detection.NARROW_KERNEL = True
    return narrow_phase(x, topo, d0, limit, pairs, sunk), want


def _same_candidates(got, want):
    assert got.pairs == want.pairs
    for name in ("vertex", "edge", "bj", "bk"):
        a, b = getattr(got, name), getattr(want, name)
        assert a.dtype == b.dtype and np.array_equal(a, b), name
    assert (got.geometry is None) == (want.geometry is None)
    if got.geometry is not None:
        for name in ("p1", "p2", "p3", "length", "tau", "normal", "gap", "xi"):
            assert np.array_equal(getattr(got.geometry, name), getattr(want.geometry, name)), name


@pytest.mark.parametrize("seed", range(40))
def test_narrow_phase_kernel_is_the_composed_narrow_phase(seed):
    rng = np.random.default_rng(seed)
    x, model = _random_blocks(rng)
    nb = model.n_blocks
    d0 = float(10.0 ** rng.uniform(-4, -0.5))
    limit = float(10.0 ** rng.uniform(-3, 0))
    pairs = broad_phase(bounding_boxes(x, model.offsets), max(d0, limit))
    sunk = rng.choice([np.inf, 0.0, float(rng.uniform(0, 0.2))])
    sunk = rng.uniform(0.0, 0.2, nb) if rng.random() < 0.3 else sunk
    for p in (pairs, None):
        _same_candidates(*_narrow_both(x, model.topo, d0, limit, p, sunk))


@pytest.mark.parametrize("sink", [0.0, 1e-4, 3e-3])
def test_narrow_phase_kernel_on_corners_that_meet(sink):
    """A 3 x 3 stack of unit squares, every other row sunk ``sink`` into the one below: the
    vertex-vertex cases whose mirrored pairs the narrow phase drops."""
    rng = np.random.default_rng(7)
    polys = []
    for row in range(3):
        for col in range(3):
            x0, y0 = col + rng.normal(0, 1e-9), row - sink * (row % 2)
            polys.append(np.array([(x0, y0), (x0 + 1, y0), (x0 + 1, y0 + 1), (x0, y0 + 1)]))
    x, model = _model(polys)
    pairs = broad_phase(bounding_boxes(x, model.offsets), 1e-2)
    got, want = _narrow_both(x, model.topo, 1e-3, 1e-2, pairs, 1e-3)
    _same_candidates(got, want)
    assert len(got) > 0


@pytest.mark.parametrize("seed", range(12))
def test_newton_residuals_kernel_is_the_numpy_one(seed):
    """An iterate's out-of-balance vectors (``dda.solvers.newton._residuals``) from the kernel
    and from numpy, on random blocks (some fixed, some rigid) and contacts."""
    from dda.solvers import newton

    rng = np.random.default_rng(seed)
    nb, m = int(rng.integers(1, 30)), int(rng.integers(0, 60))
    free = rng.random(nb) < 0.8
    rigid = (rng.random(nb) < 0.3) if seed % 2 else None
    scale = 10.0 ** rng.uniform(-6, 9, (nb, 6, 6))
    problem = SimpleNamespace(
        block_k=rng.standard_normal((nb, 6, 6)) * scale, block_f=rng.standard_normal((nb, 6)),
        free=free, rigid=rigid,
        element=SimpleNamespace(bj=rng.integers(0, nb, m), bk=rng.integers(0, nb, m)))
    d = rng.standard_normal((nb, 6)) * 10.0 ** rng.uniform(-9, -2, (nb, 6))
    pair_r = rng.standard_normal((m, 12)) * 10.0 ** rng.uniform(0, 8, (m, 12))
    try:
        newton.RESIDUAL_KERNEL = False
        want = newton._residuals(problem, d, pair_r)
    finally:
        newton.RESIDUAL_KERNEL = True
    got = newton._residuals(problem, d, pair_r)
    for a, b in zip(got, want, strict=True):
        assert a.shape == b.shape and np.array_equal(a, b)


@pytest.mark.parametrize("seed", range(10))
def test_joint_lookups_are_the_numpy_ones(seed):
    """The compiled joint rows and deepest spring (dda.kernels.joints) against the joint
    table's searchsorted and numpy's reduction of the spring depths."""
    from dda.contact.contacts import pair_key
    from dda.kernels.joints import deepest_spring, joint_rows
    from dda.model import JointTable

    rng = np.random.default_rng(seed)
    nb, m, n_joints = int(rng.integers(2, 40)), int(rng.integers(0, 80)), 4
    pairs = {tuple(sorted(rng.choice(nb, 2, replace=False))) for _ in range(rng.integers(0, 30))}
    keys = np.sort(np.array([pair_key(a, b, nb) for a, b in pairs], dtype=np.int64))
    table = JointTable(int(rng.integers(-1, n_joints)), keys,
                       rng.integers(0, n_joints, len(keys)).astype(np.int64),
                       10.0 ** rng.uniform(6, 11, n_joints), np.ones(n_joints),
                       np.zeros(n_joints, dtype=np.int64), (), {})
    bj, bk = rng.integers(0, nb, m), rng.integers(0, nb, m)
    rows = joint_rows(bj, bk, nb, table.pair_keys, table.pair_joint, table.default)
    assert np.array_equal(rows, table.index(pair_key(bj, bk, nb)))
    state = rng.integers(0, 3, m).astype(np.int8)
    t_n = np.where(state != 0, -rng.uniform(0, 1e7, m), 0.0)
    t_n[rng.random(m) < 0.2] *= -1.0  # some closed contacts in tension
    closed = state != 0
    want = np.maximum.reduce(-t_n[closed] / table.normal_penalty[rows[closed]], initial=0.0)
    got = deepest_spring(state, t_n, bj, bk, nb, table.pair_keys, table.pair_joint,
                         table.default, table.normal_penalty)
    assert np.array_equal(np.float64(got), np.float64(want))
