r"""Compiled collocation and continuity rows of every collocated orbit, and a cycle's rows.

One kernel fills the rows that connections, landings and cycles share
(:class:`~continuation.bvp.layout.OrbitLayout`: the collocation rows of all stages,
then the continuity rows) from the orbit's values ``X`` (``(M, n)``, ``M = N (m + 1) +
1`` points) and ``f``, ``f_x``, ``f_p`` at the ``N m`` stages. Row ``s n + i`` of stage
``s = j m + k`` and row ``n N m + j n + i`` of interval ``j`` are::

    collocation   sum_l D[k,l] X_{j,l,i} / d_j - c f_i(X_{j,k}, p)
    continuity    sum_l e[l] X_{j,l,i} - X_{j+1,0,i}

with the row scale ``d_j`` and the factor ``c`` of the problem: a connection or landing
(:mod:`continuation.bvp.casadi_backend`, through :func:`collocation_residual` and
:func:`linearize`) has ``d_j = h_j T``, ``c = 1`` (its truncation time ``T`` is data), a
cycle (:mod:`continuation.periodic.problem`, through :func:`cycle_residual` and
:func:`cycle_linearize`, which call the same functions) ``d_j = h_j``, ``c = T`` (its
period is an unknown); each keeps the scaling, and so the Newton iterates and
tolerances, it had before the rows were shared. The values of the Jacobian are written
into one array ``vals`` in the order::

    blocks      B[j,k,l] = D[k,l] / d_j I - [l = k+1] c f_x(X_{j,k})    (N, m, m+1, n, n)
    parameters  -c f_p(X_s)[i, q]                                       (N m, n, n_p)
    continuity  e[l] at (j, l, i), then -1 at (j, i)                    (N (m+1) n + N n)

(the constant part ``D[k,l] / d_j I`` of the blocks given, :func:`constant_blocks`),
after which come the values of the problem's own rows; the CSC data of the problem's
pattern are then taken from ``vals`` (``order``: the ``vals`` index of each CSC slot;
``slot_of``, if not empty, sums duplicates, :func:`scatter`). A pattern needs not take
every value: a connection's takes only the diagonal of the blocks ``l != k + 1``, as its
CasADi graph had, a cycle's the whole blocks.

A cycle's own rows (:class:`~continuation.periodic.collocation.CollocationLayout`):
periodicity ``x_N - x_0 - shift`` (``n``) and the integral phase condition
``sum_s w_s <X_s - ref_s, dref_s>`` (1); its Jacobian values after the shared ones are
the periodicity entries ``+-1``, the ``T`` column ``-f`` of the collocation rows and
the phase row ``w_s dref_s``, and its ``dG/dp`` is ``-T f_p`` on the collocation rows.
All of it is one call, in place of a dozen NumPy calls whose overhead dominates at the
sizes of continuation.

``f_x`` arrives as ``J[s, a, b] = df_a/dx_b`` and ``f_p`` as ``Jp[s, i, q]`` (row-major
blocks). Compiled on first use and cached on disk (one module: Numba's cache does not
track calls across modules, so the cycle's functions live beside the shared ones).
"""

from __future__ import annotations

from typing import Any

import numba

_jit = numba.njit(cache=True, nogil=True, boundscheck=False)


@_jit
def collocation_residual(
    X: Any, F: Any, c: float, D: Any, e: Any, d: Any, G: Any
) -> None:  # pragma: no cover - compiled
    """Collocation and continuity rows of ``G`` (its first ``n N (m + 1)`` entries)."""
    n = X.shape[1]
    N = d.shape[0]
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
                G[row + i] = acc / d[j] - c * F[j * m + k, i]
        row = rc + j * n
        for i in range(n):
            acc = 0.0
            for l in range(m1):
                acc += e[l] * X[base + l, i]
            G[row + i] = acc - X[base + m1, i]


