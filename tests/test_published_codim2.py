"""Two-parameter continuation (continuation.codim2) on published problems at defaults.

A robustness probe of fold and Hopf curves, their codimension-two points and the first
Lyapunov coefficient, run the way a researcher would: ``continue_equilibria`` with
default settings (a parameter window only), then ``continue_codim2`` from the located
fold/Hopf points with default ``ContinuationSettings`` (a window in the second
parameter only). None of these problems is used elsewhere in the tests.

References are closed forms derived in the docstrings, published values (cited with
the file they come from), or independent computations written here: SciPy root
finders on hand-written defining equations (Routh-Hurwitz conditions of the
characteristic polynomial) and an independent implementation of the first Lyapunov
coefficient (Kuznetsov 2004, "Elements of Applied Bifurcation Theory", 3rd ed.,
eq. (3.20)) with hand-written second and third derivatives (:func:`_l1`).

Tolerances: curve rows and located codim-2 points are Newton solutions of the
augmented systems (residual tolerance 1e-10, location tolerance 1e-10 in
pseudo-arclength), so closed forms are met to 1e-8 absolute on O(1) quantities;
published values are compared to the digits they are printed with.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest
from scipy.optimize import brentq, fsolve

from continuation import ContinuationSettings, System, continue_codim2, continue_equilibria
from continuation.branch import SpecialKind
from continuation.status import Status


def _one(branch, kind):
    """The single located special point of ``kind`` on ``branch``."""
    found = branch.find(kind)
    assert len(found) == 1, [(s.label, s.p) for s in branch.special_points]
    assert found[0].located
    return found[0]


def _l1(J, B, C):
    """First Lyapunov coefficient, Kuznetsov (2004) eq. (3.20), written independently.

    ``J`` (n, n) has the pair ``±i omega``; ``B(u, v)``, ``C(u, v, w)`` are the
    hand-written multilinear forms of the model (complex arguments allowed).
    ``q``: ``J q = i omega q``, ``<q, q> = 1``; ``p``: ``J^T p = -i omega p``,
    ``<p, q> = 1`` with ``<a, b> = conj(a) . b``.
    """
    lam, vec = np.linalg.eig(J)
    k = int(np.argmin(np.abs(lam.real) + 1e3 * (lam.imag <= 0)))
    om = lam[k].imag
    q = vec[:, k] / np.linalg.norm(vec[:, k])
    lt, vt = np.linalg.eig(J.T)
    p = vt[:, int(np.argmin(np.abs(lt + 1j * om)))]
    p = p / np.conj(np.vdot(p, q))
    n = J.shape[0]
    h11 = np.linalg.solve(J, B(q, q.conj()))
    h20 = np.linalg.solve(2j * om * np.eye(n) - J, B(q, q))
    val = np.vdot(p, C(q, q, q.conj())) - 2 * np.vdot(p, B(q, h11)) + np.vdot(p, B(q.conj(), h20))
    return float(val.real / (2 * om)), om


def _l1_along(curve):
    """The engine's l1 at every row of a Hopf curve (NaN on neutral saddles)."""
    P = curve.problem
    return np.array([P.lyapunov_coefficient(z, p) for z, p in zip(curve.x, curve.p, strict=True)])


# ============================================================================ Gray-Scott
def gray_scott() -> System:
    def rhs(x, p, ops):
        F, k = p[0], p[1]
        u, v = x[0], x[1]
        return ops.stack([-u * v**2 + F * (1 - u), u * v**2 - (F + k) * v])

    return System(rhs, ("u", "v"), ("F", "k"))


def _gs_jac(u, v, F, k):
    return np.array([[-(v**2) - F, -2 * u * v], [v**2, 2 * u * v - (F + k)]])


def _gs_B(u, v):
    def Bn(a, b):  # second derivative of u v^2
        return 2 * v * (a[0] * b[1] + a[1] * b[0]) + 2 * u * a[1] * b[1]

    return lambda a, b: np.array([-Bn(a, b), Bn(a, b)])


def _gs_C(a, b, c):
    cn = 2 * (a[0] * b[1] * c[1] + a[1] * b[0] * c[1] + a[1] * b[1] * c[0])
    return np.array([-cn, cn])


def _gs_hopf_point(v, sign=-1.0):
    """Point of the Hopf curve parametrised by ``v`` (closed form, see the class)."""
    c = (v + sign * np.sqrt(v * v - 4 * v**3)) / 2
    F = c * c / v
    return c / v, v, F, c - F  # u, v, F, k


