"""Published bifurcation problems beyond the engine's own test set (generality audit).

Each test uses the public API the way a researcher would and checks the engine's
answer against a closed form derived from the cited source (the derivation is in the
docstring), a published value, or an independent computation written here (SciPy root
finders on hand-written defining equations, SciPy integrators). None of these problems
is used elsewhere in the test suite; the Nagumo, Fisher-KPP, KdV, damped-pendulum,
CSTR (dimensionless), Brusselator (ODE), Sel'kov, Lorenz-84 and Bratu problems are
covered in ``test_reference_problems.py``, ``test_codim2.py`` and ``test_connection.py``.

Tolerances: equilibria, folds and Hopf points are located by Newton on the defining
systems, so their parameter values are matched to ~1e-9 relative or better (the
locator tolerance is 1e-10); BVP results carry a discretisation error that is bounded
in each test by a convergence study (mesh halving, longer truncation time).
"""

from __future__ import annotations

import numpy as np
import pytest
from connection_problems import lorenz
from helpers import brusselator_rd
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve
from scipy.special import ai_zeros

from continuation.api import continue_equilibria
from continuation.bvp.collocation import CollocationMesh
from continuation.bvp.connection import HeteroclinicProblem, PinPhase
from continuation.bvp.solve import check_convergence, continue_connection, solve_connection
from continuation.codim2 import continue_codim2
from continuation.dynamics import PoincareSection, simulate, unstable_manifold
from continuation.settings import ContinuationSettings
from continuation.status import Status
from continuation.system import System

SQ2 = np.sqrt(2.0)


def _codim2_curve(br, point, free2, window, *, ds, max_steps):
    """The codim-2 curve from ``point`` of ``br`` in ``free2`` over ``window``
    ``(p_min, p_max)`` with steps ``ds = (ds, ds_max)``; asserts that it ran."""
    settings = ContinuationSettings(
        ds=ds[0], ds_max=ds[1], p_min=window[0], p_max=window[1], max_steps=max_steps
    )
    curve = continue_codim2(br, point, free2, settings)
    assert curve.status.ok, curve.message
    return curve


def _one(branch, kind):
    """The single located special point of ``kind`` on ``branch``."""
    found = branch.find(kind)
    assert len(found) == 1, [(s.kind.value, s.p) for s in branch.special_points]
    assert found[0].located
    return found[0]


# =============================================================================== Lorenz
def _lorenz_hopf_r(sigma, beta):
    return sigma * (sigma + beta + 3) / (sigma - beta - 1)


def test_lorenz_pitchfork_and_subcritical_hopf():
    """Lorenz (1963), "Deterministic nonperiodic flow", J. Atmos. Sci. 20:130-141;
    Sparrow (1982), "The Lorenz Equations", ch. 1; Strogatz (2015), "Nonlinear Dynamics
    and Chaos", 2nd ed., sec. 9.2. sigma = 10, beta = 8/3.

    Origin: eigenvalue ``(-(sigma+1) + sqrt((sigma+1)^2 + 4 sigma (r-1)))/2`` crosses 0
    at r = 1, where C+- = (+-sqrt(beta (r-1)), +-sqrt(beta (r-1)), r-1) branch off
    (pitchfork). On C+ the characteristic polynomial is
    ``l^3 + (sigma+beta+1) l^2 + beta (r+sigma) l + 2 beta sigma (r-1)``; it has roots
    ``+-i omega`` where ``(sigma+beta+1) beta (r+sigma) = 2 beta sigma (r-1)``, i.e.
    ``r_H = sigma (sigma+beta+3)/(sigma-beta-1) = 470/19``, ``omega^2 = beta (r_H+sigma)``.
    """
    s = lorenz()
    sigma, beta = 10.0, 8.0 / 3.0
    origin = continue_equilibria(
        s, [0.0, 0.0, 0.0], {"sigma": sigma, "r": 0.5, "beta": beta}, "r", p_min=0.0, p_max=3.0
    )
    bp = _one(origin, "bp")
    assert bp.p == pytest.approx(1.0, abs=1e-10)
    assert np.abs(bp.x).max() < 1e-10
    assert np.all(origin.n_unstable[origin.p < 1 - 1e-6] == 0)
    assert np.all(origin.n_unstable[origin.p > 1 + 1e-6] == 1)
    assert not origin.find("hopf") and not origin.find("fold")

    r0 = 2.0
    c0 = np.sqrt(beta * (r0 - 1))
    cplus = continue_equilibria(
        s,
        [c0, c0, r0 - 1],
        {"sigma": sigma, "r": r0, "beta": beta},
        "r",
        p_max=30.0,
        direction="forward",
    )
    assert cplus.status is Status.PARAM_BOUND
    # the branch stays on C+ (closed form) all along
    np.testing.assert_allclose(cplus.x[:, 0], np.sqrt(beta * (cplus.p - 1)), rtol=1e-9)
    np.testing.assert_allclose(cplus.x[:, 2], cplus.p - 1, rtol=1e-9)
    h = _one(cplus, "hopf")
    r_h = _lorenz_hopf_r(sigma, beta)
    assert r_h == pytest.approx(470 / 19, rel=1e-15)
    assert h.p == pytest.approx(r_h, rel=1e-10)
    assert h.data["omega"] == pytest.approx(np.sqrt(beta * (r_h + sigma)), rel=1e-10)
    assert h.delta_unstable == (0, 1)  # a complex pair becomes unstable
    assert np.all(cplus.n_unstable[cplus.p < r_h - 1e-6] == 0)
    assert np.all(cplus.n_unstable[cplus.p > r_h + 1e-6] == 2)


def test_lorenz_hopf_curve_in_sigma():
    """The Hopf point of C+ continued in (sigma, r): ``r_H(sigma) =
    sigma (sigma+beta+3)/(sigma-beta-1)``, ``omega^2 = beta (r_H + sigma)`` (closed form
    above; Sparrow 1982, sec. 1.2). The curve is exact, so the only error is the Newton
    tolerance of the augmented system (1e-10 in its residual)."""
    s = lorenz()
    beta = 8.0 / 3.0
    r0 = 20.0
    c0 = np.sqrt(beta * (r0 - 1))
    br = continue_equilibria(
        s,
        [c0, c0, r0 - 1],
        {"sigma": 10.0, "r": r0, "beta": beta},
        "r",
        p_max=30.0,
        direction="forward",
    )
    curve = _codim2_curve(br, _one(br, "hopf"), "sigma", (5.0, 30.0), ds=(0.05, 0.5), max_steps=400)
    sg = curve.p
    assert sg.min() == pytest.approx(5.0) and sg.max() == pytest.approx(30.0)
    r_h = _lorenz_hopf_r(sg, beta)
    np.testing.assert_allclose(curve.records["r"], r_h, rtol=1e-9)
    np.testing.assert_allclose(curve.records["omega"], np.sqrt(beta * (r_h + sg)), rtol=1e-9)
    # r_H has its minimum over sigma at sigma = beta+1 + sqrt((beta+1)(2 beta+4))
    assert curve.records["r"].min() == pytest.approx(
        _lorenz_hopf_r(beta + 1 + np.sqrt((beta + 1) * (2 * beta + 4)), beta), rel=1e-4
    )


