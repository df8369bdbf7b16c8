r"""The one layout of an orbit discretised by collocation: connections, landings, cycles.

Every orbit the engine computes by Gauss-Legendre collocation on a
:class:`~continuation.bvp.collocation.CollocationMesh` (``N`` intervals, degree ``m``,
``M = N (m + 1) + 1`` mesh and collocation points) -- a connection between saddles
(:mod:`continuation.bvp.connection`), a landing from a given point onto a saddle
(:mod:`continuation.bvp.landing`) and a periodic orbit
(:mod:`continuation.periodic.problem`) -- is one boundary-value problem
:math:`x'(\tau) = T f(x, p)` on :math:`\tau \in [0, 1]` with its own boundary
conditions. :class:`OrbitLayout` fixes, once for all three, where the orbit's unknowns
and its collocation and continuity equations sit::

    unknowns   z[q n + i] = X_q[i]       q = 0..M-1 (points in tau order), i = 0..n-1
               z[n M:]                   the problem's own unknowns
    rows       s n + i                   collocation at stage s = j m + k      (n N m)
               n N m + j n + i           continuity of interval j               (n N)
               n N (m + 1):              the problem's boundary conditions

The equations of interval ``j`` (``X_{j,0} = x_j`` its left node, ``X_{j,k}`` its stage
values, ``D``, ``e`` the mesh's derivative and end-value tableaux)::

    collocation   sum_l D[k,l] X_{j,l} / h_j  =  T f(X_{j,k}, p)        k = 1..m
    continuity    sum_l e[l] X_{j,l} - x_{j+1} = 0

and the boundary conditions of each problem:

* connection: ``f(x_-) = 0`` (and ``f(x_+) = 0``), the Riccati equations and the
  projection conditions at both ends, the phase condition; own unknowns the saddles,
  the Riccati unknowns and the solved parameters;
* landing: ``x(0) = x_0(s)``, ``f(x_e) = 0``, the Riccati equations and the projection
  condition at the end (the start point fixes the time shift: no phase condition);
  own unknowns ``x_e``, the Riccati unknowns and the solved parameters;
* periodic orbit: ``x(1) - x(0) = k o period`` and the integral phase condition; own
  unknown the period ``T``.

A landing is a connection whose start condition is a point instead of a saddle
(:attr:`~continuation.bvp.casadi_backend.ConnectionLayout.start_point`); a periodic
orbit is one whose ends are tied to each other.

Because the stage values of interval ``j`` appear only in its own ``n m`` collocation
rows, the stage blocks (:meth:`OrbitLayout.stage_blocks`) are eliminated interval by
interval before a small LU (:class:`~continuation.bvp.condense.StageCondenser`, as
AUTO-07p's condensation of parameters) -- one condensation for all three problems.
:class:`~continuation.bvp.casadi_backend.ConnectionLayout` (connections and landings) is
an :class:`OrbitLayout`; :class:`~continuation.periodic.collocation.CollocationLayout`
(cycles) holds one. The integral phase condition of connections and cycles takes its
reference from :func:`phase_reference`.

Accuracy: every adaptive mesh equidistributes the monitor of
:class:`~continuation.bvp.collocation.LocalError`
(:meth:`~continuation.bvp.collocation.CollocationMesh.equidistributed`), and a cycle's
error estimate (its records, its mesh refinement and its ``error_tol``) is that same
estimate. Connections and landings then bound their *solved parameters* by re-solves
on the halved mesh and on a longer interval (:func:`~continuation.bvp.accuracy.controlled`,
one loop for both). A cycle's mesh adaptation and the discretisation estimate of its
parameter at a period limit are two steps of that loop
(:func:`~continuation.bvp.accuracy.adapted`,
:func:`~continuation.bvp.accuracy.discretisation_changes`) with the cycle's re-solves
(:func:`~continuation.periodic.solve.cycle_resolves`); a cycle has no truncation, and the
size of its mesh follows its orbit's error estimate against ``error_tol`` (along a branch
its parameter is the continuation parameter, not a solved one).
Their results are one class body (:class:`~continuation.bvp.result.OrbitResult`; a
landing's result records its start condition) and one driver adapter
(:class:`~continuation.bvp.solve.ContinuedOrbit`).

What is shared in the values too: one compiled kernel
(:mod:`continuation.bvp._collocation_jit`) fills the collocation and continuity rows,
the values of their Jacobian in the orbit's unknowns (the blocks
``D[k, l] / d_j I - [l = k + 1] c f_x``) and their derivatives in the parameters
(``-c f_p``) for all three problems, from ``f``, ``f_x``, ``f_p`` at the stages; a
cycle's compiled residual and Jacobian (in the same module) call its functions, and so
does a connection's or landing's
:class:`~continuation.bvp.casadi_backend.ConnectionFunctions`. The two scalings of the
collocation row are its arguments ``d_j`` (the row scale) and ``c`` (the factor on
``f``): connections and landings divide by ``T``
(:math:`(1/(h_j T)) \sum_l D_{kl} X_{j,l} - f`: ``d_j = h_j T``, ``c = 1``), cycles
multiply ``f`` by their unknown period (``d_j = h_j``, ``c = T``), kept so that the Newton
iterates and tolerances are those of before.

What is *not* shared, and why: where the stage values and the boundary rows come from.
Connections and landings evaluate ``f``, ``f_x``, ``f_p`` at the stages in the same CasADi
graph (:mod:`continuation.bvp.casadi_backend`) as their boundary rows (Riccati
equations of the projection bases, equilibria, projections, start point, phase), which
need exact derivatives by automatic differentiation. Periodic orbits have linear
boundary rows (periodicity, phase), filled in their compiled kernel, and take ``f``,
``f_x``, ``f_p`` from a mapped point function
(:class:`~continuation.periodic.collocation.StageEvaluator`), compiled to C in the
background for a large model. Both place their entries by the index arrays of this
module.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..typing import FloatArray
from .collocation import CollocationMesh, stage_points, stage_unknowns


@dataclass(frozen=True)
class OrbitLayout:
    """Positions of the orbit's unknowns and of its collocation and continuity rows.

    Parameters
    ----------
    n : int
        State dimension.
    n_intervals : int
        ``N``, the mesh intervals.
    degree : int
        ``m``, Gauss-Legendre points per interval.
    """

    n: int
    n_intervals: int
    degree: int

    # ------------------------------------------------------------------ sizes
    @property
    def n_points(self) -> int:
        """``M = N (m + 1) + 1`` mesh and collocation points."""
        return self.n_intervals * (self.degree + 1) + 1

    @property
    def n_stages(self) -> int:
        """``N m`` collocation points."""
        return self.n_intervals * self.degree

    @property
    def n_orbit_unknowns(self) -> int:
        """``n M``: the values at all points, ``z[:n M]``."""
        return self.n * self.n_points

    @property
    def continuity_row(self) -> int:
        """``n N m``: the first continuity row (the collocation rows come first)."""
        return self.n * self.n_stages

    @property
    def boundary_row(self) -> int:
        """``n N (m + 1)``: the first row of the problem's boundary conditions."""
        return self.n * (self.n_stages + self.n_intervals)

    @property
    def stage_points(self) -> np.ndarray:
        """Point indices of the ``N m`` stages, shape ``(N m,)`` (:func:`.stage_points`)."""
        return _stage_points(self.n_intervals, self.degree)

    # ------------------------------------------------------------------ entries
    def collocation_blocks(self) -> tuple[np.ndarray, np.ndarray]:
        r"""Rows and columns of the collocation blocks, two arrays ``(N, m, m + 1, n, n)``.

        Entry ``[j, k, l, i, ii]`` is where :math:`\partial G_{j,k,i} / \partial X_{j,l,ii}`
        sits: the row of component ``i`` of the collocation equation at stage ``(j, k)``
        and the column of component ``ii`` of point ``l`` of interval ``j``
        (``D[k, l] / h_j`` on the diagonal ``i = ii``, and ``-T f_x`` at ``l = k + 1``).
        """
        return _collocation_blocks(self.n, self.n_intervals, self.degree)

    def continuity_entries(self, e: FloatArray) -> tuple[np.ndarray, np.ndarray, FloatArray]:
        """``(rows, cols, values)`` of the (constant) continuity Jacobian.

        ``e[l]`` at ``(n N m + j n + i, (j (m + 1) + l) n + i)`` and ``-1`` at
        ``(n N m + j n + i, (j + 1) (m + 1) n + i)``: first all ``e`` entries
        (ordered ``j, l, i``), then the ``-1`` entries (``j, i``).
        """
        n, N, m = self.n, self.n_intervals, self.degree
        m1 = m + 1
        j, l, i = np.meshgrid(np.arange(N), np.arange(m1), np.arange(n), indexing="ij")
        rows_e = (self.continuity_row + j * n + i).ravel()
        cols_e = ((j * m1 + l) * n + i).ravel()
        vals_e = np.broadcast_to(np.asarray(e, dtype=float)[None, :, None], (N, m1, n)).ravel()
        jj, ii = np.meshgrid(np.arange(N), np.arange(n), indexing="ij")
        rows_1 = (self.continuity_row + jj * n + ii).ravel()
        cols_1 = ((jj + 1) * m1 * n + ii).ravel()
        return (
            np.concatenate([rows_e, rows_1]),
            np.concatenate([cols_e, cols_1]),
            np.concatenate([vals_e, -np.ones(rows_1.size)]),
        )

    def stage_blocks(self) -> tuple[np.ndarray, np.ndarray]:
        """Collocation rows and stage unknowns of each interval, two ``(N, m n)`` arrays.

        The rows of interval ``j`` involve only its own stage values besides the mesh
        nodes: the blocks that :class:`~continuation.bvp.condense.StageCondenser`
        eliminates.
        """
        n, N, m = self.n, self.n_intervals, self.degree
        rows = np.arange(N * m * n).reshape(N, m * n)
        return rows, stage_unknowns(n, N, m)

    # ------------------------------------------------------------------ matrices
    def derivative_matrix(self, D: FloatArray) -> sp.csc_matrix:
        """The constant part ``sum_l D[k, l] X_{j,l}`` of the collocation rows, ``(n N m, n M)``.

        The diagonal (``i = ii``) of :meth:`collocation_blocks` with the values
        ``D[k, l]``; with ``n = 1`` it acts on one state's values at the ``M`` points.
        """
        rows, cols = self.collocation_blocks()
        n = self.n
        diag = np.arange(n)
        r = rows[..., diag, diag]  # (N, m, m+1, n)
        c = cols[..., diag, diag]
        D = np.asarray(D, dtype=float)
        vals = np.broadcast_to(D[None, :, :, None], r.shape)
        return sp.csc_matrix(
            (vals.ravel(), (r.ravel(), c.ravel())),
            shape=(n * self.n_stages, self.n_orbit_unknowns),
        )

    def stage_selection(self) -> sp.csc_matrix:
        """``Sel`` ``(n N m, n M)``: ``Sel z`` are the stage values, row ``s n + i``.

        The entries of :meth:`collocation_blocks` at ``l = k + 1``, ``i = ii`` (where
        ``-T f_x(X_{j,k})`` sits) with the value 1.
        """
        rows, cols = self.collocation_blocks()
        n, m = self.n, self.degree
        diag = np.arange(n)
        k = np.arange(m)
        r = rows[:, k, k + 1][..., diag, diag]  # (N, m, n)
        c = cols[:, k, k + 1][..., diag, diag]
        return sp.csc_matrix(
            (np.ones(r.size), (r.ravel(), c.ravel())),
            shape=(n * self.n_stages, self.n_orbit_unknowns),
        )

    def continuity_matrix(self, e: FloatArray) -> sp.csc_matrix:
        """The continuity rows as a matrix ``(n N, n M)`` (rows counted from ``n N m``)."""
        rows, cols, vals = self.continuity_entries(e)
        return sp.csc_matrix(
            (vals, (rows - self.continuity_row, cols)),
            shape=(self.n * self.n_intervals, self.n_orbit_unknowns),
        )


