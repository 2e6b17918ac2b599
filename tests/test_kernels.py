"""The compiled assembly (dda.kernels) against the numpy one, and the contacts' rank-one terms
against the (m, 12, 12) formulas they replace."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from dda.contact.kinematics import trial_kinematics
from dda.contact.tangent import consistent_tangent, spring_stiffness
from dda.kernels import PairStiffness
from dda.kernels.assembly import contact_matrix, upper_update
from dda.solvers.linear import DENSE_LIMIT, SystemPattern, assemble_and_solve


def random_system(n_blocks, n_contacts, rng, rigid=False):
    """Random blocks (a few known, some rigid) and contacts between them, with random
    rank-one terms."""
    free = np.ones(n_blocks, dtype=bool)
    free[rng.choice(n_blocks, max(2, n_blocks // 8), replace=False)] = False
    bj = rng.integers(0, n_blocks, n_contacts)
    bk = (bj + rng.integers(1, n_blocks, n_contacts)) % n_blocks
    a = rng.normal(size=(n_blocks, 6, 6))
    block_k = np.einsum("bij,bkj->bik", a, a) + 30.0 * np.eye(6)
    pair_k = PairStiffness(rng.normal(size=(n_contacts, 4, 12)),
                           [[0, 0], [1, 2], [3, 1], [2, 3], [1, 1]],
                           rng.normal(size=(n_contacts, 5)))
    rigid_blocks = (rng.random(n_blocks) < 0.3) if rigid else None
    return dict(block_k=block_k, block_f=rng.normal(size=(n_blocks, 6)), free=free, bj=bj,
                bk=bk, pair_k=pair_k, pair_f=rng.normal(size=(n_contacts, 12)),
                d_known=np.where(free[:, None], 0.0, rng.normal(size=(n_blocks, 6))),
                rigid=rigid_blocks)


def as_array(k):
    return k if isinstance(k, np.ndarray) else k.toarray()


def reference_system(s):
    """Matrix and right-hand side of the unknowns, summed entry by entry into one dense
    matrix of every block (no pattern): known blocks' columns times their increments go to
    the right side, rigid blocks' strain rows and columns are left out."""
    nb = len(s["free"])
    k = np.zeros((6 * nb, 6 * nb))
    f = s["block_f"].reshape(-1).copy()
    for b in range(nb):
        k[6 * b:6 * b + 6, 6 * b:6 * b + 6] += s["block_k"][b]
    for c, (j, kk) in enumerate(zip(s["bj"], s["bk"], strict=True)):
        idx = np.r_[6 * j:6 * j + 6, 6 * kk:6 * kk + 6]
        k[np.ix_(idx, idx)] += s["pair_k"].dense()[c]
        f[idx] += s["pair_f"][c]
    unknown = np.repeat(s["free"], 6)
    known = ~unknown
    if s["rigid"] is not None:
        unknown &= ~(np.repeat(s["rigid"], 6) & np.tile(np.arange(6) >= 3, nb))
    f = f - k[:, known] @ s["d_known"].reshape(-1)[known]
    return k[np.ix_(unknown, unknown)], f[np.repeat(s["free"], 6)]


def assert_close(compiled, reference, rtol=1e-12):
    compiled, reference = as_array(compiled), as_array(reference)
    assert compiled.shape == reference.shape
    np.testing.assert_allclose(compiled, reference, rtol=0,
                               atol=rtol * np.abs(reference).max())


SIZES = [(12, 40), (90, 400)]  # 60 unknowns at most (dense) and about 470 (sparse)


@pytest.mark.parametrize("rigid", [False, True], ids=["strain", "rigid"])
@pytest.mark.parametrize("n_blocks, n_contacts", SIZES, ids=["dense", "sparse"])
def test_compiled_matrix_and_rhs_equal_the_numpy_assembly(n_blocks, n_contacts, rigid):
    s = random_system(n_blocks, n_contacts, np.random.default_rng(n_blocks), rigid)
    pattern = SystemPattern(s["free"], s["bj"], s["bk"], s["rigid"])
    assert (pattern.n <= DENSE_LIMIT) == (n_blocks == 12)
    assert (pattern.keep is not None) == rigid
    # every coupling occurs between free blocks and with a known block on either side
    assert np.all((pattern.pair_base >= 0).any(axis=1))
    assert np.any((pattern.side_row[0] >= 0) & (pattern.side_row[1] < 0))
    assert np.any((pattern.side_row[0] < 0) & (pattern.side_row[1] >= 0))
    dense_k = s["pair_k"].dense()
    matrix = pattern.matrix(s["block_k"], s["pair_k"])
    rhs = pattern.rhs(s["block_f"], s["pair_k"], s["pair_f"], s["d_known"])
    assert_close(matrix, pattern.matrix(s["block_k"], dense_k))
    assert_close(rhs, pattern.rhs(s["block_f"], dense_k, s["pair_f"], s["d_known"]))
    k_ref, rhs_ref = reference_system(s)
    assert_close(matrix, k_ref)
    assert_close(rhs, rhs_ref)


