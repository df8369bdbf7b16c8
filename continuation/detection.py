r"""Rows of a run and the special points between them.

A :class:`Row` is one accepted point of a run with what the detection needs (the
eigenvalues and unstable counts, records, event values and slopes). A
:class:`RunContext` holds what one run of :func:`~continuation.driver.continue_branch`
needs besides the loop itself: it makes the rows, detects special points by sign
changes of their test functions between consecutive rows and locates them inside the
step (:mod:`continuation.locate`): folds (``dp/ds``), Hopf points (a complex pair
crossing the imaginary axis, :class:`~continuation.events.HopfTest`), branch points
(the sign of the bordered determinant, verified by its condition), user events
(including zeros of the same sign at both rows, found from the Hermite interpolant of
the event along the step); and it finds where a run stops inside a step (a parameter
bound, exactly on it, or a terminal event) and whether the branch closed on itself.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from .algorithms.base import ContinuationAlgorithm, theta_norm
from .algorithms.corrector import CorrectorResult, correct
from .algorithms.point import PointInfo, make_point
from .branch import BranchPoint, SpecialKind, SpecialPoint
from .dynamics.trajectory import hermite
from .events import (
    MAX_DIP_POINTS,
    Event,
    HopfTest,
    bp_test,
    complex_mask,
    crossed,
    event_slope,
    hermite_dip,
)
from .linalg import bordered_column_max, bordered_rcond
from .locate import LocateResult, fold_guess, locate_beyond, locate_zero, point_at
from .problem import difference, has_periodic_states, record_function
from .row_eigs import eig_function
from .settings import ContinuationSettings
from .stability import count_unstable
from .status import Status
from .typing import ComplexArray, FloatArray

log = logging.getLogger(__name__)

ProgressFn = Callable[[BranchPoint], None]

#: A located branch point must have a reciprocal condition number of the bordered matrix
#: at most this fraction of the larger of its values at the two rows around it.
BP_SINGULAR_RATIO = 0.1
_EPS = float(np.finfo(float).eps)

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


def _plain_difference(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.asarray(a) - np.asarray(b)


def _hermite_at_p(
    ua: FloatArray, ub: FloatArray, ta: FloatArray, tb: FloatArray, h: float, p: float
) -> FloatArray:
    r"""The point at parameter ``p`` of the cubic Hermite interpolant of a step.

    :math:`u(s) = h_{00} u_a + h_{10} h \tau_a + h_{01} u_b + h_{11} h \tau_b` (``h``
    the chord's length, ``tau`` the unit tangents at the rows, the parameter last),
    error :math:`O(h^4)` against the chord's :math:`O(h^2)`; ``s`` solves
    :math:`p(s) = p` by Newton's method on the cubic from the chord's value. Where the
    cubic is not monotone in ``p`` on ``[0, 1]`` or Newton leaves it, the chord's point.
    """
    pa, pb = float(ua[-1]), float(ub[-1])
    s_lin = (p - pa) / (pb - pa)
    chord_pt = ua + s_lin * (ub - ua)
    ma, mb = h * float(ta[-1]), h * float(tb[-1])
    # p(s) = c3 s^3 + c2 s^2 + c1 s + pa
    c3 = 2 * pa + ma - 2 * pb + mb
    c2 = -3 * pa - 2 * ma + 3 * pb - mb
    c1 = ma
    monotone_ends = ma * (pb - pa) > 0 and mb * (pb - pa) > 0
    if not (monotone_ends and all(math.isfinite(c) for c in (c3, c2, c1))):
        return chord_pt
    sv = s_lin
    for _ in range(8):
        g = ((c3 * sv + c2) * sv + c1) * sv + pa - p
        dg = (3 * c3 * sv + 2 * c2) * sv + c1
        if not dg * (pb - pa) > 0:
            return chord_pt
        step = g / dg
        sv -= step
        if not 0.0 < sv < 1.0:
            return chord_pt
        if abs(step) <= 1e-14:
            break
    return np.asarray(hermite(sv, h, ua, ta, ub, tb))


def hopf_beside_real_crossing(a: Any, b: Any, imag_tol: float) -> bool:
    """Whether a step whose real *and* pair counts changed may hold a Hopf point.

    The Hopf test asks for a change of the number of unstable complex pairs. Alone it
    is one; where the number of unstable real eigenvalues changed too, the pairs' change
    may instead come from two real eigenvalues colliding into a pair (or a pair
    splitting) off the axis. That is told apart by the total number of complex pairs,
    stable or not, which a collision changes and a Hopf point with a real eigenvalue
    crossing zero beside it (a fold or branch point in the same step, e.g. the
    pitchfork next to the Hopf point of AUTO-07p's demo ``tor``) does not. Accepted
    here: the pair count changed by one, the real count by an odd number (a real zero
    crossing: the determinant's sign changed) and the total number of complex pairs is
    the same at both rows; the crossing pair must then still be found by
    :class:`~continuation.events.HopfTest`.
    """
    ac, bc = a.counts, b.counts
    if a.eig is None or b.eig is None or abs(bc[1] - ac[1]) != 1 or (bc[0] - ac[0]) % 2 == 0:
        return False
    na = int(np.count_nonzero(complex_mask(a.eig, imag_tol)))
    nb = int(np.count_nonzero(complex_mask(b.eig, imag_tol)))
    return na == nb


@dataclass(eq=False, slots=True)
class Row:
    """One accepted (or trial) point of a run with what detection needs of it.

    Attributes are the unknowns ``z`` (N,), the parameter ``p``, the stability
    eigenvalues and their unstable counts, the step ``ds`` that reached it, the Newton
    iterations, the records, the event values and their slopes ``d(event)/ds``.
    """

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


def _minus_bound(bound: float) -> Callable[[Any, float], float]:
    """``(point, t) -> p - bound``: the test function of a parameter bound."""
    return lambda pt, t: float(pt.p) - bound


class RunContext:
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
        self.eig = eig_function(problem, settings, rightmost)
        self.diff = difference(problem) or _plain_difference
        self.grow_iters = int(getattr(algorithm, "grow_iters", 3))
        self.terminal = any(e.terminal for e in self.events)
        # event sub-brackets of the last step refined inside it (see event_brackets)
        self._dip_cache: tuple[Row, Row, dict[int, list[Any]]] | None = None
        # the protocol's record() of plain equilibria is always empty: not called per row
        self.record = record_function(problem)
        # plain differences (no periodic state): distances without problem.difference
        self.plain_diff = not has_periodic_states(problem)

    # ------------------------------------------------------------------ rows
    def make_row(self, pt: PointInfo, ds: float) -> Row:
        """The :class:`Row` of a corrected point: eigenvalues, counts, records, events."""
        ev = self.eig(pt)
        counts = pt.cache.get("counts") if ev is not None else None
        if counts is None and ev is not None:
            det = self.settings.detect
            counts = count_unstable(ev, det.eig_tol, det.imag_tol)
        rec = self.record(pt.z, pt.p) if self.record is not None else None
        rec = {str(k): float(v) for k, v in dict(rec).items()} if rec else {}
        if not self.events:
            return Row(pt.z, pt.p, ev, counts, ds, pt.iters, rec, [], pt)
        z, p, tau = pt.z, pt.p, pt.tau
        evs = [e.value(z, p) for e in self.events]
        slopes = [event_slope(e, z, p, tau, g) for e, g in zip(self.events, evs, strict=True)]
        return Row(z, p, ev, counts, ds, pt.iters, rec, evs, pt, slopes)

    # ------------------------------------------------------------------ location
    def locate(
        self,
        a: Row,
        b: Row,
        sigma_b: float,
        w: FloatArray,
        test: Callable[..., float],
        g_a: float,
        g_b: float,
        first: float | None = None,
        continuity: float | None = None,
        bracket: tuple[tuple[float, PointInfo, float], tuple[float, PointInfo, float]]
        | None = None,
        same_branch: bool = False,
    ) -> LocateResult:
        """The zero of ``test`` between rows ``a`` and ``b`` (:func:`.locate_zero`).

        With ``settings.detect.locate`` off, the bracket's end (or row ``a``) unlocated.
        """
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
            same_branch=same_branch,
        )

    def event_brackets(
        self, a: Row, b: Row, sigma_b: float, w: FloatArray, k: int
    ) -> list[tuple[tuple[float, PointInfo, float], tuple[float, PointInfo, float]]]:
        """The sub-brackets of the step from ``a`` to ``b`` where event ``k`` crosses zero.

        Crossings in the event's direction, in branch order: ``[((sigma_lo, point_lo, g_lo),
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
        a: Row,
        b: Row,
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
        self, a: Row, b: Row, sigma_b: float, w: FloatArray, e: Event, lo: Any, hi: Any
    ) -> LocateResult:
        """Locate the zero of event ``e`` in the sub-bracket ``(lo, hi)`` of the step.

        The ends are ``(sigma, point, g)`` from :meth:`event_brackets`.

        An event at a parameter value whose bracket is the whole step is solved
        directly at that value (:meth:`bound_direct`) where ``p`` is monotone along the
        step; otherwise, and if that solve fails, its zero is located as any other.
        """
        if (
            e.param_value is not None
            and self.settings.detect.locate
            and lo[0] == 0.0
            and hi[0] == sigma_b
        ):
            r = self.bound_direct(a, b, sigma_b, e.param_value, w)
            if r is not None:
                return r
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
            # a test smooth along the branch is evaluated on the branch only (not on a
            # crossing branch next to a branch point, see locate.tangent_agrees)
            same_branch=e.continuity is not None,
        )

    def detect(
        self,
        a: Row,
        b: Row,
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
        hopf = det.hopf and ac is not None and bc is not None and ac[1] != bc[1]
        # a real eigenvalue crossing zero in the same step (a fold or branch point next to
        # the Hopf point) changes the real count too: see hopf_beside_real_crossing
        mixed = hopf and ac[0] != bc[0]  # type: ignore[index]
        if mixed and not hopf_beside_real_crossing(a, b, det.imag_tol):
            hopf = False
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
            if abs(bc[1] - ac[1]) > 1:
                log.warning(
                    "%d complex pairs crossed between p=%.8g and p=%.8g; only one Hopf point "
                    "is located: reduce ds_max to separate them",
                    abs(bc[1] - ac[1]),
                    pa.p,
                    pb.p,
                )
            ht = HopfTest(a.eig, b.eig, det.imag_tol, det.eig_tol)
            if mixed and not ht.ok:
                pass  # (no pair crosses: the real count's change explains the pairs')
            elif ht.ok:

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
        quiet = {e.name for e in self.events or () if not e.report}
        for kind, r, data, label in found:
            if label in quiet:
                pass  # (the caller classifies these zeros and reports what it keeps)
            elif not r.located:
                log.warning(
                    "%s between p=%.8g and p=%.8g was detected but not located (%s)",
                    label or kind.value,
                    pa.p,
                    pb.p,
                    r.message,
                )
            elif r.error > det.tol:
                log.warning(
                    "%s between p=%.8g and p=%.8g was located with error %.1e > tol %.1e (%s)",
                    label or kind.value,
                    pa.p,
                    pb.p,
                    r.error,
                    det.tol,
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
                    error=float(r.error),
                )
            )
        out.sort(key=lambda sp: sp.s)
        return out

    def branch_point(
        self,
        a: Row,
        b: Row,
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
        at a point (:func:`~continuation.linalg.bordered_rcond`, one column
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
    def on_bound(self, a: Row, r: LocateResult, bound: float, w: FloatArray) -> LocateResult:
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
        # (on p = bound exactly: no location error beyond the corrector's)
        return LocateResult(sigma, pt, 0.0, True, r.iterations, r.message, error=0.0)

    def point_on_bound(
        self, u: FloatArray, bound: float, c: FloatArray, w: FloatArray
    ) -> tuple[CorrectorResult, PointInfo] | None:
        """Newton's method at fixed ``p = bound`` from ``u`` (its ``p`` replaced).

        Returns the point with its tangent (border ``c``); None if either fails.
        """
        guess = np.array(u, dtype=float)
        guess[-1] = bound
        e_p = np.zeros(guess.size)
        e_p[-1] = 1.0
        res = correct(self.problem, guess, np.zeros(guess.size), e_p, bound,
                      self.settings.newton, final_lu=False)  # (make_point factorises)  # fmt: skip
        if not res.converged or res.lin is None:
            return None
        try:
            return res, make_point(res.z, bound, res.lin, c, w, iters=res.iters)
        except np.linalg.LinAlgError:
            return None

    def bound_direct(
        self, a: Row, b: Row, sigma_b: float, bound: float, w: FloatArray
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
        chord = ub - ua
        guess = _hermite_at_p(ua, ub, pa.tau, pb.tau, theta_norm(chord, w), bound)
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
        # (on p = bound exactly: no location error beyond the corrector's)
        return LocateResult(sigma, pt, 0.0, True, 1, error=0.0)

    def stop_point(
        self, a: Row, b: Row, sigma_b: float, w: FloatArray
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
                    _minus_bound(bound),
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

    def closed(self, start: Row, a: Row, b: Row, w: FloatArray, far: float) -> bool:
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

    def distance_to_start(self, start: Row, b: Row, w: FloatArray) -> float:
        """``theta``-distance from ``b`` to the start point, modulo periods."""
        if self.plain_diff:
            d = b.point.u - start.point.u
        else:
            d = np.concatenate((self.diff(b.z, start.z), (b.p - start.p,)))
        return math.sqrt(float((w * d).dot(d)))


__all__ = ["BP_CONTINUITY", "BP_ROUNDOFF_SINGULAR", "BP_SINGULAR_RATIO", "Row", "RunContext"]
