r"""Compiled kernels of the stage condensation (:mod:`continuation.bvp.condense`).

At the sizes of continuation (tens of stage blocks of 8 to 32 rows) batched NumPy
calls (inverses, condition numbers, products, determinants) cost more in
call overhead than in arithmetic. Here one call per factorisation does, for every
stage block ``A_j`` (``b x b``):

* the LU factorisation with partial pivoting, :math:`P_j A_j = L_j U_j`, in place
  (no explicit inverse: the solves use the factors);
* :math:`\log|\det A_j|` and its sign, from the pivots;
* an estimate of :math:`\kappa_1(A_j) = \|A_j\|_1 \|A_j^{-1}\|_1`, with
  :math:`\|A_j^{-1}\|_1` by Hager's estimator (Hager 1984, SIAM J. Sci. Stat. Comput.
  5:311-316; Higham 1988, ACM TOMS 14:381-396, as LAPACK's ``dgecon``): at most
  ``HAGER_ITERATIONS`` (2) pairs of solves with :math:`A_j` and :math:`A_j^T`, a lower
  bound, exact or within a small factor in practice;
* :math:`W_j = A_j^{-1} A_{sr,j}` (``b x w_c``) and :math:`U_j = A_{rs,j} W_j`
  (``w_r x w_c``), the block's update of the Schur complement.

and one call per solve applies :math:`A_j^{-1}` or :math:`A_j^{-T}` to the blocks of
a right-hand side. A zero pivot marks the block singular (``cond = inf``); the caller
then falls back to a general sparse LU, as for a block whose condition exceeds its
bound. Compiled on first use and cached on disk (``cache=True``); imported only when
a factorisation is first needed, since importing Numba takes about half a second.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np

_jit = numba.njit(cache=True, nogil=True, boundscheck=False)

#: Iterations of Hager's estimator (each a solve with ``A`` and one with ``A^T``); it
#: usually settles in two (Higham 1988), and the estimate is a lower bound at every one.
HAGER_ITERATIONS = 2


@_jit
def _lu_solve(lu: Any, piv: Any, x: Any, trans: bool) -> None:  # pragma: no cover - compiled
    """``x <- A^{-1} x`` (``A^{-T} x`` with ``trans``) in place.

    ``P A = L U`` in ``lu`` (unit lower ``L``), ``piv`` the row interchanges in LAPACK's
    order.
    """
    b = lu.shape[0]
    if not trans:
        for k in range(b):  # apply P
            p = piv[k]
            if p != k:
                t = x[k]
                x[k] = x[p]
                x[p] = t
        for r in range(b):  # L y = P x
            s = x[r]
            for q in range(r):
                s -= lu[r, q] * x[q]
            x[r] = s
        for r in range(b - 1, -1, -1):  # U x = y
            s = x[r]
            for q in range(r + 1, b):
                s -= lu[r, q] * x[q]
            x[r] = s / lu[r, r]
    else:
        for r in range(b):  # U^T y = x
            s = x[r]
            for q in range(r):
                s -= lu[q, r] * x[q]
            x[r] = s / lu[r, r]
        for r in range(b - 1, -1, -1):  # L^T w = y
            s = x[r]
            for q in range(r + 1, b):
                s -= lu[q, r] * x[q]
            x[r] = s
        for k in range(b - 1, -1, -1):  # x = P^T w
            p = piv[k]
            if p != k:
                t = x[k]
                x[k] = x[p]
                x[p] = t


@_jit
def _lu_inplace(lu: Any, piv: Any) -> tuple[float, float, bool]:  # pragma: no cover
    """LU with partial pivoting of ``lu`` (b, b) in place, interchanges in ``piv``.

    Returns ``(log|det|, sign of det, singular)``.
    """
    b = lu.shape[0]
    lg = 0.0
    sg = 1.0
    for k in range(b):
        p = k
        big = abs(lu[k, k])
        for r in range(k + 1, b):
            v = abs(lu[r, k])
            if v > big:
                big = v
                p = r
        piv[k] = p
        if big == 0.0 or not math.isfinite(big):
            return -math.inf, 0.0, True
        if p != k:
            sg = -sg
            for c in range(b):
                t = lu[k, c]
                lu[k, c] = lu[p, c]
                lu[p, c] = t
        d = lu[k, k]
        if d < 0.0:
            sg = -sg
        lg += math.log(abs(d))
        inv_d = 1.0 / d
        for r in range(k + 1, b):
            f = lu[r, k] * inv_d
            lu[r, k] = f
            if f != 0.0:
                for c in range(k + 1, b):
                    lu[r, c] -= f * lu[k, c]
    return lg, sg, False


@_jit
def solve_many(K: Any, R: Any, X: Any) -> bool:  # pragma: no cover - compiled
    """``X[j] = K_j^{-1} R[j]``; False if a block is singular.

    ``K (N, b, b)`` is overwritten by its LU factors; ``R, X (N, b, k)``.
    """
    N, b, k = R.shape
    piv = np.empty(b, dtype=np.int64)
    col = np.empty(b)
    for j in range(N):
        lg, sg, singular = _lu_inplace(K[j], piv)
        if singular:
            return False
        for c in range(k):
            for r in range(b):
                col[r] = R[j, r, c]
            _lu_solve(K[j], piv, col, False)
            for r in range(b):
                X[j, r, c] = col[r]
    return True


@_jit
def _inv_norm1(lu: Any, piv: Any, x: Any, y: Any) -> float:  # pragma: no cover - compiled
    """Hager's estimate of ``||A^{-1}||_1`` from the factors (module doc)."""
    b = lu.shape[0]
    for i in range(b):
        x[i] = 1.0 / b
    est = 0.0
    last = -1
    for _ in range(HAGER_ITERATIONS):
        for i in range(b):
            y[i] = x[i]
        _lu_solve(lu, piv, y, False)  # y = A^{-1} x
        s1 = 0.0
        for i in range(b):
            s1 += abs(y[i])
        if s1 <= est:
            break
        est = s1
        for i in range(b):  # z = A^{-T} sign(y), in y
            y[i] = 1.0 if y[i] >= 0.0 else -1.0
        _lu_solve(lu, piv, y, True)
        j = 0
        zmax = abs(y[0])
        zx = 0.0
        for i in range(b):
            zx += y[i] * x[i]
            if abs(y[i]) > zmax:
                zmax = abs(y[i])
                j = i
        if zmax <= zx or j == last:
            break
        last = j
        for i in range(b):
            x[i] = 0.0
        x[j] = 1.0
    return est