@pytest.mark.parametrize("n_blocks, n_contacts", SIZES, ids=["dense", "sparse"])
def test_the_comparison_sees_a_misplaced_entry(n_blocks, n_contacts):
    """Negative control: two contacts' couplings swapped, or one known block swapped, and the
    compiled assembly no longer equals the numpy one (the kernels do not check bounds: the
    swapped places stay inside the matrix)."""
    s = random_system(n_blocks, n_contacts, np.random.default_rng(n_blocks))
    pattern = SystemPattern(s["free"], s["bj"], s["bk"])
    dense_k = s["pair_k"].dense()
    reference = pattern.matrix(s["block_k"], dense_k)
    c = np.flatnonzero(pattern.pair_base[1] >= 0)
    c = [c[0], c[np.flatnonzero(pattern.pair_base[1, c] != pattern.pair_base[1, c[0]])[0]]]
    pattern.pair_base[1, c] = pattern.pair_base[1, c[::-1]]
    pattern.pair_step[1, c] = pattern.pair_step[1, c[::-1]]
    with pytest.raises(AssertionError):
        assert_close(pattern.matrix(s["block_k"], s["pair_k"]), reference)
    reference = pattern.rhs(s["block_f"], dense_k, s["pair_f"], s["d_known"])
    c = int(np.flatnonzero((pattern.side_row[0] >= 0) & (pattern.side_row[1] < 0))[0])
    pattern.side_block[1, c] = np.flatnonzero(~s["free"] & (np.arange(n_blocks)
                                                            != pattern.side_block[1, c]))[0]
    with pytest.raises(AssertionError):
        assert_close(pattern.rhs(s["block_f"], s["pair_k"], s["pair_f"], s["d_known"]),
                     reference)


@pytest.mark.parametrize("rigid", [False, True], ids=["strain", "rigid"])
@pytest.mark.parametrize("n_blocks, n_contacts", SIZES, ids=["dense", "sparse"])
def test_the_solve_takes_either_form(n_blocks, n_contacts, rigid):
    s = random_system(n_blocks, n_contacts, np.random.default_rng(7 * n_blocks), rigid)
    args = [s[k] for k in ("block_k", "block_f", "free", "bj", "bk")]
    rest = dict(rigid=s["rigid"])
    d_compiled = assemble_and_solve(*args, s["pair_k"], s["pair_f"], s["d_known"], **rest)
    d_numpy = assemble_and_solve(*args, s["pair_k"].dense(), s["pair_f"], s["d_known"], **rest)
    np.testing.assert_allclose(d_compiled, d_numpy, rtol=1e-9,
                               atol=1e-12 * np.abs(d_numpy).max())


def test_without_contacts_or_unknowns():
    rng = np.random.default_rng(3)
    block_k = np.tile(np.eye(6), (3, 1, 1))
    empty = PairStiffness(np.zeros((0, 2, 12)), [[0, 0], [1, 1]], np.zeros((0, 2)))
    pattern = SystemPattern(np.array([True, False, True]), np.zeros(0, int), np.zeros(0, int))
    np.testing.assert_array_equal(pattern.matrix(block_k, empty), np.eye(12))
    f = rng.normal(size=(3, 6))
    np.testing.assert_array_equal(pattern.rhs(f, empty, np.zeros((0, 12)), np.zeros((3, 6))),
                                  f[[0, 2]].reshape(-1))


