r"""Condensation of the collocation stage unknowns: the linear solves of a BVP.

The Jacobian of the collocation system, with the unknowns split into the stage
values ``s`` (the ``n m`` values :math:`x_{j,1..m}` of each interval ``j``) and the
rest ``r`` (mesh points, end points, Riccati unknowns, parameters and any border
row and column of the continuation driver), and its equations into the collocation
rows of each interval and the rest,

.. math::

    M = \begin{pmatrix} A_{ss} & A_{sr} \\ A_{rs} & A_{rr} \end{pmatrix},

has a block-diagonal :math:`A_{ss}` (one ``(n m, n m)`` block per interval: the
collocation equations of an interval involve only its own stages). Eliminating the
stages interval by interval (as AUTO-07p's condensation of parameters does) leaves
the Schur complement :math:`S = A_{rr} - A_{rs} A_{ss}^{-1} A_{sr}` on the
``n (N + 1) + ...`` remaining unknowns, a small dense matrix:

.. math::

    S x_r = b_r - A_{rs} A_{ss}^{-1} b_s, \qquad
    x_s = A_{ss}^{-1} (b_s - A_{sr} x_r), \qquad
    \det M = \pm \det A_{ss} \det S .

The stage blocks are factorised in one compiled call (:mod:`continuation.bvp._condense_jit`:
block LU with partial pivoting, a condition estimate, the determinants from the pivots,
and the products with the few rest columns (rows) each block touches; Numba is
required). ``S`` couples each
mesh point only with its neighbours and the few global unknowns, so it is sparse (2 %
non-zeros for 3 states on 55 intervals); from ``SPARSE_SCHUR_MIN`` unknowns on, with at
most ``SPARSE_SCHUR_DENSITY`` of its entries structurally non-zero, it is factorised
by SuperLU in its natural (mesh) order with partial pivoting, as a band, instead of by
the dense LU whose ``O(n_r^3)`` cost then dominates. Where a block is
singular or badly conditioned (``cond_1 > 1e10``, Hager's estimate) the factorisation
returns None and
the caller uses a general sparse LU instead.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg.lapack as lapack
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .._jit import compiled
from ..typing import FloatArray

#: Largest accepted 1-norm condition estimate of a stage block (else: general LU).
MAX_BLOCK_COND = 1e10

#: Largest dense Schur complement factorised here: a larger one that is not sparse
#: enough for the sparse path (``SPARSE_SCHUR_DENSITY``) is left to the general sparse LU
#: of ``M``, for which the dense O(n_r^3) factorisation would cost more than it saves. A
#: sparse one of any size is condensed (the ship's 8 states on 80-90 intervals give
#: about 700: its periodic orbits' Jacobians factorise in about a third of the time of
#: SuperLU on the whole ``M``, 2.9 s against 8.4 s over the cycles study's 350).
MAX_SCHUR = 256

#: Schur complements of at least this many unknowns, with at most
#: ``SPARSE_SCHUR_DENSITY`` of their entries structurally non-zero, are factorised as
#: sparse matrices (SuperLU, natural order); smaller ones densely (LAPACK ``getrf``).
#: Measured crossover: at 144 unknowns (2 states, 70 intervals) the dense path takes 207
#: against 264 us per factorisation, at 176 (3 states, 55 intervals) 300 against 250 us.
SPARSE_SCHUR_MIN = 160
SPARSE_SCHUR_DENSITY = 0.1


#: The compiled kernels of the condensation (:func:`continuation._jit.compiled`).
KERNELS = "continuation.bvp._condense_jit"


class _Structure:
    """Index maps of one sparsity pattern of ``M`` (built once per pattern)."""

    def __init__(self, M: sp.csc_matrix, rows_s: np.ndarray, cols_s: np.ndarray) -> None:
        size = M.shape[0]
        N, b = rows_s.shape
        self.size, self.N, self.b = size, N, b
        self.indptr, self.indices = M.indptr, M.indices  # kept: ids stay valid
        blk_r = np.full(size, -1)
        loc_r = np.zeros(size, dtype=np.int64)
        blk_c = np.full(size, -1)
        loc_c = np.zeros(size, dtype=np.int64)
        blk_r[rows_s.ravel()] = np.repeat(np.arange(N), b)
        loc_r[rows_s.ravel()] = np.tile(np.arange(b), N)
        blk_c[cols_s.ravel()] = np.repeat(np.arange(N), b)
        loc_c[cols_s.ravel()] = np.tile(np.arange(b), N)
        rest_r = np.flatnonzero(blk_r < 0)
        rest_c = np.flatnonzero(blk_c < 0)
        if rest_r.size != rest_c.size:
            raise ValueError("stage rows and columns differ in number")
        nr = rest_r.size
        self.nr = nr
        rix = np.full(size, -1)
        rix[rest_r] = np.arange(nr)
        cix = np.full(size, -1)
        cix[rest_c] = np.arange(nr)
        self.rows_s, self.cols_s, self.rest_r, self.rest_c = rows_s, cols_s, rest_r, rest_c
        nnz = int(M.indptr[-1])
        r = M.indices[:nnz].astype(np.int64)
        c = np.repeat(np.arange(size), np.diff(M.indptr))
        br, bc = blk_r[r], blk_c[c]
        ss = (br >= 0) & (bc >= 0)
        if np.any(br[ss] != bc[ss]):
            raise ValueError("stage blocks are coupled: A_ss is not block diagonal")
        k = np.flatnonzero(ss)
        self.ss = (k, br[k] * b * b + loc_r[r[k]] * b + loc_c[c[k]])
        k = np.flatnonzero((br < 0) & (bc < 0))
        self.rr = (k, rix[r[k]] * nr + cix[c[k]])
        self.rr_pad = rix[r[k]] * (nr + 1) + cix[c[k]]  # the same in the padded matrix
        # per block: the rest columns its rows touch (A_sr), the rest rows touching its
        # columns (A_rs); padded to a common width with a dummy index nr (zero entries)
        k_sr = np.flatnonzero((br >= 0) & (bc < 0))
        k_rs = np.flatnonzero((br < 0) & (bc >= 0))
        self.sr_cols, sr_pos = _per_block(br[k_sr], cix[c[k_sr]], N, nr)
        self.rs_rows, rs_pos = _per_block(bc[k_rs], rix[r[k_rs]], N, nr)
        wc, wr = self.sr_cols.shape[1], self.rs_rows.shape[1]
        self.wc, self.wr = wc, wr
        self.sr = (k_sr, br[k_sr] * b * wc + loc_r[r[k_sr]] * wc + sr_pos)
        self.rs = (k_rs, bc[k_rs] * wr * b + rs_pos * b + loc_c[c[k_rs]])
        # one gather of the block entries: A_ss, A_sr and A_rs side by side in a buffer
        n_ss, n_sr = N * b * b, N * b * wc
        self.gather_src = np.concatenate((self.ss[0], self.sr[0], self.rs[0]))
        self.gather_dst = np.concatenate((self.ss[1], n_ss + self.sr[1], n_ss + n_sr + self.rs[1]))
        self.gather_len = n_ss + n_sr + N * wr * b
        self.gather_cut = (n_ss, n_ss + n_sr)
        # flat positions of the Schur updates in the padded (nr + 1)^2 matrix
        self.upd = (self.rs_rows[:, :, None] * (nr + 1) + self.sr_cols[:, None, :]).ravel()
        # the sparsity pattern of S (CSC): the A_rr entries and the block updates, and
        # the slot of each contribution in it (padding entries go to a dropped slot)
        upd_r = np.broadcast_to(self.rs_rows[:, :, None], (N, wr, wc)).ravel()
        upd_c = np.broadcast_to(self.sr_cols[:, None, :], (N, wr, wc)).ravel()
        all_r = np.concatenate((rix[r[k]], upd_r))
        all_c = np.concatenate((cix[c[k]], upd_c))
        real = (all_r < nr) & (all_c < nr)
        key = all_c * nr + all_r
        ukey = np.unique(key[real])
        self.s_nnz = int(ukey.size)
        slot = np.full(key.size, self.s_nnz)
        slot[real] = np.searchsorted(ukey, key[real])
        self.s_slot = slot  # A_rr contributions first, then the updates (flattened)
        self.s_indices = (ukey % nr).astype(np.int32)
        self.s_indptr = np.searchsorted(ukey // nr, np.arange(nr + 1)).astype(np.int32)
        self.sparse_schur = nr >= SPARSE_SCHUR_MIN and self.s_nnz <= SPARSE_SCHUR_DENSITY * nr * nr
        # sign of the permutation [stages by block, rest] of rows times that of columns
        self.perm_sign = _parity(np.concatenate((rows_s.ravel(), rest_r))) * _parity(
            np.concatenate((cols_s.ravel(), rest_c))
        )


def _per_block(blk: np.ndarray, idx: np.ndarray, N: int, pad: int) -> tuple[np.ndarray, np.ndarray]:
    """Distinct ``idx`` per block (padded with ``pad``) and each entry's slot in its block."""
    pairs = np.unique(blk * (pad + 1) + idx)
    pb, pi = pairs // (pad + 1), pairs % (pad + 1)
    counts = np.bincount(pb, minlength=N)
    w = max(int(counts.max()) if counts.size else 0, 1)
    table = np.full((N, w), pad)
    start = np.concatenate(([0], np.cumsum(counts)[:-1]))
    slot = np.arange(pairs.size) - start[pb]
    table[pb, slot] = pi
    pos = slot[np.searchsorted(pairs, blk * (pad + 1) + idx)]
    return table, pos


