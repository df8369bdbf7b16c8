r"""Shared machinery of the continuation algorithms.

Notation: ``u = (z, p)`` in ``R^(N+1)``; ``G(z, p) = 0`` has ``N`` equations. The
``theta``-weighted inner product (settings ``theta``) is

.. math::

    \langle a, b \rangle_\theta = \frac{1-\theta}{N}\, a_z \cdot b_z + \theta\, a_p b_p
    = (w \circ a) \cdot b ,

with weight vector ``w`` (:func:`theta_weights`). Tangents ``tau`` have unit
``theta``-norm.

Bordered systems
----------------
Every linear solve is with a bordered matrix

.. math::

    M = \begin{pmatrix} G_z & G_p \\ c^T & \end{pmatrix} \in R^{(N+1)\times(N+1)},

factorised once (:class:`BorderedLU`: dense LAPACK LU, or SuperLU ``splu`` on an
assembled CSC matrix when ``G_z`` is sparse). The same factorisation gives the tangent
(``M t = e_{N+1}``, then ``tau = t / ||t||_theta``), which is oriented so that
``c . tau > 0`` (with ``c = w o tau_prev`` this keeps the orientation of the branch),
and the sign of ``det M``.

Evaluation
----------
The corrector evaluates ``G``, ``G_z``, ``G_p`` through the fastest interface the
problem offers: a fused evaluator of the bordered residual and matrix
(``problem.bordered_evaluator()``: one compiled CasADi call per Newton iteration, dense
problems), a linearizer specialised to the free parameter (``problem.linearizer()``,
e.g. sparse problems), or ``problem.linearize`` / the protocol methods. All give the
same values; the first two only remove Python overhead, which dominates the steps of
small systems.

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

import abc
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any, NamedTuple

import numpy as np
import scipy.linalg as la
import scipy.linalg.blas as sla_blas
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..typing import FloatArray
from ..settings import ContinuationSettings, NewtonSettings

log = logging.getLogger(__name__)


# ---------------------------------------------------------------------------- norms
def theta_weights(n_unknowns: int, theta: float) -> FloatArray:
    """Weights ``w`` of the ``theta`` inner product, shape ``(N + 1,)``."""
    w = np.full(n_unknowns + 1, (1.0 - theta) / max(n_unknowns, 1))
    w[-1] = theta
    return w


def theta_norm(v: FloatArray, w: FloatArray) -> float:
    """``sqrt(sum(w * v**2))``."""
    return math.sqrt(float((w * v).dot(v)))


_idamax = sla_blas.idamax


def _inf_norm(v: FloatArray) -> float:
    """``max |v|`` (0 for an empty vector; BLAS ``idamax``, no temporary array).

    Not reliable for vectors containing NaN: check finiteness separately.
    """
    return abs(float(v[_idamax(v)])) if v.size else 0.0


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
    """The corrector's convergence test (see :func:`correct`), shared by its dense and
    sparse iterations. ``rn``: ``max |r|`` now, ``rn_prev`` before the last step;
    ``dn = max |du|`` of the correction at the current point and ``dn_ok`` its
    componentwise test; ``step``/``step_ok`` the same of the last step taken; ``hi`` the
    upper bound of :func:`_step_bounds`; ``ratio()`` gives :func:`_step_ratio` of the
    correction and ``backward_error()`` :func:`_backward_error` at the current point,
    both evaluated only when the clause needing them is reached."""
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


def _finite(v: FloatArray) -> bool:
    """True when every entry of ``v`` is finite (one dot product; entries beyond
    ``1e154`` in magnitude also count as non-finite, which only ever happens for
    diverging iterates)."""
    s = float(v.dot(v))
    return s < math.inf  # False for inf and NaN


# ---------------------------------------------------------------------------- linear algebra
# LAPACK getrf/getrs directly: same factorisation as scipy.linalg.lu_factor, without its
# per-call overhead (a few microseconds, which matters for small systems) and warnings.
_getrf, _getrs, _gesv = la.get_lapack_funcs(("getrf", "getrs", "gesv"), (np.zeros(1),))
_ARANGE: dict[int, Any] = {}


def _arange(n: int) -> Any:
    r = _ARANGE.get(n)
    if r is None:
        r = _ARANGE[n] = np.arange(n, dtype=np.int32)
    return r


_PARITY_CACHE: dict[bytes, int] = {}


_UNIT: dict[int, Any] = {}


def _last_unit(n: int) -> FloatArray:
    """The unit vector ``e_n`` of length ``n`` (cached, read-only)."""
    e = _UNIT.get(n)
    if e is None:
        e = np.zeros(n)
        e[-1] = 1.0
        e.setflags(write=False)
        _UNIT[n] = e
    return e


def _perm_parity(perm: Any) -> int:
    """Sign (+1/-1) of the permutation ``perm`` (array of images of 0..n-1).

    Cached: SuperLU's column ordering depends only on the sparsity pattern and the row
    pivoting rarely changes along a branch, so the same permutations recur.
    """
    perm = np.asarray(perm)
    key = perm.tobytes()
    sign = _PARITY_CACHE.get(key)
    if sign is None:
        sign = _perm_parity_uncached(perm)
        if len(_PARITY_CACHE) > 64:
            _PARITY_CACHE.clear()
        _PARITY_CACHE[key] = sign
    return sign


def _perm_parity_uncached(perm: Any) -> int:
    n = perm.size
    seen = np.zeros(n, dtype=bool)
    sign = 1
    for i in range(n):
        if seen[i]:
            continue
        j = i
        length = 0
        while not seen[j]:
            seen[j] = True
            j = perm[j]
            length += 1
        if length % 2 == 0:
            sign = -sign
    return sign


def csc_with_data(template: Any, data: FloatArray) -> Any:
    """A new sparse matrix with the structure of ``template`` (CSC/CSR) and ``data``.

    ``data`` must have the length and dtype of ``template.data``. The index arrays are
    shared with ``template`` (not copied; never modified by SciPy for a matrix in
    canonical form) and the format checks of SciPy's constructor, which dominate the
    cost of assembling small sparse matrices, are skipped: the structure was checked
    when ``template`` was built.
    """
    cls = template.__class__
    M = cls.__new__(cls)
    M.__dict__.update(template.__dict__)
    M.data = data
    return M


class _BorderPattern:
    """Positions of the entries of ``Gz``, ``Gp`` and ``c`` in the bordered CSC matrix
    (depends only on the sparsity pattern of ``Gz``; built once per pattern)."""

    __slots__ = ("indptr", "indices", "nnz", "pos", "border_pos", "template")

    def __init__(self, Gz: Any) -> None:
        n = Gz.shape[0]
        indptr, indices = Gz.indptr, Gz.indices
        self.indptr, self.indices = indptr, indices  # references keep the ids valid
        nnz = int(indptr[-1])
        self.nnz = nnz
        counts = np.diff(indptr)
        total = nnz + n + (n + 1)
        new_indices = np.empty(total, dtype=np.int32)
        self.pos = np.arange(nnz) + np.repeat(np.arange(n), counts)
        new_indices[self.pos] = indices[:nnz]
        self.border_pos = indptr[1:] + np.arange(n)
        new_indices[self.border_pos] = n
        new_indices[nnz + n :] = np.arange(n + 1)
        new_indptr = np.empty(n + 2, dtype=np.int32)
        new_indptr[: n + 1] = indptr + np.arange(n + 1)
        new_indptr[n + 1] = total
        # one checked construction; later matrices share its (canonical) structure
        self.template = sp.csc_matrix(
            (np.ones(total), new_indices, new_indptr), shape=(n + 1, n + 1)
        )
        # canonical (sorted, no duplicates) exactly when Gz is: flag computed once here
        self.template.has_canonical_format  # noqa: B018

    def assemble(self, data: FloatArray, Gp: FloatArray, c: FloatArray) -> sp.csc_matrix:
        n = self.indptr.size - 1
        new_data = np.empty(self.template.data.size, dtype=float)
        new_data[self.pos] = data[: self.nnz]
        new_data[self.border_pos] = c[:n]
        start = self.nnz + n
        new_data[start : start + n] = Gp
        new_data[-1] = c[n]
        return csc_with_data(self.template, new_data)


_PATTERNS: dict[tuple[int, int, int], _BorderPattern] = {}


def assemble_bordered_csc(Gz: Any, Gp: FloatArray, c: FloatArray) -> sp.csc_matrix:
    """CSC matrix ``[[Gz, Gp], [c^T]]`` built directly from the CSC arrays of ``Gz``.

    ``Gp`` is stored as a dense column and ``c`` as a dense row. The positions of the
    entries depend only on the sparsity pattern of ``Gz``, which is fixed along a
    branch: they are computed once per pattern (recognised by the identity of
    ``Gz``'s index arrays, as handed out by the problem's evaluator) and reused.
    """
    Gz = Gz if sp.isspmatrix_csc(Gz) or isinstance(Gz, sp.csc_array) else sp.csc_matrix(Gz)
    if not Gz.has_canonical_format:  # (SciPy may sort / sum it in place: no sharing)
        return _BorderPattern(Gz).assemble(Gz.data, Gp, c)
    key = (id(Gz.indptr), id(Gz.indices), Gz.shape[0])
    pat = _PATTERNS.get(key)
    if pat is None or pat.indptr is not Gz.indptr or pat.indices is not Gz.indices:
        if len(_PATTERNS) >= 16:
            _PATTERNS.clear()
        pat = _PATTERNS[key] = _BorderPattern(Gz)
    return pat.assemble(Gz.data, Gp, c)


class BorderedLU:
    """LU factorisation of ``M = [[Gz, Gp], [c^T]]`` with determinant sign.

    Parameters
    ----------
    Gz : ndarray (N, N) or SciPy sparse matrix
    Gp : ndarray, shape (N,)
    c : ndarray, shape (N + 1,)

    Raises
    ------
    numpy.linalg.LinAlgError
        If ``M`` is exactly singular or the factorisation fails.
    """

    __slots__ = ("sparse", "_lu", "_piv", "_sign", "_logdet", "n")

    def __init__(self, Gz: Any, Gp: FloatArray, c: FloatArray) -> None:
        n = Gz.shape[0]
        self.n = n + 1
        self._sign = 2.0  # not computed yet
        self._logdet = math.nan
        if isinstance(Gz, np.ndarray):
            self.sparse = False
            # Fortran order: LAPACK factorises it in place, no copy
            M = np.empty((n + 1, n + 1), order="F")
            M[:n, :n] = Gz
            M[:n, n] = Gp
            M[n, :] = c
            lu, piv, info = _getrf(M, overwrite_a=1)
            if info != 0:
                raise np.linalg.LinAlgError(f"singular bordered matrix (getrf info={info})")
            self._lu, self._piv = lu, piv
        else:
            self.sparse = True
            M = assemble_bordered_csc(Gz, Gp, c)
            try:
                self._lu = spla.splu(M)
            except RuntimeError as exc:
                raise np.linalg.LinAlgError(str(exc)) from exc
            self._piv = None

    @classmethod
    def from_dense_factors(cls, lu: Any, piv: Any) -> BorderedLU:
        """Wrap the output of LAPACK ``getrf`` on a dense bordered matrix (info = 0)."""
        self = cls.__new__(cls)
        self.n = lu.shape[0]
        self.sparse = False
        self._lu, self._piv = lu, piv
        self._sign = 2.0
        self._logdet = math.nan
        return self

    def _diag_parity(self) -> tuple[Any, int]:
        if self.sparse:
            d = self._lu.U.diagonal()
            parity = _perm_parity(self._lu.perm_r) * _perm_parity(self._lu.perm_c)
        else:
            d = self._lu.diagonal()
            parity = -1 if np.count_nonzero(self._piv != _arange(self.n)) % 2 else 1
        return d, parity

    @property
    def sign(self) -> float:
        """Sign of ``det M`` (+1, -1, or 0 if singular)."""
        if self._sign == 2.0:
            if not self.sparse and self.n <= 24:
                # small dense: the sign of the product of the pivots (IEEE products keep
                # the sign through overflow to inf and underflow to 0, and getrf info = 0
                # means no pivot is zero), times the parity of the row interchanges
                prod = math.prod(self._lu.diagonal().tolist())
                odd = int(np.count_nonzero(self._piv != _arange(self.n))) + (
                    math.copysign(1.0, prod) < 0
                )
                self._sign = -1.0 if odd % 2 else 1.0
                return self._sign
            d, parity = self._diag_parity()
            if self.sparse and not np.all(d):
                self._sign = 0.0
            else:  # the dense factorisation has no zero pivot (getrf info = 0)
                self._sign = -float(parity) if np.count_nonzero(d < 0) % 2 else float(parity)
        return self._sign

    @property
    def logabsdet(self) -> float:
        """``log |det M|``."""
        if math.isnan(self._logdet):
            d, _ = self._diag_parity()
            with np.errstate(divide="ignore"):
                self._logdet = float(np.log(np.abs(d)).sum())
        return self._logdet

    def solve(self, b: FloatArray, trans: bool = False) -> FloatArray:
        """Solve ``M x = b`` (``M^T x = b`` if ``trans``); LinAlgError if not finite."""
        if self.sparse:
            x = self._lu.solve(np.asarray(b, dtype=float), trans="T" if trans else "N")
        else:
            x, info = _getrs(self._lu, self._piv, b, trans=1 if trans else 0)
        if not _finite(x) and not np.all(np.isfinite(x)):
            raise np.linalg.LinAlgError("singular or ill-conditioned bordered matrix")
        return x


def _abs_bordered(Gz: Any, Gp: FloatArray, c: FloatArray) -> Any:
    """``|M|`` of the bordered matrix ``[[Gz, Gp], [c^T]]``: dense ndarray or CSC."""
    if sp.issparse(Gz):
        M = assemble_bordered_csc(Gz, Gp, c)
        M.data = np.abs(M.data)
        return M
    n = Gz.shape[0]
    A = np.empty((n + 1, n + 1))
    A[:n, :n] = np.abs(Gz)
    A[:n, n] = np.abs(Gp)
    A[n, :] = np.abs(c)
    return A


def bordered_column_max(pt: PointInfo) -> FloatArray:
    """Column maxima of ``|M|``, ``M = [[Gz, Gp], [border^T]]`` at ``pt``, shape (N + 1,)."""
    A = _abs_bordered(pt.Gz, pt.Gp, pt.border)
    m = A.max(axis=0)
    return np.asarray(m.toarray() if sp.issparse(m) else m, dtype=float).ravel()


def bordered_rcond(pt: PointInfo, col_max: FloatArray | None = None) -> float:
    r"""Reciprocal condition estimate of the column-scaled bordered matrix at ``pt``.

    With ``M = [[G_z, G_p], [c^T]]`` (``c = pt.border``) and ``D = diag(1 / col_max)``
    (default: the column maxima of ``|M|`` itself), returns
    ``1 / (||M D||_1 ||(M D)^{-1}||_1)``, about ``dist(M D, singular) / ||M D||``.
    Column scaling removes the effect of badly scaled states and parameter (a huge
    ``G_p``, say) and leaves the pivoting of the LU factorisation unchanged, so this is
    the condition that decides whether the computed determinant sign of ``M`` can be
    trusted; passing the same ``col_max`` for several points compares them in one
    scaling. ``||(M D)^{-1}||_1`` is estimated from the existing factorisation
    ``pt.lu`` by Hager's method with Higham's refinements (Hager 1984, SIAM J. Sci.
    Stat. Comput. 5:311-316; Higham 1988, ACM TOMS 14:381-396; LAPACK ``dlacn2``): a
    few solves with ``M`` and ``M^T``, no new factorisation.

    Returns 0 when ``pt.lu`` is None (an exactly singular point) or a solve fails.
    """
    lu = pt.lu
    if lu is None:
        return 0.0
    A = _abs_bordered(pt.Gz, pt.Gp, pt.border)
    if col_max is None:
        col_max = bordered_column_max(pt)
    cm = np.asarray(col_max, dtype=float)
    if not np.all(cm > 0):
        return 0.0
    d = 1.0 / cm
    norm_md = float((np.asarray(A.sum(axis=0), dtype=float).ravel() * d).max())
    n = d.size
    try:
        x = np.full(n, 1.0 / n)
        est = 0.0
        for k in range(5):
            y = lu.solve(x) / d  # (M D)^{-1} x = D^{-1} M^{-1} x
            new = float(np.abs(y).sum())
            if k > 0 and new <= est:
                break
            est = new
            z = lu.solve(np.where(y >= 0, 1.0, -1.0) / d, trans=True)  # (M D)^{-T} xi
            j = int(np.argmax(np.abs(z)))
            if k > 0 and abs(z[j]) <= float(z.dot(x)):
                break
            x = np.zeros(n)
            x[j] = 1.0
        alt = np.where(np.arange(n) % 2 == 0, 1.0, -1.0) * (1.0 + np.arange(n) / max(n - 1, 1))
        est = max(est, 2.0 * float(np.abs(lu.solve(alt) / d).sum()) / (3.0 * n))
    except np.linalg.LinAlgError:
        return 0.0
    if not (est > 0 and math.isfinite(est) and norm_md > 0):
        return 0.0
    return 1.0 / (norm_md * est)


# ---------------------------------------------------------------------------- evaluation
def linearize(problem: Any, z: FloatArray, p: float) -> tuple[FloatArray, Any, FloatArray]:
    """``(G, G_z, G_p)`` at ``(z, p)``: one call of ``problem.linearize`` if it has one."""
    lin = getattr(problem, "linearize", None)
    if lin is not None:
        G, Gz, Gp = lin(z, p)
    else:
        G, Gz, Gp = problem.residual(z, p), problem.jacobian(z, p), problem.dp(z, p)
    G = np.asarray(G, dtype=float).reshape(-1)
    Gp = np.asarray(Gp, dtype=float).reshape(-1)
    if not sp.issparse(Gz):
        Gz = np.asarray(Gz, dtype=float)
    return G, Gz, Gp


class PointInfo:
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

    __slots__ = (
        "z",
        "p",
        "tau",
        "G",
        "Gz",
        "Gp",
        "lu",
        "border",
        "t_raw",
        "ctau",
        "iters",
        "residual_norm",
        "cache",
        "_u",
        "_bp_sign",
        "_bp_logdet",
    )

    def __init__(
        self,
        z: FloatArray,
        p: float,
        tau: FloatArray,
        G: FloatArray,
        Gz: Any,
        Gp: FloatArray,
        lu: BorderedLU | None,
        border: FloatArray,
        t_raw: FloatArray,
        bp_sign: float | None = None,
        ctau: float = 1.0,
        iters: int = 0,
        residual_norm: float = 0.0,
        cache: dict[str, Any] | None = None,
        _u: FloatArray | None = None,
        _bp_logdet: float | None = None,
    ) -> None:
        self.z = z
        self.p = p
        self.tau = tau
        self.G = G
        self.Gz = Gz
        self.Gp = Gp
        self.lu = lu
        self.border = border
        self.t_raw = t_raw
        self.ctau = ctau
        self.iters = iters
        self.residual_norm = residual_norm
        self.cache = {} if cache is None else cache
        self._u = _u
        self._bp_sign = bp_sign
        self._bp_logdet = _bp_logdet

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

    @property
    def u(self) -> FloatArray:
        """``(z, p)``, shape ``(N + 1,)`` (computed once; do not modify)."""
        if self._u is None:
            self._u = np.concatenate((self.z, (self.p,)))
        return self._u


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
        corrector's step tolerance. This is AUTO's practice (Doedel et al., AUTO-07p
        manual, Sec. "pseudo-arclength continuation": the new direction vector comes
        from the Jacobian of the last Newton iteration); it perturbs the tangent by
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
        {"jac_finite": True} if jac_finite else None,
        u,
    )


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


@dataclass(eq=False, slots=True)
class CorrectorResult:
    """Outcome of :func:`correct`.

    ``lu`` is the factorisation of the bordered matrix at the last Newton iterate (the
    returned point, or the iterate one step before it, within the step tolerance), or
    None; ``u_full`` is ``(z, p)`` when known; ``t_raw`` is the solution of
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
    u_full: FloatArray | None = None
    t_raw: FloatArray | None = None
    g_norm: float | None = None
    jac_finite: bool = False

    @property
    def u(self) -> FloatArray:
        """``(z, p)``, shape ``(N + 1,)``."""
        if self.u_full is None:
            self.u_full = np.concatenate((self.z, (self.p,)))
        return self.u_full


