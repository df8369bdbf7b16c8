"""Periodic orbits by collocation (continuation.periodic), each against a reference."""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest
from helpers import pendulum_loop_returns, vdp_period
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from continuation import (
    ContinuationSettings,
    SpecialKind,
    Status,
    System,
    continue_equilibria,
    simulate,
)
from continuation.bvp import CollocationMesh, solve_connection
from continuation.periodic import (
    PeriodicOrbitProblem,
    continue_from_hopf,
    continue_period_doubled,
    continue_periodic,
    error_estimate,
    first_lyapunov_coefficient,
    multipliers,
    orbit_at,
    orbit_from_array,
    orbit_from_trajectory,
    period_limit,
    periodic_orbit_from_hopf,
    problem_at,
    solve_orbit,
)

#: van der Pol x'' - mu (1 - x^2) x' + x = 0 at mu = 1: the commonly tabulated period
#: 6.6632868593... (the digits beyond the tenth are from our own independent scipy
#: shooting computation, which test_van_der_pol_period_published_and_shooting repeats).
VDP_T_MU1 = 6.663286859323130


def _hopf_nf(x, p, ops):
    r2 = x[0] ** 2 + x[1] ** 2
    return ops.stack([p[0] * x[0] - x[1] - x[0] * r2, x[0] + p[0] * x[1] - x[1] * r2])


def _bautin(x, p, ops):
    r2 = x[0] ** 2 + x[1] ** 2
    g = p[0] + p[1] * r2 - r2 * r2
    return ops.stack([g * x[0] - x[1], x[0] + g * x[1]])


def _vdp(x, p, ops):
    return ops.stack([x[1], p[0] * (1 - x[0] ** 2) * x[1] - x[0]])


def _rossler(x, p, ops):
    return ops.stack([-x[1] - x[2], x[0] + p[0] * x[1], p[1] + x[2] * (x[0] - p[2])])


def _pendulum(x, p, ops):
    return ops.stack([x[1], p[0] - p[1] * x[1] - ops.sin(x[0])])


def _vdp_orbit(mu: float, mesh: CollocationMesh):
    s = System(_vdp, ("x", "y"), ("mu",))
    tr = simulate(s, [2.0, 0.0], {"mu": mu}, (0.0, 60.0), dt=0.01)
    return s, orbit_from_trajectory(s, {"mu": mu}, tr, mesh=mesh)


# ------------------------------------------------------------------ normal forms
def test_hopf_normal_form_radius_period_multiplier():
    """Cycles r = sqrt(mu), T = 2 pi, multiplier exp(-4 pi mu) (closed form)."""
    s = System(_hopf_nf, ("x", "y"), ("mu",))
    assert first_lyapunov_coefficient(s, [0.0, 0.0], {"mu": 0.0}) == pytest.approx(-2.0, 1e-12)
    eq = continue_equilibria(s, [0, 0], {"mu": -0.5}, "mu", p_min=-1, p_max=1,
                             direction="forward", ds=0.05)  # fmt: skip
    (h,) = eq.find("hopf")
    orb = periodic_orbit_from_hopf(eq, h.label, amplitude=0.05)
    # first-order amplitude: the parameter offset from the normal form (r^2 = mu)
    assert orb.param("mu") == pytest.approx(0.05**2, rel=1e-6)
    br = continue_from_hopf(eq, h.label, ContinuationSettings(ds=0.05, ds_max=0.1,
                            max_steps=40, p_max=1.5), mesh=CollocationMesh(20, 4, 1.0))  # fmt: skip
    assert br.status == Status.PARAM_BOUND and br.p[-1] == pytest.approx(1.5)
    assert np.all(np.diff(br.p) > 0)  # left the Hopf point
    np.testing.assert_allclose(br.records["max_x"], np.sqrt(br.p), rtol=1e-8)
    np.testing.assert_allclose(br.records["T"], 2 * np.pi, rtol=1e-10)
    mu = multipliers(br)[:, 0]
    np.testing.assert_allclose(np.log(mu.real), -4 * np.pi * br.p, rtol=1e-7)  # exponents
    assert np.all(br.stable)
    assert not br.special_points


def test_bautin_fold_of_cycles():
    """r' = r (mu + r^2 - r^4): cycles mu = r^4 - r^2, LPC at mu = -1/4, r^2 = 1/2,
    multiplier exp(2 pi (2 r^2 - 4 r^4))."""
    s = System(_bautin, ("x", "y"), ("mu", "beta"))
    eq = continue_equilibria(s, [0, 0], {"mu": -0.5, "beta": 1.0}, "mu", p_min=-1, p_max=1,
                             direction="forward", ds=0.05)  # fmt: skip
    (h,) = eq.find("hopf")
    assert first_lyapunov_coefficient(s, h.x, {"mu": h.p, "beta": 1.0}) == pytest.approx(2.0)
    br = continue_from_hopf(eq, h.label, ContinuationSettings(ds=0.01, ds_max=0.05,
                            max_steps=100, p_min=-1, p_max=0.5), amplitude=0.05,
                            mesh=CollocationMesh(20, 4, 1.0))  # fmt: skip
    assert br.p[1] < br.p[0]  # subcritical: cycles for mu < 0
    lpc = br.find("fold")
    assert [sp.label for sp in lpc] == ["LPC1"]
    assert lpc[0].located
    assert lpc[0].p == pytest.approx(-0.25, abs=1e-9)
    X = orbit_at(br, lpc[0]).X  # (the mesh of the LPC's row)
    assert np.max(np.hypot(X[:, 0], X[:, 1])) ** 2 == pytest.approx(0.5, abs=1e-7)
    r = br.records["max_x"]
    np.testing.assert_allclose(br.p, r**4 - r**2, atol=1e-10)
    mu = multipliers(br)[:, 0].real
    np.testing.assert_allclose(np.log(mu), 2 * np.pi * (2 * r**2 - 4 * r**4), rtol=1e-6, atol=1e-9)
    # unstable small cycles, stable large ones
    assert not br.stable[1] and br.stable[-1]