def test_pair_stiffness_is_its_array():
    rng = np.random.default_rng(4)
    rows, w = rng.normal(size=(5, 2, 12)), rng.normal(size=(5, 3))
    k = PairStiffness(rows, [[0, 1], [1, 0], [1, 1]], w)
    expected = (w[:, 0, None, None] * rows[:, 0, :, None] * rows[:, 1, None, :]
                + w[:, 1, None, None] * rows[:, 1, :, None] * rows[:, 0, None, :]
                + w[:, 2, None, None] * rows[:, 1, :, None] * rows[:, 1, None, :])
    np.testing.assert_allclose(np.asarray(k), expected, rtol=1e-14, atol=1e-14)
    assert k.shape == (5, 12, 12) and len(k) == 5
    with pytest.raises(ValueError, match="do not fit"):
        PairStiffness(rows, [[0, 1]], w)
    with pytest.raises(ValueError, match="outside"):
        PairStiffness(rows, [[0, 2], [1, 0], [1, 1]], w)


def test_contact_matrix_is_the_pair_stiffness_and_symmetric_springs_stay_symmetric():
    """The assembly's per-contact 12 x 12 matrix equals :meth:`PairStiffness.dense` to
    round-off (terms of weight 0 skipped); one of terms that pair each row with itself is
    symmetric to the bit."""
    rng = np.random.default_rng(11)
    k = random_system(12, 40, rng)["pair_k"]
    k.weights[::3, 0] = 0.0
    out = np.empty((12, 12))
    dense = k.dense()
    for c in range(len(k)):
        contact_matrix(out, k.rows, k.terms, k.weights, c)
        np.testing.assert_allclose(out, dense[c], rtol=0,
                                   atol=1e-14 * np.abs(dense[c]).max())
    springs = PairStiffness(rng.normal(size=(40, 2, 12)), [[0, 0], [1, 1]],
                            np.abs(rng.normal(size=(40, 2))) * 1e9)
    for c in range(40):
        contact_matrix(out, springs.rows, springs.terms, springs.weights, c)
        assert np.array_equal(out, out.T)
        np.testing.assert_allclose(out, springs.dense()[c], rtol=0,
                                   atol=1e-14 * np.abs(out).max())


def test_springs_are_the_legacy_outer_products():
    rng = np.random.default_rng(5)
    e, i = rng.normal(size=(2, 30, 12))
    kn, ks = rng.random(30) * 1e9, np.where(rng.random(30) < 0.5, 1e9, 0.0)
    expected = kn[:, None, None] * (e[:, :, None] * e[:, None, :])
    expected += ks[:, None, None] * (i[:, :, None] * i[:, None, :])
    np.testing.assert_array_equal(spring_stiffness(e, i, kn, ks).dense(), expected)


def test_consistent_tangent_equals_the_hessian_form():
    """The four rank-one terms equal k_n E^T E + I^T S + t_n Delta delta g_n
    + t_s Delta delta g_s with the second variations of trial_kinematics."""
    rng = np.random.default_rng(6)
    m = 40
    p1, p2, p3 = rng.normal(size=(3, m, 2))
    maps = tuple(rng.normal(size=(m, 2, 12)) for _ in range(3))
    xi0 = rng.random(m)
    kin = trial_kinematics(p1, p2, p3, xi0, maps, second=True)
    closed = rng.random(m) < 0.7
    kn = np.where(closed, 1e3, 0.0)
    kss, ksn = np.where(closed, rng.normal(size=(2, m)), 0.0)
    t_n = np.where(closed, -rng.random(m), 0.0)
    t_s = np.where(closed, rng.normal(size=m), 0.0)
    e, i = kin.e_row, kin.i_row
    expected = kn[:, None, None] * (e[:, :, None] * e[:, None, :])
    shear_row = kss[:, None] * i + ksn[:, None] * e
    expected += np.where(closed[:, None, None], i[:, :, None] * shear_row[:, None, :], 0.0)
    expected += t_n[:, None, None] * kin.gn_hessian + t_s[:, None, None] * kin.gs_hessian
    got = consistent_tangent(kin, maps, xi0, kn, kss, ksn, t_n, t_s, closed).dense()
    scale = np.abs(expected).max(axis=(1, 2), keepdims=True)
    assert np.all(np.abs(got - expected) <= 1e-12 * scale)
    assert np.all(got[~closed] == 0.0)


def symmetric_system(rng, n_blocks=90, n_contacts=400):
    """:func:`random_system` with rank-one terms that pair each row with itself (a symmetric
    matrix, as legacy DDA's springs give) and no rigid blocks."""
    s = random_system(n_blocks, n_contacts, rng)
    rows = rng.normal(size=(n_contacts, 3, 12))
    s["pair_k"] = PairStiffness(rows, [[0, 0], [1, 1], [2, 2]],
                                np.abs(rng.normal(size=(n_contacts, 3))))
    return s


