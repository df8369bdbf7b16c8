"""The engine's return-map periodic-orbit solver (:mod:`continuation.dynamics.shooting`).

References
----------
* Hopf normal form ``x' = mu x - w y - x r^2``, ``y' = w x + mu y - y r^2``: the limit
  cycle ``r = sqrt(mu)`` has period ``2 pi / w`` and nontrivial Floquet multiplier
  ``exp(-2 mu T)`` (the radial equation ``r' = mu r - r^3`` linearised at
  ``sqrt(mu)``); an oscillation, sectioned at ``y = 0`` crossed upwards.
* Driven damped pendulum ``theta'' = F - g theta' - sin(theta)`` with ``F`` large
  enough: a rotation orbit (``theta`` advances by ``2 pi`` per period), checked
  against an independent SciPy DOP853 integration of the return and the power
  balance ``2 pi F = g int_0^T omega^2 dt``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from continuation.dynamics.shooting import ShootingSettings, shoot_orbit
from continuation.status import Status
from continuation.system import System


def _hopf(x, p, ops):
    mu, w = p[0], p[1]
    r2 = x[0] ** 2 + x[1] ** 2
    return ops.stack([mu * x[0] - w * x[1] - x[0] * r2, w * x[0] + mu * x[1] - x[1] * r2])


def _pendulum(x, p, ops):
    g, F = p[0], p[1]
    return ops.stack([x[1], F - g * x[1] - ops.sin(x[0])])


HOPF = System(_hopf, ("x", "y"), ("mu", "w"))
PEND = System(_pendulum, ("theta", "omega"), ("g", "F"), periodic={"theta": 2 * np.pi})


def test_hopf_limit_cycle_closed_form():
    mu, w = 0.5, 2.0
    o = shoot_orbit(HOPF, [mu, w], [0.3, 0.0], state="y", section=0.0, direction=1)
    assert o.status is Status.SUCCESS, o.message
    assert o.shift == 0 and o.direction == 1
    assert o.x_section[0] == pytest.approx(math.sqrt(mu), abs=1e-8)
    assert o.x_section[1] == 0.0
    assert o.period == pytest.approx(2 * math.pi / w, rel=1e-8)
    assert o.closure < 1e-9
    assert o.attracting
    # the return map's Jacobian (variational equations by default; forward differences
    # for a NumPy-only system, error O(fd_step)): within the forward differences' bound
    assert abs(o.multipliers[0]) == pytest.approx(math.exp(-2 * mu * o.period), abs=1e-5)
    # state_at: the crossing of x = 0 (downwards in x: y > 0 there) is (0, sqrt(mu))
    # at a quarter period; here the section state is y, so ask for the level y = y0
    x = o.state_at(0.5 * math.sqrt(mu))
    assert x[1] == 0.5 * math.sqrt(mu)
    assert math.hypot(x[0], x[1]) == pytest.approx(math.sqrt(mu), abs=1e-7)
    # a level asked again is the state found the first time (kept, not re-integrated),
    # and changing a returned array does not change what is kept
    x[0] = 99.0
    again = o.state_at(0.5 * math.sqrt(mu))
    assert math.hypot(again[0], again[1]) == pytest.approx(math.sqrt(mu), abs=1e-7)
    fresh = dataclasses.replace(o).state_at(0.5 * math.sqrt(mu))  # a copy: found anew
    np.testing.assert_array_equal(again, fresh)


def test_pendulum_rotation_orbit_against_scipy_and_power_balance():
    g, F = 0.5, 1.0
    o = shoot_orbit(PEND, [g, F], [0.0, 1.0], state="theta", section=0.0)
    assert o.status is Status.SUCCESS, o.message
    assert o.shift == 1 and o.direction == 1  # theta advances by one period per return

    def rhs(t, z):
        th, om, _ = z
        return [om, F - g * om - math.sin(th), om * om]

    def back(t, z):
        return z[0] - 2 * math.pi

    back.terminal, back.direction = True, 1
    sol = solve_ivp(
        rhs, (0.0, 10 * o.period), [*o.x_section, 0.0], method="DOP853", rtol=1e-12,
        atol=1e-12, events=back,
    )  # fmt: skip
    T = float(sol.t_events[0][0])
    z = sol.y_events[0][0]
    assert T == pytest.approx(o.period, rel=1e-7)
    assert z[1] == pytest.approx(o.x_section[1], abs=1e-7)  # closes in omega
    assert 2 * math.pi * F == pytest.approx(g * z[2], rel=1e-7)  # power balance


def test_bad_input():
    with pytest.raises(ValueError, match="direction"):  # y is no angle: no rotation
        shoot_orbit(HOPF, [0.5, 2.0], [0.3, 0.0], state="y")
    with pytest.raises(ValueError, match="state"):
        shoot_orbit(HOPF, [0.5, 2.0], [0.3, 0.0], state="z")
    with pytest.raises(ValueError, match="direction"):
        shoot_orbit(HOPF, [0.5, 2.0], [0.3, 0.0], state="y", direction=2)
    with pytest.raises(ValueError, match="scale"):
        shoot_orbit(HOPF, [0.5, 2.0], [0.3, 0.0], state="y", scale=[1.0, -1.0])
    with pytest.raises(ValueError, match="max_newton"):
        ShootingSettings(max_newton=0)
    with pytest.raises(ValueError, match="return_tol"):
        ShootingSettings(return_tol=-1.0)
