"""Periodic-orbit continuation at the default settings on published problems.

Three of AUTO-07p's demos (Doedel et al., AUTO-07p manual, chapter "AUTO Demos"; the
equations are those of ``demos/tor/tor.f90``, ``demos/chu/chu.f90`` and
``demos/pp2/pp2.f90`` of the AUTO-07p repository), run as a researcher would: the
equilibria in one parameter, the Hopf point, the cycles born there, with
:class:`~continuation.settings.ContinuationSettings` at its defaults (only bounds set).
Every value is checked against a closed form or an independent computation in this
file (SciPy shooting with the variational equations, ``rtol = 1e-12``; stable and
unstable manifolds integrated to a section):

* ``tor`` -- Freire, Rodriguez-Luis, Gamero & Ponce (1993), "A case study for
  homoclinic chaos in an autonomous electronic circuit", Physica D 62:230-253: a Hopf
  point of the origin next to a pitchfork (both in one default step), a fold and a
  symmetry-breaking branch point of cycles, a Shilnikov snake of folds of cycles.
* ``chu`` -- Chua's circuit with the smooth nonlinearity ``|x| ~ (2 x / pi)
  arctan(K x)``, ``K = 10`` (Khibnik, Roose & Chua 1993, "On periodic orbits and
  homoclinic bifurcations in Chua's circuit with a smooth nonlinearity", IJBC
  3:363-384): Hopf point, period doubling, the snake of folds and period doublings of
  cycles approaching the saddle-focus homoclinic orbit of the origin.
* ``pp2`` -- a predator-prey model with harvesting (AUTO-07p manual, demo pp2): a
  branch of cycles ending at a heteroclinic cycle between two saddles on the prey axis.

Tolerances. Cycles are solved with the collocation error estimate below ``error_tol =
1e-6`` (states' units, the default), and special points located to ``1e-10`` in their
test functions; the parameter of a special point or of the period limit then carries
an error of the order of the states' error (the test functions are smooth functions of
the cycle with O(1) derivatives), so 1e-6 is allowed, 1e-5 where a multiplier of the
cycle is of order 1e4 (the snake). The SciPy references are converged to 1e-10 or
better (checked by varying their own tolerances while writing the test).
"""

from __future__ import annotations

import logging
import math
import re

import numpy as np
import pytest
from helpers import chua_rhs
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from continuation import ContinuationSettings, Status, System, continue_equilibria
from continuation.periodic import continue_from_hopf, multipliers, orbit_at, period_limit


# ------------------------------------------------------------------ shooting reference
def _flow(f, jac, x0, T, var=True):
    """``x(T)`` and the monodromy ``dx(T)/dx0`` by SciPy (DOP853, rtol 1e-12)."""
    n = x0.size
    if not var:
        r = solve_ivp(lambda t, x: f(x), (0, T), x0, rtol=1e-12, atol=1e-13, method="DOP853")
        return r.y[:, -1], None

    def rhs(t, y):
        x, M = y[:n], y[n:].reshape(n, n)
        return np.concatenate([f(x), (jac(x) @ M).ravel()])

    y0 = np.concatenate([x0, np.eye(n).ravel()])
    r = solve_ivp(rhs, (0, T), y0, rtol=1e-12, atol=1e-13, method="DOP853")
    return r.y[:n, -1], r.y[n:, -1].reshape(n, n)


def _shoot(f, jac, x0, T):
    """The cycle through the section ``x[k] = x0[k]`` (``k``: the largest component of the
    flow at ``x0``): Newton on ``x(T) - x0`` for the other components of ``x0`` and
    ``T``. Returns ``(x0, T, monodromy)``."""
    x0 = np.array(x0, dtype=float)
    fix = int(np.argmax(np.abs(f(x0))))
    free = [i for i in range(x0.size) if i != fix]
    for _ in range(20):
        xT, M = _flow(f, jac, x0, T)
        A = np.column_stack([(M - np.eye(x0.size))[:, free], f(xT)])
        d = np.linalg.solve(A, x0 - xT)
        x0[free] += d[:-1]
        T += d[-1]
        if np.max(np.abs(d)) < 1e-11:
            break
    _, M = _flow(f, jac, x0, T)
    return x0, T, M


def _shoot_at_period(fp, jacp, p, x0, T, h=1e-7):
    """The cycle of period ``T`` through the section of :func:`_shoot`: Newton for
    ``(x0, p)`` (``d x(T) / dp`` by a forward difference). Returns ``p``."""
    x0 = np.array(x0, dtype=float)
    n = x0.size
    fix = int(np.argmax(np.abs(fp(x0, p))))
    free = [i for i in range(n) if i != fix]
    for _ in range(30):
        xT, M = _flow(lambda x, p=p: fp(x, p), lambda x, p=p: jacp(x, p), x0, T)
        dp = (_flow(lambda x, p=p: fp(x, p + h), None, x0, T, var=False)[0] - xT) / h
        A = np.column_stack([(M - np.eye(n))[:, free], dp])
        d = np.linalg.solve(A, x0 - xT)
        x0[free] += d[:-1]
        p += d[-1]
        if abs(d[-1]) < 1e-13 * (1 + abs(p)) and np.max(np.abs(d[:-1])) < 1e-11 * (
            1 + np.max(np.abs(x0))
        ):
            break
    return p


def _shoot_through(fp, jacp, dfdp, p, x0, T):
    """The planar cycle through the point ``x0``: Newton for ``(T, p)`` on ``x(T) = x0``
    (the variational equations for ``d x(T) / dp``). Returns ``p``."""
    x0 = np.asarray(x0, dtype=float)
    n = x0.size

    def rhs(t, y, p):
        x, W = y[:n], y[n:].reshape(n, n + 1)
        J = jacp(x, p)
        return np.concatenate([fp(x, p), (J @ W + np.column_stack(
            [np.zeros((n, n)), dfdp(x, p)])).ravel()])  # fmt: skip

    W0 = np.column_stack([np.eye(n), np.zeros(n)]).ravel()
    for _ in range(30):
        r = solve_ivp(rhs, (0, T), np.concatenate([x0, W0]), args=(p,), rtol=1e-12,
                      atol=1e-13, method="DOP853")  # fmt: skip
        xT, dp = r.y[:n, -1], r.y[n:, -1].reshape(n, n + 1)[:, n]
        d = np.linalg.solve(np.column_stack([fp(xT, p), dp]), x0 - xT)
        T, p = T + d[0], p + d[1]
        if abs(d[1]) < 1e-13 * (1 + abs(p)) and abs(d[0]) < 1e-11 * (1 + T):
            break
    return p


