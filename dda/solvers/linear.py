"""One assembly and one solve of the step's linear system (6x6 blocks).

Blocks whose motion is known carry no unknowns: the contact terms that couple them to a free
block go to the right-hand side. Small systems are solved dense (LAPACK), larger ones by a
sparse direct solver (:mod:`dda.solvers.sparse_factor`: MKL PARDISO or SuperLU); the switch is
at ``DENSE_LIMIT`` unknowns (measured in benchmarks/).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from dda.profiling import count_solve, section
from dda.solvers.sparse_factor import SingularSystemError, SparseFactor, make_factor

__all__ = ["assemble_and_solve", "assemble_vector", "SystemPattern", "DENSE_LIMIT",
           "SingularSystemError"]

DENSE_LIMIT = 300

_I6, _J6 = np.meshgrid(np.arange(6), np.arange(6), indexing="ij")


class SystemPattern:
    """Where every block and contact entry goes in the step's matrix and right-hand side.

    The blocks with unknowns and the contacts' block pairs do not change within a step, so
    the index work of the assembly (slots, masks, the sorted sparse structure) is done once
    per step and every OPEN-CLOSE pass or Newton iteration only sums values into place.

    Parameters
    ----------
    free : (n_blocks,) bool, blocks with unknowns
    bj, bk : (m,) the two blocks of each contact
    rigid : (n_blocks,) bool, optional
        Blocks without strain: their three strain rows and columns are left out of the
        system (``unknowns`` counts what is solved for).
    """

    def __init__(self, free, bj, bk, rigid=None):
        n_blocks = len(free)
        slot = np.full(n_blocks, -1, dtype=np.int64)
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
        brow, bcol = [slot[free_blocks]], [slot[free_blocks]]
        self.rhs_index = []  # per side a: (contacts whose block a is free, their rhs rows)
        self.couplings = []  # per (a, b): (a, b, both free, a free and b known, ...)
        if len(bj):
            for a, ba in enumerate((bj, bk)):
                sa = slot[ba]
                fa = sa >= 0
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
        if n <= DENSE_LIMIT:
            self.dense_index = ((6 * br[:, None, None] + _I6) * n
                                + 6 * bc[:, None, None] + _J6).reshape(-1)
            return
        # compressed sparse columns: block entries sorted by block column, then block row;
        # within block column J, scalar column 6J + j lists the 6 rows of each block in turn
        nf = len(free_blocks)
        ub, inverse = np.unique(bc * nf + br, return_inverse=True)
        ucol, urow = ub // nf, ub % nf
        count = np.bincount(ucol, minlength=nf)
        bptr = np.concatenate([[0], np.cumsum(count)])
        rank = np.arange(len(ub)) - bptr[ucol]
        # position of entry (i, j) of unique block u in the CSC data
        pos = (36 * bptr[ucol][:, None, None] + _J6 * 6 * count[ucol][:, None, None]
               + 6 * rank[:, None, None] + _I6)
        self.slot_of_entry = pos[inverse].reshape(-1)
        self.nnz = 36 * len(ub)
        indices = np.empty(self.nnz, dtype=np.int32)
        indices[pos.reshape(-1)] = (6 * urow[:, None, None] + _I6 + 0 * _J6).reshape(-1)
        self.indices = indices
        col_start = 36 * bptr[:-1][:, None] + np.arange(6)[None, :] * 6 * count[:, None]
        self.indptr = np.append(col_start.reshape(-1), self.nnz).astype(np.int32)

    def matrix(self, block_k, pair_k):
        """The matrix of the unknowns: dense up to ``DENSE_LIMIT`` unknowns, else CSC."""
        k = self._full_matrix(block_k, pair_k)
        if self.keep is None:
            return k
        if isinstance(k, np.ndarray):
            return k[np.ix_(self.keep, self.keep)]
        return k[:, self.keep][self.keep, :].tocsc()

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

    def _full_matrix(self, block_k, pair_k):
        vals = [block_k[self.free_blocks].reshape(-1)]
        for a, b, both, _, _ in self.couplings:
            vals.append(pair_k[both, 6 * a:6 * a + 6, 6 * b:6 * b + 6].reshape(-1))
        v = np.concatenate(vals)
        n = self.n
        if n <= DENSE_LIMIT:
            return np.bincount(self.dense_index, weights=v, minlength=n * n).reshape(n, n)
        data = np.bincount(self.slot_of_entry, weights=v, minlength=self.nnz)
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(n, n))

    def rhs(self, block_f, pair_k, pair_f, d_known):
        """The free blocks' right-hand side; contacts with a known block move its increment
        (times the coupling) to this side."""
        rhs = block_f[self.free_blocks].reshape(-1).copy()
        for a, (fa, index) in enumerate(self.rhs_index):
            rhs += np.bincount(index, weights=pair_f[fa, 6 * a:6 * a + 6].reshape(-1),
                               minlength=self.n)
        for a, b, _, to_rhs, (known_block, index) in self.couplings:
            if len(to_rhs):
                sub = pair_k[to_rhs, 6 * a:6 * a + 6, 6 * b:6 * b + 6]
                load = np.einsum("mij,mj->mi", sub, d_known[known_block])
                rhs -= np.bincount(index, weights=load.reshape(-1), minlength=self.n)
        return rhs


def assemble_and_solve(block_k, block_f, free, bj, bk, pair_k, pair_f, d_known, pattern=None,
                       rigid=None, factor: SparseFactor | None = None):
    """Assemble and solve ``K d = F`` for the free blocks.

    Parameters
    ----------
    block_k : (n_blocks, 6, 6) effective block matrices (stiffness, inertia, constraints)
    block_f : (n_blocks, 6) effective block forces
    free : (n_blocks,) bool, blocks with unknowns
    bj, bk : (m,) the two blocks of each contact
    pair_k : (m, 12, 12) contact stiffness on [d_j; d_k]
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
        k = pattern.matrix(block_k, pair_k)
        rhs = pattern.reduce(pattern.rhs(block_f, pair_k, pair_f, d_known))
    with section("solve"):
        count_solve()
        sol = _solve(k, rhs, factor)
    d[pattern.free_blocks] = pattern.expand(sol).reshape(-1, 6)
    return d


def _solve(k, rhs, factor: SparseFactor | None):
    """Dense LAPACK for an ndarray; a sparse matrix goes to ``factor`` (a one-off holder of
    the default backend when None, :mod:`dda.solvers.sparse_factor`)."""
    if isinstance(k, np.ndarray):
        try:
            sol = np.linalg.solve(k, rhs)
        except np.linalg.LinAlgError as exc:
            raise SingularSystemError(str(exc)) from None
    else:
        sol = (factor or make_factor()).solve(k, rhs)
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
            np.add.at(out, bj, pair_f[:, :6])
            np.add.at(out, bk, pair_f[:, 6:])
        out[~free] = 0.0
        if rigid is not None:
            out[rigid, 3:] = 0.0
        return out
