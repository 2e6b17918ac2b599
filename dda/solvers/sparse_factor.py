"""Sparse direct solvers for the step's system, and the choice between them.

Two backends factorize the step's sparse matrix ``K`` (CSC, sorted, structurally symmetric):

``pardiso``
    Intel MKL PARDISO through :mod:`pypardiso` (``pip install pypardiso``; MKL wheels exist for
    x86-64 Linux and Windows). Supernodal, with a METIS ordering. The legacy system is
    symmetric positive definite (Newmark inertia plus springs) and is factorized as
    ``K = L D L^T`` of its upper triangle (matrix type 2); the fully implicit tangent, which
    the slip coupling makes unsymmetric, as ``K = L U`` (type 11). The symbolic analysis
    (ordering, elimination tree) depends on the matrix's pattern only and is kept while the
    pattern stands: a step whose contacts couple the same blocks as the last one pays the
    numeric factorization alone.
``superlu``
    SciPy's SuperLU in symmetric mode (minimum degree on ``K + K^T``, diagonal pivots
    preferred), with a residual check and scipy's default as a fallback. No dependency beyond
    SciPy; four to eleven times slower on the stacks of ``benchmarks/stacks.py``.

Measured on the systems of the N x N stacks (one thread): 5,400 unknowns, SuperLU 39-58 ms a
factorization, PARDISO 7.6 ms analysis + 4.5 ms numeric (LDL^T) or 10-12 ms (LU); 21,600
unknowns, 400 ms against 52 + 35 ms.

PARDISO reads a symmetric matrix as the upper triangle of its rows (CSR); the OPEN-CLOSE
passes hand it an :class:`UpperTriangle` summed straight into that layout
(:meth:`dda.solvers.linear.SystemPattern.upper_matrix`): on the 60 x 60 stack 4.7 ms a pass
against 9.7 ms for the whole matrix and its reordering (30 x 30: 1.2 against 2.3 ms), with
the same numbers to the bit.

PARDISO's defaults refine every solution by two steps of iterative refinement, which made a
solve cost a third to a half of a factorization and left the residual where it was (about
2e-15 of the right-hand side either way): a solve of the 30 x 30 stack's system took 2.8 ms
refined and 0.83 ms not (60 x 60: 17.9 against 4.7 ms; Newton's LU, 4.8 against 1.35 ms and
21 against 5.6 ms). The solves here refine only after a factorization that perturbed pivots
(PARDISO's own rule when it is left to choose), and the residual is checked either way.

Both keep the numeric factorization of the last matrix: an OPEN-CLOSE pass that changes only
loads (the friction of sliding contacts) and not the springs solves with it again.

:func:`default_backend` picks ``pardiso`` when it can be loaded, else ``superlu``; the
environment variable ``DDA_SPARSE_SOLVER`` (``pardiso`` or ``superlu``) overrides the choice.
"""

from __future__ import annotations

import os

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["SparseFactor", "UpperTriangle", "SuperLUFactor", "PardisoFactor", "FactorSet",
           "default_backend", "make_factor", "BACKENDS", "SingularSystemError"]

# SuperLU's diagonal pivot threshold in symmetric mode: an off-diagonal pivot only when the
# diagonal is below this fraction of the column's largest entry
SYMMETRIC_PIVOT = 0.1
# the largest residual, relative to the right-hand side, a factorization's solution may leave
RESIDUAL_RTOL = 1e-8
# :meth:`SparseFactor.solve_near`: the residual (2-norm, relative to the right-hand side's) at
# which GMRES preconditioned by the last factorization stops, and its iterations before the
# matrix is factorized after all
NEAR_RTOL = 1e-10
NEAR_ITERATIONS = 8

BACKENDS = ("pardiso", "superlu")


class SingularSystemError(RuntimeError):
    """The step's matrix is singular (a block with no support in a static analysis)."""