def _linearizer(problem: Any) -> Callable[[FloatArray, float], tuple[FloatArray, Any, FloatArray]]:
    """The problem's fast evaluator (``problem.linearizer()``) or :func:`linearize`."""
    fn = getattr(problem, "__dict__", {}).get("_linearizer")  # cached by the problem
    if fn is None:
        get = getattr(problem, "linearizer", None)
        fn = get() if get is not None else None
    if fn is None:
        return partial(linearize, problem)
    return fn  # type: ignore[no-any-return]


def _bordered_evaluator(problem: Any) -> Any:
    """The problem's fused bordered evaluator (``problem.bordered_evaluator()``) or None."""
    ev = getattr(problem, "__dict__", {}).get("_bordered", False)
    if ev is False:
        get = getattr(problem, "bordered_evaluator", None)
        ev = get() if get is not None else None
    return ev


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
    gn = mm = math.nan  # max |f| and sum M_ij^2 of the last evaluation, when known
    rt = getattr(ev, "rt", None)
    own_rt = rt is None  # an evaluator without the two-column buffer: copy r into one
    if own_rt:
        rt = np.zeros((n + 1, 2), order="F")
        rt[n, 1] = 1.0
    u[:] = u_pred
    ev.c[:] = c  # (ev.set_border, inlined: the hot path of small problems)
    ev.h[0] = float(c.dot(u_ref)) + sigma
    tol, step_tol, max_iter = newton.tol, newton.step_tol, newton.max_iter
    run()
    if nv is not None:
        rn, rr, un, gn, mm = nv.tolist()
        finite = rr < math.inf
    else:
        finite = float(r.dot(r)) < math.inf
        rn, un = _inf_norm(r), _inf_norm(u)
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
                     lambda du=du: _step_ratio(du, u_pred, u_ref, a),
                     lambda u=u: _backward_error(M, r, u)):  # fmt: skip
            lin = ev.lin()
            lu: BorderedLU | None = BorderedLU.from_dense_factors(f_lu, f_piv)
            t_raw: FloatArray | None = x[:, 1]
            if dn_ok:
                u -= du
                if exact:
                    run()
                    lin = ev.lin()
                    if nv is not None:
                        rn, rr, un, gn, mm = nv.tolist()
                    else:
                        rr, rn = float(r.dot(r)), _inf_norm(r)
                    rn = rn if rr < math.inf else math.inf
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
        if it >= max_iter:
            return CorrectorResult(False, u[:n].copy(), float(u[n]), ev.lin(), it, rn,
                                   "max_iter reached")  # fmt: skip
        if it >= 2 and rn > 1e4 * max(rn0, tol):
            return CorrectorResult(False, u[:n].copy(), float(u[n]), ev.lin(), it, rn,
                                   "diverging")  # fmt: skip
        u -= du
        it += 1
        step_prev, step, step_ok = step, dn, dn_ok
        if (
            max_contraction is not None
            and it >= 2
            and step > max_contraction * step_prev
            and not step_ok
            and rn > tol
        ):
            msg = f"corrector contracts too slowly (rate {step / step_prev:.2g} at step {it})"
            return CorrectorResult(False, u[:n].copy(), float(u[n]), None, it, rn, msg)
        rn_prev = rn
        run()
        if nv is not None:
            rn, rr, un, gn, mm = nv.tolist()
            finite = rr < math.inf
        else:
            finite = float(r.dot(r)) < math.inf
            rn = _inf_norm(r)


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
    points use ``exact=True``). Stops early (not converged) when the residual becomes
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
            f_lu, f_piv, info = _getrf(M, overwrite_a=1)
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
                     lambda du=du: _step_ratio(du, u_pred, u_ref, a),
                     lambda J=lin[1], Gp=lin[2], r=r, u=u: _backward_error(J, r, u, Gp, c),
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
                    try:
                        lu = BorderedLU(lin[1], lin[2], c)
                    except np.linalg.LinAlgError:
                        lu = None  # type: ignore[assignment]
            return CorrectorResult(True, u[:n].copy(), float(u[n]), lin, it, rn, "", lu, u)
        if it >= max_iter:
            return fail("max_iter reached", lin)
        if it >= 2 and rn > 1e4 * max(rn0, tol):
            return fail("diverging", lin)
        u -= du
        it += 1
        step_prev, step, step_ok = step, dn, dn_ok
        if (
            max_contraction is not None
            and it >= 2
            and step > max_contraction * step_prev
            and not step_ok
            and rn > tol
        ):
            return fail(
                f"corrector contracts too slowly (rate {step / step_prev:.2g} at step {it})"
            )
        rn_prev = rn
        lin = lin_fn(u[:n], float(u[n]))
        r[:n] = lin[0]
        r[n] = float(c.dot(u)) - h
        finite = _finite(r)
        rn = _inf_norm(r)