def test_lorenz_homoclinic_explosion():
    """The first homoclinic orbit of the origin ("homoclinic explosion") of the Lorenz
    system at sigma = 10, beta = 8/3: r = 13.926 (Sparrow 1982, "The Lorenz Equations",
    sec. 3.1; Kaplan & Yorke 1979), r = 13.9265574 (Doedel, Krauskopf & Osinga 2006,
    "Global bifurcations of the Lorenz manifold", Nonlinearity 19:2947-2972).

    Workflow: simulate one branch of the origin's unstable manifold at r = 14, cut it at
    its closest return to the origin, and solve the homoclinic BVP (shift = 0) for r.
    Tolerance: the published value has 8 digits (5e-8 rounding); the collocation error
    is bounded below by re-solving on a halved mesh and a longer interval (here both
    changes are < 1e-7, see the convergence check), so 2e-7 is a tight bound.
    """
    s = lorenz()
    par = s.params(sigma=10.0, r=14.0, beta=8.0 / 3.0)
    wu = unstable_manifold(s, par, [0.0, 0.0, 0.0], eps=1e-6, t_max=5.0, branches=(1,))
    assert wu.eigenvalue == pytest.approx((-11 + np.sqrt(81 + 40 * 14.0)) / 2, rel=1e-12)
    t, x = wu.plus.as_guess()
    d = np.linalg.norm(x, axis=1)
    k = int(np.argmax(d))
    k += int(np.argmin(d[k:]))  # closest return after the excursion
    prob = HeteroclinicProblem(
        s,
        par,
        "r",
        saddle_from=[0.0, 0.0, 0.0],
        shift=[0.0, 0.0, 0.0],
        mesh=CollocationMesh(160, 4, 8.0),
    )
    res = solve_connection(prob, (t[: k + 1], x[: k + 1]))
    assert res.success, res.message
    assert res.value("r") == pytest.approx(13.9265574, abs=2e-7)
    ck = check_convergence(res)
    assert ck.ok and ck.converged(1e-7)
    # a converged result is a good guess on a longer interval (same time scale: the
    # orbit is centred, not stretched) and the answer does not move
    longer = solve_connection(prob.replace(mesh=CollocationMesh(320, 4, 16.0)), res)
    assert longer.success, longer.message
    assert longer.newton_iters <= 4
    assert longer.value("r") == pytest.approx(res.value("r"), abs=1e-8)


# ============================================================== Rosenzweig-MacArthur
def rosenzweig_macarthur() -> System:
    def rhs(x, p, ops):
        K, m, d = p[0], p[1], p[2]
        g = m * x[0] / (1 + x[0])  # Holling type II functional response
        return ops.stack([x[0] * (1 - x[0] / K) - g * x[1], x[1] * (g - d)])

    return System(rhs, ("x", "y"), ("K", "m", "d"))


def test_rosenzweig_macarthur_transcritical_and_hopf():
    """Rosenzweig & MacArthur (1963), Am. Nat. 97:209-223; "paradox of enrichment"
    (Rosenzweig 1971, Science 171:385-387). Scaled form
    ``x' = x (1 - x/K) - m x y/(1+x)``, ``y' = y (m x/(1+x) - d)``, m = 1, d = 0.4.

    Coexistence: ``x* = d/(m-d)``, ``y* = (1 - x*/K)(1 + x*)/m``; it meets the prey-only
    state (K, 0) at K = x* (transcritical branch point). At the coexistence point
    ``J11 = x* (1 - 1/K - 2x*/K)/(1+x*)``, ``J12 = -d``, ``J22 = 0``, so the Hopf point is
    ``trace = 0 <=> K_H = 1 + 2 x* = (m+d)/(m-d)`` with
    ``omega^2 = det = d (1 - x*/K)/(1+x*) = d (m-d)/(m+d)``.
    """
    s = rosenzweig_macarthur()
    m, d = 1.0, 0.4
    xs = d / (m - d)
    K_h = (m + d) / (m - d)
    K0 = 1.5
    coex = continue_equilibria(
        s,
        [xs, (1 - xs / K0) * (1 + xs) / m],
        {"K": K0, "m": m, "d": d},
        "K",
        p_min=0.3,
        p_max=6.0,
    )
    bp = _one(coex, "bp")
    assert bp.p == pytest.approx(xs, rel=1e-10)
    # state to the locator's tolerance times dy*/dK = x* (1 + x*)/K^2 = 2.5
    np.testing.assert_allclose(bp.x, [xs, 0.0], atol=1e-9)
    h = _one(coex, "hopf")
    assert h.p == pytest.approx(K_h, rel=1e-10)
    assert h.data["omega"] == pytest.approx(np.sqrt(d * (m - d) / (m + d)), rel=1e-10)
    np.testing.assert_allclose(coex.x[:, 0], xs, rtol=1e-10)  # x* does not depend on K
    between = (coex.p > xs + 1e-6) & (coex.p < K_h - 1e-6)
    assert between.any() and np.all(coex.n_unstable[between] == 0)  # stable in between
    assert np.all(coex.n_unstable[coex.p > K_h + 1e-6] == 2)  # enrichment destabilises
    # the prey-only branch (K, 0) has the same branch point
    prey = continue_equilibria(s, [2.0, 0.0], {"K": 2.0, "m": m, "d": d}, "K", p_min=0.1, p_max=4.0)
    np.testing.assert_allclose(prey.x[:, 0], prey.p, rtol=1e-10)
    bp2 = _one(prey, "bp")
    assert bp2.p == pytest.approx(xs, rel=1e-10)
    assert not prey.find("hopf")


def test_rosenzweig_macarthur_hopf_curve():
    """The Hopf point continued in (d, K): ``K_H(d) = (m+d)/(m-d)``,
    ``omega(d) = sqrt(d (m-d)/(m+d))`` (closed form of the previous test)."""
    s = rosenzweig_macarthur()
    m, d = 1.0, 0.4
    br = continue_equilibria(
        s, [2 / 3, 0.9], {"K": 2.0, "m": m, "d": d}, "K", p_max=4.0, direction="forward"
    )
    curve = _codim2_curve(br, _one(br, "hopf"), "d", (0.05, 0.9), ds=(0.01, 0.05), max_steps=400)
    dd = curve.p
    assert dd.min() == pytest.approx(0.05) and dd.max() == pytest.approx(0.9)
    np.testing.assert_allclose(curve.records["K"], (m + dd) / (m - dd), rtol=1e-10)
    np.testing.assert_allclose(
        curve.records["omega"], np.sqrt(dd * (m - dd) / (m + dd)), rtol=1e-10
    )
    assert not curve.special_points  # no codim-2 point on this curve


# =============================================================================== Rossler
def rossler() -> System:
    def rhs(x, p, ops):
        a, b, c = p[0], p[1], p[2]
        return ops.stack([-x[1] - x[2], x[0] + a * x[1], b + x[2] * (x[0] - c)])

    return System(rhs, ("x", "y", "z"), ("a", "b", "c"))


def _rossler_jac(x, a, c):
    return np.array([[0.0, -1.0, -1.0], [1.0, a, 0.0], [x[2], 0.0, x[0] - c]])


def _rossler_inner(a, b, c):
    """Equilibrium nearest the origin: x = -a y, z = -y, a y^2 + c y + b = 0."""
    y = (-c + np.sqrt(c * c - 4 * a * b)) / (2 * a)
    return np.array([-a * y, y, -y])