def _parity(perm: np.ndarray) -> int:
    perm = np.asarray(perm).copy()
    seen = np.zeros(perm.size, dtype=bool)
    odd = 0
    for i in range(perm.size):
        if not seen[i]:
            j, length = i, 0
            while not seen[j]:
                seen[j] = True
                j = perm[j]
                length += 1
            odd += length - 1
    return -1 if odd % 2 else 1


class CondensedLU:
    """Factorisation of ``M`` by condensation of the stage blocks (see module doc).

    Same interface as the parts of SciPy's ``SuperLU`` the engine uses:
    ``solve(b, trans="N" | "T")``, plus ``diag_parity()`` for the determinant.
    """

    def __init__(
        self,
        st: _Structure,
        W: FloatArray,
        Ars: FloatArray,
        lu: Any,
        piv: np.ndarray | None,
        block_lu: tuple[Any, ...],
    ) -> None:
        # lu, piv: LAPACK getrf factors of S, or (piv None) SciPy's SuperLU of S.
        # The stage blocks: block_lu = (kernels, LU factors, pivots, log|det|, sign)
        self._st, self._W, self._Ars = st, W, Ars
        self._lu, self._piv = lu, piv
        self._block_lu = block_lu
        self.shape = (st.size, st.size)

    def _blocks_solve(self, B: FloatArray, trans: bool) -> FloatArray:
        """``A_j^{-1} B[j]`` (``A_j^{-T}`` with ``trans``) for ``B`` of shape (N, b, k)."""
        kern, LU, bpiv = self._block_lu[:3]
        return kern.solve_blocks(LU, bpiv, np.ascontiguousarray(B), trans)  # type: ignore[no-any-return]

    def _solve_schur(self, b: FloatArray, trans: int) -> FloatArray:
        """``S^{-1} b`` (``S^{-T} b`` for ``trans=1``), ``b`` of shape (n_r, k)."""
        if self._piv is None:
            return np.asarray(self._lu.solve(b, trans="T" if trans else "N"))
        x, info = lapack.dgetrs(self._lu, self._piv, b, trans=trans)
        return np.asarray(x)

    def solve(self, rhs: FloatArray, trans: str = "N") -> FloatArray:
        """``M^{-1} rhs`` (``trans="T"``: ``M^{-T} rhs``), rhs of shape (size,) or (size, k)."""
        st = self._st
        rhs = np.asarray(rhs, dtype=float)
        one = rhs.ndim == 1
        B = rhs.reshape(st.size, -1)
        k = B.shape[1]
        if trans == "N":  # two compiled halves
            kern, LU, bpiv = self._block_lu[:3]
            Bc = np.ascontiguousarray(B)
            ys = np.empty((st.N, st.b, k))
            brp = np.empty((st.nr + 1, k))
            kern.solve_pre(Bc, st.rows_s, st.rest_r, LU, bpiv, self._Ars, st.rs_rows, ys, brp)
            xr = np.ascontiguousarray(self._solve_schur(brp[:-1], 0))
            out = np.empty((st.size, k))
            kern.solve_post(ys, self._W, xr, st.sr_cols, st.cols_s, st.rest_c, out)
            return out.ravel() if one else out
        # trans == "T": A_sr^T y_s = (A_ss W)^T y_s = W^T A_ss^T y_s = W^T bs (by blocks)
        bs = B[st.cols_s]  # (N, b, k)
        br = np.zeros((st.nr + 1, k))
        br[:-1] = B[st.rest_c]
        np.subtract.at(br, st.sr_cols, np.swapaxes(self._W, 1, 2) @ bs)
        xr = self._solve_schur(br[:-1], 1)
        xr_pad = np.vstack((xr, np.zeros((1, k))))
        # x_s = A_ss^{-T} (b_s - A_rs^T x_r)
        xs = self._blocks_solve(bs - np.swapaxes(self._Ars, 1, 2) @ xr_pad[st.rs_rows], True)
        out = np.empty_like(B)
        out[st.rows_s] = xs
        out[st.rest_r] = xr
        return out.ravel() if one else out

    def diag_parity(self) -> tuple[FloatArray, int]:
        """Numbers whose product is ``|det M|`` up to the sign returned, and that sign.

        Returns ``(d, parity)`` with ``det M = parity * prod(d)``: ``d`` holds the
        pivots of the Schur complement and, per stage block, ``|det|^(1/b)`` with the
        block's sign folded into ``parity`` (the engine's convention for SuperLU).
        """
        st = self._st
        logabs, sgn = self._block_lu[3], self._block_lu[4]
        if self._piv is None:
            dS = self._lu.U.diagonal().copy()
            parity = st.perm_sign * _parity(self._lu.perm_r) * _parity(self._lu.perm_c)
        else:
            dS = np.diagonal(self._lu).copy()
            swaps = int(np.count_nonzero(self._piv != np.arange(self._piv.size)))
            parity = st.perm_sign * (-1 if swaps % 2 else 1)
        if np.any(sgn == 0):
            return np.concatenate((np.zeros(1), dS)), parity
        parity *= -1 if np.count_nonzero(sgn < 0) % 2 else 1
        d_blocks = np.repeat(np.exp(logabs / st.b), st.b)
        return np.concatenate((d_blocks, dS)), parity


