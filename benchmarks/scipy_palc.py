r"""A plain SciPy pseudo-arclength continuation, the baseline of the continuation benchmark.

Written from the textbook method (Keller 1977, "Numerical solution of bifurcation and
nonlinear eigenvalue problems"; Allgower & Georg 1990, "Numerical Continuation Methods",
ch. 2-3; Seydel 2010, "Practical Bifurcation and Stability Analysis", ch. 4), with no
tricks: one fresh LU factorisation of the bordered matrix per Newton iteration, one more
for the tangent, one eigenvalue solve per accepted point. It shares no code with
``continuation/``: it only needs NumPy callables ``f``, ``jac``, ``dfdp``.

With ``z = (x, p)`` and the unit tangent ``tau`` at the last point ``z_k``, one step is

* predictor: ``z_pred = z_k + ds * tau``;
* corrector: Newton on ``[f(x, p); tau . (z - z_pred)] = 0`` with the bordered matrix
  ``A = [[f_x, f_p], [tau^T]]`` (dense ``scipy.linalg.lu_factor``/``lu_solve``, or sparse
  ``scipy.sparse.linalg.splu`` on a CSC matrix), stopped when the Newton step satisfies
  ``||dz||_inf <= tol (1 + ||z||_inf)``;
* new tangent: ``A(z_{k+1}) tau_new = e_{n+1}``, normalised (Euclidean norm on ``z``);
  the bordering row ``tau`` keeps the orientation (``tau_new . tau > 0``);
* step size: ``ds *= 1.5`` (up to ``ds_max``) after at most 3 Newton iterations; on
  failure ``ds *= 0.5`` and retry, stop below ``ds_min``;
* stability: all eigenvalues of ``f_x`` (``scipy.linalg.eigvals``) when dense, or the
  ``n_eigs`` eigenvalues nearest 0 (``scipy.sparse.linalg.eigs``, shift-invert at
  ``sigma = 0``) when sparse, so the unstable count is exact as long as every unstable
  eigenvalue is among them;
* fold: sign change of the parameter component ``tau_p`` of the tangent; Hopf: change
  in the number of unstable complex-conjugate pairs. Both are located by the Illinois
  variant of regula falsi in the arclength ``sigma`` from ``z_k`` along ``tau``
  (corrector on the hyperplane through ``z_k + sigma tau``), on the test functions
  ``tau_p`` (fold) and the real part of the complex pair nearest the imaginary axis
  (Hopf); no branch-point detection.

The branch stops (status) when ``p`` leaves ``[p_min, p_max]`` (``"param_bound"``),
``||x||_2 > norm_max`` (``"norm_bound"``), after ``max_steps`` steps (``"max_steps"``),
on ``|ds| < ds_min`` (``"ds_min"``) or a singular matrix (``"singular"``). The point that
crosses a bound is kept, as AUTO-07p does.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

FloatArray = np.ndarray


@dataclass(frozen=True)
class PalcSpecialPoint:
    """A located special point.

    Attributes
    ----------
    kind : {"fold", "hopf"}
    p : float
        Free parameter at the point.
    x : ndarray, shape (n,)
        State at the point.
    index : int
        Branch row just before the point.
    omega : float
        Hopf frequency ``|Im lambda|`` (NaN for folds).
    located : bool
        False when the locator did not converge (``p`` is then the last iterate).
    """

    kind: str
    p: float
    x: FloatArray
    index: int
    omega: float = math.nan
    located: bool = True


@dataclass(frozen=True)
class PalcResult:
    """A computed branch.

    Attributes
    ----------
    p : ndarray, shape (N,)
    x : ndarray, shape (N, n)
    n_unstable : ndarray of int, shape (N,)
        Eigenvalues with ``Re > eig_tol`` (among those computed).
    newton_iters : ndarray of int, shape (N,)
        Corrector iterations of each accepted point (0 for the start).
    special : tuple of PalcSpecialPoint
    status : str
        Why the branch stopped (see module docstring).
    """

    p: FloatArray
    x: FloatArray
    n_unstable: FloatArray
    newton_iters: FloatArray
    special: tuple[PalcSpecialPoint, ...]
    status: str

    @property
    def steps(self) -> int:
        """Accepted continuation steps (rows minus the start point)."""
        return len(self.p) - 1

    def find(self, kind: str) -> tuple[PalcSpecialPoint, ...]:
        """Special points of one kind, in branch order."""
        return tuple(s for s in self.special if s.kind == kind)


class _Singular(Exception):
    pass


class _Solver:
    """Bordered-matrix factorisation, dense or sparse."""

    def __init__(self, n: int, sparse: bool) -> None:
        self.n = n
        self.sparse = sparse
        self._dense = np.zeros((n + 1, n + 1)) if not sparse else None

    def factor(self, J: Any, fp: FloatArray, row: FloatArray) -> Any:
        n = self.n
        if self.sparse:
            Jc = sp.coo_matrix(J)
            rows = np.concatenate((Jc.row, np.arange(n), np.full(n + 1, n)))
            cols = np.concatenate((Jc.col, np.full(n, n), np.arange(n + 1)))
            vals = np.concatenate((Jc.data, fp, row))
            A = sp.csc_matrix((vals, (rows, cols)), shape=(n + 1, n + 1))
            try:
                return spla.splu(A)
            except RuntimeError as exc:  # "Factor is exactly singular"
                raise _Singular(str(exc)) from exc
        A = self._dense
        A[:n, :n] = J
        A[:n, n] = fp
        A[n, :] = row
        lu = la.lu_factor(A, check_finite=False)
        if np.any(np.diag(lu[0]) == 0.0):
            raise _Singular("exactly singular bordered matrix")
        return lu

    def solve(self, lu: Any, b: FloatArray) -> FloatArray:
        x = lu.solve(b) if self.sparse else la.lu_solve(lu, b, check_finite=False)
        if not np.all(np.isfinite(x)):
            raise _Singular("non-finite solution of the bordered system")
        return x


def _eigenvalues(J: Any, sparse: bool, n_eigs: int) -> FloatArray:
    if sparse:
        n = J.shape[0]
        k = min(n_eigs, n - 2)
        return spla.eigs(sp.csc_matrix(J), k=k, sigma=0.0, which="LM", return_eigenvectors=False)
    return la.eigvals(np.asarray(J), check_finite=False)


def _hopf_test(ev: FloatArray, eig_tol: float) -> float:
    """Real part of the complex pair nearest the imaginary axis (inf if none)."""
    cplx = ev[np.abs(ev.imag) > eig_tol]
    if cplx.size == 0:
        return math.inf
    return float(cplx.real[np.argmin(np.abs(cplx.real))])


def _counts(ev: FloatArray, eig_tol: float) -> tuple[int, int]:
    unstable = ev.real > eig_tol
    return int(np.sum(unstable)), int(np.sum(unstable & (ev.imag > eig_tol)))


def palc(
    f: Callable[[FloatArray, FloatArray], FloatArray],
    jac: Callable[[FloatArray, FloatArray], Any],
    dfdp: Callable[[FloatArray, FloatArray], FloatArray],
    x0: FloatArray,
    params: FloatArray,
    free_index: int,
    *,
    ds: float = 0.01,
    ds_min: float = 1e-8,
    ds_max: float = 0.1,
    p_min: float = -math.inf,
    p_max: float = math.inf,
    norm_max: float = math.inf,
    max_steps: int = 1000,
    tol: float = 1e-10,
    max_iter: int = 8,
    sparse: bool | None = None,
    n_eigs: int = 6,
    eig_tol: float = 1e-10,
    locate: bool = True,
    progress: Callable[[int, float], None] | None = None,
) -> PalcResult:
    """Continue equilibria ``f(x, p) = 0`` in one parameter by pseudo-arclength.

    Parameters
    ----------
    f : callable
        ``f(x, p) -> (n,)`` with ``x`` shape ``(n,)`` and the full parameter vector ``p``.
    jac : callable
        ``jac(x, p) -> (n, n)``, dense ndarray or SciPy sparse.
    dfdp : callable
        ``dfdp(x, p) -> (n,)``, derivative of ``f`` with respect to ``p[free_index]``.
    x0 : ndarray, shape (n,)
        A converged equilibrium at ``params``.
    params : ndarray, shape (m,)
        Parameter vector at the start.
    free_index : int
        Position of the continuation parameter in ``params``.
    ds, ds_min, ds_max : float
        Initial signed step (its sign sets the initial direction of ``p``) and bounds.
    p_min, p_max, norm_max : float
        Stop when ``p`` leaves ``[p_min, p_max]`` or ``||x||_2 > norm_max``.
    max_steps : int
        Maximum number of accepted steps.
    tol : float
        Newton step tolerance, ``||dz||_inf <= tol (1 + ||z||_inf)``.
    max_iter : int
        Newton iterations per corrector.
    sparse : bool, optional
        Sparse LU and ``eigs``; default: whether ``jac`` returns a sparse matrix.
    n_eigs : int
        Eigenvalues computed in sparse mode.
    eig_tol : float
        ``Re lambda > eig_tol`` counts as unstable.
    locate : bool
        Locate folds and Hopf points (else record the first point after them).
    progress : callable, optional
        ``progress(step, p)`` after every accepted step.

    Returns
    -------
    PalcResult

    Raises
    ------
    ValueError
        On inconsistent step sizes, a bad ``free_index`` or a start point that is not an
        equilibrium (``||f||_inf > 1e-6 (1 + ||jac||)``).
    """
    if not (ds_max >= abs(ds) >= ds_min > 0):
        raise ValueError(f"need ds_max >= |ds| >= ds_min > 0, got {ds_max=}, {ds=}, {ds_min=}")
    if max_steps < 1:
        raise ValueError(f"`max_steps` must be >= 1, got {max_steps}")
    params = np.array(params, dtype=float).reshape(-1)
    if not 0 <= free_index < params.size:
        raise ValueError(f"`free_index` must be in [0, {params.size}), got {free_index}")
    x = np.array(x0, dtype=float).reshape(-1)
    n = x.size
    J0 = jac(x, params)
    if sparse is None:
        sparse = sp.issparse(J0)
    if np.max(np.abs(f(x, params))) > 1e-6 * (1.0 + abs(J0).max()):
        raise ValueError("`x0` is not an equilibrium at `params` (||f|| too large)")
    solver = _Solver(n, bool(sparse))
    e_last = np.zeros(n + 1)
    e_last[n] = 1.0

    def pvec(p: float) -> FloatArray:
        v = params.copy()
        v[free_index] = p
        return v

    def tangent_at(z: FloatArray, row: FloatArray) -> tuple[FloatArray, Any]:
        pv = pvec(z[n])
        J = jac(z[:n], pv)
        lu = solver.factor(J, dfdp(z[:n], pv), row)
        t = solver.solve(lu, e_last)
        return t / np.linalg.norm(t), J

    def correct(z_pred: FloatArray, tau: FloatArray) -> tuple[FloatArray | None, int]:
        z = z_pred.copy()
        for it in range(1, max_iter + 1):
            pv = pvec(z[n])
            r = np.empty(n + 1)
            r[:n] = f(z[:n], pv)
            r[n] = tau @ (z - z_pred)
            if not np.all(np.isfinite(r)):
                return None, it
            lu = solver.factor(jac(z[:n], pv), dfdp(z[:n], pv), tau)
            dz = solver.solve(lu, r)
            z -= dz
            if np.max(np.abs(dz)) <= tol * (1.0 + np.max(np.abs(z))):
                return z, it
        return None, max_iter

    # initial tangent: border with e_{n+1} (increasing p), then orient by sign(ds)
    z = np.append(x, params[free_index])
    tau, J = tangent_at(z, e_last)
    if tau[n] * ds < 0:
        tau = -tau
    h = abs(ds)
    ev = _eigenvalues(J, bool(sparse), n_eigs)
    n_un, n_pairs = _counts(ev, eig_tol)
    ev_prev = ev
    ps, xs, nus, its = [z[n]], [z[:n].copy()], [n_un], [0]
    special: list[PalcSpecialPoint] = []
    status = "max_steps"

    def locate_between(
        z_a: FloatArray, tau_a: FloatArray, h_b: float, kind: str, g_a: float, g_b: float
    ) -> PalcSpecialPoint:
        """Illinois regula falsi on sigma in [0, h_b]."""
        a, b, ga, gb = 0.0, h_b, g_a, g_b
        best = None
        omega = math.nan
        converged = False
        for _ in range(60):
            s = (a * gb - b * ga) / (gb - ga) if gb != ga else 0.5 * (a + b)
            if not (min(a, b) < s < max(a, b)):
                s = 0.5 * (a + b)
            zs, _it = correct(z_a + s * tau_a, tau_a)
            if zs is None:
                break
            t_s, J_s = tangent_at(zs, tau_a)
            if kind == "fold":
                g = float(t_s[n])
            else:
                ev_s = _eigenvalues(J_s, bool(sparse), n_eigs)
                g = _hopf_test(ev_s, eig_tol)
                cplx = ev_s[np.abs(ev_s.imag) > eig_tol]
                if cplx.size:
                    omega = float(abs(cplx.imag[np.argmin(np.abs(cplx.real))]))
            best = zs
            if g == 0.0 or abs(b - a) <= 1e-13 * (1.0 + abs(h_b)):
                converged = True
                break
            if g * gb < 0:
                a, ga = b, gb
                b, gb = s, g
            else:
                b, gb = s, g
                ga *= 0.5  # Illinois: halve the retained end's value
            if abs(g) < 1e-14:
                converged = True
                break
        if best is None:
            best = z_a + h_b * tau_a
        return PalcSpecialPoint(
            kind, float(best[n]), best[:n].copy(), len(ps) - 1, omega, converged
        )

    try:
        for _step in range(max_steps):
            while True:
                z_new, it = correct(z + h * tau, tau)
                if z_new is not None:
                    break
                h *= 0.5
                if h < ds_min:
                    status = "ds_min"
                    raise StopIteration
            tau_new, J = tangent_at(z_new, tau)
            ev = _eigenvalues(J, bool(sparse), n_eigs)
            n_un_new, n_pairs_new = _counts(ev, eig_tol)
            if tau_new[n] * tau[n] < 0:
                sp_ = (
                    locate_between(z, tau, h, "fold", float(tau[n]), float(tau_new[n]))
                    if locate
                    else PalcSpecialPoint(
                        "fold", float(z_new[n]), z_new[:n].copy(), len(ps) - 1, located=False
                    )
                )
                special.append(sp_)
            if n_pairs_new != n_pairs:
                if locate:
                    g_a = _hopf_test(ev_prev, eig_tol)
                    g_b = _hopf_test(ev, eig_tol)
                    special.append(locate_between(z, tau, h, "hopf", g_a, g_b))
                else:
                    special.append(
                        PalcSpecialPoint(
                            "hopf", float(z_new[n]), z_new[:n].copy(), len(ps) - 1, located=False
                        )
                    )
            z, tau, n_un, n_pairs, ev_prev = z_new, tau_new, n_un_new, n_pairs_new, ev
            ps.append(z[n])
            xs.append(z[:n].copy())
            nus.append(n_un)
            its.append(it)
            if progress is not None:
                progress(len(ps) - 1, float(z[n]))
            if not p_min <= z[n] <= p_max:
                status = "param_bound"
                break
            if np.linalg.norm(z[:n]) > norm_max:
                status = "norm_bound"
                break
            if it <= 3:
                h = min(h * 1.5, ds_max)
    except StopIteration:
        pass
    except _Singular:
        status = "singular"
    except KeyboardInterrupt:
        status = "interrupted"
    return PalcResult(
        p=np.array(ps),
        x=np.array(xs),
        n_unstable=np.array(nus, dtype=int),
        newton_iters=np.array(its, dtype=int),
        special=tuple(special),
        status=status,
    )


def palc_problem(problem: Any, **overrides: Any) -> PalcResult:
    """Run :func:`palc` on a :class:`benchmarks.problems.BenchmarkProblem`.

    ``overrides`` replace the keyword arguments taken from the problem (``ds``,
    ``ds_min``, ``ds_max``, ``p_min``, ``p_max``, ``norm_max``, ``max_steps``, ``sparse``).
    """
    kw: dict[str, Any] = {
        **problem.step_settings(),
        "norm_max": problem.norm_max,
        "sparse": problem.sparse,
    }
    kw.update(overrides)
    return palc(
        problem.f,
        problem.jac,
        problem.dfdp,
        problem.x0,
        problem.param_vector(),
        problem.free_index,
        **kw,
    )


__all__ = ["PalcResult", "PalcSpecialPoint", "palc", "palc_problem"]