def _nontrivial(M, f0):
    """Multipliers of ``M`` without the trivial one (the eigenvalue nearest 1 whose
    eigenvector is along the flow ``f0``)."""
    w, V = np.linalg.eig(M)
    along = np.abs(f0 @ V) / (np.linalg.norm(V, axis=0) * np.linalg.norm(f0))
    k = int(np.argmax(along - np.abs(w - 1.0)))
    return np.delete(w, k)


# ------------------------------------------------------------------ tor (Freire et al. 1993)
TOR = {"nu": -0.9, "beta": 0.5, "gamma": -0.6, "r": 0.6, "a3": 0.328578, "b3": 0.933578}


def _tor_rhs(x, p, ops):
    nu, be, ga, r, a3, b3 = p[0], p[1], p[2], p[3], p[4], p[5]
    d3 = (x[1] - x[0]) ** 3
    return ops.stack([
        (-(be + nu) * x[0] + be * x[1] - a3 * x[0] ** 3 + b3 * d3) / r,
        be * x[0] - (be + ga) * x[1] - x[2] - b3 * d3,
        x[1],
    ])  # fmt: skip


def _tor_f(x, nu):
    be, ga, r, a3, b3 = (TOR[k] for k in ("beta", "gamma", "r", "a3", "b3"))
    d3 = (x[1] - x[0]) ** 3
    return np.array([(-(be + nu) * x[0] + be * x[1] - a3 * x[0] ** 3 + b3 * d3) / r,
                     be * x[0] - (be + ga) * x[1] - x[2] - b3 * d3, x[1]])  # fmt: skip


def _tor_jac(x, nu):
    be, ga, r, a3, b3 = (TOR[k] for k in ("beta", "gamma", "r", "a3", "b3"))
    q = 3 * b3 * (x[1] - x[0]) ** 2
    return np.array([[(-(be + nu) - 3 * a3 * x[0] ** 2 - q) / r, (be + q) / r, 0.0],
                     [be + q, -(be + ga) - q, -1.0], [0.0, 1.0, 0.0]])  # fmt: skip


def _tor_hopf():
    r"""The Hopf point of the origin in closed form.

    With ``a = (beta + nu) / r`` the characteristic polynomial at the origin is
    :math:`\lambda^3 + (s + a)\lambda^2 + (q + a s)\lambda + a`, ``s = beta + gamma``,
    ``q = 1 - beta^2 / r``; a pair ``+-i omega`` where ``(s + a)(q + a s) = a``, i.e.
    :math:`s a^2 + (q + s^2 - 1) a + s q = 0`, with :math:`\omega^2 = q + a s > 0`.
    Returns ``(nu_H, omega)`` for the root in ``nu > -0.9``.
    """
    be, ga, r = TOR["beta"], TOR["gamma"], TOR["r"]
    s, q = be + ga, 1 - be**2 / r
    roots = np.roots([s, q + s * s - 1, s * q]).real
    nus = r * roots - be
    nu = float(nus[nus > -0.9][0])
    a = (be + nu) / r
    return nu, math.sqrt(q + a * s)


@pytest.fixture(scope="module")
def tor_equilibria():
    s = System(_tor_rhs, ("x", "y", "z"), tuple(TOR))
    return continue_equilibria(s, [0, 0, 0], TOR, "nu", p_min=-0.9, p_max=-0.4,
                               direction="forward")  # fmt: skip


def test_tor_hopf_point_beside_the_pitchfork_at_defaults(tor_equilibria):
    """The Hopf point of the origin (closed form) and the pitchfork at ``nu = -beta``.

    At the default step the pitchfork (a real eigenvalue through zero) and the Hopf
    point fall in one step, where the real and the pair counts of unstable eigenvalues
    both change: the Hopf point was not detected before (regression)."""
    eq = tor_equilibria
    nu_h, omega = _tor_hopf()
    (h,) = eq.find("hopf")
    assert h.located and h.p == pytest.approx(nu_h, abs=1e-9)
    assert h.data["omega"] == pytest.approx(omega, abs=1e-8)
    (bp,) = eq.find("bp")
    assert bp.located and bp.p == pytest.approx(-TOR["beta"], abs=1e-9)


