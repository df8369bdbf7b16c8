"""Compare time integrators for :func:`continuation.dynamics.simulate.simulate` side by side.

Run: ``python benchmarks/simulate_overhead.py`` (a few minutes on one core; methods
slower than ``TIME_LIMIT`` once are not re-run).

Two systems:

* ``pendulum``: damped pendulum, 2 states (non-stiff), t in [0, 200];
* ``ship8``: an 8-state surge-sway-yaw-roll-rudder-*like* toy with a periodic wave
  coordinate, a lightly damped roll mode and a fast rudder servo (time constant
  0.2 s, so mildly stiff), t in [0, 300]. It only mimics the size and time scales of
  the ship model; it is not the paper's model;
* ``purse_seiner`` (if ``ship_models`` is importable): the paper's 8-state model
  (a CasADi expression of about 12000 operations), t in [0, 50] from next to its
  crest saddle.

For each: wall time per run of every ``simulate`` method (with a Poincare section and
a terminal "capsize" event that never fires), the raw ``scipy.integrate.solve_ivp``
with the same CasADi right-hand side (no events, SciPy's own loop), and the cost of one
right-hand-side call through CasADi vs plain NumPy. Times are reported as ratios to
the fastest ``simulate`` method, plus the deviation of the final state from a
tight-tolerance DOP853 reference (an accuracy sanity check).
"""

from __future__ import annotations

import time
from functools import partial

import numpy as np
from scipy.integrate import solve_ivp

from continuation.dynamics import PoincareSection, SimEvent, simulate
from continuation.ops import NUMPY_OPS
from continuation.system import System


def pendulum_rhs(x, p, ops):
    return ops.stack([x[1], -ops.sin(x[0]) - p[0] * x[1] + p[1]])


def ship8_rhs(x, p, ops):
    xi, u, v, chi, r, phi, pr, delta = (x[i] for i in range(8))
    fn, chi_c = p[0], p[1]
    s = ops.sin(2 * ops.pi * xi)
    c = ops.cos(2 * ops.pi * xi)
    u0 = fn * 10.0
    return ops.stack(
        [
            (u * ops.cos(chi) - v * ops.sin(chi) - 12.0) / 60.0,
            0.05 * (u0 - u) * (1 + 0.1 * u) - 0.6 * s * ops.cos(chi),
            -0.5 * v - 0.3 * r + 0.2 * s * ops.sin(chi) + 0.1 * delta,
            r,
            -0.8 * r - 0.1 * v + 0.4 * delta + 0.05 * c * ops.sin(chi),
            pr,
            -0.1 * pr - 0.7 * ops.sin(phi) * (1 + 0.2 * c) + 0.2 * v + 0.1 * r,
            (-delta - 1.5 * (chi - chi_c) - 3.0 * r) / 0.2,
        ]
    )


CASES = {
    "pendulum": (
        System(pendulum_rhs, ("theta", "omega"), ("g", "F"), periodic={"theta": 2 * np.pi}),
        np.array([0.0, 3.0]),
        np.array([0.1, 1.2]),
        200.0,
        PoincareSection("theta", 0.0, direction=1),
        SimEvent("capsize", lambda t, x: abs(x[1]) - 100.0, terminal=True, direction=1),
    ),
    "ship8": (
        System(
            ship8_rhs,
            ("xi_G", "u", "v", "chi", "r", "phi", "p_roll", "delta"),
            ("Fn", "chi_c"),
            periodic={"xi_G": 1.0},
        ),
        np.array([0.3, 8.0, 0.0, 0.1, 0.0, 0.05, 0.0, 0.0]),
        np.array([0.7, 0.17]),
        300.0,
        PoincareSection("xi_G", 0.0),
        SimEvent("capsize", lambda t, x: abs(x[5]) - 1.5, terminal=True, direction=1),
    ),
}