# ------------------------------------------------------------------ van der Pol
def test_van_der_pol_period_published_and_shooting():
    s, orb = _vdp_orbit(1.0, CollocationMesh(60, 4, 1.0))
    assert orb.T == pytest.approx(VDP_T_MU1, abs=1e-10)

    # independent: scipy shooting on the section y = 0 (x > 0), DOP853
    def ret(x0: float) -> tuple[float, float]:
        ev = lambda t, x: x[1]  # noqa: E731
        ev.direction = -1
        r = solve_ivp(lambda t, x: [x[1], (1 - x[0] ** 2) * x[1] - x[0]], (0, 20),
                      [x0, 0.0], events=ev, rtol=1e-13, atol=1e-13, method="DOP853")  # fmt: skip
        k = int(np.argmax(r.t_events[0] > 1.0))
        return float(r.y_events[0][k][0]), float(r.t_events[0][k])

    x_star = brentq(lambda a: ret(a)[0] - a, 1.5, 2.5, xtol=1e-13)
    assert orb.T == pytest.approx(ret(x_star)[1], abs=1e-8)


@pytest.mark.parametrize("degree", [2, 3])
def test_collocation_order(degree):
    """The period converges with the mesh-point order 2 m (Gauss collocation)."""
    errs = []
    Ns = (16, 32, 64) if degree == 2 else (20, 40, 80)
    for N in Ns:
        _, orb = _vdp_orbit(1.0, CollocationMesh(N, degree, 1.0))
        errs.append(abs(orb.T - VDP_T_MU1))
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(orders - 2 * degree) < 0.6), orders


def test_error_estimate_tracks_the_true_error():
    """The uniform-error estimate is within a factor 10 of the actual error of the
    collocation polynomial (against a fine solution), and of order m + 1."""
    _, fine = _vdp_orbit(1.0, CollocationMesh(160, 4, 1.0))
    out = []
    for N in (20, 40):
        _, orb = _vdp_orbit(1.0, CollocationMesh(N, 3, 1.0))
        # align phases: both start on the same hyperplane only approximately, so
        # compare x(t) sampled at the same times after a shift minimising the distance
        tau = np.linspace(0, 1, 2001)
        a = orb.mesh.interpolate(orb.X, tau)
        shifts = np.linspace(-0.02, 0.02, 401) * fine.T
        best = min(shifts, key=lambda d: np.max(np.abs(fine(orb.T * tau + d) - a)))
        true = float(np.max(np.abs(fine(fine.T * tau + best) - a)))
        est = error_estimate(orb.mesh, orb.X)
        out.append((true, est))
    for true, est in out:
        assert 0.1 * true < est < 10 * true, out


def test_adapted_mesh_resolves_a_relaxation_oscillation():
    """van der Pol mu = 10 (fast jumps, slow drifts): 60 equidistributed intervals beat
    120 uniform ones by orders of magnitude in the period (reference: 240 adapted)."""
    s = System(_vdp, ("x", "y"), ("mu",))
    tr = simulate(s, [2.0, 0.0], {"mu": 10.0}, (0.0, 200.0), dt=0.005)
    ref = orbit_from_trajectory(s, {"mu": 10.0}, tr, mesh=CollocationMesh(240, 4, 1.0), adapt=True)
    uni = orbit_from_trajectory(s, {"mu": 10.0}, tr, mesh=CollocationMesh(120, 4, 1.0))
    ada = orbit_from_trajectory(s, {"mu": 10.0}, tr, mesh=CollocationMesh(60, 4, 1.0), adapt=True)
    assert ref.T == pytest.approx(19.0784, abs=1e-4)  # tabulated: T(10) = 19.0784
    e_uni, e_ada = abs(uni.T - ref.T), abs(ada.T - ref.T)
    assert e_ada < 1e-3 * e_uni
    assert error_estimate(ada.mesh, ada.X) < error_estimate(uni.mesh, uni.X)


