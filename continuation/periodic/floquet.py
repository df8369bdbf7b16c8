r"""Floquet multipliers of a collocated cycle and the test functions of its bifurcations.

The multipliers are the eigenvalues of the monodromy matrix obtained by condensing
the collocation Jacobian (:func:`~continuation.periodic.collocation.monodromy_factors`),
not by a new simulation. One multiplier of an autonomous cycle is exactly 1
(eigenvector :math:`f(x(0))`); it is identified by its eigenvector, removed, and its
distance from 1 is kept as an accuracy check (``trivial_error``).

Test functions of the codimension-one bifurcations of cycles (nontrivial multipliers
:math:`\mu_1 \dots \mu_{n-1}`; Kuznetsov 2004, *Elements of Applied Bifurcation
Theory*, Sec. 10.3; Govaerts 2000, Ch. 9):

======== ================================================ ===============================
point    condition                                        test function
======== ================================================ ===============================
LPC      a second multiplier at 1 (fold of cycles)        ``dp/ds`` (the driver's fold)
PD       a real multiplier at -1                          :math:`\prod_i (\mu_i + 1)`
NS       a complex pair on the unit circle                :math:`\prod_{i<j} (\mu_i\mu_j - 1)`
BPC      branch point of cycles                           the driver's bordered determinant
======== ================================================ ===============================

The NS product also vanishes at a *neutral saddle* cycle (real ``mu``, ``1/mu``); such
zeros are not reported as NS (:func:`is_neimark_sacker`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._types import ComplexArray, FloatArray


@dataclass(frozen=True)
class FloquetResult:
    """Floquet multipliers of one cycle.

    Attributes
    ----------
    multipliers : ndarray, shape (n - 1,) complex
        Nontrivial multipliers, by decreasing modulus.
    trivial : complex
        The multiplier identified as the trivial one (``1`` exactly for the exact cycle).
    trivial_error : float
        ``|trivial - 1|``: a measure of the discretisation error of the multipliers.
    """

    multipliers: ComplexArray
    trivial: complex
    trivial_error: float

    @property
    def all(self) -> ComplexArray:
        """All ``n`` multipliers, the trivial one first."""
        return np.concatenate([[self.trivial], self.multipliers])

    @property
    def n_unstable(self) -> int:
        """Number of nontrivial multipliers with ``|mu| > 1``."""
        return int(np.count_nonzero(np.abs(self.multipliers) > 1.0))


def monodromy(factors: FloatArray) -> FloatArray:
    """``Phi_{N-1} ... Phi_0`` from the transfer matrices ``(N, n, n)``."""
    Mo = np.eye(factors.shape[1])
    for P in factors:
        Mo = P @ Mo
    return Mo


def floquet(factors: FloatArray, f0: FloatArray) -> FloquetResult:
    """Multipliers from the transfer matrices; ``f0 = f(x(0))`` picks the trivial one.

    The trivial multiplier is the one whose eigenvector is most nearly parallel to
    ``f0`` among those within 0.5 of 1 (the nearest to 1 if none qualifies).
    """
    Mo = monodromy(factors)
    mu, V = np.linalg.eig(Mo)
    f0 = np.asarray(f0, dtype=float)
    nf = float(np.linalg.norm(f0))
    if nf > 0:
        align = np.abs(V.conj().T @ f0) / (np.linalg.norm(V, axis=0) * nf)
    else:
        align = np.zeros(mu.size)
    near = np.abs(mu - 1.0) < 0.5
    if np.any(near):
        score = np.where(near, align, -1.0)
        k = int(np.argmax(score))
    else:
        k = int(np.argmin(np.abs(mu - 1.0)))
    rest = np.delete(mu, k)
    rest = rest[np.argsort(-np.abs(rest), kind="stable")]
    return FloquetResult(np.asarray(rest, dtype=complex), complex(mu[k]), float(abs(mu[k] - 1)))


def exponents(mu: ComplexArray, imag_tol: float = 1e-8) -> ComplexArray:
    r"""Floquet exponents per period, :math:`\ln|\mu| + i \arg\mu`, for the driver's
    stability count.

    Real multipliers (``|Im mu| <= imag_tol |mu|``), negative ones included, give real
    exponents :math:`\ln|\mu|`, so that ``Re > 0`` counts each multiplier outside the
    unit circle once (a negative real multiplier would otherwise look like half of a
    complex pair). Zero multipliers give ``-inf`` replaced by ``-745`` (``ln`` of the
    smallest double).
    """
    mu = np.asarray(mu, dtype=complex)
    a = np.abs(mu)
    re = np.log(np.maximum(a, 5e-324))
    im = np.where(np.abs(mu.imag) > imag_tol * np.maximum(a, 1e-300), np.angle(mu), 0.0)
    return re + 1j * im


def pd_test(mu: ComplexArray) -> float:
    r"""Period-doubling test :math:`\prod_i (\mu_i + 1)` (real; zero at ``mu = -1``)."""
    return float(np.prod(np.asarray(mu, dtype=complex) + 1.0).real)


def ns_test(mu: ComplexArray) -> float:
    r"""Neimark-Sacker test :math:`\prod_{i<j} (\mu_i \mu_j - 1)` (real)."""
    mu = np.asarray(mu, dtype=complex)
    out = complex(1.0)
    for i in range(mu.size):
        for j in range(i + 1, mu.size):
            out *= mu[i] * mu[j] - 1.0
    return float(out.real)


def is_neimark_sacker(mu: ComplexArray, tol: float = 1e-3) -> tuple[bool, float]:
    """At a zero of :func:`ns_test`: a complex pair on the unit circle? Returns
    ``(True, theta)`` with the pair's argument ``theta`` in ``(0, pi)``, or
    ``(False, nan)`` (a neutral saddle: real ``mu``, ``1/mu``)."""
    mu = np.asarray(mu, dtype=complex)
    best = math.inf
    theta = math.nan
    for z in mu:
        if z.imag > tol and abs(abs(z) - 1.0) < best:
            best = abs(abs(z) - 1.0)
            theta = float(np.angle(z))
    return (best < tol, theta) if math.isfinite(best) else (False, math.nan)


__all__ = [
    "FloquetResult",
    "exponents",
    "floquet",
    "is_neimark_sacker",
    "monodromy",
    "ns_test",
    "pd_test",
]
