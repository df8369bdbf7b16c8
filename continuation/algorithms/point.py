r"""A converged branch point with its linearisation, factorisation and tangent.

:func:`make_point` factorises the bordered matrix ``M = [[G_z, G_p], [c^T]]`` at a
converged point (or reuses the corrector's factorisation) and solves ``M t = e_{N+1}``;
``tau = t / ||t||_theta`` is the unit tangent, oriented so that ``c . tau > 0``.

Branch-point test function
--------------------------
For any row ``c`` with ``c . tau != 0``, linearity of the determinant in its last row
gives ``det [G_z G_p; (w o tau)^T] = det M / (c . tau)`` (``tau`` spans the kernel of
``[G_z G_p]``, and ``(w o tau) . tau = 1``). This quantity is smooth along the branch,
non-zero at regular points and at folds, and changes sign at simple branch points
(Allgower & Georg 1990, *Numerical Continuation Methods*, Sec. 8.1; Govaerts 2000,
Sec. 3.3). :class:`PointInfo` stores its sign and ``log|.|``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..linalg import BorderedLU
from ..linalg import getrs as _getrs
from ..linalg import inf_norm as _inf_norm
from ..linalg import last_unit as _last_unit
from ..problem import linearize
from ..typing import FloatArray


class PointVector:
    """Base of a point ``(z, p)`` whose vector ``u = (z, p)`` is joined on first use.

    It owns the slot ``_u``: None until :attr:`u` is first read, or the vector itself
    when the maker of the point already had it (a dataclass subclass declares ``_u``
    as a field; the slot stays this class's).
    """

    __slots__ = ("_u",)

    z: FloatArray
    p: float
    _u: FloatArray | None

    @property
    def u(self) -> FloatArray:
        """``(z, p)``, shape ``(N + 1,)`` (computed once; do not modify)."""
        if self._u is None:
            self._u = np.concatenate((self.z, (self.p,)))
        return self._u


@dataclass(eq=False, repr=False, slots=True)
class PointInfo(PointVector):
    """A converged branch point with its linearisation and tangent.

    Attributes
    ----------
    z : ndarray, shape (N,)
    p : float
    tau : ndarray, shape (N + 1,)
        Unit (``theta``-norm) tangent, oriented so that ``border . tau > 0``.
    G, Gz, Gp
        Residual ``(N,)``, Jacobian ``(N, N)`` (dense or sparse), ``dG/dp (N,)``.
    lu : BorderedLU or None
        Factorisation of ``[[Gz, Gp], [border^T]]`` (None at an exactly singular point).
        At points made by a continuation step it may be the factorisation of the last
        corrector iterate instead, within the corrector's step tolerance of the point.
    border : ndarray, shape (N + 1,)
    t_raw : ndarray, shape (N + 1,)
        ``M^{-1} e_{N+1}`` (un-normalised tangent, sign as solved).
    bp_sign : float
        Sign of ``det [Gz Gp; (w o tau)^T]`` (branch-point test function; lazy).
    ctau : float
        ``border . tau`` (for the determinant identity above).
    iters : int
        Corrector iterations spent on this point.
    residual_norm : float
        ``max |G|``.
    cache : dict
        Per-point cache of derived quantities (eigenvalues, test functions).
    """

    z: FloatArray
    p: float
    tau: FloatArray
    G: FloatArray
    Gz: Any
    Gp: FloatArray
    lu: BorderedLU | None
    border: FloatArray
    t_raw: FloatArray
    _bp_sign: float | None = None
    ctau: float = 1.0
    iters: int = 0
    residual_norm: float = 0.0
    cache: dict[str, Any] = field(default_factory=dict)
    _u: FloatArray | None = None
    _bp_logdet: float | None = None

    def __repr__(self) -> str:
        return f"PointInfo(p={self.p!r}, iters={self.iters}, |G|={self.residual_norm:.2e})"

    @property
    def bp_sign(self) -> float:
        """Sign of ``det [Gz Gp; (w o tau)^T] = det M / (border . tau)`` (lazy)."""
        if self._bp_sign is None:
            sign = self.lu.sign if self.lu is not None else 0.0
            self._bp_sign = sign if self.ctau > 0 else -sign
        return self._bp_sign

    @property
    def bp_logdet(self) -> float:
        """``log |det [Gz Gp; (w o tau)^T]| = log |det M| - log |border . tau|`` (lazy)."""
        if self._bp_logdet is None:
            self._bp_logdet = self.lu.logabsdet - math.log(abs(self.ctau))  # type: ignore[union-attr]
        return self._bp_logdet


def make_point(
    z: FloatArray,
    p: float,
    lin: tuple[FloatArray, Any, FloatArray],
    border: FloatArray,
    w: FloatArray,
    *,
    iters: int = 0,
    orient: FloatArray | None = None,
    lu: BorderedLU | None = None,
    u: FloatArray | None = None,
    residual_norm: float | None = None,
    t_raw: FloatArray | None = None,
    jac_finite: bool = False,
) -> PointInfo:
    """Factorise the bordered matrix at a converged point and compute its tangent.

    Parameters
    ----------
    z, p
        The point.
    lin : tuple
        ``(G, Gz, Gp)`` at the point.
    border : ndarray, shape (N + 1,)
        Last row ``c`` of the bordered matrix.
    w : ndarray, shape (N + 1,)
        ``theta`` weights.
    orient : ndarray, shape (N + 1,), optional
        Orientation: ``tau`` is chosen with ``orient . tau >= 0``; default ``border``.
    lu : BorderedLU, optional
        A factorisation of ``[[Gz, Gp], [border^T]]`` to reuse instead of factorising:
        that of the last corrector iterate, whose distance to the point is below the
        corrector's step tolerance (with the corrector's ``predict_final``: the last
        step, taken in the quadratic regime, e.g. 1e-6 relative). This is AUTO's
        practice (Doedel et al., AUTO-07p manual, Sec. "pseudo-arclength continuation":
        the new direction vector comes from the Jacobian of the last Newton iteration);
        it perturbs the tangent by
        that distance, which only affects the next predictor and the sign of the test
        functions within that distance of a zero (located special points are always
        computed with a fresh factorisation).
    u : ndarray, shape (N + 1,), optional
        ``(z, p)`` if already available.
    residual_norm : float, optional
        ``max |G|`` if already known.
    t_raw : ndarray, shape (N + 1,), optional
        ``lu``'s solution of ``M t = e_{N+1}`` if already known (ignored without ``lu``).
    jac_finite : bool
        ``Gz`` is known to be finite (recorded in the point's cache as ``"jac_finite"``,
        so that its eigenvalue solver can skip the check).

    Raises
    ------
    numpy.linalg.LinAlgError
        If the bordered matrix is singular.
    """
    G, Gz, Gp = lin
    if lu is None:
        lu = BorderedLU(Gz, Gp, border)
        t_raw = None
    if t_raw is not None:
        t = t_raw
    elif lu.sparse:
        t = lu.solve(_last_unit(lu.n))
    else:  # LAPACK directly; a non-finite t fails the norm test below
        t = _getrs(lu._lu, lu._piv, _last_unit(lu.n))[0]
    nrm2 = float((w * t).dot(t))
    if not (0.0 < nrm2 < math.inf):
        raise np.linalg.LinAlgError("degenerate tangent")
    tau = t * (1.0 / math.sqrt(nrm2))
    if orient is not None and float(orient.dot(tau)) < 0:
        tau = -tau
    ctau = float(border.dot(tau))
    if orient is None and ctau < 0:
        tau, ctau = -tau, -ctau
    if ctau == 0.0:
        raise np.linalg.LinAlgError("border orthogonal to the tangent")
    return PointInfo(
        z,
        float(p),
        tau,
        G,
        Gz,
        Gp,
        lu,
        border,
        t,
        None,
        ctau,
        iters,
        _inf_norm(G) if residual_norm is None else residual_norm,
        {"jac_finite": True} if jac_finite else {},
        u,
    )


def oriented_point(pt: PointInfo, w: FloatArray, target: FloatArray) -> PointInfo:
    r"""``pt`` with its tangent turned to point along ``target``.

    Parameters
    ----------
    pt : PointInfo
        A point whose tangent may point away from ``target``.
    w : ndarray, shape (N + 1,)
        ``theta`` weights.
    target : ndarray, shape (N + 1,)
        The direction: the returned tangent has :math:`\langle \tau, target\rangle_\theta
        = (w \circ \tau) \cdot target \ge 0`.

    Returns
    -------
    PointInfo
        ``pt`` itself unless its tangent points against ``target``; else the point
        made again (:func:`make_point`, reusing ``pt.lu``) with ``orient = w o target``,
        so that the reversed tangent, ``border . tau``, the branch-point sign and the
        iteration count go together.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the bordered matrix is singular.
    """
    if not float((w * pt.tau).dot(target)) < 0:
        return pt
    lin = (pt.G, pt.Gz, pt.Gp)
    return make_point(pt.z, pt.p, lin, pt.border, w, orient=w * target, lu=pt.lu, iters=pt.iters)


def initial_point(
    problem: Any,
    z: FloatArray,
    p: float,
    w: FloatArray,
    direction: float,
    lin: tuple[FloatArray, Any, FloatArray] | None = None,
) -> PointInfo:
    """Tangent and factorisation at a start point, with ``sign(dp/ds) = direction``.

    Uses the border ``c = e_p`` (tangent ``(-G_z^{-1} G_p, 1)``); at a singular ``G_z``
    (start on a fold) a fixed pseudo-random border is used instead.
    """
    lin = lin or linearize(problem, z, p)
    n = z.size
    e_p = np.zeros(n + 1)
    e_p[-1] = direction
    try:
        return make_point(z, p, lin, e_p, w)
    except np.linalg.LinAlgError:
        rng = np.random.default_rng(12345)
        c = rng.standard_normal(n + 1)
        c[-1] = abs(c[-1]) * direction
        pt = make_point(z, p, lin, c, w)
        if pt.tau[-1] * direction < 0:
            pt = make_point(z, p, lin, c, w, orient=-pt.tau)
        return pt


__all__ = ["PointInfo", "initial_point", "make_point", "oriented_point"]
