"""The step's linear solve: dense and sparse paths agree, known blocks go to the right side."""

from __future__ import annotations

import numpy as np
import pytest

from dda.solvers import sparse_factor
from dda.solvers.linear import SingularSystemError, assemble_and_solve


def chain(n_blocks, rng, unsymmetric=0.0):
    """n blocks in a row, each coupled to the next by a random (12, 12) contact matrix."""
    a = rng.normal(size=(n_blocks, 6, 6))
    block_k = np.einsum("bij,bkj->bik", a, a) + 50.0 * np.eye(6)
    block_f = rng.normal(size=(n_blocks, 6))
    bj = np.arange(n_blocks - 1)
    bk = bj + 1
    c = rng.normal(size=(n_blocks - 1, 12, 12))
    pair_k = np.einsum("mij,mkj->mik", c, c) + unsymmetric * rng.normal(size=c.shape)
    pair_f = rng.normal(size=(n_blocks - 1, 12))
    return block_k, block_f, bj, bk, pair_k, pair_f


def dense_reference(block_k, block_f, free, bj, bk, pair_k, pair_f, d_known):
    nb = len(free)
    k = np.zeros((6 * nb, 6 * nb))
    f = block_f.reshape(-1).copy()
    for b in range(nb):
        k[6 * b:6 * b + 6, 6 * b:6 * b + 6] += block_k[b]
    for m, (j, kk) in enumerate(zip(bj, bk, strict=True)):
        idx = np.r_[6 * j:6 * j + 6, 6 * kk:6 * kk + 6]
        k[np.ix_(idx, idx)] += pair_k[m]
        f[idx] += pair_f[m]
    dof = np.flatnonzero(np.repeat(free, 6))
    known = np.flatnonzero(~np.repeat(free, 6))
    d = d_known.reshape(-1).copy()
    d[dof] = np.linalg.solve(k[np.ix_(dof, dof)], f[dof] - k[np.ix_(dof, known)] @ d[known])
    return d.reshape(nb, 6)


