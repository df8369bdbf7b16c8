"""Published reference problems: folds and Hopf points against independent values.

Every reference is computed independently of the engine: from a closed form derived in
the cited source, by an independent root solve of the defining equations, or by a
convergence study against a published limit.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import assert_invariants, bratu, bratu_branch, brusselator, cstr, lorenz84, selkov
from scipy.optimize import fsolve

from continuation.algorithms.palc import PALC
from continuation.api import continue_equilibria
from continuation.events import Event
from continuation.status import Status

REL = 1e-7  # the task asks for ~1e-5; these finite systems are matched much closer


# ------------------------------------------------------------------------- CSTR (AUTO "ab")
def test_cstr_folds_and_hopf_closed_form():
    """Exothermic CSTR of Uppal, Ray & Poore (1974), Chem. Eng. Sci. 29:967-985; AUTO-07p
    demo ``ab`` (Doedel et al., AUTO-07p manual), B = 14, beta = 2, continuation in Da.

    On the equilibrium curve u2 = B u1 / (1 + beta) and Da = u1 exp(-u2) / (1 - u1).
    Folds: d(ln Da)/du1 = 0  <=>  u1 (1 - u1) = (1 + beta) / B.
    Hopf: trace J = 0  <=>  B u1^2 - (B + 1 + beta) u1 + (2 + beta) = 0, with det J > 0;
    omega^2 = det J.
    """
    B, beta = 14.0, 2.0
    br = continue_equilibria(
        cstr(),
        [0.0, 0.0],
        {"Da": 0.0, "B": B, "beta": beta},
        "Da",
        p_min=0.0,
        p_max=0.4,
        direction="forward",
    )
    assert br.status is Status.PARAM_BOUND

    def da(u1):
        return u1 * np.exp(-B * u1 / (1 + beta)) / (1 - u1)

    u_fold = (1 + np.array([-1.0, 1.0]) * np.sqrt(1 - 4 * (1 + beta) / B)) / 2
    folds = br.find("fold")
    assert len(folds) == 2
    for f, u1 in zip(folds, u_fold, strict=True):  # encountered in order of increasing u1
        assert f.located
        assert f.p == pytest.approx(da(u1), rel=REL)
        assert f.x[0] == pytest.approx(u1, rel=1e-4)  # state error ~ sqrt(p error)

    u_h = np.roots([B, -(B + 1 + beta), 2 + beta])
    E = u_h / (1 - u_h)
    det = (-1 - E) * (-1 - beta + B * u_h) + B * E * u_h
    hopfs = br.find("hopf")
    assert len(hopfs) == 1  # the other root has det J < 0: a neutral saddle, not a Hopf
    k = int(np.argmax(det))
    assert det[k] > 0 > det[1 - k]
    (h,) = hopfs
    assert h.located
    assert h.p == pytest.approx(da(u_h[k]), rel=REL)
    assert h.x[0] == pytest.approx(u_h[k], rel=REL)
    assert h.data["omega"] == pytest.approx(np.sqrt(det[k]), rel=REL)
    assert_invariants(br)
    assert br.newton_iters.mean() < 4


# ------------------------------------------------------------------------- Brusselator
@pytest.mark.parametrize("A", [1.0, 1.7, 0.45])
def test_brusselator_hopf(A):
    """Brusselator: Hopf at B = 1 + A^2 with omega = A (Nicolis & Prigogine 1977,
    *Self-Organization in Nonequilibrium Systems*, Sec. 7.4)."""
    br = continue_equilibria(
        brusselator(),
        [A, 0.5 / A],
        {"A": A, "B": 0.5},
        "B",
        p_min=0.0,
        p_max=1 + A**2 + 1.3,
        direction="forward",
    )
    (h,) = br.find("hopf")
    assert h.located
    assert h.p == pytest.approx(1 + A**2, rel=REL)
    assert h.data["omega"] == pytest.approx(A, rel=REL)
    np.testing.assert_allclose(h.x, [A, (1 + A**2) / A], rtol=REL)
    # equilibrium (A, B/A) all along the branch
    np.testing.assert_allclose(br.x[:, 0], A, rtol=1e-10)
    np.testing.assert_allclose(br.x[:, 1], br.p / A, rtol=1e-10)
    assert_invariants(br)


# ------------------------------------------------------------------------- Sel'kov
def test_selkov_two_hopf_points():
    """Sel'kov glycolysis, a = 0.08: Hopf where b^2 = (1 - 2a +- sqrt(1 - 8a)) / 2 and
    omega^2 = det J = a + b^2 (Strogatz 2015, *Nonlinear Dynamics and Chaos*, 2nd ed.,
    Example 7.3.2 / Fig. 7.3.7)."""
    a = 0.08
    br = continue_equilibria(
        selkov(), [0.2, 0.2 / (a + 0.04)], {"a": a, "b": 0.2}, "b", p_min=0.05, p_max=1.2
    )
    b_ref = np.sqrt((1 - 2 * a + np.array([-1.0, 1.0]) * np.sqrt(1 - 8 * a)) / 2)
    hopfs = br.find("hopf")
    assert len(hopfs) == 2
    got = sorted(hopfs, key=lambda h: h.p)
    for h, b in zip(got, b_ref, strict=True):
        assert h.located
        assert h.p == pytest.approx(b, rel=REL)
        assert h.data["omega"] == pytest.approx(np.sqrt(a + b**2), rel=REL)
    # stable outside the Hopf interval, unstable focus inside
    inside = (br.p > b_ref[0] + 1e-6) & (br.p < b_ref[1] - 1e-6)
    outside = (br.p < b_ref[0] - 1e-6) | (br.p > b_ref[1] + 1e-6)
    assert np.all(br.n_unstable[inside] == 2) and np.all(br.n_unstable[outside] == 0)
    assert_invariants(br)


# ------------------------------------------------------------------------- Lorenz-84
def _lorenz84_jac(x, a, b, F, G):
    X, Y, Z = x
    return np.array([[-a, -2 * Y, -2 * Z], [Y - b * Z, X - 1, -b * X], [b * Y + Z, b * X, X - 1]])


def _lorenz84_f(x, a, b, F, G):
    X, Y, Z = x
    return np.array(
        [-(Y**2) - Z**2 - a * X + a * F, X * Y - b * X * Z - Y + G, b * X * Y + X * Z - Z]
    )


def test_lorenz84_folds_and_hopf_independent_solve():
    """Lorenz-84 (Lorenz 1984, Tellus 36A:98-110; Shil'nikov, Nicolis & Nicolis 1995,
    Int. J. Bifurcation Chaos 5:1701-1711), a = 1/4, b = 4, G = 1, continuation in F.

    Reference: the defining equations solved independently with ``scipy.optimize.fsolve``
    and a hand-written Jacobian: folds ``f = 0, det J = 0``; Hopf ``f = 0`` and the
    Routh-Hurwitz condition ``c2 c1 = c0`` of ``lambda^3 + c2 lambda^2 + c1 lambda + c0``
    (with ``c1 > 0``), ``omega^2 = c1``.
    """
    a, b, G = 0.25, 4.0, 1.0
    br = continue_equilibria(
        lorenz84(),
        [0.0, G, 0.0],
        {"a": a, "b": b, "G": G, "F": 0.0},
        "F",
        p_min=-1.0,
        p_max=8.0,
        max_steps=3000,
    )

    def fold_eqs(v):
        x, F = v[:3], v[3]
        return [*_lorenz84_f(x, a, b, F, G), np.linalg.det(_lorenz84_jac(x, a, b, F, G))]

    def hopf_eqs(v):
        x, F = v[:3], v[3]
        c = np.poly(_lorenz84_jac(x, a, b, F, G))  # [1, c2, c1, c0]
        return [*_lorenz84_f(x, a, b, F, G), c[1] * c[2] - c[3]]

    folds = br.find("fold")
    assert len(folds) == 2
    for f in folds:
        ref = fsolve(fold_eqs, np.append(f.x, f.p) + 1e-3, xtol=1e-13)
        assert np.max(np.abs(fold_eqs(ref))) < 1e-10
        assert f.located and f.p == pytest.approx(ref[3], rel=REL)
    (h,) = br.find("hopf")
    ref = fsolve(hopf_eqs, np.append(h.x, h.p) + 1e-3, xtol=1e-13)
    assert np.max(np.abs(hopf_eqs(ref))) < 1e-10
    c = np.poly(_lorenz84_jac(ref[:3], a, b, ref[3], G))
    assert c[2] > 0
    assert h.located and h.p == pytest.approx(ref[3], rel=REL)
    assert h.data["omega"] == pytest.approx(np.sqrt(c[2]), rel=REL)
    assert_invariants(br)


# ------------------------------------------------------------------------- Bratu
BRATU_LAMBDA_STAR = 3.513830719125161  # continuous fold (e.g. Mohsen 2014, Boyd 1986)


def _bratu_branch(n: int, stop: Event, *, ds: float):
    """Bratu's branch from the trivial solution at lambda = 0, up to the event ``stop``."""
    return bratu_branch(
        n, p_min=0.0, p_max=4.0, ds=ds, ds_max=0.5, direction="forward", events=[stop]
    )


