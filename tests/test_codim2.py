"""Two-parameter continuation of fold and Hopf curves (continuation.codim2).

Every numerical claim is checked against a closed form derived in the test (with
the derivation in the docstring), a published result (cited), or finite
differences.
"""

from __future__ import annotations

import numpy as np
import pytest

from continuation.codim2 import FoldProblem, HopfProblem
from continuation.differentiation import fd_jacobian
from continuation.errors import ConvergenceError
from continuation.system import System

# --------------------------------------------------------------------------- systems


def cusp_rhs(x, p, ops):
    """Cusp normal form x' = b1 + b2 x - x^3 (Kuznetsov 2004, Sec. 8.2)."""
    b1, b2 = p[0], p[1]
    return ops.stack([b1 + b2 * x[0] - x[0] ** 3])


CUSP = System(cusp_rhs, ("x",), ("b1", "b2"), name="cusp")
CUSP_NUMPY = System(
    lambda x, p: np.array([p[0] + p[1] * x[0] - x[0] ** 3]), ("x",), ("b1", "b2"), name="cuspnp"
)


def bt_rhs(x, p, ops):
    """Bogdanov-Takens normal form x' = y, y' = b1 + b2 x + x^2 + s x y (Kuznetsov Sec. 8.4)."""
    b1, b2, s = p[0], p[1], p[2]
    return ops.stack([x[1], b1 + b2 * x[0] + x[0] ** 2 + s * x[0] * x[1]])


BT = System(bt_rhs, ("x", "y"), ("b1", "b2", "s"), defaults={"b1": 0.0, "b2": 0.0, "s": -1.0})


def brusselator_rhs(x, p, ops):
    """Brusselator x' = A - (B+1) x + x^2 y, y' = B x - x^2 y (Prigogine & Lefever 1968)."""
    A, B = p[0], p[1]
    return ops.stack([A - (B + 1) * x[0] + x[0] ** 2 * x[1], B * x[0] - x[0] ** 2 * x[1]])


BRUSSELATOR = System(brusselator_rhs, ("x", "y"), ("A", "B"))


def cstr_rhs(x, p, ops):
    """CSTR with a first-order exothermic reaction, infinite activation energy limit.

    x1' = -x1 + Da (1 - x1) exp(x2),  x2' = -x2 + B Da (1 - x1) exp(x2) - beta x2
    (Uppal, Ray & Poore 1974, "On the dynamic behavior of continuous stirred tank
    reactors", Chem. Eng. Sci. 29, 967-985, model (2.4) with gamma -> infinity and
    coolant temperature x2c = 0).
    """
    Da, B, beta = p[0], p[1], p[2]
    r = Da * (1 - x[0]) * ops.exp(x[1])
    return ops.stack([-x[0] + r, -x[1] + B * r - beta * x[1]])


CSTR = System(cstr_rhs, ("x1", "x2"), ("Da", "B", "beta"))


def zero_hopf_rhs(x, p, ops):
    """Fold-Hopf unfolding x1' = b1 - x1^2, (x2 + i x3)' = (b2 + x1 + i)(x2 + i x3)."""
    b1, b2 = p[0], p[1]
    mu = b2 + x[0]
    return ops.stack([b1 - x[0] ** 2, mu * x[1] - x[2], x[1] + mu * x[2]])


ZERO_HOPF = System(zero_hopf_rhs, ("x1", "x2", "x3"), ("b1", "b2"))


def bautin_rhs(x, p, ops):
    """Bautin normal form: z' = (b1 + i) z + b2 z|z|^2 - z|z|^4, z = x + i y."""
    b1, b2 = p[0], p[1]
    r2 = x[0] ** 2 + x[1] ** 2
    g = b1 + b2 * r2 - r2**2
    return ops.stack([g * x[0] - x[1], x[0] + g * x[1]])


BAUTIN = System(bautin_rhs, ("x", "y"), ("b1", "b2"))


# --------------------------------------------------------------------------- helpers


def _fd_check(prob, z, p):
    """Max relative error of the exact dG/dz and dG/dp against central differences."""
    Jz = np.asarray(prob.jacobian(z, p))
    Jz_fd = fd_jacobian(lambda w: prob.residual(w, p), z)
    Jp = prob.dp(z, p)
    Jp_fd = fd_jacobian(lambda q: prob.residual(z, q[0]), np.array([p])).ravel()
    scale = max(1.0, np.abs(Jz_fd).max())
    return np.abs(Jz - Jz_fd).max() / scale, np.abs(Jp - Jp_fd).max() / max(1.0, np.abs(Jp).max())


# --------------------------------------------------------------------------- problems


