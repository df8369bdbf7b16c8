r"""Compiled kernel of the periodic collocation system.

See :class:`~continuation.periodic.collocation.CollocationLayout`.

From the unknowns ``X`` (``(M, n)``, ``M = N (m + 1) + 1`` points), the period ``T``
and ``f``, ``f_x``, ``df/dp`` at the ``N m`` stage points, one call fills

* the residual ``G`` (collocation, continuity, periodicity and phase rows, in the
  order of :class:`~continuation.bvp.layout.OrbitLayout` shared with connections and
  landings: the collocation rows of all stages, then the continuity rows, then the
  boundary conditions),
* the values of the sparse Jacobian in its CSC order (the blocks
  :math:`B_{j,k,l} = D_{kl}/h_j I - [l = k+1] T f_x(x_{j,k})`, the constant continuity
  and periodicity entries, the ``T`` column ``-f`` and the phase row), as
  :meth:`CollocationLayout.blocks` does, on the pattern of :class:`CollocationLayout`,
* ``dG/dp`` (``-T df/dp`` on the collocation rows),

in place of a dozen NumPy calls whose overhead dominates at the sizes of continuation.
Compiled on first use and cached on disk.
"""

from __future__ import annotations

from typing import Any

import numba

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
    rc = N * m * n  # the continuity rows follow the collocation rows (OrbitLayout)
    for j in range(N):
        base = j * m1
        for k in range(m):
            row = (j * m + k) * n
            for i in range(n):
                acc = 0.0
                for l in range(m1):
                    acc += D[k, l] * X[base + l, i]
                G[row + i] = acc / h[j] - T * F[j * m + k, i]
        row = rc + j * n
        for i in range(n):
            acc = 0.0
            for l in range(m1):
                acc += e[l] * X[base + l, i]
            G[row + i] = acc - X[base + m1, i]
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
    X: Any, T: float, F: Any, J: Any, Jp0: Any, D: Any, e: Any, h: Any, shift: Any,
    ref: Any, dref: Any, w: Any, stage_points: Any, Bc: Any, const_vals: Any,
    order: Any, slot_of: Any, G: Any, vals: Any, data: Any, Gp: Any,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """``G``, the CSC values ``data`` of ``dG/dz`` and ``Gp`` (module doc).

    ``vals`` receives the unordered values, its first ``Bc.size`` entries the blocks ``B``
    (``(N, m, m + 1, n, n)`` flattened). ``slot_of`` (empty: none) sums duplicates.
    """
    residual(X, T, F, D, e, h, shift, ref, dref, w, stage_points, G)
    n = X.shape[1]
    N = h.shape[0]
    m, m1 = D.shape
    nB = Bc.size
    for q in range(nB):
        vals[q] = Bc[q]
    for j in range(N):
        for k in range(m):
            s = j * m + k
            base = (((j * m + k) * m1 + (k + 1)) * n) * n
            for a in range(n):
                for b in range(n):
                    vals[base + a * n + b] -= T * J[s, a, b]
    off = nB
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
    if slot_of.size == 0:
        for q in range(data.size):
            data[q] = vals[order[q]]
    else:
        for q in range(data.size):
            data[q] = 0.0
        for q in range(order.size):
            data[slot_of[q]] += vals[order[q]]
    for q in range(Gp.size):
        Gp[q] = 0.0
    for s in range(N * m):
        for i in range(n):
            Gp[s * n + i] = -T * Jp0[s, i]


__all__ = ["linearize", "residual"]
