"""Tests of fate classification (continuation.dynamics.fates) and fate bisection.

Reference systems with known fates:

* damped pendulum: both branches of the upper saddle end at the hanging equilibrium,
  shifted by one period and by none;
* Adler's equation ``theta' = F - sin(theta)``, ``F > 1``: a rotation of period
  ``2 pi / sqrt(F^2 - 1)`` (Adler 1946, "A study of locking phenomena in oscillators",
  Proc. IRE 34);
* driven damped pendulum ``theta'' + g theta' + sin(theta) = F``, ``F > 1``: a running
  periodic orbit, checked against an independent SciPy integration and the power balance
  ``2 pi F = g \\int_0^T omega^2 dt`` over one period;
* the planar system ``x' = 1 - x^2``, ``y' = x y + mu - c x^2``, whose saddle
  ``L = (-1, mu - c)`` has the explicit unstable manifold ``x = tanh t``,
  ``y = cosh t \\int_{-inf}^t (mu - c tanh^2 s) sech s ds``. As ``t -> inf``,
  ``y ~ cosh(t) (pi mu - pi c / 2)``: the branch escapes upwards for ``mu > c/2`` and
  downwards for ``mu < c/2`` (using ``\\int sech = pi``, ``\\int sech^3 = pi/2``), and at
  ``mu = c/2`` it is a heteroclinic connection to the saddle ``R = (1, c - mu)``. So the
  fate switches at exactly ``mu* = c/2``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from continuation.dynamics import (
    EquilibriumTracker,
    FateClassifier,
    FateKind,
    PoincareSection,
    SimEvent,
    bisect_fate,
    classify_fate,
    fate_label,
    manifold_fate_function,
    passage_side,
    simulate,
    unstable_manifold,
)
from continuation.errors import ContinuationError
from continuation.status import Status
from continuation.system import System


def _pendulum(x, p, ops):
    return ops.stack([x[1], -ops.sin(x[0]) - p[0] * x[1] + p[1]])


def _adler(x, p, ops):
    return ops.stack([p[0] - ops.sin(x[0])])


def _switch(x, p, ops):
    return ops.stack([1 - x[0] ** 2, x[0] * x[1] + p[0] - p[1] * x[0] ** 2])


PEND = System(_pendulum, ("theta", "omega"), ("gamma", "F"), periodic={"theta": 2 * np.pi})
ADLER = System(_adler, ("theta",), ("F",), periodic={"theta": 2 * np.pi})
SWITCH = System(_switch, ("x", "y"), ("mu", "c"))
C = 1.3  # mu* = C / 2 = 0.65
SWITCH_EVENTS = (
    SimEvent("y_up", lambda t, x: x[1] - 20.0, terminal=True, direction=1),
    SimEvent("y_down", lambda t, x: x[1] + 20.0, terminal=True, direction=-1),
    SimEvent("x_escape", lambda t, x: x[0] + 5.0, terminal=True, direction=-1),
)


def _switch_eqs(mu):
    return {"L": [-1.0, mu - C], "R": [1.0, C - mu]}


# ----------------------------------------------------------------------- classification
def test_damped_pendulum_branches_end_at_shifted_equilibria():
    eqs = {"down": [0.0, 0.0], "up": [np.pi, 0.0]}
    clf = FateClassifier(PEND, [0.5, 0.0], equilibria=eqs, t_max=200.0)
    assert [e.n_unstable for e in clf.equilibria] == [0, 1]
    res = unstable_manifold(PEND, [0.5, 0.0], [np.pi, 0.0], classify=clf)
    plus, minus = res.plus.fate, res.minus.fate
    assert plus.kind is FateKind.EQUILIBRIUM and plus.name == "down" and plus.shift == (1,)
    assert minus.kind is FateKind.EQUILIBRIUM and minus.name == "down" and minus.shift == (0,)
    assert plus.label == "equilibrium:down@+1" and minus.label == "equilibrium:down"
    assert plus.visits == () and minus.visits == ()
    # decided at convergence: within tol of the (shifted) equilibrium
    np.testing.assert_allclose(plus.x, [2 * np.pi, 0.0], atol=1e-6)
    np.testing.assert_allclose(plus.x_equilibrium, [2 * np.pi, 0.0], atol=1e-12)
    assert plus.trajectory.t[-1] == pytest.approx(plus.t)
    assert plus.status is Status.SUCCESS


@pytest.mark.parametrize("F", [1.2, 2.0])
def test_adler_rotation_period_exact(F):
    fate = classify_fate(ADLER, [F], [0.3], t_max=100.0, rtol=1e-12, atol=1e-14)
    assert fate.kind is FateKind.PERIODIC
    assert fate.shift == (1,) and fate.multiplicity == 1
    assert fate.period == pytest.approx(2 * np.pi / np.sqrt(F**2 - 1), rel=1e-8)


def test_adler_locked_below_one_goes_to_unknown_stable_equilibrium():
    # F < 1: theta -> arcsin F, which was not given: found by the speed test + Newton
    fate = classify_fate(ADLER, [0.5], [2.0], t_max=100.0)
    assert fate.kind is FateKind.EQUILIBRIUM and fate.index is None
    assert np.mod(fate.x_equilibrium[0], 2 * np.pi) == pytest.approx(np.arcsin(0.5), abs=1e-10)


def test_slowly_attracting_known_equilibrium_recognised_by_speed():
    # x' = -0.01 x: the speed falls below tol (at x < 1e-4, t > 921) long before the
    # distance does (x < 1e-6, t > 1382); the segment-end speed test names the equilibrium
    slow = System(lambda x, p, ops: ops.stack([-0.01 * x[0]]), ("x",), ())
    fate = classify_fate(slow, [], [1.0], equilibria={"O": [0.0]}, t_max=2000.0)
    assert fate.label == "equilibrium:O" and fate.index == 0
    assert 921.0 < fate.t < 1382.0


def test_driven_pendulum_running_orbit():
    g, F = 0.25, 1.5
    sec = PoincareSection("theta", 0.0, direction=1, name="sec")
    fate = classify_fate(PEND, [g, F], [0.0, 0.0], poincare=sec, t_max=400.0)
    assert fate.kind is FateKind.PERIODIC and fate.shift == (1,) and fate.multiplicity == 1
    # independent check 1: SciPy DOP853 from the detected section point to the next one
    rhs = lambda t, y: [y[1], -np.sin(y[0]) - g * y[1] + F]  # noqa: E731
    ev = lambda t, y: y[0] - fate.x[0] - 2 * np.pi  # noqa: E731
    x0 = np.array(fate.x)
    sol = solve_ivp(
        rhs, (0, 10), x0, method="DOP853", rtol=1e-12, atol=1e-12, events=ev, dense_output=True
    )
    t_ret = sol.t_events[0]
    # (the return map has converged to tol = 1e-6, so x is that close to the orbit and
    # the period measured on the transient is good to about that relative accuracy)
    assert fate.period == pytest.approx(t_ret[0], rel=1e-6)
    np.testing.assert_allclose(sol.sol(t_ret[0]) - [2 * np.pi, 0], x0, atol=1e-6)
    # independent check 2: power balance over one period, 2 pi F = g int omega^2 dt
    work = quad(lambda t: sol.sol(t)[1] ** 2, 0, t_ret[0], epsabs=1e-12, epsrel=1e-12)[0]
    assert g * work == pytest.approx(2 * np.pi * F, rel=1e-6)


def test_spiral_through_section_is_not_periodic():
    # damped oscillator crossing the section x = 0 every half turn with shrinking
    # amplitude: the returns converge (to the equilibrium), but it is no periodic orbit
    osc = System(lambda x, p, ops: ops.stack([x[1], -x[0] - 0.3 * x[1]]), ("x", "v"), ())
    sec = PoincareSection("x", 0.0, direction=0)
    fate = classify_fate(osc, [], [1.0, 0.0], poincare=sec, t_max=300.0)
    assert fate.kind is FateKind.EQUILIBRIUM and fate.name == "unknown"
    np.testing.assert_allclose(fate.x_equilibrium, [0.0, 0.0], atol=1e-12)
    # with the equilibrium given it is recognised by name
    fate2 = classify_fate(osc, [], [1.0, 0.0], equilibria={"O": [0, 0]}, poincare=sec)
    assert fate2.label == "equilibrium:O"


def test_terminal_event_and_visit_of_neighbouring_saddle():
    # mu slightly above c/2: the + branch of L passes near R, then escapes upwards;
    # the - branch runs off to x -> -inf (caught by the x_escape event)
    mu = C / 2 + 1e-4
    clf = FateClassifier(
        SWITCH, [mu, C], equilibria=_switch_eqs(mu), events=SWITCH_EVENTS, t_max=60.0
    )
    res = unstable_manifold(SWITCH, [mu, C], [-1.0, mu - C], classify=clf)
    plus, minus = res.plus.fate, res.minus.fate
    assert plus.kind is FateKind.EVENT and plus.name == "y_up"
    assert [v.name for v in plus.visits] == ["R"]
    assert plus.visits[0].distance < 1e-2
    assert plus.path == ("R", "event:y_up")
    assert plus.trajectory.status is Status.EVENT
    assert minus.label == "event:x_escape" and minus.visits == ()


def test_blow_up_without_event_is_escape():
    blow = System(lambda x, p, ops: ops.stack([x[0] ** 2]), ("x",), ())
    fate = classify_fate(blow, [], [1.0], t_max=5.0, poincare=None)
    assert fate.kind is FateKind.ESCAPE
    assert fate.status is Status.INTEGRATION_FAILED
    assert 0.99 < fate.t < 1.0


def test_undecided_and_interrupted():
    eqs = {"down": [0.0, 0.0], "up": [np.pi, 0.0]}
    fate = classify_fate(PEND, [0.05, 0.0], [3.0, 0.0], equilibria=eqs, t_max=10.0)
    assert fate.kind is FateKind.UNDECIDED and not fate.decided
    assert fate.status is Status.SUCCESS and fate.t == pytest.approx(10.0)

    def stop(t, x):
        raise KeyboardInterrupt

    fate = classify_fate(PEND, [0.05, 0.0], [3.0, 0.0], equilibria=eqs, t_max=500.0, progress=stop)
    assert fate.kind is FateKind.UNDECIDED and fate.status is Status.INTERRUPTED
    assert 0 < fate.t < 500.0


def test_trajectory_input_is_continued():
    eqs = {"down": [0.0, 0.0], "up": [np.pi, 0.0]}
    direct = classify_fate(PEND, [0.5, 0.0], [3.5, 0.0], equilibria=eqs, t_max=200.0)
    head = simulate(
        PEND,
        [3.5, 0.0],
        [0.5, 0.0],
        (0.0, 7.0),
        dt=0.05,
        events=[PoincareSection("theta", 0.0, name="_fate_section")],
    )
    cont = classify_fate(PEND, [0.5, 0.0], head, equilibria=eqs, t_max=200.0)
    assert cont.label == direct.label == "equilibrium:down@+1"
    assert cont.t == pytest.approx(direct.t, abs=0.1)
    # the returned trajectory starts with the given one
    assert cont.trajectory.t[0] == 0.0 and cont.trajectory.t[-1] == pytest.approx(cont.t)
    np.testing.assert_array_equal(cont.trajectory.x[: len(head)], head.x)


def test_classifier_bad_input():
    eqs = {"down": [0.0, 0.0]}
    with pytest.raises(ValueError, match="tol"):
        FateClassifier(PEND, [0.5, 0.0], equilibria=eqs, tol=0.0)
    with pytest.raises(ValueError, match="saddle_radius"):
        FateClassifier(PEND, [0.5, 0.0], equilibria=eqs, tol=1e-2, saddle_radius=1e-3)
    with pytest.raises(ValueError, match="scale"):
        FateClassifier(PEND, [0.5, 0.0], equilibria=eqs, scale=[1.0])
    with pytest.raises(ValueError, match="same point"):
        FateClassifier(PEND, [0.5, 0.0], equilibria=[[0.0, 0.0], [2 * np.pi, 0.0]])
    with pytest.raises(ValueError, match="not close to an equilibrium"):
        FateClassifier(PEND, [0.5, 0.0], equilibria=[[1.0, 0.3]])
    with pytest.raises(ValueError, match="poincare"):
        FateClassifier(PEND, [0.5, 0.0], poincare="sometimes")
    with pytest.raises(ValueError, match="events"):
        FateClassifier(PEND, [0.5, 0.0], events=[PoincareSection("theta", 0.0)])
    with pytest.raises(ValueError, match="t_max"):
        FateClassifier(PEND, [0.5, 0.0], t_max=-1.0)
    with pytest.raises(ValueError, match="x0"):
        classify_fate(PEND, [0.5, 0.0], [0.0, 0.0, 0.0])


# ----------------------------------------------------------------------- bisection
def _switch_fates(**options):
    """Fates of the switch system's saddle branch +1 against mu (heteroclinic at C / 2)."""
    return manifold_fate_function(SWITCH, [0.2, C], "mu", [-1.0, 0.2 - C], branch=1,
                                  equilibria={"R": [1.0, C - 0.2]}, events=SWITCH_EVENTS,
                                  t_max=60.0, **options)  # fmt: skip