def _bratu_fold(n: int) -> float:
    # stop soon after the fold, on the upper branch (max u = 2 > 1.39 at the fold)
    stop = Event("upper", lambda x, p: float(np.max(x)) - 2.0, terminal=True)
    br = _bratu_branch(n, stop, ds=0.1)
    assert br.status is Status.EVENT
    assert br.problem.sparse == (n >= 100)
    (f,) = br.find("fold")
    assert f.located
    # the fold is the maximum of lambda along the branch
    assert f.p >= br.p.max() - 1e-12
    return f.p


def test_bratu_fold_converges_at_second_order():
    """Finite-difference Bratu fold lambda*_h -> 3.513830719125161 at O(h^2)
    (continuous value: Mohsen 2014, Boyd 1986); N = 199 runs on sparse LU."""
    ns = (49, 99, 199)
    lam = np.array([_bratu_fold(n) for n in ns])
    err = lam - BRATU_LAMBDA_STAR
    assert np.all(err < 0)  # the discrete fold lies below the continuous one
    orders = np.log2(err[:-1] / err[1:])
    np.testing.assert_allclose(orders, 2.0, atol=2e-3)
    richardson = (4 * lam[-1] - lam[-2]) / 3
    assert richardson == pytest.approx(BRATU_LAMBDA_STAR, rel=1e-8)  # O(h^4) remainder


