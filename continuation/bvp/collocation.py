r"""Gauss-Legendre collocation meshes on the scaled interval :math:`\tau \in [0, 1]`.

A boundary-value problem :math:`\dot x = f(x, p)` on :math:`t \in [0, T]` is written
in the scaled time :math:`\tau = t / T` as :math:`x'(\tau) = T f(x, p)`. The unit
interval is cut into ``N`` intervals :math:`[\tau_j, \tau_{j+1}]` of lengths
:math:`h_j`. On each interval the solution is a polynomial of degree ``m``
(the ``degree``) that interpolates the left mesh value :math:`x_j` at the local
coordinate :math:`s = 0` and ``m`` stage values :math:`x_{j,k}` at the
Gauss-Legendre points :math:`c_1 < \dots < c_m` of :math:`(0, 1)`::

    x_j(s) = sum_{l=0..m} L_l(s) X_{j,l},     X_{j,0} = x_j,  X_{j,k} = x_{j,k}
    collocation:  (1 / (h_j T)) sum_l L_l'(c_k) X_{j,l} = f(X_{j,k}, p),   k = 1..m
    continuity:   sum_l L_l(1) X_{j,l} = x_{j+1}

This is the Gauss (Runge-Kutta) collocation method: for smooth solutions the
error at the mesh points is :math:`O(h^{2m})` (superconvergence) and the uniform
error of the piecewise polynomial, in particular at the collocation points, is
:math:`O(h^{m+1})` (de Boor & Swartz 1973, "Collocation at Gaussian points", SIAM J.
Numer. Anal. 10:582-606; Ascher, Mattheij & Russell 1995, "Numerical Solution of
Boundary Value Problems for ODEs", SIAM, ch. 5).

:class:`CollocationMesh` holds the nodes, the degree and the truncation time ``T``
and precomputes the constant matrices (built once, reused by every residual).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..typing import FloatArray

MAX_DEGREE = 12


@functools.lru_cache(maxsize=32)
def _gauss_tableau(m: int) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Gauss points ``c`` (m,), weights ``b`` (m,), derivative ``D`` (m, m+1), end ``e`` (m+1,)."""
    xg, wg = np.polynomial.legendre.leggauss(m)
    c = 0.5 * (xg + 1.0)
    b = 0.5 * wg
    nodes = np.concatenate(([0.0], c))
    D = _lagrange_derivative(nodes, c)
    e = _lagrange_values(nodes, np.array([1.0]))[0]
    for a in (c, b, D, e):
        a.setflags(write=False)
    return c, b, D, e


def _lagrange_values(nodes: FloatArray, s: FloatArray) -> FloatArray:
    """``L[i, l] = L_l(s_i)`` for the Lagrange basis on ``nodes``; shape (len(s), len(nodes))."""
    s = np.asarray(s, dtype=float).reshape(-1)
    q = nodes.size
    out = np.ones((s.size, q))
    for l in range(q):
        for i in range(q):
            if i != l:
                out[:, l] *= (s - nodes[i]) / (nodes[l] - nodes[i])
    return out


def _lagrange_derivative(nodes: FloatArray, s: FloatArray) -> FloatArray:
    """``D[i, l] = L_l'(s_i)``; shape (len(s), len(nodes))."""
    s = np.asarray(s, dtype=float).reshape(-1)
    q = nodes.size
    out = np.zeros((s.size, q))
    for l in range(q):
        for i in range(q):
            if i == l:
                continue
            term = np.full(s.size, 1.0 / (nodes[l] - nodes[i]))
            for j in range(q):
                if j not in (l, i):
                    term *= (s - nodes[j]) / (nodes[l] - nodes[j])
            out[:, l] += term
    return out


def _uniform(n: int) -> FloatArray:
    return np.linspace(0.0, 1.0, n + 1)


@functools.lru_cache(maxsize=32)
def _leading(m: int) -> FloatArray:
    """``m!`` times the leading coefficients of the Lagrange basis on ``(0, c_1..c_m)``."""
    local = np.concatenate(([0.0], _gauss_tableau(m)[0]))
    lead = np.array(
        [1.0 / np.prod([local[l] - local[i] for i in range(m + 1) if i != l]) for l in range(m + 1)]
    ) * float(np.prod(np.arange(1, m + 1)))
    lead.setflags(write=False)
    return lead


