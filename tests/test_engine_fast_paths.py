"""The engine's fast paths give the values of the plain computations they replace.

* :func:`continuation.stability.dense_stability` (one ``dgeev`` call, counts from its
  real and imaginary parts) against ``numpy.linalg.eigvals`` + ``sort_eigenvalues`` +
  ``count_unstable``, an independent route through NumPy's own ``dgeev`` driver;
* the norms ``(max |r|, r . r, max |u|)`` returned by the fused CasADi bordered
  evaluator against NumPy on its residual and input buffers;
* the corrector with and without those norms (an evaluator stripped of them) gives the
  same branch, bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import block_diag

from continuation.driver import continue_branch
from continuation.params import Params
from continuation.problem import EquilibriumProblem
from continuation.settings import ContinuationSettings
from continuation.stability import count_unstable, dense_stability, sort_eigenvalues
from continuation.system import System


def _reference(J: np.ndarray, eig_tol: float, imag_tol: float) -> tuple[np.ndarray, tuple]:
    ev = sort_eigenvalues(np.linalg.eigvals(J))
    return ev, count_unstable(ev, eig_tol, imag_tol)


@pytest.mark.parametrize("n", [1, 2, 5, 8, 33, 40])
def test_dense_stability_matches_numpy(n: int) -> None:
    rng = np.random.default_rng(n)
    for shift in (-3.0, 0.0, 3.0):
        J = rng.standard_normal((n, n)) + shift * np.eye(n)
        ev, counts = dense_stability(J, 1e-10, 1e-8)
        ref, ref_counts = _reference(J, 1e-10, 1e-8)
        assert counts == ref_counts
        np.testing.assert_allclose(ev, ref, rtol=1e-10, atol=1e-12 * max(1, abs(ref).max()))
        # sorted by decreasing real part (the order count_unstable's callers rely on)
        assert np.all(np.diff(ev.real) <= 1e-12 * max(1.0, abs(ev).max()))


def test_dense_stability_complex_pairs_and_tolerances() -> None:
    """Block-diagonal matrix with known spectrum: 1 +- 2i, 0.5, -1 +- 1i, 1e-12, -3."""
    blocks = [
        np.array([[1.0, -2.0], [2.0, 1.0]]),
        np.array([[0.5]]),
        np.array([[-1.0, -1.0], [1.0, -1.0]]),
        np.array([[1e-12]]),  # below eig_tol: counts as stable
        np.array([[-3.0]]),
    ]
    J = block_diag(*blocks)
    ev, counts = dense_stability(J, 1e-10, 1e-8)
    assert counts == (1, 1)
    expected = np.array([1 + 2j, 1 - 2j, 0.5, 1e-12, -1 + 1j, -1 - 1j, -3.0])
    np.testing.assert_allclose(ev, expected, atol=1e-13)
    # a huge imag_tol makes the pair count as two real unstable eigenvalues
    assert dense_stability(J, 1e-10, 10.0)[1] == (3, 0)


def test_dense_stability_rejects_nan() -> None:
    with pytest.raises(np.linalg.LinAlgError):
        dense_stability(np.array([[np.nan, 0.0], [0.0, 1.0]]))


def _cubic3() -> System:
    def rhs(x, p, ops):  # noqa: ANN001, ANN202
        return ops.stack(
            [p[0] - x[0] ** 3 + 3.0 * x[0], -x[1] + 0.2 * ops.tanh(x[0]), -2.0 * x[2] + x[1]]
        )

    return System(rhs, ("a", "b", "c"), ("mu",))


def test_bordered_evaluator_norms_match_numpy() -> None:
    sys = _cubic3()
    ev = sys.bordered_evaluator(0, [0.3])
    assert ev is not None and ev.norms is not None
    rng = np.random.default_rng(0)
    for _ in range(5):
        ev.u[:] = rng.standard_normal(4) * 3
        c = rng.standard_normal(4)
        ev.set_border(c, 0.7)
        ev()
        r = ev.r
        rn, rr, un, gn, mm = ev.norms.tolist()
        assert rn == np.abs(r).max()
        assert rr == pytest.approx(float(r @ r), rel=1e-14)
        assert un == np.abs(ev.u).max()
        assert gn == np.abs(r[:-1]).max()  # the residual of f alone, without the border row
        assert mm == pytest.approx(float(np.sum(ev.M**2)), rel=1e-14)
    ev.u[:] = [np.nan, 0.0, 0.0, 0.0]
    ev()
    assert not ev.norms[1] < np.inf  # r . r flags the non-finite residual
    assert not ev.norms[4] < np.inf  # and sum M_ij^2 the non-finite matrix


class _Stripped:
    """A fused evaluator that does not offer the norms (as a third-party one may not)."""

    def __init__(self, ev) -> None:  # noqa: ANN001
        self._ev = ev  # (keeps the wrapped buffers alive)
        self.u, self.r, self.M, self.c, self.h = ev.u, ev.r, ev.M, ev.c, ev.h
        self.norms = None

    def __call__(self) -> None:
        self._ev()

    def lin(self):  # noqa: ANN201
        return self._ev.lin()


class _NoNorms(EquilibriumProblem):
    """The same problem, its fused evaluator without the norms output."""

    def bordered_evaluator(self):  # noqa: ANN201
        ev = self.__dict__.get("_bordered")
        if not isinstance(ev, _Stripped):
            ev = _Stripped(super().bordered_evaluator())
            object.__setattr__(self, "_bordered", ev)  # the corrector's cache slot
        return ev


def test_corrector_same_branch_with_and_without_norms() -> None:
    sys = _cubic3()
    par = Params(("mu",), [-4.0])
    x0 = np.array([-2.1038034, -0.19409, -0.097])
    st = ContinuationSettings(ds=0.05, ds_max=0.2, p_min=-4.0, p_max=4.0, max_steps=300)
    a = continue_branch(EquilibriumProblem(sys, par, "mu"), x0, -4.0, settings=st)
    plain = _NoNorms(sys, par, "mu")
    b = continue_branch(plain, x0, -4.0, settings=st)
    assert isinstance(plain.__dict__["_bordered"], _Stripped)
    assert a.status == b.status and a.status.ok
    assert len(a) == len(b)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.p, b.p)
    assert [(s.kind, s.p) for s in a.special_points] == [(s.kind, s.p) for s in b.special_points]
    # the folds of mu - a^3 + 3a: a = +-1, mu = -+2 (closed form)
    folds = sorted(s.p for s in a.special_points if s.kind.value == "fold")
    np.testing.assert_allclose(folds, [-2.0, 2.0], atol=1e-9)


def test_bordered_lu_sign_small_dense_against_slogdet() -> None:
    """Sign of det M of small dense bordered matrices (the branch-point test) against
    ``numpy.linalg.slogdet``, including entries spread over 1e-150..1e150 where the
    product of the pivots over- or underflows."""
    from continuation.linalg import BorderedLU

    rng = np.random.default_rng(3)
    checked = 0
    for n in range(1, 12):
        for k in range(30):
            Gz = rng.standard_normal((n, n))
            if k % 2:
                Gz *= 10.0 ** rng.uniform(-150, 150, size=(n, n))
            Gp, c = rng.standard_normal(n), rng.standard_normal(n + 1)
            M = np.block([[Gz, Gp[:, None]], [c[None, :]]])
            sign_ref, logdet = np.linalg.slogdet(M)
            if sign_ref == 0 or not np.isfinite(logdet):
                continue
            assert BorderedLU(Gz, Gp, c).sign == sign_ref
            checked += 1
    assert checked > 250


@pytest.mark.parametrize("n", [1, 4, 8, 40])
def test_dense_stability_real_spectrum_same_order(n: int) -> None:
    """All-real spectra (symmetric, and triangular with repeated eigenvalues) take the
    float-sort path: exactly the order of ``sort_eigenvalues`` on the same dgeev output."""
    from continuation.stability import _dense_eigvals

    rng = np.random.default_rng(10 + n)
    A = rng.standard_normal((n, n))
    tri = np.triu(A, 1) + np.diag(np.repeat([0.5, -1.0, 2.0, 0.0], n)[:n])
    for J in (A + A.T, tri):
        ev, counts = dense_stability(np.asfortranarray(J), 1e-10, 1e-8)
        ref = sort_eigenvalues(_dense_eigvals(np.asfortranarray(J)))
        np.testing.assert_array_equal(ev, ref)
        assert counts == count_unstable(ref, 1e-10, 1e-8)
        assert ev.dtype == complex and ev.shape == (n,)
