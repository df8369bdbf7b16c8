r"""The kernel of :math:`A = [G_z\; G_p]` at a branch point, and its left null vector.

At a simple branch point :math:`A` (``N x (N+1)``) has rank ``N - 1``:
:math:`\ker A = \mathrm{span}\{q_1, q_2\}` (``theta``-orthonormal) and
:math:`\ker A^T = \mathrm{span}\{\psi\}`. Dense or moderately sized problems get them
from the SVD of :math:`A\, W^{-1/2}` (``W = diag(theta weights)``), large sparse ones
from two solves with the bordered matrix (Govaerts 2000; Keller 1977)

.. math::

    M = \begin{pmatrix} A & b \\ C^T & 0 \end{pmatrix}, \quad
    M \begin{pmatrix} q_k \\ y \end{pmatrix} = e_{N + k}, \quad
    M^T \begin{pmatrix} \psi \\ \eta \end{pmatrix} = e_{N + 2},

first with ``b`` random and ``C = W [t_old, r]``, then again with ``b = psi`` and
``C = W [q_1, q_2]`` (which makes ``M`` well conditioned). References in
:mod:`continuation.switching`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..algorithms.base import theta_norm
from ..status import Status
from ..typing import FloatArray

#: Problems with more unknowns than this and a sparse Jacobian get their kernel from
#: bordered solves instead of a dense SVD.
DENSE_KERNEL_MAX = 400

#: The two smallest singular values of ``A W^{-1/2}`` must be separated by this factor
#: (``sigma_N <= KERNEL_GAP * sigma_{N-1}``), else the kernel is not two-dimensional.
KERNEL_GAP = 0.1


class Failure(Exception):
    """Not a simple branch point (or not computable there).

    Carries ``status`` and ``message`` for the failed result.
    """

    def __init__(self, status: Status, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


def dense(Gz: Any) -> FloatArray:
    """``G_z`` (ndarray or scipy sparse, shape (N, N)) as a dense float ndarray."""
    return np.asarray(Gz.toarray() if sp.issparse(Gz) else Gz, dtype=float)


def w_orthonormal(a: FloatArray, b: FloatArray, w: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Gram-Schmidt of ``a, b`` (shape (N + 1,)) in the ``theta`` inner product.

    With weights ``w``; raises :class:`Failure` (``SINGULAR``) when ``b`` is parallel to
    ``a``.
    """
    a = a / theta_norm(a, w)
    b = b - float((w * a).dot(b)) * a
    nb = theta_norm(b, w)
    if not nb > 0:
        raise Failure(Status.SINGULAR, "the kernel of [G_z G_p] is not two-dimensional")
    return a, b / nb


def kernel_svd(
    Gz: Any, Gp: FloatArray, w: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    """``q1, q2`` (``theta``-orthonormal kernel of ``A``), ``psi`` and the gap ratio."""
    A = np.column_stack((dense(Gz), Gp))
    n = A.shape[0]
    s = 1.0 / np.sqrt(w)
    U, sv, Vt = np.linalg.svd(A * s[None, :])
    if not np.all(np.isfinite(sv)):
        raise Failure(Status.NONFINITE, "non-finite Jacobian at the branch point")
    gap = float(sv[-1] / sv[-2]) if n >= 2 and sv[-2] > 0 else 0.0
    if n >= 2 and not gap <= KERNEL_GAP:
        raise Failure(
            Status.SINGULAR,
            f"[G_z G_p] has no two-dimensional kernel at the point (sigma_N / sigma_N-1 = "
            f"{gap:.2g}): not a branch point",
        )
    if n >= 3 and sv[-2] <= KERNEL_GAP * sv[-3] and sv[-2] <= 1e-8 * sv[0]:
        raise Failure(
            Status.SINGULAR,
            "[G_z G_p] has a kernel of dimension > 2 at the point: not a simple branch point",
        )
    return s * Vt[-1], s * Vt[-2], U[:, -1].copy(), gap


def kernel_bordered(
    Gz: Any, Gp: FloatArray, w: FloatArray, t_ref: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    """Kernel and left null vector of ``A = [G_z G_p]`` from bordered sparse solves."""
    n = Gp.size
    A = sp.hstack([sp.csc_matrix(Gz), sp.csc_matrix(Gp.reshape(-1, 1))], format="csc")
    rng = np.random.default_rng(20000)
    c1, c2 = w_orthonormal(t_ref, rng.standard_normal(n + 1), w)
    b = rng.standard_normal(n)
    rhs = np.zeros((n + 2, 2))
    rhs[n, 0] = rhs[n + 1, 1] = 1.0
    e_last = np.zeros(n + 2)
    e_last[n + 1] = 1.0
    for _ in range(2):  # the second pass borders with the first pass's vectors
        C = np.column_stack((w * c1, w * c2))
        M = sp.bmat([[A, sp.csc_matrix(b.reshape(-1, 1))], [sp.csc_matrix(C.T), None]])
        try:
            lu = spla.splu(sp.csc_matrix(M))
            X = lu.solve(rhs)
            Y = lu.solve(e_last, trans="T")
        except RuntimeError as exc:  # SuperLU: exactly singular
            raise Failure(Status.SINGULAR, f"singular bordered matrix: {exc}") from None
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(Y))):
            raise Failure(Status.SINGULAR, "singular bordered matrix at the branch point")
        c1, c2 = w_orthonormal(X[: n + 1, 0], X[: n + 1, 1], w)
        psi = Y[:n]
        npsi = float(np.linalg.norm(psi))
        if not npsi > 0:
            raise Failure(Status.SINGULAR, "no left null vector of [G_z G_p]")
        b = psi / npsi
    scale = float(abs(A).max()) * max(float(np.max(np.abs(c1))), float(np.max(np.abs(c2))))
    res = max(float(np.max(np.abs(A @ c1))), float(np.max(np.abs(A @ c2))))
    gap = res / scale if scale > 0 else 0.0
    if not gap <= 1e-6:
        raise Failure(
            Status.SINGULAR,
            f"[G_z G_p] has no two-dimensional kernel at the point (relative residual "
            f"{gap:.2g} of the bordered kernel vectors): not a branch point",
        )
    return c1, c2, b, gap


__all__ = ["DENSE_KERNEL_MAX", "KERNEL_GAP", "Failure", "dense", "kernel_bordered", "kernel_svd"]