class TestGrayScott:
    """Gray-Scott autocatalator in a CSTR (Gray & Scott 1983, Chem. Eng. Sci. 38, 29-43;
    1984, Chem. Eng. Sci. 39, 1087-1097): ``u' = -u v^2 + F (1 - u)``,
    ``v' = u v^2 - (F + k) v``.

    With ``c = F + k``, a nontrivial equilibrium has ``u v = c`` and
    ``c v^2 - F v + F c = 0``; ``J = [[-v^2 - F, -2c], [v^2, c]]``, so
    ``tr J = c - v^2 - F`` and ``det J = c (v^2 - F)``.

    * Fold curve (``det J = 0``, ``v^2 = F``, double root ``v = F/(2c)``):
      ``F = 4 c^2``, i.e. ``F = s^2``, ``k = s/2 - s^2``, ``v = s``, ``u = 1/2``.
    * Hopf curve (``tr J = 0``, ``det J > 0``): ``v = c^2/F``, ``v^2 = c - F``, i.e.
      ``c^2 - v c + v^3 = 0``, ``F = c^2/v``, ``omega^2 = c (c - 2F)``.
    * Bogdanov-Takens point (both): ``s = 1/4``: ``F = k = 1/16``, ``u = 1/2``,
      ``v = 1/4`` (the double root ``v = 1/4`` of the Hopf parametrisation).
    * At ``s = 0`` (``F = k = 0``) ``J = 0``: both eigenvalues vanish with a
      two-dimensional kernel, a point of higher codimension that is neither a
      Bogdanov-Takens point (which needs ``J != 0``, Kuznetsov 2004, Sec. 8.4) nor a
      cusp (the fold curve is smooth there and its quadratic coefficient
      ``a = -2 s^2 / (1 - 4 s)`` does not change sign). Regression: the engine
      reported BT1 and CP1 there.
    * Generalised Hopf point: the zero of ``l1`` on the Hopf curve, found
      independently by ``brentq`` on :func:`_l1` with the hand-written derivatives;
      it is the rational point ``(F, k) = (3/256, 9/256)``, ``v = 3/16``,
      ``c = 3/64`` (to the 1e-12 of that root finder).
    """

    @pytest.fixture(scope="class")
    @classmethod
    def branch(cls):
        F, k = 0.04, 0.055
        c = F + k
        v = (F + np.sqrt(F * F - 4 * F * c * c)) / (2 * c)
        return continue_equilibria(gray_scott(), [c / v, v], {"F": F, "k": k}, "k",
                                   p_min=0.0, p_max=0.1)  # fmt: skip

    def test_one_parameter_points(self, branch):
        # at F = 0.04: the fold where F = 4 c^2 (k = 0.06), the Hopf point from the
        # Hopf parametrisation solved for F = 0.04
        fold = _one(branch, "fold")
        assert fold.p == pytest.approx(np.sqrt(0.04) / 2 - 0.04, abs=1e-10)
        hopf = _one(branch, "hopf")
        v = brentq(lambda v: _gs_hopf_point(v)[2] - 0.04, 0.2, 0.2499999)
        u, v, F, k = _gs_hopf_point(v)
        assert hopf.p == pytest.approx(k, abs=1e-10)
        np.testing.assert_allclose(hopf.x, [u, v], atol=1e-9)
        c = F + k
        assert hopf.data["omega"] == pytest.approx(np.sqrt(c * (c - 2 * F)), abs=1e-9)

    def test_fold_curve_bt_and_no_false_points_at_the_degenerate_corner(self, branch, caplog):
        st = ContinuationSettings(p_min=0.0, p_max=0.3)
        with caplog.at_level(logging.WARNING, logger="continuation.codim2"):
            curve = continue_codim2(branch, _one(branch, "fold"), "F", st)
        assert curve.status is Status.PARAM_BOUND
        u, v, k, F = curve.x[:, 0], curve.x[:, 1], curve.records["k"], curve.p
        np.testing.assert_allclose(F, v**2, atol=1e-9)
        np.testing.assert_allclose(k, v / 2 - v**2, atol=1e-9)
        np.testing.assert_allclose(u, 0.5, atol=1e-8)
        # both sheets v > 0 and v < 0 are traced, through the corner F = k = 0
        assert v.min() < -0.4 and v.max() > 0.4
        bt = _one(curve, "bt")
        assert bt.p == pytest.approx(1 / 16, abs=1e-9)
        assert bt.data["k"] == pytest.approx(1 / 16, abs=1e-9)
        np.testing.assert_allclose(bt.x[:2], [0.5, 0.25], atol=1e-8)
        # the corner s = 0 (J = 0) is no BT point and no cusp
        assert not curve.find("cusp") and not curve.find("zh")
        assert "kernel has dimension two or more" in caplog.text

    def test_hopf_curve_bt_and_bautin_point(self, branch):
        curve = continue_codim2(
            branch, _one(branch, "hopf"), "F", ContinuationSettings(p_min=0.005, p_max=0.3)
        )
        assert curve.status is Status.PARAM_BOUND
        u, v, F, k = curve.x[:, 0], curve.x[:, 1], curve.p, curve.records["k"]
        c = F + k
        kappa = curve.records["kappa"]
        np.testing.assert_allclose(u * v, c, atol=1e-9)
        np.testing.assert_allclose(v**2, c - F, atol=1e-9)  # tr J = 0
        np.testing.assert_allclose(kappa, c * (c - 2 * F), atol=1e-9)  # det J (< 0: saddle)
        bt = _one(curve, "bt")
        assert bt.p == pytest.approx(1 / 16, abs=1e-9)
        assert bt.data["k"] == pytest.approx(1 / 16, abs=1e-9)

        # the independent l1 of eq. (3.20) with hand-written derivatives, on the closed-form
        # Hopf curve, and its zero by brentq
        def l1_ref(v):
            u, v, F, k = _gs_hopf_point(v)
            return _l1(_gs_jac(u, v, F, k), _gs_B(u, v), _gs_C)[0]

        v_gh = brentq(l1_ref, 0.1, 0.24, xtol=1e-12)
        _, _, F_gh, k_gh = _gs_hopf_point(v_gh)
        assert (F_gh, k_gh) == pytest.approx((3 / 256, 9 / 256), abs=1e-12)
        gh = _one(curve, "gh")
        assert gh.p == pytest.approx(F_gh, abs=1e-9)
        assert gh.data["k"] == pytest.approx(k_gh, abs=1e-9)
        assert gh.kind is SpecialKind.GENERALIZED_HOPF
        # the engine's l1 against the independent one along the curve
        l1 = _l1_along(curve)
        for j in range(0, len(curve), 7):
            if kappa[j] > 1e-4:
                ref = _l1(_gs_jac(u[j], v[j], F[j], k[j]), _gs_B(u[j], v[j]), _gs_C)[0]
                assert l1[j] == pytest.approx(ref, rel=1e-7, abs=1e-9 * abs(ref) + 1e-12)
        assert not curve.find("zh") and not curve.find("hh") and not curve.find("cusp")


# ===================================================================== FitzHugh-Nagumo
def fitzhugh_nagumo(backend: str = "auto") -> System:
    def rhs(x, p, ops):
        a, b, c = p[0], p[1], p[2]
        return ops.stack([c * (x[0] - x[0] ** 3 / 3 + x[1]), -(x[0] - a + b * x[1]) / c])

    return System(rhs, ("x", "y"), ("a", "b", "c"), backend=backend)