def phase_reference(mesh: CollocationMesh, X: FloatArray) -> tuple[FloatArray, FloatArray]:
    r"""The reference of the integral phase condition of connections and cycles.

    The condition (Doedel & Friedman 1989; AUTO-07p) is the Gauss quadrature at the
    stages of :math:`\int_0^1 \langle x(\tau) - \hat x(\tau), \hat x'(\tau) \rangle
    d\tau = 0`, i.e. :math:`\sum_j h_j \sum_k b_k \langle X_{j,k} - \hat X_{j,k},
    \hat X'_{j,k} \rangle = 0`.

    Parameters
    ----------
    mesh : CollocationMesh
    X : ndarray, shape (M, n)
        The reference orbit :math:`\hat x` at all points of ``mesh``.

    Returns
    -------
    ref, dref : ndarray, shape (N m, n)
        :math:`\hat X_{j,k}` and :math:`\hat X'_{j,k}` (``d/dtau`` of the collocation
        polynomial) at the stages, in stage order.
    """
    X = np.asarray(X, dtype=float)
    return X[_stage_points(mesh.n_intervals, mesh.degree)], mesh.derivative(X)


@functools.lru_cache(maxsize=32)
def _stage_points(N: int, m: int) -> np.ndarray:
    out = stage_points(N, m)
    out.setflags(write=False)
    return out


#: (a few MB for the ship: 8 states, 90 intervals of degree 4; as many as the cycle
#: layouts keep, continuation.periodic.collocation.PATTERNS_KEPT)
@functools.lru_cache(maxsize=8)
def _collocation_blocks(n: int, N: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    m1 = m + 1
    j, k, l, i, ii = np.meshgrid(
        np.arange(N), np.arange(m), np.arange(m1), np.arange(n), np.arange(n), indexing="ij"
    )
    rows = (j * m + k) * n + i
    cols = (j * m1 + l) * n + ii
    for a in (rows, cols):
        a.setflags(write=False)
    return rows, cols


__all__ = ["OrbitLayout", "phase_reference"]