def upper_of(k):
    """The upper triangle of sparse ``k`` as CSR with sorted indices (no arithmetic)."""
    u = sp.triu(k.tocsr(), format="csr")
    u.sort_indices()
    return u


def test_upper_triangle_is_assembled_in_place_with_the_full_matrixs_bits():
    """The symmetric system's upper triangle, summed straight into PARDISO's CSR layout, has
    the full matrix's structure there and every entry's bits (the same sums in the same
    order), so the solver gets what it got from the full matrix, with half the sums."""
    s = symmetric_system(np.random.default_rng(5))
    pattern = SystemPattern(s["free"], s["bj"], s["bk"])
    full = pattern.matrix(s["block_k"], s["pair_k"])
    assert abs(full - full.T).max() == 0.0
    upper = pattern.upper_matrix(s["block_k"], s["pair_k"])
    ref = upper_of(full)
    np.testing.assert_array_equal(upper.csr.indptr, ref.indptr)
    np.testing.assert_array_equal(upper.csr.indices, ref.indices)
    np.testing.assert_array_equal(upper.csr.data, ref.data)
    x = np.random.default_rng(1).normal(size=pattern.n)
    np.testing.assert_allclose(upper @ x, full @ x, rtol=0, atol=1e-12 * np.abs(full @ x).max())
    assert abs(upper.full() - full).max() == 0.0
    # negative control: two contacts' places swapped
    c = np.flatnonzero((pattern._upper_layout[4][0, 1] >= 0)
                       & (pattern._upper_layout[4][2, 1] >= 0))
    c = [c[0], c[np.flatnonzero(pattern._upper_layout[4][2, 1, c]
                                != pattern._upper_layout[4][2, 1, c[0]])[0]]]
    pattern._upper_layout[4][:, 1, c] = pattern._upper_layout[4][:, 1, c[::-1]]
    pattern.__dict__.pop("_last_upper")  # (the same springs would reuse the last sums)
    assert not np.array_equal(pattern.upper_matrix(s["block_k"], s["pair_k"]).csr.data,
                              ref.data)


def test_upper_triangle_only_where_it_applies():
    """Dense systems, rigid blocks and stiffness given as arrays take the full matrix."""
    rng = np.random.default_rng(2)
    s = symmetric_system(rng, 12, 40)
    assert SystemPattern(s["free"], s["bj"], s["bk"]).upper_matrix(
        s["block_k"], s["pair_k"]) is None
    s = symmetric_system(rng)
    pattern = SystemPattern(s["free"], s["bj"], s["bk"])
    assert pattern.upper_matrix(s["block_k"], s["pair_k"].dense()) is None
    rigid = random_system(90, 400, rng, rigid=True)
    assert SystemPattern(rigid["free"], rigid["bj"], rigid["bk"], rigid["rigid"]).upper_matrix(
        rigid["block_k"], rigid["pair_k"]) is None


