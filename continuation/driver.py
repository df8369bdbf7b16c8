r"""The one entry point of one-parameter continuation: :func:`continue_branch`.

``continue_branch(problem, z0, p0, algorithm, settings)`` corrects the start point,
then repeats ``algorithm.step`` with adaptive step length, computing at every accepted
point the stability eigenvalues (once), the records and the test functions of the
special points and events; special points are detected by sign changes between
consecutive rows and located inside the step (:mod:`continuation.locate`). It stops at
``max_steps``, at a parameter bound (the last row is then exactly on the bound), at a
terminal event, when the branch closes on itself (periodic states compared modulo their
periods) or when the step falls below ``ds_min``; the reason is ``Branch.status``.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import scipy.sparse.linalg as spla
from scipy.sparse import csc_matrix

from ._threads import blas_threads_for
from .typing import ComplexArray, FloatArray
from .algorithms.base import (
    ContinuationAlgorithm,
    CorrectorResult,
    PointInfo,
    adapt_ds,
    bordered_column_max,
    bordered_rcond,
    correct,
    make_point,
    theta_norm,
)
from .algorithms.palc import PALC
from .branch import Branch, BranchPoint, SpecialKind, SpecialPoint
from .errors import ContinuationError, ConvergenceError
from .events import MAX_DIP_POINTS, Event, HopfTest, bp_test, crossed, event_slope, hermite_dip
from .locate import LocateResult, fold_guess, locate_beyond, locate_zero, point_at
from .problem import EquilibriumProblem
from .settings import ContinuationSettings
from .stability import (
    count_unstable,
    dense_stability,
    eigenvalues,
    sort_eigenvalues,
    sparse_eigs_near,
)
from .status import Status

log = logging.getLogger(__name__)

ProgressFn = Callable[[BranchPoint], None]

#: A located branch point must have a reciprocal condition number of the bordered matrix
#: at most this fraction of the larger of its values at the two rows around it.
BP_SINGULAR_RATIO = 0.1
_EPS = float(np.finfo(float).eps)
_NO_RECORDS = EquilibriumProblem.record

#: The branch-point test (a determinant) is smooth along the branch: at a located zero
#: ``|g|`` must be within this many times its mean slope over the step times the final
#: bracket (see :func:`~continuation.locate.locate_zero`), else a jump (trial points on
#: the crossing branch) was bracketed.
BP_CONTINUITY = 10.0

#: ... unless the point where the bracket closed is numerically singular: reciprocal
#: condition of the bordered matrix at most this many times its round-off level
#: ``10 (N + 1) eps``. At a branch point the crossing branch passes through the same
#: point, so trial points next to it are only determined to ``tol / sigma_min`` across
#: the branch and the test function there reflects that indeterminacy, not a jump; a
#: point singular to working precision is the branch point (a point on a jump next to
#: it, ``d`` away, has ``rcond ~ d`` times that of the rows, orders of magnitude more).
BP_ROUNDOFF_SINGULAR = 1000.0

#: ``|dp/ds|`` of the unit start tangent below which the start point counts as a fold
#: (the sign rule of the direction is then arbitrary; a warning says so).
_FOLD_START_TAU = 1e-8

_PREFIX = {
    SpecialKind.FOLD: "F",
    SpecialKind.HOPF: "H",
    SpecialKind.BRANCH_POINT: "BP",
}


# ---------------------------------------------------------------------------- helpers
def _eig_function(
    problem: Any, settings: ContinuationSettings, rightmost: bool = False
) -> Callable[[PointInfo], Any]:
    """Eigenvalues at a point (cached on it); ``rightmost``: on the sparse path, the
    ``n_eigs`` of largest real part as well as those nearest the shift."""
    det = settings.detect
    if getattr(problem, "jacobian_is_stability", False):
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
            _SparseEigs(n, k, det.eig_sigma, rightmost)
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


class _SparseEigs:
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
    point's eigenvectors saves about 12 % more on the discrete Bratu problem (N = 200)
    with one BLAS thread, but extracting the eigenvectors (ARPACK ``dneupd``) runs
    level-3 BLAS that multi-threaded OpenBLAS parallelises, which made whole runs 2-6x
    slower on a loaded machine: not done.
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
            vals = _with_rightmost(pt.Gz, vals, self.k)
        ev = np.full(self.n, np.nan + 0j)
        vals = sort_eigenvalues(vals)[: self.n]
        ev[: vals.size] = vals
        return ev


def _with_rightmost(J: Any, near: ComplexArray, k: int) -> ComplexArray:
    """``near`` together with the ``k`` eigenvalues of ``J`` of largest real part
    (ARPACK ``which="LR"``, relative tolerance 1e-12), duplicates (within 1e-9 relative)
    dropped; ``near`` alone if ARPACK fails."""
    try:
        lr = spla.eigs(csc_matrix(J), k=k, which="LR", return_eigenvectors=False, tol=1e-12)
    except (spla.ArpackNoConvergence, ValueError, RuntimeError):
        return near
    out = list(near)
    for lam in lr:
        if all(abs(lam - mu) > 1e-9 * max(1.0, abs(lam)) for mu in out):
            out.append(lam)
    return np.asarray(out, dtype=complex)


def _difference_fn(problem: Any) -> Callable[[FloatArray, FloatArray], FloatArray]:
    diff = getattr(problem, "difference", None)
    if callable(diff):
        return diff  # type: ignore[no-any-return]
    return lambda a, b: np.asarray(a) - np.asarray(b)


def _state_names(problem: Any, n: int) -> tuple[str, ...]:
    names = getattr(problem, "state_names", None)
    if names is None and hasattr(problem, "system"):
        names = getattr(problem.system, "state_names", None)
    names = tuple(names) if names is not None else ()
    return names if len(names) == n else tuple(f"z{k}" for k in range(n))


def _param_values(problem: Any, p0: float) -> dict[str, float]:
    params = getattr(problem, "params", None)
    out: dict[str, float] = {}
    if params is not None and hasattr(params, "names") and hasattr(params, "values"):
        out = {str(k): float(v) for k, v in zip(params.names, params.values, strict=False)}
    out[str(problem.free)] = float(p0)
    return out


@dataclass(eq=False, slots=True)
class _Row:
    z: FloatArray
    p: float
    eig: ComplexArray | None
    counts: tuple[int, int] | None
    ds: float
    iters: int
    records: dict[str, float]
    events: list[float]
    point: PointInfo
    slopes: list[float] = field(default_factory=list)  # d(event)/ds along the tangent


@dataclass(eq=False)
class _Run:
    rows: list[_Row] = field(default_factory=list)
    specials: list[SpecialPoint] = field(default_factory=list)
    status: Status = Status.MAX_STEPS
    message: str = ""
    arclength: float = 0.0


class _Context:
    """Everything one run needs: problem, settings, events and cached functions."""

    def __init__(
        self,
        problem: Any,
        algorithm: ContinuationAlgorithm,
        settings: ContinuationSettings,
        events: Sequence[Event],
        progress: ProgressFn | None,
        rightmost: bool = False,
    ) -> None:
        self.problem = problem
        self.algorithm = algorithm
        self.settings = settings
        self.events = tuple(events)
        self.progress = progress
        self.eig = _eig_function(problem, settings, rightmost)
        self.diff = _difference_fn(problem)
        self.grow_iters = int(getattr(algorithm, "grow_iters", 3))
        self.terminal = any(e.terminal for e in self.events)
        # event sub-brackets of the last step refined inside it (see event_brackets)
        self._dip_cache: tuple[_Row, _Row, dict[int, list[Any]]] | None = None
        # the protocol's record() of plain equilibria is always empty: not called per row
        self.record = (
            None if getattr(type(problem), "record", None) is _NO_RECORDS else problem.record
        )
        period = getattr(getattr(problem, "system", None), "period", None)
        # plain differences (no periodic state): distances without problem.difference
        self.plain_diff = not callable(getattr(problem, "difference", None)) or (
            period is not None and not np.any(np.asarray(period) > 0)
        )

    # ------------------------------------------------------------------ rows
    def make_row(self, pt: PointInfo, ds: float) -> _Row:
        ev = self.eig(pt)
        counts = pt.cache.get("counts") if ev is not None else None
        if counts is None and ev is not None:
            det = self.settings.detect
            counts = count_unstable(ev, det.eig_tol, det.imag_tol)
        rec = self.record(pt.z, pt.p) if self.record is not None else None
        rec = {str(k): float(v) for k, v in dict(rec).items()} if rec else {}
        if not self.events:
            return _Row(pt.z, pt.p, ev, counts, ds, pt.iters, rec, [], pt)
        z, p, tau = pt.z, pt.p, pt.tau
        evs = [e.value(z, p) for e in self.events]
        slopes = [event_slope(e, z, p, tau, g) for e, g in zip(self.events, evs, strict=True)]
        return _Row(z, p, ev, counts, ds, pt.iters, rec, evs, pt, slopes)

    # ------------------------------------------------------------------ location
    def locate(
        self,
        a: _Row,
        b: _Row,
        sigma_b: float,
        w: FloatArray,
        test: Callable[..., float],
        g_a: float,
        g_b: float,
        first: float | None = None,
        continuity: float | None = None,
        bracket: tuple[tuple[float, PointInfo, float], tuple[float, PointInfo, float]]
        | None = None,
    ) -> LocateResult:
        det = self.settings.detect
        if not det.locate:
            if bracket is not None:
                lo = bracket[0]
                return LocateResult(lo[0], lo[1], lo[2], False, 0, "location disabled")
            return LocateResult(0.0, a.point, g_a, False, 0, "location disabled")
        return locate_zero(
            self.problem,
            a.point,
            b.point,
            sigma_b,
            w,
            test,
            g_a,
            g_b,
            newton=self.settings.newton,
            tol=det.tol,
            max_iter=det.max_iter,
            first=first,
            continuity=continuity,
            bracket=bracket,
        )

    def event_brackets(
        self, a: _Row, b: _Row, sigma_b: float, w: FloatArray, k: int
    ) -> list[tuple[tuple[float, PointInfo, float], tuple[float, PointInfo, float]]]:
        """The sub-brackets of the step from ``a`` to ``b`` where event ``k`` crosses zero
        (in its direction), in branch order: ``[((sigma_lo, point_lo, g_lo),
        (sigma_hi, point_hi, g_hi)), ...]``.

        A sign change between the rows is the whole step. When ``g`` has the same sign
        at both rows, the slopes ``dg/ds`` stored with the rows (:func:`event_slope`)
        give the cubic Hermite interpolant of ``g(sigma)``; if it dips to zero
        (:func:`~continuation.events.hermite_dip`) a point is corrected on the branch at
        its extremum (:func:`~continuation.locate.point_at`) and, with its value and
        slope, the two halves are examined the same way, up to ``MAX_DIP_POINTS`` points
        per step. Consecutive points of opposite signs are the sub-brackets. Cached for
        the last ``(a, b)`` (the terminal check and the detection share it).
        """
        e = self.events[k]
        g_a, g_b = a.events[k], b.events[k]
        if crossed(g_a, g_b, e.direction):
            return [((0.0, a.point, g_a), (sigma_b, b.point, g_b))]
        m_a, m_b = a.slopes[k], b.slopes[k]
        if not (g_a * g_b > 0 and (g_a > 0) == (m_b > 0) != (m_a > 0)):
            return []  # (the common case: no sign change, monotone by the end slopes)
        cache = self._dip_cache
        if cache is not None and cache[0] is a and cache[1] is b and k in cache[2]:
            return cache[2][k]
        if cache is None or cache[0] is not a or cache[1] is not b:
            cache = self._dip_cache = (a, b, {})
        out = self._dip_brackets(a, b, sigma_b, w, e, g_a, g_b, m_a, m_b)
        cache[2][k] = out
        return out

    def _dip_brackets(
        self,
        a: _Row,
        b: _Row,
        sigma_b: float,
        w: FloatArray,
        e: Event,
        g_a: float,
        g_b: float,
        m_a: float,
        m_b: float,
    ) -> list[tuple[tuple[float, PointInfo, float], tuple[float, PointInfo, float]]]:
        """:meth:`event_brackets` for a step whose rows have values of the same sign."""
        pa, pb = a.point, b.point
        c = w * pa.tau
        # slopes per unit sigma: dsigma/ds = c . tau at each point
        samples: list[tuple[float, PointInfo, float, float]] = [
            (0.0, pa, g_a, m_a / float(c.dot(pa.tau))),
            (sigma_b, pb, g_b, m_b / float(c.dot(pb.tau))),
        ]
        newton, tol = self.settings.newton, self.settings.detect.tol
        done: set[float] = set()  # left ends of intervals examined without a dip
        for _ in range(MAX_DIP_POINTS):
            pick = None
            for i in range(len(samples) - 1):
                s0, q0, g0, m0 = samples[i]
                s1, q1, g1, m1 = samples[i + 1]
                if s0 in done or s1 - s0 <= tol:
                    continue
                t = hermite_dip(g0, g1, m0, m1, s1 - s0)
                if t is None:
                    done.add(s0)
                    continue
                pick = (i, s0 + t * (s1 - s0))
                break
            if pick is None:
                break
            i, s = pick
            near = min(samples[i], samples[i + 1], key=lambda q: abs(q[0] - s))
            pt = point_at(self.problem, pa, pb, s, sigma_b, w, newton, (near[0], near[1]))
            if pt is None:
                log.debug("event %r: no point at sigma=%.3g inside a step", e.name, s)
                done.add(samples[i][0])
                continue
            g = e.value(pt.z, pt.p)
            ct = float(c.dot(pt.tau))
            m = event_slope(e, pt.z, pt.p, pt.tau, g) / ct if ct > 0 else math.nan
            samples.insert(i + 1, (s, pt, g, m))
        out = []
        for (s0, q0, g0, _), (s1, q1, g1, _) in zip(samples, samples[1:], strict=False):
            if crossed(g0, g1, e.direction):
                out.append(((s0, q0, g0), (s1, q1, g1)))
        if len(samples) > 2:
            log.debug(
                "event %r: %d points corrected inside the step p=%.8g..%.8g, %d crossings",
                e.name,
                len(samples) - 2,
                pa.p,
                pb.p,
                len(out),
            )
        return out

    def locate_event(
        self, a: _Row, b: _Row, sigma_b: float, w: FloatArray, e: Event, lo: Any, hi: Any
    ) -> LocateResult:
        """Locate the zero of event ``e`` in the sub-bracket ``(lo, hi)`` of the step
        (ends ``(sigma, point, g)`` from :meth:`event_brackets`)."""
        return self.locate(
            a,
            b,
            sigma_b,
            w,
            lambda pt, t: e.value(pt.z, pt.p),
            lo[2],
            hi[2],
            continuity=e.continuity,
            bracket=(lo, hi),
        )

    def detect(
        self,
        a: _Row,
        b: _Row,
        sigma_b: float,
        w: FloatArray,
        index: int,
        s_a: float,
        terminal: tuple[int, LocateResult] | None = None,
    ) -> list[SpecialPoint]:
        """Detect and locate the special points between rows ``a`` and ``b``.

        ``terminal = (k, result)``: event ``k`` ended the step at ``b`` (already located).
        """
        det = self.settings.detect
        pa, pb = a.point, b.point
        ac, bc = a.counts, b.counts
        fold = det.fold and pa.tau[-1] * pb.tau[-1] < 0
        hopf = det.hopf and ac is not None and bc is not None and ac[0] == bc[0] and ac[1] != bc[1]
        if not (fold or hopf or self.events or (det.branch_point and pa.bp_sign != pb.bp_sign)):
            return []  # (the common case: nothing to locate)
        found: list[tuple[SpecialKind, LocateResult, dict[str, float], str]] = []
        if fold:
            r = self.locate(
                a,
                b,
                sigma_b,
                w,
                lambda pt, t: float(pt.tau[-1]),
                float(pa.tau[-1]),
                float(pb.tau[-1]),
                first=fold_guess(pa, pb, sigma_b),
            )
            found.append((SpecialKind.FOLD, r, {}, ""))
        if det.branch_point and pa.bp_sign != pb.bp_sign:
            r_fold = found[0][1] if fold and found[0][1].located else None
            bp = self.branch_point(a, b, sigma_b, w, r_fold)
            if bp is not None:
                found.append((SpecialKind.BRANCH_POINT, bp[0], bp[1], ""))
        if hopf:
            assert ac is not None and bc is not None
            assert a.eig is not None and b.eig is not None
            if abs(b.counts[1] - a.counts[1]) > 1:
                log.warning(
                    "%d complex pairs crossed between p=%.8g and p=%.8g; only one Hopf point "
                    "is located: reduce ds_max to separate them",
                    abs(b.counts[1] - a.counts[1]),
                    pa.p,
                    pb.p,
                )
            ht = HopfTest(a.eig, b.eig, det.imag_tol, det.eig_tol)
            if ht.ok:

                def g_h(pt: PointInfo, t: float) -> float:
                    lam = ht.track(self.eig(pt), t)
                    return math.nan if lam is None else lam.real

                assert ht.lam_a is not None and ht.lam_b is not None
                g_a, g_b = ht.lam_a.real, ht.lam_b.real
                if ht.outside:
                    # Re > 0 at both rows, but inside the eig_tol band at one of them
                    # (counted stable there): the zero lies just beyond that row
                    end = (0.0, pa, g_a) if abs(g_a) <= abs(g_b) else (sigma_b, pb, g_b)
                    if det.locate:
                        r = locate_beyond(
                            self.problem,
                            pa,
                            end,
                            sigma_b,
                            w,
                            g_h,
                            (g_b - g_a) / sigma_b,
                            newton=self.settings.newton,
                            tol=det.tol,
                        )
                    else:
                        r = LocateResult(end[0], end[1], end[2], False, 0, "location disabled")
                else:
                    r = self.locate(a, b, sigma_b, w, g_h, g_a, g_b)
                lam = ht.track(self.eig(r.point), r.sigma / sigma_b)
                omega = abs(lam.imag) if lam is not None else math.nan
                found.append((SpecialKind.HOPF, r, {"omega": omega}, ""))
            else:
                log.warning("Hopf bracketed near p=%.6g but no critical pair found", pa.p)
                r = LocateResult(0.0, pa, math.nan, False, 0, "no critical pair")
                found.append((SpecialKind.HOPF, r, {}, ""))
        for k, e in enumerate(self.events if self.events else ()):
            if terminal is not None and k == terminal[0]:
                r = terminal[1]
                found.append((SpecialKind.USER, r, {"g": r.g}, e.name))
            else:
                for lo, hi in self.event_brackets(a, b, sigma_b, w, k):
                    r = self.locate_event(a, b, sigma_b, w, e, lo, hi)
                    found.append((SpecialKind.USER, r, {"g": r.g}, e.name))
        if not found:
            return []
        out = []
        dr = (0, 0)
        if a.counts is not None and b.counts is not None:
            dr = (b.counts[0] - a.counts[0], b.counts[1] - a.counts[1])
        for kind, r, data, label in found:
            if not r.located:
                log.warning(
                    "%s between p=%.8g and p=%.8g was detected but not located (%s)",
                    label or kind.value,
                    pa.p,
                    pb.p,
                    r.message,
                )
            out.append(
                SpecialPoint(
                    kind=kind,
                    index=index,
                    p=float(r.point.p),
                    x=np.array(r.point.z),
                    located=bool(r.located),
                    bracket=(float(pa.p), float(pb.p)),
                    delta_unstable=dr,
                    label=label,
                    data=dict(data),
                    s=s_a + r.sigma,
                    tangent=np.array(r.point.tau),
                )
            )
        out.sort(key=lambda sp: sp.s)
        return out

    def branch_point(
        self,
        a: _Row,
        b: _Row,
        sigma_b: float,
        w: FloatArray,
        fold: LocateResult | None = None,
    ) -> tuple[LocateResult, dict[str, float]] | None:
        """Locate and verify a branch point where the BP test changes sign from a to b.

        ``fold``: a fold located in the same step. If the bordered matrix is singular
        there by the criterion below, the fold is the branch point (a pitchfork met
        along its non-trivial branch, which turns there) and is returned as such:
        locating the determinant's zero separately would correct trial points next to
        that singular matrix.

        The test function is the determinant of the bordered matrix
        ``M = [[G_z, G_p], [c^T]]``; its sign is only meaningful where ``M`` is
        numerically non-singular. With ``rho(x)`` the reciprocal condition of ``M D``
        at a point (:func:`~continuation.algorithms.base.bordered_rcond`, one column
        scaling ``D`` shared by the rows and the located point, so badly scaled
        unknowns or parameter do not matter):

        * if ``rho <= 10 (N + 1) eps`` at both rows, both signs are round-off and the
          sign change is ignored;
        * the located point must be a singular point: ``rho`` there at most
          ``BP_SINGULAR_RATIO`` (0.1) times the larger of its values at the rows (it
          vanishes linearly in the arclength at a simple branch point, so a located
          one is many orders of magnitude below its neighbours);
        * otherwise, if a row was numerically singular, the sign change was round-off
          and is dropped; if both rows were regular, ``det M`` must vanish in between
          (it is continuous), so the point is kept but reported as not located.

        Returns ``(result, data)`` with ``data = {"rcond": rho at the point,
        "rcond_ratio": rho / max(rho_a, rho_b)}``, or None if dropped.
        """
        pa, pb = a.point, b.point
        col = np.maximum(bordered_column_max(pa), bordered_column_max(pb))
        rho_a, rho_b = bordered_rcond(pa, col), bordered_rcond(pb, col)
        noise = 10.0 * pa.u.size * _EPS
        rho_ab = max(rho_a, rho_b)
        if rho_ab <= noise:
            log.info(
                "branch-point test changed sign between p=%.8g and p=%.8g where the bordered "
                "Jacobian is numerically singular (rcond %.1e, %.1e): round-off, ignored",
                pa.p,
                pb.p,
                rho_a,
                rho_b,
            )
            return None
        if fold is not None:
            rho_f = bordered_rcond(fold.point, col)
            if rho_f / rho_ab <= BP_SINGULAR_RATIO:
                return fold, {"rcond": rho_f, "rcond_ratio": rho_f / rho_ab}
        ref = pa.bp_logdet

        def g_bp(pt: PointInfo, t: float) -> float:
            return bp_test(pt.bp_sign, pt.bp_logdet, ref)

        r = self.locate(
            a,
            b,
            sigma_b,
            w,
            g_bp,
            bp_test(pa.bp_sign, pa.bp_logdet, ref),
            bp_test(pb.bp_sign, pb.bp_logdet, ref),
            continuity=BP_CONTINUITY,
        )
        rho = bordered_rcond(r.point, col)
        ratio = rho / rho_ab
        data = {"rcond": rho, "rcond_ratio": ratio}
        if ratio <= BP_SINGULAR_RATIO:
            if not r.located and r.iterations and rho <= BP_ROUNDOFF_SINGULAR * noise:
                msg = (
                    f"bracket closed on a numerically singular point (rcond {rho:.1e}); "
                    f"locator: {r.message}"
                )
                r = dataclasses.replace(r, located=True, message=msg)
            return r, data
        if min(rho_a, rho_b) <= noise:
            log.info(
                "branch-point test changed sign between p=%.8g and p=%.8g next to a "
                "numerically singular row, but no singular point lies between "
                "(rcond %.1e vs %.1e, %.1e at the rows): round-off, ignored",
                pa.p,
                pb.p,
                rho,
                rho_a,
                rho_b,
            )
            return None
        msg = (
            f"no singular point found (rcond {rho:.1e} vs {rho_a:.1e}, {rho_b:.1e} at the "
            f"rows){'; ' + r.message if r.message else ''}"
        )
        return dataclasses.replace(r, located=False, message=msg), data

    # ------------------------------------------------------------------ stopping points
    def on_bound(self, a: _Row, r: LocateResult, bound: float, w: FloatArray) -> LocateResult:
        """Move a located bound crossing exactly onto ``p = bound``.

        The locator stops within its tolerance of the bound, on either side; one Newton
        correction at fixed ``p = bound`` (from that point) puts the row exactly on it.
        Returns ``r`` unchanged if that correction fails.
        """
        c = w * a.point.tau
        solved = self.point_on_bound(r.point.u, bound, c, w)
        if solved is None:
            return r
        pt = solved[1]
        pt.iters = r.point.iters
        sigma = float(c.dot(pt.u - a.point.u))
        return LocateResult(sigma, pt, 0.0, True, r.iterations, r.message)

    def point_on_bound(
        self, u: FloatArray, bound: float, c: FloatArray, w: FloatArray
    ) -> tuple[CorrectorResult, PointInfo] | None:
        """Newton's method at fixed ``p = bound`` from ``u`` (its ``p`` replaced), and the
        point with its tangent (border ``c``); None if either fails."""
        guess = np.array(u, dtype=float)
        guess[-1] = bound
        e_p = np.zeros(guess.size)
        e_p[-1] = 1.0
        res = correct(self.problem, guess, np.zeros(guess.size), e_p, bound, self.settings.newton)
        if not res.converged or res.lin is None:
            return None
        try:
            return res, make_point(res.z, bound, res.lin, c, w, iters=res.iters)
        except np.linalg.LinAlgError:
            return None

    def bound_direct(
        self, a: _Row, b: _Row, sigma_b: float, bound: float, w: FloatArray
    ) -> LocateResult | None:
        """The row exactly on ``p = bound`` inside a step along which ``p`` is monotone.

        When ``dp/ds`` has the same sign at both rows (no fold inside the step), the
        step crosses the bound once; the crossing is then found by one Newton solve at
        fixed ``p = bound`` from the chord's point at that ``p``, instead of locating the
        zero of ``p - bound`` along the step. The result is accepted only if it lies
        inside the step (``0 < sigma <= sigma_b``) and the correction is not longer
        than the chord (the solve stayed on this branch); otherwise None (the caller
        then locates the crossing).
        """
        pa, pb = a.point, b.point
        if pa.tau[-1] * pb.tau[-1] <= 0 or not (pa.p - bound) * (pb.p - bound) < 0:
            return None
        ua, ub = pa.u, pb.u
        t = (bound - pa.p) / (pb.p - pa.p)
        chord = ub - ua
        guess = ua + t * chord
        guess[-1] = bound
        c = w * pa.tau
        solved = self.point_on_bound(guess, bound, c, w)
        if solved is None:
            return None
        res, pt = solved
        d = pt.u - ua
        sigma = float(c.dot(d))
        moved = res.u - guess
        if not (0.0 < sigma <= sigma_b * (1 + 1e-12)) or theta_norm(moved, w) > theta_norm(
            chord, w
        ):
            return None
        return LocateResult(sigma, pt, 0.0, True, 1)

    def stop_point(
        self, a: _Row, b: _Row, sigma_b: float, w: FloatArray
    ) -> tuple[LocateResult, Status, str, int | None] | None | Literal[False]:
        """The earliest parameter bound or terminal event crossed in this step.

        Returns ``(result, status, message, event_index or None)``, None if the step
        crosses neither, or False if it crosses a parameter bound that could not be
        located (the step must then be retried shorter: a row is never kept outside
        ``[p_min, p_max]``).
        """
        s = self.settings
        pa, pb = a.point.p, b.point.p
        if not self.terminal and s.p_min <= pb <= s.p_max:
            return None
        cands: list[tuple[LocateResult, Status, str, int | None]] = []
        for bound, outside in ((s.p_max, pb > s.p_max), (s.p_min, pb < s.p_min)):
            if outside and math.isfinite(bound):
                r_direct = self.bound_direct(a, b, sigma_b, bound, w)
                if r_direct is not None:
                    msg = f"{Status.PARAM_BOUND.value} ({self.problem.free}={bound:.10g})"
                    cands.append((r_direct, Status.PARAM_BOUND, msg, None))
                    continue
                r = locate_zero(
                    self.problem,
                    a.point,
                    b.point,
                    sigma_b,
                    w,
                    lambda pt, t, bound=bound: pt.p - bound,
                    pa - bound,
                    pb - bound,
                    newton=s.newton,
                    tol=s.detect.tol,
                    max_iter=s.detect.max_iter,
                )
                if r.located:
                    r = self.on_bound(a, r, bound, w)
                if not r.located or not s.p_min <= r.point.p <= s.p_max:
                    log.debug(
                        "bound %s=%.10g crossed between p=%.10g and p=%.10g but not located "
                        "(%s): step retried shorter",
                        self.problem.free,
                        bound,
                        pa,
                        pb,
                        r.message,
                    )
                    return False
                msg = f"{Status.PARAM_BOUND.value} ({self.problem.free}={bound:.10g})"
                cands.append((r, Status.PARAM_BOUND, msg, None))
        for k, e in enumerate(self.events):
            if not e.terminal:
                continue
            brackets = self.event_brackets(a, b, sigma_b, w, k)
            if brackets:
                lo, hi = brackets[0]  # the first zero in branch order ends the branch
                r = self.locate_event(a, b, sigma_b, w, e, lo, hi)
                if not r.located:
                    r = LocateResult(hi[0], hi[1], hi[2], False, r.iterations)
                cands.append((r, Status.EVENT, f"terminal event {e.name!r}", k))
        if not cands:
            return None
        return min(cands, key=lambda c: c[0].sigma)

    def closed(self, start: _Row, a: _Row, b: _Row, w: FloatArray, far: float) -> bool:
        """Did the chord ``a -> b`` pass through the start point (modulo periods)?

        Only once the branch has been farther than three step lengths from the start
        (``far``), and only if ``b`` is within one step of the start.
        """
        sigma = b.ds
        if far < 3.0 * sigma:
            return False
        d_ab = np.concatenate((self.diff(b.z, a.z), (b.p - a.p,)))
        d_a0 = np.concatenate((self.diff(start.z, a.z), (start.p - a.p,)))
        nn = float((w * d_ab).dot(d_ab))
        if nn <= 0:
            return False
        t = float((w * d_a0).dot(d_ab)) / nn
        if not (-1e-9 <= t <= 1 + 1e-9):
            return False
        dist = theta_norm(d_a0 - t * d_ab, w)
        aligned = float((w * start.point.tau).dot(b.point.tau)) > 0
        return aligned and dist <= 0.25 * sigma

    def distance_to_start(self, start: _Row, b: _Row, w: FloatArray) -> float:
        """``theta``-distance from ``b`` to the start point, modulo periods."""
        if self.plain_diff:
            d = b.point.u - start.point.u
        else:
            d = np.concatenate((self.diff(b.z, start.z), (b.p - start.p,)))
        return math.sqrt(float((w * d).dot(d)))


# ---------------------------------------------------------------------------- one run
def _run(
    ctx: _Context,
    z0: FloatArray,
    p0: float,
    iters0: int,
    orient: FloatArray | None = None,
    warn_fold: bool = True,
) -> _Run:
    """One direction from ``(z0, p0)``; ``orient``: a direction the start tangent must
    point along (``theta``-inner product > 0), overriding the sign rule of ``dp/ds``;
    ``warn_fold``: warn when the start point is a fold (the sign rule is arbitrary)."""
    s = ctx.settings
    run = _Run()
    try:
        state = ctx.algorithm.init(ctx.problem, z0, p0, s)
        pt = state.point
        if orient is not None and float((state.w * pt.tau).dot(orient)) < 0:
            state.point = make_point(
                pt.z, pt.p, (pt.G, pt.Gz, pt.Gp), pt.border, state.w, orient=orient, lu=pt.lu
            )
    except np.linalg.LinAlgError as exc:
        run.status, run.message = Status.SINGULAR, f"no tangent at the start point: {exc}"
        return run
    if warn_fold and abs(float(state.point.tau[-1])) < _FOLD_START_TAU:
        log.warning(
            "the start point %s=%.10g is (numerically) a fold: dp/ds = %.1e there, so the "
            "direction of p does not tell the two halves of the branch apart; use "
            'direction="both" to follow both',
            ctx.problem.free,
            p0,
            float(state.point.tau[-1]),
        )
    state.point.iters = iters0
    row0 = ctx.make_row(state.point, 0.0)
    run.rows.append(row0)
    if ctx.progress is not None:
        ctx.progress(_branch_point(row0, 0))
    w = state.w
    far = 0.0
    plain, u_start = ctx.plain_diff, row0.point.u
    grow, ds_max, grow_iters = s.grow, s.ds_max, ctx.grow_iters
    # (locals for the hot loop)
    step, problem, make_row, detect = ctx.algorithm.step, ctx.problem, ctx.make_row, ctx.detect
    rows, terminal_events, p_min, p_max, max_steps = (
        run.rows,
        ctx.terminal,
        s.p_min,
        s.p_max,
        s.max_steps,
    )
    # the eigenvalues are those of G_z itself (equilibria): a real one crossing zero is a
    # fold or branch point of this branch (not so for augmented codim-2 problems)
    count_guard = bool(getattr(problem, "jacobian_is_stability", False))
    p_at_bound = (p0 >= s.p_max and state.direction > 0) or (p0 <= s.p_min and state.direction < 0)
    if p_at_bound:
        run.status, run.message = Status.PARAM_BOUND, "the start point is on the parameter bound"
        return run
    try:
        while state.n_steps < max_steps:
            new_state, outcome = step(problem, state, s)
            if not outcome.converged:
                ds_new = adapt_ds(state.ds, outcome, s, grow_iters=ctx.grow_iters)
                log.debug(
                    "step rejected at p=%.6g (ds=%.3g): %s",
                    state.point.p,
                    state.ds,
                    outcome.message,
                )
                if ds_new < s.ds_min:
                    run.status = Status.DS_MIN
                    run.message = (
                        f"{Status.DS_MIN.value} Last point p={state.point.p:.10g}; last "
                        f"failure: {outcome.message}"
                    )
                    break
                state.ds = ds_new
                continue
            a = rows[-1]
            sigma_b = outcome.sigma
            b = make_row(new_state.point, sigma_b)
            ac, bc = a.counts, b.counts
            if (
                count_guard
                and ac is not None
                and bc is not None
                and abs(bc[0] - ac[0]) >= 2
                and bc[1] == ac[1]
                and state.ds > s.ds_min * (1 + 1e-12)
            ):
                # two or more real eigenvalues of G_z crossed zero in one step (the
                # complex count is unchanged, so no real pair merged into a complex one):
                # their folds / branch points cancel in the sign tests; shorten the step
                log.debug(
                    "%d real eigenvalues crossed 0 between p=%.8g and p=%.8g: step retried shorter",
                    abs(bc[0] - ac[0]),
                    a.p,
                    b.p,
                )
                state.ds = max(state.ds * s.shrink, s.ds_min)
                continue
            if not terminal_events and p_min <= b.p <= p_max:
                stop = None  # (stop_point's first test, inlined: the common case)
            else:
                stop = ctx.stop_point(a, b, sigma_b, w)
            if stop is False:  # a bound crossed but not located: never keep a row outside
                ds_new = state.ds * s.shrink
                if ds_new < s.ds_min:
                    run.status = Status.DS_MIN
                    run.message = (
                        f"{Status.DS_MIN.value} Last point p={state.point.p:.10g}; the "
                        "parameter bound was crossed but could not be located"
                    )
                    break
                state.ds = ds_new
                continue
            terminal = None
            if stop is not None:
                r, status, msg, k_event = stop
                if r.sigma < sigma_b:
                    b = ctx.make_row(r.point, r.sigma)
                    sigma_b = r.sigma
                run.status, run.message = status, msg
                if k_event is not None:
                    terminal = (k_event, r)
            index = len(rows) - 1
            if sigma_b > 0:
                found = detect(a, b, sigma_b, w, index, run.arclength, terminal)
                if found:
                    run.specials.extend(found)
            if stop is None or sigma_b > 0:
                rows.append(b)
                run.arclength += sigma_b
                if ctx.progress is not None:
                    ctx.progress(_branch_point(b, len(run.rows) - 1))
            if stop is not None:
                break
            if plain:  # (distance_to_start, inlined for plain differences)
                d0 = b.point.u - u_start
                dist0 = math.sqrt(float((w * d0).dot(d0)))
            else:
                dist0 = ctx.distance_to_start(run.rows[0], b, w)
            if (
                far >= 3.0 * sigma_b
                and dist0 <= 2.0 * sigma_b
                and ctx.closed(run.rows[0], a, b, w, far)
            ):
                run.status, run.message = Status.CLOSED_LOOP, Status.CLOSED_LOOP.value
                break
            far = max(far, dist0)
            # (adapt_ds for an accepted step, inlined)
            if outcome.newton_iters <= grow_iters:
                new_state.ds = min(new_state.ds * grow, ds_max)
            else:
                new_state.ds = min(new_state.ds, ds_max)
            state = new_state
        else:
            run.status, run.message = Status.MAX_STEPS, Status.MAX_STEPS.value
    except KeyboardInterrupt:
        run.status, run.message = Status.INTERRUPTED, Status.INTERRUPTED.value
        log.warning("continuation interrupted after %d points", len(run.rows))
    return run


def _branch_point(row: _Row, index: int) -> BranchPoint:
    ev = row.eig if row.eig is not None else np.zeros(0, complex)
    nu = -1 if row.counts is None else row.counts[0] + 2 * row.counts[1]
    return BranchPoint(
        index=index,
        p=row.p,
        x=row.z,
        eigenvalues=ev,
        n_unstable=nu,
        stable=nu == 0,
        ds=row.ds,
        newton_iters=row.iters,
        records=dict(row.records),
    )


# ---------------------------------------------------------------------------- assembling
def _relabel(specials: list[SpecialPoint]) -> tuple[SpecialPoint, ...]:
    count: dict[SpecialKind, int] = {}
    out = []
    for sp in specials:
        if sp.kind in _PREFIX:
            count[sp.kind] = count.get(sp.kind, 0) + 1
            sp = dataclasses.replace(sp, label=f"{_PREFIX[sp.kind]}{count[sp.kind]}")
        out.append(sp)
    return tuple(out)


def _merge(back: _Run, fwd: _Run) -> tuple[list[_Row], list[float], list[SpecialPoint]]:
    """Rows ordered from the backward end to the forward end (start row once)."""
    m = len(back.rows) - 1
    rows: list[_Row] = []
    ds: list[float] = []
    for j in range(m, 0, -1):
        rows.append(back.rows[j])
        ds.append(0.0 if j == m else back.rows[j + 1].ds)
    specials: list[SpecialPoint] = []
    s_back = back.arclength
    for sp in back.specials:
        specials.append(
            dataclasses.replace(
                sp,
                index=m - sp.index - 1,
                bracket=(sp.bracket[1], sp.bracket[0]),
                delta_unstable=(-sp.delta_unstable[0], -sp.delta_unstable[1]),
                s=s_back - sp.s,
                tangent=None if sp.tangent is None else -sp.tangent,
            )
        )
    specials.reverse()
    for k, row in enumerate(fwd.rows):
        rows.append(row)
        ds.append((back.rows[1].ds if m >= 1 else 0.0) if k == 0 else row.ds)
    for sp in fwd.specials:
        specials.append(dataclasses.replace(sp, index=sp.index + m, s=sp.s + s_back))
    return rows, ds, specials


def _make_branch(
    problem: Any,
    rows: list[_Row],
    ds: list[float],
    specials: list[SpecialPoint],
    status: Status,
    message: str,
    settings: ContinuationSettings,
    p0: float,
    n: int,
    events: Sequence[Event] = (),
) -> Branch:
    N = len(rows)
    eigs = [r.eig for r in rows]
    width = max((e.size for e in eigs if e is not None), default=0)
    if N and width and all(e is not None and e.size == width for e in eigs):
        eig = np.array(eigs, dtype=complex).reshape(N, width)  # (the common case at once)
    else:
        eig = np.full((N, width), np.nan + 0j)
        for k, e in enumerate(eigs):
            if e is not None:
                eig[k, : e.size] = e
    nun = np.array(
        [-1 if r.counts is None else r.counts[0] + 2 * r.counts[1] for r in rows], dtype=int
    ).reshape(N)
    keys: list[str] = []
    for r in rows:
        for key in r.records:
            if key not in keys:
                keys.append(key)
    records = {key: np.array([r.records.get(key, np.nan) for r in rows]) for key in keys}
    return Branch(
        problem=problem,
        free=str(problem.free),
        p=np.array([r.p for r in rows], dtype=float),
        x=np.array([r.z for r in rows], dtype=float).reshape(N, n),
        eigenvalues=eig,
        n_unstable=nun,
        ds=np.array(ds, dtype=float),
        newton_iters=np.array([r.iters for r in rows], dtype=int),
        records=records,
        special_points=_relabel(specials),
        status=status,
        message=message,
        settings=settings,
        state_names=_state_names(problem, n),
        param_values=_param_values(problem, p0),
        event_names=tuple(e.name for e in events),
    )


def _empty_branch(
    problem: Any,
    n: int,
    status: Status,
    message: str,
    settings: ContinuationSettings,
    p0: float,
    events: Sequence[Event] = (),
) -> Branch:
    return _make_branch(problem, [], [], [], status, message, settings, p0, n, events)


# ---------------------------------------------------------------------------- entry point
def continue_branch(
    problem: Any,
    z0: Any,
    p0: float,
    algorithm: ContinuationAlgorithm | None = None,
    settings: ContinuationSettings | None = None,
    *,
    events: Sequence[Event] = (),
    direction: Literal["forward", "backward", "both"] = "forward",
    throw: bool = False,
    progress: ProgressFn | None = None,
) -> Branch:
    r"""Continue the solutions of ``G(z, p) = 0`` in the free parameter ``p``.

    Parameters
    ----------
    problem : ContinuationProblem
        Residual, Jacobians, stability and records (:mod:`continuation.problem`).
    z0 : array_like, shape (N,)
        Start point, or a guess: it is first corrected by Newton's method at fixed
        ``p0`` (``settings.newton``).
    p0 : float
        Start value of the free parameter; must lie in ``[p_min, p_max]``.
    algorithm : ContinuationAlgorithm, optional
        Default :class:`~continuation.algorithms.palc.PALC`.
    settings : ContinuationSettings, optional
        Step control, bounds, corrector and detection settings. ``sign(ds)`` is the
        "forward" direction of ``p`` at the start.
    events : sequence of Event
        User events, detected and located like the built-in special points.
    direction : {"forward", "backward", "both"}
        ``"forward"`` follows ``sign(ds)``; ``"backward"`` the opposite; ``"both"`` runs
        backward, then forward, and returns ONE branch ordered from the backward end
        to the forward end (the start point appears once, at row ``len(backward) - 1``);
        special points are re-indexed and their ``bracket``, ``delta_unstable`` and
        ``tangent`` follow that order. ``max_steps`` applies to each direction.
    throw : bool
        Raise :class:`~continuation.errors.ConvergenceError` if the start point does
        not converge, and :class:`~continuation.errors.ContinuationError` if the branch
        ends in a numerical failure (``DS_MIN``, ``SINGULAR``, ...). Otherwise failures
        are reported in ``Branch.status``.
    progress : callable, optional
        ``progress(BranchPoint)`` after every accepted point (``index`` counts within
        the current direction).

    Returns
    -------
    Branch
        ``status`` says why it stopped; ``Status.INTERRUPTED`` (Ctrl-C) keeps the points
        computed so far.

    Raises
    ------
    ValueError
        Bad input: ``z0`` of the wrong shape or not finite, ``p0`` not finite or out of
        bounds, ``direction`` unknown, ``events`` not :class:`Event` instances.
    """
    settings = settings if settings is not None else ContinuationSettings()
    if not isinstance(settings, ContinuationSettings):
        raise ValueError(f"`settings` must be a ContinuationSettings, got {type(settings)}")
    algorithm = algorithm if algorithm is not None else PALC()
    if not isinstance(algorithm, ContinuationAlgorithm):
        raise ValueError(f"`algorithm` must be a ContinuationAlgorithm, got {algorithm!r}")
    if direction not in ("forward", "backward", "both"):
        raise ValueError(f"`direction` must be 'forward', 'backward' or 'both', got {direction!r}")
    events = tuple(events)
    for e in events:
        if not isinstance(e, Event):
            raise ValueError(f"`events` must contain Event instances, got {e!r}")
    n = int(problem.n_unknowns)
    z = np.asarray(z0, dtype=float)
    if z.shape != (n,):
        raise ValueError(f"`z0` must have shape ({n},), got {z.shape}")
    if not np.all(np.isfinite(z)):
        raise ValueError(f"`z0` contains NaN or inf: {z}")
    try:
        p0 = float(p0)
    except (TypeError, ValueError):
        raise ValueError(f"`p0` must be a float, got {p0!r}") from None
    if not math.isfinite(p0):
        raise ValueError(f"`p0` must be finite, got {p0}")
    if not settings.p_min <= p0 <= settings.p_max:
        raise ValueError(
            f"`p0`={p0} lies outside [p_min, p_max] = [{settings.p_min}, {settings.p_max}]"
        )

    start = _correct_start(problem, z, p0, settings)
    if not start.converged:
        msg = f"start point did not converge at {problem.free}={p0:.10g}: {start.message}"
        log.warning(msg)
        if throw:
            raise ConvergenceError(msg)
        return _empty_branch(problem, n, Status.NEWTON_FAILED, msg, settings, p0, events)

    ctx_args = (problem, algorithm)
    ds_abs = abs(settings.ds)
    sgn = 1.0 if settings.ds > 0 else -1.0

    def run_dir(sign: float, orient: FloatArray | None, rightmost: bool) -> _Run:
        st = dataclasses.replace(settings, ds=sign * ds_abs)
        ctx = _Context(*ctx_args, st, events, progress, rightmost)
        return _run(ctx, start.z, p0, start.iters, orient, warn_fold=direction != "both")

    def run_all(rightmost: bool) -> Branch:
        if direction == "both":
            back = run_dir(-sgn, None, rightmost)
            if back.status in (Status.INTERRUPTED, Status.CLOSED_LOOP) or not back.rows:
                # a closed loop is complete already; an interrupt stops everything
                fwd = _Run(rows=back.rows[:1], status=back.status, message=back.message)
            else:
                # the forward run leaves opposite to the backward one, whatever dp/ds is
                # (at a fold the sign of dp/ds cannot tell the two halves apart)
                fwd = run_dir(sgn, -back.rows[0].point.tau, rightmost)
            if back.rows:
                rows, ds, specials = _merge(back, fwd)
            else:
                rows, ds, specials = fwd.rows, [r.ds for r in fwd.rows], fwd.specials
            status, message = _combine(back, fwd)
        else:
            one = run_dir(sgn if direction == "forward" else -sgn, None, rightmost)
            rows, ds, specials = one.rows, [r.ds for r in one.rows], one.specials
            status, message = one.status, one.message
        return _make_branch(problem, rows, ds, specials, status, message, settings, p0, n, events)

    with blas_threads_for(n, bool(getattr(problem, "sparse", False))):
        br = _run_checked(problem, settings, run_all)
    return _finish(br, throw)


def _run_checked(
    problem: Any, settings: ContinuationSettings, run_all: Callable[[bool], Branch]
) -> Branch:
    """``run_all(False)``, and again with the rightmost eigenvalues if the sparse
    stability check finds unstable ones the shift missed (see :func:`_missed_unstable`)."""
    br = run_all(False)
    missed = _missed_unstable(problem, br, settings)
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
        still = _missed_unstable(problem, br, settings)
        if still:
            note += (
                " Stability still incomplete at some checked rows: raise "
                "DetectionSettings.n_eigs or dense_eigs_max."
            )
        br = dataclasses.replace(br, message=br.message + note)
    return br


#: Rows of a sparse branch whose saddle index is checked against the rightmost
#: eigenvalues (the first, the middle and the last; each check is one Arnoldi run
#: without shift-invert, about 10 ms at n = 200).
N_STABILITY_CHECKS = 3


def _missed_unstable(
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
    are computed there). :func:`continue_branch` then continues the branch again with
    the rightmost eigenvalues at every point.
    """
    det = settings.detect
    n = br.x.shape[1] if br.x.ndim == 2 else 0
    k = int(det.n_eigs)
    if (
        not len(br)
        or not getattr(problem, "jacobian_is_stability", False)
        or n <= det.dense_eigs_max
        or k >= n - 2
        or not getattr(problem, "linearize", None)
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


def _correct_start(
    problem: Any, z: FloatArray, p0: float, settings: ContinuationSettings
) -> CorrectorResult:
    """Newton's method on ``G(z, p0) = 0`` at fixed ``p0`` (bordered with ``e_p``)."""
    u0 = np.append(z, p0)
    e_p = np.zeros(u0.size)
    e_p[-1] = 1.0
    res = correct(problem, u0, u0, e_p, 0.0, settings.newton)
    if not res.converged and not res.message:
        res.message = "Newton did not converge"
    return res


def _combine(back: _Run, fwd: _Run) -> tuple[Status, str]:
    if Status.INTERRUPTED in (back.status, fwd.status):
        return Status.INTERRUPTED, Status.INTERRUPTED.value
    message = f"backward: {back.message}; forward: {fwd.message}"
    for run in (fwd, back):
        if not run.status.ok:
            return run.status, message
    return fwd.status, message


def _finish(branch: Branch, throw: bool) -> Branch:
    n_sp = len(branch.special_points)
    log.info(
        "branch in %s: %d points, %d special points, status %s",
        branch.free,
        len(branch),
        n_sp,
        branch.status.name,
    )
    if throw and not branch.status.ok and branch.status is not Status.INTERRUPTED:
        raise ContinuationError(branch.message or branch.status.value)
    return branch


__all__ = ["continue_branch"]