class UpperTriangle:
    """A symmetric matrix given by its upper triangle, ``csr`` (CSR, sorted indices): what
    PARDISO reads for a symmetric matrix, assembled in that layout by
    :meth:`dda.solvers.linear.SystemPattern.upper_matrix`."""

    __slots__ = ("csr",)

    def __init__(self, csr: sp.csr_matrix):
        self.csr = csr

    @property
    def shape(self):
        return self.csr.shape

    def __matmul__(self, x):
        # K x = (U + U^T - diag(U)) x
        u = self.csr
        return u @ x + u.T @ x - u.diagonal() * x

    def full(self) -> sp.csc_matrix:
        """The whole matrix (CSC, sorted indices)."""
        u = self.csr
        k = (u + u.T - sp.diags(u.diagonal())).tocsc()
        k.sort_indices()
        return k


class SparseFactor:
    """One backend's factorization of the step's matrix, reused for every right-hand side.

    ``solve(k, rhs)`` factorizes ``k`` and solves; a backend may keep work that depends on
    ``k``'s pattern only (the symbolic analysis) for the next matrix with the same pattern, and
    the factorization itself for the next call with the same matrix.
    ``symmetric`` says the caller guarantees a symmetric matrix; ``reads_upper`` that ``k`` may
    then come as an :class:`UpperTriangle`.
    """

    name = "sparse"
    reads_upper = False

    def __init__(self, symmetric: bool = False):
        self.symmetric = symmetric
        self.factorizations = 0  # numeric factorizations done
        self.analyses = 0  # symbolic analyses done
        self.near_solves = 0  # solves by GMRES with an earlier factorization (solve_near)

    def solve(self, k: sp.csc_matrix, rhs: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def solve_near(self, k, rhs: np.ndarray) -> np.ndarray:
        """Solve ``k x = rhs`` for a ``k`` close to the matrix factorized last (a later Newton
        iteration's tangent): GMRES preconditioned by that factorization, which converges in
        a few iterations where the two matrices differ by little; :meth:`solve` (a new
        factorization) when there is none of the same pattern, or GMRES has not brought the
        residual to ``NEAR_RTOL`` of the right-hand side in ``NEAR_ITERATIONS``.

        On the 30 x 30 stack of ``benchmarks/stacks.py`` a Newton iteration's tangent after
        the step's first took 2 to 4 iterations to 1e-10 with the first one's ``L U``; a new
        ``L U`` of the 60 x 60 stack's costs 79 ms, a solve with it 7.5 ms.
        """
        apply = self._last_inverse(k)
        if apply is not None:
            n = k.shape[0]
            b = np.asarray(rhs, dtype=float)
            m = spla.LinearOperator((n, n), matvec=apply, dtype=float)
            x, _ = spla.gmres(k, b, M=m, rtol=NEAR_RTOL, atol=0.0, restart=NEAR_ITERATIONS,
                              maxiter=1)
            bnorm = float(np.linalg.norm(b))
            if np.all(np.isfinite(x)) and np.linalg.norm(k @ x - b) <= NEAR_RTOL * bnorm:
                self.near_solves += 1
                return x
        return self.solve(k, rhs)

    def _last_inverse(self, k):
        """The solve with the last factorization (a function of a vector) when it was of a
        matrix with ``k``'s pattern; else None."""
        return None

    def __repr__(self):
        return f"{type(self).__name__}(symmetric={self.symmetric})"


class SuperLUFactor(SparseFactor):
    """SciPy's SuperLU (see the module docstring); keeps the last factorization for the next
    call with the same matrix."""

    name = "superlu"

    def __init__(self, symmetric: bool = False):
        super().__init__(symmetric)
        self._last = None  # (indptr, indices, data, lu) of the matrix factorized last

    def solve(self, k, rhs):
        last = self._last
        if last is not None and all(np.array_equal(x, y) for x, y in zip(
                last[:3], (k.indptr, k.indices, k.data), strict=True)):
            sol = last[3].solve(rhs)
            if _small_residual(k, sol, rhs):
                return sol
        self._last = None
        self.factorizations += 1
        self.analyses += 1
        lu = superlu_factor(k)
        if lu is not None:
            sol = lu.solve(rhs)
            if _small_residual(k, sol, rhs):
                self._last = (k.indptr.copy(), k.indices.copy(), k.data.copy(), lu)
                return sol
        return spla.spsolve(k, rhs)

    def _last_inverse(self, k):
        last = self._last
        if last is None or not (np.array_equal(last[0], k.indptr)
                                and np.array_equal(last[1], k.indices)):
            return None
        return last[3].solve


def superlu_solve(k, rhs):
    """SuperLU with a symmetric ordering, falling back to scipy's default on a poor result.

    The step's matrix is structurally symmetric (every contact couples two blocks both ways)
    and its diagonal carries the blocks' inertia and stiffness, so SuperLU's symmetric mode
    (minimum degree on K + K^T, diagonal pivots preferred) keeps the fill low: on a
    1000-brick wall 1.1 million factor entries against 2.1 million with the default column
    ordering, and 2 to 3 times faster (benchmarks/scaling.py). Pivoting can still leave the
    diagonal where it must, and the residual is checked.
    """
    lu = superlu_factor(k)
    if lu is not None:
        sol = lu.solve(rhs)
        if _small_residual(k, sol, rhs):
            return sol
    return spla.spsolve(k, rhs)


def superlu_factor(k):
    """SuperLU's factorization in symmetric mode (see :func:`superlu_solve`), or None when it
    finds the matrix exactly singular."""
    try:
        return spla.splu(k, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=SYMMETRIC_PIVOT,
                         options={"SymmetricMode": True})
    except RuntimeError:  # SuperLU: exactly singular
        return None


def _small_residual(k, sol, rhs) -> bool:
    scale = max(float(np.abs(rhs).max(initial=0.0)), 1e-300)
    return bool(np.all(np.isfinite(sol))
                and np.abs(k @ sol - rhs).max(initial=0.0) <= RESIDUAL_RTOL * scale)


class PardisoFactor(SparseFactor):
    """MKL PARDISO (see the module docstring): ``L D L^T`` of a symmetric matrix (type 2,
    positive definite), ``L U`` otherwise (type 11), the symbolic analysis kept while the
    pattern stands.

    A matrix PARDISO refuses (not positive definite, a zero pivot) or whose solution leaves a
    residual above ``RESIDUAL_RTOL`` is solved again by SuperLU, so the answer never depends on
    which backend could be loaded.
    """

    name = "pardiso"

    def __init__(self, symmetric: bool = False):
        super().__init__(symmetric)
        self.reads_upper = symmetric
        self._solver = _pardiso_solver(mtype=2 if symmetric else 11)
        self._pattern = None  # (indptr, indices) of the analysed matrix (PARDISO's CSR)
        self._csr = None  # (CSC -> CSR data order, indptr, indices) of the last pattern
        self._values = None  # the values of the matrix factorized last
        self._factored = None  # ... and the matrix (PARDISO's CSR)
        self.fallbacks = 0

    def solve(self, k, rhs):
        from pypardiso.pardiso_wrapper import PyPardisoError  # noqa: PLC0415

        a = k.csr if isinstance(k, UpperTriangle) else self._pardiso_matrix(k)
        same = (self._pattern is not None and np.array_equal(self._pattern[0], a.indptr)
                and np.array_equal(self._pattern[1], a.indices))
        b = np.ascontiguousarray(rhs, dtype=float).reshape(-1, 1)
        try:
            if not same:
                self._analyse(a)
            if not (same and self._values is not None and np.array_equal(self._values, a.data)):
                self._values = None
                self._solver.set_phase(22)
                self._solver._call_pardiso(a, b)
                self.factorizations += 1
                # refine the solutions only where PARDISO's own rule would need it: after a
                # factorization that perturbed pivots (iparm[13] counts them)
                self._solver.iparm[7] = 2 if self._solver.iparm[13] > 0 else 0
                self._values = a.data.copy()
                self._factored = a
            self._solver.set_phase(33)
            sol = self._solver._call_pardiso(a, b).reshape(-1)
        except PyPardisoError:
            self._pattern = self._values = None
            sol = None
        if sol is not None and _small_residual(k, sol, rhs):
            return sol
        self.fallbacks += 1
        return superlu_solve(k.full() if isinstance(k, UpperTriangle) else k, rhs)

    def _last_inverse(self, k):
        if self._values is None or self._pattern is None:
            return None
        if isinstance(k, UpperTriangle):
            indptr, indices = k.csr.indptr, k.csr.indices
            same = (np.array_equal(self._pattern[0], indptr)
                    and np.array_equal(self._pattern[1], indices))
        else:  # the CSC pattern whose CSR the analysis was of
            cached = self._csr
            same = cached is not None and (cached[3] is k.indptr or (
                np.array_equal(cached[3], k.indptr) and np.array_equal(cached[4], k.indices)))
        if not same:
            return None
        from pypardiso.pardiso_wrapper import PyPardisoError  # noqa: PLC0415

        a = self._factored

        def apply(v):
            self._solver.set_phase(33)
            try:
                return self._solver._call_pardiso(
                    a, np.ascontiguousarray(v, dtype=float).reshape(-1, 1)).reshape(-1)
            except PyPardisoError:  # GMRES then ends non-finite: solve() factorizes
                return np.full(len(v), np.nan)

        return apply

    def _analyse(self, a):
        self._pattern = self._values = None
        self._solver.set_phase(11)
        self._solver._call_pardiso(a, np.zeros((a.shape[0], 1)))
        self.analyses += 1
        # the analysis has filled iparm with PARDISO's defaults; from here on PARDISO reads
        # them from the array (iparm[0] = 1), so a solve's refinement can be turned off
        self._solver.iparm[0] = 1
        self._pattern = (a.indptr.copy(), a.indices.copy())

    def _pardiso_matrix(self, k):
        """The matrix as PARDISO reads it: CSR with sorted indices, and for type 2 its upper
        triangle only. The CSC data are put in row order by a permutation that depends on
        the pattern alone (worked out once per pattern)."""
        if not k.has_sorted_indices:
            k = k.copy()
            k.sort_indices()
        cached = self._csr
        if cached is None or not (cached[3] is k.indptr or (
                np.array_equal(cached[3], k.indptr) and np.array_equal(cached[4], k.indices))):
            order = sp.csc_matrix((np.arange(k.nnz, dtype=float), k.indices, k.indptr),
                                  shape=k.shape).tocsr()
            order.sort_indices()
            take = order.data.astype(np.int64)
            indptr, indices = order.indptr, order.indices
            if self.symmetric:
                row = np.repeat(np.arange(k.shape[0]), np.diff(indptr))
                upper = indices >= row
                take = take[upper]
                indptr = np.concatenate([[0], np.cumsum(np.bincount(
                    row[upper], minlength=k.shape[0]))])
                indices = indices[upper]
            cached = (take, indptr.astype(np.int32), indices.astype(np.int32), k.indptr,
                      k.indices)
            self._csr = cached
        take, indptr, indices = cached[:3]
        return sp.csr_matrix((k.data[take], indices, indptr), shape=k.shape)


def default_backend() -> str:
    """``DDA_SPARSE_SOLVER`` if set, else ``pardiso`` when pypardiso and MKL load, else
    ``superlu``."""
    name = os.environ.get("DDA_SPARSE_SOLVER", "").strip().lower()
    if name:
        if name not in BACKENDS:
            raise ValueError(f"DDA_SPARSE_SOLVER must be one of {', '.join(BACKENDS)}, "
                             f"got {name!r}")
        return name
    return "pardiso" if _pardiso_available() else "superlu"


_PARDISO_OK: bool | None = None


def _pardiso_available() -> bool:
    global _PARDISO_OK
    if _PARDISO_OK is None:
        try:
            _pardiso_solver(11)
            _PARDISO_OK = True
        except Exception:  # noqa: BLE001 (no pypardiso, no MKL for this platform)
            _PARDISO_OK = False
    return _PARDISO_OK


def _pardiso_solver(mtype: int):
    """A new pypardiso solver. pypardiso looks for MKL's runtime library by a recursive search
    of the Python prefix when the system loader does not know it (2 s here, at every new
    solver); the library found the first time is handed to the later ones through
    ``PYPARDISO_MKL_RT``, pypardiso's own setting, unless the user has set it (before the
    import: importing pypardiso makes a solver)."""
    if "PYPARDISO_MKL_RT" not in os.environ:
        found = _mkl_runtime()
        if found:
            os.environ["PYPARDISO_MKL_RT"] = found
    from pypardiso import PyPardisoSolver  # noqa: PLC0415 (optional at import time)

    solver = PyPardisoSolver(mtype=mtype)
    if "PYPARDISO_MKL_RT" not in os.environ:
        name = getattr(solver.libmkl, "_name", None)
        if name and os.path.isabs(name):
            os.environ["PYPARDISO_MKL_RT"] = name
    return solver


def _mkl_runtime() -> str | None:
    """MKL's runtime library where its wheel puts it (``<prefix>/lib`` on Linux and macOS,
    ``<prefix>\\Library\\bin`` on Windows), or None."""
    import glob  # noqa: PLC0415
    import site  # noqa: PLC0415
    import sys  # noqa: PLC0415

    for base in (sys.prefix, site.USER_BASE or ""):
        for pattern in ("lib/libmkl_rt.so*", "lib/libmkl_rt*.dylib", "Library/bin/mkl_rt*.dll"):
            hits = sorted(glob.glob(os.path.join(base, pattern)), key=len)
            if hits:
                return hits[0]
    return None


def make_factor(backend: str | None = None, symmetric: bool = False) -> SparseFactor:
    """A new factorization holder of ``backend`` (default: :func:`default_backend`)."""
    backend = backend or default_backend()
    if backend == "pardiso":
        return PardisoFactor(symmetric)
    if backend == "superlu":
        return SuperLUFactor(symmetric)
    raise ValueError(f"unknown sparse solver {backend!r}; choose one of {', '.join(BACKENDS)}")


class FactorSet:
    """The factorizations a solver keeps from step to step: one for symmetric systems (the
    OPEN-CLOSE passes), one for general ones (Newton's tangent), each with its own symbolic
    analysis, made on first use with ``backend`` (default: :func:`default_backend`)."""

    def __init__(self, backend: str | None = None):
        self.backend = backend or default_backend()
        self._factors: dict[bool, SparseFactor] = {}
        self._kept: dict[str, tuple] = {}

    def kept(self, name: str, key: tuple, build):
        """``build()``, or the object built last under ``name`` when ``key`` (a tuple of
        arrays or None) equals the one it was built from: the assembly's index work
        (:class:`dda.solvers.linear.SystemPattern`) stands while the step's blocks and
        contacts do."""
        last = self._kept.get(name)
        if last is not None and len(last[0]) == len(key) and all(
                _same_key(a, b) for a, b in zip(last[0], key, strict=True)):
            return last[1]
        made = build()
        self._kept[name] = (tuple(None if a is None else np.array(a, copy=True) for a in key),
                            made)
        return made

    def superset(self, name: str, n: int, needed: np.ndarray, slack: float) -> np.ndarray:
        """The sorted keys kept under ``name`` while they include every one of ``needed``
        (sorted, unique) for the same ``n`` and number at most ``slack`` times as many; else
        ``needed``, kept from now on. A sparse structure built on the keys
        (:class:`dda.solvers.linear.SystemPattern`) then stands, and the solver's analysis of
        it, while the contacts move among the block pairs it covers."""
        last = self._kept.get("superset " + name)
        if last is not None and last[0] == n and len(last[1]) <= slack * len(needed):
            kept = last[1]
            pos = np.searchsorted(kept, needed)
            if len(needed) == 0 or (pos[-1] < len(kept)
                                    and np.array_equal(kept[pos], needed)):
                return kept
        self._kept["superset " + name] = (n, needed)
        return needed

    def get(self, symmetric: bool) -> SparseFactor:
        """The factorization holder for symmetric (or general) matrices."""
        f = self._factors.get(symmetric)
        if f is None:
            f = self._factors[symmetric] = make_factor(self.backend, symmetric)
        return f

    @property
    def counts(self) -> tuple[int, int]:
        """(numeric factorizations, symbolic analyses) done so far."""
        return (sum(f.factorizations for f in self._factors.values()),
                sum(f.analyses for f in self._factors.values()))


def _same_key(a, b) -> bool:
    """Whether two parts of a :meth:`FactorSet.kept` key are equal (arrays by value; integer
    and boolean ones of one dtype by their bytes, the cheap test on a small scene's step)."""
    if a is None or b is None:
        return a is None and b is None
    if a.dtype == b.dtype and a.dtype.kind in "biu":
        return a.shape == b.shape and a.tobytes() == b.tobytes()
    return bool(np.array_equal(a, b))