def test_a_branch_on_too_coarse_a_mesh_says_so_and_error_tol_fixes_it():
    """van der Pol from mu = 1 to 10 (the jumps sharpen as mu grows). On a fixed mesh
    (40 uniform intervals, error_tol=None) the period at mu = 10 is off by more than 1 %,
    and the message must say that the collocation error estimate is large there. With
    ``error_tol`` the mesh grows: the start cycle is refined before the first step
    (its estimate within the tolerance) and the periods at mu = 5 and 10 agree with a
    simulation to 1e-6 (relative)."""
    from continuation import Event

    s, orb = _vdp_orbit(1.0, CollocationMesh(40, 4, 1.0))
    uz = [Event("UZ5", lambda z, p: p - 5.0), Event("UZ10", lambda z, p: p - 10.0)]
    st = ContinuationSettings(p_max=10.0)
    ref = {"UZ5": vdp_period(5.0), "UZ10": vdp_period(10.0)}
    assert ref["UZ10"] == pytest.approx(19.0784, abs=1e-4)  # tabulated: T(10) = 19.0784

    def periods(br):
        return {sp.label: float(sp.x[-1]) for sp in br.special_points
                if sp.label in ref and sp.located}  # fmt: skip

    coarse = continue_periodic(s, orb, {"mu": 1.0}, "mu", st, events=uz, error_tol=None)
    assert coarse.status == Status.PARAM_BOUND
    assert abs(periods(coarse)["UZ10"] - ref["UZ10"]) > 1e-2 * ref["UZ10"]
    assert "Collocation error estimate above" in coarse.message
    assert "pass error_tol" in coarse.message

    tol = 1e-6
    fine = continue_periodic(s, orb, {"mu": 1.0}, "mu", st, events=uz, error_tol=tol)
    assert fine.status == Status.PARAM_BOUND
    assert fine.records["error"][0] <= tol
    got = periods(fine)
    assert set(got) == set(ref)
    for k in ref:
        assert got[k] == pytest.approx(ref[k], rel=1e-6), (k, got[k], ref[k])
    assert "of the cycle's range" not in fine.message  # (only without error_tol)


# ------------------------------------------------------------------ Floquet
def _variational_monodromy(f, jac, x0, T):
    n = x0.size

    def rhs(t, y):
        x, Y = y[:n], y[n:].reshape(n, n)
        return np.concatenate([f(x), (jac(x) @ Y).ravel()])

    r = solve_ivp(rhs, (0, T), np.concatenate([x0, np.eye(n).ravel()]), rtol=1e-12,
                  atol=1e-12, method="DOP853")  # fmt: skip
    return r.y[n:, -1].reshape(n, n)


def test_floquet_multipliers_against_variational_equations():
    """Rossler cycle (a = b = 0.2, c = 2.5): multipliers by condensation vs the
    monodromy matrix of the variational equations integrated by scipy."""
    s = System(_rossler, ("x", "y", "z"), ("a", "b", "c"))
    P = {"a": 0.2, "b": 0.2, "c": 2.5}
    tr = simulate(s, [1.0, 1.0, 0.0], P, (0.0, 300.0), dt=0.01)
    orb = orbit_from_trajectory(s, P, tr, mesh=CollocationMesh(60, 4, 1.0))
    prob = PeriodicOrbitProblem.from_orbit(orb, "c")
    fl = prob.floquet(prob.reference, 2.5)
    pv = np.array([0.2, 0.2, 2.5])
    Mo = _variational_monodromy(lambda x: s.f(x, pv), lambda x: s.jacobian(x, pv),
                                orb.X[0], orb.T)  # fmt: skip
    ref = np.linalg.eigvals(Mo)
    ref = ref[np.argsort(np.abs(ref - 1.0))]
    assert abs(fl.trivial - 1) < 1e-9 and abs(ref[0] - 1) < 1e-7
    np.testing.assert_allclose(np.sort(np.abs(fl.multipliers)), np.sort(np.abs(ref[1:])),
                               rtol=1e-6, atol=1e-10)  # fmt: skip
    np.testing.assert_allclose(prob.monodromy(prob.reference, 2.5), Mo, rtol=1e-6, atol=1e-6)


def test_van_der_pol_multiplier_liouville():
    """2D: the nontrivial multiplier is exp(int_0^T div f dt) (Liouville)."""
    s, orb = _vdp_orbit(2.0, CollocationMesh(60, 4, 1.0))
    prob = PeriodicOrbitProblem.from_orbit(orb, "mu")
    mu = prob.floquet(prob.reference, 2.0).multipliers[0]
    lay = prob.layout
    Xs = orb.X[lay.stage_points]
    div = float(np.sum(lay.weights * 2.0 * (1 - Xs[:, 0] ** 2))) * orb.T
    assert mu.real == pytest.approx(math.exp(div), rel=1e-8)