def test_tor_fold_and_symmetry_breaking_branch_point_of_cycles(tor_equilibria):
    """The symmetric cycles from HB1 turn at a fold (LPC) and lose their symmetry at a
    branch point (BPC), both within 0.006 of the Hopf point. References by shooting:
    the LPC is the largest ``nu`` of the cycles of fixed period (a parabola through
    three shooting solutions at fixed period around the LPC's); at the BPC one
    nontrivial multiplier is 1 (secant of ``mu(nu) - 1`` from two shooting solutions)."""
    eq = tor_equilibria
    nu_h, omega = _tor_hopf()
    br = continue_from_hopf(eq, eq.find("hopf")[0], ContinuationSettings(p_min=-0.7))
    assert br.status == Status.PARAM_BOUND, br.message
    assert br.records["T"][0] == pytest.approx(2 * math.pi / omega, rel=1e-3)
    assert np.max(br.records["error"]) <= 1.01e-6
    (lpc,) = br.find("fold")
    (bpc,) = br.find("bp")
    assert lpc.label == "LPC1" and bpc.label == "BPC1" and lpc.located and bpc.located
    # LPC: max of nu over the cycles of fixed period
    o = orbit_at(br, lpc)
    h = 0.02
    nus = [_shoot_at_period(_tor_f, _tor_jac, lpc.p, o.X[0], o.T + d) for d in (-h, 0.0, h)]
    curv = (nus[0] - 2 * nus[1] + nus[2]) / h**2
    nu_lpc = nus[1] - (nus[2] - nus[0]) ** 2 / (8 * h**2 * curv)
    assert curv < 0 and lpc.p == pytest.approx(nu_lpc, abs=1e-6)
    # BPC: a nontrivial multiplier crosses 1 along the symmetric branch
    o = orbit_at(br, bpc)

    def mu_near_1(nu):
        x0, T, M = _shoot(lambda x: _tor_f(x, nu), lambda x: _tor_jac(x, nu), o.X[0], o.T)
        w = _nontrivial(M, _tor_f(x0, nu))
        return float(w[np.argmin(np.abs(w - 1.0))].real)

    m0, m1 = mu_near_1(bpc.p), mu_near_1(bpc.p - 1e-4)
    nu_bpc = bpc.p - (m0 - 1.0) * (-1e-4) / (m1 - m0)
    assert bpc.p == pytest.approx(nu_bpc, abs=1e-6)
    # the branch's own multipliers there: one of the nontrivial ones at 1
    k = int(np.argmin(np.abs(br.p - bpc.p)))
    assert np.min(np.abs(multipliers(br)[k] - 1.0)) < 0.2


def _tor_saddle(nu):
    """The equilibrium ``(x, 0, beta x + b3 x^3)``, ``x^2 = -(beta + nu) / (a3 + b3)``."""
    x = math.sqrt(-(TOR["beta"] + nu) / (TOR["a3"] + TOR["b3"]))
    return np.array([x, 0.0, TOR["beta"] * x + TOR["b3"] * x**3])


def _tor_homoclinic_nu():
    """``nu`` of the homoclinic orbit of the saddle-focus ``E`` (:func:`_tor_saddle`;
    eigenvalues -1.67 and 0.25 +- 0.63 i): its 1-D stable manifold, integrated backward
    from ``E`` towards the origin's side, spirals back into ``E`` and is ejected along
    ``+v_s`` or ``-v_s``; the side (``w_s . (x - E)`` where it leaves the ball of radius
    0.3 after coming within 0.11) changes sign at the homoclinic orbit (Brent, 1e-14;
    radii 0.115 and 0.25 give the same value to 3e-14)."""

    def ev(E, r, d):
        e = lambda t, x: float((x - E) @ (x - E)) - r * r  # noqa: E731
        e.terminal, e.direction = True, d
        return e

    def side(nu):
        E = _tor_saddle(nu)
        J = _tor_jac(E, nu)
        w, V = np.linalg.eig(J)
        wl, W = np.linalg.eig(J.T)
        vs = V[:, int(np.argmin(w.real))].real
        vs = -vs * np.sign(vs @ E)
        ws = W[:, int(np.argmin(wl.real))].real
        ws = ws * np.sign(ws @ vs)
        x = E + 1e-9 * vs
        for r, d in ((0.5, 1), (0.11, -1), (0.3, 1)):
            sol = solve_ivp(lambda t, y: -_tor_f(y, nu), (0, 100), x, rtol=1e-12, atol=1e-16,
                            method="DOP853", events=ev(E, r, d))  # fmt: skip
            x = E + (sol.y_events[0][0] - E) * (1 + 1e-12 * d)
        return float(ws @ (x - E))

    return brentq(side, -0.729, -0.7289, xtol=1e-14)


def _tor_heteroclinic_nu():
    """``nu`` of the heteroclinic cycle ``E- -> E+ -> E-`` of the two saddle-foci ``E+-``
    (:func:`_tor_saddle`; one exists with the other by the symmetry ``x -> -x``): the
    1-D stable manifold of ``E-``, integrated backward from ``E-`` towards ``E+``, comes
    within 0.15 of ``E+`` and is ejected along ``+-v_s(E+)``; the side changes sign at
    the connection (Brent; 1e-8 / 1e-10 offsets and rtol 1e-12 / 1e-13 agree to 1e-14)."""

    def ev(E, r, d):
        e = lambda t, x: float((x - E) @ (x - E)) - r * r  # noqa: E731
        e.terminal, e.direction = True, d
        return e

    def side(nu):
        Ep = _tor_saddle(nu)
        Em = -Ep
        w, V = np.linalg.eig(_tor_jac(Em, nu))
        vs = V[:, int(np.argmin(w.real))].real
        vs = vs * np.sign(vs @ (Ep - Em))
        wp, Vp = np.linalg.eig(_tor_jac(Ep, nu))
        wl, W = np.linalg.eig(_tor_jac(Ep, nu).T)
        ws = W[:, int(np.argmin(wl.real))].real
        ws = ws * np.sign(ws @ Vp[:, int(np.argmin(wp.real))].real)
        x = Em + 1e-9 * vs
        for r, d in ((0.15, -1), (0.3, 1)):
            sol = solve_ivp(lambda t, y: -_tor_f(y, nu), (0, 200), x, rtol=1e-12, atol=1e-16,
                            method="DOP853", events=ev(Ep, r, d))  # fmt: skip
            x = Ep + (sol.y_events[0][0] - Ep) * (1 + 1e-12 * d)
        return float(ws @ (x - Ep))

    return brentq(side, -0.7975, -0.79752, xtol=1e-15)


