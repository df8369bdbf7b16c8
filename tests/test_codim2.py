"""Two-parameter continuation of fold and Hopf curves (continuation.codim2).

Every numerical claim is checked against a closed form derived in the test (with
the derivation in the docstring), a published result (cited), or finite
differences.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

from continuation.api import continue_equilibria
from continuation.branch import SpecialKind
from continuation.codim2 import FoldProblem, HopfProblem, continue_codim2
from continuation.differentiation import fd_jacobian
from continuation.errors import ConvergenceError
from continuation.settings import ContinuationSettings
from continuation.status import Status
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


# --------------------------------------------------------------------------- curves


def _branch(system, x0, params, free, **kw):
    kw.setdefault("direction", "both")
    return continue_equilibria(system, x0, params, free, **kw)


def _da_branch(system, x0, B):
    """Equilibria of a CSTR-type ``system`` from ``Da = 0`` forward to 0.3 (beta = 2)."""
    return _branch(
        system,
        x0,
        {"Da": 0.0, "B": B, "beta": 2.0},
        "Da",
        p_min=0.0,
        p_max=0.3,
        ds=0.01,
        direction="forward",
    )


def _only(branch, kind):
    pts = branch.find(kind)
    assert len(pts) == 1, pts
    assert pts[0].located
    return pts[0]


class TestCuspNormalForm:
    """x' = b1 + b2 x - x^3: fold curve b1 = -2 x^3, b2 = 3 x^2, i.e.
    b1 = ∓2 (b2/3)^{3/2} (Kuznetsov 2004, Sec. 8.2), with a cusp at the origin."""

    @pytest.fixture(scope="class")
    @classmethod
    def curve(cls):
        br = _branch(CUSP, [-1.5], {"b1": -1.0, "b2": 1.0}, "b1", p_min=-2, p_max=2, ds=0.05)
        fold = br.find("fold")[0]
        st = ContinuationSettings(ds=0.05, ds_max=0.1, p_min=-0.5, p_max=2.0)
        return continue_codim2(br, fold, "b2", st)

    def test_fold_curve_closed_form(self, curve):
        x, b1, b2 = curve.x[:, 0], curve.records["b1"], curve.p
        assert curve.status.ok and len(curve) > 20
        np.testing.assert_allclose(b2, 3 * x**2, atol=1e-8)
        np.testing.assert_allclose(b1, -2 * x**3, atol=1e-8)
        np.testing.assert_allclose(np.abs(b1), 2 * (b2 / 3) ** 1.5, atol=1e-8)
        # both sheets of the fold curve are traced, through the cusp
        assert x.min() < -0.7 and x.max() > 0.7
        assert curve.p.max() == pytest.approx(2.0, abs=1e-12)

    def test_cusp_at_origin(self, curve):
        cp = _only(curve, "cusp")
        assert cp.label == "CP1"
        assert abs(cp.p) < 1e-8 and abs(cp.data["b1"]) < 1e-8 and abs(cp.x[0]) < 1e-6
        assert not curve.find("bt") and not curve.find("zh")

    def test_user_event_and_one_direction(self):
        from continuation.events import Event

        br = _branch(CUSP, [-1.5], {"b1": -1.0, "b2": 1.0}, "b1", p_min=-2, p_max=2, ds=0.05)
        fold = min(br.find("fold"), key=lambda s: s.p)  # lower sheet: x > 0, b1 < 0
        ev = Event("b1_half", lambda z, p: z[1] - 0.5)
        st = ContinuationSettings(ds=0.05, ds_max=0.1, p_min=-0.5, p_max=2.0)
        curve = continue_codim2(br, fold, "b2", st, direction="backward", events=(ev,))
        assert curve.event_names == ("b1_half",)
        # backward (b2 decreasing) from the x > 0 sheet through the cusp onto the x < 0
        # sheet, where b1 = -2 x^3 > 0 reaches 0.5
        hit = curve.find("b1_half")
        assert len(hit) == 1 and hit[0].located
        x = -(0.25 ** (1 / 3))
        assert hit[0].p == pytest.approx(3 * x**2, abs=1e-8)
        assert hit[0].x[0] == pytest.approx(x, abs=1e-8)
        assert len(curve.find("cusp")) == 1

    def test_rows_solve_the_augmented_system(self, curve):
        prob = curve.problem
        res = [np.abs(prob.residual(z, p)).max() for z, p in zip(curve.x, curve.p, strict=True)]
        assert max(res) < 1e-9
        assert curve.newton_iters.mean() < 4
        assert curve.state_names == ("x", "b1", "v_x")


class TestBogdanovTakensNormalForm:
    """x' = y, y' = b1 + b2 x + x^2 + s x y (Kuznetsov 2004, Sec. 8.4).

    Equilibria y = 0, x^2 + b2 x + b1 = 0: fold curve b1 = b2^2/4 at x = -b2/2; at
    x = 0 (b1 = 0) trace J = s x = 0 and det J = -b2, so the Hopf curve is b1 = 0,
    b2 < 0 with omega = sqrt(-b2), continued by the neutral-saddle curve b1 = 0,
    b2 > 0 (kappa = -b2); both curves meet at the BT point (0, 0)."""

    @pytest.fixture(scope="class", params=[-1.0, 1.0])
    @classmethod
    def branch(cls, request):
        return _branch(
            BT,
            [0.0, 0.0],
            {"b1": 0.1, "b2": -1.0, "s": request.param},
            "b1",
            p_min=-1,
            p_max=1,
            ds=0.02,
        )

    def test_fold_curve(self, branch):
        st = ContinuationSettings(ds=0.02, ds_max=0.05, p_min=-1.5, p_max=1.0)
        curve = continue_codim2(branch, branch.find("fold")[0], "b2", st)
        b1, b2, x = curve.records["b1"], curve.p, curve.x[:, 0]
        assert curve.status is Status.PARAM_BOUND
        assert b2.min() == pytest.approx(-1.5) and b2.max() == pytest.approx(1.0)
        np.testing.assert_allclose(b1, b2**2 / 4, atol=1e-8)
        np.testing.assert_allclose(x, -b2 / 2, atol=1e-8)
        bt = _only(curve, "bt")
        assert abs(bt.p) < 1e-8 and abs(bt.data["b1"]) < 1e-8
        assert not curve.find("cusp")

    def test_hopf_curve_through_bt(self, branch):
        st = ContinuationSettings(ds=0.02, ds_max=0.05, p_min=-1.5, p_max=0.8)
        curve = continue_codim2(branch, branch.find("hopf")[0], "b2", st)
        b1, b2, kappa = curve.records["b1"], curve.p, curve.records["kappa"]
        assert curve.status is Status.PARAM_BOUND
        assert b2.min() == pytest.approx(-1.5) and b2.max() == pytest.approx(0.8)
        np.testing.assert_allclose(b1, 0.0, atol=1e-8)
        np.testing.assert_allclose(kappa, -b2, atol=1e-8)
        hopf = b2 < 0
        np.testing.assert_allclose(curve.records["omega"][hopf], np.sqrt(-b2[hopf]), atol=1e-8)
        assert np.all(np.isnan(curve.records["omega"][b2 > 0]))
        bt = _only(curve, "bt")
        assert abs(bt.p) < 1e-8 and bt.kind is SpecialKind.BOGDANOV_TAKENS
        # l1 = s / (2 omega^3 (1 + omega^2)) never vanishes: no Bautin point
        assert not curve.find("gh")
        assert curve.newton_iters.mean() < 4


class TestBrusselator:
    """Brusselator (Prigogine & Lefever 1968): equilibrium (A, B/A), trace J =
    B - 1 - A^2, det J = A^2, so the Hopf curve is B = 1 + A^2 with omega = A."""

    def test_hopf_curve(self):
        br = _branch(BRUSSELATOR, [1.0, 1.0], {"A": 1.0, "B": 1.0}, "B", p_min=0.5, p_max=3)
        st = ContinuationSettings(ds=0.05, ds_max=0.2, p_min=0.2, p_max=3.0)
        curve = continue_codim2(br, _only(br, "hopf"), "A", st)
        A, B = curve.p, curve.records["B"]
        assert curve.status is Status.PARAM_BOUND
        assert A.min() == pytest.approx(0.2) and A.max() == pytest.approx(3.0)
        np.testing.assert_allclose(B, 1 + A**2, atol=1e-8, rtol=0)
        np.testing.assert_allclose(curve.records["omega"], A, atol=1e-8)
        np.testing.assert_allclose(curve.x[:, 0], A, atol=1e-8)
        np.testing.assert_allclose(curve.x[:, 1], B / A, atol=1e-8)
        assert not curve.special_points


def _planar_lyapunov_value(system, x, P):
    """Guckenheimer & Holmes (1983) eq. (3.4.11) for a planar Hopf point.

    Independent of the engine's l1: the coordinates (u, w) with x = x* + T (u, w),
    T = [Im q, Re q], turn J into [[0, -omega], [omega, 0]]; then
    16 a = f_uuu + f_uww + g_uuw + g_www
           + (f_uw (f_uu + f_ww) - g_uw (g_uu + g_ww) - f_uu g_uu + f_ww g_ww) / omega.
    a has the sign of Kuznetsov's l1 (both are positive multiples of the first
    Lyapunov value).
    """
    J = system.jacobian(x, P)
    lam, vec = np.linalg.eig(J)
    k = int(np.argmax(lam.imag))
    omega, q = lam[k].imag, vec[:, k]
    T = np.column_stack([q.imag, q.real])
    U = ca.SX.sym("u", 2)
    F = ca.mtimes(ca.DM(np.linalg.inv(T)), system.symbolic(ca.DM(x) + ca.mtimes(ca.DM(T), U), P))
    d = {}
    for i, name in enumerate("fg"):
        Fi = F[i]
        d[name + "u"] = ca.jacobian(Fi, U[0])
        d[name + "w"] = ca.jacobian(Fi, U[1])
        d[name + "uu"] = ca.jacobian(d[name + "u"], U[0])
        d[name + "ww"] = ca.jacobian(d[name + "w"], U[1])
        d[name + "uw"] = ca.jacobian(d[name + "u"], U[1])
        d[name + "uuu"] = ca.jacobian(d[name + "uu"], U[0])
        d[name + "uuw"] = ca.jacobian(d[name + "uu"], U[1])
        d[name + "uww"] = ca.jacobian(d[name + "ww"], U[0])
        d[name + "www"] = ca.jacobian(d[name + "ww"], U[1])
    ev = {k: float(ca.Function("e", [U], [v])(np.zeros(2))) for k, v in d.items()}
    np.testing.assert_allclose(
        [[ev["fu"], ev["fw"]], [ev["gu"], ev["gw"]]], [[0, -omega], [omega, 0]], atol=1e-8
    )
    return (
        ev["fuuu"]
        + ev["fuww"]
        + ev["guuw"]
        + ev["gwww"]
        + (
            ev["fuw"] * (ev["fuu"] + ev["fww"])
            - ev["guw"] * (ev["guu"] + ev["gww"])
            - ev["fuu"] * ev["guu"]
            + ev["fww"] * ev["gww"]
        )
        / omega
    ) / 16


class TestCSTR:
    """CSTR of Uppal, Ray & Poore (1974), Chem. Eng. Sci. 29, 967-985, with B = 14.

    At an equilibrium r = Da (1 - x1) e^{x2} = x1 and x2 = B x1 / (1 + beta), and
    det J = (1 + beta - B x1 (1 - x1)) / (1 - x1),
    tr J = B x1 - (1 + beta) - 1 / (1 - x1).
    Fold curve (det J = 0): beta = B x1 (1 - x1) - 1, x2 = 1/(1 - x1),
    Da = x1 e^{-x2} / (1 - x1); its cusp is at x1 = 1/2: beta = B/4 - 1,
    Da = e^{-2}, for every B (Uppal, Ray & Poore 1974, Sec. 3, the boundary of the
    multiplicity region). Hopf curve (tr J = 0): beta = B x1 - 1/(1 - x1) - 1,
    omega^2 = det J. Bogdanov-Takens points (both): B x1^2 (1 - x1) = 1.
    """

    B = 14.0

    @pytest.fixture(scope="class")
    @classmethod
    def branch(cls):
        return _da_branch(CSTR, [0.0, 0.0], cls.B)

    def _bt_points(self):
        r = np.roots([-self.B, self.B, 0.0, -1.0])
        x1 = r.real[(r.real > 0) & (r.real < 1) & (np.abs(r.imag) < 1e-12)]
        beta, da = self.B * x1 * (1 - x1) - 1, x1 * np.exp(-1 / (1 - x1)) / (1 - x1)
        order = np.argsort(beta)
        return beta[order], da[order]

    def test_fold_curve_cusp_and_bt(self, branch):
        assert len(branch.find("fold")) == 2
        st = ContinuationSettings(ds=0.05, ds_max=0.05, p_min=0.05, p_max=2.6)
        curve = continue_codim2(branch, branch.find("fold")[0], "beta", st)
        x1, x2, Da, beta = curve.x[:, 0], curve.x[:, 1], curve.records["Da"], curve.p
        assert curve.status.ok
        np.testing.assert_allclose(beta, self.B * x1 * (1 - x1) - 1, atol=1e-8)
        np.testing.assert_allclose(x2, 1 / (1 - x1), atol=1e-8)
        np.testing.assert_allclose(Da, x1 * np.exp(-x2) / (1 - x1), atol=1e-8)
        cp = _only(curve, "cusp")
        assert cp.p == pytest.approx(self.B / 4 - 1, abs=1e-8)
        assert cp.data["Da"] == pytest.approx(np.exp(-2.0), abs=1e-8)
        beta_bt, da_bt = self._bt_points()
        bts = curve.find("bt")
        assert len(bts) == 2 and all(b.located for b in bts)
        np.testing.assert_allclose(sorted(b.p for b in bts), beta_bt, atol=1e-8)
        bts = sorted(bts, key=lambda b: b.p)
        np.testing.assert_allclose([b.data["Da"] for b in bts], da_bt, atol=1e-8)

    def test_hopf_curve_bt_and_bautin(self, branch):
        hopf = _only(branch, "hopf")
        st = ContinuationSettings(ds=0.05, ds_max=0.2, p_min=0.05, p_max=6.0)
        curve = continue_codim2(branch, hopf, "beta", st, detect=("bt", "gh"))
        x1, x2, Da, beta = curve.x[:, 0], curve.x[:, 1], curve.records["Da"], curve.p
        kappa = curve.records["kappa"]
        assert curve.status.ok
        # the curve turns at beta ~ 5.5 and ends on the neutral-saddle side below BT2
        assert beta.max() > 5.4 and kappa.min() < -0.5
        np.testing.assert_allclose(beta, self.B * x1 - 1 / (1 - x1) - 1, atol=1e-8)
        np.testing.assert_allclose(x2, self.B * x1 / (1 + beta), atol=1e-8)
        np.testing.assert_allclose(Da, x1 * np.exp(-x2) / (1 - x1), atol=1e-8)
        det = (self.B * x1**2 - 1 / (1 - x1)) / (1 - x1)
        np.testing.assert_allclose(kappa, det, atol=1e-8)
        beta_bt, _ = self._bt_points()
        bts = curve.find("bt")
        assert len(bts) == 2 and all(b.located for b in bts)
        np.testing.assert_allclose(sorted(b.p for b in bts), beta_bt, atol=1e-8)
        # generalised Hopf points: zeros of l1, checked with the independent planar
        # formula (Guckenheimer & Holmes 1983)
        prob = curve.problem
        ghs = curve.find("gh")
        assert len(ghs) == 2 and all(g.located for g in ghs)
        k = int(np.argmax(kappa))
        a_ref = _planar_lyapunov_value(CSTR, curve.x[k, :2], prob.param_vector(curve.x[k], beta[k]))
        for gh in ghs:
            a_gh = _planar_lyapunov_value(CSTR, gh.x[:2], prob.param_vector(gh.x, gh.p))
            assert abs(a_gh) < 1e-7 * abs(a_ref)
        for j in range(0, len(curve), 9):
            if kappa[j] > 0.1:
                l1 = prob.lyapunov_coefficient(curve.x[j], beta[j])
                a = _planar_lyapunov_value(
                    CSTR, curve.x[j, :2], prob.param_vector(curve.x[j], beta[j])
                )
                assert np.sign(l1) == np.sign(a)


def _check_invariants(curve):
    """Special points sit between their rows, in arclength and in bracket."""
    s = curve.arclength
    for sp in curve.special_points:
        i = sp.index
        assert 0 <= i < len(curve) - 1
        assert sp.bracket == (curve.p[i], curve.p[i + 1])
        assert s[i] - 1e-9 <= sp.s <= s[i + 1] + 1e-9


class TestZeroHopf:
    """x1' = b1 - x1^2, (x2 + i x3)' = (b2 + x1 + i)(x2 + i x3).

    Equilibria x1 = ±sqrt(b1), x2 = x3 = 0; eigenvalues -2 x1 and b2 + x1 ± i.
    Fold curve b1 = 0 (x1 = 0) with a zero-Hopf point where b2 = 0; Hopf curve
    x1 = -b2, b1 = b2^2, omega = 1, with a zero-Hopf point where -2 x1 = 0, b2 = 0."""

    @pytest.fixture(scope="class")
    @classmethod
    def branch(cls):
        return _branch(
            ZERO_HOPF, [1.0, 0, 0], {"b1": 1.0, "b2": -0.5}, "b1", p_min=-0.5, p_max=1.5, ds=0.02
        )

    def test_fold_curve(self, branch):
        st = ContinuationSettings(ds=0.02, ds_max=0.05, p_min=-1.0, p_max=1.0)
        curve = continue_codim2(branch, _only(branch, "fold"), "b2", st)
        np.testing.assert_allclose(curve.records["b1"], 0.0, atol=1e-8)
        np.testing.assert_allclose(curve.x[:, 0], 0.0, atol=1e-8)
        zh = _only(curve, "zh")
        assert abs(zh.p) < 1e-8 and zh.kind is SpecialKind.ZERO_HOPF
        assert not curve.find("bt") and not curve.find("cusp")
        _check_invariants(curve)

    def test_hopf_curve(self, branch):
        st = ContinuationSettings(ds=0.02, ds_max=0.05, p_min=-1.0, p_max=1.0)
        curve = continue_codim2(branch, _only(branch, "hopf"), "b2", st)
        b2 = curve.p
        np.testing.assert_allclose(curve.records["b1"], b2**2, atol=1e-8)
        np.testing.assert_allclose(curve.x[:, 0], -b2, atol=1e-8)
        np.testing.assert_allclose(curve.records["omega"], 1.0, atol=1e-8)
        zh = _only(curve, "zh")
        assert abs(zh.p) < 1e-8 and abs(zh.data["b1"]) < 1e-8
        assert not curve.find("bt") and not curve.find("gh")
        _check_invariants(curve)


def test_lyapunov_pole_at_zero_hopf_is_not_a_bautin_point():
    """Fold-Hopf normal form x1' = b1 - x1^2 + x2^2 + x3^2 with the oscillator of
    ZERO_HOPF: same equilibria and Hopf curve b1 = b2^2, but now B(q, qbar) has a
    component along the null vector at the zero-Hopf point, so l1 ~ 1/x1 changes
    sign through a pole there (Kuznetsov 2004, Sec. 8.5). Only the ZH point is real."""

    def rhs(x, p, ops):
        b1, b2 = p[0], p[1]
        mu = b2 + x[0]
        return ops.stack(
            [b1 - x[0] ** 2 + x[1] ** 2 + x[2] ** 2, mu * x[1] - x[2], x[1] + mu * x[2]]
        )

    sys3 = System(rhs, ("x1", "x2", "x3"), ("b1", "b2"))
    br = _branch(sys3, [1.0, 0, 0], {"b1": 1.0, "b2": -0.5}, "b1", p_min=-0.5, p_max=1.5, ds=0.02)
    st = ContinuationSettings(ds=0.02, ds_max=0.05, p_min=-1.0, p_max=1.0)
    curve = continue_codim2(br, _only(br, "hopf"), "b2", st)
    P = curve.problem
    l1 = np.array([P.lyapunov_coefficient(z, p) for z, p in zip(curve.x, curve.p, strict=True)])
    assert np.any(l1 > 0) and np.any(l1 < 0)  # the sign change the filter must reject
    assert abs(_only(curve, "zh").p) < 1e-8
    assert not curve.find("gh")


class TestBautinAndDoubleHopf:
    def test_bautin_normal_form(self):
        """z' = (b1 + i) z + b2 z|z|^2 - z|z|^4: Hopf curve b1 = 0, omega = 1, and
        l1 = 2 b2 (see test_first_lyapunov_coefficient_bautin): a generalised Hopf
        point at b2 = 0 (Kuznetsov 2004, Sec. 8.3)."""
        br = _branch(BAUTIN, [0, 0], {"b1": -0.5, "b2": -0.5}, "b1", p_min=-1, p_max=1, ds=0.05)
        st = ContinuationSettings(ds=0.05, ds_max=0.1, p_min=-1, p_max=1)
        curve = continue_codim2(br, _only(br, "hopf"), "b2", st)
        np.testing.assert_allclose(curve.records["b1"], 0.0, atol=1e-8)
        np.testing.assert_allclose(curve.records["omega"], 1.0, atol=1e-8)
        l1 = [
            curve.problem.lyapunov_coefficient(z, p) for z, p in zip(curve.x, curve.p, strict=True)
        ]
        np.testing.assert_allclose(l1, 2 * curve.p, atol=1e-8)
        gh = _only(curve, "gh")
        assert abs(gh.p) < 1e-8 and gh.kind is SpecialKind.GENERALIZED_HOPF
        _check_invariants(curve)

    def test_double_hopf(self):
        """Two oscillators with frequencies 1 and 2 and growth rates b1, b2: along the
        Hopf curve b1 = 0 of the first pair the second pair crosses at b2 = 0."""

        def rhs(x, p, ops):
            b1, b2 = p[0], p[1]
            r2, s2 = x[0] ** 2 + x[1] ** 2, x[2] ** 2 + x[3] ** 2
            return ops.stack(
                [
                    b1 * x[0] - x[1] - r2 * x[0] + x[0] * s2,
                    x[0] + b1 * x[1] - r2 * x[1],
                    b2 * x[2] - 2 * x[3] - s2 * x[2] + r2 * x[2],
                    2 * x[2] + b2 * x[3] - s2 * x[3],
                ]
            )

        sys4 = System(rhs, ("x1", "y1", "x2", "y2"), ("b1", "b2"))
        br = _branch(sys4, [0, 0, 0, 0], {"b1": -0.5, "b2": -0.5}, "b1", p_min=-1, p_max=1, ds=0.05)
        st = ContinuationSettings(ds=0.05, ds_max=0.1, p_min=-1, p_max=1)
        curve = continue_codim2(br, _only(br, "hopf"), "b2", st)
        np.testing.assert_allclose(curve.records["omega"], 1.0, atol=1e-8)
        hh = curve.find("hh")
        assert len(hh) == 1 and hh[0].label == "HH1" and hh[0].located and abs(hh[0].p) < 1e-8
        assert not curve.find("zh")


class TestRenormalisation:
    def test_neutral_saddle_curve_with_restarts(self):
        """BT normal form, Hopf curve b1 = 0 continued far into the neutral-saddle
        region b2 > 0 (kappa = -b2): the fixed normalisation vector degrades and the
        curve is restarted; every row must still be a neutral saddle of the model."""
        br = _branch(
            BT, [0.0, 0.0], {"b1": 0.1, "b2": -1.0, "s": -1.0}, "b1", p_min=-1, p_max=1, ds=0.02
        )
        st = ContinuationSettings(ds=0.02, ds_max=0.05, p_min=-1.5, p_max=3.0)
        curve = continue_codim2(br, _only(br, "hopf"), "b2", st, direction="forward")
        assert curve.status is Status.PARAM_BOUND and "renormalisation" in curve.message
        assert curve.p.max() == pytest.approx(3.0)
        np.testing.assert_allclose(curve.records["b1"], 0.0, atol=1e-8)
        np.testing.assert_allclose(curve.records["kappa"], -curve.p, atol=1e-8)
        P = curve.problem
        for z, p in zip(curve.x, curve.p, strict=True):
            lam = np.linalg.eigvals(P.state_jacobian(z, p))
            np.testing.assert_allclose(lam**2, -P.kappa(z), atol=1e-8)
        assert len(curve.find("bt")) == 1
        _check_invariants(curve)

    def test_save_load_roundtrip(self, tmp_path):
        from continuation.branch import Branch

        br = _branch(
            BT, [0.0, 0.0], {"b1": 0.1, "b2": -1.0, "s": -1.0}, "b1", p_min=-1, p_max=1, ds=0.02
        )
        st = ContinuationSettings(ds=0.02, ds_max=0.05, p_min=-1.5, p_max=0.5)
        curve = continue_codim2(br, _only(br, "hopf"), "b2", st)
        back = Branch.load(curve.save(tmp_path / "hopf_curve"))
        np.testing.assert_array_equal(back.x, curve.x)
        np.testing.assert_array_equal(back.records["omega"], curve.records["omega"])
        assert back.state_names == ("x", "y", "b1", "kappa", "v_x", "v_y")
        assert [s.label for s in back.special_points] == ["BT1"]


class TestInputValidation:
    @pytest.fixture(scope="class")
    @classmethod
    def branch(cls):
        return _branch(CUSP, [-1.5], {"b1": -1.0, "b2": 1.0}, "b1", p_min=-2, p_max=2, ds=0.05)

    def test_bad_free2(self, branch):
        fold = branch.find("fold")[0]
        with pytest.raises(ValueError, match="free2"):
            continue_codim2(branch, fold, "b1")
        with pytest.raises(ValueError, match="free2"):
            continue_codim2(branch, fold, "nope")

    def test_bad_point(self, branch):
        fold = branch.find("fold")[0]
        foreign = dataclasses.replace(fold)
        with pytest.raises(ValueError, match="`sp`"):
            continue_codim2(branch, foreign, "b2")
        with pytest.raises(ValueError, match="`sp`"):
            HopfProblem.from_point(branch, fold, "b2")
        unlocated = dataclasses.replace(fold, located=False)
        br2 = dataclasses.replace(branch, special_points=(unlocated,))
        with pytest.raises(ValueError, match="not located"):
            continue_codim2(br2, unlocated, "b2")
        with pytest.raises(ValueError, match="`sp` must be a fold or hopf"):
            bp = dataclasses.replace(fold, kind="bp")
            continue_codim2(dataclasses.replace(branch, special_points=(bp,)), bp, "b2")

    def test_bad_options(self, branch):
        fold = branch.find("fold")[0]
        with pytest.raises(ValueError, match="direction"):
            continue_codim2(branch, fold, "b2", direction="sideways")
        with pytest.raises(ValueError, match="detect"):
            continue_codim2(branch, fold, "b2", detect=("gh",))
        with pytest.raises(ValueError, match="detect"):
            continue_codim2(branch, fold, "b2", detect="bt")
        loaded = dataclasses.replace(branch, problem=None)  # e.g. Branch.load without problem
        with pytest.raises(ValueError, match="`branch`"):
            continue_codim2(loaded, loaded.special_points[0], "b2")

    def test_interrupt_keeps_finished_rows(self, branch):
        calls = []

        def progress(row):
            calls.append(row)
            if len(calls) == 5:
                raise KeyboardInterrupt

        st = ContinuationSettings(ds=0.05, ds_max=0.1, p_min=-0.5, p_max=2.0)
        curve = continue_codim2(branch, branch.find("fold")[0], "b2", st, progress=progress)
        assert curve.status is Status.INTERRUPTED
        assert 1 <= len(curve) <= 5
        np.testing.assert_allclose(curve.records["b1"], -2 * curve.x[:, 0] ** 3, atol=1e-8)


def test_numpy_only_hopf_curve():
    """The finite-difference path (System without a CasADi trace) on the Brusselator
    Hopf curve B = 1 + A^2, omega = A; accuracy limited by the differences."""

    def brus(x, p):
        A, B = p
        return np.array([A - (B + 1) * x[0] + x[0] ** 2 * x[1], B * x[0] - x[0] ** 2 * x[1]])

    sys_np = System(brus, ("x", "y"), ("A", "B"))
    br = _branch(sys_np, [1.0, 1.0], {"A": 1.0, "B": 1.0}, "B", p_min=0.5, p_max=3)
    st = ContinuationSettings(ds=0.05, ds_max=0.2, p_min=0.2, p_max=3.0)
    curve = continue_codim2(br, _only(br, "hopf"), "A", st)
    assert not curve.problem.functions.exact and curve.status is Status.PARAM_BOUND
    np.testing.assert_allclose(curve.records["B"], 1 + curve.p**2, atol=1e-7)
    np.testing.assert_allclose(curve.records["omega"], curve.p, atol=1e-7)


class TestEmbeddedCSTR:
    """The CSTR embedded in R^10 and rotated: y = Q u, u = (x1, x2, w), with
    w' = -D w + g(x1, x2). The (x1, x2) dynamics do not depend on w, so every
    bifurcation of the 2-D model (Uppal, Ray & Poore 1974) is a bifurcation of the
    10-D one at the same parameters, with the same centre-manifold coefficients;
    the dense orthogonal Q couples all coordinates of y."""

    n = 10
    B = 14.0

    @pytest.fixture(scope="class")
    @classmethod
    def setup(cls):
        n = cls.n
        Q, _ = np.linalg.qr(np.random.default_rng(0).standard_normal((n, n)))
        D = np.linspace(1.0, 3.0, n - 2)

        def rhs(y, p, ops):
            Da, B, beta = p[0], p[1], p[2]
            u = [sum(Q[k, i] * y[k] for k in range(n)) for i in range(n)]
            x1, x2 = u[0], u[1]
            r = Da * (1 - x1) * ops.exp(x2)
            F = [-x1 + r, -x2 + B * r - beta * x2]
            F += [-D[j] * u[2 + j] + 0.1 * (j + 1) * x1 * x2 + 0.05 * x1**2 for j in range(n - 2)]
            return ops.stack([sum(Q[i, k] * F[k] for k in range(n)) for i in range(n)])

        sysn = System(rhs, tuple(f"y{i}" for i in range(n)), ("Da", "B", "beta"))
        br = _da_branch(sysn, np.zeros(n), cls.B)
        return Q, br

    def test_fold_curve(self, setup):
        Q, br = setup
        st = ContinuationSettings(ds=0.05, ds_max=0.05, p_min=0.05, p_max=2.6)
        curve = continue_codim2(br, br.find("fold")[0], "beta", st)
        u = curve.x[:, : self.n] @ Q
        x1, x2, beta = u[:, 0], u[:, 1], curve.p
        np.testing.assert_allclose(beta, self.B * x1 * (1 - x1) - 1, atol=1e-8)
        np.testing.assert_allclose(x2, 1 / (1 - x1), atol=1e-8)
        np.testing.assert_allclose(curve.records["Da"], x1 * np.exp(-x2) / (1 - x1), atol=1e-8)
        cp = _only(curve, "cusp")
        assert cp.p == pytest.approx(self.B / 4 - 1, abs=1e-8)
        assert cp.data["Da"] == pytest.approx(np.exp(-2.0), abs=1e-8)
        beta_bt, _ = TestCSTR._bt_points(self)
        np.testing.assert_allclose(sorted(b.p for b in curve.find("bt")), beta_bt, atol=1e-8)

    def test_hopf_curve(self, setup):
        Q, br = setup
        st = ContinuationSettings(ds=0.05, ds_max=0.2, p_min=0.05, p_max=6.0)
        curve = continue_codim2(br, _only(br, "hopf"), "beta", st)
        u = curve.x[:, : self.n] @ Q
        x1, beta = u[:, 0], curve.p
        np.testing.assert_allclose(beta, self.B * x1 - 1 / (1 - x1) - 1, atol=1e-8)
        beta_bt, _ = TestCSTR._bt_points(self)
        np.testing.assert_allclose(sorted(b.p for b in curve.find("bt")), beta_bt, atol=1e-8)
        ghs = curve.find("gh")
        assert len(ghs) == 2
        prob = curve.problem
        k = int(np.argmax(curve.records["kappa"]))
        a_ref = _planar_lyapunov_value(CSTR, u[k, :2], prob.param_vector(curve.x[k], beta[k]))
        for gh in ghs:
            ugh = gh.x[: self.n] @ Q
            a_gh = _planar_lyapunov_value(CSTR, ugh[:2], prob.param_vector(gh.x, gh.p))
            assert abs(a_gh) < 1e-7 * abs(a_ref)
        assert not curve.find("zh") and not curve.find("user")
        assert curve.newton_iters.mean() < 4


@pytest.mark.parametrize("ds_max", [0.1, 1.0])
def test_cusp_next_to_a_bogdanov_takens_point_in_one_step(ds_max):
    """CSTR of Uppal, Ray & Poore (1974) with B = 8.05, just above B = 8 where the cusp
    (x1 = 1/2: beta = B/4 - 1, Da = e^{-2}) meets a Bogdanov-Takens point
    (B x1^2 (1 - x1) = 1, beta = B x1 (1 - x1) - 1; see TestCSTR): both lie inside
    one step of the fold curve. The cusp must be kept (a screen that compared the
    quadratic coefficient's sign at the two rows dropped it: the coefficient has a pole
    at the BT point and a zero at the cusp), and the BT point's own zero of the cusp
    test is no cusp."""
    B = 8.05
    br = _branch(CSTR, [0.0, 0.0], {"Da": 0.0, "B": B, "beta": 0.5}, "Da", p_min=0.0,
                 p_max=0.3, ds=0.01, direction="forward")  # fmt: skip
    st = ContinuationSettings(ds=0.05, ds_max=ds_max, p_min=0.05, p_max=3.0)
    curve = continue_codim2(br, br.find("fold")[0], "beta", st)
    cp = _only(curve, "cusp")
    assert cp.p == pytest.approx(B / 4 - 1, abs=1e-8)
    assert cp.data["Da"] == pytest.approx(np.exp(-2.0), abs=1e-8)
    x1 = np.roots([-B, B, 0.0, -1.0])  # B x1^2 (1 - x1) = 1
    x1 = np.sort(x1[(abs(x1.imag) < 1e-12) & (x1.real > 0) & (x1.real < 1)].real)
    bts = sorted(b.p for b in curve.find("bt"))
    np.testing.assert_allclose(bts, np.sort(B * x1 * (1 - x1) - 1), atol=1e-8)
    assert min(abs(b - cp.p) for b in bts) < 1e-3  # the two really are close
