r"""Compiled kernel of the deflation of the trivial Floquet multiplier.

See :func:`continuation.periodic.floquet.floquet`.

For the transfer matrices ``Phi_j`` (``n x n``) and ``f_j = f(x_j)`` at the mesh nodes,
one call builds the Householder frames :math:`Q_j = [f_j/|f_j|, Q_j^\perp]` (with
``v = f_j / |f_j|``, ``s = sign(v_0)`` and ``u = (v + s e_1) / |.|``,
``Q_j = -s (I - 2 u u^T)``, whose first column is ``v``), the products
:math:`A_j = Q_{j+1}^T \Phi_j Q_j` (:math:`Q_N = Q_0`), and returns their trailing
blocks :math:`C_j` with :math:`\sum_j \ln|r_j|`, :math:`\operatorname{sign}\prod_j r_j`
(:math:`r_j = (A_j)_{00}`) and the neglected coupling
:math:`\max_j \max_{i \ge 1} |(A_j)_{i0}| / \|A_j\|_F` (in one call: a dozen batched
NumPy calls would cost more than the work at the sizes of continuation). Compiled on
first use and cached on disk.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np

_jit = numba.njit(cache=True, nogil=True, boundscheck=False)


@_jit
def _deflate(Phi: Any, F: Any, C: Any) -> tuple[float, float, float]:  # pragma: no cover
    N, n, _ = Phi.shape
    Q = np.empty((N, n, n))
    for j in range(N):  # frames: -s H, H = I - 2 u u^T, u = (v + s e_1) / |.|
        nv = 0.0
        for i in range(n):
            nv += F[j, i] * F[j, i]
        nv = max(math.sqrt(nv), 1e-300)
        s = 1.0 if F[j, 0] / nv >= 0.0 else -1.0
        u = np.empty(n)
        for i in range(n):
            u[i] = F[j, i] / nv
        u[0] += s
        nu = 0.0
        for i in range(n):
            nu += u[i] * u[i]
        nu = math.sqrt(nu)
        for i in range(n):
            u[i] /= nu
        for a in range(n):
            for c in range(n):
                h = (1.0 if a == c else 0.0) - 2.0 * u[a] * u[c]
                Q[j, a, c] = -s * h
    log_r = 0.0
    sign_r = 1.0
    eps = 0.0
    T = np.empty((n, n))
    A = np.empty((n, n))
    for j in range(N):
        jn = j + 1 if j + 1 < N else 0
        for a in range(n):  # T = Phi_j Q_j
            for c in range(n):
                acc = 0.0
                for q in range(n):
                    acc += Phi[j, a, q] * Q[j, q, c]
                T[a, c] = acc
        fro = 0.0
        for a in range(n):  # A = Q_{j+1}^T T
            for c in range(n):
                acc = 0.0
                for q in range(n):
                    acc += Q[jn, q, a] * T[q, c]
                A[a, c] = acc
                fro += acc * acc
        fro = max(math.sqrt(fro), 1e-300)
        r = A[0, 0]
        log_r += math.log(max(abs(r), 5e-324))
        if r < 0.0:
            sign_r = -sign_r
        for a in range(1, n):
            eps = max(eps, abs(A[a, 0]) / fro)
            for c in range(1, n):
                C[j, a - 1, c - 1] = A[a, c]
    return log_r, sign_r, eps


def deflate(Phi: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, float, float, float]:
    """``(C (N, n-1, n-1), sum ln|r_j|, sign of prod r_j, eps)`` (module doc).

    For ``Phi (N, n, n)`` and ``F (N, n)``.
    """
    N, n, _ = Phi.shape
    C = np.empty((N, n - 1, n - 1))
    log_r, sign_r, eps = _deflate(
        np.ascontiguousarray(Phi, dtype=float), np.ascontiguousarray(F, dtype=float), C
    )
    return C, float(log_r), float(sign_r), float(eps)


__all__ = ["deflate"]