def test_fitzhugh_nagumo_hopf_curve_and_bautin_points():
    """AUTO-07p demo ``fhn`` (auto-07p/auto-07p, demos/fhn/fhn.f90 and c.fhn.1/3/4):
    ``x' = c (x - x^3/3 + y)``, ``y' = -(x - a + b y)/c``, ``b = 0.8``, ``c = 3``,
    equilibria continued in ``a`` from 0, the Hopf point continued in ``(a, c)``
    up to ``c = 10``.

    Equilibria: ``y = x^3/3 - x``, ``a = x + b (x^3/3 - x)``;
    ``J = [[c k, c], [-1/c, -b/c]]``, ``k = 1 - x^2``. Hopf curve (``tr J = 0``):
    ``x^2 = 1 - b/c^2``, ``omega^2 = det J = 1 - b^2/c^2``; no fold (``det J > 0`` for
    ``b < 1``).

    First Lyapunov coefficient in closed form, derived here from Kuznetsov (2004),
    eq. (3.20): for a planar ``J = [[al, be], [ga, -al]]`` with the nonlinearity
    ``(A xi^2 + C xi^3, 0)`` in the first equation only, ``q = (be, i omega - al)``,
    ``p_1 = -ga / (2 omega (omega - i al))`` (conjugated), ``N = be^2 + al^2 + omega^2``
    (for ``<q, q> = 1``), ``l1 = K (6 C + 4 A^2 al / omega^2)`` with
    ``K = -be^3 ga / (4 omega (omega^2 + al^2) N)``. For FHN ``al = b/c``, ``be = c``,
    ``ga = -1/c``, ``A = -c x``, ``C = -c/3``, so ``K > 0`` and
    ``l1 = 2 c K (2 b x^2 / omega^2 - 1)``: the Bautin points are
    ``c^2 = b^2/(2b - 1)``, ``x = ±sqrt((1 - b)/b)``; for ``b = 0.8``
    ``c = sqrt(16/15)``, ``x = ±1/2``, ``a = ±2/15``, ``omega^2 = 2/5``.
    """
    b = 0.8
    br = continue_equilibria(fitzhugh_nagumo(), [0, 0], {"a": 0, "b": b, "c": 3.0}, "a",
                             p_min=-0.1, p_max=1.0, direction="forward")  # fmt: skip
    hopf = _one(br, "hopf")
    x_h = np.sqrt(1 - b / 9)  # the equilibrium at the Hopf point (x > 0 for a > 0)
    assert hopf.p == pytest.approx(x_h + b * (x_h**3 / 3 - x_h), abs=1e-10)
    assert hopf.data["omega"] == pytest.approx(np.sqrt(1 - b * b / 9), abs=1e-10)
    curve = continue_codim2(br, hopf, "c", ContinuationSettings(p_min=0.0, p_max=10.0))
    assert curve.status is Status.PARAM_BOUND and curve.p.max() == pytest.approx(10.0)
    x, c, a = curve.x[:, 0], curve.p, curve.records["a"]
    np.testing.assert_allclose(x**2, 1 - b / c**2, atol=1e-9)
    np.testing.assert_allclose(a, x + b * (x**3 / 3 - x), atol=1e-9)
    np.testing.assert_allclose(curve.records["omega"] ** 2, 1 - b * b / c**2, atol=1e-9)
    # both arms x < 0 and x > 0 of the U-shaped curve, through its turn at c = sqrt(b)
    assert x.min() < -0.9 and x.max() > 0.9
    assert np.sqrt(b) - 1e-12 <= c.min() < np.sqrt(b) + 0.01
    # l1 against the closed form along the curve
    l1 = _l1_along(curve)
    om2 = 1 - b * b / c**2
    al, be, ga = b / c, c, -1 / c
    N = be**2 + al**2 + om2
    K = -(be**3) * ga / (4 * np.sqrt(om2) * (om2 + al**2) * N)
    ref = K * (6 * (-c / 3) + 4 * (c * x) ** 2 * al / om2)
    np.testing.assert_allclose(l1, ref, rtol=1e-8, atol=1e-10)
    ghs = sorted(curve.find("gh"), key=lambda s: s.data["a"])
    assert len(ghs) == 2 and all(g.located for g in ghs)
    for g, sgn in zip(ghs, (-1, 1), strict=True):
        assert g.p == pytest.approx(np.sqrt(b * b / (2 * b - 1)), abs=1e-9)
        assert g.x[0] == pytest.approx(sgn * np.sqrt((1 - b) / b), abs=1e-8)
        assert g.data["a"] == pytest.approx(sgn * 2 / 15, abs=1e-9)
        assert g.data["omega"] ** 2 == pytest.approx(0.4, abs=1e-9)
    assert not curve.find("bt") and not curve.find("zh") and not curve.find("hh")


@pytest.mark.parametrize("backend", ["casadi", "numpy"])
def test_fitzhugh_nagumo_bautin_points_carry_their_error(backend):
    """The Bautin points of AUTO demo ``fhn`` (closed form ``c^2 = b^2/(2b - 1)``, see
    above) lie within the error they carry: ``|c - c*| <= error / sqrt(theta)``
    (``SpecialPoint.error`` is in pseudo-arclength, ``|dp/ds| <= 1/sqrt(theta)``).

    With CasADi ``l1`` is exact to round-off and the points are located to ``tol``.
    Without it (``backend="numpy"``) ``B(v, v)`` is a second difference with step
    ``h = eps^(1/4)``: round-off ``eps / h^2 ~ sqrt(eps) ~ 1.5e-8`` relative, amplified
    in ``l1`` to noise of about ``2e-7`` (|g'| ~ 1), so the zero of ``l1`` is only known to
    that: the points must say so (``error > tol``) and still cover the true point.
    Regression: they were reported located (to ``tol = 1e-10``) 5e-8 off.
    """
    b = 0.8
    theta = ContinuationSettings().theta
    tol = ContinuationSettings().detect.tol
    br = continue_equilibria(fitzhugh_nagumo(backend), [0, 0], {"a": 0, "b": b, "c": 3.0}, "a",
                             p_min=-0.1, p_max=1.0, direction="forward")  # fmt: skip
    curve = continue_codim2(br, _one(br, "hopf"), "c", ContinuationSettings(p_min=0.0, p_max=10.0))
    ghs = curve.find("gh")
    assert len(ghs) == 2 and all(g.located for g in ghs)
    c_gh = np.sqrt(b * b / (2 * b - 1))
    for g in ghs:
        assert abs(g.p - c_gh) <= g.error / np.sqrt(theta)
        if backend == "casadi":
            assert g.error <= tol
        else:
            assert tol < g.error < 1e-5  # (finite-difference noise, not a lost point)


# ================================================================ A -> B -> C reaction
ABC = {"alpha": 1.0, "B": 8.0, "s": 0.04}  # AUTO-07p demo abc, PAR(2), PAR(4), PAR(5)