def _pendulum_fates(g, F0, **options):
    """Fates of the driven pendulum's saddle branch +1 against F (damping g)."""
    return manifold_fate_function(PEND, [g, F0], "F", [np.pi - np.arcsin(F0), 0.0], branch=1,
                                  equilibria={"down": [np.arcsin(F0), 0.0]},
                                  t_max=20 / g + 200, tol=1e-5, **options)  # fmt: skip


def test_switch_system_fates_on_both_sides():
    fate_at = _switch_fates()
    assert fate_at(0.6).label == "event:y_down"
    assert fate_at(0.7).label == "event:y_up"
    assert fate_at(0.2).label == "event:y_down"


def test_bisect_fate_finds_exact_heteroclinic_parameter():
    fate_at = _switch_fates()
    seen = []
    res = bisect_fate(fate_at, 0.1, 1.25, tol=1e-7, progress=lambda lo, hi, n: seen.append(n))
    assert res.status is Status.SUCCESS
    lo, hi = res.bracket
    assert hi - lo <= 1e-7
    assert lo <= C / 2 + 1e-6 and hi >= C / 2 - 1e-6
    assert res.p_critical == pytest.approx(C / 2, abs=1e-6)
    # the bracket ends have different fates, with y_down below and y_up or R above
    assert fate_label(res.fate_lo) == "event:y_down"
    assert fate_label(res.fate_hi) in ("event:y_up", "saddle:R")
    assert fate_label(res.fate_lo) != fate_label(res.fate_hi)
    assert res.n_evaluations == len(res.history) == len(seen)
    assert res.n_evaluations <= 2 + int(np.ceil(np.log2(1.15 / 1e-7)))