@pytest.mark.slow
def test_tor_symmetric_cycles_snake_into_the_heteroclinic_cycle(tor_equilibria):
    """At the default settings the symmetric cycles from HB1 snake towards the
    heteroclinic cycle between the saddle-foci ``E+-`` (eigenvalues -1.67 and 0.28 +-
    0.6 i): folds of cycles on both sides of its ``nu``, closing in on it, the swings of
    the rows decaying like ``exp(-0.28 T / 2)``. The branch goes on until the cycles'
    multipliers (1e14 and more) make the collocation system too ill-conditioned; it ends
    there with a failure status that says so (no false PERIOD_UNBOUNDED claim), or at the
    period limit."""
    eq = tor_equilibria
    br = continue_from_hopf(eq, eq.find("hopf")[0], ContinuationSettings())
    nu_het = _tor_heteroclinic_nu()  # -0.79751983065330
    if br.status != Status.PERIOD_UNBOUNDED:
        assert not br.status.ok and "ill-conditioned" in br.message, br.message
    else:
        star = float(re.search(r"nu\*=(-[0-9.]+)", br.message).group(1))
        assert star == pytest.approx(nu_het, abs=1e-8)
    folds = [f for f in br.find("fold") if f.located and f.p < -0.7]
    assert len(folds) >= 6
    d = [f.p - nu_het for f in folds]
    assert min(d) < 0 < max(d)  # folds on both sides
    assert abs(d[-1]) < abs(d[0]) / 100  # closing in
    T = br.records["T"]
    assert np.all(np.abs(br.p[T > 100] - nu_het) < 1e-6)
    assert np.all(np.abs(br.p[T > 130] - nu_het) < 3e-8)
    assert np.max(br.records["error"]) <= 1.01e-6
    o = orbit_at(br, len(br) - 1)
    E = _tor_saddle(br.p[-1])
    assert np.min(np.linalg.norm(o.X - E, axis=1)) < 1e-5
    assert np.min(np.linalg.norm(o.X + E, axis=1)) < 1e-5


def test_tor_switch_at_the_branch_point_onto_the_asymmetric_cycles(tor_equilibria):
    """AUTO demo tor, run 3 (``run(r2('BP1'), ISW=-1)``): the asymmetric cycles born at
    BPC1 lose stability at a Neimark-Sacker (torus) bifurcation, TR1, then period-double
    and snake into the homoclinic orbit of the saddle-focus ``E``, with a fold and a
    period doubling at every turn. ``switch_branch`` continues them as cycles (the NS was
    reported as a 'hopf' point of the Floquet exponents before, no PD, no mesh
    adaptation, rows past the homoclinic end). References: shooting for NS (``|mu| = 1``,
    secant) and PD, the stable manifold of ``E`` for the end."""
    from continuation import switch_branch

    eq = tor_equilibria
    br = continue_from_hopf(eq, eq.find("hopf")[0], ContinuationSettings(p_min=-0.7))
    b2 = switch_branch(br, "BPC1", settings=ContinuationSettings(p_min=-0.9, p_max=-0.4),
                       direction="forward")  # fmt: skip
    assert not b2.find("hopf")
    (ns,) = b2.find("ns")
    assert ns.located
    o = orbit_at(b2, ns)

    def pair(nu):
        x0, T, M = _shoot(lambda x: _tor_f(x, nu), lambda x: _tor_jac(x, nu), o.X[0], o.T)
        w = _nontrivial(M, _tor_f(x0, nu))
        return w[int(np.argmax(w.imag))]

    w0, w1 = pair(ns.p), pair(ns.p - 1e-4)
    nu_ns = ns.p - (abs(w0) - 1.0) * (-1e-4) / (abs(w1) - abs(w0))
    assert ns.p == pytest.approx(nu_ns, abs=1e-6)  # -0.5916501950
    assert ns.data["theta"] == pytest.approx(float(np.angle(w0)), abs=1e-6)  # 0.6090741
    pds = b2.find("pd")
    pd = pds[0]
    assert pd.located and pd.p < ns.p
    o = orbit_at(b2, pd)

    def mu_near_m1(nu):
        x0, T, M = _shoot(lambda x: _tor_f(x, nu), lambda x: _tor_jac(x, nu), o.X[0], o.T)
        w = _nontrivial(M, _tor_f(x0, nu))
        return float(w[np.argmin(np.abs(w + 1.0))].real)

    m0, m1 = mu_near_m1(pd.p), mu_near_m1(pd.p - 1e-4)
    assert pd.p == pytest.approx(pd.p - (m0 + 1.0) * (-1e-4) / (m1 - m0), abs=1e-6)
    # a located PD has a multiplier at -1; deep in the snake (multipliers of 1e10 and
    # more) sign changes of the PD test without one are reported as bracketed only
    assert all(abs(p.data["mu"] + 1.0) <= 1e-3 for p in pds if p.located)
    assert len(b2.find("fold")) >= 4
    assert b2.status == Status.PERIOD_UNBOUNDED, b2.message
    nu_hom = _tor_homoclinic_nu()  # -0.72894100482
    star = float(re.search(r"nu\*=(-[0-9.]+)", b2.message).group(1))
    assert star == pytest.approx(nu_hom, abs=1e-8)
    lim = period_limit(b2)
    assert lim.saddle == pytest.approx(_tor_saddle(nu_hom), abs=1e-6)
    assert np.max(b2.records["error"]) <= 1.01e-6


# ------------------------------------------------------------------ chu (Chua's circuit)
CHUA = {"alpha": 1.0, "beta": 14.3, "K": 10.0, "a0": -1.0 / 7.0, "a1": 2.0 / 7.0}


def _chua_h(x, derivative=False):
    K, a0, a1 = CHUA["K"], CHUA["a0"], CHUA["a1"]
    if derivative:
        d = lambda u: 2 / math.pi * (np.arctan(K * u) + K * u / (1 + (K * u) ** 2))  # noqa: E731
        return a1 + 0.5 * (a0 - a1) * (d(x + 1) - d(x - 1))
    ab = lambda u: 2 * u * np.arctan(K * u) / math.pi  # noqa: E731
    return a1 * x + 0.5 * (a0 - a1) * (ab(x + 1) - ab(x - 1))


def _chua_f(x, al):
    return np.array([al * (x[1] - _chua_h(x[0])), x[0] - x[1] + x[2], -CHUA["beta"] * x[1]])


