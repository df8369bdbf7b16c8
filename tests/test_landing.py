"""Landing orbits: from a given point onto a saddle's stable manifold (continuation.bvp.landing).

References (closed forms):

* ``u' = u - p + y^2``, ``y' = -y``: ``y = c e^{-t}``,
  ``u = p + A e^t - (c^2 / 3) e^{-2t}``; the stable manifold of the saddle ``(p, 0)``
  is ``u = p - y^2 / 3``, so the orbit from ``(s, c)`` lands on it for
  ``p* = s + c^2 / 3``. With ``x(T)`` on the stable eigenspace ``u = p`` (the BVP's end
  condition) ``A = (c^2 / 3) e^{-3T}`` and ``p(T) = s + (c^2 / 3)(1 - e^{-3T})``: the
  truncated problem has a closed form too.
* the same flow on the cylinder, ``u = tan((theta - p) / 2)``:
  ``theta' = sin(theta - p) + y^2 (1 + cos(theta - p))`` (period 2 pi in theta), landing
  on the saddle shifted by one period: ``p* = theta_0 - 2 pi + 2 arctan(c^2 / 3)``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from continuation.bvp.accuracy import ConnectionAccuracy
from continuation.bvp.landing import LandingProblem
from continuation.bvp.landing_solve import continue_landing, landing_at, solve_landing
from continuation.errors import ConvergenceError
from continuation.settings import ContinuationSettings
from continuation.status import Status
from continuation.system import System

C = 1.0
PLAIN = ConnectionAccuracy(estimate=False)


def _rhs(x, p, ops):
    return ops.stack([x[0] - p[0] + x[1] ** 2, -x[1]])


def _rhs_cyl(x, p, ops):
    d = x[0] - p[0]
    return ops.stack([ops.sin(d) + x[1] ** 2 * (1 + ops.cos(d)), -x[1]])


@pytest.fixture(scope="module")
def plane():
    return System(_rhs, ("u", "y"), ("p",))


@pytest.fixture(scope="module")
def cylinder():
    return System(_rhs_cyl, ("theta", "y"), ("p",), periodic={"theta": 2 * math.pi})


def _problem(system, T, s=0.1, **kw):
    return LandingProblem(system, {"p": 0.3}, "p", start=lambda v: [v, C], saddle=[0.3, 0.0],
                          T=T, s=s, start_name="s", **kw)  # fmt: skip


def _zero_guess(T):
    t = np.linspace(0.0, T, 60)
    return t, np.column_stack([np.zeros_like(t), C * np.exp(-t)])


@pytest.mark.parametrize("T", [1.0, 2.5, 6.0])
def test_truncated_problem_matches_its_closed_form(plane, T):
    """Plain solve at fixed T: p(T) = s + c^2 (1 - e^{-3T}) / 3 to 1e-10."""
    r = solve_landing(_problem(plane, T), _zero_guess(T), accuracy=PLAIN)
    assert r.success, r.message
    assert r.value("p") == pytest.approx(0.1 + C**2 / 3 * (1 - math.exp(-3 * T)), abs=1e-10)
    assert np.allclose(r.x[0], [0.1, C])  # the start condition
    assert r.errors is None and math.isnan(r.error("p"))
    # the end distance is free: |y(T)| = c e^{-T} on the eigenspace u = p
    assert r.end_distance == pytest.approx(C * math.exp(-T), rel=1e-6)


def test_estimated_solve_bounds_its_error(plane):
    """With estimates: SUCCESS, true error <= the estimate <= the tolerance."""
    acc = ConnectionAccuracy(rtol=1e-8, atol=1e-10)
    r = solve_landing(_problem(plane, 4.0), _zero_guess(4.0), accuracy=acc)
    assert r.success, r.message
    exact = 0.1 + C**2 / 3
    assert abs(r.value("p") - exact) <= r.error("p")
    assert r.error("p") <= 2 * acc.tolerance(exact)
    assert r.T > 4.0  # T = 4 alone is not enough (error e^{-12} / 3): it was extended


def test_truncation_error_is_reported(plane):
    """No extension allowed: T = 1 gives e^{-3} / 3 error, so TRUNCATION_ERROR."""
    acc = ConnectionAccuracy(max_extensions=0)
    r = solve_landing(_problem(plane, 1.0), _zero_guess(1.0), accuracy=acc)
    assert r.status is Status.TRUNCATION_ERROR
    assert "truncation error of p" in r.message
    with pytest.raises(ConvergenceError):
        solve_landing(_problem(plane, 1.0), _zero_guess(1.0), accuracy=acc, throw=True)


def test_continuation_in_the_start_follows_the_closed_form(plane):
    """PALC in s: every row p = s + c^2 (1 - e^{-3T}) / 3 (linear in s), to 1e-10."""
    r = solve_landing(_problem(plane, 4.0), _zero_guess(4.0), accuracy=PLAIN)
    br = continue_landing(r, ContinuationSettings(p_min=-0.5, p_max=0.9, ds=0.1, ds_max=0.2))
    s = np.asarray(br.p)
    assert br.status is Status.PARAM_BOUND and s[-1] == pytest.approx(0.9)
    p_rows = np.asarray(br.records["p"])
    np.testing.assert_allclose(p_rows, s + C**2 / 3 * (1 - math.exp(-12.0)), atol=1e-10)
    last = landing_at(br, -1)
    assert last.s == pytest.approx(0.9) and last.x[0, 0] == pytest.approx(0.9)


def test_landing_on_the_saddle_one_period_on(cylinder):
    """Periodic state: start one period up, land on the saddle + 2 pi (closed form)."""
    th0, T = 2 * math.pi + 0.2, 10.0
    prob = LandingProblem(cylinder, {"p": 0.5}, "p", start=[th0, C], saddle=[0.5, 0.0],
                          shift={"theta": 2 * math.pi}, T=T)  # fmt: skip
    t = np.linspace(0.0, T, 80)
    guess = (t, np.column_stack([np.full_like(t, th0), C * np.exp(-t)]))
    r = solve_landing(prob, guess, accuracy=ConnectionAccuracy(rtol=1e-9, atol=1e-10))
    assert r.success, r.message
    exact = th0 - 2 * math.pi + 2 * math.atan(C**2 / 3)
    assert abs(r.value("p") - exact) <= max(r.error("p"), 1e-12)
    assert r.x_eq[0] == pytest.approx(exact + 2 * math.pi, abs=1e-8)


def test_bad_input(plane, cylinder):
    with pytest.raises(ValueError, match="`free`"):
        _problem(plane, 2.0).replace(free=("q",))
    none = System(lambda x, p, ops: ops.stack([1 + p[0] + x[0] ** 2, -x[1]]), ("a", "b"), ("p",))
    with pytest.raises(ValueError, match="`saddle`"):  # no equilibrium anywhere
        LandingProblem(none, {"p": 0.3}, "p", start=[0.1, C], saddle=[0.0, 0.0], T=2.0)
    with pytest.raises(ValueError, match="`start"):
        LandingProblem(plane, {"p": 0.3}, "p", start=[0.1, C, 0.0], saddle=[0.3, 0.0], T=2.0)
    with pytest.raises(ValueError, match="`start"):
        LandingProblem(plane, {"p": 0.3}, "p", start=lambda s: [math.nan, 0.0],
                       saddle=[0.3, 0.0], T=2.0)  # fmt: skip
    with pytest.raises(ValueError, match="`T="):
        LandingProblem(plane, {"p": 0.3}, "p", start=[0.1, C], saddle=[0.3, 0.0])
    with pytest.raises(ValueError, match="not periodic"):
        LandingProblem(plane, {"p": 0.3}, "p", start=[0.1, C], saddle=[0.3, 0.0],
                       shift={"u": 1.0}, T=2.0)  # fmt: skip
    with pytest.raises(ValueError, match="whole multiple"):
        LandingProblem(cylinder, {"p": 0.3}, "p", start=[0.1, C], saddle=[0.3, 0.0],
                       shift={"theta": 1.0}, T=2.0)  # fmt: skip
    with pytest.raises(ValueError, match="`s`"):
        _problem(plane, 2.0, s=math.inf)
    # the count: a source (two unstable directions) with one solved parameter
    src = System(lambda x, p, ops: ops.stack([x[0] - p[0], x[1]]), ("a", "b"), ("p",))
    with pytest.raises(ValueError, match="count does not close"):
        LandingProblem(src, {"p": 0.0}, "p", start=[0.1, 0.1], saddle=[0.0, 0.0], T=2.0)
    with pytest.raises(ValueError, match="`problem`"):
        solve_landing("not a problem", _zero_guess(2.0))
    with pytest.raises(ValueError, match="`guess`"):
        solve_landing(_problem(plane, 2.0), "nothing")
    fixed = LandingProblem(plane, {"p": 0.3}, "p", start=[0.1, C], saddle=[0.3, 0.0], T=3.0)
    r = solve_landing(fixed, _zero_guess(3.0), accuracy=PLAIN)
    with pytest.raises(ValueError, match="fixed start"):
        continue_landing(r)
