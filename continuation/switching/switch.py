r"""Branch switching at simple branch points (AUTO's ``ISW=-1``, MATCONT's "BP -> EP").

At a simple branch point :math:`u^* = (z^*, p^*)` of :math:`G(u) = 0`,
:math:`G: R^{N+1} \to R^N`, two branches of solutions cross transversally. The
Jacobian :math:`A = DG(u^*) = [G_z\; G_p]` (``N x (N+1)``) has rank ``N - 1``:

.. math::

    \ker A = \mathrm{span}\{q_1, q_2\}, \qquad \ker A^T = \mathrm{span}\{\psi\},

with :math:`q_1, q_2` orthonormal in the ``theta`` inner product of the continuation
(:func:`~continuation.algorithms.base.theta_weights`). Every branch through
:math:`u^*` has the form :math:`u(s) = u^* + s\,(\alpha q_1 + \beta q_2) + O(s^2)`;
projecting the second-order expansion of :math:`G(u(s)) = 0` on :math:`\psi` gives the
*algebraic bifurcation equation* (ABE; Keller 1977; Doedel, Keller & Kernevez 1991;
Govaerts 2000; Kuznetsov 2004, Sec. 10.2)

.. math::

    c_{11}\alpha^2 + 2 c_{12}\alpha\beta + c_{22}\beta^2 = 0, \qquad
    c_{ij} = \psi^T D^2G(u^*)[q_i, q_j].

The point is a *simple* branch point when :math:`c_{12}^2 - c_{11}c_{22} > 0`: the ABE
then has two real root directions, the tangents of the two branches. One is the
tangent :math:`t_{old}` of the branch the point was found on; the other,
:math:`t_{new}`, is the tangent of the crossing branch. The roots are computed from the
eigen-decomposition :math:`C = [[c_{11}, c_{12}], [c_{12}, c_{22}]] = \lambda_- e_-
e_-^T + \lambda_+ e_+ e_+^T` (:math:`\lambda_- < 0 < \lambda_+`):
:math:`(\alpha, \beta) \propto \sqrt{-\lambda_-}\, e_+ \pm \sqrt{\lambda_+}\, e_-`.
Only when the two branches are orthogonal (transcritical and pitchfork bifurcations in
the usual coordinates) is :math:`t_{new}` simply the kernel direction orthogonal to
:math:`t_{old}`; in general it is not, which is why the ABE is solved.

The second derivatives :math:`D^2G[a, b]` come from the CasADi trace of the model
(forward-over-forward directional derivatives, ``casadi.jtimes``) for an
:class:`~continuation.problem.EquilibriumProblem` of a traced
:class:`~continuation.system.System`, else from central differences of the Jacobian,
:math:`(A(u^* + h b) - A(u^* - h b))\, a / 2h`.

The kernel comes from the SVD of :math:`A\, W^{-1/2}` (``W = diag(theta weights)``)
for dense or moderately sized problems, and for large sparse ones from two solves with
the bordered matrix (Govaerts 2000, on bordered matrices; Keller 1977)

.. math::

    M = \begin{pmatrix} A & b \\ C^T & 0 \end{pmatrix}, \quad
    M \begin{pmatrix} q_k \\ y \end{pmatrix} = e_{N + k}, \quad
    M^T \begin{pmatrix} \psi \\ \eta \end{pmatrix} = e_{N + 2},

first with ``b`` random and ``C = W [t_old, r]``, then again with ``b = psi`` and
``C = W [q_1, q_2]`` (which makes ``M`` well conditioned).

Start on the crossing branch. With :math:`\varphi_2` the part of :math:`t_{new}`
``theta``-orthogonal to :math:`t_{old}` and :math:`S = \langle\varphi_2,
t_{new}\rangle_\theta = \sin\angle(t_{old}, t_{new})`, the start point for the half
``sign = +-1`` solves, by Newton's method from :math:`u^* + \mathrm{sign}\, a\, t_{new}`,

.. math::

    G(u) = 0, \qquad \langle \varphi_2, u - u^* \rangle_\theta = \mathrm{sign}\, a S,

a hyperplane *parallel to the current branch* at distance :math:`a S` from it, so the
corrector cannot fall back onto the current branch near :math:`u^*` (``a`` is the
``amplitude``). The corrected point is accepted only if it lies within ``a / 2`` of the
prediction and its tangent is within 45 degrees of :math:`t_{new}`; the continuation is
then started there with the tangent oriented along :math:`\pm t_{new}`
(:func:`~continuation.driver.continue_branch`). With ``direction="both"`` the run
towards :math:`u^*` passes through the branch point (where the driver detects it again,
on the new branch) into the other half; the rows next to :math:`u^*` are checked to lie
on the crossing branch (their offset from the current branch,
:math:`\langle\varphi_2, u - u^*\rangle_\theta`, must be at least half of
:math:`S \langle t_{new}, u - u^*\rangle_\theta`).

References
----------
Keller, H. B. (1977), "Numerical solution of bifurcation and nonlinear eigenvalue
problems", in *Applications of Bifurcation Theory*, P. H. Rabinowitz (ed.), Academic
Press, 359-384.

Doedel, E. J., Keller, H. B. & Kernevez, J. P. (1991), "Numerical analysis and control
of bifurcation problems (I): bifurcation in finite dimensions", *Int. J. Bifurcation
and Chaos* 1(3), 493-520.

Govaerts, W. J. F. (2000), *Numerical Methods for Bifurcations of Dynamical
Equilibria*, SIAM.

Kuznetsov, Yu. A. (2004), *Elements of Applied Bifurcation Theory*, 3rd ed., Springer,
Sec. 10.2.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import casadi as ca
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..algorithms.base import (
    ContinuationAlgorithm,
    StepOutcome,
    StepState,
    theta_norm,
    theta_weights,
)
from ..algorithms.corrector import correct
from ..algorithms.palc import PALC
from ..algorithms.point import make_point
from ..branch import Branch, BranchPoint, SpecialKind, SpecialPoint
from ..driver import continue_branch
from ..errors import ContinuationError, ConvergenceError
from ..events import Event
from ..problem import EquilibriumProblem, difference, linearize
from ..settings import ContinuationSettings, NewtonSettings
from ..status import Status
from ..typing import FloatArray

log = logging.getLogger(__name__)

#: Problems with more unknowns than this and a sparse Jacobian get their kernel from
#: bordered solves instead of a dense SVD.
DENSE_KERNEL_MAX = 400

#: The two smallest singular values of ``A W^{-1/2}`` must be separated by this factor
#: (``sigma_N <= KERNEL_GAP * sigma_{N-1}``), else the kernel is not two-dimensional.
KERNEL_GAP = 0.1

#: ABE coefficients below this fraction of ``max ||D^2G[q_i, q_j]||`` count as zero.
ABE_ZERO = 1e-8

#: Smallest accepted ``min(|lambda_-|, lambda_+) / max |lambda|`` of the ABE matrix
#: (about the squared angle between the roots): below it the two roots coincide to
#: working accuracy and the branch point is not simple.
ABE_SIMPLE = 1e-12

#: The root of the ABE nearer the current branch must make at most this cosine with
#: the new one (``theta`` metric; an angle of about 1.4e-5 rad), else the crossing
#: branch is indistinguishable from the current one.
MAX_COS_BRANCHES = 1.0 - 1e-10

#: The start point must be within this fraction of the amplitude of its prediction.
START_DISTANCE = 0.5

#: ... and its tangent within this angle (degrees) of the crossing direction.
START_ANGLE_DEG = 45.0

#: Rows near the branch point must have at least this fraction of the off-branch
#: offset that the crossing tangent predicts.
CROSSING_RATIO = 0.5

#: The ABE coefficients must be at least this fraction of their size estimated from the
#: rows around the point (``sigma_N(A) / distance``, which is first order in the distance
#: at a simple branch point); else the point is degenerate (e.g. cubic tangency).
ABE_DEGENERATE = 1e-3

#: Start points tried, the amplitude divided by 4 after each failure (a failed start
#: costs a few Newton iterations).
N_START_ATTEMPTS = 8

#: Runs tried through the branch point, the amplitude divided by 4 after a run that
#: fails the row check next to the branch point.
N_CROSSING_ATTEMPTS = 2

#: Below this sine of the crossing angle the default amplitude shrinks in proportion
#: (the start corrector's basin and the separation of the two branches near the branch
#: point scale with ``amplitude * sin(angle)``).
SMALL_ANGLE_SIN = 0.1

_EPS = float(np.finfo(float).eps)

Direction = Literal["forward", "backward", "both"]


# ---------------------------------------------------------------------------- result types
@dataclass(frozen=True, eq=False)
class CrossingTangents:
    r"""The two branch directions at a simple branch point (solution of the ABE).

    Attributes
    ----------
    z : ndarray, shape (N,)
    p : float
        The branch point :math:`u^* = (z, p)`.
    t_old : ndarray, shape (N + 1,)
        Root of the ABE along the current branch (unit in the ``theta`` norm; sign as
        the reference tangent). NaN when ``status`` is not ``SUCCESS``.
    t_new : ndarray, shape (N + 1,)
        Root of the ABE along the crossing branch (unit; sign arbitrary).
    phi2 : ndarray, shape (N + 1,)
        Unit part of ``t_new`` ``theta``-orthogonal to ``t_old``.
    psi : ndarray, shape (N,)
        Unit left null vector of ``A = [G_z G_p]``.
    coefficients : tuple of float
        ``(c11, c12, c22)`` of the ABE in the kernel basis ``(q1, q2)``.
    angle_deg : float
        Angle between the two branches (``theta`` metric), in ``(0, 90]``.
    cos_reference : float
        ``|<t_old, reference>_theta|``: how well the root identified as the current
        branch matches the reference tangent passed in.
    kernel_gap : float
        ``sigma_N / sigma_{N-1}`` of ``A W^{-1/2}`` (dense kernel; 0 for ``N = 1``), or
        the relative kernel residual ``max ||A q_k|| / ||A||`` (bordered kernel).
    kernel : {"svd", "bordered"}
    second_derivatives : {"casadi", "finite differences"}
    status : Status
        ``SUCCESS``, or ``SINGULAR`` when the point is not a simple branch point (no
        two-dimensional kernel, a degenerate or double-rooted ABE).
    message : str
    """

    z: FloatArray
    p: float
    t_old: FloatArray
    t_new: FloatArray
    phi2: FloatArray
    psi: FloatArray
    coefficients: tuple[float, float, float]
    angle_deg: float
    cos_reference: float
    kernel_gap: float
    kernel: str
    second_derivatives: str
    status: Status
    message: str = ""

    @property
    def sin_angle(self) -> float:
        """``S = <phi2, t_new>_theta``, the sine of the angle between the branches."""
        return math.sin(math.radians(self.angle_deg))


class _Failure(Exception):
    def __init__(self, status: Status, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


# ---------------------------------------------------------------------------- kernel
def _dense(Gz: Any) -> FloatArray:
    return np.asarray(Gz.toarray() if sp.issparse(Gz) else Gz, dtype=float)


def _w_orthonormal(a: FloatArray, b: FloatArray, w: FloatArray) -> tuple[FloatArray, FloatArray]:
    a = a / theta_norm(a, w)
    b = b - float((w * a).dot(b)) * a
    nb = theta_norm(b, w)
    if not nb > 0:
        raise _Failure(Status.SINGULAR, "the kernel of [G_z G_p] is not two-dimensional")
    return a, b / nb


def _kernel_svd(
    Gz: Any, Gp: FloatArray, w: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    """``q1, q2`` (``theta``-orthonormal kernel of ``A``), ``psi`` and the gap ratio."""
    A = np.column_stack((_dense(Gz), Gp))
    n = A.shape[0]
    s = 1.0 / np.sqrt(w)
    U, sv, Vt = np.linalg.svd(A * s[None, :])
    if not np.all(np.isfinite(sv)):
        raise _Failure(Status.NONFINITE, "non-finite Jacobian at the branch point")
    gap = float(sv[-1] / sv[-2]) if n >= 2 and sv[-2] > 0 else 0.0
    if n >= 2 and not gap <= KERNEL_GAP:
        raise _Failure(
            Status.SINGULAR,
            f"[G_z G_p] has no two-dimensional kernel at the point (sigma_N / sigma_N-1 = "
            f"{gap:.2g}): not a branch point",
        )
    if n >= 3 and sv[-2] <= KERNEL_GAP * sv[-3] and sv[-2] <= 1e-8 * sv[0]:
        raise _Failure(
            Status.SINGULAR,
            "[G_z G_p] has a kernel of dimension > 2 at the point: not a simple branch point",
        )
    return s * Vt[-1], s * Vt[-2], U[:, -1].copy(), gap


def _kernel_bordered(
    Gz: Any, Gp: FloatArray, w: FloatArray, t_ref: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    """Kernel and left null vector of ``A = [G_z G_p]`` from bordered sparse solves."""
    n = Gp.size
    A = sp.hstack([sp.csc_matrix(Gz), sp.csc_matrix(Gp.reshape(-1, 1))], format="csc")
    rng = np.random.default_rng(20000)
    c1, c2 = _w_orthonormal(t_ref, rng.standard_normal(n + 1), w)
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
            raise _Failure(Status.SINGULAR, f"singular bordered matrix: {exc}") from None
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(Y))):
            raise _Failure(Status.SINGULAR, "singular bordered matrix at the branch point")
        c1, c2 = _w_orthonormal(X[: n + 1, 0], X[: n + 1, 1], w)
        psi = Y[:n]
        npsi = float(np.linalg.norm(psi))
        if not npsi > 0:
            raise _Failure(Status.SINGULAR, "no left null vector of [G_z G_p]")
        b = psi / npsi
    scale = float(abs(A).max()) * max(float(np.max(np.abs(c1))), float(np.max(np.abs(c2))))
    res = max(float(np.max(np.abs(A @ c1))), float(np.max(np.abs(A @ c2))))
    gap = res / scale if scale > 0 else 0.0
    if not gap <= 1e-6:
        raise _Failure(
            Status.SINGULAR,
            f"[G_z G_p] has no two-dimensional kernel at the point (relative residual "
            f"{gap:.2g} of the bordered kernel vectors): not a branch point",
        )
    return c1, c2, b, gap


# ---------------------------------------------------------------------------- D^2 G
SecondDerivative = Callable[[FloatArray, FloatArray, FloatArray], FloatArray]


def _casadi_second_derivative(problem: EquilibriumProblem) -> SecondDerivative:
    """``(u, a, b) -> D^2G(u)[a, b]`` from the CasADi trace of the system's ``rhs``."""
    system = problem.system
    n = system.n_states
    idx = system.param_names.index(problem.free)
    U = ca.SX.sym("u", n + 1)
    a = ca.SX.sym("a", n + 1)
    b = ca.SX.sym("b", n + 1)
    vals = np.asarray(problem.params.values, dtype=float)
    P = ca.vertcat(*[U[n] if k == idx else ca.SX(float(v)) for k, v in enumerate(vals)])
    F = system.symbolic(U[0:n], P)
    d2 = ca.jtimes(ca.jtimes(F, U, a), U, b)
    fn = ca.Function("d2G", [U, a, b], [d2])

    def d2G(u: FloatArray, aa: FloatArray, bb: FloatArray) -> FloatArray:
        return np.asarray(fn(u, aa, bb), dtype=float).reshape(-1)

    return d2G