def _chua_jac(x, al):
    return np.array([[-al * _chua_h(x[0], True), al, 0.0], [1.0, -1.0, 1.0],
                     [0.0, -CHUA["beta"], 0.0]])  # fmt: skip


def _chua_hopf():
    r"""Hopf point of the equilibrium ``(x*, 0, -x*)``, ``h(x*) = 0``, in closed form.

    With ``k = h'(x*)`` the characteristic polynomial is :math:`\lambda^3 + (1 + \alpha
    k)\lambda^2 + (\beta + \alpha k - \alpha)\lambda + \alpha k \beta`; Routh-Hurwitz
    ``a_2 a_1 = a_0`` gives :math:`\beta + \alpha (k - 1) + \alpha^2 k (k - 1) = 0`,
    :math:`\omega^2 = \beta + \alpha k - \alpha`. Returns ``(x*, alpha_H, omega)``.
    """
    xs = brentq(_chua_h, 1.2, 2.0, xtol=1e-15)
    k, be = _chua_h(xs, True), CHUA["beta"]
    al = float(max(np.roots([k * (k - 1), k - 1, be]).real))
    return xs, al, math.sqrt(be + al * k - al)


def _chua_cycles(p_max, max_steps=500):
    s = System(chua_rhs, ("x", "y", "z"), tuple(CHUA))
    xs = _chua_hopf()[0]
    eq = continue_equilibria(s, [xs, 0, -xs], CHUA, "alpha", p_min=0.0, p_max=20.0,
                             direction="forward")  # fmt: skip
    st = ContinuationSettings(p_max=p_max, max_steps=max_steps)
    return eq, continue_from_hopf(eq, eq.find("hopf")[0], st)


def _chua_mu_near_m1(o, al):
    """Shooting from the cycle ``o`` at ``alpha = al``: the Floquet multiplier nearest -1
    and the period (variational equations, ``_shoot``)."""
    x0, T, M = _shoot(lambda x: _chua_f(x, al), lambda x: _chua_jac(x, al), o.X[0], o.T)
    w = _nontrivial(M, _chua_f(x0, al))
    return float(w[np.argmin(np.abs(w + 1.0))].real), T


def test_chua_hopf_and_period_doubling():
    """Hopf point (closed form) and the first period doubling of the cycles born there.
    Reference: at the located ``alpha`` the shooting monodromy has a multiplier at -1
    (secant of ``mu(alpha) + 1`` from two shooting solutions gives ``alpha_PD``)."""
    xs, al_h, omega = _chua_hopf()
    eq, br = _chua_cycles(9.0)
    (h,) = eq.find("hopf")
    assert h.located and h.p == pytest.approx(al_h, abs=1e-9)
    assert h.data["omega"] == pytest.approx(omega, abs=1e-8)
    assert br.status == Status.PARAM_BOUND, br.message
    (pd,) = br.find("pd")
    assert pd.located and pd.data["mu"] == pytest.approx(-1.0, abs=1e-8)
    o = orbit_at(br, pd)

    (m0, T0), (m1, _) = _chua_mu_near_m1(o, pd.p), _chua_mu_near_m1(o, pd.p + 1e-3)
    al_pd = pd.p - (m0 + 1.0) * 1e-3 / (m1 - m0)
    assert pd.p == pytest.approx(al_pd, abs=1e-6)
    assert o.T == pytest.approx(T0, abs=1e-8)


def test_chua_cycle_from_a_trajectory_and_the_doubled_branch():
    """The stable cycle simulated at ``alpha = 7.5`` (``orbit_from_trajectory``), continued
    both ways: backward its cycles shrink onto the equilibrium at the Hopf point (the
    branch ends there, the point bracketed), forward the PD of
    :func:`test_chua_hopf_and_period_doubling`; on the doubled branch
    (``continue_period_doubled``) the next PD of the cascade. Reference: shooting of the
    doubled cycle (period ``~2 T``), multiplier -1 by a secant in ``alpha``."""
    from continuation import simulate
    from continuation.periodic import (
        continue_period_doubled,
        continue_periodic,
        orbit_from_trajectory,
    )

    _, al_h, omega = _chua_hopf()
    s = System(chua_rhs, ("x", "y", "z"), tuple(CHUA))
    P = dict(CHUA, alpha=7.5)
    tr = simulate(s, [1.6, 0.0, -1.5], P, (0.0, 200.0), dt=0.01)
    orb = orbit_from_trajectory(s, P, tr)
    br = continue_periodic(s, orb, P, "alpha", ContinuationSettings(p_min=0.0, p_max=9.0),
                           direction="both")  # fmt: skip
    assert br.status == Status.PARAM_BOUND and "Hopf point" in br.message, br.message
    (h,) = br.find("hopf")
    assert not h.located and h.index == 0 and h.p == pytest.approx(al_h, abs=1e-3)
    assert h.data["omega"] == pytest.approx(omega, rel=1e-3)
    assert not br.find("fold") and not br.find("bp")
    (pd,) = br.find("pd")
    assert pd.located and pd.p == pytest.approx(8.19599212, abs=1e-6)  # the Hopf start's
    b2 = continue_period_doubled(br, pd, ContinuationSettings(p_min=0.0, p_max=9.5))
    assert b2.records["T"][0] == pytest.approx(2 * orbit_at(br, pd).T, rel=1e-4)
    (pd2,) = b2.find("pd")
    assert pd2.located
    o = orbit_at(b2, pd2)

    (m0, T0), (m1, _) = _chua_mu_near_m1(o, pd2.p), _chua_mu_near_m1(o, pd2.p + 1e-3)
    assert pd2.p == pytest.approx(pd2.p - (m0 + 1.0) * 1e-3 / (m1 - m0), abs=1e-6)  # 8.4183872
    assert o.T == pytest.approx(T0, abs=1e-7)


