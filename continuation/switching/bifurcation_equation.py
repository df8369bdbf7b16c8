r"""The algebraic bifurcation equation (ABE) at a simple branch point, and its roots.

Every branch through the branch point :math:`u^*` has the form
:math:`u(s) = u^* + s\,(\alpha q_1 + \beta q_2) + O(s^2)` (:math:`q_1, q_2` the
``theta``-orthonormal kernel of :math:`A = [G_z\; G_p]`, :math:`\psi` its left null
vector: :mod:`~continuation.switching.kernel`); projecting the second-order expansion
of :math:`G(u(s)) = 0` on :math:`\psi` gives

.. math::

    c_{11}\alpha^2 + 2 c_{12}\alpha\beta + c_{22}\beta^2 = 0, \qquad
    c_{ij} = \psi^T D^2G(u^*)[q_i, q_j]

(second derivatives: :mod:`~continuation.switching.second_derivatives`). Its two real
roots, :math:`(\alpha, \beta) \propto \sqrt{-\lambda_-}\, e_+ \pm \sqrt{\lambda_+}\, e_-`
from the eigen-decomposition of :math:`C = [[c_{11}, c_{12}], [c_{12}, c_{22}]]`, are
the tangents of the current and the crossing branch (module notes of
:mod:`continuation.switching`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import scipy.sparse as sp

from ..algorithms.base import theta_norm, theta_weights
from ..arguments import finite_number
from ..errors import ContinuationError
from ..problem import linearize
from ..status import Status
from ..typing import FloatArray
from . import kernel as kernel_module
from .kernel import Failure, kernel_bordered, kernel_svd
from .second_derivatives import SecondDerivative, second_derivative

log = logging.getLogger(__name__)

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


def abe_roots(
    d2G: SecondDerivative, u: FloatArray, q1: FloatArray, q2: FloatArray, psi: FloatArray
) -> tuple[tuple[float, float, float], FloatArray, FloatArray]:
    """ABE coefficients and the two root directions.

    The directions are ``theta``-unit, as combinations of the ``theta``-orthonormal ``q1,
    q2``.
    """
    D = [d2G(u, q1, q1), d2G(u, q1, q2), d2G(u, q2, q2)]
    if not all(np.all(np.isfinite(d)) for d in D):
        raise Failure(Status.NONFINITE, "non-finite second derivatives at the branch point")
    c11, c12, c22 = (float(psi.dot(d)) for d in D)
    scale = max(float(np.linalg.norm(d)) for d in D)
    cmax = max(abs(c11), abs(c12), abs(c22))
    if not (scale > 0 and cmax > ABE_ZERO * scale):
        raise Failure(
            Status.SINGULAR,
            "the algebraic bifurcation equation vanishes identically (all second-order "
            f"coefficients ~0: c = ({c11:.3g}, {c12:.3g}, {c22:.3g})): a degenerate, not a "
            "simple, branch point",
        )
    lam, E = np.linalg.eigh(np.array([[c11, c12], [c12, c22]]))
    lmax = float(np.max(np.abs(lam)))
    if not (lam[0] < 0.0 < lam[1] and min(-lam[0], lam[1]) > ABE_SIMPLE * lmax):
        raise Failure(
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
        bordered solves for sparse Jacobians with more than
        ``kernel.DENSE_KERNEL_MAX`` unknowns.
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
    return solve_crossing_tangents(
        problem, z, p, reference, theta, kernel, throw, kernel_module.DENSE_KERNEL_MAX
    )


def solve_crossing_tangents(
    problem: Any,
    z: Any,
    p: float,
    reference: Any,
    theta: float,
    kernel: Literal["auto", "svd", "bordered"],
    throw: bool,
    dense_max: int,
) -> CrossingTangents:
    """:func:`crossing_tangents` with the size limit of the dense kernel passed in.

    Parameters
    ----------
    problem, z, p, reference, theta, kernel, throw
        As for :func:`crossing_tangents`.
    dense_max : int
        ``kernel="auto"`` takes the bordered solves for sparse Jacobians with more than
        ``dense_max`` unknowns: ``kernel.DENSE_KERNEL_MAX`` from
        :func:`crossing_tangents`, ``switch.DENSE_KERNEL_MAX`` from
        :func:`~continuation.switching.switch.switch_branch` (each read at call time).

    Returns
    -------
    CrossingTangents
    """
    n = int(problem.n_unknowns)
    z = np.asarray(z, dtype=float)
    if z.shape != (n,) or not np.all(np.isfinite(z)):
        raise ValueError(f"`z` must be a finite array of shape ({n},), got {z!r}")
    p = finite_number("p", p)
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
            kernel == "auto" and sp.issparse(Gz) and n > dense_max
        )
        if use_bordered:
            method = "bordered"
            q1, q2, psi, gap = kernel_bordered(Gz, Gp, w, ref)
        else:
            q1, q2, psi, gap = kernel_svd(Gz, Gp, w)
        d2G, d2_name = second_derivative(problem)
        coef, r1, r2 = abe_roots(d2G, u, q1, q2, psi)
        cos1, cos2 = abs(float((w * r1).dot(ref))), abs(float((w * r2).dot(ref)))
        t_old, t_new = (r1, r2) if cos1 >= cos2 else (r2, r1)
        cos_ref = max(cos1, cos2)
        if float((w * t_old).dot(ref)) < 0:
            t_old = -t_old
        c_on = abs(float((w * t_old).dot(t_new)))
        if c_on > MAX_COS_BRANCHES:
            raise Failure(
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
    except (Failure, np.linalg.LinAlgError) as exc:
        status = exc.status if isinstance(exc, Failure) else Status.SINGULAR
        msg = exc.message if isinstance(exc, Failure) else f"linear algebra failed: {exc}"
        if throw:
            raise ContinuationError(msg) from None
        return CrossingTangents(
            z, p, nan, nan, nan, np.full(n, np.nan), (math.nan,) * 3, math.nan, math.nan,
            math.nan, method, d2_name, status, msg,
        )  # fmt: skip


__all__ = ["CrossingTangents", "abe_roots", "crossing_tangents", "solve_crossing_tangents"]