@_jit
def factor_blocks(
    A: Any, Asr: Any, Ars: Any, piv: Any, W: Any, U: Any, cond: Any, logdet: Any, sign: Any
) -> None:  # pragma: no cover - compiled
    """Factorise the blocks ``A (N, b, b)`` in place.

    Fills ``piv (N, b)``, ``W (N, b, wc)``, ``U (N, wr, wc)``, ``cond``, ``logdet``,
    ``sign`` (``(N,)`` each) from ``Asr (N, b, wc)`` and ``Ars (N, wr, b)`` (module doc).
    ``A`` holds ``L`` and ``U`` on return.
    """
    N, b, _ = A.shape
    wc = Asr.shape[2]
    wr = Ars.shape[1]
    col = np.empty(b)
    x = np.empty(b)
    y = np.empty(b)
    for j in range(N):
        lu = A[j]
        norm1 = 0.0  # ||A_j||_1, before the factorisation overwrites it
        for c in range(b):
            s = 0.0
            for r in range(b):
                s += abs(lu[r, c])
            norm1 = max(norm1, s)
        lg, sg, singular = _lu_inplace(lu, piv[j])
        if singular:
            cond[j] = math.inf
            logdet[j] = -math.inf
            sign[j] = 0.0
            continue
        logdet[j] = lg
        sign[j] = sg
        cond[j] = norm1 * _inv_norm1(lu, piv[j], x, y)
        for c in range(wc):  # W_j = A_j^{-1} A_sr,j, column by column
            for r in range(b):
                col[r] = Asr[j, r, c]
            _lu_solve(lu, piv[j], col, False)
            for r in range(b):
                W[j, r, c] = col[r]
        for r in range(wr):
            for c in range(wc):
                s = 0.0
                for q in range(b):
                    s += Ars[j, r, q] * W[j, q, c]
                U[j, r, c] = s


