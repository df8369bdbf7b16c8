r"""Stability eigenvalues of the rows of a branch.

:func:`eig_function` gives, for one run, the function that computes (once, cached on
the point) the eigenvalues deciding stability at a converged point: from the Jacobian
itself when the problem says they are its eigenvalues
(:func:`~continuation.problem.jacobian_is_stability`): all of them by LAPACK when it is
dense or small, else the ``n_eigs`` nearest ``eig_sigma`` by shift-invert Arnoldi
(:class:`SparseEigs`), else from ``problem.stability``.

On the sparse path an unstable eigenvalue far from the shift is not seen, so
:func:`run_checked` checks the saddle index at a few rows against the rightmost
eigenvalues (:func:`missed_unstable`) and, if some were missed, continues the branch
again with the rightmost eigenvalues at every point (the *second pass*).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse.linalg as spla
from scipy.sparse import csc_matrix

from .algorithms.point import PointInfo
from .branch import Branch
from .problem import has_linearize, jacobian_is_stability
from .settings import ContinuationSettings
from .stability import (
    count_unstable,
    dense_stability,
    eigenvalues,
    sort_eigenvalues,
    sparse_eigs_near,
)
from .status import Status
from .typing import ComplexArray, FloatArray

log = logging.getLogger(__name__)


def eig_function(
    problem: Any, settings: ContinuationSettings, rightmost: bool = False
) -> Callable[[PointInfo], Any]:
    """Eigenvalues at a point (cached on it).

    ``rightmost``: on the sparse path, the ``n_eigs`` of largest real part as well as those
    nearest the shift.
    """
    det = settings.detect
    if jacobian_is_stability(problem):
        eig_tol, imag_tol = det.eig_tol, det.imag_tol

        def from_jacobian(pt: PointInfo) -> ComplexArray:
            cache = pt.cache
            ev = cache.get("eig")
            if ev is None:
                if isinstance(pt.Gz, np.ndarray):  # dense: LAPACK directly, counts too
                    ev, cache["counts"] = dense_stability(
                        pt.Gz, eig_tol, imag_tol, check_finite="jac_finite" not in cache
                    )
                elif shift_invert is not None:
                    ev = shift_invert(pt)
                else:
                    ev = eigenvalues(
                        pt.Gz,
                        n_eigs=det.n_eigs,
                        sigma=det.eig_sigma,
                        dense_max=det.dense_eigs_max,
                    )
                pt.cache["eig"] = ev
            return ev

        n = int(problem.n_unknowns)
        k = int(det.n_eigs)
        shift_invert = (
            SparseEigs(n, k, det.eig_sigma, rightmost)
            if n > det.dense_eigs_max and k < n - 2
            else None
        )
        return from_jacobian

    def from_problem(pt: PointInfo) -> ComplexArray | None:
        if "eig" not in pt.cache:
            ev = problem.stability(pt.z, pt.p)
            pt.cache["eig"] = None if ev is None else sort_eigenvalues(ev)
        return pt.cache["eig"]

    return from_problem


#: ARPACK relative tolerance of the shift-inverted Ritz values along a branch (the
#: eigenvalues near the shift come out with about this relative accuracy, well below the
#: ``eig_tol`` used to count unstable ones).
SPARSE_EIG_TOL = 1e-12


class SparseEigs:
    """The ``k`` eigenvalues nearest ``sigma`` of sparse Jacobians along one branch.

    Two savings over a plain :func:`~continuation.stability.eigenvalues` call, neither
    of which changes what is computed beyond ARPACK's tolerance:

    * ARPACK stops at relative accuracy :data:`SPARSE_EIG_TOL` (1e-12) of the
      shift-inverted Ritz values instead of machine precision;
    * for ``sigma = 0`` the shift-invert operator ``G_z^{-1}`` reuses the corrector's
      factorisation of the bordered matrix ``M = [[G_z, G_p], [c^T]]`` at the point
      (the one the tangent came from): with ``t = M^{-1} e_{N+1} = (t_z, t_p)`` and
      ``M (x, y) = (b, 0)``, ``G_z (x - (y / t_p) t_z) = b`` (bordering lemma; Govaerts
      2000, *Numerical Methods for Bifurcations of Dynamical Equilibria*, Sec. 3.2).
      Used only while ``|t_p|`` is not tiny (away from folds, where ``G_z`` is
      singular); otherwise SciPy factorises ``G_z`` itself.

    The Arnoldi iteration starts from a fixed vector. Starting it from the previous
    point's eigenvectors saves a little with one BLAS thread, but extracting the
    eigenvectors (ARPACK ``dneupd``) runs level-3 BLAS that multi-threaded OpenBLAS
    parallelises, which made whole runs several times slower on a loaded machine: not
    done (measurements in ``benchmarks/README.md``, *Engine design measurements*).
    """

    __slots__ = ("n", "k", "sigma", "rightmost")

    def __init__(self, n: int, k: int, sigma: float, rightmost: bool = False) -> None:
        self.n, self.k, self.sigma = n, k, float(sigma)
        self.rightmost = bool(rightmost)

    def _opinv(self, pt: PointInfo) -> Callable[[FloatArray], FloatArray] | None:
        lu, t = pt.lu, pt.t_raw
        if self.sigma != 0.0 or lu is None or not getattr(lu, "sparse", False) or t is None:
            return None
        if t.size != self.n + 1:
            return None
        tp = float(t[-1])
        if not abs(tp) > 1e-8 * float(np.max(np.abs(t))):
            return None
        tz = t[:-1] / tp
        n = self.n
        rhs = np.zeros(n + 1)

        def apply(b: FloatArray) -> FloatArray:
            rhs[:n] = np.ravel(b)
            xy = lu.solve(rhs)
            return xy[:n] - xy[n] * tz

        return apply

    def __call__(self, pt: PointInfo) -> ComplexArray:
        """The ``k`` eigenvalues of ``pt.Gz`` nearest ``sigma``, NaN-padded to shape ``(n,)``."""
        out = sparse_eigs_near(
            pt.Gz,
            self.k,
            self.sigma,
            tol=SPARSE_EIG_TOL,
            opinv=self._opinv(pt),
            vectors=False,
        )
        if out is None:
            vals = eigenvalues(pt.Gz, n_eigs=self.k, sigma=self.sigma, dense_max=self.n)
            vals = vals[np.isfinite(vals)]
        else:
            vals = out[0]
        if self.rightmost:
            vals = with_rightmost(pt.Gz, vals, self.k)
        ev = np.full(self.n, np.nan + 0j)
        vals = sort_eigenvalues(vals)[: self.n]
        ev[: vals.size] = vals
        return ev


def with_rightmost(J: Any, near: ComplexArray, k: int) -> ComplexArray:
    """``near`` together with the ``k`` eigenvalues of ``J`` of largest real part.

    ARPACK ``which="LR"``, relative tolerance 1e-12; duplicates (within 1e-9 relative)
    dropped; ``near`` alone if ARPACK fails.
    """
    try:
        lr = spla.eigs(csc_matrix(J), k=k, which="LR", return_eigenvectors=False, tol=1e-12)
    except (spla.ArpackNoConvergence, ValueError, RuntimeError):
        return near
    out = list(near)
    for lam in lr:
        if all(abs(lam - mu) > 1e-9 * max(1.0, abs(lam)) for mu in out):
            out.append(lam)
    return np.asarray(out, dtype=complex)


def run_checked(
    problem: Any, settings: ContinuationSettings, run_all: Callable[[bool], Branch]
) -> Branch:
    """``run_all(False)``, again with the rightmost eigenvalues if some were missed.

    Again if the sparse stability check finds unstable ones the shift missed (see
    :func:`missed_unstable`).
    """
    br = run_all(False)
    missed = missed_unstable(problem, br, settings)
    if missed and br.status is not Status.INTERRUPTED:
        p_i, had, lr = missed[0]
        log.warning(
            "the %d eigenvalues nearest eig_sigma=%g missed unstable ones (at %s=%.8g: %d "
            "unstable among the rightmost, %d counted): continuing again with the rightmost "
            "eigenvalues at every point",
            settings.detect.n_eigs,
            settings.detect.eig_sigma,
            problem.free,
            p_i,
            lr,
            had,
        )
        br = run_all(True)
        note = (
            f" (Second pass: the {settings.detect.n_eigs} eigenvalues nearest "
            f"eig_sigma={settings.detect.eig_sigma:g} missed unstable ones, at "
            f"{br.free}={p_i:.8g} {lr} against {had}; this branch has the "
            f"{settings.detect.n_eigs} rightmost eigenvalues too at every point.)"
        )
        still = missed_unstable(problem, br, settings)
        if still:
            note += (
                " Stability still incomplete at some checked rows: raise "
                "DetectionSettings.n_eigs or dense_eigs_max."
            )
        br = dataclasses.replace(br, message=br.message + note)
    return br


#: Rows of a sparse branch whose saddle index is checked against the rightmost
#: eigenvalues (the first, the middle and the last; each check is one Arnoldi run
#: without shift-invert).
N_STABILITY_CHECKS = 3


def missed_unstable(
    problem: Any, br: Branch, settings: ContinuationSettings
) -> list[tuple[float, int, int]]:
    """Rows of a sparse branch whose saddle index misses unstable eigenvalues.

    On the sparse path only the ``n_eigs`` eigenvalues nearest ``eig_sigma`` are
    computed at every row (shift-invert Arnoldi), so an unstable eigenvalue far from
    the shift (a Hopf pair of large frequency behind many slow modes, say) is not seen
    and ``n_unstable`` would only be a lower bound. At :data:`N_STABILITY_CHECKS` rows
    the ``n_eigs`` eigenvalues of largest real part are computed as well (ARPACK
    ``which="LR"``, Lehoucq, Sorensen & Yang 1998). Returns ``[(p, counted,
    unstable among the rightmost), ...]`` for the rows where the rightmost ones hold
    more unstable eigenvalues than counted; empty for dense branches (all eigenvalues
    are computed there). :func:`run_checked` then continues the branch again with the
    rightmost eigenvalues at every point.
    """
    det = settings.detect
    n = br.x.shape[1] if br.x.ndim == 2 else 0
    k = int(det.n_eigs)
    if (
        not len(br)
        or not jacobian_is_stability(problem)
        or n <= det.dense_eigs_max
        or k >= n - 2
        or not has_linearize(problem)
    ):
        return []
    rows = sorted(set(np.linspace(0, len(br) - 1, N_STABILITY_CHECKS).round().astype(int)))
    missed = []
    for i in rows:
        try:
            _, Gz, _ = problem.linearize(br.x[i], float(br.p[i]))
            vals = spla.eigs(csc_matrix(Gz), k=k, which="LR", return_eigenvectors=False, tol=1e-6)
        except (spla.ArpackNoConvergence, ValueError, RuntimeError):
            continue
        n_lr = count_unstable(sort_eigenvalues(vals), det.eig_tol, det.imag_tol)
        unstable_lr = n_lr[0] + 2 * n_lr[1]
        if unstable_lr > max(int(br.n_unstable[i]), 0):
            missed.append((float(br.p[i]), int(br.n_unstable[i]), unstable_lr))
    return missed


__all__ = [
    "N_STABILITY_CHECKS",
    "SPARSE_EIG_TOL",
    "SparseEigs",
    "eig_function",
    "missed_unstable",
    "run_checked",
    "with_rightmost",
]
