"""Derivatives of a right-hand side: CasADi tracing and finite-difference fallbacks."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .typing import FloatArray

VectorFn = Callable[[FloatArray], FloatArray]


def fd_jacobian(fun: VectorFn, x: FloatArray, *, rel_step: float | None = None) -> FloatArray:
    """Central-difference Jacobian of ``fun`` at ``x``.

    Parameters
    ----------
    fun : callable
        ``fun(x) -> y`` with ``x`` of shape ``(n,)`` and ``y`` of shape ``(m,)``.
    x : ndarray, shape (n,)
        Point of evaluation.
    rel_step : float, optional
        Relative step; default ``eps ** (1/3)``, which balances truncation
        ``O(h**2)`` against round-off ``O(eps / h)``.

    Returns
    -------
    ndarray, shape (m, n)
        ``J[i, j] = (f_i(x + h_j e_j) - f_i(x - h_j e_j)) / (2 h_j)``.
    """
    x = np.asarray(x, dtype=float)
    h0 = np.finfo(float).eps ** (1.0 / 3.0) if rel_step is None else rel_step
    cols = []
    for j in range(x.size):
        h = h0 * max(1.0, abs(x[j]))
        xp = x.copy()
        xm = x.copy()
        xp[j] += h
        xm[j] -= h
        cols.append((np.asarray(fun(xp), dtype=float) - np.asarray(fun(xm), dtype=float)) / (2 * h))
    return np.column_stack(cols) if cols else np.zeros((np.asarray(fun(x)).size, 0))


__all__ = ["fd_jacobian"]
