"""The periodic QR iteration started from the dominant subspaces of the formed product
(continuation.periodic.floquet.dominance_basis): converged, and as accurate as the
iteration itself, against products with known eigenvalues."""

from __future__ import annotations

import numpy as np
from scipy.linalg import block_diag

from continuation.periodic.floquet import dominance_basis, periodic_eigenvalues


def _rot(r: float, theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return r * np.array([[c, -s], [s, c]])


def _factors(blocks: list[np.ndarray], G: int, seed: int = 0) -> np.ndarray:
    """``G`` factors ``V_{j+1} D V_j^{-1}`` (``V_G = V_0``) whose product is similar to
    the block-diagonal ``D^G`` (``D`` holds the ``G``-th roots of the blocks)."""
    rng = np.random.default_rng(seed)
    D = block_diag(*blocks)
    n = D.shape[0]
    V = [np.eye(n) + 0.3 * rng.standard_normal((n, n)) for _ in range(G)]
    V.append(V[0])
    return np.array([V[j + 1] @ D @ np.linalg.inv(V[j]) for j in range(G)])


def _close(mu: np.ndarray, ref: np.ndarray, rtol: float) -> bool:
    mu = np.sort_complex(np.asarray(mu, dtype=complex))
    ref = np.sort_complex(np.asarray(ref, dtype=complex))
    return bool(np.all(np.abs(mu - ref) <= rtol * np.abs(ref)))


def test_two_pairs_of_nearly_equal_modulus_converge_from_the_start():
    """Moduli 0.7072 and 0.7054 (ratio 0.9975, as the ship's cycle at Fn 0.1): from the
    identity the iteration does not converge in its sweeps; from the dominant basis it
    does, to the exact eigenvalues."""
    G = 16
    r1, t1, r2, t2 = 0.7072, 2.0, 0.7054, 0.2
    blocks = [_rot(r1 ** (1 / G), t1 / G), _rot(r2 ** (1 / G), t2 / G),
              np.array([[0.9139 ** (1 / G)]]), np.array([[1.088e-5 ** (1 / G)]])]  # fmt: skip
    F = _factors(blocks, G)
    ref = np.array([r1 * np.exp(1j * t1), r1 * np.exp(-1j * t1), r2 * np.exp(1j * t2),
                    r2 * np.exp(-1j * t2), 0.9139, 1.088e-5])  # fmt: skip
    mu0, ok0, _ = periodic_eigenvalues(F, None)
    assert not ok0  # (the slow case this start is for)
    mu, ok, _ = periodic_eigenvalues(F, dominance_basis(F))
    assert ok
    assert _close(mu, ref, 1e-9)


def test_widely_spread_multipliers_keep_their_relative_accuracy():
    """Multipliers from 3 down to 1e-40: the formed product has lost the small ones
    (its eigenvalues are wrong by more than 100 %), the iteration started from it still
    gives every one to 1e-9 relative."""
    G = 16
    vals = [3.0, 0.5, 1e-12, 1e-25, 1e-40]
    F = _factors([np.array([[v ** (1 / G)]]) for v in vals], G, seed=1)
    prod = np.eye(5)
    for P in F:
        prod = P @ prod
    naive = np.sort(np.abs(np.linalg.eigvals(prod)))
    assert abs(naive[0] - 1e-40) > 1e-40  # the formed product cannot resolve it
    mu, ok, _ = periodic_eigenvalues(F, dominance_basis(F))
    assert ok
    assert _close(mu, np.array(vals), 1e-9)


def test_no_start_for_a_product_that_overflows():
    F = np.array([np.eye(3) * 1e200, np.eye(3) * 1e200])
    assert dominance_basis(F) is None
