r"""Events and test functions along a branch.

A special point is where a scalar *test function* ``g`` changes sign between two
consecutive branch rows; the same mechanism serves the built-in bifurcations and the
user's :class:`Event`:

========== ============================================= ===============================
kind       detected when                                 located as the zero of
========== ============================================= ===============================
fold       ``dp/ds`` (last tangent component) changes     ``dp/ds``
           sign
bp         ``det [G_z G_p; tau^T]`` changes sign           that determinant (scaled)
hopf       the number of unstable complex-conjugate       ``Re`` of the critical pair
           pairs changes by one while the number of
           unstable real eigenvalues stays the same
user       ``fn(x, p)`` changes sign (``direction``),     ``fn(x, p)``
           or dips through zero inside a step (below)
========== ============================================= ===============================

A Hopf pair counted as stable (``Re <= eig_tol``) at one row and unstable at the other
is the crossing pair even if both real parts are positive (:func:`crossing_pair`); the
zero of ``Re`` then lies just beyond the row inside the band and is located there
(:func:`~continuation.locate.locate_beyond`).

*Double crossings of user events.* A user event whose ``g`` has the same sign at both
rows of a step may still cross zero twice inside it (a dip of ``g`` between the rows).
Every row also stores ``dg/ds = grad g . tau`` for each event, by one forward difference
along the unit tangent (:func:`event_slope`: one extra evaluation of ``fn`` per row per
event, none without events). When the end slopes point towards zero at the first row
and away from it at the second, the cubic Hermite interpolant of ``g(sigma)`` over the
step has an interior extremum; if it comes within ``DIP_MARGIN`` (10 %) of the smaller
end value of zero (:func:`hermite_dip`), a point is corrected on the branch at that
extremum; if ``g`` there has the opposite sign, the step holds two sign-changing
sub-brackets, each located like an ordinary crossing (``direction`` applies to each,
``continuity`` too); otherwise the two halves are examined in the same way, at most
``MAX_DIP_POINTS`` (6) corrected points per step and event. A terminal event ends the
branch at the first such zero. A ``g`` that only touches zero (a double root) gives no
sign change at the corrected points and so no special point, unless a corrected point
hits ``g == 0`` exactly, which is reported as a located zero, as at a row. Not
detected: zeros the end slopes do not announce (e.g. more than one extremum of ``g``
inside a step whose end slopes point the same way, or an even number of extra zeros
next to a sign change); the built-in tests (fold, branch point, Hopf) rely on the sign
test at the rows only. Steps with a monotone event (end slopes of the same sign) or
without events cost nothing extra beyond the slope evaluation.

References: Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical
Equilibria*, SIAM, Ch. 3-4; Kuznetsov (2004), *Elements of Applied Bifurcation
Theory*, 3rd ed., Sec. 10.2.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from .linalg import inf_norm as _inf_norm
from .typing import ComplexArray, FloatArray

Direction = Literal["both", "up", "down"]


@dataclass(frozen=True)
class Event:
    """A user event: a zero of ``fn(x, p)`` along the branch.

    Parameters
    ----------
    name : str
        Label of the special points it creates (``SpecialPoint.label``).
    fn : callable
        ``fn(x, p) -> float`` with ``x`` the unknowns ``(N,)`` and ``p`` the free
        parameter.
    direction : {"both", "up", "down"}
        ``"up"``: only crossings from negative to positive (in branch order);
        ``"down"``: positive to negative.
    terminal : bool
        Stop the branch at the (located) event; the branch then ends with
        ``Status.EVENT`` and its last row is the event point. With two zeros inside
        one step (see below), the first one in branch order stops it.
    continuity : float, optional
        For a ``fn`` known to be continuous along the branch: a zero counts as located
        only if ``|fn|`` at the returned point is at most ``continuity`` times the mean
        slope of ``fn`` over the step times the final bracket, plus round-off
        (:func:`~continuation.locate.locate_zero`). A sign change across a jump of
        ``fn`` is then reported as bracketed, not located. Trial points are also kept
        on the branch (their tangent must be the branch's,
        :func:`~continuation.locate.tangent_agrees`), so ``fn`` is never evaluated on
        a crossing branch next to a branch point; where no trial point of the branch
        can be corrected, the zero is interpolated through the points found on it,
        located only within the tolerance by its error estimate. ``None`` (default):
        only the loose rule ``|fn| <= 1e-3 max(|fn_a|, |fn_b|)``.
    slope : bool
        Evaluate ``dg/ds`` at every row for the detection of zeros between rows of the
        same sign (default). ``False``: the sign test at the rows only, as for the
        built-in tests (fold, branch point, Hopf), which saves one evaluation of
        ``fn`` off the branch per row: for test functions as costly as a point
        (e.g. the Floquet tests of cycles).
    param_value : float, optional
        A point at this value of the continuation parameter (AUTO-07p's ``UZR``): give
        it instead of ``fn``, which is then ``p - param_value``. Its slope along the
        branch is the tangent's ``dp/ds`` (no extra evaluation), and a crossing inside
        a step along which ``p`` is monotone is found by one Newton solve at fixed
        ``p = param_value`` (as a parameter bound), exactly on the value, instead of
        the secant search of a general event.
    report : bool
        Log a warning where a zero is detected but not located (default). ``False``
        where the caller classifies the zeros afterwards and reports the ones it keeps
        itself (the codim-2 tests: a zero that is dropped there is no point at all).

    Notes
    -----
    A crossing is detected by a sign change of ``fn`` between consecutive rows, and
    also when ``fn`` has the same sign at both rows of a step but dips through zero
    between them: ``fn`` is evaluated once more per row, at a point ``O(sqrt(eps))``
    along the tangent (off the branch, so ``fn`` must be defined in a neighbourhood of
    it), for its slope along the branch; when the slopes announce an extremum whose
    cubic Hermite estimate nears zero, a point on the branch there decides, and both
    zeros are located (see the module docstring). ``fn`` should therefore be smooth
    along the branch for this second mechanism to see its dips.
    """

    name: str
    fn: Callable[[FloatArray, float], float] | None = None
    direction: Direction = "both"
    terminal: bool = False
    continuity: float | None = None
    param_value: float | None = None
    slope: bool = True
    report: bool = True

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name):
            raise ValueError(f"`name` must be a non-empty string, got {self.name!r}")
        for flag in ("terminal", "slope", "report"):
            if not isinstance(getattr(self, flag), (bool, np.bool_)):
                raise ValueError(
                    f"event {self.name!r}: `{flag}` must be True or False, "
                    f"got {getattr(self, flag)!r}"
                )
        if self.param_value is not None:
            if self.fn is not None:
                raise ValueError(f"event {self.name!r}: give `fn` or `param_value`, not both")
            if isinstance(self.param_value, bool) or not (
                isinstance(self.param_value, int | float | np.floating | np.integer)
                and math.isfinite(float(self.param_value))
            ):
                raise ValueError(
                    f"`param_value` of event {self.name!r} must be a finite number, "
                    f"got {self.param_value!r}"
                )
            object.__setattr__(self, "param_value", float(self.param_value))
            object.__setattr__(self, "fn", _ParamOffset(float(self.param_value)))
        if not callable(self.fn):
            raise ValueError(
                f"`fn` of event {self.name!r} must be callable (or give `param_value`)"
            )
        if self.direction not in ("both", "up", "down"):
            raise ValueError(
                f"`direction` of event {self.name!r} must be 'both', 'up' or 'down', "
                f"got {self.direction!r}"
            )
        if self.continuity is not None and not (
            isinstance(self.continuity, int | float) and self.continuity > 0
        ):
            raise ValueError(
                f"`continuity` of event {self.name!r} must be a positive number or None, "
                f"got {self.continuity!r}"
            )

    def value(self, x: FloatArray, p: float) -> float:
        """``fn(x, p)`` as a float."""
        return float(self.fn(x, p))  # type: ignore[misc]


@dataclass(frozen=True)
class _ParamOffset:
    """``fn(x, p) = p - value``: the test function of an event at a parameter value."""

    value: float

    def __call__(self, x: FloatArray, p: float) -> float:
        return float(p) - self.value


def crossed(g_a: float, g_b: float, direction: Direction = "both") -> bool:
    """True when ``g`` changes sign from ``g_a`` to ``g_b`` in ``direction``.

    A zero at the end row ``g_b == 0`` counts (a zero at ``g_a`` was counted in the
    previous step).
    """
    if not (math.isfinite(g_a) and math.isfinite(g_b)):
        return False
    if g_a == 0.0 or not (g_a * g_b < 0 or g_b == 0.0):
        return False
    if direction == "up":
        return g_a < 0
    if direction == "down":
        return g_a > 0
    return True


#: Relative step of the directional finite difference of an event function along the
#: unit tangent (:func:`event_slope`): ``sqrt(eps)`` times ``1 + max |u|``.
SLOPE_STEP = math.sqrt(float(np.finfo(float).eps))

#: A step whose event values have the same sign at both rows is refined only if the
#: cubic Hermite interpolant of ``g`` comes within this fraction of the smaller end
#: value ``min(|g_a|, |g_b|)`` of zero (or crosses it): a safety margin for the error of
#: the cubic, at the price of one corrected point in steps where ``g`` dips that far.
DIP_MARGIN = 0.1

#: At most this many points are corrected inside one step per event to resolve zeros
#: the rows' sign test misses.
MAX_DIP_POINTS = 6


def event_slope(event: Event, z: FloatArray, p: float, tau: FloatArray, g: float) -> float:
    """``dg/ds = grad g . tau`` of an event at a point, by one forward difference.

    ``g = fn(z, p)`` at the point, ``tau`` its unit tangent (``s`` the arclength);
    the difference step is ``h = SLOPE_STEP (1 + max |(z, p)|)`` (of the order of
    ``sqrt(eps)`` relative), i.e. one extra evaluation of ``fn`` off the branch, at
    ``(z, p) + h tau``, with a first-order error ``O(h g'')``, plenty for deciding
    whether ``g`` may have an interior extremum in a step. NaN if either value is not
    finite.
    """
    if not math.isfinite(g):
        return math.nan
    if event.param_value is not None:
        return float(tau[-1])  # g = p - value: dg/ds = dp/ds exactly
    if not event.slope:
        return math.nan  # (no dip test: the sign test at the rows only)
    h = SLOPE_STEP * (1.0 + max(abs(p), _inf_norm(z)))
    try:
        g_h = event.value(z + h * tau[:-1], p + h * float(tau[-1]))
    except (ValueError, ArithmeticError):
        return math.nan
    return (g_h - g) / h if math.isfinite(g_h) else math.nan


def hermite_dip(g0: float, g1: float, m0: float, m1: float, h: float) -> float | None:
    """Where ``g`` may cross zero twice between two values of the same sign.

    ``g0, g1``: values of ``g`` at the ends of an interval of length ``h``, of the same
    sign; ``m0, m1``: its derivatives there. When the derivatives point towards zero at
    the start and away from it at the end (``sign(g0) m0 < 0 < sign(g0) m1``), the cubic
    Hermite interpolant ``H`` of ``g`` has one interior extremum, at ``t* h``; if
    ``sign(g0) H(t* h) < DIP_MARGIN min(|g0|, |g1|)`` the interval may hold two zeros
    of ``g`` (or a double one): returns ``t*`` in ``(0, 1)``. None otherwise (in
    particular when ``g`` is monotone by its end derivatives).
    """
    if not (g0 * g1 > 0 and h > 0):
        return None
    sg = 1.0 if g0 > 0 else -1.0
    if not (sg * m0 < 0 < sg * m1):  # (False for NaN)
        return None
    M0, M1, d = m0 * h, m1 * h, g1 - g0
    c2 = 3.0 * d - 2.0 * M0 - M1
    c3 = M0 + M1 - 2.0 * d
    # H'(t) = M0 + 2 c2 t + 3 c3 t^2 changes sign once on (0, 1) (H'(0) = M0 and
    # H'(1) = M1 have opposite signs): its root there
    A, B, C = 3.0 * c3, 2.0 * c2, M0
    t = math.nan
    if abs(A) <= 1e-14 * (abs(B) + abs(C)):
        if B != 0.0:
            t = -C / B
    else:
        disc = max(B * B - 4.0 * A * C, 0.0)
        q = -0.5 * (B + math.copysign(math.sqrt(disc), B))
        for r in (q / A, C / q if q != 0.0 else math.nan):
            if 0.0 < r < 1.0:
                t = r
                break
    if not 0.0 < t < 1.0:
        t = 0.5
    H = g0 + t * (M0 + t * (c2 + t * c3))
    if sg * H < DIP_MARGIN * min(abs(g0), abs(g1)):
        return t
    return None


def fold_test(tau: FloatArray) -> float:
    """Fold test function: the parameter component ``dp/ds`` of the unit tangent."""
    return float(tau[-1])


def bp_test(sign: float, logdet: float, ref_logdet: float) -> float:
    """Branch-point test function ``det[G_z G_p; tau^T]`` scaled by ``exp(-ref_logdet)``."""
    return float(sign * math.exp(min(logdet - ref_logdet, 700.0)))


def complex_mask(eigs: ComplexArray, imag_tol: float) -> Any:
    """Boolean mask of eigenvalues with ``Im > imag_tol * max(1, |lambda|)``."""
    v = np.asarray(eigs, dtype=complex)
    ok = ~np.isnan(v)
    out = np.zeros(v.shape, dtype=bool)
    out[ok] = v[ok].imag > imag_tol * np.maximum(1.0, np.abs(v[ok]))
    return out


def critical_pair(eigs: ComplexArray, imag_tol: float) -> complex | None:
    """The eigenvalue with ``Im > 0`` nearest the imaginary axis, or None."""
    v = np.asarray(eigs, dtype=complex)
    m = complex_mask(v, imag_tol)
    if not np.any(m):
        return None
    c = v[m]
    return complex(c[int(np.argmin(np.abs(c.real)))])


def crossing_pair(
    eig_a: ComplexArray, eig_b: ComplexArray, imag_tol: float, eig_tol: float = 0.0
) -> tuple[complex | None, complex | None]:
    """Match the complex eigenvalue that crosses the imaginary axis between two rows.

    Among the eigenvalues with ``Im > 0`` at rows ``a`` and ``b``, the candidates are
    the pairs ``(lambda_a, lambda_b)`` whose classification as unstable changes
    (``Re > eig_tol`` at one row, not at the other: these change the unstable count
    that detects a Hopf point), or, if there is no such pair, those with real parts of
    opposite signs (or one zero); the chosen one is the closest candidate: eigenvalues
    move continuously, so the crossing pair is the nearest match. With the ``eig_tol``
    band a pair whose real part lies in ``(0, eig_tol]`` at one row and above
    ``eig_tol`` at the other is matched although both real parts are positive (the
    zero of ``Re`` then lies within ``|Re| / slope`` of that row, just outside the
    step). ``(None, None)`` if there is no candidate.

    Parameters
    ----------
    eig_a, eig_b : array_like, complex
        Eigenvalues at the two rows (NaN entries ignored).
    imag_tol : float
        As in :func:`complex_mask`.
    eig_tol : float
        Real parts ``<= eig_tol`` count as stable
        (:attr:`~continuation.settings.DetectionSettings.eig_tol`); 0 gives the plain
        sign rule.

    Returns
    -------
    (complex or None, complex or None)
    """
    va = np.asarray(eig_a, dtype=complex)
    vb = np.asarray(eig_b, dtype=complex)
    ca, cb = va[complex_mask(va, imag_tol)], vb[complex_mask(vb, imag_tol)]
    if ca.size == 0 or cb.size == 0:
        return None, None
    dist = np.abs(ca[:, None] - cb[None, :])
    cand = (ca.real[:, None] > eig_tol) != (cb.real[None, :] > eig_tol)
    if not np.any(cand):
        cand = ca.real[:, None] * cb.real[None, :] <= 0
        if not np.any(cand):
            return None, None
    dist[~cand] = np.inf
    i, j = np.unravel_index(int(np.argmin(dist)), dist.shape)
    return complex(ca[i]), complex(cb[j])


class HopfTest:
    """Test function for locating a Hopf point between rows ``a`` and ``b``.

    The crossing pair ``(lambda_a, lambda_b)`` is chosen by :func:`crossing_pair`
    (with the ``eig_tol`` band); at a trial point at fraction ``t`` of the step, the
    tracked eigenvalue is the complex one nearest ``(1 - t) lambda_a + t lambda_b``, and
    the test value is its real part. ``omega`` is its imaginary part.
    """

    def __init__(
        self, eig_a: ComplexArray, eig_b: ComplexArray, imag_tol: float, eig_tol: float = 0.0
    ) -> None:
        self.imag_tol = imag_tol
        self.eig_tol = eig_tol
        self.lam_a, self.lam_b = crossing_pair(eig_a, eig_b, imag_tol, eig_tol)

    @property
    def ok(self) -> bool:
        """Both rows have a critical pair, its real parts on both sides of zero.

        Real parts of opposite signs, or one of them inside the ``eig_tol`` band (``0 <= Re
        <= eig_tol``) and the other above.
        """
        if self.lam_a is None or self.lam_b is None:
            return False
        ra, rb = self.lam_a.real, self.lam_b.real
        return ra * rb <= 0 or (ra > self.eig_tol) != (rb > self.eig_tol)

    @property
    def outside(self) -> bool:
        """The real parts have the same (positive) sign, one of them in the ``eig_tol`` band.

        The zero of ``Re`` lies just outside the step, beyond that row.
        """
        return self.ok and self.lam_a.real * self.lam_b.real > 0  # type: ignore[union-attr]

    def track(self, eigs: ComplexArray, t: float) -> complex | None:
        """The tracked eigenvalue at fraction ``t`` in ``[0, 1]`` of the step."""
        if self.lam_a is None or self.lam_b is None:
            return None
        target = (1 - t) * self.lam_a + t * self.lam_b
        v = np.asarray(eigs, dtype=complex)
        m = complex_mask(v, self.imag_tol)
        if not np.any(m):
            m = ~np.isnan(v) & (v.imag >= 0)
            if not np.any(m):
                return None
        c = v[m]
        return complex(c[int(np.argmin(np.abs(c - target)))])


__all__ = [
    "Event",
    "HopfTest",
    "crossing_pair",
    "bp_test",
    "complex_mask",
    "critical_pair",
    "crossed",
    "event_slope",
    "fold_test",
    "hermite_dip",
]