def abc_reaction() -> System:
    def rhs(x, p, ops):
        D, al, be, B, s = p[0], p[1], p[2], p[3], p[4]
        e = ops.exp(x[2])
        x1c = 1 - x[0]
        return ops.stack(
            [
                -x[0] + D * x1c * e,
                -x[1] + D * e * (x1c - s * x[1]),
                -x[2] - be * x[2] + D * B * e * (x1c + al * s * x[1]),
            ]
        )

    return System(rhs, ("x1", "x2", "x3"), ("D", "alpha", "beta", "B", "s"))


def _abc_f(x, D, be, al=ABC["alpha"], B=ABC["B"], s=ABC["s"]):
    e = np.exp(x[2])
    return np.array(
        [
            -x[0] + D * (1 - x[0]) * e,
            -x[1] + D * e * (1 - x[0] - s * x[1]),
            -(1 + be) * x[2] + D * B * e * (1 - x[0] + al * s * x[1]),
        ]
    )


def _abc_forms(x, D, be, al=ABC["alpha"], B=ABC["B"], s=ABC["s"]):
    """Jacobian (3, 3) and the multilinear forms B, C, written out.

    ``f = -diag(1, 1, 1 + beta) x + D e^{x3} (L1, L2, B L3)`` with the affine
    ``L1 = 1 - x1``, ``L2 = 1 - x1 - s x2``, ``L3 = 1 - x1 + alpha s x2``; for
    ``g = e^{x3} L``: ``d2g(p, q) = e^{x3} (L p3 q3 + (L'p) q3 + (L'q) p3)`` and
    ``d3g(p, q, r) = e^{x3} (L p3 q3 r3 + (L'p) q3 r3 + (L'q) p3 r3 + (L'r) p3 q3)``.
    """
    e = np.exp(x[2])
    L = np.array([1 - x[0], 1 - x[0] - s * x[1], 1 - x[0] + al * s * x[1]])
    dL = np.array([[-1.0, 0, 0], [-1.0, -s, 0], [-1.0, al * s, 0]])
    w = D * e * np.array([1.0, 1.0, B])
    J = -np.diag([1.0, 1.0, 1 + be]) + w[:, None] * (dL + np.outer(L, [0, 0, 1.0]))

    def Bf(p, q):
        return w * (L * p[2] * q[2] + (dL @ p) * q[2] + (dL @ q) * p[2])

    def Cf(p, q, r):
        return w * (
            L * p[2] * q[2] * r[2]
            + (dL @ p) * q[2] * r[2]
            + (dL @ q) * p[2] * r[2]
            + (dL @ r) * p[2] * q[2]
        )

    return J, Bf, Cf


def _charpoly(J):
    """``[1, c1, ..., cn]`` of ``det(lambda I - J)``."""
    return np.poly(J)


@pytest.fixture(scope="module")
def abc_branch():
    return continue_equilibria(
        abc_reaction(),
        [0.0, 0.0, 0.0],
        {"D": 0.0, "beta": 1.55, **ABC},
        "D",
        p_min=0.0,
        p_max=0.4,
        direction="forward",
    )


def test_abc_reaction_hopf_curve_bt_and_bautin_points(abc_branch):
    """AUTO-07p demo ``abc`` (auto-07p/auto-07p, demos/abc/abc.f90, c.abc.1; Doedel &
    Heinemann 1983, Chem. Eng. Sci. 38, 1493-1499): the A -> B -> C reaction in a CSTR,
    ``x1' = -x1 + D (1 - x1) e^{x3}``, ``x2' = -x2 + D e^{x3} (1 - x1 - s x2)``,
    ``x3' = -x3 - beta x3 + D B e^{x3} (1 - x1 + alpha s x2)``, ``alpha = 1``,
    ``beta = 1.55``, ``B = 8``, ``s = 0.04``, continued in ``D`` from 0 to 0.4 as in the
    demo; the Hopf points then continued in ``(D, beta)``, ``0 <= beta <= 5``.

    References, all independent of the engine: the Hopf curve rows satisfy the
    Routh-Hurwitz condition ``c1 c2 = c3`` of ``lambda^3 + c1 lambda^2 + c2 lambda + c3``
    with ``kappa = c2`` (also on the neutral-saddle part, where ``c2 < 0``); the
    Bogdanov-Takens points solve ``f = 0, c2 = c3 = 0`` (``fsolve``, hand-written ``f``);
    the Bautin points are zeros of :func:`_l1` (eq. (3.20) with the derivatives of
    :func:`_abc_forms`) along the Hopf curve solved by ``fsolve`` at fixed ``beta``,
    found by ``brentq``. Every one of the demo's four Hopf points lies on the same
    closed Hopf curve: each continuation finds the same two BT and four GH points.
    """
    hopfs = abc_branch.find("hopf")
    assert len(hopfs) == 4 and all(h.located for h in hopfs)
    assert not abc_branch.find("fold")
    st = ContinuationSettings(p_min=0.0, p_max=5.0)
    curves = [continue_codim2(abc_branch, h, "beta", st) for h in hopfs]
    for curve in curves:
        assert curve.status is Status.PARAM_BOUND
        for z, be, D, kappa in zip(
            curve.x, curve.p, curve.records["D"], curve.records["kappa"], strict=True
        ):
            assert np.abs(_abc_f(z[:3], D, be)).max() < 1e-9
            c = _charpoly(_abc_forms(z[:3], D, be)[0])
            assert c[1] * c[2] - c[3] == pytest.approx(0.0, abs=1e-8 * max(1.0, abs(c[3])))
            assert kappa == pytest.approx(c[2], abs=1e-8)

    def bt_eqs(v):
        c = _charpoly(_abc_forms(v[:3], v[3], v[4])[0])
        return [*_abc_f(v[:3], v[3], v[4]), c[2], c[3]]

    def hopf_at(beta, guess):
        def eqs(v):
            c = _charpoly(_abc_forms(v[:3], v[3], beta)[0])
            return [*_abc_f(v[:3], v[3], beta), c[1] * c[2] - c[3]]

        v = fsolve(eqs, guess, xtol=1e-12)
        assert np.abs(eqs(v)).max() < 1e-9  # (terms of c1 c2 - c3 reach 1e3)
        return v

    def l1_ref(beta, guess):
        v = hopf_at(beta, guess)
        return _l1(*_abc_forms(v[:3], v[3], beta))[0]

    for curve in curves:
        bts = sorted(curve.find("bt"), key=lambda q: q.p)
        assert len(bts) == 2 and all(q.located for q in bts)
        for q in bts:
            ref = fsolve(bt_eqs, np.array([*q.x[:3], q.data["D"], q.p]) + 1e-4, xtol=1e-12)
            assert np.abs(bt_eqs(ref)).max() < 1e-9  # c3 has terms of order 1e3 at x3 = 12
            assert q.p == pytest.approx(ref[4], abs=1e-8)
            assert q.data["D"] == pytest.approx(ref[3], abs=1e-8)
        ghs = sorted(curve.find("gh"), key=lambda q: q.p)
        assert len(ghs) == 4 and all(q.located for q in ghs)
        for q in ghs:
            guess = [*q.x[:3], q.data["D"]]
            lo, hi = q.p - 1e-3, q.p + 1e-3
            assert l1_ref(lo, guess) * l1_ref(hi, guess) < 0
            beta_gh = brentq(l1_ref, lo, hi, args=(guess,), xtol=1e-13)
            assert q.p == pytest.approx(beta_gh, abs=1e-8)
            assert q.data["D"] == pytest.approx(hopf_at(beta_gh, guess)[3], abs=1e-8)
        assert not curve.find("zh") and not curve.find("hh")
    # one closed curve: the same points from each of the four starts
    for curve in curves[1:]:
        for kind in ("bt", "gh"):
            np.testing.assert_allclose(
                sorted(q.p for q in curve.find(kind)),
                sorted(q.p for q in curves[0].find(kind)),
                atol=1e-8,
            )