class TestAugmentedJacobians:
    """Exact (CasADi) Jacobians of the augmented systems against central differences."""

    @pytest.mark.parametrize(
        ("system", "free1", "free2", "params"),
        [
            (CUSP, "b1", "b2", {"b1": 0.3, "b2": 1.2}),
            (BT, "b1", "b2", {"b1": 0.1, "b2": -0.4, "s": -1.0}),
            (CSTR, "Da", "beta", {"Da": 0.08, "B": 14.0, "beta": 2.5}),
            (ZERO_HOPF, "b2", "b1", {"b1": 0.2, "b2": -0.3}),
        ],
    )
    def test_fold_jacobian(self, system, free1, free2, params):
        prob = FoldProblem(system, system.params(**params), free1, free2)
        rng = np.random.default_rng(1)
        z = rng.normal(size=prob.n_unknowns) * 0.5
        z[: prob.n] = np.abs(z[: prob.n]) * 0.3
        ez, ep = _fd_check(prob, z, params[free2] + 0.1)
        assert ez < 1e-8 and ep < 1e-8

    @pytest.mark.parametrize(
        ("system", "free1", "free2", "params"),
        [
            (BRUSSELATOR, "B", "A", {"A": 1.3, "B": 2.1}),
            (BT, "b1", "b2", {"b1": 0.1, "b2": -0.4, "s": 1.0}),
            (CSTR, "Da", "beta", {"Da": 0.08, "B": 14.0, "beta": 2.5}),
            (BAUTIN, "b1", "b2", {"b1": 0.1, "b2": 0.3}),
        ],
    )
    def test_hopf_jacobian(self, system, free1, free2, params):
        n = system.n_states
        c = np.linspace(1.0, 2.0, n)
        prob = HopfProblem(system, system.params(**params), free1, free2, c=c, sigma=0.7)
        rng = np.random.default_rng(2)
        z = rng.normal(size=prob.n_unknowns) * 0.5
        z[:n] = np.abs(z[:n]) * 0.3
        ez, ep = _fd_check(prob, z, params[free2] - 0.05)
        assert ez < 1e-8 and ep < 1e-8

    def test_linearize_matches_parts(self):
        prob = HopfProblem(
            BRUSSELATOR, BRUSSELATOR.params(A=1.0, B=2.0), "B", "A", c=[1.0, 0.5], sigma=0.3
        )
        z = np.array([1.1, 1.9, 2.2, 0.9, 0.3, -0.7])
        G, Gz, Gp = prob.linearize(z, 1.1)
        np.testing.assert_allclose(G, prob.residual(z, 1.1), rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(Gz, prob.jacobian(z, 1.1), rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(Gp, prob.dp(z, 1.1), rtol=1e-14, atol=1e-14)

    def test_sparse_jacobian_equals_dense(self):
        prob = FoldProblem(CSTR, CSTR.params(Da=0.1, B=14.0, beta=3.0), "Da", "beta", sparse=True)
        dense = FoldProblem(CSTR, CSTR.params(Da=0.1, B=14.0, beta=3.0), "Da", "beta")
        z = np.array([0.4, 1.5, 0.1, 0.6, -0.8])
        np.testing.assert_allclose(prob.jacobian(z, 3.0).toarray(), dense.jacobian(z, 3.0))


class TestOneShotSolves:
    """Newton solves of the augmented systems from a nearby guess, against closed forms."""

    @pytest.mark.parametrize("x_fold", [1.3, 0.4, -0.7])
    def test_cusp_fold_point(self, x_fold):
        # fold of x' = b1 + b2 x - x^3: b2 = 3 x^2, b1 = -2 x^3 (f = f_x = 0)
        b2 = 3 * x_fold**2
        params = CUSP.params(b1=-2 * x_fold**3 + 0.05, b2=b2)
        prob = FoldProblem.from_state(CUSP, params, "b1", "b2", [x_fold * 1.05])
        z = prob.z0
        assert abs(z[0] - x_fold) < 1e-10
        assert abs(prob.p1(z) + 2 * x_fold**3) < 1e-10
        assert abs(abs(z[2]) - 1.0) < 1e-12

    def test_numpy_only_system_uses_finite_differences(self):
        x_fold = 0.8
        params = CUSP_NUMPY.params(b1=-2 * x_fold**3 + 0.02, b2=3 * x_fold**2)
        prob = FoldProblem.from_state(CUSP_NUMPY, params, "b1", "b2", [x_fold + 0.02])
        assert not prob.functions.exact
        assert abs(prob.p1(prob.z0) + 2 * x_fold**3) < 1e-8
        exact = FoldProblem(CUSP, CUSP.params(b1=0.0, b2=1.0), "b1", "b2")
        z = np.array([0.3, 0.1, 0.9])
        np.testing.assert_allclose(prob.jacobian(z, 1.2), exact.jacobian(z, 1.2), atol=1e-6)

    @pytest.mark.parametrize("A", [0.5, 1.0, 2.5])
    def test_brusselator_hopf_point(self, A):
        # equilibrium (A, B/A); trace J = B - 1 - A^2, det J = A^2 -> Hopf at B = 1 + A^2,
        # omega = A
        B = 1 + A**2 + 0.03
        params = BRUSSELATOR.params(A=A, B=B)
        prob = HopfProblem.from_state(BRUSSELATOR, params, "B", "A", [A, B / A])
        z = prob.z0
        assert abs(prob.p1(z) - (1 + A**2)) < 1e-10
        assert abs(prob.omega(z) - A) < 1e-10
        np.testing.assert_allclose(prob.state(z), [A, (1 + A**2) / A], atol=1e-10)
        np.testing.assert_allclose(prob.record(z, A)["omega"], A, atol=1e-10)

    def test_hopf_from_state_rejects_real_spectrum(self):
        with pytest.raises(ValueError, match="`x`"):
            HopfProblem.from_state(CUSP, CUSP.params(b1=0.0, b2=1.0), "b1", "b2", [0.0])

    def test_newton_failure_raises(self):
        # x' = b1 + b2 x - x^3 has no fold for b2 < 0: Newton cannot converge
        params = CUSP.params(b1=0.0, b2=-1.0)
        with pytest.raises(ConvergenceError):
            FoldProblem.from_state(CUSP, params, "b1", "b2", [0.5])

    def test_bad_arguments(self):
        p = CUSP.params(b1=0.0, b2=1.0)
        with pytest.raises(ValueError, match="free1"):
            FoldProblem(CUSP, p, "nope", "b2")
        with pytest.raises(ValueError, match="free2"):
            FoldProblem(CUSP, p, "b1", "b1")
        with pytest.raises(ValueError, match="z0"):
            FoldProblem(CUSP, p, "b1", "b2", z0=np.zeros(5))
        with pytest.raises(ValueError, match="`c`"):
            HopfProblem(BRUSSELATOR, BRUSSELATOR.params(A=1.0, B=2.0), "B", "A")


class TestNormalFormCoefficients:
    def test_fold_quadratic_coefficient_cusp(self):
        # x' = b1 + b2 x - x^3 at the fold x*: B(v,v) = -6 x* v^2, w = v -> a = -3 x*
        x_fold = 0.7
        prob = FoldProblem.from_state(
            CUSP, CUSP.params(b1=-2 * x_fold**3, b2=3 * x_fold**2), "b1", "b2", [x_fold]
        )
        assert abs(prob.quadratic_coefficient(prob.z0, prob.p0) + 3 * x_fold) < 1e-10

    @pytest.mark.parametrize("b2", [-0.4, 0.0, 0.7])
    def test_first_lyapunov_coefficient_bautin(self, b2):
        """l1 of z' = (b1 + i) z + b2 z|z|^2 - z|z|^4 at b1 = 0.

        Kuznetsov (2004) eq. (3.20) with <q, q> = 1: q = (1, -i)/sqrt(2), the cubic
        term F3(x) = b2 |x|^2 x has C(q, q, qbar) = 2 b2 [2 (q.qbar) q + (q.q) qbar]
        = 4 b2 q, B = 0, so l1 = Re <p, 4 b2 q> / (2 omega) = 2 b2.
        """
        prob = HopfProblem.from_state(
            BAUTIN, BAUTIN.params(b1=0.02, b2=b2), "b1", "b2", [0.0, 0.0], omega=1.0
        )
        assert abs(prob.p1(prob.z0)) < 1e-12
        assert abs(prob.lyapunov_coefficient(prob.z0, prob.p0) - 2 * b2) < 1e-10

    @pytest.mark.parametrize("s", [-1.0, 1.0])
    @pytest.mark.parametrize("b2", [-0.25, -2.0])
    def test_first_lyapunov_coefficient_bt_hopf_curve(self, s, b2):
        """l1 on the Hopf curve b1 = 0, b2 = -omega^2 of the BT normal form.

        Hand evaluation of Kuznetsov (2004) eq. (3.20) at the origin of
        x' = y, y' = -omega^2 x + x^2 + s x y: q = (1, i omega)/k, k^2 = 1 + omega^2,
        p = (-i omega, 1) i k / (2 omega), B(q, qbar) = (0, 2/k^2),
        B(q, q) = (0, 2 (1 + i s omega)/k^2), C = 0, giving
        l1 = s / (2 omega^3 (1 + omega^2)). Its sign agrees with Kuznetsov (2004),
        Sec. 8.4: subcritical for s = +1, supercritical for s = -1.
        """
        omega = np.sqrt(-b2)
        prob = HopfProblem.from_state(BT, BT.params(b1=0.0, b2=b2, s=s), "b1", "b2", [0.0, 0.0])
        expected = s / (2 * omega**3 * (1 + omega**2))
        assert abs(prob.lyapunov_coefficient(prob.z0, prob.p0) - expected) < 1e-10