def test_rossler_hopf_against_routh_hurwitz_and_fold():
    """Rossler (1976), "An equation for continuous chaos", Phys. Lett. A 57:397-398,
    b = 0.2, c = 5.7.

    Equilibria: ``x = -a y``, ``z = -y``, ``a y^2 + c y + b = 0``; they fold where
    ``c^2 = 4 a b``. Hopf of the inner equilibrium in ``a``: reference from the
    Routh-Hurwitz condition ``c2 c1 = c0`` of ``l^3 + c2 l^2 + c1 l + c0`` (hand-written
    Jacobian, closed-form equilibrium, Brent's method), ``omega^2 = c1``.
    """
    s = rossler()
    b, c = 0.2, 5.7

    def hurwitz(a):
        cc = np.poly(_rossler_jac(_rossler_inner(a, b, c), a, c))
        return cc[1] * cc[2] - cc[3]

    a_ref = brentq(hurwitz, 1e-3, 0.1, xtol=1e-15)
    c1 = np.poly(_rossler_jac(_rossler_inner(a_ref, b, c), a_ref, c))[2]
    a0 = 0.2
    br = continue_equilibria(
        s, _rossler_inner(a0, b, c), {"a": a0, "b": b, "c": c}, "a", p_min=-0.3, p_max=0.5
    )
    h = _one(br, "hopf")
    assert h.p == pytest.approx(a_ref, rel=1e-9)
    assert h.data["omega"] == pytest.approx(np.sqrt(c1), rel=1e-10)
    np.testing.assert_allclose(h.x, _rossler_inner(a_ref, b, c), atol=1e-10)
    # fold in c of the two equilibria at c = 2 sqrt(a b)
    a = 0.2
    fb = continue_equilibria(
        s, _rossler_inner(a, b, c), {"a": a, "b": b, "c": c}, "c", p_min=0.1, p_max=10.0,
        max_steps=2000,
    )  # fmt: skip
    f = _one(fb, "fold")
    assert f.p == pytest.approx(2 * np.sqrt(a * b), rel=1e-10)
    np.testing.assert_allclose(f.x, [f.p / 2, -f.p / (2 * a), f.p / (2 * a)], rtol=1e-6)


def test_rossler_fold_curve_zero_hopf_and_bogdanov_takens():
    """Fold curve of the Rossler equilibria in (a, c) with b = 0.3: ``c^2 = 4 a b``.

    On it ``y = -c/(2a)``, ``x = c/2``, ``z = c/(2a)``, so ``trace J = a - c/2`` and the
    sum of the principal 2x2 minors is ``c1 = 1 + c/(2a) - a c/2``; ``det J = 0``. The
    characteristic polynomial is ``l (l^2 - trace l + c1)``:
    zero-Hopf (Gavrilov-Guckenheimer) where trace = 0, c1 > 0: ``a = b``, ``c = 2b``,
    ``omega^2 = 2 - b^2``; Bogdanov-Takens where ``c1 = 0`` (root of a scalar equation,
    Brent's method). Derived from Rossler (1976) as above.
    """
    s = rossler()
    a, b = 0.2, 0.3
    br = continue_equilibria(
        s, _rossler_inner(a, b, 5.7), {"a": a, "b": b, "c": 5.7}, "c", p_min=0.1, p_max=10.0,
        max_steps=2000,
    )  # fmt: skip
    curve = _codim2_curve(br, _one(br, "fold"), "a", (0.05, 3.0), ds=(0.01, 0.1), max_steps=500)
    np.testing.assert_allclose(curve.records["c"] ** 2, 4 * curve.p * b, rtol=1e-10)
    zh = _one(curve, "zh")
    assert zh.p == pytest.approx(b, rel=1e-9)
    assert zh.data["c"] == pytest.approx(2 * b, rel=1e-9)
    eig = np.linalg.eigvals(_rossler_jac(zh.x[:3], zh.p, zh.data["c"]))
    eig = eig[np.argsort(np.abs(eig))]
    assert abs(eig[0]) < 1e-7
    np.testing.assert_allclose(
        np.sort(eig[1:].imag), np.array([-1, 1]) * np.sqrt(2 - b * b), rtol=1e-7
    )

    def c1(a):
        c = 2 * np.sqrt(a * b)
        return 1 + c / (2 * a) - a * c / 2

    a_bt = brentq(c1, 0.5, 5.0, xtol=1e-15)
    bt = _one(curve, "bt")
    assert bt.p == pytest.approx(a_bt, rel=1e-9)
    assert bt.data["c"] == pytest.approx(2 * np.sqrt(a_bt * b), rel=1e-9)


# ===================================================================== cusps, pitchforks
def spruce_budworm() -> System:
    def rhs(x, p, ops):
        r, k = p[0], p[1]
        return ops.stack([r * x[0] * (1 - x[0] / k) - x[0] ** 2 / (1 + x[0] ** 2)])

    return System(rhs, ("x",), ("r", "k"))


def test_spruce_budworm_folds_and_cusp():
    """Spruce budworm outbreaks: Ludwig, Jones & Holling (1978), J. Anim. Ecol.
    47:315-332; Strogatz (2015), sec. 3.7: ``x' = r x (1 - x/k) - x^2/(1+x^2)``.

    Nonzero equilibria satisfy ``r (1 - x/k) = x/(1+x^2)``; with the fold condition this
    gives the fold curve parametrically, ``r = 2x^3/(1+x^2)^2``, ``k = 2x^3/(x^2-1)``,
    with its cusp at ``x = sqrt 3``: ``(k, r) = (3 sqrt 3, 3 sqrt 3 / 8)``. At k = 10 the
    fold points are the roots ``x > 1`` of ``2 x^3 - 10 x^2 + 10 = 0``.
    """
    s = spruce_budworm()
    k = 10.0
    x0 = 5.0
    r0 = x0 / (1 + x0**2) / (1 - x0 / k)
    br = continue_equilibria(s, [x0], {"r": r0, "k": k}, "r", p_min=0.2, p_max=0.8, ds_max=0.05)
    roots = np.roots([2.0, -k, 0.0, k])
    xf = np.sort(roots[(np.abs(roots.imag) < 1e-12) & (roots.real > 1)].real)
    folds = sorted(br.find("fold"), key=lambda f: f.x[0])
    assert len(folds) == 2 and all(f.located for f in folds)
    for f, x in zip(folds, xf, strict=True):
        assert f.p == pytest.approx(2 * x**3 / (1 + x**2) ** 2, rel=1e-10)
        assert f.x[0] == pytest.approx(x, rel=1e-6)  # sqrt of the locator tolerance
    curve = _codim2_curve(br, folds[0], "k", (3.0, 20.0), ds=(0.05, 0.2), max_steps=500)
    xx = curve.x[:, 0]
    np.testing.assert_allclose(curve.records["r"], 2 * xx**3 / (1 + xx**2) ** 2, rtol=1e-10)
    np.testing.assert_allclose(curve.p, 2 * xx**3 / (xx**2 - 1), rtol=1e-10)
    cp = _one(curve, "cusp")
    assert cp.p == pytest.approx(3 * np.sqrt(3), rel=1e-9)
    assert cp.data["r"] == pytest.approx(3 * np.sqrt(3) / 8, rel=1e-9)
    assert cp.x[0] == pytest.approx(np.sqrt(3), rel=1e-6)


def mean_field() -> System:
    def rhs(x, p, ops):
        beta, h = p[0], p[1]
        return ops.stack([-x[0] + ops.tanh(beta * x[0] + h)])

    return System(rhs, ("m",), ("beta", "h"))


