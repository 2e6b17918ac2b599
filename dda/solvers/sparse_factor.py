r"""Sparse direct solvers for the step's system, and the choice between them.

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
the same numbers to the bit (a later pass of the same step adds only the change of the
contacts whose springs changed to the last pass's, the same matrix to round-off). A
nonsymmetric matrix (Newton's tangent) goes to PARDISO as its own CSC arrays, which PARDISO
reads as the CSR of ``K^T``; it factorizes that and solves transposed (``iparm[11] = 2``), so
nothing is reordered (3 ms a factorization of the 60 x 60 stack's tangent). The
double-precision products of the refinement below take one compiled pass over the upper
triangle (:func:`dda.kernels.sparse_products.upper_symmetric_matvec`).

PARDISO's defaults refine every solution by two steps of iterative refinement, which made a
solve cost a third to a half of a factorization and left the residual where it was (about
2e-15 of the right-hand side either way): a solve of the 30 x 30 stack's system took 2.8 ms
refined and 0.83 ms not (60 x 60: 17.9 against 4.7 ms; Newton's LU, 4.8 against 1.35 ms and
21 against 5.6 ms). The solves here refine only after a factorization that perturbed pivots
(PARDISO's own rule when it is left to choose), and the residual is checked either way.

Both keep the numeric factorization of the last matrix: an OPEN-CLOSE pass that changes only
loads (the friction of sliding contacts) and not the springs solves with it again.

**Low-rank updates.** A later OPEN-CLOSE pass of the same step whose springs differ from the
factorized matrix's in at most ``LOW_RANK_TERMS`` springs (a contact that opened, closed, or
switched between stick and slip) is not factorized: its matrix comes with the change
(:attr:`UpperTriangle.change`, ``A + U diag(lam) U^T`` with a column of ``U`` per spring), and
:meth:`PardisoFactor._low_rank_solve` solves it by the Sherman-Morrison-Woodbury formula with
the factors of ``A`` (one solve with a right-hand side per spring) inside the refinement
below, whose residuals are the new matrix's, so the answer is as accurate as a new
factorization's. On the 60 x 60 stack of ``benchmarks/stacks.py`` (legacy DDA) 0.7 of 4.7
passes a step take it, and the median step went from 247-265 to 222-238 ms. Newton's
predictor uses it too (:data:`dda.solvers.newton.PREDICTOR_LOW_RANK`).

**Mixed precision.** A system of at least ``MIXED_MIN_UNKNOWNS`` unknowns is factorized by
PARDISO in single precision (its ``iparm[27]``) and its solution refined in double precision,
the residual computed from the double matrix (Wilson's iterative refinement):

.. math::

    x_0 = \tilde K^{-1} b, \qquad x_{i+1} = x_i + \tilde K^{-1} (b - K x_i),

where :math:`\tilde K^{-1}` is the solve with the single-precision factors. Each refinement
shrinks the error by about :math:`\rho \approx \kappa(K)\,\epsilon_{32}`; on the stacks'
systems (dynamic analysis: Newmark's inertia on the diagonal) the first solve is off by 4e-7 to
3e-6 of the solution and one refinement leaves 2e-13 to 8e-13 of it (the double factorization:
about 1e-15). The refinement stops when the estimated error of the new iterate,
:math:`\|\Delta x_i\|\,\rho_i` with :math:`\rho_i = \|\Delta x_i\| / \|\Delta x_{i-1}\|`,
is below ``MIXED_RTOL`` of :math:`\|x\|`, or, for a caller that needs less (a Newton correction:
``solve``'s ``atol``), once the residual :math:`\|b - K x_i\|` is within ``atol``; a
refinement that shrinks the correction by less than
``MIXED_CONTRACTION`` (an ill-conditioned matrix, a static analysis' loose block), a PARDISO
error or ``MIXED_REFINEMENTS`` refinements without convergence send the matrix back to a
double-precision factorization; when that one succeeds the holder stays in double precision
from then on (when it fails too, as for an indefinite matrix, the matrix was the trouble).
Measured on the stacks' systems, one thread: a factorization of 21,600 unknowns 50 -> 32 ms
(``L D L^T``) and 100 -> 65 ms (``L U``), of 5,400 unknowns 7.5 -> 5.2 and 16 -> 11.2 ms, of
2,400 unknowns 2.1 -> 1.5 ms. With the refinement's second solve and product, a factorization
and its solve (median of the steps' systems, both kinds) take 8.08 -> 7.15 ms at 5,400
unknowns, 2.52 -> 2.17 at 2,400, 1.74 -> 1.51 at 1,734, 0.88 -> 0.85 at 1,014 and 0.50 -> 0.52
at 600: hence ``MIXED_MIN_UNKNOWNS``. ``DDA_PARDISO_PRECISION`` (``auto``, ``double`` or
``mixed``) overrides the choice.

:func:`default_backend` picks ``pardiso`` when it can be loaded, else ``superlu``; the
environment variable ``DDA_SPARSE_SOLVER`` (``pardiso`` or ``superlu``) overrides the choice.
"""

