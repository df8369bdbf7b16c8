r"""Linear stability of equilibria: eigenvalues, saddle index, eigenvectors.

An equilibrium ``x*`` of ``x' = f(x, p)`` is linearly stable when every eigenvalue of
``J = df/dx(x*, p)`` has negative real part. The *saddle index* (``n_unstable``) is the
number of eigenvalues with real part ``> eig_tol``.

Dense problems get all ``n`` eigenvalues from LAPACK (``numpy.linalg.eigvals``). For a
large sparse Jacobian (``n > dense_max``) only the ``n_eigs`` eigenvalues nearest the
shift ``sigma`` are computed with ARPACK in shift-invert mode
(``scipy.sparse.linalg.eigs(J, k, sigma=sigma)``); the other entries are NaN. This is
how AUTO and BifurcationKit treat large problems: the eigenvalues that cross the
imaginary axis first are the ones near the origin.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .problem import jacobian_is_stability
from .typing import ComplexArray

log = logging.getLogger(__name__)


def sort_eigenvalues(vals: Any) -> ComplexArray:
    """Sort by decreasing real part, then decreasing imaginary part; NaN last.

    Parameters
    ----------
    vals : array_like, shape (k,)

    Returns
    -------
    ndarray, shape (k,) complex
    """
    v = np.asarray(vals, dtype=complex).reshape(-1)
    # NumPy sorts complex numbers lexicographically (real, then imaginary part) with NaN
    # entries last; sorting -v ascending is sorting v descending
    return -np.sort(-v)


def _sorted_pairs(vals: ComplexArray, vecs: Any) -> tuple[ComplexArray, Any]:
    re, im = vals.real, vals.imag
    order = np.lexsort((-im, -re))
    return vals[order], (vecs[:, order] if vecs is not None else None)


def eigenvalues(
    J: Any,
    *,
    n_eigs: int | None = None,
    sigma: float = 0.0,
    dense_max: int = 100,
    v0: Any = None,
) -> ComplexArray:
    """Eigenvalues of a dense or sparse square matrix, sorted by decreasing real part.

    Parameters
    ----------
    J : ndarray or SciPy sparse matrix, shape (n, n)
    n_eigs : int, optional
        For sparse ``J`` with ``n > dense_max``: number of eigenvalues nearest
        ``sigma`` to compute by shift-invert ARPACK (default 6).
    sigma : float
        Shift for the sparse solve.
    dense_max : int
        Sparse matrices up to this size are converted and solved densely.
    v0 : ndarray, shape (n,), optional
        ARPACK start vector (default: a fixed vector, for reproducibility).

    Returns
    -------
    ndarray, shape (n,) complex
        Sorted eigenvalues; NaN entries (at the end) for those not computed.
    """
    n = J.shape[0]
    if n == 0:
        return np.zeros(0, dtype=complex)
    if sp.issparse(J):
        k = int(n_eigs or 6)
        if n > dense_max and k < n - 2:
            vals = _sparse_eigs(J, k, sigma, v0)
            if vals is not None:
                out = np.full(n, np.nan + 0j)
                out[: vals.size] = sort_eigenvalues(vals)
                return out
        J = J.toarray()
    return sort_eigenvalues(_dense_eigvals(np.asarray(J, dtype=float)))


_GEEV = la.get_lapack_funcs("geev", (np.zeros(1),))


def _dense_eigvals(J: Any) -> ComplexArray:
    """All eigenvalues of a dense real matrix (LAPACK ``dgeev`` called directly).

    This avoids the per-call overhead of ``numpy.linalg.eigvals`` on small matrices.
    """
    flat = J.ravel(order="K")
    if not float(flat.dot(flat)) < np.inf and not np.all(np.isfinite(J)):
        raise np.linalg.LinAlgError("Jacobian contains NaN or inf")
    wr, wi, _, _, info = _GEEV(J, compute_vl=0, compute_vr=0)
    if info != 0:
        return np.asarray(np.linalg.eigvals(J), dtype=complex)
    out = np.empty(wr.size, dtype=complex)
    out.real = wr
    out.imag = wi
    return out


def dense_stability(
    J: Any, eig_tol: float = 1e-10, imag_tol: float = 1e-8, *, check_finite: bool = True
) -> tuple[ComplexArray, tuple[int, int]]:
    """Sorted eigenvalues of a dense real matrix and their unstable counts, in one pass.

    The same values as ``sort_eigenvalues(numpy.linalg.eigvals(J))`` and
    :func:`count_unstable` of them, from one LAPACK ``dgeev`` call: the counts are taken
    from its real and imaginary parts directly (no complex intermediate), which is what
    a continuation step needs at every row of a small dense system.

    Parameters
    ----------
    J : ndarray, shape (n, n)
    eig_tol, imag_tol : float
        As in :func:`count_unstable`.
    check_finite : bool
        Check that ``J`` is finite first (skip only when the caller knows it is: LAPACK
        on NaN or inf input is undefined).

    Returns
    -------
    eigs : ndarray, shape (n,) complex
        Sorted by decreasing real part, then decreasing imaginary part.
    counts : tuple of int
        ``(n_real, n_complex_pairs)`` unstable, as :func:`count_unstable`.

    Raises
    ------
    numpy.linalg.LinAlgError
        If ``J`` contains NaN or inf.
    """
    if check_finite:
        flat = J.ravel(order="K")
        if not float(flat.dot(flat)) < math.inf and not np.all(np.isfinite(J)):
            raise np.linalg.LinAlgError("Jacobian contains NaN or inf")
    wr, wi, _, _, info = _GEEV(J, compute_vl=0, compute_vr=0)
    if info != 0:
        ev = sort_eigenvalues(np.linalg.eigvals(J))
        return ev, count_unstable(ev, eig_tol, imag_tol)
    n_real = n_pairs = 0
    if wr.size <= 32:  # plain Python on a few values (dgeev's output is finite here)
        wr_l, wi_l = wr.tolist(), wi.tolist()
        if max(wr_l, default=0.0) > eig_tol:
            for re, im in zip(wr_l, wi_l, strict=True):
                if re > eig_tol:
                    if abs(im) > imag_tol * max(1.0, math.hypot(re, im)):
                        n_pairs += im > 0
                    else:
                        n_real += 1
        if not any(wi_l):  # all real: a float sort gives the same order
            return np.array(sorted(wr_l, reverse=True), dtype=complex), (n_real, n_pairs)
        counts = (n_real, n_pairs)
    out = np.empty(wr.size, dtype=complex)
    # sorted descending = negated, sorted ascending (lexicographic), negated back
    np.negative(wr, out=out.real)
    np.negative(wi, out=out.imag)
    out.sort()
    np.negative(out, out=out)
    if wr.size > 32:
        counts = count_unstable(out, eig_tol, imag_tol)
    return out, counts


def _sparse_eigs(J: Any, k: int, sigma: float, v0: Any) -> ComplexArray | None:
    out = sparse_eigs_near(J, k, sigma, v0=v0, tol=0.0)
    return None if out is None else out[0]


def sparse_eigs_near(
    J: Any,
    k: int,
    sigma: float = 0.0,
    *,
    v0: Any = None,
    tol: float = 0.0,
    opinv: Any = None,
    vectors: bool = False,
) -> tuple[ComplexArray, Any] | None:
    r"""The ``k`` eigenvalues of a sparse real matrix nearest a real shift ``sigma``.

    ARPACK's implicitly restarted Arnoldi method in shift-invert mode (Lehoucq,
    Sorensen & Yang 1998, *ARPACK Users' Guide*, SIAM, Sec. 3.2): the largest
    eigenvalues ``nu`` of ``(J - sigma I)^{-1}`` give ``lambda = sigma + 1 / nu``.

    Parameters
    ----------
    J : SciPy sparse matrix, shape (n, n)
    k : int
        Number of eigenvalues, ``k < n - 1``.
    sigma : float
        Real shift.
    v0 : ndarray, shape (n,), optional
        Start vector of the Arnoldi iteration (default: a fixed vector). A combination
        of the wanted eigenvectors (e.g. those of a neighbouring point of a branch)
        cuts the number of iterations several-fold.
    tol : float
        ARPACK's relative accuracy of the Ritz values of the shift-inverted operator
        (0: machine precision).
    opinv : LinearOperator or callable, optional
        ``b -> (J - sigma I)^{-1} b`` from an existing factorisation; default:
        SciPy factorises ``J - sigma I`` with SuperLU.
    vectors : bool
        Also return the eigenvectors, shape ``(n, k')``.

    Returns
    -------
    (values, vectors) or None
        ``values`` shape ``(k',)`` complex, ``k' >= k`` when a complex pair cut at the
        ``k`` boundary is completed by its conjugate (its vector is then conjugated
        too); ``vectors`` is None unless requested. None if ARPACK fails at ``sigma``
        and at ``sigma + 1e-6 (1 + |sigma|)``.
    """
    n = J.shape[0]
    if v0 is None:
        v0 = np.cos(np.arange(n) + 1.0)
    A = J if sp.isspmatrix_csc(J) or isinstance(J, sp.csc_array) else sp.csc_matrix(J)
    vecs = None
    for attempt, shift in enumerate((sigma, sigma + 1e-6 * (1.0 + abs(sigma)))):
        op = None
        if opinv is not None and attempt == 0:
            op = opinv
            if not isinstance(op, spla.LinearOperator):
                op = spla.LinearOperator((n, n), matvec=opinv, dtype=float)
        try:
            out = spla.eigs(
                A,
                k=k,
                sigma=shift,
                which="LM",
                v0=v0,
                tol=tol,
                OPinv=op,
                return_eigenvectors=vectors,
            )
            break
        except (RuntimeError, spla.ArpackError, spla.ArpackNoConvergence) as exc:
            log.debug("sparse eigs failed at shift %g: %s", shift, exc)
    else:
        log.info("ARPACK failed; falling back to dense eigenvalues (n=%d)", n)
        return None
    if vectors:
        vals, vecs = out
    else:
        vals = out
    vals = np.asarray(vals, dtype=complex)
    # A real matrix has conjugate pairs: complete a pair cut at the k boundary.
    tol_pair = 1e-8 * max(1.0, float(np.max(np.abs(vals))))
    missing = [
        i
        for i, v in enumerate(vals)
        if abs(v.imag) > tol_pair and np.min(np.abs(vals - np.conj(v))) > tol_pair * 10
    ]
    if missing and vals.size + len(missing) <= n:
        vals = np.concatenate([vals, np.conj(vals[missing])])
        if vecs is not None:
            vecs = np.concatenate([vecs, np.conj(vecs[:, missing])], axis=1)
    return vals, vecs


def count_unstable(eigs: Any, eig_tol: float = 1e-10, imag_tol: float = 1e-8) -> tuple[int, int]:
    """Count unstable eigenvalues: ``(n_real, n_complex_pairs)``.

    An eigenvalue is unstable when ``Re > eig_tol``; it is complex when
    ``|Im| > imag_tol * max(1, |lambda|)``. NaN entries are ignored. The saddle index is
    ``n_real + 2 * n_complex_pairs`` (pairs are counted by their member with
    ``Im > 0``).
    """
    v = np.asarray(eigs, dtype=complex).reshape(-1)
    if v.size <= 32:  # plain Python is faster than NumPy calls on a few values
        n_real = n_pairs = 0
        for z in v.tolist():
            if z.real > eig_tol:  # False for NaN
                if abs(z.imag) > imag_tol * max(1.0, abs(z)):
                    n_pairs += z.imag > 0
                else:
                    n_real += 1
        return n_real, n_pairs
    if v.real.max() <= eig_tol:  # (a NaN maximum takes the long way)
        return 0, 0
    unstable = v.real > eig_tol  # False for NaN
    v = v[unstable]
    if v.size == 0:
        return 0, 0
    if not v.imag.any():  # all real
        return int(v.size), 0
    cplx = np.abs(v.imag) > imag_tol * np.maximum(1.0, np.abs(v))
    n_pairs = int(np.count_nonzero(cplx & (v.imag > 0)))
    return int(v.size - np.count_nonzero(cplx)), n_pairs


def n_unstable(eigs: Any, eig_tol: float = 1e-10) -> int:
    """Saddle index: number of eigenvalues with real part ``> eig_tol`` (NaN ignored)."""
    v = np.asarray(eigs, dtype=complex).reshape(-1)
    return int(np.count_nonzero(v.real[~np.isnan(v)] > eig_tol))


@dataclass(frozen=True, eq=False)
class EigenResult:
    """Eigen-decomposition at one point.

    Attributes
    ----------
    values : ndarray, shape (n,) complex
        Sorted by decreasing real part.
    vectors : ndarray, shape (n, n) complex or None
        Column ``k`` is the unit eigenvector of ``values[k]``.
    n_unstable : int
        Number of values with ``Re > eig_tol``.
    """

    values: ComplexArray
    vectors: Any
    n_unstable: int

    @property
    def stable(self) -> bool:
        """True when no eigenvalue has positive real part."""
        return self.n_unstable == 0


def _jacobian_of(obj: Any, x: Any, p: Any) -> Any:
    if hasattr(obj, "state_names") and hasattr(obj, "param_names") and hasattr(obj, "f"):
        # a DynamicalSystem: p is the full parameter vector / Params / mapping
        xv = obj.check_state(x, "x") if hasattr(obj, "check_state") else np.asarray(x, float)
        pv = obj.check_params(p, "p") if hasattr(obj, "check_params") else np.asarray(p, float)
        return obj.jacobian(xv, pv)
    if hasattr(obj, "residual") and hasattr(obj, "jacobian"):
        xv = np.asarray(x, dtype=float)
        if hasattr(obj, "system") and jacobian_is_stability(obj):
            return obj.system.jacobian(xv, obj.param_vector(float(p)))
        if not jacobian_is_stability(obj):
            raise ValueError(
                "`problem_or_system`: this problem's stability is not the spectrum of its "
                "Jacobian; call its `stability` method instead"
            )
        J = obj.jacobian(xv, float(p))
        return J.toarray() if sp.issparse(J) else J
    raise ValueError(
        f"`problem_or_system` must be a System or a ContinuationProblem, got {type(obj).__name__}"
    )


def eigen(
    problem_or_system: Any,
    x: Any,
    p: Any,
    vectors: bool = True,
    *,
    eig_tol: float = 1e-10,
) -> EigenResult:
    """All eigenvalues (and unit eigenvectors) of the Jacobian at ``(x, p)``.

    Parameters
    ----------
    problem_or_system : System or EquilibriumProblem
        For a system, ``p`` is the full parameter vector (array, Params or mapping);
        for an equilibrium problem, ``p`` is the value of its free parameter.
    x : ndarray, shape (n,)
    p : see above
    vectors : bool
        Also return eigenvectors (dense ``numpy.linalg.eig``).
    eig_tol : float
        Threshold for counting unstable eigenvalues.

    Returns
    -------
    EigenResult
    """
    J = np.asarray(_jacobian_of(problem_or_system, x, p), dtype=float)
    if vectors:
        vals, vecs = np.linalg.eig(J)
        vals, vecs = _sorted_pairs(np.asarray(vals, complex), np.asarray(vecs, complex))
    else:
        vals, vecs = sort_eigenvalues(np.linalg.eigvals(J)), None
    return EigenResult(values=vals, vectors=vecs, n_unstable=n_unstable(vals, eig_tol))


__all__ = [
    "EigenResult",
    "count_unstable",
    "dense_stability",
    "eigen",
    "eigenvalues",
    "n_unstable",
    "sort_eigenvalues",
    "sparse_eigs_near",
]