def test_mean_field_magnet_pitchfork_folds_and_cusp():
    """Curie-Weiss mean-field magnet, relaxational dynamics ``m' = -m + tanh(beta m + h)``
    (e.g. Stanley 1971, "Introduction to Phase Transitions and Critical Phenomena",
    ch. 6): a non-polynomial cusp.

    With ``t = tanh(beta m + h) = m`` the fold condition ``beta (1 - t^2) = 1`` gives
    ``m = +-sqrt(1 - 1/beta)``, ``h = atanh(m) - beta m``: the fold curve, with its
    cusp at ``(beta, h) = (1, 0)``. At h = 0 the symmetric state m = 0 loses
    stability at beta = 1 (pitchfork; a branch point on the trivial branch).
    """
    s = mean_field()
    trivial = continue_equilibria(s, [0.0], {"beta": 0.5, "h": 0.0}, "beta", p_min=0.2, p_max=2)
    bp = _one(trivial, "bp")
    assert bp.p == pytest.approx(1.0, abs=1e-10)
    assert bp.delta_unstable == (1, 0)
    beta = 2.0
    br = continue_equilibria(s, [0.0], {"beta": beta, "h": 0.0}, "h", p_min=-1, p_max=1)
    folds = sorted(br.find("fold"), key=lambda f: f.p)
    m_f = np.sqrt(1 - 1 / beta)
    h_f = np.arctanh(m_f) - beta * m_f
    assert len(folds) == 2 and all(f.located for f in folds)
    assert folds[0].p == pytest.approx(h_f, rel=1e-10)
    assert folds[1].p == pytest.approx(-h_f, rel=1e-10)
    curve = _codim2_curve(br, folds[0], "beta", (0.5, 3.0), ds=(0.02, 0.1), max_steps=500)
    m, b = curve.x[:, 0], curve.p
    np.testing.assert_allclose(b * (1 - m**2), 1.0, rtol=1e-10)
    np.testing.assert_allclose(curve.records["h"], np.arctanh(m) - b * m, atol=1e-12)
    cp = _one(curve, "cusp")
    assert cp.p == pytest.approx(1.0, abs=1e-9)
    assert abs(cp.data["h"]) < 1e-12 and abs(cp.x[0]) < 1e-8


# ============================================================================== Bazykin
def bazykin() -> System:
    def rhs(x, p, ops):
        alpha, delta, gamma, eps = p[0], p[1], p[2], p[3]
        g = x[0] * x[1] / (1 + alpha * x[0])
        return ops.stack([x[0] - g - eps * x[0] ** 2, -gamma * x[1] + g - delta * x[1] ** 2])

    return System(rhs, ("x", "y"), ("alpha", "delta", "gamma", "eps"))


def _bazykin_f(x, alpha, delta, gamma=1.0, eps=0.01):
    X, Y = x
    g = X * Y / (1 + alpha * X)
    return np.array([X - g - eps * X**2, -gamma * Y + g - delta * Y**2])


def _bazykin_jac(x, alpha, delta, gamma=1.0, eps=0.01):
    X, Y = x
    q = 1 + alpha * X
    gx, gy = Y / q**2, X / q
    return np.array([[1 - gx - 2 * eps * X, -gy], [gx, -gamma + gy - 2 * delta * Y]])


def _bazykin_hessians(x, alpha, delta, eps=0.01):
    """Second derivatives (2, 2) of f1 and f2, written out."""
    X, Y = x
    q = 1 + alpha * X
    gxx, gxy = -2 * alpha * Y / q**3, 1 / q**2
    return (
        np.array([[-gxx - 2 * eps, -gxy], [-gxy, 0.0]]),
        np.array([[gxx, gxy], [gxy, -2 * delta]]),
    )


def test_bazykin_predator_prey_bogdanov_takens_and_cusp():
    """Bazykin's predator-prey system (Bazykin 1998, "Nonlinear Dynamics of Interacting
    Populations", World Scientific; Kuznetsov 2004, "Elements of Applied Bifurcation
    Theory", 3rd ed., ch. 8 example):
    ``x' = x - x y/(1 + alpha x) - eps x^2``, ``y' = -gamma y + x y/(1 + alpha x) - delta y^2``,
    gamma = 1, eps = 0.01, parameters (alpha, delta).

    Reference: the Bogdanov-Takens points solve ``f = 0, trace J = 0, det J = 0`` in
    (x, y, alpha, delta), here solved independently by ``fsolve`` with a hand-written
    Jacobian. Both points must be found on the fold curve *and* on the Hopf curve. The
    cusp is checked by its definition: at the located point ``det J = 0`` and the
    quadratic coefficient ``w^T D^2 f(v, v)`` (hand-written second derivatives; ``v``,
    ``w`` the null vectors of J from an SVD) vanishes.
    """
    s = bazykin()
    base = {"alpha": 0.1, "delta": 0.05, "gamma": 1.0, "eps": 0.01}
    x0 = fsolve(lambda x: _bazykin_f(x, 0.1, 0.05), [2.0, 1.0], xtol=1e-14)
    br = continue_equilibria(s, x0, base, "alpha", p_min=0.0, p_max=1.0, max_steps=2000)
    folds = br.find("fold")
    assert len(folds) == 2
    st = ContinuationSettings(ds=0.01, ds_max=0.05, p_min=0.0, p_max=1.0, max_steps=1000)
    fold_curve = continue_codim2(br, folds[0], "delta", st)
    hopf_curve = continue_codim2(br, _one(br, "hopf"), "delta", st)
    assert fold_curve.status.ok and hopf_curve.status.ok

    def bt_eqs(v):
        J = _bazykin_jac(v[:2], v[2], v[3])
        return [*_bazykin_f(v[:2], v[2], v[3]), np.trace(J), np.linalg.det(J)]

    refs = [fsolve(bt_eqs, g, xtol=1e-13) for g in ([6.2, 3.6, 0.45, 0.17], [42, 21, 0.86, 0.006])]
    for ref in refs:
        assert np.max(np.abs(bt_eqs(ref))) < 1e-10
    for curve in (fold_curve, hopf_curve):
        bts = sorted(curve.find("bt"), key=lambda q: q.p)
        assert len(bts) == 2 and all(q.located for q in bts)
        for q, ref in zip(bts, sorted(refs, key=lambda v: v[3]), strict=True):
            assert q.p == pytest.approx(ref[3], rel=1e-8)
            assert q.data["alpha"] == pytest.approx(ref[2], rel=1e-8)
            np.testing.assert_allclose(q.x[:2], ref[:2], rtol=1e-6)
    cp = _one(fold_curve, "cusp")
    x, alpha, delta = cp.x[:2], cp.data["alpha"], cp.p
    J = _bazykin_jac(x, alpha, delta)
    u, sv, vt = np.linalg.svd(J)
    assert sv[1] < 1e-10 * sv[0]  # a fold: J singular
    v, w = vt[-1], u[:, -1]  # right and left null vectors
    H = _bazykin_hessians(x, alpha, delta)
    coef = w @ np.array([v @ Hi @ v for Hi in H])
    # the coefficient is O(1e-2) along the curve (it changes sign at the cusp); at the
    # located point it vanishes to the locator's tolerance
    assert abs(coef) < 1e-10
    assert max(abs(v @ Hi @ v) for Hi in H) > 1e-3