def _chua_homoclinic_alpha():
    """``alpha`` of the homoclinic orbit of the origin (a saddle-focus) by bisection on the
    side of its unstable manifold: the branch ``+v_u`` leaves the origin, spirals back
    into it, and is ejected along ``+v_u`` or ``-v_u`` (``w_u . x`` at ``|x| = 0.4``
    after it came within 0.15). The bisection brackets the sign change to 1e-13."""

    def ev(r, d):
        e = lambda t, x: float(x @ x) - r * r  # noqa: E731
        e.terminal, e.direction = True, d
        return e

    def side(al):
        J = _chua_jac(np.zeros(3), al)
        w, V = np.linalg.eig(J)
        wl, W = np.linalg.eig(J.T)
        vu = V[:, int(np.argmax(w.real))].real
        wu = W[:, int(np.argmax(wl.real))].real
        wu = wu * np.sign(wu @ vu)
        x = 1e-9 * vu
        for r, d in ((0.5, 1), (0.15, -1), (0.4, 1)):
            sol = solve_ivp(lambda t, y: _chua_f(y, al), (0, 60), x, rtol=1e-12, atol=1e-16,
                            method="DOP853", events=ev(r, d))  # fmt: skip
            x = sol.y_events[0][0] * (1 + 1e-12 * d)
        return float(wu @ x)

    return brentq(side, 11.07835, 11.07845, xtol=1e-13)


@pytest.mark.slow
def test_chua_cycles_snake_into_the_shilnikov_homoclinic_orbit(caplog):
    """The cycles approach the homoclinic orbit of the saddle-focus origin (Shilnikov:
    ``lambda_u = 2.83 > -Re lambda_s = 1.12``) by a snake: the branch passes the limit,
    turns at folds of cycles on both sides of it, each with a period doubling beside it,
    the period growing through every turn. The branch ends with PERIOD_UNBOUNDED at the
    limit; before the fix the rows were cut at the first pass of the limit (no fold,
    one PD)."""
    al_hom = _chua_homoclinic_alpha()  # 11.0784015787...
    _, br = _chua_cycles(20.0)
    assert br.status == Status.PERIOD_UNBOUNDED, br.message
    star = float(re.search(r"alpha\*=([0-9.]+)", br.message).group(1))
    assert star == pytest.approx(al_hom, abs=1e-7)
    assert abs(br.p[-1] - al_hom) < 1e-5
    folds = br.find("fold")
    assert len(folds) >= 4 and all(f.located for f in folds[:4])
    left = [f.p for f in folds if f.p < al_hom]
    right = [f.p for f in folds if f.p > al_hom]
    assert left and right  # folds on both sides of the limit
    # the folds close in on the limit
    assert abs(folds[3].p - al_hom) < abs(folds[0].p - al_hom)
    assert np.all(np.diff(br.records["T"]) > 0)
    assert len(br.find("pd")) >= 4
    assert all(abs(p.data["mu"] + 1.0) <= 1e-3 for p in br.find("pd") if p.located)
    assert np.max(br.records["error"]) <= 1.01e-6
    # the last cycle passes next to the origin
    o = orbit_at(br, len(br) - 1)
    assert np.min(np.linalg.norm(o.X, axis=1)) < 1e-3
    # the kept rows swing about the limit: a fit of the monotone law to them says so
    with caplog.at_level(logging.WARNING, logger="continuation.periodic.limit"):
        lim = period_limit(br)
    assert "unreliable" in caplog.text and lim.fit_residual > abs(br.p[-1] - lim.p_star)


# ------------------------------------------------------------------ pp2 (predator-prey)
PP2 = {"quota": 0.0, "p2": 3.0, "p3": 5.0, "p4": 3.0}


def _pp2_rhs(x, p, ops):
    q, p2, p3, p4 = p[0], p[1], p[2], p[3]
    return ops.stack([p2 * x[0] * (1 - x[0]) - x[0] * x[1] - q * (1 - ops.exp(-p3 * x[0])),
                      -x[1] + p4 * x[0] * x[1]])  # fmt: skip


def _pp2_hopf():
    r"""Hopf point in closed form: at the coexistence equilibrium ``u1 = 1 / p4`` the
    Jacobian has ``J22 = 0`` and trace ``J11 = p2 (1 - 2 u1) - u2 - q p3 e``, ``e =
    exp(-p3 u1)``, ``u2 = p2 (1 - u1) - q (1 - e) / u1``; trace 0 at :math:`q =
    p_2 u_1 / ((1 - e)/u_1 - p_3 e)`, :math:`\omega^2 = \det = p_4 u_1 u_2`."""
    p2, p3, p4 = PP2["p2"], PP2["p3"], PP2["p4"]
    u1 = 1 / p4
    e = math.exp(-p3 * u1)
    q = p2 * u1 / ((1 - e) / u1 - p3 * e)
    u2 = p2 * (1 - u1) - q * (1 - e) / u1
    return q, math.sqrt(p4 * u1 * u2)


def _pp2_prey_equilibria(q):
    """The two prey-only equilibria ``(u, 0)``, ``p2 (1 - u) = q (1 - exp(-p3 u)) / u``."""
    p2, p3 = PP2["p2"], PP2["p3"]
    g = lambda u: p2 * (1 - u) - q * (1 - math.exp(-p3 * u)) / u  # noqa: E731
    us = np.linspace(1e-3, 1.0, 1001)
    gv = [g(u) for u in us]
    return [brentq(g, us[i], us[i + 1], xtol=1e-15) for i in range(us.size - 1)
            if gv[i] * gv[i + 1] < 0]  # fmt: skip


