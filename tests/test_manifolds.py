"""Tests of continuation.dynamics.manifolds against closed-form unstable manifolds."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline

from continuation.dynamics import (
    FateClassifier,
    SimEvent,
    oriented_unstable_direction,
    unstable_manifold,
)
from continuation.status import Status
from continuation.system import System


def _quadratic(x, p, ops):
    # x' = x, y' = -y + x^2: W^u(0) is the parabola y = x^2 / 3 exactly
    return ops.stack([x[0], -x[1] + x[0] ** 2])


def _pendulum(x, p, ops):
    return ops.stack([x[1], -ops.sin(x[0]) - p[0] * x[1]])


QUAD = System(_quadratic, ("x", "y"), ())
PEND = System(_pendulum, ("theta", "omega"), ("gamma",), periodic={"theta": 2 * np.pi})
OUT = SimEvent("out", lambda t, x: abs(x[0]) - 2.0, terminal=True, direction=1)


def test_parabola_manifold_closed_form():
    res = unstable_manifold(QUAD, [], [0.0, 0.0], t_max=30.0, events=[OUT])
    assert res.eigenvalue == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(res.eigenvector, [1.0, 0.0], atol=1e-12)
    assert res.status is Status.SUCCESS
    for br in res.branches:
        tr = br.trajectory
        assert tr.status is Status.EVENT and tr.terminal_event == "out"
        assert np.sign(tr.x[-1, 0]) == br.sign  # + branch goes to x > 0
        # on the manifold y = x^2/3 up to O(eps^2) and the integration error
        assert np.max(np.abs(tr.x[:, 1] - tr.x[:, 0] ** 2 / 3)) < 1e-8
        np.testing.assert_allclose(tr.x[0], br.sign * 1e-6 * res.eigenvector, atol=1e-15)


def test_undamped_pendulum_separatrix():
    # theta'' = -sin(theta): W^u of the upper saddle is the separatrix of energy 1,
    # theta(t) = pi + 4 atan(exp(t - t0)) on the + branch, ending at the saddle + 2 pi.
    # The branch returns to within ~2 sqrt(delta) of the saddle, delta its integration
    # error transverse to the stable manifold: tight tolerances resolve it to 1e-4.
    clf = FateClassifier(
        PEND,
        [0.0],
        equilibria={"up": [np.pi, 0.0]},
        t_max=40.0,
        tol=1e-4,
        rtol=1e-12,
        atol=1e-14,
    )
    res = unstable_manifold(PEND, [0.0], [np.pi, 0.0], classify=clf, eps=1e-7)
    assert res.eigenvalue == pytest.approx(1.0, abs=1e-10)
    plus, minus = res.plus, res.minus
    assert plus.fate.label == "saddle:up@+1"  # homoclinic on the cylinder
    assert minus.fate.label == "saddle:up@-1"
    for br in res.branches:
        th, om = br.trajectory.x.T
        energy = 0.5 * om**2 - np.cos(th)
        assert np.max(np.abs(energy - 1.0)) < 1e-8
    # time-shift-free check of the time parameterisation: theta - pi = 4 atan(exp(t - t0))
    # gives the travel time between theta = 2 pi - 1 and 2 pi + 1 in closed form
    evs = [SimEvent(f"s{k}", lambda t, x, k=k: x[0] - (2 * np.pi + k)) for k in (-1, 1)]
    res2 = unstable_manifold(PEND, [0.0], [np.pi, 0.0], eps=1e-7, t_max=25.0, events=evs)
    tr = res2.plus.trajectory
    travel = tr.events["s1"].t[0] - tr.events["s-1"].t[0]
    exact = np.log(np.tan((np.pi + 1) / 4)) - np.log(np.tan((np.pi - 1) / 4))
    assert travel == pytest.approx(exact, abs=1e-8)


def _monotone_arc(tr, system, p):
    """theta, omega and d omega / d theta on the first arc where theta is monotone."""
    th, om = tr.x.T
    stop = np.flatnonzero(np.sign(om) != np.sign(om[1]))
    k = stop[0] if stop.size else th.size
    f = np.array([system.f(x, p) for x in tr.x[1:k]])
    return th[1:k], om[1:k], f[:, 1] / f[:, 0]


def test_result_does_not_depend_on_eps():
    # damped pendulum: the same fates for eps = 1e-6 and 1e-7, and the same curve:
    # omega(theta) of the two branches agree on their first monotone arc. (At equal
    # times they differ by a time shift ln(10)/lambda_u, uncertain by the integration
    # error along the manifold, which the unstable direction amplifies.)
    kw = dict(equilibria={"down": [0.0, 0.0], "up": [np.pi, 0.0]}, t_max=200.0)
    clf = FateClassifier(PEND, [0.5], **kw)
    r6 = unstable_manifold(PEND, [0.5], [np.pi, 0.0], classify=clf, eps=1e-6)
    r7 = unstable_manifold(PEND, [0.5], [np.pi, 0.0], classify=clf, eps=1e-7)
    assert [f.label for f in r6.fates] == [f.label for f in r7.fates]
    assert [f.label for f in r6.fates] == ["equilibrium:down@+1", "equilibrium:down"]
    p = np.array([0.5])
    for sgn in (1, -1):
        th6, om6, s6 = _monotone_arc(r6.branch(sgn).trajectory, PEND, p)
        th7, om7, s7 = _monotone_arc(r7.branch(sgn).trajectory, PEND, p)
        order = np.argsort(th7)
        curve7 = CubicHermiteSpline(th7[order], om7[order], s7[order])
        # away from the turning point, where omega(theta) has an infinite slope
        inside = (th6 > th7.min()) & (th6 < th7.max()) & (np.abs(om6) > 0.3)
        assert inside.sum() > 50
        assert np.max(np.abs(om6[inside] - curve7(th6[inside]))) < 1e-7


def test_orientation_convention():
    # the first periodic state's component is positive; `orient` overrides it
    res = unstable_manifold(PEND, [0.5], [np.pi, 0.0], t_max=1.0)
    assert res.eigenvector[0] > 0
    assert np.linalg.norm(res.eigenvector) == pytest.approx(1.0)
    J = PEND.jacobian(np.array([np.pi, 0.0]), np.array([0.5]))
    lam, v, _ = oriented_unstable_direction(PEND, J, orient="omega")
    assert v[1] > 0 and lam == pytest.approx((-0.5 + np.sqrt(0.25 + 4)) / 2)
    lam2, v2, _ = oriented_unstable_direction(PEND, J, orient=1)
    np.testing.assert_allclose(v2, v)
    # scale-weighted unit norm
    _, v3, _ = oriented_unstable_direction(PEND, J, scale=[2.0, 0.5])
    assert np.linalg.norm(v3 / [2.0, 0.5]) == pytest.approx(1.0)


def test_as_guess_cuts_at_closest_approach():
    res = unstable_manifold(PEND, [0.0], [np.pi, 0.0], t_max=40.0, eps=1e-7, rtol=1e-12)
    t, x = res.plus.as_guess(target=[3 * np.pi, 0.0])
    assert t.shape == (x.shape[0],) and x.shape[1] == 2
    # the separatrix comes closest to the shifted saddle at its last kept sample
    d = np.linalg.norm(x - [3 * np.pi, 0.0], axis=1)
    assert d[-1] == d.min() and d[-1] < 1e-3
    t_all, _ = res.plus.as_guess()
    assert t_all.size == len(res.plus.trajectory)
    with pytest.raises(ValueError, match="target"):
        res.plus.as_guess(target=[1.0])


def test_plain_callable_classifier():
    # any callable x0 -> label works; without a Trajectory the branch keeps its start
    res = unstable_manifold(PEND, [0.5], [np.pi, 0.0], classify=lambda x0: bool(x0[0] > np.pi))
    assert res.plus.fate is True and res.minus.fate is False  # noqa: E712
    assert res.status is Status.SUCCESS and len(res.plus.trajectory) == 1


def test_single_branch_and_refinement():
    # a slightly wrong saddle is refined by Newton; only the requested branch is computed
    res = unstable_manifold(PEND, [0.5], [np.pi + 1e-4, 1e-4], branches=(-1,), t_max=2.0)
    assert res.plus is None and res.minus is not None
    assert res.x_saddle == pytest.approx([np.pi, 0.0], abs=1e-12)
    with pytest.raises(ValueError, match="not computed"):
        res.branch(1)


@pytest.mark.parametrize(
    ("x", "match"),
    [
        ([0.0, 0.0], "exactly one unstable"),  # stable focus of the pendulum
        ([1.0, 0.0], "not close to an equilibrium"),
    ],
)
def test_non_saddle_raises(x, match):
    with pytest.raises(ValueError, match=match):
        unstable_manifold(PEND, [0.5], x)


def test_index_two_saddle_and_non_hyperbolic_raise():
    source = System(lambda x, p, ops: ops.stack([x[0], 2 * x[1]]), ("a", "b"), ())
    with pytest.raises(ValueError, match="exactly one unstable"):
        unstable_manifold(source, [], [0.0, 0.0])
    center = System(lambda x, p, ops: ops.stack([x[0], -(x[1] ** 3)]), ("a", "b"), ())
    with pytest.raises(ValueError):  # zero eigenvalue: not hyperbolic (or not isolated)
        unstable_manifold(center, [], [0.0, 0.0], refine=False)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"eps": 0.0}, "eps"),
        ({"eps": -1e-6}, "eps"),
        ({"branches": (2,)}, "branches"),
        ({"branches": ()}, "branches"),
        ({"orient": "nope"}, "orient"),
        ({"scale": [1.0]}, "scale"),
        ({"classify": 3}, "classify"),
    ],
)
def test_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        unstable_manifold(PEND, [0.5], [np.pi, 0.0], **kwargs)