# ---------------------------------------------------------------------------- algorithm API
@dataclass(eq=False, slots=True)
class StepState:
    """Mutable iteration state passed between the driver and an algorithm.

    Attributes
    ----------
    point : PointInfo
        The last accepted point.
    ds : float
        Current step length (``> 0``; the direction is carried by ``point.tau``).
    w : ndarray, shape (N + 1,)
        ``theta`` weights.
    direction : float
        ``+1`` or ``-1``: the sign of ``dp/ds`` requested at the start.
    n_steps : int
        Accepted steps so far.
    prev_d : ndarray, shape (N + 1,), or None
        ``u - (u_0 + prev_h * prev_tau)`` of ``point``'s ``u``, with ``u_0`` the accepted
        point before it: how far the last step's corrector moved ``point`` from the
        tangent prediction (for predictors that extrapolate the branch; None at the start
        or when unknown).
    prev_tau : ndarray, shape (N + 1,), or None
        Tangent at ``u_0``.
    prev_h : float
        Pseudo-arclength from ``u_0`` to ``point``.
    retries : int
        Rejected attempts from ``point`` so far (set by the algorithm).
    """

    point: PointInfo
    ds: float
    w: FloatArray
    direction: float = 1.0
    n_steps: int = 0
    prev_d: FloatArray | None = None
    prev_tau: FloatArray | None = None
    prev_h: float = 0.0
    retries: int = 0


