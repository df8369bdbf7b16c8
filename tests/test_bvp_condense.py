"""Condensation of the collocation stages (continuation.bvp.condense) against SuperLU.

Reference: SciPy's general sparse LU of the same matrices (solutions, transposed
solutions, sign and log-modulus of the determinant); the condensed factorisation
is exact algebra, so they agree to round-off.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from continuation.bvp.condense import CondensedLU, StageCondenser
from continuation.linalg import BorderedLU, _perm_parity, assemble_bordered_csc
from tests.connection_problems import cir_connection


@pytest.fixture(scope="module")
def linearised():
    res = cir_connection()
    prob = res.problem.with_vary("beta")
    g, J, gp = prob.linearize(res.z, 0.6)
    return J, gp


def _det_sign_log(lu):
    d = lu.U.diagonal()
    parity = _perm_parity(lu.perm_r) * _perm_parity(lu.perm_c)
    sign = -parity if np.count_nonzero(d < 0) % 2 else parity
    return sign, float(np.log(np.abs(d)).sum())


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bordered_solves_and_determinant_match_superlu(linearised, seed):
    J, gp = linearised
    rng = np.random.default_rng(seed)
    c = rng.standard_normal(J.shape[0] + 1)
    lu = BorderedLU(J, gp, c)
    assert isinstance(lu._lu, CondensedLU)  # the hook was taken
    ref = spla.splu(assemble_bordered_csc(J, gp, c))
    b = rng.standard_normal(J.shape[0] + 1)
    for trans, t in ((False, "N"), (True, "T")):
        x = lu.solve(b, trans=trans)
        x_ref = ref.solve(b, trans=t)
        assert np.max(np.abs(x - x_ref)) <= 1e-10 * np.max(np.abs(x_ref))
    sign, logdet = _det_sign_log(ref)
    assert lu.sign == sign
    assert lu.logabsdet == pytest.approx(logdet, rel=1e-12)
    # flipping the sign of the border row flips the determinant
    assert BorderedLU(J, gp, -c).sign == -sign


def test_newton_system_and_multiple_rhs(linearised):
    J, _ = linearised
    rng = np.random.default_rng(3)
    B = rng.standard_normal((J.shape[0], 3))
    fac = J.condensed_lu(J)
    X = fac.solve(B)
    assert np.max(np.abs(J @ X - B)) <= 1e-10 * np.max(np.abs(B))


def test_coupled_blocks_fall_back():
    # a coupling between the stage blocks: not condensable, the caller's general LU
    D = sp.random(6, 6, density=0.6, random_state=0).toarray() + np.eye(6)
    D[0, 3] = 1.0
    A = sp.csc_matrix(D)
    A.sum_duplicates()
    cond = StageCondenser(np.array([[0, 1], [2, 3]]), np.array([[0, 1], [2, 3]]))
    assert cond.factor(A) is None


def test_singular_block_falls_back():
    A = sp.csc_matrix(np.array([[0.0, 0, 1], [0, 1, 0], [1, 0, 1]]))
    A.sum_duplicates()
    cond = StageCondenser(np.array([[0]]), np.array([[0]]))  # block A[0, 0] = 0
    assert cond.factor(A) is None
    x = spla.splu(A).solve(np.ones(3))
    assert np.allclose(A @ x, 1.0)


def _assert_matches_superlu(fac, M, B):
    """Solves, transposed solves and the determinant of ``fac`` against SuperLU of ``M``."""
    ref = spla.splu(M)
    for t in ("N", "T"):
        X, X_ref = fac.solve(B, trans=t), ref.solve(B, trans=t)
        assert np.max(np.abs(X - X_ref)) <= 1e-10 * np.max(np.abs(X_ref))
    d, parity = fac.diag_parity()
    sign = -parity if np.count_nonzero(d < 0) % 2 else parity
    ref_sign, ref_log = _det_sign_log(ref)
    assert sign == ref_sign
    assert float(np.log(np.abs(d)).sum()) == pytest.approx(ref_log, rel=1e-12)


@pytest.mark.parametrize("sparse_min", [0, 10**9], ids=["sparse Schur", "dense Schur"])
def test_both_factorisations_of_the_schur_complement_match_superlu(
    linearised, sparse_min, monkeypatch
):
    # the Schur complement is factorised by SuperLU (band, natural order) from
    # SPARSE_SCHUR_MIN unknowns on, else by LAPACK: each against SuperLU of the whole matrix
    import continuation.bvp.condense as cd

    J, gp = linearised
    monkeypatch.setattr(cd, "SPARSE_SCHUR_MIN", sparse_min)
    owner = J.condensed_lu.__self__
    fresh = StageCondenser(owner.rows_s, owner.cols_s)  # no cached structure
    rng = np.random.default_rng(7)
    c = rng.standard_normal(J.shape[0] + 1)
    M = assemble_bordered_csc(J, gp, c)
    fac = fresh.factor(M)
    assert isinstance(fac, CondensedLU)
    assert (fac._piv is None) == (sparse_min == 0)  # the path asked for was taken
    _assert_matches_superlu(fac, M, rng.standard_normal((M.shape[0], 2)))


def test_block_factorisation_matches_superlu(linearised):
    # the stage blocks are factorised by the compiled kernel (block LU, Hager's condition
    # estimate, determinants from the pivots; Numba is required): against SuperLU of the
    # whole matrix, solves, transposed solves and the determinant
    J, gp = linearised
    owner = J.condensed_lu.__self__
    fresh = StageCondenser(owner.rows_s, owner.cols_s)
    rng = np.random.default_rng(11)
    c = rng.standard_normal(J.shape[0] + 1)
    M = assemble_bordered_csc(J, gp, c)
    fac = fresh.factor(M)
    assert isinstance(fac, CondensedLU)
    _assert_matches_superlu(fac, M, rng.standard_normal((M.shape[0], 3)))


def test_an_ill_conditioned_block_falls_back():
    # two 3 x 3 stage blocks coupled through one rest unknown; block 1 has condition
    # number about 1e13 > MAX_BLOCK_COND: no condensation (the caller's general LU)
    rng = np.random.default_rng(5)
    Q1, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    Q2, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    D = np.zeros((7, 7))
    D[0:3, 0:3] = np.eye(3) + 0.1 * rng.standard_normal((3, 3))
    D[3:6, 3:6] = Q1 @ np.diag([1.0, 1.0, 1e-13]) @ Q2
    D[0:6, 6] = 1.0
    D[6, 0:6] = 1.0
    D[6, 6] = 2.0
    A = sp.csc_matrix(D)
    A.sum_duplicates()
    cond = StageCondenser(np.array([[0, 1, 2], [3, 4, 5]]), np.array([[0, 1, 2], [3, 4, 5]]))
    assert cond.factor(A) is None
    D[3:6, 3:6] = Q1 @ np.diag([1.0, 1.0, 1e-3]) @ Q2  # well conditioned: condensed
    A = sp.csc_matrix(D)
    A.sum_duplicates()
    fac = StageCondenser(np.array([[0, 1, 2], [3, 4, 5]]), np.array([[0, 1, 2], [3, 4, 5]]))
    lu = fac.factor(A)
    assert lu is not None
    b = rng.standard_normal(7)
    assert np.allclose(D @ lu.solve(b), b, rtol=0, atol=1e-12)