# ------------------------------------------------------------------ period doubling
def test_rossler_period_doubling_against_shooting():
    """Rossler a = b = 0.2: first period doubling near c = 2.83 (e.g. Kuznetsov 2004,
    Sec. 10.? example values 2.83); confirmed by an independent computation: at the
    located c, scipy shooting plus the variational equations give a multiplier -1."""
    s = System(_rossler, ("x", "y", "z"), ("a", "b", "c"))
    P = {"a": 0.2, "b": 0.2, "c": 2.5}
    tr = simulate(s, [1.0, 1.0, 0.0], P, (0.0, 300.0), dt=0.01)
    orb = orbit_from_trajectory(s, P, tr, mesh=CollocationMesh(50, 4, 1.0))
    br = continue_periodic(s, orb, P, "c", ContinuationSettings(ds=0.05, ds_max=0.1,
                           max_steps=40, p_max=3.0))  # fmt: skip
    (pd,) = br.find("PD")
    assert br.find("pd") == (pd,) and pd.kind is SpecialKind.PERIOD_DOUBLING
    assert pd.located and pd.data["mu"] == pytest.approx(-1.0, abs=1e-8)
    assert pd.p == pytest.approx(2.83, abs=0.01)
    # independent: the cycle at c_PD by shooting (Newton on x(T) - x(0) with the
    # section x_1 = x_1(0)), then its monodromy from the variational equations
    c = pd.p
    pv = np.array([0.2, 0.2, c])
    X0, T0 = orbit_at(br, pd).X[0], orbit_at(br, pd).T
    y = np.array([X0[0], X0[2], T0])
    for _ in range(8):
        x0 = np.array([y[0], X0[1], y[1]])
        Mo = _variational_monodromy(lambda x: s.f(x, pv), lambda x: s.jacobian(x, pv), x0, y[2])
        xT = solve_ivp(lambda t, x: s.f(x, pv), (0, y[2]), x0, rtol=1e-12, atol=1e-12,
                       method="DOP853").y[:, -1]  # fmt: skip
        r = xT - x0
        A = np.column_stack([(Mo - np.eye(3))[:, [0, 2]], s.f(xT, pv)])
        y = y - np.linalg.solve(A, r)
    ref = np.linalg.eigvals(Mo)
    assert np.min(np.abs(ref + 1.0)) < 1e-5
    assert y[2] == pytest.approx(orbit_at(br, pd).T, abs=1e-7)


def test_rossler_switch_onto_doubled_branch():
    """From the first PD the doubled branch (period 2 T) starts; along it the next PD
    lies near c = 3.837 (published cascade values c_1 = 2.83, c_2 = 3.84); a doubled
    cycle is confirmed by direct integration (it closes after 2 T, not after T)."""
    s = System(_rossler, ("x", "y", "z"), ("a", "b", "c"))
    P = {"a": 0.2, "b": 0.2, "c": 2.5}
    tr = simulate(s, [1.0, 1.0, 0.0], P, (0.0, 300.0), dt=0.01)
    orb = orbit_from_trajectory(s, P, tr, mesh=CollocationMesh(40, 4, 1.0))
    st = ContinuationSettings(ds=0.05, ds_max=0.1, max_steps=60, p_max=3.0)
    br = continue_periodic(s, orb, P, "c", st)
    (pd,) = br.find("PD")
    T1 = orbit_at(br, pd).T
    b2 = continue_period_doubled(br, pd, dataclasses.replace(st, p_max=4.0))
    assert b2.records["T"][0] == pytest.approx(2 * T1, rel=1e-4)
    assert np.all(np.diff(b2.p) > 0)
    (pd2,) = b2.find("PD")
    assert pd2.located and pd2.p == pytest.approx(3.837, abs=0.005)
    k = int(np.argmin(np.abs(b2.p - 3.3)))
    o2 = orbit_at(b2, k)
    pv = np.array([0.2, 0.2, b2.p[k]])
    r = solve_ivp(lambda t, x: s.f(x, pv), (0, o2.T), o2.X[0], rtol=1e-12, atol=1e-12,
                  method="DOP853", dense_output=True)  # fmt: skip
    assert np.max(np.abs(r.y[:, -1] - o2.X[0])) < 1e-6
    assert np.max(np.abs(r.sol(o2.T / 2) - o2.X[0])) > 0.1


def _torus(x, p, ops):
    """A Hopf-normal-form cycle (x, y) times a decoupled focus (u, w) with rate p - 1
    and a pitchfork direction s with rate p - 2: multipliers exp(2 pi (p - 1 +- 2.3 i)) and
    exp(2 pi (p - 2)) on the cycle r = 1, s = 0."""
    r2 = x[0] ** 2 + x[1] ** 2
    a = p[0] - 1.0
    return ops.stack([
        x[0] - x[1] - x[0] * r2,
        x[0] + x[1] - x[1] * r2,
        a * x[2] - 2.3 * x[3],
        2.3 * x[2] + a * x[3],
        (p[0] - 2.0) * x[4] - x[4] ** 3,
    ])  # fmt: skip


def test_neimark_sacker_and_branch_point_of_cycles_closed_form():
    """NS at p = 1 (the pair exp(+-4.6 pi i) on the unit circle, angle 0.6 pi) and a
    pitchfork of cycles (BPC) at p = 2, both in closed form."""
    s = System(_torus, ("x", "y", "u", "w", "s"), ("p",))
    t = np.linspace(0, 2 * np.pi, 100)
    X = np.column_stack([np.cos(t), np.sin(t), 0 * t, 0 * t, 0 * t])
    orb = orbit_from_array(s, {"p": 0.5}, t, X, mesh=CollocationMesh(20, 4, 1.0))
    br = continue_periodic(s, orb, {"p": 0.5}, "p", ContinuationSettings(ds=0.05, ds_max=0.1,
                           max_steps=60, p_max=2.5))  # fmt: skip
    (ns,) = br.find("NS")
    assert br.find("ns") == (ns,) and ns.kind is SpecialKind.NEIMARK_SACKER
    assert ns.located and ns.p == pytest.approx(1.0, abs=1e-8)
    assert ns.data["theta"] == pytest.approx(0.6 * np.pi, abs=1e-6)
    bpc = br.find("bp")
    assert [b.label for b in bpc] == ["BPC1"]
    assert bpc[0].p == pytest.approx(2.0, abs=1e-6)
    assert br.n_unstable[0] == 0 and br.n_unstable[-1] == 3


