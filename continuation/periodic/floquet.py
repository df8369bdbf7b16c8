r"""Floquet multipliers of a collocated cycle and the test functions of its bifurcations.

The multipliers are the eigenvalues of the monodromy matrix obtained by condensing
the collocation Jacobian (:func:`~continuation.periodic.collocation.monodromy_factors`),
not by a new simulation. One multiplier of an autonomous cycle is exactly 1
(eigenvector :math:`f(x(0))`); it is deflated in the frames of ``f`` along the cycle
(:func:`floquet`) and the others come from a periodic QR iteration on the deflated
factors (:func:`periodic_eigenvalues`); the departure of the deflated structure from
exactness is kept as an accuracy check (``trivial_error``).

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

from .._jit import compiled
from ..typing import ComplexArray, FloatArray


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


#: Sweeps of the periodic QR iteration (:func:`periodic_eigenvalues`) at most.
MAX_SWEEPS = 60


def _blocks_of(D: FloatArray, Rd: list[FloatArray], Rlog: FloatArray, Rsign: FloatArray,
               Rprod: FloatArray) -> ComplexArray:  # fmt: skip
    """Eigenvalues of ``D R_prod`` (``D = Q_0^T Q_N``) by 1x1 / 2x2 diagonal blocks."""
    n = D.shape[0]
    out: list[complex] = []
    i = 0
    while i < n:
        if i + 1 < n and abs(D[i + 1, i]) > 1e-6:
            blk = D[i : i + 2, i : i + 2] @ Rprod[i : i + 2, i : i + 2]
            out.extend(complex(v) for v in np.linalg.eigvals(blk))
            i += 2
        else:
            out.append(complex(np.sign(D[i, i]) * Rsign[i] * math.exp(min(Rlog[i], 709.0))))
            i += 1
    return np.array(out, dtype=complex)


#: The factors are first multiplied in at most this many consecutive groups (each
#: product spans a fraction ``1/GROUPS`` of the period, so its own conditioning is
#: mild); the periodic QR iteration then runs on the group products.
GROUPS = 16


def grouped(factors: FloatArray, groups: int = GROUPS) -> FloatArray:
    """Products of consecutive factors in ``min(N, groups)`` groups, ``(G, n, n)``."""
    N = factors.shape[0]
    if N <= groups:
        return factors
    edges = np.linspace(0, N, groups + 1).round().astype(int)
    out = np.empty((groups,) + factors.shape[1:])
    for g in range(groups):
        P = factors[edges[g]]
        for j in range(edges[g] + 1, edges[g + 1]):
            P = factors[j] @ P
        out[g] = P
    return out


def dominance_basis(factors: FloatArray) -> FloatArray | None:
    r"""A start for :func:`periodic_eigenvalues`: an orthonormal ``Q``.

    Its first ``k`` columns span the invariant subspace of the ``k`` eigenvalues of largest
    modulus of the explicitly formed product (real and imaginary parts of the eigenvectors,
    by decreasing modulus, orthonormalised in that order), for every ``k``.

    The dominant invariant subspaces of the formed product are accurate even where its
    small eigenvalues have lost all digits, so the iteration starts next to its fixed
    point and converges in two or three sweeps instead of dozens (its rate is the
    ratio of neighbouring moduli); the eigenvalues themselves still come from the
    iteration. None if the product is not finite.
    """
    n = factors.shape[1]
    with np.errstate(over="ignore", invalid="ignore"):
        Mo = monodromy(factors)
    if not np.all(np.isfinite(Mo)):
        return None
    try:
        lam, V = np.linalg.eig(Mo)
    except np.linalg.LinAlgError:
        return None
    order = np.argsort(-np.abs(lam), kind="stable")
    cols: list[FloatArray] = []
    used = np.zeros(n, dtype=bool)
    for k in order:
        if used[k]:
            continue
        used[k] = True
        v = V[:, k]
        cols.append(v.real)
        if lam[k].imag != 0.0:
            free = np.flatnonzero(~used)
            if free.size:
                j = free[np.argmin(np.abs(lam[free] - np.conj(lam[k])))]
                used[j] = True
            cols.append(v.imag)
    Q, _ = np.linalg.qr(np.column_stack(cols[:n]))
    return Q  # type: ignore[no-any-return]


def periodic_eigenvalues(
    factors: FloatArray, Q_start: FloatArray | None = None
) -> tuple[ComplexArray, bool, FloatArray]:
    r"""Eigenvalues of :math:`\Phi_{N-1} \cdots \Phi_0` without forming the product.

    Periodic QR (simultaneous) iteration: one sweep computes
    :math:`\Phi_j Q_j = Q_{j+1} R_j` (``j = 0..N-1``) and restarts from
    :math:`Q_0 \leftarrow Q_N`; at convergence :math:`Q_0^T M Q_0 = (Q_0^T Q_N)
    R_{N-1} \cdots R_0` is block upper triangular and its real eigenvalues are the
    products of the diagonals of the ``R_j`` (summed in logarithms), accurate to
    working precision in each factor even when the multipliers span many orders of
    magnitude (near-homoclinic cycles, stiff systems) where the eigenvalues of the
    explicitly formed product lose all digits of the small ones. Complex pairs come
    from their 2x2 diagonal blocks. ``Q_start``: the first ``Q_0`` (e.g. the last one
    of a nearby cycle). Returns ``(eigenvalues, converged, Q_0)``.
    """
    N, n, _ = factors.shape
    Q = np.eye(n) if Q_start is None or Q_start.shape != (n, n) else Q_start
    prev = None
    for _ in range(MAX_SWEEPS):
        Q0 = Q
        Rlog = np.zeros(n)
        Rsign = np.ones(n)
        Rprod = np.eye(n)
        Rs = []
        for P in factors:
            Q, R = np.linalg.qr(P @ Q)
            d = np.diag(R)
            Rlog += np.log(np.maximum(np.abs(d), 5e-324))
            Rsign *= np.sign(d)
            Rprod = R @ Rprod
            Rs.append(R)
        D = Q0.T @ Q
        mu = _blocks_of(D, Rs, Rlog, Rsign, Rprod)
        if prev is not None and prev.shape == mu.shape:
            srt = np.sort_complex(mu)
            if np.all(np.abs(srt - np.sort_complex(prev)) <= 1e-11 * np.maximum(1.0, np.abs(srt))
                      + 1e-300):  # fmt: skip
                return mu, True, Q0
        prev = mu
    return mu, False, Q


#: The compiled deflation (:func:`continuation._jit.compiled`).
KERNELS = "continuation.periodic._floquet_jit"


def floquet(
    factors: FloatArray, f_nodes: FloatArray, memo: dict[str, object] | None = None
) -> FloquetResult:
    r"""Multipliers from the transfer matrices, the trivial one deflated.

    ``f_nodes``: ``f(x_j)`` at the mesh nodes ``j = 0..N`` (``(N + 1, n)``; the last is
    replaced by the first, the cycle being closed). For the exact cycle the
    variational flow maps :math:`f(x_j)` to :math:`f(x_{j+1})`, so in the orthonormal
    frames :math:`Q_j = [f_j / |f_j|, Q_j^\perp]` (:math:`Q_N = Q_0`)

    .. math:: Q_{j+1}^T \Phi_j Q_j = egin{pmatrix} r_j & b_j \ arepsilon_j &
              C_j \end{pmatrix}, \qquad arepsilon_j = 0 ,

    and the monodromy matrix is similar to a block-triangular product: the trivial
    multiplier is :math:`\prod r_j` and the nontrivial ones are the eigenvalues of
    :math:`C_{N-1} \cdots C_0`, computed by :func:`periodic_eigenvalues` (Lust 2001,
    "Improved numerical Floquet multipliers", Int. J. Bif. Chaos 11:2389-2410, on
    deflation and periodic Schur methods). The discretisation leaves
    :math:`arepsilon_j = O(h^{2m})`; it is neglected: near a homoclinic orbit the
    off-diagonal :math:`b_j` products grow like :math:`e^{\lambda_u T}` and would
    multiply these errors into the eigenvalues of the undeflated product.

    ``trivial_error`` is the larger of ``|prod r_j - 1|`` and the relative size
    ``max_j |epsilon_j| / |Phi_j|`` of the neglected coupling. ``memo``: a dict that
    keeps the last Schur basis (a warm start for the next, nearby cycle).
    """
    N, n, _ = factors.shape
    f = np.asarray(f_nodes, dtype=float)
    if n == 1:
        mu1 = complex(np.prod(factors[:, 0, 0]))
        return FloquetResult(np.zeros(0, dtype=complex), mu1, float(abs(mu1 - 1)))
    # frames, A_j = Q_{j+1}^T Phi_j Q_j, its blocks and the trivial product: one call
    C, log_r, sign_r, eps = compiled(KERNELS).deflate(factors, f[:N])
    trivial = sign_r * math.exp(min(log_r, 709.0))
    if n == 2:  # one nontrivial multiplier: the product of the 1x1 blocks
        c = C[:, 0, 0]
        lg = float(np.sum(np.log(np.maximum(np.abs(c), 5e-324))))
        sg = float(np.prod(np.where(c >= 0, 1.0, -1.0)))
        mu_1 = np.array([sg * math.exp(min(lg, 709.0))], dtype=complex)
        return FloquetResult(mu_1, complex(trivial), max(abs(trivial - 1.0), eps))
    Cg = grouped(C)
    Q_start = dominance_basis(Cg)
    if Q_start is None and memo is not None:
        Q_start = memo.get("Q")  # type: ignore[assignment]
    mu, ok, Q = periodic_eigenvalues(Cg, Q_start)
    if memo is not None:
        memo["Q"] = Q
    if not ok:
        mu = np.asarray(np.linalg.eigvals(monodromy(Cg)), dtype=complex)
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    return FloquetResult(np.asarray(mu, dtype=complex), complex(trivial),
                         max(abs(trivial - 1.0), eps))  # fmt: skip


def exponents(mu: ComplexArray, imag_tol: float = 1e-8) -> ComplexArray:
    r"""Floquet exponents per period, :math:`\ln|\mu| + i \arg\mu` (the driver's stability count).

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
    """At a zero of :func:`ns_test`: a complex pair on the unit circle?

    Returns ``(True, theta)`` with the pair's argument ``theta`` in ``(0, pi)``, or
    ``(False, nan)`` (a neutral saddle: real ``mu``, ``1/mu``).
    """
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
    "dominance_basis",
    "grouped",
    "is_neimark_sacker",
    "monodromy",
    "ns_test",
    "periodic_eigenvalues",
    "pd_test",
]