def test_upper_triangle_of_a_later_pass_adds_the_changed_contacts_only(monkeypatch):
    """An OPEN-CLOSE pass that changes a few contacts' springs gets the last pass's upper
    triangle plus their change (:func:`dda.kernels.assembly.upper_update`): the matrix summed
    whole, to round-off; whole again when many changed, or the step's blocks or contacts are
    others."""
    import dda.solvers.linear as linear

    rng = np.random.default_rng(8)
    s = symmetric_system(rng)
    pattern = SystemPattern(s["free"], s["bj"], s["bk"])
    k = s["pair_k"]
    first = pattern.upper_matrix(s["block_k"], k)
    calls = []
    monkeypatch.setattr(linear, "upper_update", lambda *a: calls.append(a) or upper_update(*a))
    weights = k.weights.copy()
    changed = rng.choice(len(weights), 12, replace=False)
    weights[changed[:6]] = 0.0  # six contacts open ...
    weights[changed[6:], 1] *= 3.0  # ... and six change a spring
    later = PairStiffness.checked_by_caller(k.rows, k.terms, weights)
    got = pattern.upper_matrix(s["block_k"], later)
    assert len(calls) == 1 and sorted(calls[0][-1]) == sorted(changed)
    fresh = SystemPattern(s["free"], s["bj"], s["bk"]).upper_matrix(s["block_k"], later)
    scale = np.abs(fresh.csr.data).max()
    np.testing.assert_allclose(got.csr.data, fresh.csr.data, rtol=0, atol=1e-14 * scale)
    assert np.abs(got.csr.data - first.csr.data).max() > 1e-3 * scale
    # the last pass's matrix is not changed under its holder (PARDISO may still use it)
    np.testing.assert_array_equal(first.csr.data, SystemPattern(
        s["free"], s["bj"], s["bk"]).upper_matrix(s["block_k"], k).csr.data)
    # a third of the contacts changed: summed whole, the bits of the whole sum
    many = weights.copy()
    many[: len(many) // 3] *= 2.0
    again = pattern.upper_matrix(s["block_k"], PairStiffness.checked_by_caller(
        k.rows, k.terms, many))
    assert len(calls) == 1
    np.testing.assert_array_equal(again.csr.data, SystemPattern(
        s["free"], s["bj"], s["bk"]).upper_matrix(s["block_k"], PairStiffness.checked_by_caller(
            k.rows, k.terms, many)).csr.data)
    # another step's blocks (another array, the same values): summed whole
    pattern.upper_matrix(s["block_k"].copy(), later)
    assert len(calls) == 1
    # off: every pass summed whole
    monkeypatch.setattr(linear, "INCREMENTAL_UPPER", False)
    pattern.upper_matrix(s["block_k"].copy(), k)
    pattern.upper_matrix(s["block_k"], later)
    assert len(calls) == 1


def test_pardiso_solves_the_upper_triangle_as_the_full_matrix():
    """Legacy DDA's solves through the upper triangle give the full matrix's solution to the
    bit (PARDISO reads the same numbers either way)."""
    from dda.solvers import sparse_factor as sf

    if not sf._pardiso_available():
        pytest.skip("PARDISO (pypardiso with MKL) is not available here")
    s = symmetric_system(np.random.default_rng(9))
    args = [s[k] for k in ("block_k", "block_f", "free", "bj", "bk", "pair_k", "pair_f",
                           "d_known")]
    reading = sf.PardisoFactor(symmetric=True)
    assert reading.reads_upper
    d_upper = assemble_and_solve(*args, factor=reading)
    full = sf.PardisoFactor(symmetric=True)
    full.reads_upper = False
    d_full = assemble_and_solve(*args, factor=full)
    np.testing.assert_array_equal(d_upper, d_full)
    assert reading.fallbacks == full.fallbacks == 0


def test_pair_vectors_add_as_numpy_add_at():
    """The compiled sum of contact vectors onto their blocks: numpy.add.at's order, so its
    bits, repeated blocks included."""
    from dda.solvers.linear import assemble_vector

    rng = np.random.default_rng(4)
    s = random_system(30, 200, rng)
    ref = s["block_f"].copy()
    np.add.at(ref, s["bj"], s["pair_f"][:, :6])
    np.add.at(ref, s["bk"], s["pair_f"][:, 6:])
    ref[~s["free"]] = 0.0
    out = assemble_vector(s["block_f"], s["free"], s["bj"], s["bk"], s["pair_f"])
    np.testing.assert_array_equal(out, ref)
    assert not np.array_equal(out, s["block_f"])


def test_compiled_legacy_springs_are_the_numpy_ones():
    """Legacy DDA's springs of a pass come from a compiled kernel: numpy's weights and forces
    to the bit, for open, sticking and sliding contacts."""
    from dda.kernels.pair_stiffness import legacy_springs

    rng = np.random.default_rng(0)
    m = 300
    state = rng.integers(0, 3, m).astype(np.int8)
    gap0, p_n, p_s, t_stick, t_slip = (rng.normal(size=m) for _ in range(5))
    e, i = rng.normal(size=(m, 12)), rng.normal(size=(m, 12))
    stick, slip = state == 1, state == 2
    kn = np.where(state != 0, p_n, 0.0)
    ks = np.where(stick, p_s, 0.0)
    fs = np.where(stick, t_stick, 0.0) + np.where(slip, t_slip, 0.0)
    weights, force = legacy_springs(state, gap0, p_n, p_s, t_stick, t_slip, e, i)
    np.testing.assert_array_equal(weights, np.stack([kn, ks], axis=1))
    np.testing.assert_array_equal(force, -((kn * gap0)[:, None] * e + fs[:, None] * i))
    np.testing.assert_array_equal(spring_stiffness(e, i, kn, ks).dense(),
                                  PairStiffness(np.stack([e, i], axis=1), [[0, 0], [1, 1]],
                                                weights).dense())