# ====================================================================== extended Lorenz-84
L84 = {"alpha": 0.25, "beta": 1.0, "gamma": 0.987, "delta": 1.04, "G": 0.25}


def lorenz84_extended() -> System:
    def rhs(x, p, ops):
        al, be, ga, de, G, F, T = p[0], p[1], p[2], p[3], p[4], p[5], p[6]
        X, Y, Z, U = x[0], x[1], x[2], x[3]
        return ops.stack(
            [
                -(Y**2) - Z**2 - al * X + al * F - ga * U**2,
                X * Y - be * X * Z - Y + G,
                be * X * Y + X * Z - Z,
                -de * U + ga * U * X + T,
            ]
        )

    return System(rhs, ("X", "Y", "Z", "U"), ("alpha", "beta", "gamma", "delta", "G", "F", "T"))


def _l84_f(x, F, T, al=L84["alpha"], be=L84["beta"], ga=L84["gamma"], de=L84["delta"]):
    X, Y, Z, U = x
    G = L84["G"]
    return np.array(
        [
            -(Y**2) - Z**2 - al * X + al * F - ga * U**2,
            X * Y - be * X * Z - Y + G,
            be * X * Y + X * Z - Z,
            -de * U + ga * U * X + T,
        ]
    )


def _l84_jac(x, al=L84["alpha"], be=L84["beta"], ga=L84["gamma"], de=L84["delta"]):
    X, Y, Z, U = x
    return np.array(
        [
            [-al, -2 * Y, -2 * Z, -2 * ga * U],
            [Y - be * Z, X - 1, -be * X, 0.0],
            [be * Y + Z, be * X, X - 1, 0.0],
            [ga * U, 0.0, 0.0, -de + ga * X],
        ]
    )


def _l84_B(p, q, be=L84["beta"], ga=L84["gamma"]):
    """Second derivative of the (quadratic) vector field; the third vanishes."""
    return np.array(
        [
            -2 * (p[1] * q[1] + p[2] * q[2] + ga * p[3] * q[3]),
            p[0] * q[1] + p[1] * q[0] - be * (p[0] * q[2] + p[2] * q[0]),
            be * (p[0] * q[1] + p[1] * q[0]) + p[0] * q[2] + p[2] * q[0],
            ga * (p[3] * q[0] + p[0] * q[3]),
        ]
    )


def _l84_C(p, q, r):
    return np.zeros(4, dtype=complex)


def _l84_branch():
    """Equilibria from the published start ``z0`` (``F = 3``, ``T = 0.04``) in ``F``."""
    z0 = [2.9787004394953343, -0.03868302503393752, 0.058232737694740085, -0.02105288273117459]
    return continue_equilibria(lorenz84_extended(), z0, {**L84, "F": 3.0, "T": 0.04}, "F",
                               p_min=-1.5, p_max=3.0)  # fmt: skip