# ======================================================================= dimensional CSTR
CSTR_DATA = {  # Henson & Seborg (1997), "Nonlinear Process Control", Prentice Hall
    "q": 100.0,  # L/min
    "V": 100.0,  # L
    "Cf": 1.0,  # mol/L
    "Tf": 350.0,  # K
    "k0": 7.2e10,  # 1/min
    "ER": 8750.0,  # K
    "dH": -5.0e4,  # J/mol
    "rho": 1000.0,  # g/L
    "cp": 0.239,  # J/(g K)
    "UA": 5.0e4,  # J/(min K)
}


def test_dimensional_cstr_in_kelvin_folds_and_hopf():
    """Exothermic CSTR in dimensional variables (concentration in mol/L, temperature in
    K, rate constant 7.2e10/min with E/R = 8750 K), coolant temperature ``Tc`` as the
    parameter (data of the classic example of Henson & Seborg 1997, ch. 1; Morningred
    et al. 1992):

    ``C' = q/V (Cf - C) - k(T) C``,
    ``T' = q/V (Tf - T) + (-dH)/(rho cp) k(T) C - UA/(V rho cp) (T - Tc)``,
    ``k = k0 exp(-E/(R T))``.

    Badly scaled on purpose (state entries 0.1 and 400, exp of -25). Reference: the
    steady states parametrised by T, ``C(T) = q Cf/(q + V k)``,
    ``Tc(T) = T - (q rho cp (Tf - T) + (-dH) V k C)/UA``; folds where ``dTc/dT = 0``
    (derivative written out), Hopf where ``trace J = 0`` with ``det J > 0``; each a 1-D
    Brent root, independent of the engine.
    """
    P = CSTR_DATA
    a = P["q"] / P["V"]
    bq = -P["dH"] / (P["rho"] * P["cp"])
    gq = P["UA"] / (P["V"] * P["rho"] * P["cp"])

    def rhs(x, p, ops):
        C, T = x[0], x[1]
        k = P["k0"] * ops.exp(-P["ER"] / T)
        return ops.stack(
            [a * (P["Cf"] - C) - k * C, a * (P["Tf"] - T) + bq * k * C - gq * (T - p[0])]
        )

    s = System(rhs, ("C", "T"), ("Tc",))

    def k_(T):
        return P["k0"] * np.exp(-P["ER"] / T)

    def C_(T):
        return P["q"] * P["Cf"] / (P["q"] + P["V"] * k_(T))

    def Tc_(T):
        return (
            T
            - (P["q"] * P["rho"] * P["cp"] * (P["Tf"] - T) + -P["dH"] * P["V"] * k_(T) * C_(T))
            / P["UA"]
        )

    def dTc(T):
        dk = k_(T) * P["ER"] / T**2
        d_kC = P["q"] ** 2 * P["Cf"] * dk / (P["q"] + P["V"] * k_(T)) ** 2
        return 1 - (-P["q"] * P["rho"] * P["cp"] + -P["dH"] * P["V"] * d_kC) / P["UA"]

    def jac(T):
        k, C = k_(T), C_(T)
        dk = k * P["ER"] / T**2
        return np.array([[-a - k, -dk * C], [bq * k, -a + bq * dk * C - gq]])

    T_fold = [brentq(dTc, 330, 345, xtol=1e-13), brentq(dTc, 350, 370, xtol=1e-13)]
    T_hopf = brentq(lambda T: np.trace(jac(T)), 370, 390, xtol=1e-13)
    assert np.linalg.det(jac(T_hopf)) > 0
    # the other zero of the trace (T ~ 337.1) lies on the middle (saddle) branch: det < 0
    T_ns = brentq(lambda T: np.trace(jac(T)), 336, 338.5, xtol=1e-13)
    assert np.linalg.det(jac(T_ns)) < 0

    T0 = 320.0
    br = continue_equilibria(
        s, [C_(T0), T0], {"Tc": Tc_(T0)}, "Tc", p_min=250, p_max=350, ds=0.1, ds_max=1.0,
        max_steps=3000,
    )  # fmt: skip
    assert br.status is Status.PARAM_BOUND, br.message
    folds = sorted(br.find("fold"), key=lambda f: f.x[1])
    assert len(folds) == 2 and all(f.located for f in folds)
    for f, T in zip(folds, T_fold, strict=True):
        assert f.p == pytest.approx(Tc_(T), rel=1e-12)  # 300 K to ~3e-10 K
        assert f.x[1] == pytest.approx(T, rel=1e-6)
    h = _one(br, "hopf")
    assert h.p == pytest.approx(Tc_(T_hopf), rel=1e-12)
    assert h.x[1] == pytest.approx(T_hopf, rel=1e-10)
    assert h.data["omega"] == pytest.approx(np.sqrt(np.linalg.det(jac(T_hopf))), rel=1e-8)


# ======================================================== Brusselator reaction-diffusion
def test_brusselator_reaction_diffusion_hopf_on_the_sparse_path():
    """Brusselator reaction-diffusion (Prigogine & Lefever 1968, J. Chem. Phys.
    48:1695; Nicolis & Prigogine 1977, ch. 7), u_t = D1 u_xx + A - (B+1) u + u^2 v,
    v_t = D2 v_xx + B u - u^2 v on [0, 1], u = A, v = B/A at both ends; N = 100
    interior nodes, n = 200 unknowns (sparse LU, ARPACK eigenvalues).

    The homogeneous state (A, B/A) solves the discrete problem exactly. On the
    discrete sine mode k the Laplacian is ``-mu_k``, ``mu_k = (4/h^2) sin^2(k pi h/2)``,
    so the linearisation splits into 2x2 blocks
    ``[[B-1-D1 mu_k, A^2], [-B, -A^2-D2 mu_k]]``: mode k has a Hopf point at
    ``B = 1 + A^2 + (D1+D2) mu_k`` (if det > 0 there), with ``omega^2 = det``. With
    D1 = 0.008, D2 = 0.004 the Turing instability (det = 0) needs B > 14, far away.
    """
    N, A, D1, D2 = 100, 2.0, 0.008, 0.004
    s = brusselator_rd(N, D1, D2)
    h = 1.0 / (N + 1)
    mu = 4 / h**2 * np.sin(np.arange(1, 3) * np.pi * h / 2) ** 2
    B_h = 1 + A**2 + (D1 + D2) * mu
    om = np.sqrt((B_h - 1 - D1 * mu) * (-(A**2) - D2 * mu) + A**2 * B_h)
    B0 = 3.0
    br = continue_equilibria(
        s, np.r_[np.full(N, A), np.full(N, B0 / A)], {"A": A, "B": B0}, "B",
        p_min=2.0, p_max=6.0, direction="forward",
    )  # fmt: skip
    assert br.problem.sparse
    hopfs = sorted(br.find("hopf"), key=lambda q: q.p)
    assert len(hopfs) == 2 and all(q.located for q in hopfs)
    for q, Bk, wk in zip(hopfs, B_h, om, strict=True):
        assert q.p == pytest.approx(Bk, rel=1e-10)
        assert q.data["omega"] == pytest.approx(wk, rel=1e-8)
    np.testing.assert_allclose(br.n_unstable, 2 * (br.p > B_h[0]) + 2 * (br.p > B_h[1]))