def _ship_case():
    """The paper's purse seiner (ship_models), from its crest saddle; None if unavailable."""
    try:
        from ship_models import purse_seiner
        from ship_models.analysis.fixed_points import find_fixed_point
    except ImportError:  # pragma: no cover - the engine does not need ship_models
        return None
    model = purse_seiner()
    par = model.default_params()
    crest = find_fixed_point(model, par, "crest").x
    x0 = crest - 1e-4 * np.eye(8)[0]
    i_phi = model.state_index("phi")
    return (
        model,
        x0,
        np.asarray(par.values, dtype=float),
        50.0,
        PoincareSection("xi_G", 0.0),
        SimEvent("capsize", lambda t, x: abs(x[i_phi]) - 1.5, terminal=True, direction=1),
    )


_ship = _ship_case()
if _ship is not None:
    CASES["purse_seiner"] = _ship

METHODS = ("cvodes", "cvodes_adams", "LSODA", "DOP853", "RK45", "BDF", "Radau")
TIME_LIMIT = 20.0  # s: a method slower than this once is not repeated or re-run


def timed(fn, repeat=3):
    """Best wall time of ``repeat`` runs (one run if it takes over a second)."""
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        el = time.perf_counter() - t0
        best = min(best, el)
        if el > 1.0:
            break
    return best, out


def rhs_call_cost(sys_, fun, x0, p, n=20000):
    f = sys_.casadi_functions()["f"]
    t0 = time.perf_counter()
    for _ in range(n):
        f(x0, p)
    t_ca = (time.perf_counter() - t0) / n
    t0 = time.perf_counter()
    for _ in range(n):
        fun(x0, p, NUMPY_OPS)
    return t_ca, (time.perf_counter() - t0) / n


def run_case(name, case, rtol, too_slow):
    sys_, x0, p, t_end, sec, cap = case
    atol = rtol * 1e-2
    ref = simulate(sys_, x0, p, (0, t_end), method="DOP853", rtol=1e-13, atol=1e-14, dt=0.1)
    common = {"rtol": rtol, "atol": atol, "dt": 0.1}
    times, errs = {}, {}
    tr = ref
    for m in METHODS:
        if (name, m) in too_slow:
            continue
        simulate(sys_, x0, p, (0, 1.0), method=m)  # warm-up (compile and cache)
        run = partial(simulate, sys_, x0, p, (0, t_end), method=m, events=[sec, cap], **common)
        el, tr = timed(run)
        times[m] = el
        errs[m] = float(np.max(np.abs(tr.x - ref.x)))
        if el > TIME_LIMIT:
            too_slow.add((name, m))
    el_noev, _ = timed(partial(simulate, sys_, x0, p, (0, t_end), **common))
    f = sys_.casadi_functions()["f"]

    def fun(t, x):
        return np.asarray(f(x, p)).ravel()

    raw = partial(solve_ivp, fun, (0, t_end), x0, method="DOP853", rtol=rtol, atol=atol)
    el_raw, _ = timed(raw)
    fastest = min(times.values())
    n_sec = len(tr.events[sec.name])
    print(
        f"-- {name} (t_end={t_end:g}, {n_sec} section crossings): fastest "
        f"{min(times, key=times.get)} = {fastest * 1e3:.1f} ms per run; ratios:"
    )
    for m, el in times.items():
        print(f"   {m:14s} {el / fastest:7.1f} x   max|x - x_ref| = {errs[m]:.1e}")
    print(f"   {'cvodes, no events':14s} {el_noev / fastest:7.1f} x")
    print(f"   {'raw solve_ivp DOP853, no events':14s} {el_raw / fastest:7.1f} x")
    rhs = {"pendulum": pendulum_rhs, "ship8": ship8_rhs}.get(name)
    if rhs is not None:
        t_ca, t_np = rhs_call_cost(sys_, rhs, x0, p)
        print(f"   one rhs call from Python: CasADi {t_ca * 1e6:.1f} us, NumPy {t_np * 1e6:.1f} us")


def main() -> None:
    too_slow: set[tuple[str, str]] = set()
    for rtol in (1e-8, 1e-10):
        print(f"\n=== rtol={rtol:g}, atol={rtol * 1e-2:g}, output dt=0.1 ===")
        for name, case in CASES.items():
            run_case(name, case, rtol, too_slow)
        if too_slow:
            print(f"   (not re-run, slower than {TIME_LIMIT:g} s: {sorted(too_slow)})")


if __name__ == "__main__":
    main()