class TestExtendedLorenz84:
    """Extended Lorenz-84 model of the MatCont tutorials (Kuznetsov), as in the
    BifurcationKit.jl test suite (bifurcationkit/BifurcationKit.jl,
    test/hopf_codim_2/lorenz84.jl): ``X' = -Y^2 - Z^2 - alpha X + alpha F - gamma U^2``,
    ``Y' = X Y - beta X Z - Y + G``, ``Z' = beta X Y + X Z - Z``,
    ``U' = -delta U + gamma U X + T``, ``alpha = 1/4``, ``beta = 1``, ``G = 1/4``,
    ``delta = 1.04``, ``gamma = 0.987``; equilibria from the published start
    ``z0`` at ``F = 3``, ``T = 0.04``, continued in ``F`` over ``[-1.5, 3]``; the fold
    and Hopf points then in ``(F, T)``, ``|T| <= 0.1``.

    Published values (that file): the one-parameter points lie in the bisection
    brackets (2.859863413561998, 2.859897757930758), (2.467211879219629,
    2.467246154619121), (1.619657484413436, 1.6196654620692468) (Hopf) and
    (1.546648372620807, 1.5466483727182652) (fold); a double-Hopf point at
    ``T = ±0.02627393`` (rtol 1e-5 there) and the Bautin point's frequency
    ``omega = 0.6903636672622595`` (atol 1e-5 there). Its fold-curve values
    ``T = 0.02058724, -0.02135893`` (BT) and ``4.983e-5, -4.5281e-4`` (ZH) are not used:
    the model is invariant under ``(U, T) -> (-U, -T)``, so the fold curve and its
    points are symmetric in ``T``, which those bisection values are not.

    Independent references: BT ``f = 0, c3 = c4 = 0``; zero-Hopf
    ``f = 0, c4 = 0, c1 c2 = c3`` (the cubic factor has ``±i omega``, ``c2 > 0``);
    double Hopf ``f = 0, c1 = c3 = 0`` (two imaginary pairs, ``c2^2 > 4 c4 > 0``);
    Hopf ``f = 0, c3 (c1 c2 - c3) = c1^2 c4`` (``omega^2 = c3 / c1``), all for
    ``lambda^4 + c1 lambda^3 + ... + c4``, solved by ``fsolve``; the Bautin point by
    ``brentq`` on :func:`_l1` along that Hopf curve. The cusp is the symmetric
    pitchfork at ``T = 0``: ``U = 0``, ``X = delta/gamma`` (the ``U`` equation
    decouples), ``(Y, Z)`` from the linear ``Y, Z`` equations at that ``X`` and
    ``F = X + (Y^2 + Z^2)/alpha``.
    """

    @pytest.fixture(scope="class")
    @classmethod
    def branch(cls):
        return _l84_branch()

    def test_one_parameter_points_in_the_published_brackets(self, branch):
        brackets = {
            "hopf": [
                (1.619657484413436, 1.6196654620692468),
                (2.467211879219629, 2.467246154619121),
                (2.859863413561998, 2.859897757930758),
            ],
            "fold": [(1.546648372620807, 1.5466483727182652)],
        }
        for kind, refs in brackets.items():
            pts = sorted(branch.find(kind), key=lambda s: s.p)
            assert len(pts) == len(refs) and all(s.located for s in pts)
            for s, (lo, hi) in zip(pts, refs, strict=True):
                # the published brackets come from bisection to ~1e-10: 1e-9 of slack
                assert lo - 1e-9 <= s.p <= hi + 1e-9

    def test_fold_curve_bt_zero_hopf_and_symmetric_cusp(self, branch):
        curve = continue_codim2(
            branch, _one(branch, "fold"), "T", ContinuationSettings(p_min=-0.1, p_max=0.1)
        )
        assert curve.status is Status.PARAM_BOUND

        def bt_eqs(v):
            c = _charpoly(_l84_jac(v[:4]))
            return [*_l84_f(v[:4], v[4], v[5]), c[3], c[4]]

        def zh_eqs(v):
            c = _charpoly(_l84_jac(v[:4]))
            return [*_l84_f(v[:4], v[4], v[5]), c[4], c[1] * c[2] - c[3]]

        for kind, eqs in (("bt", bt_eqs), ("zh", zh_eqs)):
            pts = sorted(curve.find(kind), key=lambda s: s.p)
            assert len(pts) == 2 and all(s.located for s in pts)
            assert pts[0].p == pytest.approx(-pts[1].p, abs=1e-9)  # the symmetry
            for s in pts:
                ref = fsolve(eqs, np.array([*s.x[:4], s.data["F"], s.p]) + 1e-5, xtol=1e-12)
                assert np.abs(eqs(ref)).max() < 1e-11
                assert s.p == pytest.approx(ref[5], abs=1e-9)
                assert s.data["F"] == pytest.approx(ref[4], abs=1e-9)
                if kind == "zh":
                    assert _charpoly(_l84_jac(ref[:4]))[2] > 0  # imaginary pair, no saddle
        cp = _one(curve, "cusp")
        X = L84["delta"] / L84["gamma"]
        Y, Z = np.linalg.solve([[X - 1, -X], [X, X - 1]], [-L84["G"], 0.0])  # beta = 1
        assert abs(cp.p) < 1e-9 and abs(cp.x[3]) < 1e-9
        np.testing.assert_allclose(cp.x[:3], [X, Y, Z], atol=1e-9)
        assert cp.data["F"] == pytest.approx(X + (Y * Y + Z * Z) / L84["alpha"], abs=1e-9)
        assert not curve.find("gh") and not curve.find("hh")

    def test_hopf_curve_bt_bautin_and_double_hopf(self, branch):
        h2 = sorted(branch.find("hopf"), key=lambda s: s.p)[1]  # F = 2.4672
        curve = continue_codim2(branch, h2, "T", ContinuationSettings(p_min=-0.1, p_max=0.1))
        assert curve.status is Status.PARAM_BOUND

        def hopf_eqs(v, T):
            c = _charpoly(_l84_jac(v[:4]))
            return [*_l84_f(v[:4], v[4], T), c[3] * (c[1] * c[2] - c[3]) - c[1] ** 2 * c[4]]

        def hh_eqs(v):
            c = _charpoly(_l84_jac(v[:4]))
            return [*_l84_f(v[:4], v[4], v[5]), c[1], c[3]]

        for z, T, F, kappa in zip(
            curve.x, curve.p, curve.records["F"], curve.records["kappa"], strict=True
        ):
            assert np.abs(hopf_eqs([*z[:4], F], T)).max() < 1e-9
            c = _charpoly(_l84_jac(z[:4]))
            assert kappa == pytest.approx(c[3] / c[1], rel=1e-8)
        for kind, n_pts in (("bt", 2), ("gh", 2), ("hh", 2)):
            pts = sorted(curve.find(kind), key=lambda s: s.p)
            assert len(pts) == n_pts and all(s.located for s in pts), kind
            assert pts[0].p == pytest.approx(-pts[1].p, abs=1e-9)  # the symmetry
        for s in curve.find("hh"):
            ref = fsolve(hh_eqs, np.array([*s.x[:4], s.data["F"], s.p]) + 1e-5, xtol=1e-12)
            assert np.abs(hh_eqs(ref)).max() < 1e-11
            c = _charpoly(_l84_jac(ref[:4]))
            assert c[2] ** 2 > 4 * c[4] > 0  # two imaginary pairs
            assert s.p == pytest.approx(ref[5], abs=1e-9)
            assert abs(s.p) == pytest.approx(0.02627393, rel=1e-5)  # published
        for s in curve.find("bt"):
            bt = fsolve(
                lambda v: [*_l84_f(v[:4], v[4], v[5]), *_charpoly(_l84_jac(v[:4]))[3:]],
                np.array([*s.x[:4], s.data["F"], s.p]) + 1e-5,
                xtol=1e-12,
            )
            assert s.p == pytest.approx(bt[5], abs=1e-9)
            assert s.data["F"] == pytest.approx(bt[4], abs=1e-9)

        def l1_ref(T, guess):
            v = fsolve(hopf_eqs, guess, args=(T,), xtol=1e-12)
            assert np.abs(hopf_eqs(v, T)).max() < 1e-11
            return _l1(_l84_jac(v[:4]), _l84_B, _l84_C)[0]

        for s in curve.find("gh"):
            guess = [*s.x[:4], s.data["F"]]
            T_gh = brentq(l1_ref, s.p - 1e-3, s.p + 1e-3, args=(guess,), xtol=1e-13)
            assert s.p == pytest.approx(T_gh, abs=1e-9)
            # published frequency at the Bautin point (to the 1e-5 printed there)
            assert s.data["omega"] == pytest.approx(0.6903636672622595, abs=1e-5)
        assert not curve.find("zh") and not curve.find("cusp")