@pytest.mark.parametrize("unsymmetric", [0.0, 0.3])
@pytest.mark.parametrize("n_blocks", [10, 120])  # dense (60 unknowns) and sparse (714)
def test_solution_matches_a_dense_reference(n_blocks, unsymmetric):
    rng = np.random.default_rng(n_blocks)
    block_k, block_f, bj, bk, pair_k, pair_f = chain(n_blocks, rng, unsymmetric)
    free = np.ones(n_blocks, dtype=bool)
    free[[0, n_blocks // 2]] = False  # known blocks: their coupling goes to the right side
    d_known = np.where(free[:, None], 0.0, rng.normal(size=(n_blocks, 6)))
    d = assemble_and_solve(block_k, block_f, free, bj, bk, pair_k, pair_f, d_known)
    ref = dense_reference(block_k, block_f, free, bj, bk, pair_k, pair_f, d_known)
    np.testing.assert_allclose(d, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())


def test_sparse_solve_falls_back_when_the_diagonal_cannot_pivot():
    """A zero diagonal needs off-diagonal pivots; the result is still exact (SuperLU)."""
    import scipy.sparse as sp

    n = 400
    rng = np.random.default_rng(1)
    k = sp.random(n, n, density=0.02, random_state=2, format="csc") + sp.eye(n, format="csc")
    k = k.tolil()
    k[0, 0] = 0.0
    k[0, 1] = 1.0
    k[1, 0] = 1.0
    k = k.tocsc()
    rhs = rng.normal(size=n)
    x = sparse_factor.superlu_solve(k, rhs)
    np.testing.assert_allclose(k @ x, rhs, atol=1e-9)


def test_singular_system_is_reported():
    block_k = np.zeros((1, 6, 6))
    with pytest.raises(SingularSystemError):
        assemble_and_solve(block_k, np.ones((1, 6)), np.array([True]), np.zeros(0, int),
                           np.zeros(0, int), np.zeros((0, 12, 12)), np.zeros((0, 12)),
                           np.zeros((1, 6)))


@pytest.mark.parametrize("reads_upper", [False, True])
def test_a_kept_sparse_structure_serves_fewer_contacts(reads_upper):
    """With a FactorSet the sparse structure of a step stands for the next one whose contacts
    couple a subset of its block pairs (no new analysis), holding the pairs no longer in
    contact as zeros: the same solution as a structure of its own. A new pair, or a
    structure more than STRUCTURE_SLACK times too large, is built anew."""
    from dda.kernels import PairStiffness
    from dda.solvers.linear import STRUCTURE_SLACK, SystemPattern

    rng = np.random.default_rng(7)
    n_blocks = 80  # 474 unknowns: sparse
    block_k, block_f, bj, bk, _, pair_f = chain(n_blocks, rng)
    rows = rng.normal(size=(len(bj), 2, 12))
    pair_k = PairStiffness(rows, [[0, 0], [1, 1]], rng.uniform(1.0, 2.0, (len(bj), 2)))
    free = np.ones(n_blocks, dtype=bool)
    free[0] = False
    d_known = np.where(free[:, None], 0.0, rng.normal(size=(n_blocks, 6)))
    cache = sparse_factor.FactorSet()
    factor = cache.get(True) if reads_upper else None
    first = SystemPattern(free, bj, bk, cache=cache)
    assemble_and_solve(block_k, block_f, free, bj, bk, pair_k, pair_f, d_known, first,
                       factor=factor)
    keep = np.arange(len(bj)) % 5 != 0  # a fifth of the contacts are gone
    sub = PairStiffness(rows[keep], [[0, 0], [1, 1]], pair_k.weights[keep])
    later = SystemPattern(free, bj[keep], bk[keep], cache=cache)
    assert later.indices is first.indices and later.nnz == first.nnz
    d = assemble_and_solve(block_k, block_f, free, bj[keep], bk[keep], sub, pair_f[keep],
                           d_known, later, factor=factor)
    own = SystemPattern(free, bj[keep], bk[keep])
    assert own.nnz < later.nnz
    ref = assemble_and_solve(block_k, block_f, free, bj[keep], bk[keep], sub, pair_f[keep],
                             d_known, own)
    np.testing.assert_allclose(d, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())
    new_pair = SystemPattern(free, np.r_[bj, 3], np.r_[bk, 40], cache=cache)
    assert new_pair.indices is not first.indices
    few = int(len(bj) / (2 * STRUCTURE_SLACK))
    assert SystemPattern(free, bj[:few], bk[:few], cache=cache).nnz < new_pair.nnz


def test_a_kept_structure_is_searched_column_by_column_with_the_same_layout(monkeypatch):
    """A step whose entries the kept structure holds finds them column by column
    (dda.kernels.pattern.entry_positions) instead of sorting and searching every key: the
    same structure, the same places for every block entry and contact coupling, upper
    triangle included, as the sorted search, over steps whose contacts shrink, grow past the
    structure, come back and fall below its slack."""
    from dda.solvers.linear import SystemPattern

    rng = np.random.default_rng(11)
    n_blocks = 90
    free = np.ones(n_blocks, dtype=bool)
    free[[0, 7]] = False
    bj = rng.integers(0, n_blocks, 400)
    bk = (bj + rng.integers(1, 6, 400)) % n_blocks
    steps = [np.arange(400), np.arange(400) % 3 != 0, np.arange(400) % 2 == 0,
             np.arange(400), np.arange(400) < 60, np.arange(400) < 300]
    extra = (np.array([3, 50]), np.array([80, 9]))  # a pair the first structure lacks
    layouts = []
    found = []
    search = SystemPattern._in_kept_structure
    monkeypatch.setattr(SystemPattern, "_in_kept_structure", staticmethod(
        lambda *a: found.append(search(*a)) or found[-1]))
    for fast in (True, False):
        cache = sparse_factor.FactorSet()
        if not fast:
            monkeypatch.setattr(cache, "kept_superset", lambda name, n: None)
        runs = []
        for i, keep in enumerate(steps):
            j, k = bj[keep], bk[keep]
            if i == 3:
                j, k = np.r_[j, extra[0]], np.r_[k, extra[1]]
            p = SystemPattern(free, j, k, cache=cache)
            runs.append((p.nnz, p.indices, p.indptr, p.block_base, p.block_step, p.pair_base,
                         p.pair_step, *p._upper_layout[:3], *p._upper_layout[3],
                         *p._upper_layout[4]))
        layouts.append(runs)
    kept_hits = 0
    for i, (a, b) in enumerate(zip(*layouts, strict=True)):
        assert a[0] == b[0]
        for x, y in zip(a[1:], b[1:], strict=True):
            np.testing.assert_array_equal(x, y)
        kept_hits += i > 0 and layouts[0][i][1] is layouts[0][i - 1][1]
    assert kept_hits >= 2  # steps 1 and 2 kept the first structure
    # the column-by-column search answered where the structure was kept (the fast run's
    # steps 1 and 2; not after a new pair, nor with too few contacts, nor in the slow run)
    assert [f is not None for f in found[:len(steps)]] == [False, True, True, False, False,
                                                           False]
    assert all(f is None for f in found[len(steps):])
