"""One assembly and one solve of the step's linear system (6x6 blocks).

Blocks whose motion is known carry no unknowns: the contact terms that couple them to a free
block go to the right-hand side. Small systems are solved dense (LAPACK), larger ones by a
sparse direct solver (:mod:`dda.solvers.sparse_factor`: MKL PARDISO or SuperLU); the switch is
at ``DENSE_LIMIT`` unknowns (measured in benchmarks/).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from dda.kernels.assembly import (
    add_pair_vectors,
    matrix_data,
    rhs_data,
    upper_data,
    upper_update,
)
from dda.kernels.pair_stiffness import PairStiffness
from dda.kernels.pattern import entry_positions
from dda.profiling import count_solve, section
from dda.solvers import sparse_factor
from dda.solvers.sparse_factor import (
    SingularSystemError,
    SparseFactor,
    UpperTriangle,
    make_factor,
)

__all__ = ["assemble_and_solve", "assemble_vector", "SystemPattern", "DENSE_LIMIT",
           "SingularSystemError"]

DENSE_LIMIT = 300
#: whether the symmetric matrix of an OPEN-CLOSE pass is summed as the last pass's plus the
#: change of the contacts whose springs changed (:meth:`SystemPattern.upper_matrix`) ...
INCREMENTAL_UPPER = True
#: ... when at most this share of the contacts changed (else summed whole)
INCREMENTAL_SHARE = 0.25
# a kept sparse structure is given up when it has more than this many times the block entries
# the step's contacts need (the explicit zeros cost fill and time)
STRUCTURE_SLACK = 2.0

_I6, _J6 = np.meshgrid(np.arange(6), np.arange(6), indexing="ij")


class SystemPattern:
    """Where every block and contact entry goes in the step's matrix and right-hand side.

    The blocks with unknowns and the contacts' block pairs do not change within a step, so
    the index work of the assembly (slots, masks, the sorted sparse structure) is done once
    per step and every OPEN-CLOSE pass or Newton iteration only sums values into place (in
    compiled code when the contacts' stiffness comes as a :class:`dda.kernels.PairStiffness`).

    Parameters
    ----------
    free : (n_blocks,) bool, blocks with unknowns
    bj, bk : (m,) the two blocks of each contact
    rigid : (n_blocks,) bool, optional
        Blocks without strain: their three strain rows and columns are left out of the
        system (``unknowns`` counts what is solved for).
    cache : FactorSet, optional
        Keeps a sparse system's structure from step to step (see below).

    A sparse solver analyses the structure of a matrix (its fill-reducing ordering) once for
    as long as the structure stands, but on a shaken slope contacts between block pairs come
    and go from step to step (the 311-block slope of ``examples/jointed_slope.py``: an
    analysis in 56% of its legacy steps, 103% of its Newton ones). With a ``cache`` a
    sparse structure is kept while it holds every block pair in contact and has at most
    ``STRUCTURE_SLACK`` times the entries they need (the pairs no longer in contact stay in
    it as explicit zeros). Covering the pairs that may come into contact soon (the broad
    phase's) from the start cost more in fill than it saved in analyses: 28.7 against 23.7
    ms a legacy step of that slope.
    """

    def __init__(self, free, bj, bk, rigid=None, cache=None):
        n_blocks = len(free)
        slot = np.full(n_blocks, -1, dtype=np.int64)
        self._structure_keys = None  # a sparse structure's block entries, when kept
        self.free_blocks = free_blocks = np.flatnonzero(free)
        slot[free_blocks] = np.arange(len(free_blocks))
        self.n = n = 6 * len(free_blocks)
        self.n_blocks = n_blocks
        # the unknowns actually solved for: a rigid block keeps translation and rotation only
        self.keep = None
        self.unknowns = n
        if rigid is not None and np.any(rigid[free_blocks]):
            mask = np.ones((len(free_blocks), 6), dtype=bool)
            mask[rigid[free_blocks], 3:] = False
            self.keep = np.flatnonzero(mask.ravel())
            self.unknowns = len(self.keep)
        # the matrix is made of 6 x 6 blocks: index work on block entries, not scalars
        m = len(bj)
        brow, bcol = [slot[free_blocks]], [slot[free_blocks]]
        self.rhs_index = []  # per side a: (contacts whose block a is free, their rhs rows)
        self.couplings = []  # per (a, b): (a, b, both free, a free and b known, ...)
        # per side a of each contact: its block, and its first rhs row (-1: a known block)
        self.side_block = np.zeros((2, m), dtype=np.int64)
        self.side_row = np.full((2, m), -1, dtype=np.int64)
        if m:
            for a, ba in enumerate((bj, bk)):
                sa = slot[ba]
                fa = sa >= 0
                self.side_block[a] = ba
                self.side_row[a, fa] = 6 * sa[fa]
                self.rhs_index.append((fa, ((6 * sa[fa])[:, None] + np.arange(6)).ravel()))
                for b, bb in enumerate((bj, bk)):
                    sb = slot[bb]
                    both = fa & (sb >= 0)
                    brow.append(sa[both])
                    bcol.append(sb[both])
                    to_rhs = np.flatnonzero(fa & (sb < 0))
                    known = (bb[to_rhs], ((6 * sa[to_rhs])[:, None] + np.arange(6)).ravel())
                    self.couplings.append((a, b, both, to_rhs, known))
        br, bc = np.concatenate(brow), np.concatenate(bcol)
        self._blocks = (br, bc)
        self._cache = cache
        # entry (i, j) of block entry e goes to data[base[e] + i row_step + j col_step[e]]
        if n <= DENSE_LIMIT:
            self.nnz = n * n
            self.row_step = n
            base = 6 * br * n + 6 * bc
            col_step = np.ones_like(base)
        else:
            base, col_step = self._csc_layout(br, bc, len(free_blocks), cache)
        self._entry_layout = (base, col_step)
        nf = len(free_blocks)
        self.block_base, self.block_step = base[:nf], col_step[:nf]
        # per coupling (a, b) = divmod(row, 2): where each contact's block goes (-1: nowhere)
        self.pair_base = np.full((4, m), -1, dtype=np.int64)
        self.pair_step = np.zeros((4, m), dtype=np.int64)
        start = nf
        for ab, (_, _, both, _, _) in enumerate(self.couplings):
            idx = np.flatnonzero(both)
            self.pair_base[ab, idx] = base[start:start + len(idx)]
            self.pair_step[ab, idx] = col_step[start:start + len(idx)]
            start += len(idx)
        if self.keep is not None and n > DENSE_LIMIT:
            self._kept_structure()

    def _csc_layout(self, br, bc, nf, cache=None):
        """Compressed sparse columns: block entries sorted by block column, then block row;
        within block column J, scalar column 6J + j lists the 6 rows of each block in turn.
        Sets the structure and returns each block entry's base and column step.

        The structure depends on the coupled block pairs alone: with a ``cache`` (a
        :class:`dda.solvers.sparse_factor.FactorSet`) the last one is kept for the next
        steps whose contacts couple a subset of its block pairs, within
        ``STRUCTURE_SLACK`` (the same arrays, so the sparse solver sees the same pattern at
        once and keeps its analysis)."""
        keys = bc * nf + br
        if cache is None:
            ub, inverse = np.unique(keys, return_inverse=True)
            layout = self._csc_structure(ub, nf)
        else:
            found = self._in_kept_structure(cache, nf, br, bc)
            if found is not None:  # the kept structure holds every entry (the common step)
                ub, inverse = found
            else:
                ub = cache.superset("csc", nf, np.unique(keys), STRUCTURE_SLACK)
                inverse = np.searchsorted(ub, keys)
            self._structure_keys = ub
            layout = cache.kept("csc", (np.array([nf]), ub),
                                lambda: self._csc_structure(ub, nf))
        self.nnz, self.indices, self.indptr, base, step = layout
        self.row_step = 1
        return base[inverse], step[inverse]

    @staticmethod
    def _in_kept_structure(cache, nf, br, bc):
        """``(keys, positions)`` of the kept structure when it holds every block entry
        ``(br, bc)`` and has at most ``STRUCTURE_SLACK`` times the entries they need (what
        :meth:`FactorSet.superset` would keep, and where each entry lies in it: the same as
        ``numpy.searchsorted``), found column by column; None otherwise."""
        kept = cache.kept_superset("csc", nf)
        if kept is None or len(br) == 0:
            return None
        rows, ptr = cache.kept("csc columns", (np.array([nf]), kept), lambda: (
            kept % nf, np.concatenate([[0], np.cumsum(np.bincount(kept // nf, minlength=nf))])))
        pos = entry_positions(ptr, rows, bc, br)
        if pos.min() < 0:
            return None
        used = np.zeros(len(kept), dtype=bool)
        used[pos] = True
        if len(kept) > STRUCTURE_SLACK * np.count_nonzero(used):
            return None
        return kept, pos

    @staticmethod
    def _csc_structure(ub, nf):
        """(nnz, indices, indptr, base, column step) of the unique block entries ``ub``
        (column * nf + row, sorted)."""
        ucol, urow = ub // nf, ub % nf
        count = np.bincount(ucol, minlength=nf)
        bptr = np.concatenate([[0], np.cumsum(count)])
        rank = np.arange(len(ub)) - bptr[ucol]
        nnz = 36 * len(ub)
        base = 36 * bptr[ucol] + 6 * rank
        step = 6 * count[ucol]
        pos = base[:, None, None] + _J6 * step[:, None, None] + _I6
        indices = np.empty(nnz, dtype=np.int32)
        indices[pos.reshape(-1)] = (6 * urow[:, None, None] + _I6 + 0 * _J6).reshape(-1)
        col_start = 36 * bptr[:-1][:, None] + np.arange(6)[None, :] * 6 * count[:, None]
        indptr = np.append(col_start.reshape(-1), nnz).astype(np.int32)
        return nnz, indices, indptr, base, step

    def _kept_structure(self):
        """The CSC structure of the unknowns (rigid blocks' strain rows and columns left
        out): which data entries stay, their rows and the columns' starts."""
        kept = np.zeros(self.n, dtype=bool)
        kept[self.keep] = True
        col = np.repeat(np.arange(self.n), np.diff(self.indptr))
        self._take = np.flatnonzero(kept[self.indices] & kept[col])
        renumber = np.cumsum(kept) - 1
        self._kept_indices = renumber[self.indices[self._take]].astype(np.int32)
        count = np.bincount(renumber[col[self._take]], minlength=self.unknowns)
        self._kept_indptr = np.concatenate([[0], np.cumsum(count)]).astype(np.int32)

    def matrix(self, block_k, pair_k):
        """The matrix of the unknowns: dense up to ``DENSE_LIMIT`` unknowns, else CSC.

        ``pair_k`` is the contacts' (m, 12, 12) stiffness, or a
        :class:`dda.kernels.PairStiffness`, which is summed in compiled code without building
        the array (the same matrix).
        """
        if isinstance(pair_k, PairStiffness):
            data = matrix_data(self.nnz, self.row_step, self.block_base, self.block_step,
                               np.ascontiguousarray(block_k, dtype=np.float64),
                               self.free_blocks, self.pair_base, self.pair_step, pair_k.rows,
                               pair_k.terms, pair_k.weights)
        else:
            data = self._full_data(block_k, pair_k)
        n = self.n
        if n <= DENSE_LIMIT:
            k = data.reshape(n, n)
            return k if self.keep is None else k[np.ix_(self.keep, self.keep)]
        if self.keep is None:
            return sp.csc_matrix((data, self.indices, self.indptr), shape=(n, n))
        return sp.csc_matrix((data[self._take], self._kept_indices, self._kept_indptr),
                             shape=(self.unknowns, self.unknowns))

    def upper_matrix(self, block_k, pair_k) -> UpperTriangle | None:
        """The matrix of the unknowns as its upper triangle in CSR (what PARDISO reads for a
        symmetric matrix), assembled straight into that layout: half the sums of
        :meth:`matrix`, no reordering, and every entry the bits :meth:`matrix` gives it.
        None where this path does not apply (a dense system, rigid blocks, or contact
        stiffness given as an array): use :meth:`matrix`.

        A later call with the same blocks' matrices and contact rows (the next OPEN-CLOSE
        pass of the step) in which at most ``INCREMENTAL_SHARE`` of the contacts' weights
        changed returns the last matrix plus their change,
        ``K' = K + sum_c sum_t (w'_ct - w_ct) r_c,u(t) r_c,v(t)^T``
        (:func:`dda.kernels.assembly.upper_update`; the matrix is linear in the weights): the
        same matrix to round-off, not to the bit. On the 60 x 60 stack of
        ``benchmarks/stacks.py`` a legacy pass's assembly went from 8.5 to 5.9 ms."""
        if (self.n <= DENSE_LIMIT or self.keep is not None
                or not isinstance(pair_k, PairStiffness)):
            return None
        nnz, indptr, indices, block, pair = self._upper_layout
        weights = pair_k.weights
        last = self.__dict__.get("_last_upper")
        data = change = None
        if (INCREMENTAL_UPPER and last is not None and last[0] is block_k
                and last[1] is pair_k.rows and last[2] is pair_k.terms
                and last[3].shape == weights.shape):
            # the same step's blocks and contacts: only the contacts whose springs changed
            # (an OPEN-CLOSE pass switches a few) are summed again, as a change of the last
            changed = np.flatnonzero((weights != last[3]).any(axis=1))
            if len(changed) <= INCREMENTAL_SHARE * len(weights):
                data = upper_update(last[4].copy(), pair[0], pair[1], pair[2], pair_k.rows,
                                    pair_k.terms, weights - last[3], changed)
                change = self._low_rank_change(last[4], pair_k, weights - last[3], changed)
        if data is None:
            data = upper_data(nnz, block[0], block[1],
                              np.ascontiguousarray(block_k, dtype=np.float64),
                              self.free_blocks, pair[0], pair[1], pair[2], pair_k.rows,
                              pair_k.terms, weights)
        k = UpperTriangle(sp.csr_matrix((data, indices, indptr), shape=(self.n, self.n)),
                          change)
        if INCREMENTAL_UPPER:
            self.__dict__["_last_upper"] = (block_k, pair_k.rows, pair_k.terms, weights.copy(),
                                            k.csr.data)
        return k

    def _low_rank_change(self, base, pair_k, delta, changed):
        """The change from the matrix whose upper-triangle data is ``base`` as
        ``(base, rows, u, lam)``: ``Delta = P u diag(lam) u^T P^T`` with ``P`` the unknowns
        ``rows``, one column of ``u`` per changed weight ``lam`` of a term that pairs a row with
        itself (a legacy spring: ``lam r r^T``). None when a changed term pairs two rows
        or more terms changed than ``sparse_factor.LOW_RANK_TERMS``."""
        terms = pair_k.terms
        d = delta[changed]
        c_idx, t_idx = np.nonzero(d)
        if (len(c_idx) > sparse_factor.LOW_RANK_TERMS
                or np.any(terms[t_idx, 0] != terms[t_idx, 1])):
            return None
        contacts = changed[c_idx]
        start = self.side_row[:, contacts]  # (2, r): each side's first unknown, or -1
        rows = np.unique(start[start >= 0])
        rows = (rows[:, None] + np.arange(6)).reshape(-1)
        u = np.zeros((len(rows), len(contacts)))
        vec = pair_k.rows[contacts, terms[t_idx, 0]]  # (r, 12)
        col = np.arange(len(contacts))
        for a in range(2):
            has = start[a] >= 0
            at = np.searchsorted(rows, start[a, has])
            for i in range(6):
                u[at + i, col[has]] = vec[has, 6 * a + i]
        return base, rows, u, d[c_idx, t_idx]

    @cached_property
    def _upper_layout(self):
        """(nnz, indptr, indices, (start, count) per free block, (start, count, rank) per
        contact coupling) of the upper-triangle CSR (:func:`dda.kernels.assembly.upper_data`).
        """
        br, bc = self._blocks
        nf = len(self.free_blocks)
        if self._structure_keys is None:
            ub = np.unique((br * nf + bc)[br < bc])
        else:  # the kept structure's upper entries (row * nf + column)
            keys = self._structure_keys
            ub = self._cache.kept("upper keys", (np.array([nf]), keys),
                                  lambda: _upper_keys(keys, nf))
        if self._cache is None:
            structure = self._upper_structure(ub, nf)
        else:
            structure = self._cache.kept("upper", (np.array([nf]), ub),
                                         lambda: self._upper_structure(ub, nf))
        nnz, indptr, indices, start, count = structure
        # each block entry's place: its row's start and count, and its rank right of the
        # diagonal (-1 on it); entries below the diagonal go nowhere
        e_start = np.where(br <= bc, start[br], -1)
        e_count = count[br]
        e_rank = np.full(len(br), -1, dtype=np.int64)
        up = np.flatnonzero(br < bc)
        row_ptr = np.concatenate([[0], np.cumsum(count)])
        e_rank[up] = entry_positions(row_ptr, ub % nf, br[up], bc[up]) - row_ptr[br[up]]
        pair = np.full((3, 4, len(self.side_row[0])), -1, dtype=np.int64)
        pair[1] = 0
        first = nf
        for ab, (_, _, both, _, _) in enumerate(self.couplings):
            idx = np.flatnonzero(both)
            sel = slice(first, first + len(idx))
            pair[0, ab, idx], pair[1, ab, idx], pair[2, ab, idx] = (
                e_start[sel], e_count[sel], e_rank[sel])
            first += len(idx)
        block = (e_start[:nf], e_count[:nf])
        return nnz, indptr, indices, block, pair

    @staticmethod
    def _upper_structure(ub, nf):
        """(nnz, indptr, indices, row start, row count) of the upper-triangle CSR whose
        blocks right of the diagonal are ``ub`` (row * nf + column, sorted)."""
        urow, ucol = ub // nf, ub % nf
        count = np.bincount(urow, minlength=nf)
        size = 21 + 36 * count  # a row of blocks: the diagonal's upper triangle, then 6 x 6
        start = np.concatenate([[0], np.cumsum(size)[:-1]])
        nnz = int(size.sum())
        i = np.arange(6)
        row_start = start[:, None] + 6 * i * count[:, None] + 6 * i - i * (i - 1) // 2
        indptr = np.append(row_start.reshape(-1), nnz).astype(np.int32)
        indices = np.empty(nnz, dtype=np.int32)
        for ii in range(6):  # the diagonal blocks: columns 6P + ii..6P + 5 of row 6P + ii
            for j in range(ii, 6):
                indices[row_start[:, ii] + j - ii] = 6 * np.arange(nf) + j
        rank = np.arange(len(ub)) - np.concatenate([[0], np.cumsum(count)])[urow]
        for ii in range(6):  # the blocks right of it, in column order
            base = row_start[urow, ii] + 6 - ii + 6 * rank
            for j in range(6):
                indices[base + j] = 6 * ucol + j
        return nnz, indptr, indices, start, count

    def reduce(self, vector):
        """The entries of a free blocks' vector (6 per block) that are unknowns."""
        return vector if self.keep is None else vector[self.keep]

    def expand(self, solution):
        """The free blocks' increments (6 per block) from the unknowns (zero strain of a
        rigid block)."""
        if self.keep is None:
            return solution
        out = np.zeros(self.n)
        out[self.keep] = solution
        return out

    @cached_property
    def _entry_positions(self):
        """Where each value of the numpy assembly goes in the data (block entries, 36 each)."""
        base, col_step = self._entry_layout
        return (base[:, None, None] + _I6 * self.row_step
                + _J6 * col_step[:, None, None]).reshape(-1)

    def _full_data(self, block_k, pair_k):
        """The matrix's data from (m, 12, 12) ``pair_k`` in numpy (the reference)."""
        vals = [block_k[self.free_blocks].reshape(-1)]
        for a, b, both, _, _ in self.couplings:
            vals.append(pair_k[both, 6 * a:6 * a + 6, 6 * b:6 * b + 6].reshape(-1))
        return np.bincount(self._entry_positions, weights=np.concatenate(vals),
                           minlength=self.nnz)

    def rhs(self, block_f, pair_k, pair_f, d_known):
        """The free blocks' right-hand side; contacts with a known block move its increment
        (times the coupling) to this side (compiled for a :class:`PairStiffness`)."""
        rhs = block_f[self.free_blocks].reshape(-1).copy()
        if isinstance(pair_k, PairStiffness):
            return rhs_data(rhs, self.side_row, self.side_block,
                            np.ascontiguousarray(pair_f, dtype=np.float64),
                            np.ascontiguousarray(d_known, dtype=np.float64), pair_k.rows,
                            pair_k.terms, pair_k.weights)
        for a, (fa, index) in enumerate(self.rhs_index):
            rhs += np.bincount(index, weights=pair_f[fa, 6 * a:6 * a + 6].reshape(-1),
                               minlength=self.n)
        for a, b, _, to_rhs, (known_block, index) in self.couplings:
            if len(to_rhs):
                sub = pair_k[to_rhs, 6 * a:6 * a + 6, 6 * b:6 * b + 6]
                load = np.einsum("mij,mj->mi", sub, d_known[known_block])
                rhs -= np.bincount(index, weights=load.reshape(-1), minlength=self.n)
        return rhs


def _upper_keys(keys, nf):
    """The upper entries (row * nf + column, sorted) of a CSC structure's block keys
    (column * nf + row)."""
    col, row = np.divmod(keys, nf)
    return np.sort((row * nf + col)[row < col])


def assemble_and_solve(block_k, block_f, free, bj, bk, pair_k, pair_f, d_known, pattern=None,
                       rigid=None, factor: SparseFactor | None = None, near: bool = False,
                       atol: float | None = None):
    """Assemble and solve ``K d = F`` for the free blocks.

    Parameters
    ----------
    block_k : (n_blocks, 6, 6) effective block matrices (stiffness, inertia, constraints)
    block_f : (n_blocks, 6) effective block forces
    free : (n_blocks,) bool, blocks with unknowns
    bj, bk : (m,) the two blocks of each contact
    pair_k : PairStiffness or (m, 12, 12) array, contact stiffness on [d_j; d_k]
        (:class:`dda.kernels.PairStiffness`, the rank-one terms the contact element gives,
        takes the compiled assembly; an array takes the numpy path)
    pair_f : (m, 12) contact forces on [d_j; d_k]
    d_known : (n_blocks, 6) increments of the blocks whose motion is known
    pattern : SystemPattern, optional
        The index work for (free, bj, bk, rigid), when it is reused (built here otherwise).
    rigid : (n_blocks,) bool, optional
        Blocks without strain unknowns (used when the pattern is built here).
    factor : SparseFactor, optional
        Who factorizes a sparse system (and may keep its symbolic analysis for the next one
        with the same pattern): :meth:`dda.solvers.StepProblem.factor`. A one-off holder of
        the default backend when None.
    near : bool
        The matrix is close to the one ``factor`` factorized last (a later Newton iteration
        of the same step): a sparse system is solved by :meth:`SparseFactor.solve_near`
        (GMRES preconditioned by that factorization, a new one only when it does not
        converge at once).
    atol : float, optional
        The residual ``|F - K d|`` (2-norm over the free unknowns) the solution may leave:
        a refined sparse solve stops there (Newton's correction needs no more than its own
        tolerance; :meth:`SparseFactor.solve`). None: as accurate as the solver gets.

    Returns
    -------
    d : (n_blocks, 6), the free blocks solved and the known ones as given
    """
    with section("assembly"):
        if pattern is None:
            pattern = SystemPattern(free, bj, bk, rigid)
        d = d_known.copy()
        if pattern.unknowns == 0:
            return d
        k = None
        if factor is not None and factor.reads_upper:
            k = pattern.upper_matrix(block_k, pair_k)
        if k is None:
            k = pattern.matrix(block_k, pair_k)
        rhs = pattern.reduce(pattern.rhs(block_f, pair_k, pair_f, d_known))
    with section("solve"):
        count_solve()
        sol = _solve(k, rhs, factor, near, atol)
    d[pattern.free_blocks] = pattern.expand(sol).reshape(-1, 6)
    return d


def _solve(k, rhs, factor: SparseFactor | None, near: bool = False,
           atol: float | None = None):
    """Dense LAPACK for an ndarray; a sparse matrix goes to ``factor`` (a one-off holder of
    the default backend when None, :mod:`dda.solvers.sparse_factor`), by
    :meth:`SparseFactor.solve_near` when ``near``, with the residual ``atol`` it may stop at
    (:meth:`SparseFactor.solve`)."""
    if isinstance(k, np.ndarray):
        try:
            sol = np.linalg.solve(k, rhs)
        except np.linalg.LinAlgError as exc:
            raise SingularSystemError(str(exc)) from None
    else:
        factor = factor or make_factor()
        sol = factor.solve_near(k, rhs, atol) if near else factor.solve(k, rhs, atol)
    if not np.all(np.isfinite(sol)):
        raise SingularSystemError("the step's system has no finite solution")
    return sol


def assemble_vector(block_f, free, bj, bk, pair_f, rigid=None):
    """Add per-contact vectors (m, 12) on [d_j; d_k] to per-block vectors (n_blocks, 6).

    Rows of blocks without unknowns are set to zero (their forces are reactions), and so are
    the strain rows of ``rigid`` blocks.
    """
    with section("assembly"):
        out = block_f.copy()
        if len(bj):
            add_pair_vectors(out, np.asarray(bj, dtype=np.int64), np.asarray(bk, dtype=np.int64),
                             np.ascontiguousarray(pair_f, dtype=np.float64))
        out[~free] = 0.0
        if rigid is not None:
            out[rigid, 3:] = 0.0
        return out