# ============================================================ predator-prey with harvesting
PP3 = {"p2": 0.25, "p3": 0.5, "p5": 3.0, "p6": 5.0}  # AUTO-07p demo pp3, STPNT


def pp3() -> System:
    def rhs(u, p, ops):
        p1, p2, p3, p4, p5, p6 = (p[i] for i in range(6))
        return ops.stack(
            [
                u[0] * (1 - u[0]) - p4 * u[0] * u[1],
                -p2 * u[1] + p4 * u[0] * u[1] - p5 * u[1] * u[2] - p1 * (1 - ops.exp(-p6 * u[1])),
                -p3 * u[2] + p5 * u[1] * u[2],
            ]
        )

    return System(rhs, ("u1", "u2", "u3"), ("p1", "p2", "p3", "p4", "p5", "p6"))


def _pp3_plane(p4):
    """The equilibrium in the plane ``u3 = 0`` with ``u2 = p3/p5`` at ``p4``, and there
    ``(p1, u1, J22)`` (see the test's docstring)."""
    p2, p3, p5, p6 = PP3["p2"], PP3["p3"], PP3["p5"], PP3["p6"]
    u2 = p3 / p5
    u1 = 1 - p4 * u2
    p1 = u2 * (p4 * u1 - p2) / (1 - np.exp(-p6 * u2))
    J22 = -p2 + p4 * u1 - p1 * p6 * np.exp(-p6 * u2)
    return p1, u1, u2, J22


@pytest.fixture(scope="module")
def pp3_branch():
    from continuation import switch_branch

    trivial = continue_equilibria(pp3(), [1.0, 0.0, 0.0], {"p1": 0.0, "p4": 4.0, **PP3}, "p1",
                                  p_min=0.0, p_max=1.0)  # fmt: skip
    st = ContinuationSettings(p_min=0.0, p_max=1.0, max_steps=200)
    return switch_branch(trivial, _one(trivial, "bp").label, settings=st)


def test_pp3_fold_curve_bt_points_without_false_cusps(pp3_branch):
    """AUTO-07p demo ``pp3`` (auto-07p/auto-07p, demos/pp3/pp3.f90, pp3.auto): a
    predator-prey-superpredator chain with exponential harvesting,
    ``u1' = u1 (1 - u1) - p4 u1 u2``,
    ``u2' = -p2 u2 + p4 u1 u2 - p5 u2 u3 - p1 (1 - e^{-p6 u2})``,
    ``u3' = -p3 u3 + p5 u2 u3``, ``(p2, p3, p4, p5, p6) = (0.25, 0.5, 4, 3, 5)``:
    from ``u = (1, 0, 0)`` in ``p1``, onto the branch through the transcritical point
    ``p1 = (p4 - p2)/p6 = 0.75`` (as the demo), its fold continued in ``(p1, p4)``.

    Closed forms. The planes ``u2 = 0`` and ``u3 = 0`` are invariant.
    (i) In ``u3 = 0`` the ``u3`` eigenvalue ``-p3 + p5 u2`` vanishes at ``u2 = p3/p5 = 1/6``;
    with ``u1 = 1 - p4 u2`` and ``p1`` from ``u2' = 0`` (:func:`_pp3_plane`) the planar
    block has ``det = u1 (p4^2 u2 - J22)``, so the fold curve meets that eigenvalue at
    ``J22 = p4^2 u2``: two Bogdanov-Takens points (``J`` has rank 2: the third column is
    nonzero). There the left null vector is ``e3`` and ``B(v, v)_3 = 2 p5 v2 v3 = 0``,
    so the cusp test vanishes at the BT points too, while the quadratic coefficient
    ``a`` keeps its sign. Regression: they were also reported as cusps (CP2, CP3).
    (ii) The fold curve meets the transcritical line ``u = (1, 0, 0)``,
    ``p1 = (p4 - p2)/p6`` where the transcritical point's quadratic coefficient
    (``u1 = 1 - p4 u2`` on the centre manifold) ``-p4^2 + p1 p6^2/2`` vanishes:
    ``p4^2 - (p6/2) p4 + p2 p6/2 = 0``, ``p4 = (2.5 -+ sqrt(3.75))/2 = 0.28175, 2.21825``;
    the Moore-Spence cusp test detects both (the fold's ``a`` changes sign there).
    """
    fold = _one(pp3_branch, "fold")
    curve = continue_codim2(pp3_branch, fold, "p4", ContinuationSettings(p_min=0.25, p_max=4.0))
    assert curve.status is Status.PARAM_BOUND
    refs = []
    for lo, hi in ((0.2, 0.6), (1.0, 1.6)):
        p4 = brentq(lambda q: _pp3_plane(q)[3] - q * q * PP3["p3"] / PP3["p5"], lo, hi, xtol=1e-14)
        refs.append((p4, *_pp3_plane(p4)[:3]))
    bts = sorted(curve.find("bt"), key=lambda s: s.p)
    assert len(bts) == 2 and all(s.located for s in bts)
    for s, (p4, p1, u1, u2) in zip(bts, refs, strict=True):
        assert s.p == pytest.approx(p4, abs=1e-9)
        assert s.data["p1"] == pytest.approx(p1, abs=1e-9)
        np.testing.assert_allclose(s.x[:3], [u1, u2, 0.0], atol=1e-8)
    # both roots of the transcritical condition lie in the window; the second sits
    # where the fold curve crosses the transcritical line next to a branch point of the
    # Moore-Spence curve, where the corrector may fail: then it must be reported as
    # bracketed (not located) with the root inside its bracket
    half, disc = PP3["p6"] / 4, np.sqrt(PP3["p6"] ** 2 / 16 - PP3["p2"] * PP3["p6"] / 2)
    roots = (half - disc, half + disc)
    cps = sorted(curve.find("cusp"), key=lambda s: s.p)
    assert len(cps) == 2 and cps[0].located
    # the crossing makes the bordered Jacobian nearly singular there (its smallest
    # singular value is ~2e-3 at the rows around it), so Newton fixes the trial points
    # only to about tol / sigma_min: 1e-8 instead of 1e-9
    for cp, p4 in zip(cps, roots, strict=True):
        if cp.located:
            assert cp.p == pytest.approx(p4, abs=1e-8)
            assert cp.data["p1"] == pytest.approx((p4 - PP3["p2"]) / PP3["p6"], abs=1e-8)
            np.testing.assert_allclose(cp.x[:3], [1.0, 0.0, 0.0], atol=1e-7)
        else:
            assert min(cp.bracket) <= p4 <= max(cp.bracket)


