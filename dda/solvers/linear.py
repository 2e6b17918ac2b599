"""One assembly and one solve of the step's linear system (6x6 blocks).

Blocks whose motion is known carry no unknowns: the contact terms that couple them to a free
block go to the right-hand side. Small systems are solved dense (LAPACK), larger ones sparse
(SuperLU); the switch is at ``DENSE_LIMIT`` unknowns, where the two cost about the same on a
two-core machine (measured in benchmarks/).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from dda.profiling import count_solve, section

__all__ = ["assemble_and_solve", "assemble_vector", "DENSE_LIMIT"]

DENSE_LIMIT = 300

_I6, _J6 = np.meshgrid(np.arange(6), np.arange(6), indexing="ij")


class SingularSystemError(RuntimeError):
    """The step's matrix is singular (a block with no support in a static analysis)."""


def assemble_and_solve(block_k, block_f, free, bj, bk, pair_k, pair_f, d_known):
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

    Returns
    -------
    d : (n_blocks, 6), the free blocks solved and the known ones as given
    """
    with section("assembly"):
        n, k, rhs, free_blocks = _assemble(block_k, block_f, free, bj, bk, pair_k, pair_f,
                                           d_known)
    d = d_known.copy()
    if n == 0:
        return d
    with section("solve"):
        count_solve()
        sol = _solve(k, rhs)
    d[free_blocks] = sol.reshape(-1, 6)
    return d


def _assemble(block_k, block_f, free, bj, bk, pair_k, pair_f, d_known):
    """The free blocks' matrix (dense up to ``DENSE_LIMIT`` unknowns, else CSC) and rhs."""
    n_blocks = len(free)
    slot = np.full(n_blocks, -1, dtype=np.int64)
    free_blocks = np.flatnonzero(free)
    slot[free_blocks] = np.arange(len(free_blocks))
    n = 6 * len(free_blocks)
    if n == 0:
        return 0, None, None, free_blocks

    rhs = block_f[free_blocks].reshape(-1).copy()
    rows = [(6 * slot[free_blocks])[:, None, None] + _I6]
    cols = [(6 * slot[free_blocks])[:, None, None] + _J6]
    vals = [block_k[free_blocks]]
    if len(bj):
        for a, ba in enumerate((bj, bk)):
            sa = slot[ba]
            fa = sa >= 0
            np.add.at(rhs, (6 * sa[fa])[:, None] + np.arange(6), pair_f[fa, 6 * a : 6 * a + 6])
            for b, bb in enumerate((bj, bk)):
                sb = slot[bb]
                sub = pair_k[:, 6 * a : 6 * a + 6, 6 * b : 6 * b + 6]
                both = fa & (sb >= 0)
                rows.append((6 * sa[both])[:, None, None] + _I6)
                cols.append((6 * sb[both])[:, None, None] + _J6)
                vals.append(sub[both])
                to_rhs = fa & (sb < 0)
                if to_rhs.any():
                    load = np.einsum("mij,mj->mi", sub[to_rhs], d_known[bb[to_rhs]])
                    np.add.at(rhs, (6 * sa[to_rhs])[:, None] + np.arange(6), -load)
    r = np.concatenate([x.reshape(-1) for x in rows])
    c = np.concatenate([x.reshape(-1) for x in cols])
    v = np.concatenate([x.reshape(-1) for x in vals])
    if n <= DENSE_LIMIT:
        k = np.bincount(r * n + c, weights=v, minlength=n * n).reshape(n, n)
    else:
        k = sp.csc_matrix((v, (r, c)), shape=(n, n))
    return n, k, rhs, free_blocks


def _solve(k, rhs):
    """Factorize and solve: dense LAPACK for an ndarray, SuperLU for a sparse matrix."""
    if isinstance(k, np.ndarray):
        try:
            sol = np.linalg.solve(k, rhs)
        except np.linalg.LinAlgError as exc:
            raise SingularSystemError(str(exc)) from None
    else:
        sol = spla.spsolve(k, rhs)
    if not np.all(np.isfinite(sol)):
        raise SingularSystemError("the step's system has no finite solution")
    return sol


def assemble_vector(block_f, free, bj, bk, pair_f):
    """Add per-contact vectors (m, 12) on [d_j; d_k] to per-block vectors (n_blocks, 6).

    Rows of blocks without unknowns are set to zero (their forces are reactions).
    """
    with section("assembly"):
        out = block_f.copy()
        if len(bj):
            np.add.at(out, bj, pair_f[:, :6])
            np.add.at(out, bk, pair_f[:, 6:])
        out[~free] = 0.0
        return out
