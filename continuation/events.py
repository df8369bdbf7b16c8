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
user       ``fn(x, p)`` changes sign (``direction``)      ``fn(x, p)``
========== ============================================= ===============================

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

from ._types import ComplexArray, FloatArray

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
        ``Status.EVENT`` and its last row is the event point.
    continuity : float, optional
        For a ``fn`` known to be continuous along the branch: a zero counts as located
        only if ``|fn|`` at the returned point is at most ``continuity`` times the mean
        slope of ``fn`` over the step times the final bracket, plus round-off
        (:func:`~continuation.locate.locate_zero`). A sign change across a jump of
        ``fn`` is then reported as bracketed, not located. ``None`` (default): only the
        loose rule ``|fn| <= 1e-3 max(|fn_a|, |fn_b|)``.
    """

    name: str
    fn: Callable[[FloatArray, float], float]
    direction: Direction = "both"
    terminal: bool = False
    continuity: float | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name):
            raise ValueError(f"`name` must be a non-empty string, got {self.name!r}")
        if not callable(self.fn):
            raise ValueError(f"`fn` of event {self.name!r} must be callable")
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
        return float(self.fn(x, p))


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
        """Both rows have a critical pair, with real parts of opposite signs or one of
        them inside the ``eig_tol`` band (``0 <= Re <= eig_tol``) and the other above."""
        if self.lam_a is None or self.lam_b is None:
            return False
        ra, rb = self.lam_a.real, self.lam_b.real
        return ra * rb <= 0 or (ra > self.eig_tol) != (rb > self.eig_tol)

    @property
    def outside(self) -> bool:
        """The real parts have the same (positive) sign, one of them in the ``eig_tol``
        band: the zero of ``Re`` lies just outside the step, beyond that row."""
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
    "fold_test",
]