def stage_points(n_intervals: int, degree: int) -> np.ndarray:
    """Indices ``j (m + 1) + k`` (``k = 1..m``) of the collocation points, shape ``(N m,)``.

    The points of every discretisation on a :class:`CollocationMesh` are ordered
    interval by interval (:attr:`CollocationMesh.tau`); the unknowns of connections,
    landings and periodic orbits hold their values point-major, ``z[q n + i]``.
    """
    m1 = degree + 1
    return np.array([j * m1 + k for j in range(n_intervals) for k in range(1, m1)])


def stage_unknowns(n: int, n_intervals: int, degree: int) -> np.ndarray:
    """Positions of the stage unknowns of each interval in ``z``, shape ``(N, m n)``.

    Row ``j`` lists ``q n + i`` for the ``m`` collocation points ``q`` of interval ``j``
    (``z`` point-major, see :func:`stage_points`): the columns that the stage
    condensation (:class:`~continuation.bvp.condense.StageCondenser`) eliminates.
    """
    stage = stage_points(n_intervals, degree).reshape(n_intervals, degree)
    return (stage[:, :, None] * n + np.arange(n)).reshape(n_intervals, degree * n)


@dataclass(frozen=True, eq=False)
class CollocationMesh:
    r"""A collocation mesh on :math:`[0, 1]` with ``n_intervals`` intervals, degree ``m``.

    Parameters
    ----------
    n_intervals : int
        Number of mesh intervals ``N >= 1``.
    degree : int
        Number ``m >= 1`` of Gauss-Legendre collocation points per interval (the
        local polynomial has degree ``m``).
    T : float
        Truncation time: the physical time interval is ``[0, T]``, ``t = T * tau``.
    nodes : array_like, shape (N + 1,), optional
        Mesh nodes :math:`0 = \tau_0 < \dots < \tau_N = 1`; uniform by default.

    Attributes
    ----------
    order : int
        ``2 m``: convergence order of the mesh-point values.
    uniform_order : int
        ``m + 1``: convergence order of the piecewise polynomial everywhere,
        including the collocation points.

    Raises
    ------
    ValueError
        If ``n_intervals < 1``, ``degree`` is not in ``[1, 12]``, ``T <= 0`` or the
        nodes are not strictly increasing from 0 to 1.
    """

    n_intervals: int
    degree: int
    T: float
    # None: Gauss-Legendre nodes, set in __post_init__
    nodes: FloatArray = field(default=None, repr=False)  # type: ignore[arg-type]

    def __post_init__(self) -> None:
        if isinstance(self.n_intervals, bool) or not isinstance(
            self.n_intervals, (int, np.integer)
        ):
            raise ValueError(f"`n_intervals` must be an integer >= 1, got {self.n_intervals!r}")
        if self.n_intervals < 1:
            raise ValueError(f"`n_intervals` must be an integer >= 1, got {self.n_intervals!r}")
        if isinstance(self.degree, bool) or not isinstance(self.degree, (int, np.integer)):
            raise ValueError(
                f"`degree` must be an integer in [1, {MAX_DEGREE}], got {self.degree!r}"
            )
        if not 1 <= self.degree <= MAX_DEGREE:
            raise ValueError(
                f"`degree` must be an integer in [1, {MAX_DEGREE}], got {self.degree!r}"
            )
        T = float(self.T)
        if not (np.isfinite(T) and T > 0):
            raise ValueError(f"`T` must be a positive finite time, got {self.T!r}")
        object.__setattr__(self, "n_intervals", int(self.n_intervals))
        object.__setattr__(self, "degree", int(self.degree))
        object.__setattr__(self, "T", T)
        if self.nodes is None:
            nodes = _uniform(self.n_intervals)
        else:
            nodes = np.array(self.nodes, dtype=float).reshape(-1)
            if nodes.shape != (self.n_intervals + 1,):
                raise ValueError(
                    f"`nodes` must have shape ({self.n_intervals + 1},) for "
                    f"n_intervals={self.n_intervals}, got {nodes.shape}"
                )
            if not np.all(np.isfinite(nodes)) or nodes[0] != 0.0 or nodes[-1] != 1.0:
                raise ValueError("`nodes` must start at 0.0 and end at 1.0")
            if np.any(np.diff(nodes) <= 0):
                raise ValueError("`nodes` must be strictly increasing")
        nodes.setflags(write=False)
        object.__setattr__(self, "nodes", nodes)

    # ------------------------------------------------------------------ tableau
    @property
    def c(self) -> FloatArray:
        """Gauss-Legendre points on (0, 1), shape ``(m,)``."""
        return _gauss_tableau(self.degree)[0]

    @property
    def b(self) -> FloatArray:
        """Gauss-Legendre weights on (0, 1), shape ``(m,)``; they sum to 1."""
        return _gauss_tableau(self.degree)[1]

    @property
    def D(self) -> FloatArray:
        """``D[k, l] = L_l'(c_k)``, shape ``(m, m + 1)``; basis on ``(0, c_1..c_m)``."""
        return _gauss_tableau(self.degree)[2]

    @property
    def e(self) -> FloatArray:
        """``e[l] = L_l(1)``, shape ``(m + 1,)``: the polynomial's value at the interval end."""
        return _gauss_tableau(self.degree)[3]

    @property
    def order(self) -> int:
        """Order ``2 m`` of the error at mesh points."""
        return 2 * self.degree

    @property
    def uniform_order(self) -> int:
        """Order ``m + 1`` of the uniform error (mesh and collocation points)."""
        return self.degree + 1

    # ------------------------------------------------------------------ geometry
    @property
    def h(self) -> FloatArray:
        """Interval lengths in ``tau``, shape ``(N,)``."""
        return np.diff(self.nodes)

    @property
    def n_points(self) -> int:
        """Number ``M = N (m + 1) + 1`` of mesh plus collocation points."""
        return self.n_intervals * (self.degree + 1) + 1

    @property
    def tau(self) -> FloatArray:
        """All points (mesh and collocation) in increasing order, shape ``(M,)``.

        Point ``j (m + 1)`` is mesh node ``j``; points ``j (m + 1) + k`` (``k = 1..m``)
        are the collocation points of interval ``j``.
        """
        local = np.concatenate(([0.0], self.c))
        pts = self.nodes[:-1, None] + self.h[:, None] * local[None, :]
        return np.concatenate((pts.reshape(-1), [1.0]))

    @property
    def t(self) -> FloatArray:
        """Physical times ``T * tau``, shape ``(M,)``."""
        return self.T * self.tau

    @property
    def mesh_mask(self) -> np.ndarray:
        """Boolean mask of the mesh nodes among the ``M`` points, shape ``(M,)``."""
        mask = np.zeros(self.n_points, dtype=bool)
        mask[:: self.degree + 1] = True
        return mask

    @property
    def stage_mask(self) -> np.ndarray:
        """Boolean mask of the collocation points among the ``M`` points, shape ``(M,)``."""
        return ~self.mesh_mask

    # ------------------------------------------------------------------ derived meshes
    def refined(self) -> CollocationMesh:
        """The mesh with every interval halved (``2 N`` intervals)."""
        mid = 0.5 * (self.nodes[:-1] + self.nodes[1:])
        nodes = np.empty(2 * self.n_intervals + 1)
        nodes[0::2] = self.nodes
        nodes[1::2] = mid
        return CollocationMesh(2 * self.n_intervals, self.degree, self.T, nodes)

    def with_T(self, T: float) -> CollocationMesh:
        """Same nodes, new truncation time ``T``."""
        return CollocationMesh(self.n_intervals, self.degree, T, self.nodes)

    def with_nodes(self, nodes: FloatArray) -> CollocationMesh:
        """Same degree and ``T``, new nodes (shape ``(N' + 1,)``)."""
        nodes = np.asarray(nodes, dtype=float)
        return CollocationMesh(nodes.size - 1, self.degree, self.T, nodes)

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly description."""
        return {
            "n_intervals": self.n_intervals,
            "degree": self.degree,
            "T": self.T,
            "nodes": [float(v) for v in self.nodes],
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> CollocationMesh:
        """Inverse of :meth:`to_dict`."""
        return cls(int(d["n_intervals"]), int(d["degree"]), float(d["T"]), np.array(d["nodes"]))

    # ------------------------------------------------------------------ polynomials
    def interpolate(self, X: FloatArray, tau: FloatArray) -> FloatArray:
        """Evaluate the piecewise collocation polynomial at ``tau``.

        Parameters
        ----------
        X : ndarray, shape (M, n)
            Values at all points (:attr:`tau` order).
        tau : ndarray, shape (K,)
            Evaluation points in ``[0, 1]``.

        Returns
        -------
        ndarray, shape (K, n)
        """
        X = np.asarray(X, dtype=float)
        if X.ndim != 2 or X.shape[0] != self.n_points:
            raise ValueError(f"`X` must have shape ({self.n_points}, n), got {X.shape}")
        tau = np.clip(np.asarray(tau, dtype=float).reshape(-1), 0.0, 1.0)
        j = np.clip(np.searchsorted(self.nodes, tau, side="right") - 1, 0, self.n_intervals - 1)
        s = (tau - self.nodes[j]) / self.h[j]
        local = np.concatenate(([0.0], self.c))
        L = _lagrange_values(local, s)  # (K, m+1)
        m1 = self.degree + 1
        idx = j[:, None] * m1 + np.arange(m1)[None, :]  # (K, m+1)
        return np.einsum("kl,kln->kn", L, X[idx])

    def derivative(self, X: FloatArray) -> FloatArray:
        """``dx/dtau`` of the piecewise polynomial at the collocation points, shape (N m, n)."""
        X = np.asarray(X, dtype=float)
        m1 = self.degree + 1
        blocks = X[: self.n_intervals * m1].reshape(self.n_intervals, m1, -1)  # (N, m+1, n)
        dX = (self.D @ blocks) / self.h[:, None, None]
        return dX.reshape(-1, X.shape[1])

    @property
    def leading(self) -> FloatArray:
        """``m!`` times the leading Lagrange coefficients, shape ``(m + 1,)``.

        The ``m``-th ``tau``-derivative of the polynomial of interval ``j`` is
        ``leading @ X_j / h_j^m`` (``X_j`` its ``m + 1`` values, :meth:`highest_derivative`).
        """
        return _leading(self.degree)

    def highest_derivative(self, X: FloatArray) -> FloatArray:
        """The (constant) ``m``-th ``tau``-derivative of each interval polynomial, shape (N, n)."""
        X = np.asarray(X, dtype=float)
        m = self.degree
        lead = self.leading
        m1 = m + 1
        blocks = X[: self.n_intervals * m1].reshape(self.n_intervals, m1, -1)  # (N, m+1, n)
        return (lead @ blocks) / self.h[:, None] ** m

    def equidistributed(
        self,
        X: FloatArray,
        n_intervals: int | None = None,
        fixed: tuple[int, float] | None = None,
    ) -> CollocationMesh:
        r"""A new mesh that equidistributes the local error monitor of ``X``.

        The local error of degree-``m`` collocation on interval ``j`` behaves like
        :math:`h_j^{m+1} |x^{(m+1)}|` (Russell & Christiansen 1978, "Adaptive mesh
        selection strategies for solving boundary value problems", SIAM J. Numer.
        Anal. 15:59-80). :math:`x^{(m+1)}` is estimated from differences of the
        piecewise-constant ``m``-th derivative between neighbouring intervals
        (:meth:`LocalError.derivative`, one-sided at the ends; the same estimate as the
        mesh error of a cycle, :func:`~continuation.periodic.problem.error_estimate`), and
        the new nodes equidistribute :math:`\int \rho`, with
        :math:`\rho = (\max_i |x_i^{(m+1)}|)^{1/(m+1)}` plus a floor of 5% of its
        mean, which keeps intervals from growing without bound where ``x`` is flat.

        Parameters
        ----------
        X : ndarray, shape (M, n)
            Solution values at all points of this mesh.
        n_intervals : int, optional
            Number of intervals of the new mesh (default: the same).
        fixed : (int, float), optional
            ``(j, tau)``: node ``j`` of the new mesh is placed at ``tau`` (a pinned phase
            condition keeps its node); the two sides are equidistributed separately.
        """
        N = self.n_intervals if n_intervals is None else int(n_intervals)
        if N < 1:
            raise ValueError(f"`n_intervals` must be >= 1, got {n_intervals}")
        if self.n_intervals >= 3:
            # the local error monitor of every collocated orbit (LocalError)
            w = np.max(np.abs(LocalError(self).derivative(X)), axis=1)
        else:
            w = np.max(np.abs(self.highest_derivative(X)), axis=1)
        rho = w ** (1.0 / (self.degree + 1))
        floor = 0.05 * float(np.sum(rho * self.h)) + 1e-300
        rho = rho + floor
        cum = np.concatenate(([0.0], np.cumsum(rho * self.h)))
        if fixed is None:
            targets = np.linspace(0.0, cum[-1], N + 1)
        else:
            j, at = int(fixed[0]), float(fixed[1])
            if not (0 < j < N and 0.0 < at < 1.0):
                raise ValueError(
                    f"`fixed` must be (j, tau) with 0 < j < N, 0 < tau < 1, got {fixed}"
                )
            c_at = float(np.interp(at, self.nodes, cum))
            targets = np.concatenate(
                (np.linspace(0.0, c_at, j + 1), np.linspace(c_at, cum[-1], N - j + 1)[1:])
            )
        nodes = np.interp(targets, cum, self.nodes)
        if fixed is not None:
            nodes[int(fixed[0])] = float(fixed[1])
        nodes[0], nodes[-1] = 0.0, 1.0
        # guard against coincident nodes from a degenerate monitor
        if np.any(np.diff(nodes) <= 1e-12):
            nodes = 0.5 * (nodes + _uniform(N))
        return CollocationMesh(N, self.degree, self.T, nodes)

    def __repr__(self) -> str:
        return (
            f"CollocationMesh(n_intervals={self.n_intervals}, degree={self.degree}, T={self.T:g})"
        )


class LocalError:
    r"""The local error of degree-``m`` collocation on one mesh: one estimate for all orbits.

    On interval ``j`` the uniform error of Gauss collocation of degree ``m`` is
    :math:`\approx C_m h_j^{m+1} |x^{(m+1)}|` (de Boor & Swartz 1973, "Collocation at
    Gaussian points", SIAM J. Numer. Anal. 10:582-606), with
    :math:`C_m = \max_{s \in [0, 1]} |\prod_k (s - c_k)| / (m + 1)!`. The derivative
    :math:`x^{(m+1)}` is estimated by differences of the piecewise-constant ``m``-th
    derivatives (:meth:`CollocationMesh.highest_derivative`) of neighbouring intervals,
    divided by the distance of their midpoints (Russell & Christiansen 1978).

    The one error path of connections, landings and periodic orbits: the monitor of
    :meth:`CollocationMesh.equidistributed` (the adaptive mesh of all three) and the
    error estimate of a cycle (:func:`~continuation.periodic.problem.error_estimate`:
    its records, the refinement of its mesh and the check of ``error_tol``). The
    factors that depend on the mesh only are computed once.

    Parameters
    ----------
    mesh : CollocationMesh
    periodic : bool
        The orbit closes on itself (a cycle): the differences wrap around the ends.
        Otherwise (default) they are one-sided at the first and last interval.
    """

    def __init__(self, mesh: CollocationMesh, periodic: bool = False) -> None:
        N, m = mesh.n_intervals, mesh.degree
        self.N, self.m, self.periodic = N, m, bool(periodic)
        self.lead = mesh.leading
        self.hm = (mesh.h**m)[:, None]  # (N, 1)
        mids = 0.5 * (mesh.nodes[:-1] + mesh.nodes[1:])
        if N >= 3:
            if self.periodic:
                mp = np.concatenate([[mids[-1] - 1.0], mids, [mids[0] + 1.0]])
                spacing = mp[2:] - mp[:-2]
            else:
                spacing = np.empty(N)
                spacing[1:-1] = mids[2:] - mids[:-2]
                spacing[0] = mids[1] - mids[0]
                spacing[-1] = mids[-1] - mids[-2]
            self.spacing = spacing[:, None]  # (N, 1)
        s = np.linspace(0.0, 1.0, 201)
        Cm = float(np.max(np.abs(np.prod(s[:, None] - mesh.c[None, :], axis=1))))
        Cm /= float(np.prod(np.arange(1, m + 2)))
        self.scale = (Cm * mesh.h ** (m + 1))[:, None]  # (N, 1)

    def derivative(self, X: FloatArray) -> FloatArray:
        """Estimate of :math:`x^{(m+1)}` (in ``tau``) on each interval, shape ``(N, n)``.

        ``X`` (M, n): the values at all points of the mesh. Needs ``N >= 3``.
        """
        N, m1 = self.N, self.m + 1
        if N < 3:
            raise ValueError(f"the local error needs at least 3 intervals, the mesh has {N}")
        X = np.asarray(X, dtype=float)
        dm = (self.lead @ X[: N * m1].reshape(N, m1, -1)) / self.hm  # (N, n)
        d = np.empty_like(dm)
        d[1:-1] = dm[2:] - dm[:-2]
        if self.periodic:
            d[0] = dm[1] - dm[-1]
            d[-1] = dm[0] - dm[-2]
        else:
            d[0] = dm[1] - dm[0]
            d[-1] = dm[-1] - dm[-2]
        return d / self.spacing  # type: ignore[no-any-return]

    def __call__(self, X: FloatArray) -> float:
        """``max_j C_m h_j^{m+1} |x^{(m+1)}|`` over intervals and states (nan for ``N < 3``).

        An estimate (good to a factor of a few on resolved meshes), not a bound.
        """
        if self.N < 3:
            return float("nan")
        return float(np.max(self.scale * np.abs(self.derivative(X))))


__all__ = ["CollocationMesh", "LocalError", "MAX_DEGREE", "stage_points", "stage_unknowns"]