def _pp2_heteroclinic_quota():
    """``quota`` where the unstable manifold of the large prey-only saddle ``A`` meets the
    stable manifold of the small one ``B`` (both leave the prey axis into ``u2 > 0``;
    the return ``B -> A`` along the axis exists for every quota): the gap in ``u2`` of
    the two manifolds (integrated from 1e-6 along their eigenvectors) at the section
    ``u1 = (u_A + u_B) / 2``, zero by Brent's method."""
    p2, p3, p4 = PP2["p2"], PP2["p3"], PP2["p4"]

    def gap(q):
        uB, uA = _pp2_prey_equilibria(q)
        f = lambda t, x: [p2 * x[0] * (1 - x[0]) - x[0] * x[1] - q * (1 - math.exp(-p3 * x[0])),  # noqa: E731
                          -x[1] + p4 * x[0] * x[1]]  # fmt: skip
        fp = lambda u: p2 * (1 - 2 * u) - q * p3 * math.exp(-p3 * u)  # noqa: E731
        ends = []
        for u, t_end in ((uA, 200.0), (uB, -200.0)):
            lam = -1 + p4 * u  # the eigenvalue off the axis, eigenvector (-u / (lam - f'), 1)
            v = np.array([-u / (lam - fp(u)), 1.0])
            sec = lambda t, x: x[0] - 0.5 * (uA + uB)  # noqa: E731
            sec.terminal = True
            r = solve_ivp(f, (0, t_end), np.array([u, 0.0]) + 1e-6 * v / np.linalg.norm(v),
                          events=sec, rtol=1e-12, atol=1e-14, method="DOP853")  # fmt: skip
            ends.append(r.y_events[0][0][1])
        return ends[0] - ends[1]

    return brentq(gap, 0.705, 0.71, xtol=1e-14)


def test_pp2_cycles_end_at_the_heteroclinic_cycle(caplog):
    """From the Hopf point (closed form) the cycles grow until they approach the
    heteroclinic cycle of the two prey-only saddles (the AUTO demo stops at period 36,
    "when the heteroclinic orbit is very close"); at defaults the branch ends with
    PERIOD_UNBOUNDED where the rows can no longer tell the side of the limit, the limit
    within 1e-9 of the manifolds' reference (its own accuracy about 1e-13)."""
    q_h, omega = _pp2_hopf()
    s = System(_pp2_rhs, ("fish", "sharks"), tuple(PP2))
    u1 = 1 / PP2["p4"]
    eq = continue_equilibria(s, [u1, PP2["p2"] * (1 - u1)], PP2, "quota", p_min=0.0,
                             p_max=1.0, direction="forward")  # fmt: skip
    (h,) = eq.find("hopf")
    assert h.located and h.p == pytest.approx(q_h, abs=1e-9)
    assert h.data["omega"] == pytest.approx(omega, abs=1e-8)
    br = continue_from_hopf(eq, h, ContinuationSettings(p_min=0.0, p_max=1.0))
    assert br.status == Status.PERIOD_UNBOUNDED, br.message
    assert br.records["T"][0] == pytest.approx(2 * math.pi / omega, rel=1e-3)
    assert np.max(br.records["error"]) <= 1.01e-6
    q_star = _pp2_heteroclinic_quota()  # 0.70807280749846
    with caplog.at_level(logging.WARNING, logger="continuation.periodic.limit"):
        lim = period_limit(br)
    assert "unreliable" not in caplog.text  # (a monotone approach)
    assert lim.p_star == pytest.approx(q_star, abs=1e-9)
    assert np.all(br.p < q_star) and br.p[-1] == pytest.approx(q_star, abs=1e-9)
    assert br.records["T"][-1] > 60.0
    # the saddle the cycle lingers at: the large prey-only equilibrium, its rate off the axis
    uA = max(_pp2_prey_equilibria(q_star))
    assert lim.saddle == pytest.approx([uA, 0.0], abs=1e-6)
    assert lim.lambda_u == pytest.approx(-1 + PP2["p4"] * uA, rel=1e-6)
    # every nontrivial multiplier is inside the unit circle (stable cycles) and tends to 0
    mu = multipliers(br)[:, 0]
    assert np.all(np.abs(mu) < 1.0) and abs(mu[-1]) < 1e-6


# ------------------------------------------------------------------ plp (activator-inhibitor)
PLP = {"s0": 110.0, "a0": 500.0, "alpha": 0.2, "rho": 2.021628, "kappa": 0.1}


def _plp_rhs(x, p, ops):
    s0, a0, al, rho, k = p[0], p[1], p[2], p[3], p[4]
    R = x[0] * x[1] / (1 + x[0] + k * x[0] ** 2)
    return ops.stack([(s0 - x[0]) - rho * R, al * (a0 - x[1]) - rho * R])


def _plp_f(x, rho):
    R = x[0] * x[1] / (1 + x[0] + PLP["kappa"] * x[0] ** 2)
    return np.array([(PLP["s0"] - x[0]) - rho * R, PLP["alpha"] * (PLP["a0"] - x[1]) - rho * R])


def _plp_jac(x, rho):
    s, a, k = x[0], x[1], PLP["kappa"]
    D = 1 + s + k * s * s
    Rs, Ra = (a * D - s * a * (1 + 2 * k * s)) / D**2, s / D
    return np.array([[-1 - rho * Rs, -rho * Ra], [-rho * Rs, -PLP["alpha"] - rho * Ra]])


def _plp_dfdrho(x, rho):
    R = x[0] * x[1] / (1 + x[0] + PLP["kappa"] * x[0] ** 2)
    return np.array([-R, -R])


def _plp_hopf_points():
    r"""The Hopf points of the equilibria, parametrised by ``s``.

    An equilibrium has ``a = a0 - (s0 - s) / alpha`` and ``rho = (s0 - s) / R(s, a)``;
    its Jacobian :func:`_plp_jac` has trace zero (Brent on ``s``) with positive
    determinant :math:`\omega^2`. Returns ``[(rho_H, omega), ...]`` in increasing ``rho``.
    """
    s0, a0, al = PLP["s0"], PLP["a0"], PLP["alpha"]

    def at(s):
        a = a0 - (s0 - s) / al
        rho = (s0 - s) * (1 + s + PLP["kappa"] * s * s) / (s * a)
        return rho, _plp_jac(np.array([s, a]), rho)

    ss = np.linspace(s0 - al * a0 + 1e-6, s0 - 1e-6, 4001)
    tr = np.array([np.trace(at(s)[1]) for s in ss])
    out = []
    for i in np.flatnonzero(tr[:-1] * tr[1:] < 0):
        s = brentq(lambda s: np.trace(at(s)[1]), ss[i], ss[i + 1], xtol=1e-14)
        rho, J = at(s)
        out.append((rho, math.sqrt(np.linalg.det(J))))
    return sorted(out)