from __future__ import annotations

import ctypes
import os

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from dda.kernels.sparse_products import upper_symmetric_matvec

__all__ = ["SparseFactor", "UpperTriangle", "SuperLUFactor", "PardisoFactor", "FactorSet",
           "default_backend", "default_precision", "make_factor", "BACKENDS", "PRECISIONS",
           "SingularSystemError"]

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

# mixed precision (module docstring): the smallest system factorized in single precision, the
# estimated error (relative to the solution) the refinement stops at, the most refinements,
# and the least shrinking of the correction a refinement must show
MIXED_MIN_UNKNOWNS = 1200
MIXED_RTOL = 1e-12
MIXED_REFINEMENTS = 4
MIXED_CONTRACTION = 1e-2
PRECISIONS = ("auto", "double", "mixed")
# a single-precision L D L^T whose matrix changed since by at most this many springs solves
# the new matrix by a low-rank (Woodbury) update of those factors instead of a new
# factorization (PardisoFactor._low_rank_solve); LOW_RANK False: never
LOW_RANK = True
LOW_RANK_TERMS = 16


class SingularSystemError(RuntimeError):
    """The step's matrix is singular (a block with no support in a static analysis)."""


class UpperTriangle:
    """A symmetric matrix given by its upper triangle, ``csr`` (CSR, sorted indices): what
    PARDISO reads for a symmetric matrix, assembled in that layout by
    :meth:`dda.solvers.linear.SystemPattern.upper_matrix`.

    ``change``, when known, is ``(base, rows, u, lam)``: this matrix is the one whose
    upper-triangle data is the array ``base`` plus ``P u diag(lam) u^T P^T``, with ``P`` the
    unknowns ``rows`` (those of the contacts whose springs changed since the last OPEN-CLOSE
    pass; ``u`` one column per changed spring), which a factorization of ``base`` takes as a
    low-rank update (:meth:`PardisoFactor.solve`)."""

    __slots__ = ("csr", "change")

    def __init__(self, csr: sp.csr_matrix, change: tuple | None = None):
        self.csr = csr
        self.change = change

    @property
    def shape(self):
        return self.csr.shape

    def __matmul__(self, x):
        u = self.csr
        x = np.asarray(x)
        if x.ndim == 1 and u.dtype == np.float64:  # one compiled pass over the data
            return upper_symmetric_matvec(u.indptr, u.indices, u.data,
                                          np.ascontiguousarray(x, dtype=np.float64))
        # K x = (U + U^T - diag(U)) x
        diagonal = u.diagonal()
        return u @ x + u.T @ x - (diagonal if x.ndim == 1 else diagonal[:, None]) * x

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
    # whether a solve may update the last factorization by a low-rank change of the matrix
    # instead of factorizing it (a backend that can: PardisoFactor)
    low_rank = True

    def __init__(self, symmetric: bool = False):
        self.symmetric = symmetric
        self.factorizations = 0  # numeric factorizations done
        self.analyses = 0  # symbolic analyses done
        self.near_solves = 0  # solves by GMRES with an earlier factorization (solve_near)

    def solve(self, k: sp.csc_matrix, rhs: np.ndarray, atol: float | None = None) -> np.ndarray:
        """Solve ``k x = rhs``. ``atol``: the residual ``|rhs - k x|`` (2-norm) the caller
        accepts; a backend that refines its solution (PARDISO's mixed precision) may stop
        once it is there (an inexact Newton step). None: as accurate as it can."""
        raise NotImplementedError

    def solve_near(self, k, rhs: np.ndarray, atol: float | None = None) -> np.ndarray:
        """Solve ``k x = rhs`` for a ``k`` close to the matrix factorized last (a later Newton
        iteration's tangent): GMRES preconditioned by that factorization, which converges in
        a few iterations where the two matrices differ by little; :meth:`solve` (a new
        factorization) when there is none of the same pattern, or GMRES has not brought the
        residual to ``NEAR_RTOL`` of the right-hand side (or to ``atol``, when that is
        larger; :meth:`solve`) in ``NEAR_ITERATIONS``.

        On the 30 x 30 stack of ``benchmarks/stacks.py`` a Newton iteration's tangent after
        the step's first took 2 to 4 iterations to 1e-10 with the first one's ``L U``; a new
        ``L U`` of the 60 x 60 stack's costs 79 ms, a solve with it 7.5 ms.
        """
        apply = self._last_inverse(k)
        if apply is not None:
            n = k.shape[0]
            b = np.asarray(rhs, dtype=float)
            m = spla.LinearOperator((n, n), matvec=apply, dtype=float)
            target = max(NEAR_RTOL * float(np.linalg.norm(b)), atol or 0.0)
            x, _ = spla.gmres(k, b, M=m, rtol=0.0, atol=target, restart=NEAR_ITERATIONS,
                              maxiter=1)
            if np.all(np.isfinite(x)) and np.linalg.norm(k @ x - b) <= target:
                self.near_solves += 1
                return x
        return self.solve(k, rhs, atol)

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

    def solve(self, k, rhs, atol=None):
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


