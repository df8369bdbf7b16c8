r"""The corrector: Newton's method on the bordered system of a continuation step.

Notation: ``u = (z, p)`` in ``R^(N+1)``; ``G(z, p) = 0`` has ``N`` equations and the
border ``c . u = h`` closes the system. :func:`correct` evaluates ``G``, ``G_z``,
``G_p`` through the fastest interface the problem offers (:mod:`continuation.problem`,
accessors :func:`~continuation.problem.bordered_evaluator` and
:func:`~continuation.problem.linearizer`):

* a fused evaluator of the bordered residual and matrix (dense problems with a CasADi
  trace): one compiled call and one LAPACK ``gesv`` per Newton iteration, the Newton
  correction and the unnormalised tangent from one factorisation;
* a linearizer specialised to the free parameter (e.g. sparse problems) or
  ``problem.linearize`` / the protocol methods, with a dense LAPACK or sparse SuperLU
  factorisation of the bordered matrix (:class:`~continuation.linalg.BorderedLU`).

All give the same values; the fused path only removes Python overhead, which dominates
the steps of small systems. The two iterations are written separately because the fused
one keeps its iterate in the evaluator's buffers (no array is allocated per iteration on
the hot path of small problems); everything that decides the outcome is shared: the
convergence test (:func:`_accepted`) and the tail of each iteration that gives up
(:func:`_give_up`: iteration limit, divergence; :func:`_too_slow`: contraction).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
import scipy.linalg.blas as sla_blas

from .. import linalg as _la
from ..linalg import (
    BorderedLU,
)
from ..linalg import (
    all_finite as _finite,
)
from ..linalg import (
    gesv as _gesv,
)
from ..linalg import (
    getrs as _getrs,
)
from ..linalg import (
    inf_norm as _inf_norm,
)
from ..problem import bordered_evaluator as _bordered_evaluator
from ..problem import linearizer as _linearizer
from ..settings import NewtonSettings
from ..typing import FloatArray
from .point import PointVector

_idamax = sla_blas.idamax

# ---------------------------------------------------------------------------- Newton acceptance
#: Round-off floor of the corrector's tests: a modest multiple of the unit round-off
#: ``eps``, which bounds the relative error of evaluating a short sum of terms in
#: floating point (Higham 2002, *Accuracy and Stability of Numerical Algorithms*,
#: Sec. 3.1: ``|fl(sum) - sum| <= gamma_k sum |terms|``, ``gamma_k ~ k eps``).
ROUNDOFF_FLOOR = _RF = 64.0 * np.finfo(float).eps
_TINY = 1e-300  # (keeps the scale of an all-zero vector positive)
#: A stalled correction (neither the residual nor the step halves, residual below
#: ``tol``) is accepted up to this multiple of the step tolerance: the noise of the
#: solve next to a singular bordered matrix (corrections ~ ``tol / sigma_min``).
NOISE_SLACK = 10.0
_maximum, _abs = np.maximum, np.abs


def _step_ok(
    du: FloatArray, u_pred: FloatArray, u_ref: FloatArray, a: float, step_tol: float
) -> bool:
    r"""The componentwise Newton step test ``|du_i| <= step_tol * d_i`` for every ``i``.

    .. math::

        d_i = s_i + a, \qquad s_i = \max(|u_{\mathrm{pred},i}|, |u_{\mathrm{ref},i}|),
        \qquad a = \min(1, \|u_{\mathrm{pred}}\|_\infty),

    i.e. ``|du_i| <= step_tol (|u_i| + min(1, ||u||_inf))``: the relative-plus-absolute
    test ``|du_i| <= step_tol (1 + |u_i|)`` of AUTO (``EPSU``; Doedel et al., AUTO-07p
    manual) and of Dennis & Schnabel (1983, *Numerical Methods for Unconstrained
    Optimization and Nonlinear Equations*, Sec. 7.2, typical size ``typ u = 1``), applied
    to every component separately (Deuflhard 2004, *Newton Methods for Nonlinear
    Problems*, Sec. 2.1, scaled norms; ``s`` is the scaling of NLEQ1's ``N1SCAL``, the
    larger magnitude of the component at two points), with the typical size ``1``
    lowered to the largest component when all components are smaller. Unlike one test
    of ``max |du|`` against ``step_tol (1 + max |u|)``, a large component (a parameter of
    ``1e6``) does not loosen the test of the others, and a problem whose unknowns are
    all small (states of ``1e-9`` next to a parameter of ``1e-4``) is tested relative to
    its own size, not to an absolute ``step_tol``.

    The caller first compares ``dn = max |du|`` with the bounds of :func:`_step_bounds`,
    which decide the test whatever the components, so that a step costs one ``idamax``
    as the plain ``max |du|`` test did; only between them are the components compared.
    """
    return _step_ratio(du, u_pred, u_ref, a) <= step_tol


def _step_ratio(du: FloatArray, u_pred: FloatArray, u_ref: FloatArray, a: float) -> float:
    """``max_i |du_i| / d_i`` with the scale ``d`` of :func:`_step_ok`."""
    q = du / (_maximum(_abs(u_pred), _abs(u_ref)) + a)
    return abs(float(q[_idamax(q)]))


def _step_bounds(un: float, u_ref: FloatArray, step_tol: float) -> tuple[float, float, float]:
    """``(a, lo, hi)`` of the step test :func:`_step_ok`, ``un = ||u_pred||_inf``.

    ``a = min(1, un)``; ``max |du| <= lo = step_tol * a`` passes the test and
    ``max |du| > hi = step_tol * (max(un, ||u_ref||_inf) + a)`` fails it, whatever the
    components (``a <= d_i <= max_j s_j + a``).
    """
    a = min(1.0, un) + _TINY
    return a, step_tol * a, step_tol * (max(un, _inf_norm(u_ref)) + a)


def _backward_error(M: Any, r: FloatArray, u: FloatArray, Gp: Any = None, c: Any = None) -> float:
    r"""Normwise backward error of the bordered residual, relative to the terms of ``G``.

    .. math::

        \omega = \max\Big( \frac{\|G\|_\infty}{\| |G_z| |z| + |G_p| |p| \|_\infty},
        \ \frac{|c \cdot u - h|}{|c| \cdot |u|} \Big),

    ``r = (G, c . u - h)`` the bordered residual at ``u`` and ``M`` the bordered matrix
    ``[[G_z, G_p], [c^T]]`` there. ``(|G_z| |z| + |G_p| |p|)_i`` is the size of the
    first-order terms of equation ``i`` (exact for terms linear in one component, ``k``
    times the term for a monomial of degree ``k``), so ``omega`` of the order of
    ``eps`` means that the residual is the rounding error of evaluating those terms:
    ``u`` solves ``G = 0`` up to a perturbation of ``G``'s terms at round-off, and no
    Newton step can improve it (the backward error of Rigal & Gaches, J. ACM 14 (1967),
    with the componentwise matrix-vector size of Oettli & Prager, Numer. Math. 6 (1964)
    in place of ``||M|| ||u||``, which would let a large parameter inflate the floor of
    every equation; Higham 2002, Sec. 7.1-7.2). The border row, a linear equation of
    its own scale, is measured separately.

    With ``Gp`` and ``c`` given, ``M`` is ``G_z`` alone (dense or SciPy sparse) and the
    bordered matrix is formed implicitly.
    """
    au = np.abs(u)
    n = au.size - 1
    if Gp is None:
        s = np.abs(M) @ au
        sf = s[:n]
        sb = float(s[n])
    else:
        sf = abs(M) @ au[:n]
        sf += np.abs(Gp) * au[n]
        sb = float(np.abs(c).dot(au))
    ar = np.abs(r)
    wf = float(ar[:n].max() / (sf.max() + _TINY)) if n else 0.0
    return max(wf, float(ar[n]) / (sb + _TINY))


def _accepted(
    rn: float,
    rn_prev: float,
    dn: float,
    dn_ok: bool,
    step: float,
    step_ok: bool,
    it: int,
    exact: bool,
    tol: float,
    step_tol: float,
    hi: float,
    ratio: Callable[[], float],
    backward_error: Callable[[], float],
) -> bool:
    """The corrector's convergence test (see :func:`correct`).

    Shared by its dense and sparse iterations. ``rn``: ``max |r|`` now, ``rn_prev`` before
    the last step; ``dn = max |du|`` of the correction at the current point and ``dn_ok``
    its componentwise test; ``step``/``step_ok`` the same of the last step taken; ``hi`` the
    upper bound of :func:`_step_bounds`; ``ratio()`` gives :func:`_step_ratio` of the
    correction and ``backward_error()`` :func:`_backward_error` at the current point, both
    evaluated only when the clause needing them is reached.
    """
    return bool(
        (rn <= tol and (dn_ok or step_ok))
        # stalled in the noise of an ill-conditioned solve (see correct's docstring)
        or (
            it
            and rn <= tol
            and rn > 0.5 * rn_prev
            and dn > 0.5 * step
            and dn <= NOISE_SLACK * hi
            and ratio() <= NOISE_SLACK * step_tol
        )
        # stalled (the residual did not halve) at the round-off floor of G's terms
        or (step_ok and rn > 0.5 * rn_prev and backward_error() <= _RF)
        # without exactness: the final correction is below the step tolerance and, at
        # the observed quadratic rate (residual rn after a step of length `step`),
        # leaves a residual ten times below tol
        or (not exact and it and dn_ok and 10.0 * rn * dn * dn <= tol * step * step)
    )


def _give_up(it: int, max_iter: int, rn: float, rn0: float, tol: float) -> str:
    """Why the corrector stops before taking step ``it + 1`` (empty: go on).

    The iteration limit, or divergence (residual ``1e4`` times its initial value or ``tol``
    after two iterations). Shared by both iterations of :func:`correct`.
    """
    if it >= max_iter:
        return "max_iter reached"
    if it >= 2 and rn > 1e4 * max(rn0, tol):
        return "diverging"
    return ""


def _too_slow(
    max_contraction: float | None,
    it: int,
    step: float,
    step_prev: float,
    step_ok: bool,
    rn: float,
    tol: float,
) -> str:
    """The contraction test of :func:`correct` after step ``it`` (empty: passed)."""
    if (
        max_contraction is not None
        and it >= 2
        and step > max_contraction * step_prev
        and not step_ok
        and rn > tol
    ):
        return f"corrector contracts too slowly (rate {step / step_prev:.2g} at step {it})"
    return ""


@dataclass(eq=False, slots=True)
class CorrectorResult(PointVector):
    """Outcome of :func:`correct`.

    ``lu`` is the factorisation of the bordered matrix at the last Newton iterate (the
    returned point, or the iterate one step before it: within the step tolerance, or,
    with ``predict_final``, one quadratically converging step away), or None;
    ``u`` is ``(z, p)`` (the corrector's vector when it has it, else joined on first
    use: :class:`~continuation.algorithms.point.PointVector`); ``t_raw`` is the solution of
    ``M t = e_{N+1}`` with that factorisation when the corrector already has it (fused
    evaluator), else None; ``g_norm`` is ``max |G|`` of ``lin`` when known and
    ``jac_finite`` is True when ``lin``'s Jacobian is known to be finite.
    """

    converged: bool
    z: FloatArray
    p: float
    lin: tuple[FloatArray, Any, FloatArray] | None
    iters: int
    residual_norm: float
    message: str = ""
    lu: BorderedLU | None = None
    _u: FloatArray | None = None
    t_raw: FloatArray | None = None
    g_norm: float | None = None
    jac_finite: bool = False


def _evaluate(
    run: Any, nv: Any, r: FloatArray, u: FloatArray
) -> tuple[float, float, float, float, bool]:
    """Run a fused evaluator; ``(max|r|, max|u|, max|G|, sum M_ij^2, r finite)``.

    The norms come from the evaluator's ``norms`` buffer ``nv`` when it has one (``max|G|``
    and ``sum M_ij^2`` are NaN, unknown, otherwise).
    """
    run()
    if nv is not None:
        rn, rr, un, gn, mm = nv.tolist()
        return rn, un, gn, mm, rr < math.inf
    return _inf_norm(r), _inf_norm(u), math.nan, math.nan, float(r.dot(r)) < math.inf


def _correct_fused(
    ev: Any,
    u_pred: FloatArray,
    u_ref: FloatArray,
    c: FloatArray,
    sigma: float,
    newton: NewtonSettings,
    max_contraction: float | None,
    exact: bool,
) -> CorrectorResult:
    """:func:`correct` with a fused evaluator of the bordered residual and matrix.

    Same iteration and criteria; the iterate lives in the evaluator's input buffer and
    every Newton step is one compiled-function call and one LAPACK ``gesv`` with two
    right-hand sides, the residual and ``e_{N+1}`` (``ev.rt`` when the evaluator has
    that buffer, else a copy of ``ev.r`` is put into one): the Newton correction
    and the unnormalised tangent of the same factorisation come together, so the
    result carries ``t_raw`` and :func:`make_point` needs no further solve.
    """
    n = u_pred.size - 1
    u, r, M, nv = ev.u, ev.r, ev.M, ev.norms
    run = getattr(ev, "run", ev)  # (the compiled call itself, without the wrapper)
    rt_ev: FloatArray | None = getattr(ev, "rt", None)
    own_rt = rt_ev is None  # an evaluator without the two-column buffer: copy r into one
    if rt_ev is None:
        rt = np.zeros((n + 1, 2), order="F")
        rt[n, 1] = 1.0
    else:
        rt = rt_ev
    u[:] = u_pred
    ev.c[:] = c  # (ev.set_border, inlined: the hot path of small problems)
    ev.h[0] = float(c.dot(u_ref)) + sigma
    tol, step_tol, max_iter = newton.tol, newton.step_tol, newton.max_iter
    # (gn, mm: max |f| and sum M_ij^2 of the last evaluation, when known)
    rn, un, gn, mm, finite = _evaluate(run, nv, r, u)
    rn0, rn_prev, step, it = rn, math.inf, math.inf, 0
    # the componentwise step test (_step_ok, bounds as in _step_bounds; inlined)
    a = min(1.0, un) + _TINY
    lo, hi = step_tol * a, step_tol * (max(un, _inf_norm(u_ref)) + a)
    step_ok = False  # the last step passed it
    while True:
        if not finite:
            return CorrectorResult(False, u[:n].copy(), float(u[n]), None, it, rn,
                                   "non-finite residual")  # fmt: skip
        if own_rt:
            rt[:, 0] = r
        f_lu, f_piv, x, info = _gesv(M, rt)  # copies: M and rt stay intact for lin()
        du = None
        if info == 0:
            du = x[:, 0]
            if not float(du.dot(du)) < math.inf:
                du = None
        if du is None:
            # exactly singular at a point that already solves G = 0: accept it
            msg = "singular: singular bordered matrix"
            return CorrectorResult(rn <= tol, u[:n].copy(), float(u[n]), ev.lin(), it, rn,
                                   msg, None, u.copy())  # fmt: skip
        dn = abs(float(du[_idamax(du)]))
        dn_ok = dn <= lo or (dn <= hi and _step_ok(du, u_pred, u_ref, a, step_tol))
        if _accepted(rn, rn_prev, dn, dn_ok, step, step_ok, it, exact, tol, step_tol, hi,
                     partial(_step_ratio, du, u_pred, u_ref, a),
                     partial(_backward_error, M, r, u)):  # fmt: skip
            lin = ev.lin()
            lu: BorderedLU | None = BorderedLU.from_dense_factors(f_lu, f_piv)
            t_raw: FloatArray | None = x[:, 1]
            if dn_ok:
                u -= du
                if exact:
                    rn, _, gn, mm, finite = _evaluate(run, nv, r, u)
                    lin = ev.lin()
                    rn = rn if finite else math.inf
                    if own_rt:
                        rt[:, 0] = r
                    f_lu, f_piv, x, info = _gesv(M, rt)
                    if info == 0:
                        lu, t_raw = BorderedLU.from_dense_factors(f_lu, f_piv), x[:, 1]
                    else:
                        lu = t_raw = None
            uf = u.copy()
            return CorrectorResult(True, uf[:n], float(uf[n]), lin, it, rn, "", lu, uf, t_raw,
                                   gn if gn == gn else None, mm < math.inf)  # fmt: skip
        msg = _give_up(it, max_iter, rn, rn0, tol)
        if msg:
            return CorrectorResult(False, u[:n].copy(), float(u[n]), ev.lin(), it, rn, msg)
        u -= du
        it += 1
        step_prev, step, step_ok = step, dn, dn_ok
        msg = _too_slow(max_contraction, it, step, step_prev, step_ok, rn, tol)
        if msg:
            return CorrectorResult(False, u[:n].copy(), float(u[n]), None, it, rn, msg)
        rn_prev = rn
        rn, _, gn, mm, finite = _evaluate(run, nv, r, u)


def correct(
    problem: Any,
    u_pred: FloatArray,
    u_ref: FloatArray,
    c: FloatArray,
    sigma: float,
    newton: NewtonSettings,
    *,
    max_contraction: float | None = None,
    exact: bool = True,
    predict_final: bool = False,
    final_lu: bool = True,
) -> CorrectorResult:
    r"""Newton's method on the bordered system.

    Solves ``G(z, p) = 0`` together with the linear constraint
    ``c . (u - u_ref) = sigma`` (the pseudo-arclength condition for
    ``c = w o tau_ref``; natural stepping for ``c = e_p``), from ``u_pred``.

    Steps are tested componentwise (see :func:`_step_ok`),

    .. math::

        \|du\|_d = \max_i \frac{|du_i|}{d_i}, \qquad
        d_i = s_i + \min(1, \|u_{\mathrm{pred}}\|_\infty), \quad
        s_i = \max(|u_{\mathrm{pred},i}|, |u_{\mathrm{ref},i}|),

    i.e. ``||du||_d <= step_tol`` is ``|du_i| <= step_tol (|u_i| + min(1, ||u||_inf))``
    for every component, and the residual's round-off floor is its backward error
    relative to the terms of ``G`` (see :func:`_backward_error`),

    .. math::

        \omega = \max\Big( \frac{\|G\|_\infty}{\| |G_z| |z| + |G_p| |p| \|_\infty},
        \ \frac{|c \cdot u - h|}{|c| \cdot |u|} \Big) \le \epsilon_r
        \quad (\epsilon_r = \mathtt{ROUNDOFF\_FLOOR} = 64\,\mathrm{eps}).

    Converged when (a) ``max |r| <= newton.tol`` (``r`` the bordered residual, ``G``
    and the constraint) and either the last step or the Newton correction computed at
    the current point has ``||.||_d <= newton.step_tol`` (that correction is then
    applied), or (b) the last step has ``||du||_d <= newton.step_tol``, the residual
    did not decrease by a factor 2 in the last iteration and it is at its round-off
    floor, ``omega <= eps_r``: more iterations cannot improve the point (e.g. finely
    discretised PDEs whose Jacobian entries are large, where ``newton.tol`` is below
    the round-off of ``G``), or (c) ``max |r| <= newton.tol`` after at least one
    iteration in which neither the residual nor the correction halved, and the
    correction has ``||du||_d <= NOISE_SLACK * newton.step_tol`` (``NOISE_SLACK = 10``):
    next to a singular bordered matrix (trial points of a branch-point locator) the
    correction at a residual below ``tol`` is the noise of the solve, of order
    ``tol / sigma_min``, which the componentwise test alone need not reach. A stalled
    iteration whose residual is above both ``newton.tol`` and the round-off floor is
    not converged, whatever its step. With ``exact=False`` a point is
    also converged when that correction has ``||.||_d <= newton.step_tol`` and, at the
    quadratic rate observed in the previous iteration (residual ``r_k`` after a step
    ``d_{k-1}``, in ``||.||_inf``: ``|G| ~ (r_k / d_{k-1}^2) d_k^2``), it leaves a residual
    ten times below ``newton.tol`` (Deuflhard 2004, Sec. 2.1, a-posteriori estimates
    from the observed convergence). The result carries ``lin`` and ``lu`` (the
    factorisation of the bordered matrix, for the caller's tangent): with
    ``exact=True`` they are re-evaluated at the returned point after that final
    correction; with ``exact=False`` they are those of the point before it, within the
    step tolerance of the returned one (usually within round-off, the final correction
    being quadratically small), which saves one evaluation and factorisation when the
    predictor is already converged (continuation steps use this; located special
    points use ``exact=True``).

    With ``predict_final=True`` (and ``exact=False``; for problems whose Jacobian is not
    their stability matrix, so that a Jacobian one iterate away from the point costs
    nothing but the tangent's accuracy) the iteration also stops one linearisation
    earlier: after a step ``d_k`` taken in the quadratic regime (``d_k <= d_{k-1} / 4``),
    whose predicted successor ``d_k^3 / d_{k-1}^2`` (Deuflhard 2004, Sec. 2.1) is ten
    times below the step tolerance's lower bound ``step_tol * min(1, ||u||_inf)``, only
    the residual is evaluated at the new point, and the point is converged if that
    *evaluated* residual has ``max |r| <= newton.tol``. ``lin``'s Jacobians and ``lu``
    are then those of the previous iterate (``d_k`` away, not ``step_tol``; its ``G``
    is the point's), which perturbs the tangent by that distance; otherwise the
    iteration goes on as usual. ``final_lu=False`` (with ``exact``): the bordered matrix
    at the returned point is not factorised (``lu`` None; ``lin`` is evaluated there),
    for a caller that factorises it with another border (a located point's tangent).
    Stops early (not converged) when the residual becomes
    non-finite, grows by a factor ``1e4`` over its initial value, or the bordered
    matrix is singular.

    With ``max_contraction = kappa`` it also stops (not converged) as soon as a Newton
    step is not at least ``kappa`` times shorter than the previous one,
    ``||du_{k+1}||_inf > kappa ||du_k||_inf`` (``k >= 1``), while the residual is above
    ``newton.tol`` and the step above the step tolerance: the iterates are then outside
    the region of (quadratic) convergence, and a corrector that still "converges" from
    there may land on a distant part of the solution set (Allgower & Georg 1990,
    *Numerical Continuation Methods*, Sec. 6.1 and Program 1, contraction-rate test with
    ``kappa = 0.8``; Deuflhard 2004, *Newton Methods for Nonlinear Problems*, Sec. 5.1,
    the monotonicity test of the contraction factor).
    """
    ev = _bordered_evaluator(problem)
    if ev is not None:
        return _correct_fused(ev, u_pred, u_ref, c, sigma, newton, max_contraction, exact)
    lin_fn = _linearizer(problem)
    res_fn = getattr(problem, "residual", None) if predict_final and not exact else None
    n = u_pred.size - 1
    u = np.array(u_pred, dtype=float)
    h = float(c.dot(u_ref)) + sigma  # the constraint is c . u = h
    tol, step_tol, max_iter = newton.tol, newton.step_tol, newton.max_iter
    r = np.empty(n + 1)  # bordered residual (G, c . u - h)

    def fail(msg: str, lin: Any = None) -> CorrectorResult:
        return CorrectorResult(False, u[:n].copy(), float(u[n]), lin, it, rn, msg)

    lin = lin_fn(u[:n], float(u[n]))
    r[:n] = lin[0]
    r[n] = float(c.dot(u)) - h
    finite = _finite(r)
    rn = _inf_norm(r)
    rn0, rn_prev, step, it = rn, math.inf, math.inf, 0
    a, lo, hi = _step_bounds(_inf_norm(u), u_ref, step_tol)  # componentwise step test
    step_ok = False  # the last step passed it
    dense = isinstance(lin[1], np.ndarray)
    n1 = n + 1
    lu: BorderedLU | None = None
    while True:
        if not finite:
            return fail("non-finite residual")
        if dense:  # LAPACK directly (the hot path of small problems)
            M = np.empty((n1, n1), order="F")
            M[:n, :n] = lin[1]
            M[:n, n] = lin[2]
            M[n, :] = c
            # (looked up on the module: one place to count or replace factorisations)
            f_lu, f_piv, info = _la._getrf(M, overwrite_a=1)
            du = None
            if info == 0:
                du, info = _getrs(f_lu, f_piv, r)
                if not float(du.dot(du)) < math.inf:
                    du = None
            if du is None:
                # exactly singular at a point that already solves G = 0 (e.g. a trial
                # point landing exactly on a branch point): accept it
                return CorrectorResult(rn <= tol, u[:n].copy(), float(u[n]), lin, it, rn,
                                       "singular: singular bordered matrix", None, u)  # fmt: skip
        else:
            try:
                lu = BorderedLU(lin[1], lin[2], c)
                du = lu.solve(r)
            except np.linalg.LinAlgError as exc:
                return CorrectorResult(rn <= tol, u[:n].copy(), float(u[n]), lin, it, rn,
                                       f"singular: {exc}", None, u)  # fmt: skip
        dn = _inf_norm(du)
        dn_ok = dn <= lo or (dn <= hi and _step_ok(du, u_pred, u_ref, a, step_tol))
        if _accepted(rn, rn_prev, dn, dn_ok, step, step_ok, it, exact, tol, step_tol, hi,
                     partial(_step_ratio, du, u_pred, u_ref, a),
                     partial(_backward_error, lin[1], r, u, lin[2], c),
                     ):  # fmt: skip
            if dense:
                lu = BorderedLU.from_dense_factors(f_lu, f_piv)
            if dn_ok:
                # final Newton correction, below the step tolerance
                u -= du
                if exact:
                    lin = lin_fn(u[:n], float(u[n]))
                    r[:n] = lin[0]
                    r[n] = float(c.dot(u)) - h
                    rn = _inf_norm(r) if _finite(r) else math.inf
                    lu = None  # type: ignore[assignment]
                    if final_lu:
                        try:
                            lu = BorderedLU(lin[1], lin[2], c)
                        except np.linalg.LinAlgError:
                            pass
            return CorrectorResult(True, u[:n].copy(), float(u[n]), lin, it, rn, "", lu, u)
        msg = _give_up(it, max_iter, rn, rn0, tol)
        if msg:
            return fail(msg, lin)
        u -= du
        it += 1
        step_prev, step, step_ok = step, dn, dn_ok
        msg = _too_slow(max_contraction, it, step, step_prev, step_ok, rn, tol)
        if msg:
            return fail(msg)
        rn_prev = rn
        if (
            res_fn is not None
            and it >= 2
            and step <= 0.25 * step_prev
            and step * (step / step_prev) ** 2 <= 0.1 * lo
        ):
            # the predicted next correction is far below the step tolerance: check the
            # residual alone at this point (see the docstring, predict_final)
            G_new = np.asarray(res_fn(u[:n], float(u[n])), dtype=float)
            r_new = np.append(G_new, float(c.dot(u)) - h)
            rn_new = _inf_norm(r_new) if _finite(r_new) else math.inf
            if rn_new <= tol:
                lu_k = BorderedLU.from_dense_factors(f_lu, f_piv) if dense else lu
                lin_k = (G_new, lin[1], lin[2])
                return CorrectorResult(True, u[:n].copy(), float(u[n]), lin_k, it, rn_new, "",
                                       lu_k, u.copy())  # fmt: skip
        lin = lin_fn(u[:n], float(u[n]))
        r[:n] = lin[0]
        r[n] = float(c.dot(u)) - h
        finite = _finite(r)
        rn = _inf_norm(r)


__all__ = ["NOISE_SLACK", "ROUNDOFF_FLOOR", "CorrectorResult", "correct"]