def test_pp3_cusp_next_to_a_branch_point_of_the_fold_curve_carries_its_error(pp3_branch):
    """The degenerate transcritical points of the pp3 fold curve (closed form, see
    above) sit where the fold curve crosses the line of transcritical points: a
    branch point of the Moore-Spence system, where a point with residual ``|G|`` is
    only determined to about ``sqrt(|G|)`` along the near-null direction. Every
    codim-2 point of the curve lies within the error it carries,
    ``|p4 - p4*| <= error / sqrt(theta)``, whether located or not; located points
    with ``error > tol`` say so. Regression: the first was reported located (to
    ``tol = 1e-10``) 4.6e-9 off in ``p4``, its point interpolated next to the branch
    point with a residual of 2e-16 but 2e-8 off the curve in ``u2``."""
    theta = ContinuationSettings().theta
    fold = _one(pp3_branch, "fold")
    curve = continue_codim2(pp3_branch, fold, "p4", ContinuationSettings(p_min=0.25, p_max=4.0))
    half, disc = PP3["p6"] / 4, np.sqrt(PP3["p6"] ** 2 / 16 - PP3["p2"] * PP3["p6"] / 2)
    cps = sorted(curve.find("cusp"), key=lambda s: s.p)
    assert len(cps) == 2
    for cp, p4 in zip(cps, (half - disc, half + disc), strict=True):
        assert np.isfinite(cp.error)
        assert abs(cp.p - p4) <= cp.error / np.sqrt(theta)
    for bt in curve.find("bt"):
        assert bt.located and bt.error <= ContinuationSettings().detect.tol


def test_pp3_hopf_curve_zero_hopf_points(pp3_branch):
    """The Hopf points of the same branch continued in ``(p1, p4)`` (the demo's Hopf
    locus, ``ICP = [1, 4]``) up to ``p4 = 6``. In the plane ``u3 = 0`` the Hopf curve
    (planar trace ``-u1 + J22 = 0``) meets the zero ``u3`` eigenvalue at ``u2 = 1/6``:
    zero-Hopf points with ``J22 = u1`` and ``omega^2 = u1 (p4^2 u2 - u1)``, where the
    Hopf curve of the branch with ``u3 != 0`` crosses it (a branch point of the curve,
    also reported). Both Hopf points of the branch lie on one curve through both.
    """
    hopfs = pp3_branch.find("hopf")
    assert len(hopfs) == 2
    refs = []
    for lo, hi in ((3.0, 4.0), (5.0, 5.9)):
        p4 = brentq(lambda q: _pp3_plane(q)[3] - _pp3_plane(q)[1], lo, hi, xtol=1e-14)
        refs.append((p4, *_pp3_plane(p4)[:3]))
    for h in hopfs:
        curve = continue_codim2(pp3_branch, h, "p4", ContinuationSettings(p_min=0.0, p_max=6.0))
        assert curve.status is Status.PARAM_BOUND
        zhs = sorted(curve.find("zh"), key=lambda s: s.p)
        assert len(zhs) == 2 and all(s.located for s in zhs)
        for s, (p4, p1, u1, u2) in zip(zhs, refs, strict=True):
            assert s.p == pytest.approx(p4, abs=1e-9)
            assert s.data["p1"] == pytest.approx(p1, abs=1e-9)
            np.testing.assert_allclose(s.x[:3], [u1, u2, 0.0], atol=1e-8)
            assert s.data["omega"] ** 2 == pytest.approx(u1 * (p4 * p4 * u2 - u1), abs=1e-9)
        assert len(curve.find("bp")) == 2
        assert not curve.find("bt") and not curve.find("gh") and not curve.find("hh")


def test_extended_lorenz84_points_shared_by_two_curves():
    """Each codim-2 point lies on two codim-1 curves, computed from different augmented
    systems: the zero-Hopf points of the fold curve are on the Hopf curve of the
    first Hopf point (``F = 2.8599``), and the double-Hopf points of that curve are
    those of the second Hopf point's curve, with the two frequencies swapped (setting
    of :class:`TestExtendedLorenz84`)."""
    br = _l84_branch()
    st = ContinuationSettings(p_min=-0.1, p_max=0.1)
    h1, h2 = sorted(br.find("hopf"), key=lambda s: s.p)[::-1][:2]  # F = 2.8599, 2.4672
    fold = continue_codim2(br, _one(br, "fold"), "T", st)
    c1 = continue_codim2(br, h1, "T", st)
    c2 = continue_codim2(br, h2, "T", st)
    for a, b in ((c1.find("zh"), fold.find("zh")), (c1.find("hh"), c2.find("hh"))):
        a, b = sorted(a, key=lambda s: s.p), sorted(b, key=lambda s: s.p)
        assert len(a) == len(b) == 2 and all(s.located for s in a + b)
        for s, t in zip(a, b, strict=True):
            assert s.p == pytest.approx(t.p, abs=1e-9)
            assert s.data["F"] == pytest.approx(t.data["F"], abs=1e-9)
            np.testing.assert_allclose(s.x[:4], t.x[:4], atol=1e-8)
    for s, t in zip(
        sorted(c1.find("hh"), key=lambda s: s.p),
        sorted(c2.find("hh"), key=lambda s: s.p),
        strict=True,
    ):
        lam = np.linalg.eigvals(_l84_jac(s.x[:4]))
        np.testing.assert_allclose(
            sorted(abs(lam.imag))[::2], sorted([s.data["omega"], t.data["omega"]]), atol=1e-8
        )
        assert abs(s.data["omega"] - t.data["omega"]) > 0.1
