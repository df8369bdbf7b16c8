"""Newton solvers and the bordered linear algebra under the continuation steps."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import scipy.sparse as sp

from continuation.algorithms.base import theta_norm, theta_weights
from continuation.algorithms.corrector import correct
from continuation.algorithms.point import make_point
from continuation.errors import ConvergenceError
from continuation.linalg import BorderedLU, _perm_parity_uncached, assemble_bordered_csc
from continuation.newton import newton
from continuation.settings import NewtonSettings
from continuation.status import Status


def test_newton_converges_quadratically():
    res = newton(lambda z: z**2 - 2.0, lambda z: np.diag(2 * z), np.array([1.0]))
    assert res.converged and res.status is Status.SUCCESS
    assert res.z[0] == pytest.approx(math.sqrt(2.0), abs=1e-15)
    # from 1.0: errors 8.6e-2, 2.5e-3, 2.1e-6, 1.6e-12, ~0 (quadratic), plus one check step
    assert res.iterations <= 6


def test_newton_sparse_jacobian():
    n = 50
    A = sp.diags([-np.ones(n - 1), 4 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1]).tocsc()
    b = np.arange(n, dtype=float)
    res = newton(lambda z: A @ z + z**3 - b, lambda z: A + sp.diags(3 * z**2), np.zeros(n))
    assert res.converged
    np.testing.assert_allclose(A @ res.z + res.z**3, b, atol=1e-10)


def test_newton_failure_status_and_throw():
    settings = NewtonSettings(max_iter=5)
    res = newton(lambda z: z**2 + 1.0, lambda z: np.diag(2 * z), np.array([0.5]), settings)
    assert not res.converged and res.status is Status.NEWTON_FAILED and not res.status.ok
    with pytest.raises(ConvergenceError):
        newton(
            lambda z: z**2 + 1.0, lambda z: np.diag(2 * z), np.array([0.5]), settings, throw=True
        )


@pytest.mark.parametrize("n", [1, 2, 5, 40])
def test_bordered_lu_solve_and_determinant(n):
    rng = np.random.default_rng(n)
    for _ in range(10):
        Gz = rng.standard_normal((n, n))
        Gp, c = rng.standard_normal(n), rng.standard_normal(n + 1)
        M = np.block([[Gz, Gp[:, None]], [c[None, :]]])
        sign, logdet = np.linalg.slogdet(M)
        b = rng.standard_normal(n + 1)
        for A in (Gz, sp.csc_matrix(Gz)):
            lu = BorderedLU(A, Gp, c)
            assert lu.sparse == sp.issparse(A)
            assert lu.sign == sign and lu.logabsdet == pytest.approx(logdet, abs=1e-9)
            np.testing.assert_allclose(M @ lu.solve(b), b, atol=1e-9)
    with pytest.raises(np.linalg.LinAlgError):
        BorderedLU(np.zeros((n, n)), np.zeros(n), np.ones(n + 1))


def test_assemble_bordered_csc_matches_bmat():
    rng = np.random.default_rng(0)
    A = sp.random(30, 30, density=0.1, format="csc", random_state=1)
    Gp, c = rng.standard_normal(30), rng.standard_normal(31)
    M = assemble_bordered_csc(A, Gp, c)
    ref = sp.bmat([[A, Gp[:, None]], [c[None, :30], np.array([[c[30]]])]]).toarray()
    np.testing.assert_array_equal(M.toarray(), ref)


def test_permutation_parity():
    for perm in itertools.permutations(range(5)):
        P = np.eye(5)[list(perm)]
        assert _perm_parity_uncached(np.array(perm)) == round(np.linalg.det(P))


class _Circle:
    """x^2 + p^2 - 1 = 0 as a bare ContinuationProblem."""

    free = "p"
    n_unknowns = 1

    def residual(self, z, p):
        return np.array([z[0] ** 2 + p**2 - 1])

    def jacobian(self, z, p):
        return np.array([[2 * z[0]]])

    def dp(self, z, p):
        return np.array([2 * p])

    def stability(self, z, p):
        return None

    def record(self, z, p):
        return {}


def test_bordered_corrector_solves_constraint():
    # constraint x - p = 0 (c = (1, -1), sigma = 0): solution x = p = 1/sqrt(2)
    res = correct(
        _Circle(), np.array([0.9, 0.5]), np.zeros(2), np.array([1.0, -1.0]), 0.0, NewtonSettings()
    )
    assert res.converged and res.iters <= 6
    assert abs(res.lin[0][0]) <= 1e-10  # the residual tolerance
    # |error| <= |G| / |dG/du| along the constraint line (|dG/du| = 2 sqrt(2) there)
    assert res.z[0] == pytest.approx(1 / math.sqrt(2), abs=1e-10 / 2.8)
    assert res.p == pytest.approx(res.z[0], abs=1e-15)  # linear constraint: exact


def test_corrector_accepts_round_off_floor():
    """A residual scaled by 1e8 cannot reach tol = 1e-10; the stagnation rule accepts it
    once the Newton step is below step_tol, and the solution is exact to round-off."""

    class Scaled(_Circle):
        def residual(self, z, p):
            return np.array([1e8 * (z[0] - 1.0 / 3.0)])

        def jacobian(self, z, p):
            return np.array([[1e8]])

        def dp(self, z, p):
            return np.array([0.0])

    res = correct(
        Scaled(),
        np.array([0.3, 2.0]),
        np.array([0.3, 2.0]),
        np.array([0.0, 1.0]),
        0.0,
        NewtonSettings(tol=1e-12),
    )
    assert res.converged
    assert res.z[0] == pytest.approx(1 / 3, abs=1e-15)
    # a start whose Newton correction is already tiny but whose residual is not is never
    # accepted without an iteration (the quadratic-rate rule needs an observed step)
    for exact in (True, False):
        near = correct(
            Scaled(),
            np.array([1 / 3 + 1e-11, 2.0]),
            np.array([0.3, 2.0]),
            np.array([0.0, 1.0]),
            0.0,
            NewtonSettings(tol=1e-12),
            exact=exact,
        )
        assert near.converged and near.iters >= 1
        assert near.z[0] == pytest.approx(1 / 3, abs=1e-15)


def test_tangent_and_branch_point_test_function():
    prob = _Circle()
    x = p = 1 / math.sqrt(2)
    w = theta_weights(1, 0.5)
    lin = (prob.residual(np.array([x]), p), prob.jacobian(np.array([x]), p), prob.dp([x], p))
    border = np.array([-1.0, 1.0])  # orient towards increasing p
    pt = make_point(np.array([x]), p, lin, border, w)
    assert theta_norm(pt.tau, w) == pytest.approx(1.0, abs=1e-15)
    assert pt.tau @ np.array([2 * x, 2 * p]) == pytest.approx(0.0, abs=1e-15)  # tangent
    assert pt.tau[1] > 0 and border @ pt.tau > 0
    M = np.block([[lin[1], lin[2][:, None]], [(w * pt.tau)[None, :]]])
    det = np.linalg.det(M)
    assert pt.bp_sign == np.sign(det)
    assert pt.bp_logdet == pytest.approx(math.log(abs(det)), abs=1e-12)


class _Generic:
    """A problem seen only through the ContinuationProblem protocol (no fast paths)."""

    def __init__(self, prob):
        self._p = prob
        self.free = prob.free
        self.n_unknowns = prob.n_unknowns

    def residual(self, z, p):
        return self._p.residual(z, p)

    def jacobian(self, z, p):
        return self._p.jacobian(z, p)

    def dp(self, z, p):
        return self._p.dp(z, p)


@pytest.mark.parametrize("exact", [True, False])
def test_fused_corrector_matches_generic(exact):
    """The fused CasADi path of the corrector (EquilibriumProblem) and the generic path
    (protocol methods only) follow the same iteration: same point, iterations, tangent."""
    from helpers import lorenz84

    from continuation.problem import EquilibriumProblem

    sys = lorenz84()
    prob = EquilibriumProblem(sys, sys.params(F=2.0, G=1.0), "F")
    assert prob.bordered_evaluator() is not None
    w = theta_weights(3, 0.5)
    u0 = np.array([1.9, 0.2, 0.1, 2.0])  # near an equilibrium at F = 2
    c = w * np.array([0.3, -0.2, 0.1, 0.9])
    out = []
    for problem in (prob, _Generic(prob)):
        res = correct(problem, u0, u0, c, 0.01, NewtonSettings(), exact=exact)
        assert res.converged
        out.append(res)
        pt = make_point(res.z, res.p, res.lin, c, w, lu=res.lu)
        out.append(pt)
    fused, pt_f, generic, pt_g = out
    assert fused.iters == generic.iters
    np.testing.assert_allclose(fused.u, generic.u, rtol=0, atol=1e-14)
    np.testing.assert_allclose(pt_f.tau, pt_g.tau, rtol=0, atol=1e-12)
    assert pt_f.bp_sign == pt_g.bp_sign
    G = sys.f(fused.z, prob.param_vector(fused.p))
    assert np.max(np.abs(G)) <= 1e-10
    assert float(c @ (fused.u - u0)) == pytest.approx(0.01, abs=1e-15)


def test_bordered_rcond_against_exact_condition_number():
    """Hager-Higham estimate of the column-scaled 1-norm condition (from the existing LU)
    against the exact value from the explicit inverse; badly scaled columns do not
    matter."""
    from continuation.linalg import bordered_rcond

    rng = np.random.default_rng(3)
    for n in (1, 2, 5, 20):
        for _ in range(5):
            Gz = rng.standard_normal((n, n)) * np.logspace(0, 6, n)[None, :]
            Gp = rng.standard_normal(n) * 1e9
            c = rng.standard_normal(n + 1)
            w = np.ones(n + 1)
            pt = make_point(np.zeros(n), 0.0, (np.zeros(n), Gz, Gp), c, w)
            M = np.block([[Gz, Gp[:, None]], [c[None, :]]])
            S = M / np.abs(M).max(axis=0)
            exact = 1 / (np.linalg.norm(S, 1) * np.linalg.norm(np.linalg.inv(S), 1))
            est = bordered_rcond(pt)
            # Hager's estimate of ||S^-1||_1 is a lower bound, usually exact
            assert exact <= est * (1 + 1e-9) and est <= 3 * exact
            pt_s = make_point(np.zeros(n), 0.0, (np.zeros(n), sp.csc_matrix(Gz), Gp), c, w)
            assert bordered_rcond(pt_s) == pytest.approx(est, rel=1e-6)


class _CubicSparse:
    """G_i(z, p) = z_i^3 + z_i - p (i < 6), sparse Jacobian, not a stability matrix;
    counts its linearisations and residuals."""

    n_unknowns = 6
    jacobian_is_stability = False

    def __init__(self) -> None:
        self.calls = {"linearize": 0, "residual": 0}

    def residual(self, z, p):
        self.calls["residual"] += 1
        return z**3 + z - p

    def linearize(self, z, p):
        self.calls["linearize"] += 1
        return z**3 + z - p, sp.csc_matrix(sp.diags(3 * z**2 + 1)), -np.ones(z.size)


@pytest.mark.parametrize("offset, early", [(1e-2, True), (3e-3, False), (1e-3, True)])
def test_predict_final_stops_one_linearisation_early_on_a_verified_residual(offset, early):
    # the point with z_i^3 + z_i = p on the border c . u = h: predict_final accepts it
    # one linearisation earlier than the plain iteration, on a residual it evaluated
    # itself, within the step tolerance of the exactly converged point
    newton_s = NewtonSettings(tol=1e-10, step_tol=1e-10)
    z_true = np.full(6, 0.8)  # the root of z^3 + z = p at p = 0.8^3 + 0.8
    p_true = 0.8**3 + 0.8
    u_true = np.append(z_true, p_true)
    c = np.zeros(7)
    c[-1] = 1.0  # natural parameter: p fixed
    rng = np.random.default_rng(1)
    u_pred = u_true + offset * rng.standard_normal(7)
    u_pred[-1] = p_true
    runs, points = {}, {}
    for pf in (False, True):
        prob = _CubicSparse()
        res = correct(prob, u_pred, np.zeros(7), c, p_true, newton_s, exact=False,
                      predict_final=pf)  # fmt: skip
        assert res.converged
        G = res.z**3 + res.z - res.p
        assert np.max(np.abs(G)) <= newton_s.tol  # the returned point solves G = 0
        if pf and early:  # lin's G and the residual norm are those of the returned point
            np.testing.assert_array_equal(res.lin[0], G)
            assert res.residual_norm == np.max(np.abs(G))
        np.testing.assert_allclose(res.u, u_true, rtol=0, atol=10 * newton_s.step_tol)
        runs[pf], points[pf] = prob.calls, res.u
    if early:  # the predicted correction is small enough here: one linearisation saved
        assert runs[True]["linearize"] == runs[False]["linearize"] - 1
        assert runs[True]["residual"] == 1
    else:  # it is not (3e-3: just above the bound): the plain iteration, unchanged
        assert runs[True] == runs[False]
        np.testing.assert_array_equal(points[True], points[False])