@functools.lru_cache(maxsize=4)
def _pendulum_homoclinic(gamma: float) -> float:
    """I at which the saddle's unstable manifold returns to the saddle one turn later
    (an independent shooting + bisection computation)."""
    return brentq(lambda I: pendulum_loop_returns(I, gamma), 0.3, 0.95, xtol=1e-13)


def test_pendulum_rotation_period_blows_up_at_homoclinic():
    """theta'' + gamma theta' + sin theta = I: the rotation orbit (theta advances 2 pi)
    continued down in I; its period grows without bound at the saddle loop."""
    g = 0.5
    s = System(_pendulum, ("theta", "v"), ("I", "gamma"), periodic={"theta": 2 * math.pi})
    P = {"I": 1.2, "gamma": g}
    tr = simulate(s, [0.0, 2.0], P, (0.0, 60.0), dt=0.01)
    orb = orbit_from_trajectory(s, P, tr, mesh=CollocationMesh(100, 4, 1.0),
                                winding={"theta": 1})  # fmt: skip
    assert orb.X[-1, 0] - orb.X[0, 0] == pytest.approx(2 * math.pi)
    # T = int dtheta / v: the rotation at I = 1.2 against direct simulation
    # on one mesh of 100 intervals (error_tol=None): the end at period_max, and the
    # Liouville check of the multipliers on that mesh (the default adapted mesh is
    # checked in test_periodic_defaults.py)
    br = continue_periodic(s, orb, P, "I", ContinuationSettings(ds=-0.02, ds_max=0.05,
                           max_steps=300, p_min=0.0), period_max=40.0,
                           error_tol=None)  # fmt: skip
    assert br.status == Status.PERIOD_UNBOUNDED
    assert "T=40" in br.message and "I=0.5973" in br.message
    I_hc = _pendulum_homoclinic(g)
    assert br.p[-1] == pytest.approx(I_hc, abs=1e-8)
    lim = period_limit(br)
    assert lim.p_star == pytest.approx(I_hc, abs=1e-8)
    ths = math.pi - math.asin(I_hc)
    lam_u = 0.5 * (-g + math.sqrt(g * g - 4 * math.cos(ths)))
    assert lim.rate == pytest.approx(1 / lam_u, rel=0.05)
    # 2D: the nontrivial multiplier is exp(-gamma T) (Liouville), down to 1e-9 here
    mu = multipliers(br)[:, 0].real
    np.testing.assert_allclose(np.log(mu), -g * br.records["T"], rtol=1e-6)
    assert lim.saddle == pytest.approx(np.array([ths - 2 * math.pi * round((ths - lim.saddle[0])
                                       / (2 * math.pi)), 0.0]), abs=1e-2)  # fmt: skip
    # the limit as the guess of the connection solver: the saddle loop around the
    # cylinder (x_+ = x_- + (2 pi, 0)) is found at I_hc
    res = solve_connection(lim.connection_problem(), (lim.t, lim.x))
    assert res.status == Status.SUCCESS
    assert res.value("I") == pytest.approx(I_hc, abs=1e-8)