@_jit
def solve_blocks(LU: Any, piv: Any, B: Any, trans: bool) -> Any:  # pragma: no cover
    """``X[j] = A_j^{-1} B[j]`` (``A_j^{-T}`` with ``trans``), ``B (N, b, k)``."""
    N, b, k = B.shape
    X = np.empty((N, b, k))
    col = np.empty(b)
    for j in range(N):
        for c in range(k):
            for r in range(b):
                col[r] = B[j, r, c]
            _lu_solve(LU[j], piv[j], col, trans)
            for r in range(b):
                X[j, r, c] = col[r]
    return X


@_jit
def gather(data: Any, src: Any, dst: Any, buf: Any) -> None:  # pragma: no cover
    """``buf[:] = 0; buf[dst] = data[src]`` (the block entries of a CSC matrix)."""
    for q in range(buf.size):
        buf[q] = 0.0
    for q in range(src.size):
        buf[dst[q]] = data[src[q]]


@_jit
def solve_pre(
    Bm: Any, rows_s: Any, rest_r: Any, LU: Any, piv: Any, Ars: Any, rs_rows: Any,
    ys: Any, br: Any,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """The forward half of a condensed solve (``trans="N"``).

    ``ys[j] = A_j^{-1} b_s[j]`` and the reduced right-hand side ``br = b_r - sum_j A_rs,j
    ys[j]`` (``br`` has ``n_r + 1`` rows, the last one the padding slot), for ``Bm (size,
    k)``.
    """
    N, b = rows_s.shape
    k = Bm.shape[1]
    nr = rest_r.size
    wr = Ars.shape[1]
    col = np.empty(b)
    for q in range(nr):
        for c in range(k):
            br[q, c] = Bm[rest_r[q], c]
    for c in range(k):
        br[nr, c] = 0.0
    for j in range(N):
        for c in range(k):
            for r in range(b):
                col[r] = Bm[rows_s[j, r], c]
            _lu_solve(LU[j], piv[j], col, False)
            for r in range(b):
                ys[j, r, c] = col[r]
            for r in range(wr):
                acc = 0.0
                for q in range(b):
                    acc += Ars[j, r, q] * col[q]
                br[rs_rows[j, r], c] -= acc


@_jit
def solve_post(
    ys: Any, W: Any, xr: Any, sr_cols: Any, cols_s: Any, rest_c: Any, out: Any
) -> None:  # pragma: no cover - compiled
    """The backward half: ``x_s[j] = ys[j] - W_j x_r[sr_cols[j]]``.

    The padding column ``n_r`` is zero; scattered with ``x_r`` into ``out (size, k)``.
    """
    N, b, k = ys.shape
    nr = rest_c.size
    wc = W.shape[2]
    for q in range(nr):
        for c in range(k):
            out[rest_c[q], c] = xr[q, c]
    for j in range(N):
        for r in range(b):
            for c in range(k):
                acc = ys[j, r, c]
                for t in range(wc):
                    i = sr_cols[j, t]
                    if i < nr:
                        acc -= W[j, r, t] * xr[i, c]
                out[cols_s[j, r], c] = acc


def factor(
    A: np.ndarray, Asr: np.ndarray, Ars: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(piv, W, U, cond, logdet, sign)`` of the blocks.

    ``A`` is overwritten by its LU factors (see :func:`factor_blocks` for the shapes).
    """
    N, b, _ = A.shape
    wc, wr = Asr.shape[2], Ars.shape[1]
    piv = np.zeros((N, b), dtype=np.int64)
    W = np.empty((N, b, wc))
    U = np.empty((N, wr, wc))
    cond, logdet, sign = np.empty(N), np.empty(N), np.empty(N)
    factor_blocks(A, Asr, Ars, piv, W, U, cond, logdet, sign)
    return piv, W, U, cond, logdet, sign


__all__ = ["factor", "gather", "solve_blocks", "solve_many", "solve_post", "solve_pre"]
