r"""The return map's Jacobian from the variational equations (``jacobian="variational"``).

References (closed forms)
-------------------------
* Hopf normal form with a decoupled or one-way coupled stable state,
  ``x' = mu x - w y - x r^2``, ``y' = w x + mu y - y r^2``, ``z' = -lam z + c x (1 + y)``:
  the limit cycle ``r = sqrt(mu)`` has period ``T = 2 pi / w``; the Jacobian along
  it is block triangular (``z`` does not act on ``x, y``), so the nontrivial Floquet
  multipliers are ``exp(-2 mu T)`` (the radial equation ``r' = mu r - r^3``
  linearised at ``sqrt(mu)``) and ``exp(-lam T)``, for any section.
* Driven damped pendulum ``theta'' = F - g theta' - sin(theta)`` (a rotation orbit):
  by Liouville's formula the product of the two Floquet multipliers is
  ``exp(int_0^T div f dt) = exp(-g T)``, and the trivial one is 1, so the
  nontrivial one is ``exp(-g T)``.

Tolerances: the multipliers are computed from the state transition matrix integrated
by CVODES at ``map_rtol = 1e-11``, ``map_atol = 1e-13`` (module notes of
:mod:`continuation.dynamics.shooting`): global errors of order 1e-10 times the
growth of ``Phi``; the tests ask for 1e-8 (the forward-difference path only gets
about 1e-5 on the same problems).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from continuation.dynamics.shooting import ShootingSettings, shoot_orbit
from continuation.status import Status
from continuation.system import System


def _hopf_z(x, p, ops):
    mu, w, lam, c = p[0], p[1], p[2], p[3]
    r2 = x[0] ** 2 + x[1] ** 2
    return ops.stack(
        [
            mu * x[0] - w * x[1] - x[0] * r2,
            w * x[0] + mu * x[1] - x[1] * r2,
            -lam * x[2] + c * x[0] * (1.0 + x[1]),
        ]
    )


def _pendulum(x, p, ops):
    g, F = p[0], p[1]
    return ops.stack([x[1], F - g * x[1] - ops.sin(x[0])])


HOPF_Z = System(_hopf_z, ("x", "y", "z"), ("mu", "w", "lam", "c"))
PEND = System(_pendulum, ("theta", "omega"), ("g", "F"), periodic={"theta": 2 * np.pi})


def _expected(mu: float, w: float, lam: float) -> np.ndarray:
    T = 2 * math.pi / w
    return np.sort([math.exp(-2 * mu * T), math.exp(-lam * T)])


@pytest.mark.parametrize(
    ("mu", "w", "lam", "c", "state", "section", "direction"),
    [
        (1.0, 1.0, 0.5, 0.0, "y", 0.0, 1),  # multipliers exp(-4 pi), exp(-pi)
        (0.1, 1.0, 0.05, 0.0, "y", 0.0, -1),  # 0.285, 0.730, section crossed downwards
        (0.1, 1.0, 0.05, 0.7, "x", 0.2, 1),  # z forced by x: f_z != 0 on the section
        (0.3, 2.0, 0.4, 1.0, "z", 0.0, 1),  # the section on the forced state itself
    ],
)
def test_hopf_multipliers_closed_form(mu, w, lam, c, state, section, direction):
    params = [mu, w, lam, c]
    o = shoot_orbit(HOPF_Z, params, [0.5, 0.1, 0.0], state=state, section=section,
                    direction=direction)  # fmt: skip
    assert o.status is Status.SUCCESS, o.message
    assert o.jacobian == "variational"
    assert o.period == pytest.approx(2 * math.pi / w, rel=1e-8)
    mult = np.sort_complex(o.multipliers)
    np.testing.assert_allclose(mult.imag, 0.0, atol=1e-8)
    np.testing.assert_allclose(mult.real, _expected(mu, w, lam), rtol=1e-6, atol=1e-8)


def test_hopf_smallest_multiplier_relative_accuracy():
    """exp(-4 pi) = 3.5e-6 to 1e-4 relative: the variational path resolves what the
    forward differences (noise ~1e-9 / fd_step) cannot."""
    o = shoot_orbit(HOPF_Z, [1.0, 1.0, 0.5, 0.0], [0.5, 0.1, 0.0], state="y", direction=1)
    small = np.min(np.abs(o.multipliers))
    assert small == pytest.approx(math.exp(-4 * math.pi), rel=1e-4)


def test_pendulum_rotation_multiplier_liouville():
    g, F = 0.5, 1.0
    o = shoot_orbit(PEND, [g, F], [0.0, 1.0], state="theta", section=0.0)
    assert o.status is Status.SUCCESS, o.message
    assert o.shift == 1 and o.jacobian == "variational"
    assert o.multipliers[0] == pytest.approx(math.exp(-g * o.period), abs=1e-8)
    # the section level does not change the multiplier
    o2 = shoot_orbit(PEND, [g, F], [0.0, 1.0], state="theta", section=2.0)
    assert o2.multipliers[0] == pytest.approx(o.multipliers[0], abs=1e-8)
    assert o2.period == pytest.approx(o.period, rel=1e-9)


def test_fd_path_and_variational_agree_and_are_labelled():
    params, guess = [0.1, 1.0, 0.05, 0.7], [0.5, 0.1, 0.0]
    var = shoot_orbit(HOPF_Z, params, guess, state="y", direction=1)
    fd = shoot_orbit(HOPF_Z, params, guess, state="y", direction=1,
                     settings=ShootingSettings(jacobian="fd"))  # fmt: skip
    assert var.jacobian == "variational" and fd.jacobian == "fd"
    assert var.to_json()["jacobian"] == "variational"
    # the same orbit: Newton converged to the shooting tolerance with either Jacobian
    assert fd.period == pytest.approx(var.period, rel=1e-9)
    np.testing.assert_allclose(fd.x_section, var.x_section, atol=1e-8)
    # forward differences: error O(fd_step) + noise / fd_step, about 1e-5 here
    np.testing.assert_allclose(np.sort_complex(fd.multipliers), np.sort_complex(var.multipliers),
                               atol=1e-5)  # fmt: skip
    exact = _expected(0.1, 1.0, 0.05)
    assert np.max(np.abs(np.sort(var.multipliers.real) - exact)) < 1e-8


def test_numpy_only_system_uses_forward_differences():
    def rhs(x, p):
        r2 = x[0] ** 2 + x[1] ** 2
        return np.array([p[0] * x[0] - x[1] - x[0] * r2, x[0] + p[0] * x[1] - x[1] * r2])

    sys_np = System(rhs, ("x", "y"), ("mu",), backend="numpy")
    o = shoot_orbit(sys_np, [0.5], [0.3, 0.0], state="y", direction=1)
    assert o.status is Status.SUCCESS, o.message
    assert o.jacobian == "fd"
    assert abs(o.multipliers[0]) == pytest.approx(math.exp(-2 * 0.5 * o.period), abs=1e-5)
    with pytest.raises(ValueError, match="jacobian"):
        shoot_orbit(sys_np, [0.5], [0.3, 0.0], state="y", direction=1,
                    settings=ShootingSettings(jacobian="variational"))  # fmt: skip


def test_jacobian_setting_validated():
    with pytest.raises(ValueError, match="`jacobian`"):
        ShootingSettings(jacobian="exact")
    assert ShootingSettings().jacobian == "auto"
    assert ShootingSettings().fd_step == 1e-6  # kept for the forward-difference path