def _same_array(held: np.ndarray, given: np.ndarray) -> bool:
    """Whether ``given`` holds what ``held`` does: the same array object (the assembly's
    pattern arrays, kept across passes and steps; a matrix's data solved again), or equal
    entries. A factorization holds the arrays it was given, not copies (a copy and a
    comparison of the 60 x 60 stack's 1.1 million entries cost about 1 ms a solve): the
    matrices given to :meth:`SparseFactor.solve` are not changed in place afterwards (the
    assembly builds each matrix's data anew)."""
    return held is given or np.array_equal(held, given)


def _small_residual(k, sol, rhs) -> bool:
    scale = max(float(np.abs(rhs).max(initial=0.0)), 1e-300)
    return bool(np.all(np.isfinite(sol))
                and np.abs(k @ sol - rhs).max(initial=0.0) <= RESIDUAL_RTOL * scale)


class PardisoFactor(SparseFactor):
    """MKL PARDISO (see the module docstring): ``L D L^T`` of a symmetric matrix (type 2,
    positive definite), ``L U`` otherwise (type 11), the symbolic analysis kept while the
    pattern stands; a large system in single precision with its solution refined in double
    (``precision``: "auto", "double" or "mixed", default :func:`default_precision`).

    A matrix PARDISO refuses (not positive definite, a zero pivot) or whose solution leaves a
    residual above ``RESIDUAL_RTOL`` is solved again by SuperLU, so the answer never depends on
    which backend could be loaded. A single-precision solution is checked by its refinement
    instead: each refinement must shrink the correction ``MIXED_CONTRACTION`` times, and the
    last one leave an estimated error below ``MIXED_RTOL`` of the solution; else the matrix
    is factorized again in double precision.
    """

    name = "pardiso"

    def __init__(self, symmetric: bool = False, precision: str | None = None):
        super().__init__(symmetric)
        self.reads_upper = symmetric
        self.precision = _checked_precision(precision or default_precision())
        self._solver = _pardiso_solver(mtype=2 if symmetric else 11)
        self._pattern = None  # (indptr, indices) of the analysed matrix (PARDISO's CSR)
        self._index = None  # ... 1-based, as PARDISO reads them
        self._single = False  # whether the analysis (and the factors) are single precision
        self._used = False  # whether PARDISO holds memory under the handle
        self._csr = None  # (CSC -> CSR data order, indptr, indices) of the last pattern
        self._values = None  # the values of the matrix factorized last
        self._factored = None  # ... and the matrix (an UpperTriangle, or the CSC given)
        self._data = None  # ... its values as PARDISO was given them (float32 or float64)
        self.fallbacks = 0
        self.single_failures = 0  # single-precision factors sent back to double precision
        self._in_double = False  # solving a failed single-precision matrix again in double
        self.refinements = 0  # refinements of single-precision solutions done
        self.inexact_solves = 0  # solves stopped at the caller's residual (``atol``)
        self.low_rank_solves = 0  # solves by a low-rank update of the last factors

    def wants_single(self, n: int) -> bool:
        """Whether a system of ``n`` unknowns is factorized in single precision."""
        if self.precision == "double" or self.single_failures or self._in_double:
            return False
        return self.precision == "mixed" or n >= MIXED_MIN_UNKNOWNS

    def solve(self, k, rhs, atol=None):
        from pypardiso.pardiso_wrapper import PyPardisoError  # noqa: PLC0415

        a = k.csr if isinstance(k, UpperTriangle) else self._pardiso_matrix(k)
        single = self.wants_single(a.shape[0])
        same = (self._pattern is not None and self._single == single
                and _same_array(self._pattern[0], a.indptr)
                and _same_array(self._pattern[1], a.indices))
        b = np.ascontiguousarray(rhs, dtype=float).reshape(-1, 1)
        try:
            if not same:
                self._analyse(a, single)
            if (same and single and LOW_RANK and self.low_rank and self.symmetric
                    and self._values is not None
                    and isinstance(k, UpperTriangle) and k.change is not None
                    and k.change[0] is self._values):
                if not np.all(np.isfinite(b)):
                    return np.full(len(b), np.nan)
                sol = self._low_rank_solve(k, b.reshape(-1), *k.change[1:], atol=atol)
                if sol is not None:
                    return sol
            if not (same and self._values is not None and _same_array(self._values, a.data)):
                self._values = None
                data = a.data.astype(np.float32) if single else a.data
                self._call(22, data, b)
                self.factorizations += 1
                # refine the solutions only where PARDISO's own rule would need it: after a
                # factorization that perturbed pivots (iparm[13] counts them); the single
                # precision factors are refined here, in double precision
                self._solver.iparm[7] = 2 if (self._solver.iparm[13] > 0 and not single) else 0
                self._values = a.data
                self._factored = UpperTriangle(a) if self.symmetric else k
                self._data = data
            if single:
                if not np.all(np.isfinite(b)):  # no answer, whatever the factors
                    return np.full(len(b), np.nan)
                sol = self._refined(k, b.reshape(-1), atol=atol)
                if sol is None:
                    return self._in_double_precision(k, rhs)
                return sol
            sol = self._call(33, self._data, b).reshape(-1)
        except PyPardisoError:
            self._pattern = self._values = None
            if single:  # PARDISO refused the single-precision factors
                return self._in_double_precision(k, rhs)
            sol = None
        if sol is not None and _small_residual(k, sol, rhs):
            return sol
        self.fallbacks += 1
        return superlu_solve(k.full() if isinstance(k, UpperTriangle) else k, rhs)

    def _in_double_precision(self, k, rhs):
        """The matrix whose single-precision factors failed, factorized in double precision;
        the holder stays in double precision from then on when that succeeds (when it does
        not either, as for an indefinite matrix, the matrix was the trouble, not the
        precision)."""
        self._pattern = self._values = None
        fallbacks = self.fallbacks
        self._in_double = True
        try:
            sol = self.solve(k, rhs)
        finally:
            self._in_double = False
        if self.fallbacks == fallbacks:
            self.single_failures += 1
        return sol

    def _refined(self, k, b: np.ndarray, apply=None,
                 atol: float | None = None) -> np.ndarray | None:
        """The solution of ``k x = b`` from the single-precision factors (or the approximate
        inverse ``apply``), refined in double precision (module docstring); None when the
        refinement does not converge. With ``atol``, an iterate whose residual
        ``|b - k x|`` (in double precision) is at most ``atol`` is returned as it is."""
        apply = apply or self._apply
        x = apply(b)
        last = float(np.linalg.norm(x))
        if not np.isfinite(last):
            return None
        for i in range(MIXED_REFINEMENTS):
            r = b - k @ x
            if atol is not None and float(np.linalg.norm(r)) <= atol:
                self.refinements += i
                self.inexact_solves += 1
                return x
            dx = apply(r)
            x = x + dx
            step = float(np.linalg.norm(dx))
            if not np.isfinite(step):
                return None
            rho = step / last if last > 0.0 else 0.0
            if rho > MIXED_CONTRACTION:
                return None
            if step * rho <= MIXED_RTOL * float(np.linalg.norm(x)):
                self.refinements += i + 1
                return x
            last = step
        return None

    def _low_rank_solve(self, k: UpperTriangle, b: np.ndarray, rows: np.ndarray,
                        u: np.ndarray, lam: np.ndarray, atol: float | None = None):
        r"""Solve the symmetric ``k x = b`` with the factors of the matrix ``A`` factorized
        last, where ``k = A + U \Lambda U^T`` (``U`` zero but in the rows ``rows``, where it
        is ``u``; ``\Lambda = diag(lam)``, the changed springs): the Sherman-Morrison-
        Woodbury formula

        .. math::

            Z = A^{-1} U, \qquad
            k^{-1} v = A^{-1} v - Z (\Lambda^{-1} + U^T Z)^{-1} U^T A^{-1} v,

        as the approximate inverse of :meth:`_refined`, whose residuals are those of ``k``
        itself. ``Z`` is one solve with a right-hand side per changed spring. On the
        60 x 60 stack's 21,600 unknowns 8 right-hand sides take 6.4 ms, 16 take 12 ms, and a
        factorization 32 ms. None (then ``k`` is factorized) when the update is singular or
        the refinement does not converge."""
        if len(lam) == 0:
            return self._refined(k, b, atol=atol)
        full = np.zeros((len(b), len(lam)))
        full[rows] = u
        z = self._apply_many(full)
        try:
            inverse = np.linalg.inv(np.diag(1.0 / lam) + u.T @ z[rows])
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(inverse)):
            return None

        def apply(v):
            y = self._apply(v)
            return y - z @ (inverse @ (u.T @ y[rows]))

        sol = self._refined(k, b, apply, atol)
        if sol is not None:
            self.low_rank_solves += 1
        return sol

    def _apply_many(self, v: np.ndarray) -> np.ndarray:
        """:meth:`_apply` of the columns of ``v`` (n, r) in one solve."""
        top = float(np.abs(v).max(initial=0.0))
        scale = float(np.ldexp(1.0, np.frexp(top)[1])) if top > 0.0 else 1.0
        b = np.asfortranarray(v / scale, dtype=self._data.dtype)
        return scale * self._call(33, self._data, b).astype(float, copy=False)

    def _apply(self, v: np.ndarray) -> np.ndarray:
        """A solve with the factors held (in their precision), the answer in double. A
        right-hand side for single-precision factors is scaled to a largest entry near 1
        first: a refinement's residual of 1e-40 would otherwise round to zero (and one
        beyond 3e38 overflow)."""
        v = np.asarray(v, dtype=float).reshape(-1)
        scale = 1.0
        if self._data.dtype == np.float32:
            top = float(np.abs(v).max(initial=0.0))
            if top == 0.0:
                return np.zeros_like(v)
            if np.isfinite(top):  # a power of two: the scaling itself rounds nothing
                scale = float(np.ldexp(1.0, np.frexp(top)[1]))
        b = np.ascontiguousarray(v / scale, dtype=self._data.dtype).reshape(-1, 1)
        return scale * self._call(33, self._data, b).reshape(-1).astype(float, copy=False)

    def _call(self, phase: int, data: np.ndarray, b: np.ndarray) -> np.ndarray:
        """PARDISO's one entry point on the analysed pattern (``self._index``), with the
        matrix values ``data`` and right-hand side ``b`` in the precision of the analysis
        (pypardiso's own call reads double precision only)."""
        from pypardiso.pardiso_wrapper import PyPardisoError  # noqa: PLC0415

        s = self._solver
        x = np.zeros_like(b)
        err = ctypes.c_int32(0)
        ia, ja = self._index
        int_p = ctypes.POINTER(ctypes.c_int32)
        s._mkl_pardiso(
            s.pt.ctypes.data_as(ctypes.POINTER(s._pt_type[0])), ctypes.byref(ctypes.c_int32(1)),
            ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(s.mtype)),
            ctypes.byref(ctypes.c_int32(phase)), ctypes.byref(ctypes.c_int32(len(ia) - 1)),
            data.ctypes.data_as(ctypes.c_void_p), ia.ctypes.data_as(int_p),
            ja.ctypes.data_as(int_p), s.perm.ctypes.data_as(int_p),
            ctypes.byref(ctypes.c_int32(b.shape[1])), s.iparm.ctypes.data_as(int_p),
            ctypes.byref(ctypes.c_int32(0)), b.ctypes.data_as(ctypes.c_void_p),
            x.ctypes.data_as(ctypes.c_void_p), ctypes.byref(err))
        if err.value != 0:
            raise PyPardisoError(err.value)
        return x

    def _last_inverse(self, k):
        if self._values is None or self._pattern is None:
            return None
        if isinstance(k, UpperTriangle):
            indptr, indices = k.csr.indptr, k.csr.indices
            same = (_same_array(self._pattern[0], indptr)
                    and _same_array(self._pattern[1], indices))
        elif not self.symmetric:  # the CSC arrays the analysis was of (as K^T's CSR)
            same = (_same_array(self._pattern[0], k.indptr)
                    and _same_array(self._pattern[1], k.indices))
        else:  # the CSC pattern whose upper triangle's CSR the analysis was of
            cached = self._csr
            same = cached is not None and (cached[3] is k.indptr or (
                np.array_equal(cached[3], k.indptr) and np.array_equal(cached[4], k.indices)))
        if not same:
            return None
        from pypardiso.pardiso_wrapper import PyPardisoError  # noqa: PLC0415

        # GMRES takes its preconditioner for a linear map: single-precision factors alone
        # round each answer to 1e-7 of it, which the solution GMRES puts together keeps, so
        # they are applied refined to the matrix they factorized
        factored = self._factored
        single = self._single

        def apply(v):
            try:
                x = self._refined(factored, np.asarray(v, dtype=float)) if single else \
                    self._apply(v)
            except PyPardisoError:  # GMRES then ends non-finite: solve() factorizes
                x = None
            return np.full(len(v), np.nan) if x is None else x

        return apply

    def _analyse(self, a, single: bool):
        self._pattern = self._values = None
        s = self._solver
        if self._used and single != self._single:  # the other precision's memory goes first
            self._release()
        self._index = (a.indptr.astype(np.int32) + 1, a.indices.astype(np.int32) + 1)
        if single:
            # PARDISO reads iparm[27] only from a filled array (iparm[0] = 1)
            s.iparm[:] = _default_iparm(s.mtype)
            s.iparm[0] = 1
            s.iparm[27] = 1
            data = a.data.astype(np.float32)
        else:
            if not self._used:
                s.iparm[0] = 0
            s.iparm[27] = 0
            data = a.data
        self._single = single
        self._used = True
        self._call(11, data, np.zeros((a.shape[0], 1), dtype=data.dtype))
        self.analyses += 1
        # the analysis has filled iparm with PARDISO's defaults; from here on PARDISO reads
        # them from the array (iparm[0] = 1), so a solve's refinement can be turned off
        s.iparm[0] = 1
        # a nonsymmetric matrix is given as its transpose (_pardiso_matrix): solve with it
        # transposed
        s.iparm[11] = 0 if self.symmetric else 2
        self._pattern = (a.indptr, a.indices)

    def _release(self):
        """Free the memory PARDISO holds under the handle (its phase -1)."""
        from pypardiso.pardiso_wrapper import PyPardisoError  # noqa: PLC0415

        self._index = (np.zeros(1, dtype=np.int32) + 1, np.zeros(0, dtype=np.int32))
        dtype = np.float32 if self._single else np.float64
        try:
            self._call(-1, np.zeros(0, dtype=dtype), np.zeros((0, 1), dtype=dtype))
        except PyPardisoError:
            pass
        self._used = False

    def _pardiso_matrix(self, k):
        """The matrix as PARDISO reads it: CSR with sorted indices, and for type 2 its upper
        triangle only. A nonsymmetric matrix's CSC arrays are the CSR arrays of its
        transpose, which PARDISO factorizes and solves transposed (``iparm[11] = 2``, set
        by :meth:`_analyse`): no reordering. For type 2 the CSC data are put in row order
        by a permutation that depends on the pattern alone (worked out once per pattern)."""
        if k.format != "csc":
            k = k.tocsc()
        if not k.has_sorted_indices:
            k = k.copy()
            k.sort_indices()
        if not self.symmetric:
            return sp.csr_matrix((k.data, k.indices, k.indptr), shape=k.shape)
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


