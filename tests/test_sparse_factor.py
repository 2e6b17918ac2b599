"""The sparse direct solvers: exact answers, the symbolic analysis kept only while the pattern
stands, and a fall back to SuperLU when PARDISO cannot or must not answer."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import scipy.sparse as sp

import dda
from dda.solvers import LegacyPullBack, NewtonRaphson
from dda.solvers import sparse_factor as sf
from tests.conftest import stack_scene

pardiso = pytest.mark.skipif(not sf._pardiso_available(), reason="pypardiso/MKL not installed")


def block_system(n_blocks, seed, unsymmetric=0.0, drop=()):
    """A chain of 6 x 6 blocks as the step makes them: SPD diagonal blocks, coupled to the
    next block (CSC, sorted, structurally symmetric). ``drop`` leaves couplings out."""
    rng = np.random.default_rng(seed)
    n = 6 * n_blocks
    rows, cols, vals = [], [], []
    for b in range(n_blocks):
        a = rng.normal(size=(6, 6))
        blk = a @ a.T + 40.0 * np.eye(6)
        r, c = np.meshgrid(np.arange(6) + 6 * b, np.arange(6) + 6 * b, indexing="ij")
        rows.append(r.ravel()), cols.append(c.ravel()), vals.append(blk.ravel())
        if b + 1 < n_blocks and b not in drop:
            cpl = rng.normal(size=(6, 6))
            r, c = np.meshgrid(np.arange(6) + 6 * b, np.arange(6) + 6 * b + 6, indexing="ij")
            other = cpl.T + unsymmetric * rng.normal(size=(6, 6))
            rows += [r.ravel(), c.ravel()]
            cols += [c.ravel(), r.ravel()]
            vals += [cpl.ravel(), other.T.ravel()]
    k = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(n, n))
    k.sort_indices()
    return k, rng.normal(size=n)


def assert_solves(k, x, rhs):
    np.testing.assert_allclose(k @ x, rhs, atol=1e-10 * np.abs(rhs).max())


@pytest.mark.parametrize("backend", ["superlu", pytest.param("pardiso", marks=pardiso)])
@pytest.mark.parametrize("symmetric", [True, False])
def test_backends_solve_exactly(backend, symmetric):
    k, rhs = block_system(80, 1, unsymmetric=0.0 if symmetric else 0.4)
    assert (abs(k - k.T).max() == 0.0) == symmetric
    f = sf.make_factor(backend, symmetric)
    assert_solves(k, f.solve(k, rhs), rhs)
    assert f.factorizations == 1


@pardiso
def test_symbolic_analysis_is_kept_while_the_pattern_stands():
    f = sf.make_factor("pardiso", symmetric=True)
    for seed in range(3):  # new values, same pattern: numeric factorization only
        k, rhs = block_system(60, seed)
        assert_solves(k, f.solve(k, rhs), rhs)
    assert (f.analyses, f.factorizations) == (1, 3)
    k, rhs = block_system(60, 7, drop=(10, 30))  # a coupling less: analysed again
    assert_solves(k, f.solve(k, rhs), rhs)
    assert (f.analyses, f.factorizations) == (2, 4)
    k, rhs = block_system(60, 8)  # back to the first pattern: analysed again, still exact
    assert_solves(k, f.solve(k, rhs), rhs)
    assert (f.analyses, f.factorizations, f.fallbacks) == (3, 5, 0)


@pardiso
def test_pardiso_falls_back_to_superlu_when_it_must_not_answer():
    # an indefinite symmetric matrix: not for PARDISO's positive definite type
    k, rhs = block_system(40, 3)
    k = (k - 60.0 * sp.eye(k.shape[0], format="csc")).tocsc()
    k.sort_indices()
    f = sf.make_factor("pardiso", symmetric=True)
    assert_solves(k, f.solve(k, rhs), rhs)
    # an unsymmetric matrix said to be symmetric: the upper triangle alone is the wrong
    # matrix, and the residual check sends it to SuperLU
    k2, rhs2 = block_system(40, 4, unsymmetric=0.5)
    assert_solves(k2, f.solve(k2, rhs2), rhs2)
    assert f.fallbacks == 2


def test_backend_choice_by_environment(monkeypatch):
    monkeypatch.setenv("DDA_SPARSE_SOLVER", "superlu")
    assert sf.default_backend() == "superlu"
    assert isinstance(sf.FactorSet().get(True), sf.SuperLUFactor)
    monkeypatch.setenv("DDA_SPARSE_SOLVER", "umfpack")
    with pytest.raises(ValueError, match="DDA_SPARSE_SOLVER must be one of pardiso, superlu"):
        sf.default_backend()


@pardiso
@pytest.mark.parametrize("solver", [LegacyPullBack, NewtonRaphson])
def test_a_stack_settles_alike_with_either_backend(monkeypatch, solver):
    """9 x 9 blocks (486 unknowns: the sparse path) for 15 steps: the two backends, and
    PARDISO in mixed precision, agree to round-off, and the symbolic analysis is done once
    for the steps whose pattern stands."""
    out = {}
    for backend, precision in (("superlu", "auto"), ("pardiso", "double"),
                               ("pardiso", "mixed")):
        monkeypatch.setenv("DDA_SPARSE_SOLVER", backend)
        monkeypatch.setenv("DDA_PARDISO_PRECISION", precision)
        backend = backend if precision != "mixed" else "mixed"
        s = solver()
        sim = dda.Simulation(stack_scene(9), dt=1e-3, solver=s, max_open_close=30)
        r = sim.run(0.015, progress=False)
        out[backend] = (sim.committed.x.copy(), np.asarray(r.stats["open_close_passes"]))
        factorizations, analyses = s.factors().counts
        assert 0.5 * np.sum(r.stats["solves"]) < factorizations <= np.sum(r.stats["solves"])
        if backend == "pardiso":
            assert analyses < factorizations / 3
        pickle.loads(pickle.dumps(s))  # the factorizations are not part of the solver's state
        assert "_factors" not in pickle.loads(pickle.dumps(s)).__dict__
    for other in ("pardiso", "mixed"):
        np.testing.assert_allclose(out[other][0], out["superlu"][0], rtol=0, atol=1e-9)
        np.testing.assert_array_equal(out[other][1], out["superlu"][1])


@pytest.mark.parametrize("backend", ["superlu", pytest.param("pardiso", marks=pardiso)])
def test_the_same_matrix_is_factorized_once(backend):
    """Passes that change loads only solve with the factorization they have, whether they
    give the same matrix or an equal one; a matrix with other values (same pattern) is
    factorized again."""
    f = sf.make_factor(backend, symmetric=True)
    k, rhs = block_system(60, 1)
    for scale in (1.0, -2.0, 0.5):
        assert_solves(k, f.solve(k, scale * rhs + 1.0), scale * rhs + 1.0)
    assert f.factorizations == 1
    k2 = k.copy()
    k2.data[0] *= 1.5
    assert_solves(k2, f.solve(k2, rhs), rhs)
    assert f.factorizations == 2
    assert_solves(k2, f.solve(k2.copy(), 2.0 * rhs), 2.0 * rhs)  # equal arrays, not the same
    assert f.factorizations == 2


@pardiso
@pytest.mark.parametrize("symmetric", [True, False])
def test_pardiso_solves_without_iterative_refinement(symmetric):
    """PARDISO's default refines every solution twice, which tripled a solve's cost for
    nothing on these systems: the solves refine only after a factorization that perturbed
    pivots, and their residual stays at round-off."""
    f = sf.make_factor("pardiso", symmetric=symmetric)
    k, rhs = block_system(200, 3, unsymmetric=0.0 if symmetric else 0.3)
    x = f.solve(k, rhs)
    assert_solves(k, x, rhs)
    assert np.abs(k @ x - rhs).max() <= 1e-12 * np.abs(rhs).max()
    assert f._solver.iparm[13] == 0  # no perturbed pivots
    assert f._solver.iparm[6] == 0  # refinement steps done in the last solve
    assert f.fallbacks == 0


@pardiso
def test_an_upper_triangle_falls_back_to_superlu_whole():
    """A symmetric matrix handed over as its upper triangle (the legacy passes' form) that
    PARDISO must not answer (indefinite) is solved by SuperLU on the whole matrix."""
    k, rhs = block_system(40, 3)
    k = (k - 60.0 * sp.eye(k.shape[0], format="csc")).tocsc()
    k.sort_indices()
    upper = sp.triu(k.tocsr(), format="csr")
    upper.sort_indices()
    f = sf.make_factor("pardiso", symmetric=True)
    assert f.reads_upper
    assert_solves(k, f.solve(sf.UpperTriangle(upper), rhs), rhs)
    assert f.fallbacks == 1
    x = np.random.default_rng(0).normal(size=k.shape[0])
    np.testing.assert_allclose(sf.UpperTriangle(upper) @ x, k @ x, rtol=1e-13, atol=1e-12)


@pytest.mark.parametrize("backend", ["superlu", pytest.param("pardiso", marks=pardiso),
                                     pytest.param("mixed", marks=pardiso)])
@pytest.mark.parametrize("symmetric", [True, False])
def test_solve_near_reuses_the_last_factorization(monkeypatch, backend, symmetric):
    """A matrix close to the one factorized last (a later Newton iteration's tangent) is
    solved by GMRES preconditioned with that factorization, to NEAR_RTOL, with no new one;
    one far from it, or of another pattern, is factorized. "mixed": PARDISO's factors in
    single precision, the preconditioner then."""
    if backend == "mixed":
        monkeypatch.setenv("DDA_PARDISO_PRECISION", "mixed")
        backend = "pardiso"
    unsym = 0.0 if symmetric else 0.4
    k, rhs = block_system(80, 1, unsymmetric=unsym)
    f = sf.make_factor(backend, symmetric)
    f.solve(k, rhs)
    near = k.copy()
    near.data *= 1.0 + 1e-3 * np.random.default_rng(2).normal(size=near.nnz)
    if symmetric:
        near = ((near + near.T) / 2).tocsc()
        near.sort_indices()
    x = f.solve_near(near, rhs)
    assert np.linalg.norm(near @ x - rhs) <= sf.NEAR_RTOL * np.linalg.norm(rhs)
    assert (f.factorizations, f.near_solves) == (1, 1)
    far, _ = block_system(80, 5, unsymmetric=unsym)  # same pattern, unrelated values
    assert_solves(far, f.solve_near(far, rhs), rhs)
    assert (f.factorizations, f.near_solves) == (2, 1)
    other, rhs2 = block_system(80, 1, unsymmetric=unsym, drop=(3,))
    assert_solves(other, f.solve_near(other, rhs2), rhs2)
    assert (f.factorizations, f.near_solves) == (3, 1)


def test_newton_iterations_reuse_the_tangent_factorization():
    """Later Newton iterations of a step whose contacts keep their states solve with the
    step's first tangent factorization (GMRES), and the answer is the one of a new
    factorization every iteration, within the solver's tolerance."""
    from dda.solvers import newton

    def run(switches):
        old = newton.NEAR_SWITCHES
        newton.NEAR_SWITCHES = switches
        try:
            solver = NewtonRaphson()
            sim = dda.Simulation(stack_scene(10), dt=1e-3, solver=solver)
            res = sim.run(0.05, progress=False)
        finally:
            newton.NEAR_SWITCHES = old
        near = sum(f.near_solves for f in solver.factors()._factors.values())
        return res, near

    res_new, near_new = run(-1)  # never: a factorization every iteration
    res_near, near_near = run(newton.NEAR_SWITCHES)
    assert near_new == 0 and near_near > 0
    np.testing.assert_array_equal(res_near.time, res_new.time)
    for block in range(1, 101):
        # measured: 5.6e-14 m and 5.5e-5 Pa apart (stresses up to 3e5 Pa), 3 solves by GMRES
        np.testing.assert_allclose(res_near.displacement(block), res_new.displacement(block),
                                   rtol=0, atol=1e-11)
        np.testing.assert_allclose(res_near.stress(block), res_new.stress(block),
                                   rtol=0, atol=1e-2)


def chain_laplacian(n, shift):
    """The tridiagonal ``2, -1`` chain of ``n`` unknowns plus ``shift`` on the diagonal:
    symmetric positive definite with a condition number of about ``4 / (pi^2 / n^2 + shift)``
    (a static analysis' loosely held chain)."""
    main = np.full(n, 2.0 + shift)
    k = sp.diags([-np.ones(n - 1), main, -np.ones(n - 1)], [-1, 0, 1], format="csc")
    k.sort_indices()
    return k, np.random.default_rng(0).normal(size=n)


@pardiso
@pytest.mark.parametrize("symmetric", [True, False])
def test_mixed_precision_solves_to_double_precision_accuracy(symmetric):
    """Single-precision factors with the solution refined in double precision: the answer
    within MIXED_RTOL of the double factorization's, after one refinement here, where the
    single-precision solve alone is off by about 1e-6."""
    k, rhs = block_system(400, 3, unsymmetric=0.0 if symmetric else 0.3)
    assert k.shape[0] >= sf.MIXED_MIN_UNKNOWNS
    exact = sf.PardisoFactor(symmetric, precision="double").solve(k, rhs)
    f = sf.PardisoFactor(symmetric, precision="auto")
    x = f.solve(k, rhs)
    assert f._single and f._data.dtype == np.float32
    assert f.refinements == 1 and f.single_failures == 0 and f.fallbacks == 0
    err = np.linalg.norm(x - exact) / np.linalg.norm(exact)
    assert err <= 10 * sf.MIXED_RTOL
    unrefined = f._apply(rhs)
    assert np.linalg.norm(unrefined - exact) / np.linalg.norm(exact) > 1e3 * err
    # a second right-hand side with the same matrix: no new factorization
    x2 = f.solve(k, 2.0 * rhs)
    assert f.factorizations == 1
    np.testing.assert_allclose(x2, 2.0 * exact, rtol=0, atol=1e-10 * np.abs(exact).max())


@pardiso
@pytest.mark.parametrize("symmetric", [True, False])
def test_a_refined_solve_stops_at_the_callers_residual(symmetric):
    """``atol``: the refinement of single-precision factors returns the first iterate whose
    double-precision residual is within it (an inexact Newton step needs no more), and goes
    on to MIXED_RTOL without it. Measured here: the unrefined solve leaves a residual of
    about 3e-6 of the right-hand side, one refinement 1e-12 of it."""
    k, rhs = block_system(400, 3, unsymmetric=0.0 if symmetric else 0.3)
    full = sf.PardisoFactor(symmetric, precision="auto")
    exact = full.solve(k, rhs)
    assert full.refinements == 1 and full.inexact_solves == 0
    first = np.linalg.norm(rhs - k @ full._apply(rhs))
    assert first > 1e-8 * np.linalg.norm(rhs)  # the single-precision solve alone is not exact

    loose = sf.PardisoFactor(symmetric, precision="auto")
    x = loose.solve(k, rhs, atol=2.0 * first)  # the unrefined solve is within it
    assert (loose.refinements, loose.inexact_solves, loose.factorizations) == (0, 1, 1)
    # the unrefined solve (not the bits of another: PARDISO's solves with the same factors
    # may differ at single precision's round-off from call to call)
    assert 1e-8 * np.linalg.norm(rhs) < np.linalg.norm(rhs - k @ x) <= 2.0 * first
    # an atol below the first residual: refined once, to MIXED_RTOL as without it, to the
    # same answer
    x = loose.solve(k, rhs, atol=0.5 * first)
    assert (loose.refinements, loose.inexact_solves, loose.factorizations) == (1, 1, 1)
    # (two PARDISO handles' factors of one matrix, and two solves with one's, may differ in
    # their last bits; refined, the answers agree to about MIXED_RTOL)
    same = {"rtol": 0.0, "atol": 10 * sf.MIXED_RTOL * np.abs(exact).max()}
    np.testing.assert_allclose(x, exact, **same)
    # none or 0: refined in full
    for atol in (None, 0.0):
        np.testing.assert_allclose(loose.solve(k, rhs, atol=atol), exact, **same)
    assert (loose.refinements, loose.inexact_solves) == (3, 1)


@pardiso
def test_solve_near_stops_at_the_callers_residual():
    """GMRES with the last factorization stops at ``atol`` when that is above NEAR_RTOL of
    the right-hand side, and the answer leaves at most that residual."""
    k, rhs = block_system(400, 1, unsymmetric=0.4)
    near = k.copy()
    near.data *= 1.0 + 1e-3 * np.random.default_rng(2).normal(size=near.nnz)
    tight, loose = (sf.PardisoFactor(False, precision="auto") for _ in range(2))
    for f in (tight, loose):
        f.solve(k, rhs)
    atol = 1e-6 * np.linalg.norm(rhs)
    x_tight = tight.solve_near(near, rhs)
    x_loose = loose.solve_near(near, rhs, atol=atol)
    assert tight.near_solves == loose.near_solves == 1
    assert loose.factorizations == tight.factorizations == 1
    r_tight = np.linalg.norm(rhs - near @ x_tight)
    r_loose = np.linalg.norm(rhs - near @ x_loose)
    assert r_tight <= sf.NEAR_RTOL * np.linalg.norm(rhs) < r_loose <= atol


@pardiso
def test_small_systems_stay_in_double_precision():
    k, rhs = block_system(60, 1)
    assert k.shape[0] < sf.MIXED_MIN_UNKNOWNS
    f = sf.PardisoFactor(True)
    assert f.precision == "auto"
    assert_solves(k, f.solve(k, rhs), rhs)
    assert not f._single and f.refinements == 0
    forced = sf.PardisoFactor(True, precision="mixed")
    assert_solves(k, forced.solve(k, rhs), rhs)
    assert forced._single and forced.refinements >= 1


@pardiso
def test_mixed_precision_falls_back_to_double_on_an_ill_conditioned_matrix():
    """A chain whose condition number (about 4e6) times single precision's 6e-8 is not small:
    the refinement does not contract, the matrix is factorized in double precision, and the
    holder stays in double precision from then on."""
    k, rhs = chain_laplacian(3000, 1e-9)
    f = sf.PardisoFactor(True, precision="mixed")
    x = f.solve(k, rhs)
    assert np.linalg.norm(k @ x - rhs) <= 1e-10 * np.linalg.norm(rhs)
    assert f.single_failures == 1 and not f._single and f.fallbacks == 0
    assert not f.wants_single(10**6)
    x2 = f.solve(k, rhs)  # the same factors (PARDISO on two threads: to round-off)
    assert f.factorizations == 2
    np.testing.assert_allclose(x2, x, rtol=1e-12, atol=0)
    # well conditioned, the same chain stays in single precision
    k3, rhs3 = chain_laplacian(3000, 1.0)
    g = sf.PardisoFactor(True, precision="mixed")
    assert_solves(k3, g.solve(k3, rhs3), rhs3)
    assert g._single and g.single_failures == 0


@pardiso
def test_precision_switches_between_patterns():
    """A small system then a large one then a small one through one holder: each analysed in
    its own precision (the other's memory released), each answer exact."""
    f = sf.PardisoFactor(False)
    for blocks in (60, 400, 60, 400):
        k, rhs = block_system(blocks, blocks, unsymmetric=0.3)
        assert_solves(k, f.solve(k, rhs), rhs)
        assert f._single == (k.shape[0] >= sf.MIXED_MIN_UNKNOWNS)
    assert (f.analyses, f.factorizations, f.fallbacks) == (4, 4, 0)


def test_precision_choice_by_environment(monkeypatch):
    monkeypatch.setenv("DDA_PARDISO_PRECISION", "double")
    assert sf.default_precision() == "double"
    monkeypatch.setenv("DDA_PARDISO_PRECISION", "half")
    with pytest.raises(ValueError, match="DDA_PARDISO_PRECISION must be one of auto, double"):
        sf.default_precision()
    monkeypatch.delenv("DDA_PARDISO_PRECISION")
    assert sf.default_precision() == "auto"


@pardiso
def test_a_matrix_pardiso_refuses_in_single_precision_is_factorized_in_double(monkeypatch):
    """A PARDISO error on the single-precision factors (a pivot that rounding made zero)
    sends the matrix to a double-precision factorization of PARDISO's, not to SuperLU."""
    k, rhs = block_system(400, 6)
    f = sf.PardisoFactor(True, precision="mixed")
    call = f._call

    def refuse_single(phase, data, b):
        if phase == 22 and data.dtype == np.float32:
            from pypardiso.pardiso_wrapper import PyPardisoError

            raise PyPardisoError(-4)
        return call(phase, data, b)

    monkeypatch.setattr(f, "_call", refuse_single)
    assert_solves(k, f.solve(k, rhs), rhs)
    assert (f.single_failures, f.fallbacks, f._single) == (1, 0, False)


@pardiso
@pytest.mark.parametrize("size", [1e-30, 1e40])
def test_mixed_precision_keeps_its_accuracy_at_any_scale(size):
    """A right-hand side far from 1 (a refinement's residual of 1e-40 would round to zero in
    single precision, one of 1e40 overflow): the answer to double's accuracy all the same."""
    k, rhs = block_system(400, 3)
    k = (k * 1e10).tocsc()
    exact = sf.PardisoFactor(True, precision="double").solve(k, size * rhs)
    f = sf.PardisoFactor(True, precision="mixed")
    x = f.solve(k, size * rhs)
    assert np.linalg.norm(x - exact) <= 10 * sf.MIXED_RTOL * np.linalg.norm(exact)
    assert f._single and f.single_failures == 0


@pardiso
def test_a_bad_matrix_or_load_does_not_turn_mixed_precision_off():
    """An indefinite matrix fails in double precision too (SuperLU answers it): that is the
    matrix, not the precision, and the next matrix is factorized in single precision again.
    A non-finite right-hand side has no answer and costs the factors nothing."""
    k, rhs = block_system(400, 3)
    bad = (k - 60.0 * sp.eye(k.shape[0], format="csc")).tocsc()
    bad.sort_indices()
    f = sf.PardisoFactor(True, precision="mixed")
    assert_solves(bad, f.solve(bad, rhs), rhs)
    assert f.fallbacks == 1 and f.single_failures == 0
    assert_solves(k, f.solve(k, rhs), rhs)
    assert f._single and f.single_failures == 0
    done = f.factorizations
    assert not np.all(np.isfinite(f.solve(k, np.full_like(rhs, np.nan))))
    assert_solves(k, f.solve(k, rhs), rhs)
    assert (f.factorizations, f.single_failures, f._single) == (done, 0, True)


def test_an_upper_triangle_multiplies_as_the_whole_symmetric_matrix():
    """The compiled product with a matrix stored as its upper triangle (one pass, each entry
    read once) is the whole matrix's product: rows with and without a stored diagonal, empty
    rows, a dense row."""
    from dda.kernels.sparse_products import upper_symmetric_matvec

    rng = np.random.default_rng(3)
    n = 40
    a = sp.random(n, n, density=0.15, random_state=4, format="csr")
    a = a + a.T + sp.diags(rng.uniform(1.0, 2.0, n))
    a = a.tolil()
    a[5, :] = 0.0  # an empty row (and column)
    a[:, 5] = 0.0
    a[7, 7] = 0.0  # a row without a diagonal entry
    row = rng.standard_normal(n)
    a[0, :] = row  # a dense row (and column)
    a[:, 0] = row[:, None]
    full = sp.csr_matrix(a)
    upper = sp.triu(full, format="csr")
    upper.eliminate_zeros()
    upper.sort_indices()
    assert upper.indices[upper.indptr[7]] != 7
    x = rng.standard_normal(n)
    want = full.toarray() @ x
    got = upper_symmetric_matvec(upper.indptr, upper.indices, upper.data, x)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * np.abs(want).max())
    np.testing.assert_allclose(sf.UpperTriangle(upper) @ x, want, rtol=0,
                               atol=1e-13 * np.abs(want).max())
    # a block of right-hand sides takes scipy's products, the same numbers
    xs = rng.standard_normal((n, 3))
    np.testing.assert_allclose(sf.UpperTriangle(upper) @ xs, full.toarray() @ xs, rtol=0,
                               atol=1e-13 * np.abs(want).max())


def _spring_system(monkeypatch):
    """A symmetric system of 1,800 unknowns (single precision) from legacy springs, its
    pattern and springs."""
    from dda.kernels import PairStiffness
    from dda.solvers.linear import SystemPattern
    from tests.test_kernels import random_system

    monkeypatch.setattr(sf, "MIXED_MIN_UNKNOWNS", 1200)
    rng = np.random.default_rng(12)
    s = random_system(300, 900, rng)
    k = PairStiffness(rng.normal(size=(900, 2, 12)), [[0, 0], [1, 1]],
                      np.abs(rng.normal(size=(900, 2))) * 1e3)
    return s, SystemPattern(s["free"], s["bj"], s["bk"]), k


@pardiso
@pytest.mark.parametrize("changed, low_rank", [(4, True), (17, False)])
def test_a_few_changed_springs_update_the_factors(monkeypatch, changed, low_rank):
    """An OPEN-CLOSE pass whose springs differ from the factorized matrix's in at most
    LOW_RANK_TERMS terms is solved by the Woodbury update of those factors, to the accuracy
    of a new factorization; more changes, or the option off, factorize."""
    from dda.kernels import PairStiffness

    s, pattern, k = _spring_system(monkeypatch)
    f = sf.make_factor("pardiso", symmetric=True)
    rhs = np.random.default_rng(3).normal(size=pattern.n)
    first = pattern.upper_matrix(s["block_k"], k)
    assert_solves(first.full(), f.solve(first, rhs), rhs)
    assert (f.factorizations, f.low_rank_solves) == (1, 0)
    w = k.weights.copy()
    # springs opened (weight 0), stiffened and softened: `changed` terms in all
    terms = [(c, t) for c in range(0, 3 * changed, 3) for t in (0,)][:changed]
    for i, (c, t) in enumerate(terms):
        w[c, t] = (0.0, 3.0 * w[c, t], 0.5 * w[c, t])[i % 3]
    later = pattern.upper_matrix(s["block_k"], PairStiffness.checked_by_caller(k.rows, k.terms, w))
    assert (later.change is not None) == low_rank
    x = f.solve(later, rhs)
    fresh = sf.make_factor("pardiso", symmetric=True).solve(later, rhs)
    np.testing.assert_allclose(x, fresh, rtol=0, atol=1e-11 * np.abs(fresh).max())
    assert_solves(later.full(), x, rhs)
    assert (f.factorizations, f.low_rank_solves) == ((1, 1) if low_rank else (2, 0))
    # the option off: the same change is factorized
    g = sf.make_factor("pardiso", symmetric=True)
    g.low_rank = False
    g.solve(pattern.upper_matrix(s["block_k"], k), rhs)
    g.solve(pattern.upper_matrix(s["block_k"], PairStiffness.checked_by_caller(
        k.rows, k.terms, w)), rhs)
    assert (g.factorizations, g.low_rank_solves) == (2, 0)


@pardiso
def test_a_wrong_low_rank_change_falls_back_to_a_factorization(monkeypatch):
    """A change that does not describe the matrix (here: the springs' weights misstated)
    does not pass the refinement, whose residuals are the matrix's own: the matrix is
    factorized and solved exactly."""
    from dda.kernels import PairStiffness

    s, pattern, k = _spring_system(monkeypatch)
    f = sf.make_factor("pardiso", symmetric=True)
    rhs = np.random.default_rng(4).normal(size=pattern.n)
    f.solve(pattern.upper_matrix(s["block_k"], k), rhs)
    w = k.weights.copy()
    w[:3, 0] *= 50.0
    later = pattern.upper_matrix(s["block_k"], PairStiffness.checked_by_caller(k.rows, k.terms, w))
    base, rows, u, lam = later.change
    later.change = (base, rows, u, -0.5 * lam)
    x = f.solve(later, rhs)
    assert_solves(later.full(), x, rhs)
    assert (f.factorizations, f.low_rank_solves) == (2, 0)


@pardiso
@pytest.mark.parametrize("solver", [LegacyPullBack, NewtonRaphson])
def test_a_stack_settles_alike_with_the_low_rank_update(monkeypatch, solver):
    """Legacy DDA, and Newton's OPEN-CLOSE predictor, on 9 x 9 blocks in mixed precision for
    15 steps: the passes that solve by the low-rank update of the last factors give the steps
    the same passes and the blocks the same places, to round-off, as factorizing every
    changed matrix. Measured under Newton: 14 updates, 61 factorizations against 70, the same
    passes and iterations, the blocks 2e-14 m apart."""
    monkeypatch.setenv("DDA_SPARSE_SOLVER", "pardiso")
    monkeypatch.setenv("DDA_PARDISO_PRECISION", "mixed")
    from dda.solvers import newton
    assert newton.PREDICTOR_LOW_RANK  # the default
    out = {}
    for low_rank in (True, False):
        monkeypatch.setattr(sf, "LOW_RANK", low_rank)
        s = solver()
        sim = dda.Simulation(stack_scene(9), dt=1e-3, solver=s, max_open_close=30)
        r = sim.run(0.015, progress=False)
        holder = s.factors().get(True)
        out[low_rank] = (sim.committed.x.copy(), np.asarray(r.stats["open_close_passes"]),
                         holder.low_rank_solves, s.factors().counts[0],
                         np.asarray(r.stats["iterations"]))
    assert out[True][2] >= 5 and out[False][2] == 0
    # fewer factorizations, if not by every update (a pass after one whose matrix is the
    # updated one's factorizes it: the factors held are still the older matrix's)
    assert out[True][3] < out[False][3]
    np.testing.assert_array_equal(out[True][1], out[False][1])
    np.testing.assert_array_equal(out[True][4], out[False][4])
    np.testing.assert_allclose(out[True][0], out[False][0], rtol=0, atol=1e-9)