def test_discrete_bratu_symmetry_breaking_branch_point():
    """Far up the branch (lam ~ 1.5e-6, max u ~ 20) the N = 20 discrete Bratu problem
    loses its reflection symmetry u_i <-> u_{N+1-i} in a pitchfork (a spurious solution
    of the discretisation). Independent check of the located branch point: the Jacobian
    there has an eigenvalue ~0 whose eigenvector is antisymmetric."""
    n = 20
    stop = Event("far", lambda x, p: float(np.max(x)) - 21.0, terminal=True)
    found = []
    steps = (0.5, 0.05)  # a large step makes the locator work near the BP
    # both steps (the compiled and the Python one): their rows differ by round-off,
    # which at this conditioning (rcond ~ 1e-12 at the point) decides how the locator's
    # trial points fall around the crossing branch
    for ds_max, alg in [(d, PALC(kernel=k)) for d in steps for k in (True, False)]:
        br = bratu_branch(
            n,
            p_min=0.0,
            p_max=4.0,
            ds=ds_max,
            ds_max=ds_max,
            direction="forward",
            events=[stop],
            max_steps=2000,
            algorithm=alg,
        )
        assert br.status is Status.EVENT
        (bp,) = br.find("bp")
        assert bp.located and bp.delta_unstable == (1, 0)
        J = bratu(n).jacobian(bp.x, np.array([bp.p]))
        vals, vecs = np.linalg.eig(J)
        k = int(np.argmin(np.abs(vals)))
        assert abs(vals[k]) < 1e-8 * np.max(np.abs(vals))
        v = vecs[:, k].real / np.linalg.norm(vecs[:, k].real)
        assert np.max(np.abs(v + v[::-1])) < 1e-5  # antisymmetric kernel
        # on the symmetric branch, up to the corrector's accuracy next to a branch point
        # (|G| <= 1e-10 over a smallest singular value that vanishes at the point)
        assert np.max(np.abs(bp.x - bp.x[::-1])) < 1e-6 * np.max(np.abs(bp.x))
        assert_invariants(br, tol=1e-8)
        found.append(bp.p)
    assert max(found) == pytest.approx(min(found), rel=1e-7)
    # against the independent shooting / tridiagonal-eigenvalue computation below, at the
    # accuracy the conditioning allows (tol 1e-10 over a vanishing singular value)
    lam_ref, _ = _bratu_symmetric_pitchfork(n, 19.0, 21.0)
    assert found == pytest.approx([lam_ref] * len(found), rel=1e-7)