# ============================================================================ Oregonator
def test_two_variable_oregonator_hopf_points():
    """Two-variable Oregonator of the Belousov-Zhabotinsky reaction (Field & Noyes
    1974, J. Chem. Phys. 60:1877; reduced form of Tyson & Fife 1980, J. Chem. Phys.
    73:2224): ``eps x' = x (1 - x) - f z (x - q)/(x + q)``, ``z' = x - z``,
    eps = 0.04, q = 8e-4 (stiff; the state spans 2e-3..0.5).

    Equilibrium ``z = x``, ``-x^2 + (1 - q - f) x + q (1 + f) = 0`` (positive root); the
    Hopf points are the zeros of ``trace J`` (Brent's method on the hand-written
    Jacobian): oscillations for f between about 1/2 and 1 + sqrt 2 as q -> 0.
    """
    eps, q = 0.04, 8e-4

    def rhs(x, p, ops):
        f = p[0]
        return ops.stack(
            [(x[0] * (1 - x[0]) - f * x[1] * (x[0] - q) / (x[0] + q)) / eps, x[0] - x[1]]
        )

    s = System(rhs, ("x", "z"), ("f",))

    def xs(f):
        return float(np.max(np.roots([-1.0, 1 - q - f, q * (1 + f)]).real))

    def jac(f):
        x = xs(f)
        g, dg = (x - q) / (x + q), 2 * q / (x + q) ** 2
        return np.array([[(1 - 2 * x - f * x * dg) / eps, -f * g / eps], [1.0, -1.0]])

    f_ref = [
        brentq(lambda f: np.trace(jac(f)), lo, hi, xtol=1e-15) for lo, hi in ((0.4, 0.7), (2, 3))
    ]
    assert f_ref[1] == pytest.approx(1 + SQ2, rel=0.05)  # the q -> 0 limit
    br = continue_equilibria(
        s, [xs(0.3)] * 2, {"f": 0.3}, "f", p_min=0.2, p_max=3.0, direction="forward"
    )
    hopfs = sorted(br.find("hopf"), key=lambda q_: q_.p)
    assert len(hopfs) == 2 and all(h.located for h in hopfs)
    for h, f in zip(hopfs, f_ref, strict=True):
        assert h.p == pytest.approx(f, rel=1e-10)
        assert h.data["omega"] == pytest.approx(np.sqrt(np.linalg.det(jac(f))), rel=1e-8)
        assert h.x[0] == pytest.approx(xs(f), rel=1e-8)


