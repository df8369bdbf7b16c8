r"""Dense and sparse linear algebra of the bordered systems.

Every linear solve of the continuation engine is with a bordered matrix

.. math::

    M = \begin{pmatrix} G_z & G_p \\ c^T & \end{pmatrix} \in R^{(N+1)\times(N+1)},

factorised once (:class:`BorderedLU`: dense LAPACK LU, or SuperLU ``splu`` on an
assembled CSC matrix when ``G_z`` is sparse, :func:`assemble_bordered_csc`). The same
factorisation gives the sign of ``det M`` (pivots times the parity of the
permutations, :func:`_perm_parity`) and ``log |det M|``; :func:`bordered_rcond`
estimates the reciprocal condition of the column-scaled ``M`` from it.

The LAPACK routines ``getrf``/``getrs``/``gesv`` are called directly (:data:`getrf`,
...): the same factorisation as :func:`scipy.linalg.lu_factor`, without its per-call
overhead (a few microseconds, which matters for small systems) and warnings.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.linalg as la
import scipy.linalg.blas as sla_blas
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .typing import FloatArray

_idamax = sla_blas.idamax


def _inf_norm(v: FloatArray) -> float:
    """``max |v|`` (0 for an empty vector; BLAS ``idamax``, no temporary array).

    Not reliable for vectors containing NaN: check finiteness separately.
    """
    return abs(float(v[_idamax(v)])) if v.size else 0.0


def _finite(v: FloatArray) -> bool:
    """True when every entry of ``v`` is finite (one dot product).

    Entries beyond ``1e154`` in magnitude also count as non-finite, which only ever happens
    for diverging iterates.
    """
    s = float(v.dot(v))
    return s < math.inf  # False for inf and NaN


# ---------------------------------------------------------------------------- LAPACK
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
    """Positions of the entries of ``Gz``, ``Gp`` and ``c`` in the bordered CSC matrix.

    They depend only on the sparsity pattern of ``Gz``: built once per pattern.
    """

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
            # a problem may attach a structured factoriser to its Jacobian (e.g. the
            # condensation of collocation stages, continuation.bvp.condense); None: SuperLU
            factor = getattr(Gz, "condensed_lu", None)
            self._lu = factor(M) if factor is not None else None
            if self._lu is None:
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
        if self.sparse and hasattr(self._lu, "diag_parity"):
            return self._lu.diag_parity()
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


def bordered_column_max(pt: Any) -> FloatArray:
    """Column maxima of ``|M|``, ``M = [[Gz, Gp], [border^T]]`` at ``pt``, shape (N + 1,)."""
    A = _abs_bordered(pt.Gz, pt.Gp, pt.border)
    m = A.max(axis=0)
    return np.asarray(m.toarray() if sp.issparse(m) else m, dtype=float).ravel()


def bordered_rcond(pt: Any, col_max: FloatArray | None = None) -> float:
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


#: Public names of the LAPACK wrappers and helpers shared by the corrector and the
#: point/tangent code (the underscore names stay for in-module use).
getrf, getrs, gesv = _getrf, _getrs, _gesv
inf_norm, all_finite, last_unit = _inf_norm, _finite, _last_unit

__all__ = [
    "BorderedLU",
    "all_finite",
    "assemble_bordered_csc",
    "bordered_column_max",
    "bordered_rcond",
    "csc_with_data",
    "gesv",
    "getrf",
    "getrs",
    "inf_norm",
    "last_unit",
]