@_jit
def collocation_values(
    J: Any, Jp: Any, c: float, Bc: Any, e: Any, vals: Any
) -> int:  # pragma: no cover - compiled
    """Blocks, parameter columns and continuity entries into ``vals`` (module doc).

    ``Bc`` holds the constant part ``D[k,l] / d_j I`` of the blocks, flattened
    (:func:`constant_blocks`). Returns the number of values written.
    """
    K, n = J.shape[0], J.shape[1]
    n_p = Jp.shape[2]
    m1 = e.shape[0]
    m = m1 - 1
    N = K // m
    nB = Bc.size
    for q in range(nB):
        vals[q] = Bc[q]
    for j in range(N):
        for k in range(m):
            s = j * m + k
            base = ((s * m1 + k + 1) * n) * n  # the block l = k + 1 of stage s
            for a in range(n):
                for b in range(n):
                    vals[base + a * n + b] -= c * J[s, a, b]
    off = nB
    for s in range(K):
        for i in range(n):
            for q in range(n_p):
                vals[off + (s * n + i) * n_p + q] = -c * Jp[s, i, q]
    off += K * n * n_p
    for j in range(N):
        for l in range(m1):
            for i in range(n):
                vals[off + (j * m1 + l) * n + i] = e[l]
    off += N * m1 * n
    for q in range(N * n):
        vals[off + q] = -1.0
    return off + N * n


@_jit
def scatter(vals: Any, order: Any, slot_of: Any, data: Any) -> None:  # pragma: no cover
    """``data[q] = vals[order[q]]`` (``slot_of`` empty), else the sums into ``slot_of``."""
    if slot_of.size == 0:
        for q in range(data.size):
            data[q] = vals[order[q]]
    else:
        for q in range(data.size):
            data[q] = 0.0
        for q in range(order.size):
            data[slot_of[q]] += vals[order[q]]


@_jit
def linearize(
    X: Any, F: Any, J: Any, Jp: Any, c: float, D: Any, e: Any, d: Any, Bc: Any, G: Any,
    vals: Any, order_z: Any, data_z: Any, order_p: Any, data_p: Any,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """The shared rows of ``G`` and the CSC data of ``dG/dz`` and ``dG/dp``.

    ``vals`` holds, after the values :func:`collocation_values` writes, those of the
    problem's own rows (written by the caller before the call); ``order_z`` and
    ``order_p`` place them into the data of the two patterns (no duplicates).
    """
    collocation_residual(X, F, c, D, e, d, G)
    collocation_values(J, Jp, c, Bc, e, vals)
    for q in range(data_z.size):
        data_z[q] = vals[order_z[q]]
    for q in range(data_p.size):
        data_p[q] = vals[order_p[q]]


@_jit
def cycle_residual(
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
def cycle_linearize(
    X: Any, T: float, F: Any, J: Any, Jp: Any, D: Any, e: Any, h: Any, shift: Any,
    ref: Any, dref: Any, w: Any, stage_points: Any, Bc: Any, const_vals: Any,
    order: Any, slot_of: Any, G: Any, vals: Any, data: Any, Gp: Any,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """A cycle's ``G``, the CSC values ``data`` of ``dG/dz`` and ``Gp`` (module doc).

    ``Bc`` is the constant part ``D[k,l] / h_j I`` of the blocks (flat). ``vals``
    receives the unordered values: first those of :func:`collocation_values` (the
    blocks ``B``,
    ``(N, m, m + 1, n, n)`` flattened, then ``-T f_p`` of ``Jp`` (``(N m, n, 1)``) and the
    continuity entries), then the periodicity entries ``const_vals``, the ``T`` column
    and the phase row. ``slot_of`` (empty: none) sums duplicates.
    """
    cycle_residual(X, T, F, D, e, h, shift, ref, dref, w, stage_points, G)
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


@_jit
def _constant_blocks(D: Any, d: Any, n: int, B: Any) -> None:  # pragma: no cover - compiled
    m, m1 = D.shape
    for j in range(d.shape[0]):
        for k in range(m):
            for l in range(m1):
                base = (((j * m + k) * m1 + l) * n) * n
                v = D[k, l] / d[j]
                for a in range(n):
                    for b in range(n):
                        B[base + a * n + b] = v if a == b else 0.0


def constant_blocks(D: Any, d: Any, n: int) -> Any:
    """The constant part ``D[k,l] / d_j I`` of the blocks, flat ``(N m (m + 1) n n,)``.

    ``D`` (``(m, m + 1)``) and ``d`` (``(N,)``) float arrays, ``n`` the state dimension.
    """
    import numpy as np

    m, m1 = D.shape
    B = np.empty(d.shape[0] * m * m1 * n * n)
    _constant_blocks(D, d, n, B)
    return B


__all__ = [
    "collocation_residual", "collocation_values", "constant_blocks", "cycle_linearize",
    "cycle_residual", "linearize", "scatter",
]  # fmt: skip
