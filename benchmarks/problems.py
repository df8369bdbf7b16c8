r"""Benchmark problems for the continuation benchmark, one definition shared by every tool.

Each :class:`BenchmarkProblem` carries the same mathematics in three forms:

* ``rhs(x, p, ops)`` written once against :mod:`continuation.ops`, from which
  :class:`continuation.System` takes exact (and, for Bratu, sparse) CasADi Jacobians;
* vectorised NumPy functions ``f(x, p)``, ``jac(x, p)`` (dense, or SciPy sparse for the
  large Bratu grid) and ``dfdp(x, p)`` (derivative with respect to the free parameter),
  used by the SciPy baseline and the peer adapters (AUTO-07p's native build instead
  traces ``rhs`` itself symbolically, see ``peers/auto07p.py``);
* the start point ``(x0, params[free])``, which is an exact equilibrium, the stopping
  rule (parameter window ``[p_min, p_max]`` and a cap ``norm_max`` on the Euclidean
  norm ``||x||_2``) and the reference values of the special points on the branch.

Problems
--------
``bratu20``, ``bratu200``
    Liouville-Bratu-Gelfand problem :math:`u'' + \lambda e^u = 0`, :math:`u(0)=u(1)=0`,
    second-order central differences on ``N`` interior points, :math:`h = 1/(N+1)`::

        f_i(u, lam) = (u_{i-1} - 2 u_i + u_{i+1}) / h**2 + lam * exp(u_i),  u_0 = u_{N+1} = 0.

    Starts at ``lam = 0, u = 0``, passes the fold at :math:`\lambda^*_N` and stops on the
    upper branch when ``||u||_2`` reaches ``3 sqrt(N+1)`` (grid L2 norm 3, i.e.
    ``sqrt(h sum u_i**2) = 3 (1 + h)**0.5``), about ``lam = 1.3``. The reference fold of the
    discrete system comes from :func:`bratu_fold`, an extended-system Newton solve that
    shares no code with any continuation method; it converges at second order to the
    continuous value :math:`\lambda_c = 8 t^2/\cosh^2 t` with :math:`t \tanh t = 1`,
    :math:`\lambda_c = 3.513830719125161` (Gelfand 1963; e.g. Mohsen 2014, "A simple
    solution of the Bratu problem", Comput. Math. Appl. 67:26-33).
``brusselator``
    Prigogine & Lefever (1968) Brusselator ODE, ``x' = A - (B + 1) x + x**2 y``,
    ``y' = B x - x**2 y``, ``A = 1.5``, continued in ``B`` from 1 to 4 along the
    equilibrium ``(A, B/A)``. Its Jacobian there is ``[[B - 1, A**2], [-B, -A**2]]``
    (trace ``B - 1 - A**2``, determinant ``A**2``), so the Hopf point is exactly
    ``B = 1 + A**2 = 3.25`` with frequency ``omega = A``.
``cubic8``
    Eight states with two folds (designed for this benchmark)::

        x0' = p - x0**3 + 3 x0
        xk' = -k xk + c tanh(x_{k-1}),   k = 1..7,  c = 0.2.

    The Jacobian is lower bidiagonal with eigenvalues ``3 - 3 x0**2`` and ``-1..-7``, so
    it is singular exactly where ``x0 = +-1``: folds at ``p = x0**3 - 3 x0 = -2`` and
    ``p = 2`` exactly, whatever ``c``; there is no Hopf point. Equilibria are explicit:
    ``xk = c tanh(x_{k-1}) / k``. The branch starts at ``p = -4`` on the lower sheet,
    turns at ``p = 2``, comes back along the middle (unstable) sheet to ``p = -2`` and
    leaves on the upper sheet at ``p = p_max = 4``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize as opt
import scipy.sparse as sp

FloatArray = np.ndarray


@dataclass(frozen=True)
class ExpectedPoint:
    """A special point the branch must pass.

    Attributes
    ----------
    kind : {"fold", "hopf"}
        Kind of the point.
    p : float
        Reference value of the free parameter.
    source : str
        Where ``p`` comes from (closed form, independent solve, ...).
    """

    kind: str
    p: float
    source: str


@dataclass(frozen=True)
class BenchmarkProblem:
    """One benchmark problem, identical for every tool.

    Attributes
    ----------
    name : str
        Short key (``"bratu200"``).
    title : str
        Human description.
    state_names, param_names : tuple of str
        Names of the ``n`` states and ``m`` parameters.
    params : mapping
        Values of all parameters at the start (the free one included).
    free : str
        Continuation parameter.
    x0 : ndarray, shape (n,)
        Exact equilibrium at ``params``.
    p_min, p_max : float
        Parameter window; the branch stops on leaving it.
    norm_max : float
        The branch stops when ``||x||_2`` exceeds this (``inf``: no cap).
    rhs : callable
        ``rhs(x, p, ops)`` for :class:`continuation.System`.
    f, jac, dfdp : callable
        Vectorised NumPy ``f(x, p) -> (n,)``, ``jac(x, p) -> (n, n)`` (dense ndarray or
        SciPy CSC when ``sparse``) and ``dfdp(x, p) -> (n,)`` (free parameter only);
        ``p`` is the full parameter vector in ``param_names`` order.
    sparse : bool
        Whether sparse linear algebra is the right choice (large grid).
    expected : tuple of ExpectedPoint
        Special points on the branch, in the order they are met.
    ds, ds_min, ds_max : float
        Step-size settings shared by all tools.
    max_steps : int
        Step cap shared by all tools (not reached when the tools work).
    """

    name: str
    title: str
    state_names: tuple[str, ...]
    param_names: tuple[str, ...]
    params: Mapping[str, float]
    free: str
    x0: FloatArray
    p_min: float
    p_max: float
    norm_max: float
    rhs: Callable[..., Any]
    f: Callable[[FloatArray, FloatArray], Any]
    jac: Callable[[FloatArray, FloatArray], Any]
    dfdp: Callable[[FloatArray, FloatArray], FloatArray]
    sparse: bool
    expected: tuple[ExpectedPoint, ...]
    ds: float = 0.01
    ds_min: float = 1e-8
    ds_max: float = 0.1
    max_steps: int = 2000
    notes: str = field(default="")

    @property
    def n(self) -> int:
        """Number of states."""
        return len(self.state_names)

    @property
    def free_index(self) -> int:
        """Position of the free parameter in ``param_names``."""
        return self.param_names.index(self.free)

    @property
    def p0(self) -> float:
        """Start value of the free parameter."""
        return float(self.params[self.free])

    def step_settings(self) -> dict[str, float]:
        """The settings every tool takes from the problem, as keyword arguments.

        Returns
        -------
        dict
            ``ds``, ``ds_min``, ``ds_max`` (step sizes), ``p_min``, ``p_max`` (window of
            the free parameter) and ``max_steps`` (step cap).
        """
        return {
            "ds": self.ds,
            "ds_min": self.ds_min,
            "ds_max": self.ds_max,
            "p_min": self.p_min,
            "p_max": self.p_max,
            "max_steps": self.max_steps,
        }

    def param_vector(self, p_free: float | None = None) -> FloatArray:
        """Full parameter vector, shape ``(m,)``, with the free entry set to ``p_free``."""
        v = np.array([float(self.params[k]) for k in self.param_names])
        if p_free is not None:
            v[self.free_index] = p_free
        return v

    def system(self) -> Any:
        """A :class:`continuation.System` built from ``rhs`` (CasADi-traced)."""
        from continuation.system import System

        return System(
            self.rhs,
            self.state_names,
            self.param_names,
            defaults=dict(self.params),
            name=self.name,
            backend="casadi",
        )


# ----------------------------------------------------------------------------- Bratu
def _bratu_h(n: int) -> float:
    return 1.0 / (n + 1)


def _bratu_rhs(n: int) -> Callable[..., Any]:
    inv_h2 = 1.0 / _bratu_h(n) ** 2

    def rhs(x: Any, p: Any, ops: Any) -> Any:
        lam = p[0]
        out = []
        for i in range(n):
            left = x[i - 1] if i > 0 else 0.0
            right = x[i + 1] if i < n - 1 else 0.0
            out.append((left - 2.0 * x[i] + right) * inv_h2 + lam * ops.exp(x[i]))
        return ops.stack(out)

    rhs.__name__ = f"bratu{n}"
    return rhs


def _bratu_f(n: int) -> Callable[[FloatArray, FloatArray], Any]:
    inv_h2 = 1.0 / _bratu_h(n) ** 2

    def f(u: Any, p: Any) -> Any:
        u = np.asarray(u)
        zero = np.zeros(1, dtype=u.dtype)
        left = np.concatenate((zero, u[:-1]))
        right = np.concatenate((u[1:], zero))
        return (left - 2.0 * u + right) * inv_h2 + p[0] * np.exp(u)

    return f


def _bratu_laplacian(n: int) -> sp.csc_matrix:
    inv_h2 = 1.0 / _bratu_h(n) ** 2
    off = np.full(n - 1, inv_h2)
    return sp.diags([off, np.full(n, -2.0 * inv_h2), off], [-1, 0, 1], format="csc")


def _bratu_jac(n: int, sparse: bool) -> Callable[[FloatArray, FloatArray], Any]:
    lap = _bratu_laplacian(n)
    lap_dense = lap.toarray()

    def jac(u: FloatArray, p: FloatArray) -> Any:
        d = p[0] * np.exp(np.asarray(u, dtype=float))
        if sparse:
            return (lap + sp.diags(d, 0, format="csc")).tocsc()
        out = lap_dense.copy()
        out[np.diag_indices(n)] += d
        return out

    return jac


def _bratu_dfdp(u: FloatArray, p: FloatArray) -> FloatArray:
    return np.exp(np.asarray(u, dtype=float))


def bratu_fold(n: int, *, tol: float = 1e-11, max_iter: int = 30) -> tuple[float, FloatArray]:
    r"""Fold of the discrete Bratu problem by Newton on the standard extended system.

    Solves, for ``(u, v, lam)`` (shapes ``(n,)``, ``(n,)``, scalar)::

        f(u, lam) = 0,    J(u, lam) v = 0,    sum(v) - n = 0,

    with exact second derivatives (``d(J v)/du = diag(lam e^u v)``,
    ``d(J v)/dlam = e^u v``), starting from the continuous fold profile
    ``u(x) = 2 ln(cosh t / cosh((2x - 1) t))``, ``t tanh t = 1`` (Gelfand 1963) and
    ``v = 1``. This is independent of any continuation code. Newton stops one
    iteration after the step falls below ``tol`` (relative); the round-off floor of
    ``lam`` is about ``1e-16 / h**2`` (``~1e-13`` for ``n = 200``).

    Returns
    -------
    lam : float
        Fold value :math:`\lambda^*_n` of the discrete problem.
    u : ndarray, shape (n,)
        Solution at the fold.

    Raises
    ------
    ValueError
        If ``n < 2``.
    RuntimeError
        If Newton does not converge.
    """
    if n < 2:
        raise ValueError(f"`n` must be >= 2, got {n}")
    t = opt.brentq(lambda s: s * math.tanh(s) - 1.0, 0.5, 2.0, xtol=1e-15)
    lam = 8.0 * t * t / math.cosh(t) ** 2
    xg = np.arange(1, n + 1) * _bratu_h(n)
    u = 2.0 * np.log(math.cosh(t) / np.cosh((2.0 * xg - 1.0) * t))
    v = np.ones(n)
    lap = _bratu_laplacian(n).toarray()
    done = False
    for _ in range(max_iter):
        e = np.exp(u)
        J = lap + np.diag(lam * e)
        F = np.concatenate((lap @ u + lam * e, J @ v, [v.sum() - n]))
        A = np.zeros((2 * n + 1, 2 * n + 1))
        A[:n, :n] = J
        A[:n, 2 * n] = e
        A[n : 2 * n, :n] = np.diag(lam * e * v)
        A[n : 2 * n, n : 2 * n] = J
        A[n : 2 * n, 2 * n] = e * v
        A[2 * n, n : 2 * n] = 1.0
        d = np.linalg.solve(A, F)
        u, v, lam = u - d[:n], v - d[n : 2 * n], lam - d[2 * n]
        if done:  # one polishing step after the tolerance is met
            return float(lam), u
        done = bool(np.max(np.abs(d)) <= tol * (1.0 + np.max(np.abs(v))))
    raise RuntimeError(f"bratu_fold(n={n}) did not converge")


BRATU_CONTINUOUS_FOLD = 3.513830719125161
"""Fold of the continuous Bratu problem, ``8 t**2 / cosh(t)**2`` with ``t tanh t = 1``."""


def bratu(n: int) -> BenchmarkProblem:
    """The discrete Bratu problem with ``n`` interior points (see module docstring)."""
    sparse = n >= 100
    lam_fold, _ = bratu_fold(n)
    return BenchmarkProblem(
        name=f"bratu{n}",
        title=f"1-D Bratu, N={n} interior points (fold)",
        state_names=tuple(f"u{i + 1}" for i in range(n)),
        param_names=("lam",),
        params={"lam": 0.0},
        free="lam",
        x0=np.zeros(n),
        p_min=-1.0,
        p_max=4.0,
        norm_max=3.0 * math.sqrt(n + 1),
        rhs=_bratu_rhs(n),
        f=_bratu_f(n),
        jac=_bratu_jac(n, sparse),
        dfdp=_bratu_dfdp,
        sparse=sparse,
        expected=(ExpectedPoint("fold", lam_fold, "bratu_fold(): Newton on the extended system"),),
        ds=0.01,
        ds_min=1e-8,
        ds_max=0.1,
    )


# ----------------------------------------------------------------------------- Brusselator
BRUSSELATOR_A = 1.5


def _bruss_rhs(x: Any, p: Any, ops: Any) -> Any:
    a, b = p[0], p[1]
    return ops.stack([a - (b + 1.0) * x[0] + x[0] ** 2 * x[1], b * x[0] - x[0] ** 2 * x[1]])


def _bruss_f(x: Any, p: Any) -> Any:
    a, b = p[0], p[1]
    return np.array([a - (b + 1.0) * x[0] + x[0] ** 2 * x[1], b * x[0] - x[0] ** 2 * x[1]])


def _bruss_jac(x: FloatArray, p: FloatArray) -> FloatArray:
    b = p[1]
    return np.array(
        [
            [-(b + 1.0) + 2.0 * x[0] * x[1], x[0] ** 2],
            [b - 2.0 * x[0] * x[1], -(x[0] ** 2)],
        ]
    )


def _bruss_dfdp(x: FloatArray, p: FloatArray) -> FloatArray:
    return np.array([-x[0], x[0]])


def brusselator(a: float = BRUSSELATOR_A) -> BenchmarkProblem:
    """The Brusselator continued in ``B`` (see module docstring)."""
    b0 = 1.0
    return BenchmarkProblem(
        name="brusselator",
        title=f"Brusselator ODE, A={a:g}, continued in B (Hopf)",
        state_names=("x", "y"),
        param_names=("A", "B"),
        params={"A": a, "B": b0},
        free="B",
        x0=np.array([a, b0 / a]),
        p_min=0.0,
        p_max=4.0,
        norm_max=math.inf,
        rhs=_bruss_rhs,
        f=_bruss_f,
        jac=_bruss_jac,
        dfdp=_bruss_dfdp,
        sparse=False,
        expected=(ExpectedPoint("hopf", 1.0 + a * a, "closed form B = 1 + A^2"),),
        ds=0.01,
        ds_min=1e-8,
        ds_max=0.1,
    )


# ----------------------------------------------------------------------------- cubic8
CUBIC8_C = 0.2
CUBIC8_N = 8


def _cubic8_rhs(x: Any, p: Any, ops: Any) -> Any:
    c = p[1]
    out = [p[0] - x[0] ** 3 + 3.0 * x[0]]
    for k in range(1, CUBIC8_N):
        out.append(-float(k) * x[k] + c * ops.tanh(x[k - 1]))
    return ops.stack(out)


_K = np.arange(1, CUBIC8_N, dtype=float)


def _cubic8_f(x: Any, p: Any) -> Any:
    x = np.asarray(x)
    head = np.array([p[0] - x[0] ** 3 + 3.0 * x[0]])
    tail = -_K * x[1:] + p[1] * np.tanh(x[:-1])
    return np.concatenate((head, tail))


def _cubic8_jac(x: FloatArray, p: FloatArray) -> FloatArray:
    x = np.asarray(x, dtype=float)
    J = np.zeros((CUBIC8_N, CUBIC8_N))
    J[0, 0] = 3.0 - 3.0 * x[0] ** 2
    k = np.arange(1, CUBIC8_N)
    J[k, k] = -_K
    J[k, k - 1] = p[1] / np.cosh(x[:-1]) ** 2
    return J


def _cubic8_dfdp(x: FloatArray, p: FloatArray) -> FloatArray:
    out = np.zeros(CUBIC8_N)
    out[0] = 1.0
    return out


def cubic8_equilibrium(x0: float, c: float = CUBIC8_C) -> tuple[float, FloatArray]:
    """Explicit equilibrium of ``cubic8`` with first state ``x0``.

    Returns
    -------
    p : float
        ``x0**3 - 3 x0``.
    x : ndarray, shape (8,)
        ``x[0] = x0``, ``x[k] = c tanh(x[k-1]) / k``.
    """
    x = np.zeros(CUBIC8_N)
    x[0] = x0
    for k in range(1, CUBIC8_N):
        x[k] = c * math.tanh(x[k - 1]) / k
    return x0**3 - 3.0 * x0, x


def cubic8(c: float = CUBIC8_C) -> BenchmarkProblem:
    """The eight-state S-shaped problem (see module docstring)."""
    p_start = -4.0
    # the lower sheet at p = -4: the real root of x^3 - 3x + 4 = 0
    x0_start = opt.brentq(lambda s: s**3 - 3.0 * s - p_start, -3.0, -1.0, xtol=1e-15)
    _, x_start = cubic8_equilibrium(x0_start, c)
    return BenchmarkProblem(
        name="cubic8",
        title="8 states, S-shaped cubic x0' = p - x0^3 + 3 x0 + 7 coupled stable states (2 folds)",
        state_names=tuple(f"x{k}" for k in range(CUBIC8_N)),
        param_names=("p", "c"),
        params={"p": p_start, "c": c},
        free="p",
        x0=x_start,
        p_min=-4.5,
        p_max=4.0,
        norm_max=math.inf,
        rhs=_cubic8_rhs,
        f=_cubic8_f,
        jac=_cubic8_jac,
        dfdp=_cubic8_dfdp,
        sparse=False,
        expected=(
            ExpectedPoint("fold", 2.0, "exact: x0 = -1, p = x0^3 - 3 x0"),
            ExpectedPoint("fold", -2.0, "exact: x0 = +1, p = x0^3 - 3 x0"),
        ),
        ds=0.01,
        ds_min=1e-8,
        ds_max=0.1,
    )


def all_problems() -> dict[str, BenchmarkProblem]:
    """The benchmark problems by name, in table order."""
    probs = [bratu(20), bratu(200), brusselator(), cubic8()]
    return {p.name: p for p in probs}


__all__ = [
    "BRATU_CONTINUOUS_FOLD",
    "BenchmarkProblem",
    "ExpectedPoint",
    "all_problems",
    "bratu",
    "bratu_fold",
    "brusselator",
    "cubic8",
    "cubic8_equilibrium",
]