def test_bisect_fate_with_labels_and_statuses():
    step = lambda p: "left" if p < np.sqrt(2) else "right"  # noqa: E731
    res = bisect_fate(step, 3.0, 0.0, tol=1e-9)
    assert res.status is Status.SUCCESS
    assert res.p_critical == pytest.approx(np.sqrt(2), abs=1e-9)
    assert res.fate_lo == "left" and res.fate_hi == "right" and res.bracket[0] < res.bracket[1]
    same = bisect_fate(step, 2.0, 3.0)
    assert same.status is Status.NO_BRACKET and np.isnan(same.p_critical)
    with pytest.raises(ContinuationError):
        bisect_fate(step, 2.0, 3.0, throw=True)
    capped = bisect_fate(step, 0.0, 3.0, tol=1e-12, max_evaluations=10)
    assert capped.status is Status.MAX_ITER and capped.n_evaluations == 10
    assert capped.bracket[0] < np.sqrt(2) < capped.bracket[1]

    def interrupting(p):
        if p not in (0.0, 3.0):
            raise KeyboardInterrupt
        return step(p)

    stopped = bisect_fate(interrupting, 0.0, 3.0)
    assert stopped.status is Status.INTERRUPTED and stopped.bracket == (0.0, 3.0)


def test_bisect_fate_undecided_midpoint():
    eqs = {"down": [0.0, 0.0], "up": [np.pi, 0.0]}

    def fate_at(p):
        t_max = 500.0 if p in (0.0, 1.0) else 1.0
        return classify_fate(
            PEND, [0.5, 0.0], [3.5 * (1 - p) + 2.5 * p, 0.0], equilibria=eqs, t_max=t_max
        )

    res = bisect_fate(fate_at, 0.0, 1.0)
    assert res.status is Status.UNDECIDED
    assert res.bracket == (0.0, 1.0)


