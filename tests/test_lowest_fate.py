"""The lowest parameter with a target fate (continuation.dynamics.lowest_fate).

References:

* synthetic fate functions with known windows (the scan's resolution claims);
* a textbook system where the homoclinic bifurcation is NOT the boundary of the
  escape ("capsize") basin: the torque-driven damped pendulum
  ``theta'' + alpha theta' + sin(theta) = beta`` (Andronov, Vitt & Khaikin 1966, Ch. VII;
  Strogatz 1994, Sec. 8.5) with a slaved state ``z' = (theta' - z) / tau``, a low-pass
  filter of the speed, and "capsize" when ``z`` passes ``z_c``. The upper unstable
  branch of the saddle falls back to the hanging equilibrium below the homoclinic
  bifurcation ``beta_h`` (0.5974 at alpha = 0.5) and runs onto the rotation cycle
  above it; the cycle's own maximum of ``z`` grows with ``beta`` and passes ``z_c`` at
  ``beta_c``, computed independently by a settled SciPy DOP853 integration and Brent's
  method. So the branch first capsizes at ``beta_c``, well above the connection;
* a 1-cycle whose Poincare return has a negative multiplier must not be reported as a
  2-cycle (the returns alternate while converging).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from continuation.dynamics import (
    FateClassifier,
    PoincareSection,
    SimEvent,
    bisect_fate,
    manifold_fate_function,
)
from continuation.dynamics.lowest_fate import lowest_fate
from continuation.status import Status
from continuation.system import System

TAU, ALPHA, Z_C = 2.0, 0.5, 1.5


def _pendulum_z(x, p, ops):
    a, b = p[0], p[1]
    return ops.stack([x[1], b - ops.sin(x[0]) - a * x[1], (x[1] - x[2]) / TAU])


PZ = System(_pendulum_z, ("theta", "y", "z"), ("alpha", "beta"), periodic={"theta": 2 * np.pi})


# ----------------------------------------------------------------------- synthetic
def _windows(p: float) -> str:
    return "capsize" if 0.31 <= p <= 0.33 or p >= 0.5 else "ok"


def test_lowest_fate_finds_the_first_window_not_the_last_switch():
    res = lowest_fate(_windows, 0.0, 1.0, is_target=lambda s: s == "capsize", step=0.005,
                      coarse_step=0.05, tol=1e-6)  # fmt: skip
    assert res.status is Status.SUCCESS
    assert abs(res.p - 0.31) <= res.error + 1e-12 and res.error <= 5e-7
    assert res.bracket[0] < 0.31 <= res.bracket[1]


def test_a_window_between_two_plain_fates_is_skipped_as_documented():
    """Plain fates at both ends of a coarse interval: the window inside is not seen."""
    res = lowest_fate(_windows, 0.0, 1.0, is_target=lambda s: s == "capsize",
                      is_plain=lambda s: s == "ok", step=0.005, coarse_step=0.1,
                      tol=1e-6)  # fmt: skip
    assert abs(res.p - 0.5) <= res.error + 1e-12


def test_undecided_below_is_reported_and_not_success():
    def fate(p: float) -> str | None:
        return None if abs(p - 0.2) < 1e-9 else _windows(p)

    res = lowest_fate(fate, 0.0, 1.0, is_target=lambda s: s == "capsize", step=0.05,
                      coarse_step=0.1, tol=1e-4)  # fmt: skip
    assert res.status is Status.UNDECIDED and res.undecided_below == (0.2,)
    none = lowest_fate(lambda p: "ok", 0.0, 1.0, is_target=lambda s: s == "capsize",
                       step=0.1, tol=1e-3)  # fmt: skip
    assert none.status is Status.NO_BRACKET and math.isnan(none.p)


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"lo": 1.0, "hi": 0.0}, "lo"), ({"tol": 0.2}, "tol"), ({"step": math.nan}, "step")],
)
def test_bad_arguments_are_named(kw, match):
    args = {"lo": 0.0, "hi": 1.0, "step": 0.1, "tol": 1e-3} | kw
    with pytest.raises(ValueError, match=match):
        lowest_fate(_windows, args.pop("lo"), args.pop("hi"), is_target=bool, **args)


# ----------------------------------------------------------------------- textbook system
def _cycle_max_z(beta: float) -> float:
    """max z on the rotation cycle, by a settled DOP853 integration (independent)."""

    def f(t, x):
        return [x[1], beta - math.sin(x[0]) - ALPHA * x[1], (x[1] - x[2]) / TAU]

    sol = solve_ivp(f, (0.0, 600.0), [0.0, 3.0, 2.0], method="DOP853", rtol=1e-12,
                    atol=1e-12, dense_output=True)  # fmt: skip
    t = np.linspace(500.0, 600.0, 400_001)
    return float(sol.sol(t)[2].max())


def _fate_function():
    b0 = 0.3
    return manifold_fate_function(
        PZ, [ALPHA, b0], "beta", [math.pi - math.asin(b0), 0.0, 0.0], branch=1,
        equilibria={"hanging": [math.asin(b0), 0.0, 0.0]},
        events=[SimEvent("capsize", lambda t, x: x[2] - Z_C, terminal=True, direction=1)],
        t_max=400.0, orient="theta", tol=1e-10, rtol=1e-11, atol=1e-12,
    )  # fmt: skip


def test_the_homoclinic_bifurcation_is_not_the_capsize_boundary():
    fate_at = _fate_function()
    # the connection: the branch's fate switches from the hanging equilibrium to the cycle
    het = bisect_fate(lambda b: fate_at(b).label.split("@")[0], 0.4, 0.65, tol=2e-6)
    assert het.status is Status.SUCCESS
    assert abs(het.p_critical - 0.597383) < 1e-5  # beta_h at alpha = 0.5
    # the lowest capsize: where the rotation cycle itself passes z_c
    res = lowest_fate(lambda b: fate_at(b).label, 0.4, 0.9,
                      is_target=lambda s: s == "event:capsize",
                      is_plain=lambda s: s != "event:capsize", step=0.01, coarse_step=0.05,
                      tol=2e-7)  # fmt: skip
    beta_c = brentq(lambda b: _cycle_max_z(b) - Z_C, 0.65, 0.8, xtol=1e-10)
    assert res.status is Status.SUCCESS
    # bound: the bracket, plus the fate classifier's convergence tolerance (1e-10 in the
    # states) over d(max z)/d(beta) ~ 2, plus the reference's 1e-10
    assert abs(res.p - beta_c) <= res.error + 1e-7
    assert res.p - het.p_critical > 0.1  # the connection is far from the boundary


def test_a_one_cycle_with_a_negative_multiplier_is_not_a_two_cycle():
    """theta' = 1 on the circle; (a, b) rotate by half a turn per revolution while
    contracting: the return map is -exp(-sigma 2 pi) (a, b), a 1-cycle at a = b = 0 whose
    returns alternate in sign."""

    def f(x, p, ops):
        s = p[0]
        return ops.stack([1.0 + 0 * x[0], -s * x[1] - 0.5 * x[2], -s * x[2] + 0.5 * x[1]])

    sys_ = System(f, ("theta", "a", "b"), ("sigma",), periodic={"theta": 2 * np.pi})
    clf = FateClassifier(sys_, [0.02], poincare=PoincareSection("theta", 0.0, direction=1),
                         tol=1e-6, t_max=2000.0)  # fmt: skip
    fate = clf.classify(np.array([0.1, 0.5, 0.0]))
    assert fate.kind.name == "PERIODIC"
    assert fate.multiplicity == 1
    assert abs(fate.period - 2 * math.pi) < 1e-6