# ===================================================================== van der Pol period
def test_van_der_pol_relaxation_period():
    """Period of the van der Pol relaxation oscillation, Lienard form
    ``x' = mu (y - x^3/3 + x)``, ``y' = -x/mu``: Dorodnitsyn (1947) / Grasman (1987),
    "Asymptotic Methods for Relaxation Oscillations and Applications", sec. 3.2:
    ``T = (3 - 2 ln 2) mu + 3 a mu^(-1/3) - (2/3) mu^(-1) ln mu + O(1/mu)``, ``-a`` the
    first zero of Airy Ai (Strogatz 2015, sec. 7.5, gives the leading term).

    ``simulate`` (CVODES, stiff) measures T from Poincare crossings. At mu = 1000 the
    O(1/mu) remainder is ~1.4e-3 (it scales as 1/mu between mu = 100 and 1000), so
    3/mu bounds it. At mu = 10 the reference is SciPy's DOP853 (explicit, written here) with its own
    events.
    """

    def rhs(x, p, ops):
        mu = p[0]
        return ops.stack([mu * (x[1] - (x[0] ** 3 / 3 - x[0])), -x[0] / mu])

    s = System(rhs, ("x", "y"), ("mu",))
    a = -ai_zeros(1)[0][0]
    for mu in (100.0, 1000.0):
        tr = simulate(s, [2.0, 0.0], {"mu": mu}, (0.0, 8 * mu),
                      events=[PoincareSection("y", 0.0, direction=-1, name="sec")])  # fmt: skip
        assert tr.status is Status.SUCCESS
        T = np.diff(np.asarray(tr.events["sec"].t))
        assert T.size >= 3
        assert abs(T[-1] - T[-2]) < 1e-5 * T[-1]  # on the limit cycle
        T_as = (3 - 2 * np.log(2)) * mu + 3 * a * mu ** (-1 / 3) - 2 / 3 * np.log(mu) / mu
        assert abs(T[-1] - T_as) < 3 / mu
    mu = 10.0
    tr = simulate(s, [2.0, 0.0], {"mu": mu}, (0.0, 100.0),
                  events=[PoincareSection("y", 0.0, direction=-1, name="sec")])  # fmt: skip

    def sec(t, x):
        return x[1]

    sec.direction = -1
    ref = solve_ivp(lambda t, x: [mu * (x[1] - x[0] ** 3 / 3 + x[0]), -x[0] / mu], (0, 100.0),
                    [2.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14, events=sec)  # fmt: skip
    T_ref = np.diff(ref.t_events[0])[-1]
    T = np.diff(np.asarray(tr.events["sec"].t))[-1]
    assert T == pytest.approx(T_ref, rel=1e-7)


# ====================================================================== connecting orbits
def bt_normal_form(s_sign: float) -> System:
    def rhs(x, p, ops):
        b1, b2 = p[0], p[1]
        return ops.stack([x[1], b1 + b2 * x[0] + x[0] ** 2 + s_sign * x[0] * x[1]])

    return System(rhs, ("x", "y"), ("b1", "b2"))


@pytest.mark.parametrize("s_sign", [-1.0, 1.0])
def test_bogdanov_takens_homoclinic_curve_asymptotics(s_sign):
    """Homoclinic (saddle-loop) curve of the BT normal form ``x' = y``,
    ``y' = b1 + b2 x + x^2 + s x y``: ``b1 = -(6/25) b2^2 + o(b2^2)``, ``b2 < 0``
    (Kuznetsov 2004, "Elements of Applied Bifurcation Theory", 3rd ed., sec. 8.4;
    Bogdanov 1975, Takens 1974). It follows from the Melnikov condition
    ``int x (x')^2 dt = 0`` on the loop ``x = x_s - (3/2) d sech^2(sqrt(d) t/2)`` of the
    Hamiltonian part, ``d = sqrt(b2^2 - 4 b1)``.

    The homoclinic BVP (shift = 0, unknown b1) is solved at b2 = -0.1, -0.05, -0.025
    from that loop. The ratio ``b1/b2^2`` deviates from -6/25 linearly in b2 (halving
    b2 halves the deviation, to 2 %), and Richardson extrapolation removes the linear
    term: ``2 r(b2/2) - r(b2) = -6/25 + O(b2^2)``, to 1e-5 at b2 = -0.05.
    """
    s = bt_normal_form(s_sign)
    ratio = {}
    for b2 in (-0.1, -0.05, -0.025):
        b1 = -6 / 25 * b2**2
        d = np.sqrt(b2**2 - 4 * b1)
        x_s = (-b2 + d) / 2
        lam = np.sqrt(d)  # unstable eigenvalue of the saddle at the start
        T = 24 / lam
        t = np.linspace(-T / 2, T / 2, 400)
        xg = x_s - 1.5 * d / np.cosh(lam * t / 2) ** 2
        prob = HeteroclinicProblem(
            s,
            s.params(b1=0.9 * b1, b2=b2),
            "b1",
            saddle_from=[x_s, 0.0],
            shift=[0.0, 0.0],
            mesh=CollocationMesh(80, 4, T),
            phase=PinPhase("y", 0.0),
        )
        res = solve_connection(prob, (t, np.column_stack([xg, np.gradient(xg, t)])))
        assert res.success, res.message
        ratio[b2] = res.value("b1") / b2**2
    dev = {b2: r + 6 / 25 for b2, r in ratio.items()}
    assert dev[-0.1] / dev[-0.05] == pytest.approx(2.0, rel=0.02)
    assert dev[-0.05] / dev[-0.025] == pytest.approx(2.0, rel=0.02)
    assert 2 * ratio[-0.025] - ratio[-0.05] == pytest.approx(-6 / 25, abs=1e-5)


def phi4() -> System:
    def rhs(x, p, ops):
        c, h = p[0], p[1]
        return ops.stack([x[1], -c * x[1] - x[0] + x[0] ** 3 + h])

    return System(rhs, ("u", "v"), ("c", "h"))


def test_tilted_phi4_front_speed_along_a_branch():
    """Fronts of ``u'' + c u' + u - u^3 - h = 0`` from the lower to the upper saddle.

    With the roots ``r1 < r2 < r3`` of ``u^3 - u + h`` the ansatz
    ``u' = (u - r1)(r3 - u)/sqrt 2`` solves it exactly when
    ``c = (2 r2 - r1 - r3)/sqrt 2 = 3 r2/sqrt 2`` (McKean 1970, Adv. Math. 4:209-223,
    for the Nagumo cubic; Fife & McLeod 1977, Arch. Rational Mech. Anal. 65:335-361).
    At h = 0 this is the phi^4 kink ``u = tanh(t/sqrt 2)`` with c = 0 (a heteroclinic of
    the Hamiltonian system, the speed found as 0). Continued in h over [-0.2, 0.2]:
    both saddles move with h, and c(h) is checked at every row. Tolerance: N = 60,
    degree 4, T = 30 gives a profile error 2e-9 at h = 0; c to 1e-7.
    """
    s = phi4()
    T = 30.0
    prob = HeteroclinicProblem(
        s,
        s.params(c=0.3, h=0.0),
        "c",
        saddle_from=[-1.0, 0.0],
        saddle_to=[1.0, 0.0],
        mesh=CollocationMesh(60, 4, T),
        phase=PinPhase("u", 0.0),
    )
    t = np.linspace(0, T, 300)
    u = np.tanh((t - T / 2) / 2.0)  # wrong width
    res = solve_connection(prob, (t, np.column_stack([u, np.gradient(u, t)])))
    assert res.success, res.message
    assert abs(res.value("c")) < 1e-12
    ue = np.tanh((res.t - T / 2) / SQ2)
    assert np.abs(res.state("u") - ue)[res.mesh.mesh_mask].max() < 1e-8
    br = continue_connection(
        res,
        "h",
        ContinuationSettings(ds=0.01, ds_max=0.05, p_min=-0.2, p_max=0.2, max_steps=100),
        direction="both",
    )
    assert br.status is Status.PARAM_BOUND, br.message
    assert br.p.min() == pytest.approx(-0.2) and br.p.max() == pytest.approx(0.2)
    r2 = np.array([np.sort(np.roots([1.0, 0.0, -1.0, h]).real)[1] for h in br.p])
    np.testing.assert_allclose(br.records["c"], 3 * r2 / SQ2, atol=1e-7)


def test_undamped_pendulum_separatrix_damping_found_zero():
    """Heteroclinic orbit between the saddles (-pi, 0) and (pi, 0) of
    ``theta'' + gamma theta' + sin theta = 0`` with gamma unknown: energy
    ``E = omega^2/2 - cos theta`` decays at rate ``gamma omega^2``, so the two saddles
    (both E = 1) connect only at gamma = 0, along the separatrix
    ``theta = 4 atan(e^t) - pi``, ``omega = 2 sech t`` (Guckenheimer & Holmes 1983,
    "Nonlinear Oscillations, Dynamical Systems, and Bifurcations of Vector Fields",
    sec. 4.5). Here theta is an ordinary (non-periodic) state, the end a separate
    saddle; the damping is a regular unfolding parameter (``int omega^2 dt = 8``).
    Tolerance: N = 80, T = 30: profile error ~1e-9 at the mesh nodes.
    """

    def rhs(x, p, ops):
        return ops.stack([x[1], p[1] - p[0] * x[1] - ops.sin(x[0])])

    s = System(rhs, ("theta", "omega"), ("gamma", "F"))
    T = 30.0
    prob = HeteroclinicProblem(
        s,
        s.params(gamma=0.2, F=0.0),
        "gamma",
        saddle_from=[-np.pi, 0.0],
        saddle_to=[np.pi, 0.0],
        mesh=CollocationMesh(80, 4, T),
        phase=PinPhase("theta", 0.0),
    )
    t = np.linspace(0, T, 200)
    th = 2 * np.pi / (1 + np.exp(-(t - T / 2))) - np.pi
    res = solve_connection(prob, (t, np.column_stack([th, np.gradient(th, t)])))
    assert res.success, res.message
    assert abs(res.value("gamma")) < 1e-12
    te = (res.t - T / 2)[res.mesh.mesh_mask]
    assert np.abs(res.x_mesh[:, 0] - (4 * np.arctan(np.exp(te)) - np.pi)).max() < 1e-8
    assert np.abs(res.x_mesh[:, 1] - 2 / np.cosh(te)).max() < 1e-8


# ============================================================ codim-2 on large systems
def brusselator_rd_diffusion(N: int) -> System:
    """As :func:`brusselator_rd`, with the diffusion coefficients as parameters."""
    h2 = (1.0 / (N + 1)) ** 2

    def rhs(x, p, ops):
        A, B, D1, D2 = p[0], p[1], p[2], p[3]
        out = []
        for i in range(N):
            ul = x[i - 1] if i > 0 else A
            ur = x[i + 1] if i < N - 1 else A
            out.append(D1 * (ul - 2 * x[i] + ur) / h2 + A - (B + 1) * x[i] + x[i] ** 2 * x[N + i])
        for i in range(N):
            vl = x[N + i - 1] if i > 0 else B / A
            vr = x[N + i + 1] if i < N - 1 else B / A
            v = x[N + i]
            out.append(D2 * (vl - 2 * v + vr) / h2 + B * x[i] - x[i] ** 2 * v)
        return ops.stack(out)

    names = tuple(f"u{i}" for i in range(N)) + tuple(f"v{i}" for i in range(N))
    return System(rhs, names, ("A", "B", "D1", "D2"))


def test_turing_hopf_point_on_the_hopf_curve_of_a_discretised_pde():
    """Turing-Hopf (zero-Hopf) point of the Brusselator reaction-diffusion system
    (Prigogine & Lefever 1968; e.g. De Wit, Lima, Dewel & Borckmans 1996, Phys. Rev. E
    54:261, for Turing-Hopf interaction), N = 30 nodes, n = 60.

    Mode blocks as in the sparse-path test: the Hopf curve of mode 1 is
    ``B_H(D2) = 1 + A^2 + (D1+D2) mu_1`` and mode k has a zero eigenvalue where
    ``B = B_T,k(D2) = (1 + D1 mu_k)(A^2 + D2 mu_k)/(D2 mu_k)``. Continuing the Hopf curve
    in D2 over [0.045, 0.065] crosses the Turing curve of mode 17 once: a zero-Hopf
    point at the root of ``B_H = B_T,17`` (Brent's method). Regression: the zero-Hopf
    and double-Hopf test functions are products of thousands of eigenvalue sums here
    and overflowed to NaN (no detection at all) before they were evaluated by
    ``signed_product``. (Where the curve crosses a Turing curve the uniform state is
    also at a branch point of the equilibria, so the curve has a branch point there as
    well: both are reported.)
    """
    N, A, D1, D2 = 30, 2.0, 0.002, 0.045
    s = brusselator_rd_diffusion(N)
    h = 1.0 / (N + 1)
    mu = 4 / h**2 * np.sin(np.arange(1, N + 1) * np.pi * h / 2) ** 2

    def B_H(d2):
        return 1 + A**2 + (D1 + d2) * mu[0]

    def B_T(d2, k):
        return (1 + D1 * mu[k - 1]) * (A**2 + d2 * mu[k - 1]) / (d2 * mu[k - 1])

    d2_zh = brentq(lambda d2: B_H(d2) - B_T(d2, 17), 0.045, 0.065, xtol=1e-16)
    br = continue_equilibria(
        s, np.r_[np.full(N, A), np.full(N, 3.0 / A)], {"A": A, "B": 3.0, "D1": D1, "D2": D2},
        "B", p_min=2.0, p_max=B_H(D2) + 0.1, direction="forward",
    )  # fmt: skip
    h1 = [q for q in br.find("hopf") if q.located]
    assert len(h1) == 1 and h1[0].p == pytest.approx(B_H(D2), rel=1e-10)
    curve = continue_codim2(
        br,
        h1[0],
        "D2",
        ContinuationSettings(ds=0.002, ds_max=0.004, p_min=0.04, p_max=0.065, max_steps=200),
        direction="forward",
    )
    assert curve.status.ok, curve.message
    np.testing.assert_allclose(curve.records["B"], B_H(curve.p), rtol=1e-10)
    prob = curve.problem
    for i in range(len(curve)):
        assert all(np.isfinite(list(prob.test_functions(curve.x[i], curve.p[i]).values())))
    (zh,) = curve.find("zh")
    # The zero coincides with a branch point of the curve (singular augmented Jacobian).
    # Next to it Newton's method converges onto the crossing curve (a Hopf curve of the
    # non-uniform equilibria, 6e-8 off in B), where the ZH test function has the other
    # sign: before the locator kept to the branch (tangent check), the bracket closed on
    # that jump and a point of the crossing curve was reported, off by more than this
    # test's former tolerance on some BLAS builds. Now the zero is interpolated through
    # the points of this curve around it and located within the locator's bound: its
    # error estimate is at most tol in the theta-norm, so each component is within
    # tol / sqrt(w_i) (w_i the theta weights).
    assert zh.located, zh
    lo, hi = sorted(zh.bracket)
    assert lo < d2_zh < hi
    st = ContinuationSettings()
    n_z = curve.x.shape[1]
    tol_p = st.detect.tol / np.sqrt(st.theta)  # D2 (the curve's parameter)
    tol_z = st.detect.tol / np.sqrt((1.0 - st.theta) / n_z)  # B, kappa
    assert zh.p == pytest.approx(d2_zh, abs=tol_p)
    assert zh.data["B"] == pytest.approx(B_H(zh.p), abs=tol_z + 1e-10 * B_H(zh.p))
    det1 = (B_H(zh.p) - 1 - D1 * mu[0]) * (-(A**2) - zh.p * mu[0]) + A**2 * B_H(zh.p)
    assert zh.data["kappa"] == pytest.approx(det1, abs=tol_z + 1e-10 * det1)


def test_cusp_of_a_fold_curve_in_a_stiff_chain():
    """Cusp normal form ``x' = b1 + b2 x - x^3`` (Kuznetsov 2004, sec. 8.2) driving a
    stiff chain ``w_i' = -d_i w_i + x^2 + w_{i-1}/10`` (d_i = 1 ... 1e11, n = 60): the
    x equation is closed, so the fold curve is ``b1 = -+2 (b2/3)^(3/2)`` with its cusp at
    the origin, exactly. Regression: the fold-curve test functions used the plain
    adjugate, a product of 59 singular values spanning 1 ... 1e11, which overflows to
    NaN; the scaled adjugate keeps their zeros without overflow.
    """
    n = 60
    d = np.logspace(0, 11, n - 1)

    def rhs(y, p, ops):
        b1, b2, x = p[0], p[1], y[0]
        chain = [-d[i] * y[i + 1] + x**2 + 0.1 * y[i] for i in range(n - 1)]
        return ops.stack([b1 + b2 * x - x**3, *chain])

    s = System(rhs, tuple(f"y{i}" for i in range(n)), ("b1", "b2"))

    def equilibrium(x):
        y = [x]
        for i in range(n - 1):
            y.append((x * x + 0.1 * y[-1]) / d[i])
        return np.array(y)

    b2, x0 = 3.0, 2.0
    br = continue_equilibria(s, equilibrium(x0), {"b1": x0**3 - b2 * x0, "b2": b2}, "b1",
                             p_min=-5.0, p_max=5.0)  # fmt: skip
    folds = br.find("fold")
    assert len(folds) == 2 and all(f.located for f in folds)
    assert sorted(f.p for f in folds) == pytest.approx([-2.0, 2.0], rel=1e-10)
    curve = continue_codim2(
        br, folds[0], "b2", ContinuationSettings(ds=0.1, ds_max=0.3, p_min=-1.0, p_max=4.0)
    )
    assert curve.status.ok, curve.message
    on = curve.p > 0
    np.testing.assert_allclose(
        np.abs(curve.records["b1"][on]), 2 * (curve.p[on] / 3) ** 1.5, rtol=1e-8, atol=1e-12
    )
    cp = _one(curve, "cusp")
    # the chain's eigenvalues reach -1e11: the located zero is good to ~1e-9
    assert abs(cp.p) < 1e-8 and abs(cp.data["b1"]) < 1e-12
    assert not curve.find("bt")


def test_overflow_free_products_agree_with_the_plain_ones():
    """``signed_product`` equals ``prod(...).real`` and ``scaled_adjugate`` is a positive
    multiple of the adjugate, on random small cases where the plain forms are exact."""
    from continuation.codim2._base import adjugate, scaled_adjugate, signed_product
    from continuation.codim2.fold import _pair_sum_product

    rng = np.random.default_rng(5)
    for n in (2, 3, 5, 8):
        J = rng.standard_normal((n, n))
        e = np.linalg.eigvals(J)
        assert signed_product(e) == pytest.approx(float(np.prod(e).real), rel=1e-12)
        plain = 1.0 + 0j
        for i in range(n):
            for j in range(i + 1, n):
                plain *= e[i] + e[j]
        assert _pair_sum_product(e) == pytest.approx(float(plain.real), rel=1e-12)
        A, S = adjugate(J), scaled_adjugate(J)
        ratio = A[np.abs(A) > 1e-8] / S[np.abs(A) > 1e-8]
        assert np.all(ratio > 0) and np.ptp(ratio) < 1e-10 * ratio.max()
        np.testing.assert_allclose(A @ J, np.linalg.det(J) * np.eye(n), atol=1e-10)
    assert signed_product([]) == 1.0 and signed_product([0.0, 3.0]) == 0.0
    big = np.full(5000, -7.0)  # (-7)^5000: overflows as a plain product; sign +
    assert signed_product(big) > 0 and np.isfinite(signed_product(big))
    assert signed_product(np.r_[big, -1e-3]) < 0