def test_bisect_fate_bad_input():
    with pytest.raises(ValueError, match="distinct"):
        bisect_fate(lambda p: p > 0, 1.0, 1.0)
    with pytest.raises(ValueError, match="tol"):
        bisect_fate(lambda p: p > 0, -1.0, 1.0, tol=0.0)
    with pytest.raises(ValueError, match="fate"):
        bisect_fate(lambda p: [p > 0], -1.0, 1.0)


def test_equilibrium_tracker_follows_and_detects_index_change():
    # driven pendulum equilibria: arcsin F (stable) and pi - arcsin F (saddle), F < 1
    tr = EquilibriumTracker(PEND, [0.3, 0.2], "F", {"s": [0.2, 0.0], "u": [2.9, 0.0]})
    assert tr.index == (0, 1)
    for F in (0.5, 0.9, 0.1, -0.4):
        eq = tr.at(F)
        assert eq["s"][0] == pytest.approx(np.arcsin(F), abs=1e-10)
        assert eq["u"][0] == pytest.approx(np.pi - np.arcsin(F), abs=1e-10)
    with pytest.raises(ContinuationError):
        tr.at(1.5)  # the equilibria have collided at the fold F = 1
    with pytest.raises(ValueError, match="free"):
        EquilibriumTracker(PEND, [0.3, 0.2], "Fn", [[0.2, 0.0]])
    with pytest.raises(ValueError, match="index 1"):
        manifold_fate_function(PEND, [0.3, 0.2], "F", [0.2, 0.0])


