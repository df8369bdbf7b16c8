"""Tests of continuation.dynamics.simulate against exact solutions and independent quadrature."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.linalg import expm

from continuation.dynamics import PoincareSection, SimEvent, Simulator, Trajectory, simulate
from continuation.errors import ContinuationError
from continuation.events import Event
from continuation.status import Status
from continuation.system import System

FAST_METHODS = ("cvodes", "cvodes_adams", "DOP853", "LSODA")


def _osc(x, p, ops):
    return ops.stack([x[1], -(p[0] ** 2) * x[0]])


def _logistic(x, p, ops):
    return ops.stack([p[0] * x[0] * (1 - x[0])])


def _linear(x, p, ops):
    return ops.stack(
        [-0.5 * x[0] + 2.0 * x[1], -2.0 * x[0] - 0.5 * x[1] + 0.3 * x[2], -3.0 * x[2] + x[0]]
    )


def _pendulum(x, p, ops):
    return ops.stack([x[1], -ops.sin(x[0]) - p[0] * x[1]])


def _blowup(x, p, ops):
    return ops.stack([x[0] ** 2])


OSC = System(_osc, ("x", "v"), ("w",))
LOGISTIC = System(_logistic, ("x",), ("r",))
LINEAR = System(_linear, ("a", "b", "c"), ())
PENDULUM = System(_pendulum, ("theta", "omega"), ("gamma",), periodic={"theta": 2 * np.pi})
BLOWUP = System(_blowup, ("x",), ())


# ---------------------------------------------------------------------------- accuracy
@pytest.mark.parametrize("method", FAST_METHODS)
def test_harmonic_oscillator_exact(method):
    # x = cos(w t), v = -w sin(w t); 6 periods at rtol 1e-10: global error below 1e-6
    w = 2.0
    tr = simulate(OSC, [1.0, 0.0], [w], (0.0, 20.0), method=method, rtol=1e-10, atol=1e-12)
    assert tr.status is Status.SUCCESS
    assert tr.t[0] == 0.0 and tr.t[-1] == pytest.approx(20.0, abs=1e-12)
    exact = np.column_stack([np.cos(w * tr.t), -w * np.sin(w * tr.t)])
    assert np.max(np.abs(tr.x - exact)) < 1e-6


@pytest.mark.parametrize("method", FAST_METHODS)
def test_logistic_exact(method):
    r, x0 = 1.5, 0.01
    tr = simulate(LOGISTIC, [x0], {"r": r}, (0.0, 15.0), method=method)
    exact = 1.0 / (1.0 + (1.0 / x0 - 1.0) * np.exp(-r * tr.t))
    assert np.max(np.abs(tr.x[:, 0] - exact)) < 1e-6


def test_linear_system_matches_matrix_exponential():
    A = np.array([[-0.5, 2.0, 0.0], [-2.0, -0.5, 0.3], [1.0, 0.0, -3.0]])
    x0 = np.array([1.0, -0.5, 2.0])
    tr = simulate(LINEAR, x0, [], (0.0, 8.0), dt=0.5)
    for t, x in zip(tr.t, tr.x, strict=True):
        np.testing.assert_allclose(x, expm(A * t) @ x0, atol=1e-7)


def test_tolerance_controls_error():
    # tighter tolerances must give a smaller error (the tolerance is honoured, not ignored)
    w = 1.0
    errs = []
    for rtol in (1e-6, 1e-9):
        tr = simulate(OSC, [1.0, 0.0], [w], (0.0, 10.0), rtol=rtol, atol=rtol * 1e-2)
        errs.append(np.max(np.abs(tr.x[:, 0] - np.cos(tr.t))))
    assert errs[1] < errs[0] / 30


def test_backward_integration():
    w = 1.5
    tr = simulate(OSC, [1.0, 0.0], [w], (0.0, -6.0))
    assert tr.t[-1] == pytest.approx(-6.0)
    assert np.all(np.diff(tr.t) < 0)
    np.testing.assert_allclose(tr.x[:, 0], np.cos(w * tr.t), atol=1e-6)


# ---------------------------------------------------------------------------- events
@pytest.mark.parametrize("method", FAST_METHODS)
def test_terminal_event_blowup_time(method):
    # x' = x^2, x(0) = x0: x = x0 / (1 - x0 t); crosses R at t = 1/x0 - 1/R exactly.
    # The solution grows 2000-fold, so the integration error, not the event locator,
    # limits the accuracy: tight tolerances make the located time good to 1e-8.
    x0, R = 0.5, 1e3
    ev = SimEvent("escape", lambda t, x: x[0] - R, terminal=True, direction="up")
    tr = simulate(
        BLOWUP, [x0], [], (0.0, 10.0), events=[ev], method=method, dt=0.01, rtol=1e-12, atol=1e-14
    )
    assert tr.status is Status.EVENT and tr.terminal_event == "escape"
    t_exact = 1 / x0 - 1 / R
    assert tr.events["escape"].t[0] == pytest.approx(t_exact, abs=1e-8)
    assert tr.t[-1] == tr.events["escape"].t[0]
    # located on the numerical solution to the locator's tolerance
    assert tr.x[-1, 0] == pytest.approx(R, rel=1e-9)


def test_event_directions_located():
    # x = cos t: x = 0 downward at pi/2 + 2k pi, upward at 3pi/2 + 2k pi
    evs = [
        SimEvent("down", lambda t, x: x[0], direction=-1),
        SimEvent("up", lambda t, x: x[0], direction="up"),
        SimEvent("both", lambda t, x: x[0]),
    ]
    tr = simulate(OSC, [1.0, 0.0], [1.0], (0.0, 20.0), events=evs, dt=0.3)
    k = np.arange(10)
    down, up = np.pi / 2 + 2 * np.pi * k, 3 * np.pi / 2 + 2 * np.pi * k
    np.testing.assert_allclose(tr.events["down"].t, down[down < 20], atol=1e-8)
    np.testing.assert_allclose(tr.events["up"].t, up[up < 20], atol=1e-8)
    both = np.sort(np.concatenate([tr.events["down"].t, tr.events["up"].t]))
    np.testing.assert_allclose(tr.events["both"].t, both, atol=1e-12)
    np.testing.assert_allclose(tr.events["down"].x[:, 0], 0.0, atol=1e-8)
    assert tr.status is Status.SUCCESS


def test_vectorized_event_agrees():
    ev1 = SimEvent("a", lambda t, x: x[0] - 0.3)
    ev2 = SimEvent("b", lambda t, x: x[:, 0] - 0.3, vectorized=True)
    tr = simulate(OSC, [1.0, 0.0], [1.0], (0.0, 10.0), events=[ev1, ev2])
    np.testing.assert_allclose(tr.events["a"].t, tr.events["b"].t, atol=1e-12)
    np.testing.assert_allclose(np.cos(tr.events["a"].t), 0.3, atol=1e-8)


def test_non_periodic_poincare_section():
    tr = simulate(
        OSC, [1.0, 0.0], [1.0], (0.0, 13.0), events=[PoincareSection("x", 0.5, direction=1)]
    )
    # cos t = 0.5 going up: t = 2 pi - pi/3 + 2 k pi
    np.testing.assert_allclose(tr.events["poincare"].t, [5 * np.pi / 3, 5 * np.pi / 3 + 2 * np.pi])


def _rotation_times(E, c, n):
    """Times at which the undamped pendulum with energy E (theta(0)=0) reaches c + 2 pi k."""
    speed = lambda th: np.sqrt(2 * (E + np.cos(th)))  # noqa: E731
    T = quad(lambda th: 1 / speed(th), 0, 2 * np.pi, epsabs=1e-13, epsrel=1e-13)[0]
    t_c = quad(lambda th: 1 / speed(th), 0, c, epsabs=1e-13, epsrel=1e-13)[0]
    return t_c + T * np.arange(n), T


@pytest.mark.parametrize("method", ("cvodes", "DOP853"))
def test_poincare_section_of_unwrapped_rotating_pendulum(method):
    # theta'' = -sin theta with energy E = w0^2/2 - cos(0) > 1 rotates forever;
    # the section theta = c (mod 2 pi) is crossed at c + 2 pi k, at times from quadrature.
    w0 = 2.5
    E = w0**2 / 2 - 1.0
    c = 1.0
    tr = simulate(
        PENDULUM,
        [0.0, w0],
        [0.0],
        (0.0, 40.0),
        events=[PoincareSection("theta", c, direction=1, name="sec")],
        method=method,
        rtol=1e-11,
        atol=1e-12,
    )
    hits = tr.events["sec"]
    t_ref, T = _rotation_times(E, c, len(hits))
    assert len(hits) == int((40.0 - t_ref[0]) // T) + 1
    np.testing.assert_allclose(hits.t, t_ref, atol=1e-7)
    # unwrapped coordinate at the hits is c + 2 pi k exactly; wrapped it is c
    np.testing.assert_allclose(hits.x[:, 0], c + 2 * np.pi * np.arange(len(hits)), atol=1e-9)
    assert np.all(np.diff(tr.x[:, 0]) > 0)  # integrated unwrapped
    w = tr.wrapped()
    assert np.all((w[:, 0] >= 0) & (w[:, 0] < 2 * np.pi))
    np.testing.assert_allclose(np.mod(tr.x[:, 0], 2 * np.pi), w[:, 0])


def test_section_counts_every_level_when_coordinate_moves_fast():
    # big samples: theta advances several periods per sample, every level is still found
    tr = simulate(
        PENDULUM,
        [0.0, 30.0],
        [0.0],
        (0.0, 3.0),
        dt=1.0,
        events=[PoincareSection("theta", 0.5)],
        method="DOP853",
    )
    hits = tr.events["poincare"]
    k = np.arange(len(hits))
    np.testing.assert_allclose(hits.x[:, 0], 0.5 + 2 * np.pi * k, atol=1e-9)
    assert len(hits) == int((tr.x[-1, 0] - 0.5) // (2 * np.pi)) + 1
    assert np.all(np.diff(hits.t) > 0)


def test_integration_failure_status_and_throw():
    # x' = x^2 from x=1 blows up at t=1: the integrator must stop near it with a status
    tr = simulate(BLOWUP, [1.0], [], (0.0, 2.0), dt=0.1)
    assert tr.status is Status.INTEGRATION_FAILED
    assert not tr.status.ok
    assert 0.99 < tr.t[-1] < 1.0
    # what was integrated is still right: t + 1/x = 1 is an invariant of x' = x^2
    np.testing.assert_allclose(tr.t + 1 / tr.x[:, 0], 1.0, atol=1e-7)
    with pytest.raises(ContinuationError):
        simulate(BLOWUP, [1.0], [], (0.0, 2.0), throw=True)


def test_event_found_before_failure():
    # the terminal event lies in the last sample interval before the blow-up
    ev = SimEvent("big", lambda t, x: x[0] - 50.0, terminal=True)
    tr = simulate(BLOWUP, [1.0], [], (0.0, 2.0), dt=0.5, events=[ev])
    assert tr.status is Status.EVENT
    assert tr.events["big"].t[0] == pytest.approx(1 - 1 / 50, abs=1e-8)


def test_interrupt_returns_partial_trajectory():
    calls = []

    def progress(t, x):
        calls.append(t)
        if len(calls) == 2:
            raise KeyboardInterrupt

    tr = simulate(OSC, [1.0, 0.0], [1.0], (0.0, 1000.0), dt=0.1, progress=progress)
    assert tr.status is Status.INTERRUPTED
    assert 0 < tr.t[-1] < 1000.0
    np.testing.assert_allclose(tr.x[:, 0], np.cos(tr.t), atol=1e-6)


def test_continuation_event_adapter():
    # a continuation.events.Event has fn(x, p); it is watched with p = the parameters
    ev = Event("level", lambda x, p: x[0] - p[0] / 4, direction="down", terminal=True)
    tr = simulate(OSC, [1.0, 0.0], [2.0], (0.0, 5.0), events=[ev])
    # cos(2 t) = 0.5 first at t = pi / 6
    assert tr.terminal_event == "level"
    assert tr.t[-1] == pytest.approx(np.pi / 6, abs=1e-8)


def test_numpy_only_system_uses_scipy():
    sys_np = System(lambda x, p: np.array([x[1], -x[0]]), ("x", "v"), (), backend="numpy")
    tr = simulate(sys_np, [1.0, 0.0], [], (0.0, 5.0))
    assert tr.method == "DOP853"
    np.testing.assert_allclose(tr.x[:, 0], np.cos(tr.t), atol=1e-7)
    with pytest.raises(ValueError, match="method"):
        simulate(sys_np, [1.0, 0.0], [], (0.0, 5.0), method="cvodes")


# ---------------------------------------------------------------------------- trajectory
def test_dense_hermite_interpolation_is_fourth_order():
    errs = []
    for dt in (0.2, 0.1):
        tr = simulate(OSC, [1.0, 0.0], [1.0], (0.0, 6.0), dt=dt, dense=True, rtol=1e-12, atol=1e-13)
        tq = np.linspace(0.05, 5.95, 97)
        errs.append(np.max(np.abs(tr.at(tq)[:, 0] - np.cos(tq))))
    order = np.log2(errs[0] / errs[1])
    assert abs(order - 4) < 0.5
    tr = simulate(OSC, [1.0, 0.0], [1.0], (0.0, 6.0))
    with pytest.raises(ValueError, match="dense"):
        tr.at(1.0)


def test_save_load_csv_roundtrip(tmp_path):
    tr = simulate(
        PENDULUM,
        [0.0, 2.5],
        [0.05],
        (0.0, 20.0),
        events=[PoincareSection("theta", 0.0, direction=1)],
        dense=True,
    )
    path = tr.save(tmp_path / "traj")
    back = Trajectory.load(path)
    np.testing.assert_array_equal(back.t, tr.t)
    np.testing.assert_array_equal(back.x, tr.x)
    np.testing.assert_array_equal(back.xdot, tr.xdot)
    np.testing.assert_array_equal(back.period, tr.period)
    assert back.state_names == tr.state_names and back.status is tr.status
    np.testing.assert_array_equal(back.events["poincare"].t, tr.events["poincare"].t)
    np.testing.assert_array_equal(back.events["poincare"].x, tr.events["poincare"].x)
    csv = tr.to_csv(tmp_path / "traj.csv")
    header = csv.read_text().splitlines()[0]
    assert header == "t,theta,omega"
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    np.testing.assert_allclose(data[:, 1:], tr.x, rtol=1e-15)
    with pytest.raises(AttributeError):
        tr.status = Status.SUCCESS  # frozen
    with pytest.raises(ValueError):
        tr.x[0, 0] = 1.0  # read-only arrays


def test_append_joins_segments():
    sim = Simulator(OSC, [1.0])
    a = sim.run([1.0, 0.0], (0.0, 3.0), events=[SimEvent("z", lambda t, x: x[0])])
    b = sim.run(a.x_final, (3.0, 7.0), events=[SimEvent("z", lambda t, x: x[0])])
    ab = a.append(b)
    whole = sim.run([1.0, 0.0], (0.0, 7.0), events=[SimEvent("z", lambda t, x: x[0])])
    np.testing.assert_allclose(ab.events["z"].t, whole.events["z"].t, atol=1e-8)
    assert np.all(np.diff(ab.t) > 0)
    np.testing.assert_allclose(ab.x[:, 0], np.cos(ab.t), atol=1e-7)


# ---------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"method": "euler"}, "method"),
        ({"rtol": -1.0}, "rtol"),
        ({"atol": 0.0}, "atol"),
        ({"dt": -0.1}, "dt"),
        ({"max_step": 0.0}, "max_step"),
        ({"t_span": (1.0, 1.0)}, "t_span"),
        ({"t_span": (0.0, np.nan)}, "t_span"),
        ({"x0": [1.0, 2.0, 3.0]}, "x0"),
        ({"x0": [np.nan, 0.0]}, "x0"),
        ({"params": [1.0, 2.0]}, "params"),
        ({"events": [SimEvent("a", lambda t, x: 1.0), SimEvent("a", lambda t, x: 1.0)]}, "two"),
        ({"events": [PoincareSection("nope", 0.0)]}, "state"),
        ({"events": [object()]}, "events"),
    ],
)
def test_bad_input_raises_value_error(kwargs, match):
    args = {"x0": [1.0, 0.0], "params": [1.0], "t_span": (0.0, 1.0)}
    args.update(kwargs)
    x0, params, t_span = args.pop("x0"), args.pop("params"), args.pop("t_span")
    with pytest.raises(ValueError, match=match):
        simulate(OSC, x0, params, t_span, **args)


def test_bad_event_definitions():
    with pytest.raises(ValueError, match="direction"):
        SimEvent("a", lambda t, x: 0.0, direction=2)
    with pytest.raises(ValueError, match="name"):
        SimEvent("", lambda t, x: 0.0)
    with pytest.raises(ValueError, match="fn"):
        SimEvent("a", 3.0)
    with pytest.raises(ValueError, match="value"):
        PoincareSection("x", np.inf)
