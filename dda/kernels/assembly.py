"""The step's matrix and right-hand side summed straight from the contacts' rank-one terms.

:class:`dda.solvers.linear.SystemPattern` lays the matrix out in 6 x 6 blocks and says where
each goes: entry (i, j) of a block whose entry (0, 0) is at ``base`` lies at
``base + i row_step + j col_step`` of the matrix's data (``row_step = 1`` and ``col_step`` the
block column's stride in CSC storage; ``row_step = n`` and ``col_step = 1`` for a dense
n x n matrix). Contact c couples its blocks a, b in {j, k} by the block ``K_c[6a:6a+6, 6b:6b+6]``
of its 12 x 12 matrix (:func:`contact_matrix`). The blocks' own matrices are summed first, then
the contacts one after the other, each contact's four couplings in turn: the full matrix
(:func:`matrix_data`) and its upper triangle (:func:`upper_data`) get the same bits, the numpy
assembly of an (m, 12, 12) array (``SystemPattern._full_data``) the same matrix to round-off.
Contact by contact, a contact's rows are read once for its four couplings: on the 60 x 60
stack of ``benchmarks/stacks.py`` (21,242 contacts) this took Newton's full matrix from 10.1 to
6.1 ms and legacy DDA's upper triangle from 10.6 to 3.5 ms, against coupling by coupling.

The kernels and their helper share this one file: numba's cache (``cache=True``) is renewed
when the file of the compiled function changes, not when a helper it calls from another file
does.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["contact_matrix", "matrix_data", "upper_data", "upper_update", "rhs_data",
           "add_pair_vectors", "newton_residuals"]


@njit(cache=True)
def contact_matrix(out, rows, terms, weights, c):
    """Contact c's 12 x 12 matrix into ``out``:

        out = sum_t w_ct r_c,u(t) r_c,v(t)^T

    term by term, each entry ``(w_ct r_u,i) r_v,j``; a term that pairs a row with itself is
    summed on and above the diagonal and mirrored, so a matrix of such terms (legacy DDA's
    springs) is symmetric to the bit. Terms of weight 0 (an open contact's spring) add
    nothing and are skipped.
    """
    out[:, :] = 0.0
    for t in range(terms.shape[0]):
        w = weights[c, t]
        if w == 0.0:
            continue
        u = rows[c, terms[t, 0]]
        if terms[t, 0] == terms[t, 1]:
            for i in range(12):
                wu = w * u[i]
                out[i, i] += wu * u[i]
                for j in range(i + 1, 12):
                    p = wu * u[j]
                    out[i, j] += p
                    out[j, i] += p
        else:
            v = rows[c, terms[t, 1]]
            for i in range(12):
                wu = w * u[i]
                for j in range(12):
                    out[i, j] += wu * v[j]


@njit(cache=True)
def _lands_nowhere(places, c):
    """Whether none of contact c's four couplings has a place in the matrix (``places``
    (4, m), -1: nowhere): both its blocks known, or, in the upper triangle, none on or
    above the diagonal."""
    return places[0, c] < 0 and places[1, c] < 0 and places[2, c] < 0 and places[3, c] < 0


@njit(cache=True)
def coupling_block(out, rows, terms, weights, c, a6, b6):
    """The 6 x 6 block of contact c's matrix at rows a6.., columns b6.. into ``out``:

        out[i, j] = sum_t w_ct r_c,u(t),a6+i r_c,v(t),b6+j

    summed term by term as :meth:`dda.kernels.PairStiffness.dense` does (the same values).
    """
    out[:] = 0.0
    for t in range(terms.shape[0]):
        w = weights[c, t]
        u = rows[c, terms[t, 0], a6:a6 + 6]
        v = rows[c, terms[t, 1], b6:b6 + 6]
        for i in range(6):
            for j in range(6):
                out[i, j] += w * (u[i] * v[j])


@njit(cache=True)
def matrix_data(nnz, row_step, block_base, block_step, block_k, free_blocks, pair_base,
                pair_step, rows, terms, weights):
    """The data of the step's matrix (CSC data or the dense matrix's entries, row major).

    ``data[base_s + i row_step + j col_step_s] += K~_s[i, j]`` for every free block s, then,
    contact by contact, ``data[base_cab + i row_step + j col_step_cab] += K_c[6a + i, 6b + j]``
    for each coupling (a, b) of contact c whose blocks a and b are both free
    (``pair_base[2a + b, c] >= 0``).

    Parameters
    ----------
    nnz : length of the data
    row_step : int, stride of a block's rows in the data
    block_base, block_step : (n_free,) int, where each free block's 6 x 6 block goes
    block_k : (n_blocks, 6, 6) the blocks' own matrices
    free_blocks : (n_free,) int, the blocks with unknowns
    pair_base, pair_step : (4, m) int, where each contact's coupling (a, b) goes (-1: nowhere)
    rows, terms, weights : the contacts' rank-one terms (:class:`PairStiffness`)
    """
    data = np.zeros(nnz)
    for s in range(free_blocks.shape[0]):
        base, step = block_base[s], block_step[s]
        for i in range(6):
            for j in range(6):
                data[base + i * row_step + j * step] += block_k[free_blocks[s], i, j]
    kc = np.empty((12, 12))
    for c in range(pair_base.shape[1]):
        if _lands_nowhere(pair_base, c):
            continue
        contact_matrix(kc, rows, terms, weights, c)
        for ab in range(4):
            base = pair_base[ab, c]
            if base < 0:
                continue
            a6, b6 = 6 * (ab // 2), 6 * (ab % 2)
            step = pair_step[ab, c]
            for j in range(6):
                col = base + j * step
                for i in range(6):
                    data[col + i * row_step] += kc[a6 + i, b6 + j]
    return data


@njit(cache=True)
def _upper_add(data, k, start, count, rank):
    """Add the upper-triangle entries of the 6 x 6 block ``k`` to ``data`` (CSR, upper
    triangle): the block lies in block row P (whose first entry is at ``start``, with
    ``count`` blocks right of the diagonal), on the diagonal (``rank`` -1) or as the
    ``rank``-th block right of it. Row 6P + i starts at
    ``start + 6 i count + 6 i - i (i - 1) / 2`` and holds the diagonal block's columns
    6P + i..6P + 5, then 6 columns per block right of the diagonal."""
    for i in range(6):
        row = start + 6 * i * count + 6 * i - (i * (i - 1)) // 2
        if rank < 0:
            for j in range(i, 6):
                data[row + j - i] += k[i, j]
        else:
            off = row + 6 - i + 6 * rank
            for j in range(6):
                data[off + j] += k[i, j]


@njit(cache=True)
def upper_data(nnz, block_start, block_count, block_k, free_blocks, pair_start, pair_count,
               pair_rank, rows, terms, weights):
    """The upper triangle of the step's symmetric matrix as CSR data (PARDISO's input for a
    symmetric matrix), summed in the order of :func:`matrix_data`, so every entry has the
    bits :func:`matrix_data` gives it.

    Parameters
    ----------
    nnz : length of the data
    block_start, block_count : (n_free,) int, each free block's row: where it starts and how
        many blocks lie right of its diagonal block (:func:`_upper_add`)
    block_k, free_blocks : as in :func:`matrix_data`
    pair_start, pair_count, pair_rank : (4, m) int, where each contact's coupling (a, b) goes:
        the start and count of its block row and its rank right of the diagonal (-1: the
        diagonal block); ``pair_start`` -1: nowhere (a known block, or below the diagonal)
    rows, terms, weights : the contacts' rank-one terms (:class:`PairStiffness`)
    """
    data = np.zeros(nnz)
    kc = np.empty((12, 12))
    k = kc[0:6, 0:6]  # typed as the contacts' 6 x 6 views are: _upper_add compiles once
    for s in range(free_blocks.shape[0]):
        k[:, :] = block_k[free_blocks[s]]
        _upper_add(data, k, block_start[s], block_count[s], np.int64(-1))
    for c in range(pair_start.shape[1]):
        _upper_contact(data, kc, pair_start, pair_count, pair_rank, rows, terms, weights, c)
    return data


@njit(cache=True)
def _upper_contact(data, kc, pair_start, pair_count, pair_rank, rows, terms, weights, c):
    """Add contact c's couplings with ``weights`` to the upper-triangle CSR ``data``, those
    that lie on or right of the diagonal (``kc``: a 12 x 12 work array)."""
    if _lands_nowhere(pair_start, c):
        return
    contact_matrix(kc, rows, terms, weights, c)
    for ab in range(4):
        start = pair_start[ab, c]
        if start >= 0:
            a6, b6 = 6 * (ab // 2), 6 * (ab % 2)
            _upper_add(data, kc[a6:a6 + 6, b6:b6 + 6], start, pair_count[ab, c],
                       pair_rank[ab, c])


@njit(cache=True)
def upper_update(data, pair_start, pair_count, pair_rank, rows, terms, delta, changed):
    """Add to the upper-triangle CSR ``data`` (:func:`upper_data`'s, in place) the change of
    the contacts ``changed`` whose rank-one terms' weights changed by ``delta`` (m, T):

        data += sum_(c in changed) sum_t delta_ct r_c,u(t) r_c,v(t)^T   (upper blocks)

    The matrix is linear in the weights, so this is the matrix of the new weights, but for
    round-off (the sums come in another order than :func:`upper_data`'s).
    """
    kc = np.empty((12, 12))
    for q in range(changed.shape[0]):
        _upper_contact(data, kc, pair_start, pair_count, pair_rank, rows, terms, delta,
                       changed[q])
    return data


@njit(cache=True)
def rhs_data(rhs, side_row, side_block, pair_f, d_known, rows, terms, weights):
    """Add the contacts' forces to the free blocks' right-hand side ``rhs`` (in place).

    ``rhs[r_a + i] += f_c[6a + i]`` for each side a of contact c whose block is free (its rows
    start at ``r_a = side_row[a, c] >= 0``), and, for a side b whose block is known,
    ``rhs[r_a + i] -= sum_j K_c[6a + i, 6b + j] d_known[side_block[b, c], j]``.
    """
    part = np.empty(rhs.shape[0])
    for a in range(2):
        part[:] = 0.0
        for c in range(side_row.shape[1]):
            r = side_row[a, c]
            if r >= 0:
                for i in range(6):
                    part[r + i] += pair_f[c, 6 * a + i]
        rhs += part
    k = np.empty((6, 6))
    for ab in range(4):
        a, b = ab // 2, ab % 2
        part[:] = 0.0
        for c in range(side_row.shape[1]):
            r = side_row[a, c]
            if r < 0 or side_row[b, c] >= 0:
                continue
            known = side_block[b, c]
            coupling_block(k, rows, terms, weights, c, 6 * a, 6 * b)
            for i in range(6):
                load = 0.0
                for j in range(6):
                    load += k[i, j] * d_known[known, j]
                part[r + i] += load
        rhs -= part
    return rhs


@njit(cache=True)
def add_pair_vectors(out, bj, bk, pair_f):
    """``out[bj[c]] += pair_f[c, :6]`` for every contact c, then ``out[bk[c]] += pair_f[c, 6:]``,
    one after the other (in place): ``numpy.add.at``'s order, without its per-element cost."""
    for c in range(bj.shape[0]):
        for i in range(6):
            out[bj[c], i] += pair_f[c, i]
    for c in range(bk.shape[0]):
        for i in range(6):
            out[bk[c], i] += pair_f[c, 6 + i]
    return out


@njit(cache=True)
def newton_residuals(block_k, d, block_f, free, rigid, bj, bk, pair_r):
    """The out-of-balance vectors of a Newton iterate, as the numpy expressions give them:

        inertia = K_b d_b (``numpy.einsum('bij,bj->bi')``'s order: the even and the odd terms
        apart, then the two),  block_r = inertia - f_b,
        r = block_r + sum over contacts of r_c,  contact = sum over contacts of |r_c|

    (contacts added as :func:`add_pair_vectors` does), rows of blocks without unknowns and
    the strain entries of ``rigid`` blocks zero in ``r`` and ``contact``. Returns ``block_r``
    and the free blocks' rows of ``r``, ``inertia`` and ``contact``, each (n_free, 6)."""
    nb = d.shape[0]
    inertia = np.empty((nb, 6))
    block_r = np.empty((nb, 6))
    for b in range(nb):
        for i in range(6):
            k = block_k[b, i]
            even = k[0] * d[b, 0] + k[2] * d[b, 2] + k[4] * d[b, 4]
            odd = k[1] * d[b, 1] + k[3] * d[b, 3] + k[5] * d[b, 5]
            inertia[b, i] = even + odd
            block_r[b, i] = inertia[b, i] - block_f[b, i]
    r = block_r.copy()
    contact = np.zeros((nb, 6))
    for c in range(bj.shape[0]):
        for i in range(6):
            r[bj[c], i] += pair_r[c, i]
            contact[bj[c], i] += abs(pair_r[c, i])
    for c in range(bk.shape[0]):
        for i in range(6):
            r[bk[c], i] += pair_r[c, 6 + i]
            contact[bk[c], i] += abs(pair_r[c, 6 + i])
    n_free = 0
    for b in range(nb):
        if free[b]:
            n_free += 1
    r_free = np.empty((n_free, 6))
    inertia_free = np.empty((n_free, 6))
    contact_free = np.empty((n_free, 6))
    row = 0
    for b in range(nb):
        if not free[b]:
            continue
        for i in range(6):
            strain_off = rigid[b] and i >= 3
            r_free[row, i] = 0.0 if strain_off else r[b, i]
            contact_free[row, i] = 0.0 if strain_off else contact[b, i]
            inertia_free[row, i] = inertia[b, i]
        row += 1
    return block_r, r_free, inertia_free, contact_free