def _melnikov_deviation(g):
    """Relative deviation of the computed homoclinic F_c(g) from Melnikov's 4 g / pi."""
    F0 = 4 * g / np.pi
    fate_at = _pendulum_fates(g, F0)
    res = bisect_fate(fate_at, 0.5 * F0, 1.5 * F0, tol=1e-9 * F0 / 0.1)
    assert res.status is Status.SUCCESS
    Fc = res.p_critical
    # below F_c the branch passes the next saddle and falls to the next equilibrium,
    # above it it passes the next saddle and runs on the periodic (rotating) orbit;
    # at the bracket's upper end it may reach the next saddle (the connection) itself
    assert res.fate_lo.label == "equilibrium:down@+1"
    assert res.fate_hi.label in ("periodic", "saddle:saddle@+1")
    below, above = fate_at(Fc * (1 - 1e-6)), fate_at(Fc * (1 + 1e-6))
    assert below.label == "equilibrium:down@+1"
    assert above.kind is FateKind.PERIODIC and above.shift == (1,)
    for f in (below, above):
        assert f.visits and f.visits[0].label == "saddle@+1"
    # first passage of the start's copy one period on: back towards down@+1 (theta
    # decreasing, side -1) below F_c, on over the top (side +1) above
    side_at = _pendulum_fates(g, F0, passage="saddle")
    assert side_at(Fc * (1 - 1e-6)) == "passage:saddle:-1"
    assert side_at(Fc * (1 + 1e-6)) == "passage:saddle:+1"
    return abs(Fc / F0 - 1)


