"""Cycle branches at the default settings of ``continue_periodic``: the mesh adapts to
the error tolerance, and a branch that ends at a homoclinic orbit stops on the side
where its cycles exist (issue 27).

Each check is against an independent reference: periods by scipy's DOP853 at
``rtol = atol = 1e-12`` (stable cycles by simulation, the unstable Lorenz cycle by
shooting with Newton's method on the return map), homoclinic parameters by shooting
the saddle's unstable manifold and bisection (or the published value).
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from helpers import pendulum_loop_returns, vdp_period
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from continuation import ContinuationSettings, Event, Status, System, continue_equilibria, simulate
from continuation.periodic import (
    continue_from_hopf,
    continue_periodic,
    orbit_at,
    orbit_from_trajectory,
)


# ------------------------------------------------------------------ van der Pol
def _vdp(x, p, ops):
    return ops.stack([x[1], p[0] * (1 - x[0] ** 2) * x[1] - x[0]])


def test_van_der_pol_periods_at_the_default_settings():
    """From mu = 1 to 10 at the defaults (the start cycle on the default 40 intervals):
    the periods at mu = 5 and 10 within 1e-6 of the simulation (a fixed mesh was
    2.5e-3 off at mu = 5), every row within the error tolerance, an ok status."""
    s = System(_vdp, ("x", "y"), ("mu",))
    tr = simulate(s, [2.0, 0.0], {"mu": 1.0}, (0.0, 60.0), dt=0.01)
    orb = orbit_from_trajectory(s, {"mu": 1.0}, tr)
    uz = [Event("UZ5", param_value=5.0), Event("UZ10", param_value=10.0)]
    br = continue_periodic(s, orb, {"mu": 1.0}, "mu", ContinuationSettings(p_max=10.0), events=uz)
    assert br.status == Status.PARAM_BOUND, br.message
    assert np.all(br.records["error"] <= 1.01e-6)
    got = {sp.label: orbit_at(br, sp).T for sp in br.special_points if sp.label in ("UZ5", "UZ10")}
    ref10 = vdp_period(10.0)
    assert ref10 == pytest.approx(19.0784, abs=1e-4)  # tabulated: T(10) = 19.0784
    assert got["UZ5"] == pytest.approx(vdp_period(5.0), abs=1e-6)
    assert got["UZ10"] == pytest.approx(ref10, abs=1e-6)


# ------------------------------------------------------------------ rotating pendulum
def _pendulum(x, p, ops):
    return ops.stack([x[1], p[0] - p[1] * x[1] - ops.sin(x[0])])


@functools.lru_cache(maxsize=4)
def _homoclinic_I(gamma: float) -> float:
    return brentq(lambda I: pendulum_loop_returns(I, gamma), 0.3, 0.95, xtol=1e-13)


@functools.lru_cache(maxsize=4)
def _homoclinic_gamma(I: float) -> float:
    return brentq(lambda g: -pendulum_loop_returns(I, g), 0.05, 1.5, xtol=1e-13)


def _rotation_period(I: float, gamma: float, x0) -> float:
    """Time for theta to advance by 2 pi, after 8 turns from ``x0`` (DOP853, 1e-12)."""
    f = lambda t, x: [x[1], I - gamma * x[1] - math.sin(x[0])]  # noqa: E731
    times, x = [], np.asarray(x0, dtype=float)
    t0 = 0.0
    for _ in range(9):
        target = x[0] + 2 * math.pi
        ev = lambda t, y, target=target: y[0] - target  # noqa: E731
        ev.terminal = True
        r = solve_ivp(f, (t0, t0 + 1e4), x, events=ev, rtol=1e-12, atol=1e-12, method="DOP853")
        times.append(float(r.t_events[0][0]) - t0)
        t0, x = float(r.t_events[0][0]), r.y_events[0][0]
    return times[-1]


@pytest.mark.parametrize("free", ["I", "gamma"])
def test_rotating_pendulum_stops_before_its_homoclinic_end(free):
    """theta'' + gamma theta' + sin theta = I, the rotation continued towards the saddle
    loop (down in the torque I at gamma = 0.5, up in the damping gamma at I = 0.8), at
    the defaults and without period_max: the branch ends with PERIOD_UNBOUNDED, every
    row on the side where rotations exist, and the period 1e-4 from the end is right to
    1e-6 (on a fixed mesh the rows went on 9e-7 past the end with a finite period)."""
    s = System(_pendulum, ("theta", "v"), ("I", "gamma"), periodic={"theta": 2 * math.pi})
    if free == "I":
        P, ds, end = {"I": 1.2, "gamma": 0.5}, -0.02, _homoclinic_I(0.5)
    else:
        P, ds, end = {"I": 0.8, "gamma": 0.3}, 0.02, _homoclinic_gamma(0.8)
    side = -math.copysign(1.0, ds)  # rotations exist on this side of the end
    tr = simulate(s, [0.0, 2.0], P, (0.0, 60.0), dt=0.01)
    orb = orbit_from_trajectory(s, P, tr, winding={"theta": 1})
    near = end + side * 1e-4
    st = ContinuationSettings(ds=ds, ds_max=0.05, max_steps=400, p_min=0.0, p_max=2.0)
    br = continue_periodic(s, orb, P, free, st, events=[Event("NEAR", param_value=near)])
    assert br.status == Status.PERIOD_UNBOUNDED, br.message
    assert np.all(side * (br.p - end) > 0), np.min(side * (br.p - end))
    assert side * (br.p[-1] - end) < 1e-6  # (it does get close)
    assert np.all(br.records["error"] <= 1.01e-6)
    (sp,) = [q for q in br.special_points if q.label == "NEAR"]
    cyc = orbit_at(br, sp)
    I, gamma = (near, P["gamma"]) if free == "I" else (P["I"], near)
    assert cyc.T == pytest.approx(_rotation_period(I, gamma, cyc.X[0]), abs=1e-6)


# ------------------------------------------------------------------ Lorenz
SIGMA, B = 10.0, 8.0 / 3.0
R_HOM = 13.9265574  # Doedel, Krauskopf & Osinga 2006; Sparrow 1982 (13.926)


def _lorenz(x, p, ops):
    return ops.stack(
        [SIGMA * (x[1] - x[0]), p[0] * x[0] - x[1] - x[0] * x[2], x[0] * x[1] - B * x[2]]
    )


def _shooting_period(r: float, x0, T0: float) -> float:
    """Period of the (unstable) cycle through ``x0`` by Newton's method on
    ``phi_T(x) - x = 0`` with x fixed in its first component (variational equations by
    DOP853 at 1e-12)."""

    def f(x):
        return np.array(
            [SIGMA * (x[1] - x[0]), r * x[0] - x[1] - x[0] * x[2], x[0] * x[1] - B * x[2]]
        )

    def jac(x):
        return np.array([[-SIGMA, SIGMA, 0.0], [r - x[2], -1.0, -x[0]], [x[1], x[0], -B]])

    def flow(x, T):
        def rhs(t, y):
            X, Y = y[:3], y[3:].reshape(3, 3)
            return np.concatenate([f(X), (jac(X) @ Y).ravel()])

        y = solve_ivp(rhs, (0, T), np.concatenate([x, np.eye(3).ravel()]), method="DOP853",
                      rtol=1e-12, atol=1e-12).y[:, -1]  # fmt: skip
        return y[:3], y[3:].reshape(3, 3)

    x, T = np.array(x0, dtype=float), float(T0)
    for _ in range(12):
        xT, M = flow(x, T)
        A = np.column_stack([(M - np.eye(3))[:, 1:], f(xT)])
        d = np.linalg.solve(A, -(xT - x))
        x[1:] += d[:2]
        T += d[2]
        if abs(d[2]) < 1e-13 * T:
            break
    return T


def test_unstable_lorenz_cycle_near_its_homoclinic_end():
    """Cycles born at the subcritical Hopf point of C+ continued down in r at the
    defaults: PERIOD_UNBOUNDED at the homoclinic explosion (r_hom = 13.9265574), no row
    below it, and the period of the unstable cycle 0.01 above r_hom within 1e-5 of
    shooting (the fixed mesh's was 1.1e-4 off)."""
    s = System(_lorenz, ("x", "y", "z"), ("r",))
    c = math.sqrt(B * 19.0)
    eq = continue_equilibria(s, [c, c, 19.0], {"r": 20.0}, "r", p_min=10.0, p_max=30.0,
                             ds=0.1, ds_max=0.5)  # fmt: skip
    near = R_HOM + 0.01
    st = ContinuationSettings(p_min=12.0, p_max=30.0, ds=0.05, ds_max=0.3, max_steps=400)
    br = continue_from_hopf(eq, 0, st, events=[Event("NEAR", param_value=near)])
    assert br.status == Status.PERIOD_UNBOUNDED, br.message
    assert np.all(br.p > R_HOM - 1e-7)
    assert br.p[-1] == pytest.approx(R_HOM, abs=1e-6)
    (sp,) = [q for q in br.special_points if q.label == "NEAR"]
    cyc = orbit_at(br, sp)
    assert cyc.T == pytest.approx(_shooting_period(near, cyc.X[0], cyc.T), abs=1e-5)