def _bratu_symmetric_pitchfork(n: int, m_lo: float, m_hi: float) -> tuple[float, float]:
    """Symmetry-breaking pitchfork of the discrete Bratu problem (even ``n``), computed
    without any continuation code: the symmetric solution with centre value
    ``m = u_{n/2} = u_{n/2+1}`` is shot outwards, ``u_{i-1} = 2 u_i - u_{i+1} - h^2 lam
    e^{u_i}``, and ``lam(m)`` solves ``u_0 = 0`` (Brent in ``log lam``); the Jacobian
    restricted to antisymmetric vectors (``v_i = -v_{n+1-i}``) is symmetric tridiagonal,
    and the pitchfork is where its largest eigenvalue vanishes (Brent in ``m``).

    Returns ``(lam*, max u*)``.
    """
    from scipy.linalg import eigvalsh_tridiagonal
    from scipy.optimize import brentq

    h2 = 1.0 / (n + 1) ** 2
    half = n // 2

    def shoot(m, lam):
        nodes = np.empty(half)
        prev = cur = m
        for i in range(half - 1, -1, -1):
            nodes[i] = cur
            prev, cur = cur, 2 * cur - prev - h2 * lam * np.exp(cur)
        return nodes, cur  # cur = u_0, the boundary value

    def lam_of(m):
        f = lambda ll: shoot(m, np.exp(ll))[1]  # noqa: E731
        grid = np.linspace(-2 * m - 10, 5.0, 200)
        vals = [f(x) for x in grid]
        k = next(i for i in range(len(grid) - 1) if vals[i] * vals[i + 1] < 0)
        return float(np.exp(brentq(f, grid[k], grid[k + 1], xtol=1e-14, rtol=1e-15)))

    def mu(m):
        lam = lam_of(m)
        nodes, _ = shoot(m, lam)
        d = -2.0 / h2 + lam * np.exp(nodes)
        d[-1] -= 1.0 / h2  # v_{n/2+1} = -v_{n/2}
        return eigvalsh_tridiagonal(d, np.full(half - 1, 1.0 / h2))[-1]

    m_star = brentq(mu, m_lo, m_hi, xtol=1e-13)
    return lam_of(m_star), m_star


def test_bratu_50_branch_point_near_lambda_zero_is_genuine():
    """The ``broachkit demo``-like run (N = 50, ds = 0.05, ds_max = 0.5) reports a branch
    point at lam ~ 1e-16, max u ~ 45: it was suspected to be a round-off sign flip of the
    determinant. It is the symmetry-breaking pitchfork of the discretisation (as for
    N = 20 above): checked against an independent shooting/tridiagonal-eigenvalue
    computation, and the located point's bordered Jacobian is numerically singular
    relative to its neighbours (it is verified by the driver)."""
    n = 50
    lam_ref, m_ref = _bratu_symmetric_pitchfork(n, 44.0, 46.0)
    stop = Event("far", lambda x, p: float(np.max(x)) - 50.0, terminal=True)
    br = _bratu_branch(n, stop, ds=0.05)
    assert br.status is Status.EVENT
    (bp,) = br.find("bp")
    assert bp.located and bp.delta_unstable == (1, 0)
    # accuracy limited by conditioning: the residual's round-off floor (~1e-10 here,
    # entries ~ 45 / h^2) is amplified by the bordered matrix, singular at the point
    assert bp.p == pytest.approx(lam_ref, rel=1e-7)
    assert float(np.max(bp.x)) == pytest.approx(m_ref, abs=1e-5)
    assert np.max(np.abs(bp.x - bp.x[::-1])) < 1e-5  # on the symmetric branch
    assert bp.data["rcond_ratio"] < 1e-3
    assert_invariants(br, tol=1e-8)


def test_bratu_20_branch_point_against_shooting():
    """The N = 20 symmetry-breaking pitchfork (see above) against the independent
    shooting computation."""
    n = 20
    lam_ref, m_ref = _bratu_symmetric_pitchfork(n, 19.0, 21.0)
    stop = Event("far", lambda x, p: float(np.max(x)) - 21.0, terminal=True)
    br = _bratu_branch(n, stop, ds=0.5)
    (bp,) = br.find("bp")
    assert bp.located
    assert bp.p == pytest.approx(lam_ref, rel=1e-7)
    assert float(np.max(bp.x)) == pytest.approx(m_ref, abs=1e-5)