def test_driven_pendulum_homoclinic_threshold_matches_melnikov():
    # theta'' + g theta' + sin(theta) = F: the homoclinic loop of the saddle exists at
    # F_c = 4 g / pi to first order in g (Melnikov's method; Guckenheimer & Holmes 1983,
    # "Nonlinear Oscillations, Dynamical Systems, and Bifurcations of Vector Fields",
    # Sec. 4.5). The system is reversible under (t, theta, g, F) -> (-t, -theta, -g, -F),
    # so F_c is odd in g and the relative deviation is O(g^2): check the order.
    d1, d2 = _melnikov_deviation(0.1), _melnikov_deviation(0.05)
    assert d2 < 1e-3
    order = np.log2(d1 / d2)
    assert 1.8 < order < 2.2


# ---------------------------------------------------------------------- first passage
@pytest.mark.parametrize("dmu", [1e-4, -1e-4, 1e-6, -1e-6])
def test_passage_side_of_the_neighbouring_saddle(dmu):
    """The side on which the branch leaves R is the sign of mu - c/2 (closed form above).

    At R = (1, c - mu) the unstable eigenvector is (0, 1) (eigenvalue 1; the stable one
    is -2), so leaving R upwards is side +1, the y_up fate, and downwards side -1.
    """
    mu = C / 2 + dmu
    clf = FateClassifier(
        SWITCH, [mu, C], equilibria=_switch_eqs(mu), events=SWITCH_EVENTS, t_max=60.0
    )
    fate = unstable_manifold(SWITCH, [mu, C], [-1.0, mu - C], classify=clf).plus.fate
    expected = 1 if dmu > 0 else -1
    assert fate.label == ("event:y_up" if expected > 0 else "event:y_down")
    assert [v.name for v in fate.visits] == ["R"]
    assert fate.visits[0].side == expected
    assert passage_side(fate, "R") == expected
    assert passage_side(fate, "L") == 0  # leaving the start is not a visit
    r = clf.equilibria[1]
    assert r.name == "R" and r.unstable_coordinate(np.array([0.0, 0.3])) == pytest.approx(0.3)
    # left eigenvector of J(R) = [[-2, 0], [-(c + mu), 1]] for eigenvalue 1: (-(c + mu)/3, 1)
    assert r.unstable_coordinate(np.array([0.3, 0.0])) == pytest.approx(-0.1 * (C + mu))
    with pytest.raises(ValueError, match="fate"):
        passage_side("event:y_up")


def test_bisect_first_passage_finds_exact_heteroclinic_parameter():
    fate_at = _switch_fates(passage="R", passage_labels={1: "event:y_up", -1: "event:y_down"})
    res = bisect_fate(fate_at, 0.1, 1.25, tol=1e-7)
    assert res.status is Status.SUCCESS
    lo, hi = res.bracket
    assert hi - lo <= 1e-7 and lo <= C / 2 + 1e-6 and hi >= C / 2 - 1e-6
    assert res.fate_lo == "event:y_down"
    assert fate_label(res.fate_hi) in ("event:y_up", "saddle:R")
    with pytest.raises(ValueError, match="passage"):
        manifold_fate_function(
            SWITCH, [0.2, C], "mu", [-1.0, 0.2 - C], equilibria={"R": [1.0, 1.1]}, passage="Q"
        )
    with pytest.raises(ValueError, match="passage_labels"):
        manifold_fate_function(
            SWITCH,
            [0.2, C],
            "mu",
            [-1.0, 0.2 - C],
            equilibria={"R": [1.0, 1.1]},
            passage="R",
            passage_labels={1: "up"},
        )