@pytest.mark.slow
def test_adaptive_segments_follow_the_period_blow_up_on_a_coarse_mesh():
    """40 intervals: a fixed uniform mesh (``error_tol=None``, AUTO's ``IAD = 0``; the
    default adapts) misses the homoclinic parameter by > 1e-6, segments with an
    equidistributed mesh every 10 steps hit it to 1e-8 (reference: shooting);
    the restart near the connection (fixed-parameter start correction, ill-conditioned
    there) fails and the branch says so."""
    g = 0.5
    s = System(_pendulum, ("theta", "v"), ("I", "gamma"), periodic={"theta": 2 * math.pi})
    P = {"I": 1.2, "gamma": g}
    tr = simulate(s, [0.0, 2.0], P, (0.0, 60.0), dt=0.01)
    orb = orbit_from_trajectory(s, P, tr, mesh=CollocationMesh(40, 4, 1.0), winding={"theta": 1})
    st = ContinuationSettings(ds=-0.02, ds_max=0.05, max_steps=300, p_min=0.0)
    I_hc = _pendulum_homoclinic(g)
    uni = continue_periodic(s, orb, P, "I", st, period_max=40.0, error_tol=None)
    ada = continue_periodic(s, orb, P, "I", st, period_max=40.0, adapt_every=10)
    assert abs(uni.p[-1] - I_hc) > 1e-6
    assert abs(ada.p[-1] - I_hc) < 1e-8
    assert len(ada.problem.problems) > 1
    if ada.status != Status.PERIOD_UNBOUNDED:
        assert "restart after mesh adaptation failed" in ada.message
    # every row's cycle is a solution on its own mesh
    for k in (0, len(ada) // 2, len(ada) - 1):
        prob = problem_at(ada, k)
        # (all equations but the phase condition, whose reference moved on)
        assert np.max(np.abs(prob.residual(ada.x[k], ada.p[k])[:-1])) < 1e-8


def test_rotation_orbit_period_against_simulation():
    """The rotation period at I = 1.2 equals the time a simulation takes for theta to
    advance by 2 pi once settled."""
    s = System(_pendulum, ("theta", "v"), ("I", "gamma"), periodic={"theta": 2 * math.pi})
    P = {"I": 1.2, "gamma": 0.5}
    tr = simulate(s, [0.0, 2.0], P, (0.0, 60.0), dt=0.01)
    orb = orbit_from_trajectory(s, P, tr, mesh=CollocationMesh(40, 4, 1.0), winding={"theta": 1})
    f = lambda t, x: [x[1], 1.2 - 0.5 * x[1] - math.sin(x[0])]  # noqa: E731
    ev = lambda t, x: x[0] - (orb.X[0, 0] + 2 * math.pi)  # noqa: E731
    ev.terminal = True
    r = solve_ivp(f, (0, 50), orb.X[0], events=ev, rtol=1e-12, atol=1e-12, method="DOP853")
    assert orb.T == pytest.approx(float(r.t_events[0][0]), abs=1e-8)


# ------------------------------------------------------------------ input
def test_bad_input():
    s = System(_vdp, ("x", "y"), ("mu",))
    t = np.linspace(0, 6.6, 50)
    x = np.column_stack([2 * np.cos(t), -2 * np.sin(t)])
    with pytest.raises(ValueError, match="winding"):
        orbit_from_array(s, {"mu": 1.0}, t, x, winding={"x": 1})
    with pytest.raises(ValueError, match="`x` must have shape"):
        orbit_from_array(s, {"mu": 1.0}, t, x[:, :1])
    orb = solve_orbit(orbit_from_array(s, {"mu": 1.0}, t, x))
    with pytest.raises(ValueError, match="`free`"):
        continue_periodic(s, orb, {"mu": 1.0}, "nu")
    with pytest.raises(ValueError, match="`period_max`"):
        continue_periodic(s, orb, {"mu": 1.0}, "mu", period_max=-1.0)


def _brusselator(x, p, ops):
    a, b = p[0], p[1]
    return ops.stack([a - (b + 1) * x[0] + x[0] ** 2 * x[1], b * x[0] - x[0] ** 2 * x[1]])


def test_hopf_start_amplitude_law_on_a_moving_equilibrium():
    """Brusselator (equilibrium (a, b/a) moves with b; Hopf at b = 1 + a^2, omega = a):
    the collocated cycles near the Hopf point have T -> 2 pi / a and an amplitude
    following the normal form |z|^2 = -alpha' (b - b_H) / (omega l1) (two independent
    computations: the Lyapunov coefficient and the collocation)."""
    a = 1.0
    s = System(_brusselator, ("x", "y"), ("a", "b"))
    eq = continue_equilibria(s, [a, 1.5 / a], {"a": a, "b": 1.5}, "b", p_min=1.0, p_max=3.0,
                             direction="forward", ds=0.05)  # fmt: skip
    (h,) = eq.find("hopf")
    assert h.p == pytest.approx(1 + a * a, abs=1e-9)
    l1 = first_lyapunov_coefficient(s, h.x, {"a": a, "b": h.p})
    assert l1 < 0  # supercritical
    amp = 1e-3
    orb = periodic_orbit_from_hopf(eq, h.label, amplitude=amp, mesh=CollocationMesh(30, 4, 1.0))
    assert orb.param("b") > h.p  # cycles where the equilibrium is unstable
    assert orb.T == pytest.approx(2 * np.pi / a, rel=1e-4)
    # the corrected cycle's largest distance from the equilibrium is the requested one
    # (to first order: relative O(amplitude))
    x_eq = np.array([a, orb.param("b") / a])
    dist = float(np.max(np.linalg.norm(orb.X - x_eq[None, :], axis=1)))
    assert dist == pytest.approx(amp, rel=2e-2)


def test_user_array_start_and_save_load(tmp_path):
    """A rough circle as the user's guess converges to the Hopf normal form cycle; the
    branch is saved and loaded with its records."""
    s = System(_hopf_nf, ("x", "y"), ("mu",))
    t = np.linspace(0, 2 * np.pi * 1.1, 50)
    x = np.column_stack([0.6 * np.cos(t), 0.6 * np.sin(t)])
    orb = solve_orbit(orbit_from_array(s, {"mu": 0.5}, t, x, mesh=CollocationMesh(20, 4, 1.0)))
    assert orb.T == pytest.approx(2 * np.pi, abs=1e-9)
    assert float(np.max(np.hypot(orb.X[:, 0], orb.X[:, 1]))) == pytest.approx(math.sqrt(0.5))
    br = continue_periodic(s, orb, {"mu": 0.5}, "mu", ContinuationSettings(max_steps=5))
    from continuation import Branch

    back = Branch.load(br.save(tmp_path / "cycles"))
    np.testing.assert_allclose(back.records["T"], br.records["T"])
    np.testing.assert_allclose(back.x, br.x)


@pytest.mark.parametrize("adapt_every", [0, 5])
def test_both_directions_one_branch(adapt_every):
    """direction="both" from a large Bautin cycle: one branch from the backward end to
    the forward end, every row a cycle mu = r^4 - r^2 of its own mesh."""
    s = System(_bautin, ("x", "y"), ("mu", "beta"))
    t = np.linspace(0, 2 * np.pi, 60)
    r0 = math.sqrt((1 + math.sqrt(1 - 4 * 0.2)) / 2)
    guess = orbit_from_array(s, {"mu": -0.2, "beta": 1.0}, t,
                             np.column_stack([r0 * np.cos(t), r0 * np.sin(t)]),
                             mesh=CollocationMesh(20, 4, 1.0))  # fmt: skip
    st = ContinuationSettings(ds=0.02, ds_max=0.05, max_steps=30, p_min=-0.24, p_max=0.5)
    br = continue_periodic(s, guess, guess.params, "mu", st, direction="both",
                           adapt_every=adapt_every)  # fmt: skip
    assert br.p[0] == pytest.approx(-0.24) and br.p[-1] == pytest.approx(0.5)
    assert np.all(np.diff(br.p) > 0) and np.all(br.ds[1:] > 0)
    assert np.any(np.abs(br.p + 0.2) < 1e-12)  # the start row, once
    r = br.records["max_x"]
    np.testing.assert_allclose(br.p, r**4 - r**2, atol=1e-8)
    for k in range(len(br)):
        res = problem_at(br, k).residual(br.x[k], br.p[k])[:-1]
        assert np.max(np.abs(res)) < 1e-8


def test_numpy_only_system():
    """A System without a CasADi trace (NumPy right-hand side, finite-difference
    derivatives) gives the same van der Pol period."""

    def f(x, p):
        return np.array([x[1], p[0] * (1 - x[0] ** 2) * x[1] - x[0]])

    s = System(f, ("x", "y"), ("mu",), backend="numpy")
    assert not s.has_casadi
    tr = simulate(System(_vdp, ("x", "y"), ("mu",)), [2.0, 0.0], {"mu": 1.0}, (0.0, 60.0),
                  dt=0.01)  # fmt: skip
    orb = orbit_from_trajectory(s, {"mu": 1.0}, (tr.t, tr.x), mesh=CollocationMesh(40, 4, 1.0))
    assert orb.T == pytest.approx(VDP_T_MU1, abs=1e-7)
    br = continue_periodic(s, orb, {"mu": 1.0}, "mu", ContinuationSettings(max_steps=3))
    assert br.status == Status.MAX_STEPS and len(br) == 4


@pytest.mark.parametrize("n", [2, 3, 4])
def test_compiled_floquet_kernels(n):
    # the deflation of the trivial multiplier (compiled; Numba is required) on transfer
    # matrices built with a known answer: Phi_j = Q_{j+1} A_j Q_j^T with Q_j orthonormal,
    # first column f_j / |f_j|, and A_j = [[r_j, b_j], [0, C_j]], so that the trivial
    # multiplier is prod r_j and the others are the eigenvalues of C_{N-1} ... C_0
    # (exactly, no coupling to neglect); then the stage solves of the transfer matrices
    # against NumPy's solver
    import importlib

    from continuation.bvp import _condense_jit

    fq = importlib.import_module("continuation.periodic.floquet")  # (the package exports
    # a function of the same name)

    rng = np.random.default_rng(n)
    N = 12
    f_nodes = rng.standard_normal((N + 1, n))
    f_nodes[N] = f_nodes[0]  # (a closed cycle)
    Q = []
    for j in range(N):
        q, _ = np.linalg.qr(np.column_stack([f_nodes[j], rng.standard_normal((n, n - 1))]))
        Q.append(q * np.sign(q[:, 0] @ f_nodes[j]))  # first column +f_j / |f_j|
    Q.append(Q[0])
    r = 1.0 + 0.1 * rng.standard_normal(N)
    C = np.eye(n - 1)[None] + 0.1 * rng.standard_normal((N, n - 1, n - 1))
    Phi = np.empty((N, n, n))
    for j in range(N):
        A = np.zeros((n, n))
        A[0, 0], A[0, 1:], A[1:, 1:] = r[j], rng.standard_normal(n - 1), C[j]
        Phi[j] = Q[j + 1] @ A @ Q[j].T
    prod_C = functools.reduce(lambda acc, c: c @ acc, C, np.eye(n - 1))
    got = fq.floquet(Phi, f_nodes)
    np.testing.assert_allclose(np.sort_complex(got.multipliers),
                               np.sort_complex(np.linalg.eigvals(prod_C)),
                               rtol=1e-10, atol=1e-12)  # fmt: skip
    assert got.trivial == pytest.approx(np.prod(r), rel=1e-12)
    assert got.trivial_error == pytest.approx(abs(np.prod(r) - 1), rel=1e-6)
    K = rng.standard_normal((N, 4 * n, 4 * n)) + 4 * np.eye(4 * n)
    R = rng.standard_normal((N, 4 * n, n))
    X = np.empty_like(R)
    assert _condense_jit.solve_many(K.copy(), R, X)
    np.testing.assert_allclose(X, np.linalg.solve(K, R), rtol=1e-12, atol=1e-13)
    K[3, :, 2] = 0.0  # a singular block is reported, not solved
    assert not _condense_jit.solve_many(K.copy(), R, X)


def _collocation_residual(prob, s, z, p):
    """The periodic collocation equations written out interval by interval (the
    reference of the compiled kernel): ``sum_l D[k,l] X_{j,l} / h_j - T f(X_{j,k+1})``,
    continuity ``sum_l e_l X_{j,l} - x_{j+1}``, periodicity ``x_N - x_0 - shift`` and
    the integral phase condition, in the row order of every collocated orbit
    (``continuation.bvp.layout.OrbitLayout``): the collocation rows of all stages, the
    continuity rows of all intervals, then periodicity and phase."""
    lay = prob.layout
    N, m, n = lay.N, lay.m, lay.n
    D, e, h = lay.mesh.D, lay.mesh.e, lay.mesh.h
    X, T = lay.split(z)
    pv = np.array(prob.params.values)
    pv[prob.params.index(prob.free)] = p
    G = np.zeros(lay.n_unknowns)
    row = 0
    for j in range(N):
        Xj = X[j * (m + 1) : (j + 1) * (m + 1) + 1]
        for k in range(m):
            G[row : row + n] = sum(D[k, l] * Xj[l] for l in range(m + 1)) / h[j] - T * s.f(
                Xj[k + 1], pv
            )
            row += n
    for j in range(N):
        Xj = X[j * (m + 1) : (j + 1) * (m + 1) + 1]
        G[row : row + n] = sum(e[l] * Xj[l] for l in range(m + 1)) - Xj[m + 1]
        row += n
    G[row : row + n] = X[-1] - X[0] - prob._shift
    Xs = X[lay.stage_points]
    ref, dref = prob._slot["ref"], prob._slot["dref"]
    G[row + n] = np.sum(lay.weights[:, None] * (Xs - ref) * dref)
    return G


@pytest.mark.parametrize("case", ["rotation", "rossler"])
def test_compiled_collocation_kernel(case):
    # residual, Jacobian, dG/dp and the blocks of the compiled collocation kernel (Numba
    # is required) at a point off the cycle (every term nonzero): the residual against
    # the equations written out, the derivatives against central differences of it
    # (truncation O(eps^2), round-off O(1e-16 / eps) relative: 1e-6 allows both), the
    # blocks against the layout's B = D/h I - T f_x; a rotation orbit (periodicity shift
    # 2 pi) and the 3-state Rossler cycle
    import continuation.periodic.problem as pp

    if case == "rotation":
        s = System(_pendulum, ("theta", "v"), ("I", "gamma"), periodic={"theta": 2 * math.pi})
        P = {"I": 1.2, "gamma": 0.5}
        tr = simulate(s, [0.0, 2.0], P, (0.0, 60.0), dt=0.01)
        orb = orbit_from_trajectory(s, P, tr, mesh=CollocationMesh(17, 3, 1.0),
                                    winding={"theta": 1})  # fmt: skip
        free = "I"
    else:
        s = System(_rossler, ("x", "y", "z"), ("a", "b", "c"))
        P = {"a": 0.2, "b": 0.2, "c": 2.5}
        tr = simulate(s, [1.0, 1.0, 0.0], P, (0.0, 200.0), dt=0.01)
        orb = orbit_from_trajectory(s, P, tr, mesh=CollocationMesh(23, 4, 1.0))
        free = "c"
    prob = pp.PeriodicOrbitProblem.from_orbit(orb, free)
    z = prob.reference * (1 + 1e-3 * np.sin(np.arange(prob.n_unknowns)))
    p = orb.param(free) + 0.01
    G, J, Gp = prob.linearize(z, p)
    B = prob._slot["cache"][2].copy()
    ref = _collocation_residual(prob, s, z, p)
    scale = np.max(np.abs(ref))
    assert np.max(np.abs(G - ref)) <= 1e-12 * scale
    assert np.max(np.abs(prob.residual(z, p) - ref)) <= 1e-12 * scale
    eps = 1e-6
    rng = np.random.default_rng(3)
    for _ in range(3):
        v = rng.standard_normal(z.size) * np.maximum(np.abs(z), 1.0)
        fd = (prob.residual(z + eps * v, p) - prob.residual(z - eps * v, p)) / (2 * eps)
        assert np.linalg.norm(J @ v - fd) <= 1e-6 * np.linalg.norm(fd)
    fd_p = (prob.residual(z, p + eps) - prob.residual(z, p - eps)) / (2 * eps)
    assert np.linalg.norm(Gp - fd_p) <= 1e-6 * max(np.linalg.norm(fd_p), 1e-12)
    X, T, _, _, Jx, _ = prob._stages(z, p, True)
    np.testing.assert_allclose(B, prob.layout.blocks(X, T, Jx), rtol=1e-14, atol=0)
