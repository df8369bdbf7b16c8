r"""Compiled kernel of the periodic collocation system.

See :class:`~continuation.periodic.collocation.CollocationLayout`.

From the unknowns ``X`` (``(M, n)``, ``M = N (m + 1) + 1`` points), the period ``T``
and ``f``, ``f_x``, ``df/dp`` at the ``N m`` stage points, one call fills

* the residual ``G``: its collocation and continuity rows by the kernel of every
  collocated orbit (:func:`continuation.bvp._collocation_jit.collocation_residual`, the
  one connections and landings use, with the row scale ``h_j`` and the factor ``T`` on
  ``f``), then the cycle's periodicity and phase rows,
* the values of the sparse Jacobian in its CSC order: the blocks
  :math:`B_{j,k,l} = D_{kl}/h_j I - [l = k+1] T f_x(x_{j,k})` and the continuity entries
  (:func:`continuation.bvp._collocation_jit.collocation_values`), then the periodicity
  entries, the ``T`` column ``-f`` and the phase row, on the pattern of
  :class:`CollocationLayout`,
* ``dG/dp`` (``-T df/dp`` on the collocation rows),

in place of a dozen NumPy calls whose overhead dominates at the sizes of continuation.
Compiled on first use and cached on disk.
"""

from __future__ import annotations

from typing import Any

import numba

from ..bvp._collocation_jit import collocation_residual, collocation_values, scatter

_jit = numba.njit(cache=True, nogil=True, boundscheck=False)


@_jit
def residual(
    X: Any, T: float, F: Any, D: Any, e: Any, h: Any, shift: Any, ref: Any, dref: Any,
    w: Any, stage_points: Any, G: Any,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """``G`` (``(n M + 1,)``) of the cycle ``X``, ``T`` with ``f`` at the stages ``F``."""
    M, n = X.shape
    N = h.shape[0]
    m, m1 = D.shape
    collocation_residual(X, F, T, D, e, h, G)
    rp = N * m1 * n
    for i in range(n):
        G[rp + i] = X[M - 1, i] - X[0, i] - shift[i]
    acc = 0.0
    for s in range(N * m):
        q = stage_points[s]
        for i in range(n):
            acc += w[s] * (X[q, i] - ref[s, i]) * dref[s, i]
    G[rp + n] = acc


@_jit
def linearize(
    X: Any, T: float, F: Any, J: Any, Jp: Any, D: Any, e: Any, h: Any, shift: Any,
    ref: Any, dref: Any, w: Any, stage_points: Any, Bc: Any, const_vals: Any,
    order: Any, slot_of: Any, G: Any, vals: Any, data: Any, Gp: Any,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """``G``, the CSC values ``data`` of ``dG/dz`` and ``Gp`` (module doc).

    ``Bc`` is the constant part ``D[k,l] / h_j I`` of the blocks (flat). ``vals``
    receives the unordered values: first those of
    :func:`~continuation.bvp._collocation_jit.collocation_values` (the blocks ``B``,
    ``(N, m, m + 1, n, n)`` flattened, then ``-T f_p`` of ``Jp`` (``(N m, n, 1)``) and the
    continuity entries), then the periodicity entries ``const_vals``, the ``T`` column
    and the phase row. ``slot_of`` (empty: none) sums duplicates.
    """
    residual(X, T, F, D, e, h, shift, ref, dref, w, stage_points, G)
    n = X.shape[1]
    N = h.shape[0]
    m = D.shape[0]
    off = collocation_values(J, Jp, T, Bc, e, vals)
    for q in range(const_vals.size):
        vals[off + q] = const_vals[q]
    off += const_vals.size
    for s in range(N * m):
        for i in range(n):
            vals[off + s * n + i] = -F[s, i]
    off += N * m * n
    for s in range(N * m):
        for i in range(n):
            vals[off + s * n + i] = w[s] * dref[s, i]
    scatter(vals, order, slot_of, data)
    for q in range(Gp.size):
        Gp[q] = 0.0
    nB = N * m * (m + 1) * n * n
    for q in range(N * m * n):
        Gp[q] = vals[nB + q]


__all__ = ["linearize", "residual"]