def test_plp_cycles_join_the_two_hopf_points_through_two_folds():
    """AUTO demo plp (Doedel, Keller & Kernevez 1991; the activator-inhibitor model of
    Kernevez et al. 1980), ``s0 = 110, a0 = 500, alpha = 0.2, kappa = 0.1``, free
    ``rho``: the equilibria lose stability at two Hopf points; the cycles from the first
    turn at two folds of cycles and shrink back onto the equilibrium at the second.
    References: the Hopf points in closed form (trace zero), each LPC by shooting (the
    extremum of ``rho`` over the cycles of fixed period). The branch must end at the
    second Hopf point (before, it retraced itself with false LPCs at both Hopf values
    until the mesh ran out). ``ds_max = 3`` as in the demo's constants files (the states
    are of order 100: the default 0.1 in the ``(s, a, rho)`` norm needs over 500 steps)."""
    (h1, w1), (h2, w2) = _plp_hopf_points()  # rho_H = 3.49995383, 4.65045781
    s = System(_plp_rhs, ("s", "a"), tuple(PLP))
    eq = continue_equilibria(s, [45.55974, 177.7987], PLP, "rho", p_min=0.0, p_max=6.0,
                             direction="both", ds_max=3.0)  # fmt: skip
    hs = eq.find("hopf")
    assert [h.located for h in hs] == [True, True]
    assert sorted(h.p for h in hs) == pytest.approx([h1, h2], abs=1e-9)
    assert sorted(hs, key=lambda h: h.p)[0].data["omega"] == pytest.approx(w1, abs=1e-8)
    start = min(hs, key=lambda h: abs(h.p - h1))
    br = continue_from_hopf(eq, start, ContinuationSettings(p_min=0.0, p_max=6.0, ds_max=3.0))
    assert br.status == Status.EVENT and "Hopf point" in br.message, br.message
    folds = br.find("fold")
    assert [f.label for f in folds] == ["LPC1", "LPC2"] and all(f.located for f in folds)
    for lpc in folds:
        # the cycles through the points x0 + r e of a line across them (e from the mean
        # of the LPC's cycle to its point x0): rho(r) is extremal at the LPC (a parabola
        # through three of them, sharp: rho'' ~ 1.5e3 at LPC1, so r = +-1e-5 keeps Newton
        # in its basin; the period is not monotone along the family here)
        o = orbit_at(br, lpc)
        e = o.X[0] - o.X.mean(axis=0)
        h = 1e-5
        rhos = [_shoot_through(_plp_f, _plp_jac, _plp_dfdrho, lpc.p, o.X[0] + d * e, o.T)
                for d in (-h, 0, h)]  # fmt: skip
        curv = (rhos[0] - 2 * rhos[1] + rhos[2]) / h**2
        rho_lpc = rhos[1] - (rhos[2] - rhos[0]) ** 2 / (8 * h**2 * curv)
        assert lpc.p == pytest.approx(rho_lpc, abs=1e-6)  # 2.75968746, 5.00783976
    # the end: a Hopf point bracketed (not located) near the second one
    (end,) = br.find("hopf")
    assert not end.located and end.index == len(br) - 1
    assert end.p == pytest.approx(h2, abs=0.02)
    assert end.data["omega"] == pytest.approx(w2, rel=0.02)
    assert np.max(br.records["error"]) <= 1.01e-6


def test_tor_both_halves_of_the_asymmetric_cycles_are_mirror_images(tor_equilibria):
    """The tor system is odd (``x -> -x`` maps solutions to solutions): the two halves of
    the branch crossing at the symmetry-breaking BPC1 are mirror images, each with its
    own TR1 at the same ``nu``; ``direction="both"`` joins them into one branch."""
    from continuation.periodic import continue_from_branch_point

    eq = tor_equilibria
    br = continue_from_hopf(eq, eq.find("hopf")[0], ContinuationSettings(p_min=-0.7))
    st = ContinuationSettings(p_min=-0.65, p_max=-0.4)
    fw = continue_from_branch_point(br, "BPC1", st, direction="forward")
    bw = continue_from_branch_point(br, "BPC1", st, direction="backward")
    assert fw.status == bw.status == Status.PARAM_BOUND
    assert fw.records["max_x"][-1] == pytest.approx(-bw.records["min_x"][-1], abs=1e-6)
    assert fw.records["T"][-1] == pytest.approx(bw.records["T"][-1], abs=1e-6)
    assert fw.records["max_x"][-1] > 0.2 + bw.records["max_x"][-1]  # not the same half
    (n1,), (n2,) = fw.find("ns"), bw.find("ns")
    assert n1.p == pytest.approx(n2.p, abs=1e-8)
    both = continue_from_branch_point(br, "BPC1", st, direction="both")
    assert len(both.find("ns")) == 2 and len(both.find("pd")) == 2
    # every cycle of both halves is kept (the halves start apart, off the branch point)
    assert len(both) == len(fw) + len(bw)
    # from the backward half's end to the forward half's end (the halves' ends differ by
    # more than 0.2 in max x, above; each row is within error_tol = 1e-6)
    mx = both.records["max_x"]
    assert mx[0] == pytest.approx(bw.records["max_x"][-1], abs=1e-6)
    assert mx[-1] == pytest.approx(fw.records["max_x"][-1], abs=1e-6)
    assert mx[len(bw) - 1] == pytest.approx(bw.records["max_x"][0], abs=1e-6)
    assert mx[len(bw)] == pytest.approx(fw.records["max_x"][0], abs=1e-6)
    assert both.status == fw.status
    assert both.p[0] == pytest.approx(-0.65) and both.p[-1] == pytest.approx(-0.65)