def default_precision() -> str:
    """``DDA_PARDISO_PRECISION`` if set (``auto``, ``double`` or ``mixed``), else ``auto``:
    single-precision factors with double-precision refinement from ``MIXED_MIN_UNKNOWNS``
    unknowns (module docstring)."""
    return _checked_precision(os.environ.get("DDA_PARDISO_PRECISION", "").strip().lower()
                              or "auto")


def _checked_precision(name: str) -> str:
    if name not in PRECISIONS:
        raise ValueError(f"DDA_PARDISO_PRECISION must be one of {', '.join(PRECISIONS)}, "
                         f"got {name!r}")
    return name


_DEFAULT_IPARM: dict[int, np.ndarray] = {}


def _default_iparm(mtype: int) -> np.ndarray:
    """PARDISO's default parameters for matrix type ``mtype``, as its analysis of a 1 x 1
    matrix fills them in (``iparm[0] = 0``)."""
    got = _DEFAULT_IPARM.get(mtype)
    if got is None:
        s = _pardiso_solver(mtype)
        a = sp.csr_matrix(np.ones((1, 1)))
        s.set_phase(11)
        s._call_pardiso(a, np.ones((1, 1)))
        got = _DEFAULT_IPARM[mtype] = s.iparm.copy()
        s.free_memory(everything=True)
    return got


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

    def kept_superset(self, name: str, n: int) -> np.ndarray | None:
        """The sorted keys :meth:`superset` keeps under ``name`` for ``n``, or None."""
        last = self._kept.get("superset " + name)
        return last[1] if last is not None and last[0] == n else None

    def get(self, symmetric: bool) -> SparseFactor:
        """The factorization holder for symmetric (or general) matrices."""
        f = self._factors.get(symmetric)
        if f is None:
            f = self._factors[symmetric] = make_factor(self.backend, symmetric)
        return f

    @property
    def refinements(self) -> int:
        """Refinements of solutions from single-precision factors done so far (none: every
        system was factorized in double precision)."""
        return sum(getattr(f, "refinements", 0) for f in self._factors.values())

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