class StageCondenser:
    """Condensing factoriser of the matrices of one collocation layout.

    Parameters
    ----------
    rows_s, cols_s : ndarray of int, shape (N, n m)
        Collocation rows and stage unknowns of each interval (the same for the
        Jacobian and for the driver's bordered matrix, whose border is the last
        row and column).
    """

    def __init__(self, rows_s: np.ndarray, cols_s: np.ndarray) -> None:
        self.rows_s = np.asarray(rows_s, dtype=np.int64)
        self.cols_s = np.asarray(cols_s, dtype=np.int64)
        self._cache: dict[tuple[int, int, int], _Structure | None] = {}

    def _structure(self, M: sp.csc_matrix) -> _Structure | None:
        key = (id(M.indptr), id(M.indices), M.shape[0])
        st = self._cache.get(key, False)
        stale = isinstance(st, _Structure) and (
            st.indptr is not M.indptr or st.indices is not M.indices
        )
        if st is False or stale:
            if len(self._cache) >= 8:
                self._cache.clear()
            try:
                st = _Structure(M, self.rows_s, self.cols_s)
            except ValueError:
                st = None
            self._cache[key] = st
        return st if isinstance(st, _Structure) else None

    def factor(self, M: Any) -> CondensedLU | None:
        """Condensed factorisation of the square CSC ``M``, or None (use a general LU).

        None when ``M`` is not in canonical CSC form, its stage blocks are coupled, the
        Schur complement is dense and larger than ``MAX_SCHUR``, or a block is singular
        or has ``cond_1 > MAX_BLOCK_COND``.

        Raises
        ------
        numpy.linalg.LinAlgError
            If the Schur complement is exactly singular (then so is ``M``).
        """
        if not (sp.isspmatrix_csc(M) or isinstance(M, sp.csc_array)) or not M.has_canonical_format:
            return None
        st = self._structure(M)
        if st is None:
            return None
        N, b, nr = st.N, st.b, st.nr
        if nr > MAX_SCHUR and not st.sparse_schur:
            return None
        data = M.data
        kern = compiled(KERNELS)
        buf = np.empty(st.gather_len)
        kern.gather(data, st.gather_src, st.gather_dst, buf)
        c1, c2 = st.gather_cut
        A = buf[:c1].reshape(N, b, b)
        Asr = buf[c1:c2].reshape(N, b, st.wc)
        Ars = buf[c2:].reshape(N, st.wr, b)
        # block LU, conditions, determinants, W and A_rs W: one call
        bpiv, W, U, cond, logdet, bsign = kern.factor(A, Asr, Ars)  # (A: now its LU)
        if not np.all(cond <= MAX_BLOCK_COND):
            return None
        return self._finish(M, st, W, U, Ars, (kern, A, bpiv, logdet, bsign))

    def _finish(
        self,
        M: Any,
        st: _Structure,
        W: FloatArray,
        U: FloatArray,
        Ars: FloatArray,
        block_lu: tuple[Any, ...],
    ) -> CondensedLU:
        """Form and factorise the Schur complement ``S = A_rr - sum_j U_j`` (scattered)."""
        data, nr = M.data, st.nr
        if st.sparse_schur:
            vals = np.concatenate((data[st.rr[0]], -U.ravel()))
            s_data = np.bincount(st.s_slot, weights=vals, minlength=st.s_nnz + 1)[: st.s_nnz]
            S = sp.csc_matrix((s_data, st.s_indices, st.s_indptr), shape=(nr, nr))
            try:
                slu = spla.splu(S, permc_spec="NATURAL")
            except RuntimeError as exc:
                raise np.linalg.LinAlgError(f"singular condensed matrix ({exc})") from exc
            return CondensedLU(st, W, Ars, slu, None, block_lu)
        # S = A_rr - A_rs W, the updates summed by bincount (no ufunc.at), padded
        Sp = -np.bincount(st.upd, weights=U.ravel(), minlength=(nr + 1) * (nr + 1))
        Sp[st.rr_pad] += data[st.rr[0]]
        Sp = Sp.reshape(nr + 1, nr + 1)
        lu, piv, info = lapack.dgetrf(np.asfortranarray(Sp[:nr, :nr]), overwrite_a=1)
        if info != 0:
            raise np.linalg.LinAlgError(f"singular condensed matrix (getrf info={info})")
        return CondensedLU(st, W, Ars, lu, piv, block_lu)


__all__ = ["CondensedLU", "StageCondenser"]