class StepOutcome(NamedTuple):
    """Result of one attempted step (immutable; a named tuple, cheap to create on the
    hot path of small problems).

    Attributes
    ----------
    converged : bool
        The step was accepted.
    newton_iters : int
        Corrector iterations.
    residual_norm : float
        Final ``max |G|``.
    sigma : float
        Pseudo-arclength step achieved, ``<tau_prev, u_new - u_prev>_theta``.
    message : str
        Why a step was rejected.
    """

    converged: bool
    newton_iters: int
    residual_norm: float
    sigma: float = 0.0
    message: str = ""


def adapt_ds(
    ds: float, outcome: StepOutcome, settings: ContinuationSettings, *, grow_iters: int = 3
) -> float:
    """Next step length: ``grow`` after an easy step (``<= grow_iters`` iterations),
    ``shrink`` after a failure, capped at ``ds_max`` (never below zero)."""
    if outcome.converged:
        if outcome.newton_iters <= grow_iters:
            return min(ds * settings.grow, settings.ds_max)
        return min(ds, settings.ds_max)
    return ds * settings.shrink


class ContinuationAlgorithm(abc.ABC):
    """A predictor-corrector scheme: ``init`` once, then ``step`` repeatedly."""

    def init(
        self, problem: Any, z0: FloatArray, p0: float, settings: ContinuationSettings
    ) -> StepState:
        """State at the (already corrected) start point ``(z0, p0)``.

        The tangent there is oriented so that ``sign(dp/ds) = sign(settings.ds)``;
        algorithms that need more start-up state override this.
        """
        w = theta_weights(z0.size, settings.theta)
        direction = 1.0 if settings.ds > 0 else -1.0
        pt = initial_point(problem, np.asarray(z0, float), float(p0), w, direction)
        return StepState(point=pt, ds=abs(settings.ds), w=w, direction=direction)

    @abc.abstractmethod
    def step(
        self, problem: Any, state: StepState, settings: ContinuationSettings
    ) -> tuple[StepState, StepOutcome]:
        """Attempt one step of length ``state.ds``; on success return the new state."""

    grow_iters: int = 3


__all__ = [
    "BorderedLU",
    "ContinuationAlgorithm",
    "CorrectorResult",
    "PointInfo",
    "StepOutcome",
    "StepState",
    "adapt_ds",
    "assemble_bordered_csc",
    "bordered_column_max",
    "bordered_rcond",
    "correct",
    "initial_point",
    "linearize",
    "make_point",
    "theta_norm",
    "theta_weights",
]