def _fd_second_derivative(problem: Any) -> SecondDerivative:
    """``(u, a, b) -> D^2G(u)[a, b]`` by central differences of ``[G_z G_p] a``."""

    def d2G(u: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
        n = u.size - 1
        h = _EPS ** (1.0 / 3.0) * max(1.0, float(np.max(np.abs(u)))) / float(np.max(np.abs(b)))
        out = []
        for sgn in (1.0, -1.0):
            uu = u + sgn * h * b
            _, Gz, Gp = linearize(problem, uu[:n], float(uu[n]))
            out.append(np.asarray(Gz @ a[:n]).reshape(-1) + Gp * a[n])
        return (out[0] - out[1]) / (2.0 * h)

    return d2G


def _second_derivative(problem: Any) -> tuple[SecondDerivative, str]:
    system = getattr(problem, "system", None)
    if isinstance(problem, EquilibriumProblem) and getattr(system, "has_casadi", False):
        try:
            return _casadi_second_derivative(problem), "casadi"
        except Exception as exc:  # a model CasADi cannot trace twice: fall back
            log.info("no CasADi second derivatives (%s); using finite differences", exc)
    return _fd_second_derivative(problem), "finite differences"


# ---------------------------------------------------------------------------- ABE
def _abe_roots(
    d2G: SecondDerivative, u: FloatArray, q1: FloatArray, q2: FloatArray, psi: FloatArray
) -> tuple[tuple[float, float, float], FloatArray, FloatArray]:
    """ABE coefficients and the two root directions (``theta``-unit, as combinations of
    the ``theta``-orthonormal ``q1, q2``)."""
    D = [d2G(u, q1, q1), d2G(u, q1, q2), d2G(u, q2, q2)]
    if not all(np.all(np.isfinite(d)) for d in D):
        raise _Failure(Status.NONFINITE, "non-finite second derivatives at the branch point")
    c11, c12, c22 = (float(psi.dot(d)) for d in D)
    scale = max(float(np.linalg.norm(d)) for d in D)
    cmax = max(abs(c11), abs(c12), abs(c22))
    if not (scale > 0 and cmax > ABE_ZERO * scale):
        raise _Failure(
            Status.SINGULAR,
            "the algebraic bifurcation equation vanishes identically (all second-order "
            f"coefficients ~0: c = ({c11:.3g}, {c12:.3g}, {c22:.3g})): a degenerate, not a "
            "simple, branch point",
        )
    lam, E = np.linalg.eigh(np.array([[c11, c12], [c12, c22]]))
    lmax = float(np.max(np.abs(lam)))
    if not (lam[0] < 0.0 < lam[1] and min(-lam[0], lam[1]) > ABE_SIMPLE * lmax):
        raise _Failure(
            Status.SINGULAR,
            "the algebraic bifurcation equation has no two distinct real roots "
            f"(c12^2 - c11 c22 = {c12 * c12 - c11 * c22:.3g}, coefficients ({c11:.3g}, "
            f"{c12:.3g}, {c22:.3g})): not a simple branch point",
        )
    e_minus, e_plus = E[:, 0], E[:, 1]
    roots = []
    for sgn in (1.0, -1.0):
        ab = math.sqrt(-lam[0]) * e_plus + sgn * math.sqrt(lam[1]) * e_minus
        ab = ab / float(np.linalg.norm(ab))
        roots.append(ab[0] * q1 + ab[1] * q2)  # theta-unit since q1, q2 orthonormal
    return (c11, c12, c22), roots[0], roots[1]


def crossing_tangents(
    problem: Any,
    z: Any,
    p: float,
    reference: Any,
    *,
    theta: float = 0.5,
    kernel: Literal["auto", "svd", "bordered"] = "auto",
    throw: bool = False,
) -> CrossingTangents:
    r"""Tangents of the two branches through a simple branch point (solve the ABE).

    Parameters
    ----------
    problem : ContinuationProblem
        ``G(z, p) = 0`` (an :class:`~continuation.problem.EquilibriumProblem` of a
        CasADi-traced system gets exact second derivatives; others finite differences).
    z : array_like, shape (N,)
    p : float
        The (located) branch point.
    reference : array_like, shape (N + 1,)
        A direction close to the tangent of the current branch (e.g. the chord between
        the two rows around the point); picks which ABE root is the current branch.
    theta : float
        Weight of the parameter in the inner product (as in the settings), in (0, 1].
    kernel : {"auto", "svd", "bordered"}
        Dense SVD of ``[G_z G_p]`` or sparse bordered solves; ``"auto"`` uses the
        bordered solves for sparse Jacobians with more than ``DENSE_KERNEL_MAX``
        unknowns.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` instead of returning a
        result with a failing ``status``.

    Returns
    -------
    CrossingTangents
        See the module notes for the equations.

    Raises
    ------
    ValueError
        Bad shapes, non-finite input, ``theta`` or ``kernel`` out of range.
    """
    n = int(problem.n_unknowns)
    z = np.asarray(z, dtype=float)
    if z.shape != (n,) or not np.all(np.isfinite(z)):
        raise ValueError(f"`z` must be a finite array of shape ({n},), got {z!r}")
    try:
        p = float(p)
    except (TypeError, ValueError):
        raise ValueError(f"`p` must be a float, got {p!r}") from None
    if not math.isfinite(p):
        raise ValueError(f"`p` must be finite, got {p}")
    ref = np.asarray(reference, dtype=float)
    if ref.shape != (n + 1,) or not np.all(np.isfinite(ref)) or not np.any(ref):
        raise ValueError(f"`reference` must be a finite non-zero array of shape ({n + 1},)")
    if not (isinstance(theta, (int, float)) and 0 < theta <= 1):
        raise ValueError(f"`theta` must be in (0, 1], got {theta!r}")
    if kernel not in ("auto", "svd", "bordered"):
        raise ValueError(f"`kernel` must be 'auto', 'svd' or 'bordered', got {kernel!r}")
    w = theta_weights(n, float(theta))
    ref = ref / theta_norm(ref, w)
    u = np.append(z, p)
    nan = np.full(n + 1, np.nan)
    method, d2_name = "svd", "finite differences"
    try:
        _, Gz, Gp = linearize(problem, z, p)
        use_bordered = kernel == "bordered" or (
            kernel == "auto" and sp.issparse(Gz) and n > DENSE_KERNEL_MAX
        )
        if use_bordered:
            method = "bordered"
            q1, q2, psi, gap = _kernel_bordered(Gz, Gp, w, ref)
        else:
            q1, q2, psi, gap = _kernel_svd(Gz, Gp, w)
        d2G, d2_name = _second_derivative(problem)
        coef, r1, r2 = _abe_roots(d2G, u, q1, q2, psi)
        cos1, cos2 = abs(float((w * r1).dot(ref))), abs(float((w * r2).dot(ref)))
        t_old, t_new = (r1, r2) if cos1 >= cos2 else (r2, r1)
        cos_ref = max(cos1, cos2)
        if float((w * t_old).dot(ref)) < 0:
            t_old = -t_old
        c_on = abs(float((w * t_old).dot(t_new)))
        if c_on > MAX_COS_BRANCHES:
            raise _Failure(
                Status.SINGULAR,
                f"the two roots of the algebraic bifurcation equation are almost parallel "
                f"(cos = {c_on:.6f}): not a simple branch point",
            )
        phi2 = t_new - float((w * t_new).dot(t_old)) * t_old
        phi2 = phi2 / theta_norm(phi2, w)
        if float((w * phi2).dot(t_new)) < 0:
            phi2 = -phi2
        angle = math.degrees(math.acos(min(1.0, c_on)))
        if cos_ref < 0.9:
            log.warning(
                "neither root of the algebraic bifurcation equation matches the current "
                "branch's direction well (best cosine %.3f): the point may not be located "
                "accurately",
                cos_ref,
            )
        return CrossingTangents(
            z, p, t_old, t_new, phi2, psi, coef, angle, cos_ref, gap, method, d2_name,
            Status.SUCCESS,
        )  # fmt: skip
    except (_Failure, np.linalg.LinAlgError) as exc:
        status = exc.status if isinstance(exc, _Failure) else Status.SINGULAR
        msg = exc.message if isinstance(exc, _Failure) else f"linear algebra failed: {exc}"
        if throw:
            raise ContinuationError(msg) from None
        return CrossingTangents(
            z, p, nan, nan, nan, np.full(n, np.nan), (math.nan,) * 3, math.nan, math.nan,
            math.nan, method, d2_name, status, msg,
        )  # fmt: skip


# ---------------------------------------------------------------------------- start
class _OrientedStart(ContinuationAlgorithm):
    """Wraps an algorithm so that the start tangent points along ``+orient`` when
    ``settings.ds > 0`` and along ``-orient`` otherwise (instead of the sign rule on
    ``dp/ds``, which cannot tell the halves of a crossing branch apart where it is
    vertical, e.g. at a pitchfork)."""

    def __init__(self, inner: ContinuationAlgorithm, orient: FloatArray) -> None:
        self.inner = inner
        self.orient = orient
        self.grow_iters = int(getattr(inner, "grow_iters", 3))

    def init(
        self, problem: Any, z0: FloatArray, p0: float, settings: ContinuationSettings
    ) -> StepState:
        state = self.inner.init(problem, z0, p0, settings)
        pt = state.point
        target = self.orient if settings.ds > 0 else -self.orient
        if float((state.w * pt.tau).dot(target)) < 0:
            state.point = make_point(
                pt.z,
                pt.p,
                (pt.G, pt.Gz, pt.Gp),
                pt.border,
                state.w,
                orient=state.w * target,
                lu=pt.lu,
            )
            state.point.iters = pt.iters
        state.direction = 1.0 if state.point.tau[-1] >= 0 else -1.0
        return state

    def step(
        self, problem: Any, state: StepState, settings: ContinuationSettings
    ) -> tuple[StepState, StepOutcome]:
        return self.inner.step(problem, state, settings)

    def __repr__(self) -> str:
        return f"_OrientedStart({self.inner!r})"


def _start_point(
    problem: Any,
    ct: CrossingTangents,
    t_new: FloatArray,
    amplitude: float,
    sign: float,
    w: FloatArray,
    newton: NewtonSettings,
) -> tuple[FloatArray | None, str]:
    """Solve ``G(u) = 0, <phi2, u - u*>_theta = sign a S`` from ``u* + sign a t_new``;
    returns ``(u, "")`` or ``(None, reason)``."""
    u_star = np.append(ct.z, ct.p)
    phi2 = ct.phi2 if float((w * ct.phi2).dot(t_new)) > 0 else -ct.phi2
    S = float((w * phi2).dot(t_new))
    u_pred = u_star + sign * amplitude * t_new
    res = correct(problem, u_pred, u_star, w * phi2, sign * amplitude * S, newton)
    if not res.converged or res.lin is None:
        return None, f"the start point did not converge ({res.message or 'Newton failed'})"
    dist = theta_norm(res.u - u_pred, w)
    if dist > START_DISTANCE * amplitude:
        return None, (
            f"the corrected start point is {dist / amplitude:.3g} amplitudes away from its "
            "prediction on the crossing branch"
        )
    try:
        pt = make_point(res.z, res.p, res.lin, w * t_new, w)
    except np.linalg.LinAlgError as exc:
        return None, f"no tangent at the start point ({exc})"
    cos = abs(float((w * pt.tau).dot(t_new)))
    if cos < math.cos(math.radians(START_ANGLE_DEG)):
        return None, (
            f"the tangent at the start point turns by {math.degrees(math.acos(cos)):.1f} deg "
            "from the crossing direction"
        )
    return np.array(res.u), ""


def _check_crossing(
    br: Branch, ct: CrossingTangents, t_new: FloatArray, w: FloatArray, k0: int, side: float,
    amplitude: float,
) -> tuple[bool, int, float]:  # fmt: skip
    r"""Did the run from row ``k0`` (on the ``side`` half) through the branch point stay on
    the crossing branch?

    Walks from row ``k0`` towards the branch point (decreasing row numbers for
    ``side = +1``) and checks every row within ``4 amplitude`` of ``u*`` and the first
    row past it: with ``d = u - u*``, ``s = <t_new, d>_theta`` and ``h = <phi2, d>_theta``,
    a row on the crossing branch has ``h ~ S s`` while one on the current branch has
    ``h ~ 0`` (``S = sin`` of the crossing angle). Returns ``(ok, first bad row, h / (S
    s) there)``; ``(True, -1, nan)`` when every checked row passes.
    """
    u_star = np.append(ct.z, ct.p)
    phi2 = ct.phi2 if float((w * ct.phi2).dot(t_new)) > 0 else -ct.phi2
    S = float((w * phi2).dot(t_new))
    step = -1 if side > 0 else 1
    k = k0 + step
    radius = 4.0 * amplitude
    while 0 <= k < len(br):
        d = _delta(br.problem, br.x[k], br.p[k], u_star[:-1], u_star[-1])
        s = float((w * t_new).dot(d))
        past = s * side <= 0
        near = theta_norm(d, w) <= radius
        if abs(s) > 1e-6 * amplitude and (near or past):
            ratio = float((w * phi2).dot(d)) / (S * s)
            if ratio < CROSSING_RATIO:
                return False, k, ratio
        if past and not near:
            break  # the first row past u* beyond the radius was the last one checked
        k += step
    return True, -1, math.nan


def _delta(problem: Any, z1: FloatArray, p1: float, z0: FloatArray, p0: float) -> FloatArray:
    """``(z1, p1) - (z0, p0)``, periodic states reduced modulo their period."""
    diff = difference(problem)
    dz = diff(z1, z0) if diff is not None else np.asarray(z1) - np.asarray(z0)
    return np.append(np.asarray(dz, dtype=float), float(p1) - float(p0))


def _slice(br: Branch, lo: int, hi: int) -> Branch:
    """Rows ``lo:hi`` of ``br`` with its special points inside them re-indexed."""
    s0 = float(br.arclength[lo]) if len(br) else 0.0
    ds = np.array(br.ds[lo:hi])
    if ds.size:
        ds[0] = 0.0
    sps = tuple(
        dataclasses.replace(sp, index=sp.index - lo, s=sp.s - s0)
        for sp in br.special_points
        if lo <= sp.index and sp.index + 1 < hi
    )
    return dataclasses.replace(
        br,
        p=br.p[lo:hi],
        x=br.x[lo:hi],
        eigenvalues=br.eigenvalues[lo:hi],
        n_unstable=br.n_unstable[lo:hi],
        ds=ds,
        newton_iters=br.newton_iters[lo:hi],
        records={k: v[lo:hi] for k, v in br.records.items()},
        special_points=sps,
    )


# ---------------------------------------------------------------------------- public API
def _resolve_point(branch: Branch, point: SpecialPoint | str) -> SpecialPoint:
    labels = [s.label for s in branch.special_points if s.label]
    if isinstance(point, str):
        matches = [s for s in branch.special_points if s.label == point]
        if not matches:
            raise ValueError(
                f"`point`: no special point labelled {point!r} on this branch; labels are {labels}"
            )
        sp_ = matches[0]
    elif isinstance(point, SpecialPoint):
        same = [
            s
            for s in branch.special_points
            if s is point
            or (
                s.kind == point.kind
                and s.label == point.label
                and s.p == point.p
                and np.shape(s.x) == np.shape(point.x)
                and np.array_equal(s.x, point.x)
            )
        ]
        if not same:
            raise ValueError(
                f"`point` ({point.label or point.kind.value} at p={point.p:.6g}) is not a "
                f"special point of `branch`; its special points are {labels}"
            )
        sp_ = point
    else:
        raise ValueError(
            f"`point` must be a SpecialPoint of `branch` or its label, got {type(point).__name__}"
        )
    if sp_.kind is not SpecialKind.BRANCH_POINT:
        raise ValueError(
            f"`point` must be a branch point (kind 'bp'), got {sp_.kind.value!r} "
            f"({sp_.label or '?'})"
        )
    if not sp_.located:
        raise ValueError(
            f"`point` {sp_.label or ''} was only bracketed, not located; branch switching "
            "needs a located branch point (tighten DetectionSettings or recompute the branch)"
        )
    return sp_


def _reference_tangent(branch: Branch, point: SpecialPoint, w: FloatArray) -> FloatArray:
    """Direction of the current branch at the point: the chord of the two rows around
    it (the tangent the locator stored is ill-determined exactly at a branch point,
    where the bordered matrix is singular)."""
    i = int(point.index)
    if 0 <= i and i + 1 < len(branch):
        chord = _delta(branch.problem, branch.x[i + 1], branch.p[i + 1], branch.x[i], branch.p[i])
        if np.all(np.isfinite(chord)) and theta_norm(chord, w) > 0:
            return chord / theta_norm(chord, w)
    if point.tangent is not None and np.all(np.isfinite(point.tangent)):
        t = np.asarray(point.tangent, dtype=float)
        if t.shape == w.shape and theta_norm(t, w) > 0:
            return t / theta_norm(t, w)
    raise ValueError(
        f"`point` {point.label}: no rows of `branch` around it and no tangent, so the "
        "current branch's direction is unknown"
    )


def _row_abe_scale(problem: Any, branch: Branch, point: SpecialPoint, w: FloatArray) -> float:
    r"""Size of the ABE coefficients expected from the rows around the point.

    Along the current branch ``u(s) = u* + s t_old + ...`` the smallest singular value
    of ``A(u(s)) W^{-1/2}`` is ``|s| |c| + O(s^2)`` at a simple branch point (``c`` the
    ABE coefficients in a ``theta``-orthonormal basis), so ``sigma_N / ||u - u*||`` at
    the two rows estimates ``|c|``; returns the larger estimate (NaN when the problem is
    too large for dense SVDs or no row is usable).
    """
    n = int(problem.n_unknowns)
    if n > DENSE_KERNEL_MAX:
        return math.nan
    u_star = np.append(point.x, point.p)
    s = 1.0 / np.sqrt(w)
    est = math.nan
    for i in (point.index, point.index + 1):
        if not 0 <= i < len(branch):
            continue
        u = np.append(branch.x[i], branch.p[i])
        d = theta_norm(_delta(problem, u[:-1], u[-1], u_star[:-1], u_star[-1]), w)
        if not d > 1e-8 * max(1.0, theta_norm(u_star, w)):
            continue
        _, Gz, Gp = linearize(problem, u[:-1], float(u[-1]))
        A = np.column_stack((_dense(Gz), Gp)) * s[None, :]
        try:
            sv = np.linalg.svd(A, compute_uv=False)
        except np.linalg.LinAlgError:
            continue
        e = float(sv[-1]) / d
        if math.isfinite(e):
            est = e if not math.isfinite(est) else max(est, e)
    return est


def _orient(t: FloatArray, sign_ds: float) -> FloatArray:
    """``t`` with ``sign(dp/ds) = sign_ds``; if ``t`` is (numerically) vertical, with its
    largest state component positive: the first of the components within a relative
    ``1e-3`` of the largest magnitude, so that mirror-symmetric problems (an
    antisymmetric kernel vector has two largest components of opposite sign, told apart
    only by round-off or by the point's own asymmetry, ~1e-5) are oriented the same way
    on every machine."""
    if abs(float(t[-1])) > 1e-6:
        return t if t[-1] * sign_ds > 0 else -t
    mag = np.abs(t[:-1])
    k = int(np.argmax(mag >= (1.0 - 1e-3) * mag.max()))
    return t if t[k] > 0 else -t


def _empty(
    branch: Branch, problem: Any, status: Status, message: str, settings: ContinuationSettings,
    events: Sequence[Event],
) -> Branch:  # fmt: skip
    n = int(problem.n_unknowns)
    return Branch(
        problem=problem,
        free=branch.free,
        p=np.zeros(0),
        x=np.zeros((0, n)),
        eigenvalues=np.zeros((0, n), dtype=complex),
        n_unstable=np.zeros(0, dtype=int),
        ds=np.zeros(0),
        newton_iters=np.zeros(0, dtype=int),
        records={},
        special_points=(),
        status=status,
        message=message,
        settings=settings,
        state_names=branch.state_names,
        param_values=branch.param_values,
        event_names=tuple(e.name for e in events),
    )


def switch_branch(
    branch: Branch,
    point: SpecialPoint | str,
    *,
    settings: ContinuationSettings | None = None,
    direction: Direction = "both",
    events: Sequence[Event] = (),
    amplitude: float | None = None,
    algorithm: ContinuationAlgorithm | None = None,
    throw: bool = False,
    progress: Callable[[BranchPoint], None] | None = None,
) -> Branch:
    r"""Continue the branch that crosses ``branch`` at the simple branch point ``point``.

    The tangent of the crossing branch is the root of the algebraic bifurcation
    equation (module notes)

    .. math::

        c_{11}\alpha^2 + 2 c_{12}\alpha\beta + c_{22}\beta^2 = 0, \qquad
        c_{ij} = \psi^T D^2G(u^*)[q_i, q_j],

    that is not the current branch's (Keller 1977; Doedel, Keller & Kernevez 1991;
    Govaerts 2000; Kuznetsov 2004, Sec. 10.2). A start point at distance
    ``amplitude`` along it is corrected on a hyperplane parallel to the current branch,
    checked to lie on the crossing branch, and continued with
    :func:`~continuation.driver.continue_branch`.

    Parameters
    ----------
    branch : Branch
        A branch holding its problem (computed in this session, or loaded with
        ``Branch.load(path, problem)``).
    point : SpecialPoint or str
        A located branch point of ``branch`` (kind ``"bp"``), or its label, e.g.
        ``"BP1"``.
    settings : ContinuationSettings, optional
        Default ``branch.settings``. Bounds, ``ds_max``, ``max_steps`` (per direction),
        corrector and detection apply to the new branch; the first step is
        ``0.7 * amplitude`` (so that no step lands on the singular point) and grows
        from there. ``sign(ds)`` orients the new branch (below).
    direction : {"both", "forward", "backward"}
        ``"forward"``: the half of the crossing branch along ``+t_new``, the crossing
        tangent oriented so that ``sign(dp/ds) = sign(settings.ds)`` (where the
        crossing branch is vertical, ``dp/ds = 0``, as at a pitchfork: so that its
        largest state component is positive, the first one of those within 1e-3 of the
        largest magnitude); it starts at distance ``amplitude``
        from the branch point. ``"backward"``: the other half. ``"both"``: one branch
        ordered from the backward end through the branch point (detected again there,
        with any fold of the new branch at it) to the forward end.
    events : sequence of Event
        User events monitored along the new branch.
    amplitude : float, optional
        Distance (``theta`` norm, as ``ds``) of the start point from the branch
        point along the crossing tangent; default ``min(|ds|, 0.01 max(1,
        ||u*||_theta))``, times ``sin(angle) / 0.1`` when the branches cross at less
        than ~5.7 degrees. Divided by 4 after a start that cannot be corrected onto the
        crossing branch (up to 7 times) and after a run through the branch point that
        fails the row check (once).
    algorithm : ContinuationAlgorithm, optional
        Default :class:`~continuation.algorithms.palc.PALC`.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` (a
        :class:`~continuation.errors.ConvergenceError` when no start point converges)
        instead of returning a failed branch.
    progress : callable, optional
        ``progress(BranchPoint)`` after every accepted point.

    Returns
    -------
    Branch
        The crossing branch; its message starts with the switching data (crossing
        angle). On failure an empty branch (or, if the run through the branch point
        left the crossing branch, the verified part on the start side) with
        ``status`` ``SINGULAR`` (not a simple branch point: degenerate ABE or kernel),
        ``NEWTON_FAILED`` (no start point on the crossing branch, or the run fell back
        onto ``branch``) or ``PARAM_BOUND`` (the requested half lies outside
        ``[p_min, p_max]``).

    Raises
    ------
    ValueError
        ``branch`` without a problem; ``point`` not a located branch point of
        ``branch``, or an unknown label; ``amplitude <= 0`` or not finite; unknown
        ``direction``; ``settings``/``algorithm`` of the wrong type.
    """
    if not isinstance(branch, Branch):
        raise ValueError(f"`branch` must be a Branch, got {type(branch).__name__}")
    problem = branch.problem
    if problem is None:
        raise ValueError(
            "`branch` has no problem (loaded from disk?): reload it with "
            "Branch.load(path, problem) to switch branches"
        )
    sp_ = _resolve_point(branch, point)
    if direction not in ("forward", "backward", "both"):
        raise ValueError(f"`direction` must be 'forward', 'backward' or 'both', got {direction!r}")
    if amplitude is not None:
        try:
            amplitude = float(amplitude)
        except (TypeError, ValueError):
            raise ValueError(f"`amplitude` must be a positive number, got {amplitude!r}") from None
        if not (math.isfinite(amplitude) and amplitude > 0):
            raise ValueError(f"`amplitude` must be a positive finite number, got {amplitude!r}")
    if settings is None:
        settings = branch.settings if branch.settings is not None else ContinuationSettings()
    if not isinstance(settings, ContinuationSettings):
        raise ValueError(f"`settings` must be a ContinuationSettings, got {type(settings)}")
    algorithm = algorithm if algorithm is not None else PALC()
    if not isinstance(algorithm, ContinuationAlgorithm):
        raise ValueError(f"`algorithm` must be a ContinuationAlgorithm, got {algorithm!r}")
    events = tuple(events)
    for e in events:
        if not isinstance(e, Event):
            raise ValueError(f"`events` must contain Event instances, got {e!r}")
    n = int(problem.n_unknowns)
    z_star = np.asarray(sp_.x, dtype=float)
    if z_star.shape != (n,) or not np.all(np.isfinite(z_star)):
        raise ValueError(f"`point` has a state of shape {z_star.shape}, expected finite ({n},)")

    w = theta_weights(n, settings.theta)
    label = sp_.label or "the branch point"

    def fail(status: Status, msg: str, exc: type[ContinuationError] = ContinuationError) -> Branch:
        msg = f"branch switching at {label} ({branch.free}={sp_.p:.10g}) failed: {msg}"
        log.warning(msg)
        if throw:
            raise exc(msg)
        return _empty(branch, problem, status, msg, settings, events)

    ref = _reference_tangent(branch, sp_, w)
    ct = crossing_tangents(problem, z_star, sp_.p, ref, theta=settings.theta)
    if ct.status is not Status.SUCCESS:
        return fail(ct.status, ct.message)
    est = _row_abe_scale(problem, branch, sp_, w)
    cmax = max(abs(c) for c in ct.coefficients)
    if math.isfinite(est) and est > 0 and cmax < ABE_DEGENERATE * est:
        return fail(
            Status.SINGULAR,
            f"the algebraic bifurcation equation is degenerate: its coefficients "
            f"(max {cmax:.3g}) are {cmax / est:.2g} times their size estimated from the "
            f"rows around the point ({est:.3g}); not a simple branch point",
        )
    sign_ds = 1.0 if settings.ds > 0 else -1.0
    t_new = _orient(ct.t_new, sign_ds)
    u_star = np.append(z_star, sp_.p)
    amp = amplitude
    if amp is None:
        amp = min(abs(settings.ds), 1e-2 * max(1.0, theta_norm(u_star, w)))
        amp *= min(1.0, ct.sin_angle / SMALL_ANGLE_SIN)
    info = (
        f"switched at {label} ({branch.free}={sp_.p:.10g}) onto the crossing branch "
        f"(angle {ct.angle_deg:.4g} deg, ABE coefficients "
        f"({ct.coefficients[0]:.4g}, {ct.coefficients[1]:.4g}, {ct.coefficients[2]:.4g}))"
    )
    if direction == "both":
        sides: tuple[float, ...] = (1.0, -1.0)  # either start will do; the other is spare
    else:
        sides = (1.0,) if direction == "forward" else (-1.0,)

    last_reason = ""
    n_start_fail = n_cross_fail = 0
    while n_start_fail < N_START_ATTEMPTS and n_cross_fail < N_CROSSING_ATTEMPTS:
        start: FloatArray | None = None
        side = 0.0
        out_of_bounds = 0
        for sd in sides:
            u, reason = _start_point(problem, ct, t_new, amp, sd, w, settings.newton)
            if u is None:
                last_reason = reason
                continue
            if not settings.p_min <= u[-1] <= settings.p_max:
                out_of_bounds += 1
                last_reason = f"the start point {branch.free}={u[-1]:.10g} is outside the bounds"
                continue
            start, side = u, sd
            break
        if start is None:
            if out_of_bounds == len(sides):
                msg = (
                    f"the requested half of the crossing branch leaves [p_min, p_max] at "
                    f"once ({last_reason})"
                )
                return fail(Status.PARAM_BOUND, msg)
            log.info("amplitude %.3g: %s", amp, last_reason)
            n_start_fail += 1
            amp /= 4.0
            continue
        ds0 = min(max(0.7 * amp, settings.ds_min), settings.ds_max)
        run_settings = dataclasses.replace(settings, ds=ds0)
        br = continue_branch(
            problem,
            start[:-1],
            float(start[-1]),
            _OrientedStart(algorithm, t_new),
            run_settings,
            events=events,
            direction=direction,
            throw=False,
            progress=progress,
        )
        if not len(br):
            if br.status is Status.INTERRUPTED:
                return br
            last_reason = br.message
            n_start_fail += 1
            amp /= 4.0
            continue
        if direction == "both" and br.status is not Status.INTERRUPTED:
            dist = [
                theta_norm(_delta(problem, br.x[k], br.p[k], start[:-1], start[-1]), w)
                for k in range(len(br))
            ]
            k0 = int(np.argmin(dist))
            ok, k_bad, ratio = _check_crossing(br, ct, t_new, w, k0, side, amp)
            if not ok:
                last_reason = (
                    f"the continuation through the branch point left the crossing branch "
                    f"(row {k_bad} at {branch.free}={br.p[k_bad]:.10g} has {ratio:.3g} of "
                    "the predicted offset from the current branch)"
                )
                log.info("amplitude %.3g: %s", amp, last_reason)
                n_cross_fail += 1
                if n_cross_fail < N_CROSSING_ATTEMPTS:
                    amp /= 4.0
                    continue
                kept = _slice(br, k_bad + 1, len(br)) if side > 0 else _slice(br, 0, k_bad)
                msg = (
                    f"{info}; {last_reason}: only the part on the start side is kept. "
                    "Try a smaller `amplitude` or `ds_max`."
                )
                log.warning(msg)
                if throw:
                    raise ContinuationError(msg)
                return dataclasses.replace(kept, status=Status.NEWTON_FAILED, message=msg)
        br = dataclasses.replace(br, message=f"{info}; {br.message}")
        log.info("%s: %d points, status %s", info, len(br), br.status.name)
        if throw and not br.status.ok and br.status is not Status.INTERRUPTED:
            raise ContinuationError(br.message)
        return br
    return fail(
        Status.NEWTON_FAILED,
        f"no start point on the crossing branch (amplitude down to {amp * 4:.3g}): {last_reason}",
        ConvergenceError,
    )


__all__ = ["CrossingTangents", "crossing_tangents", "switch_branch"]
