r"""Time-domain simulation of :math:`\dot x = f(x, p)` with events and Poincare sections.

The right-hand side is the :class:`~continuation.system.System`'s compiled CasADi
trace, so the integrator and the equilibrium engine evaluate the very same model. The
integrators are described in :mod:`.integrators`, event detection and location in
:mod:`.events`, the result in :mod:`.trajectory`.

Default tolerances: ``rtol = 1e-10``, ``atol = 1e-12`` (local error per step). The
*global* error grows with the integration time and with the instability of the flow
(errors are amplified along an unstable manifold); ``benchmarks/README.md`` ("Time
integrators") gives measured global errors against a tight DOP853 reference.

The solution is returned on a uniform grid of spacing ``dt`` (shortened so that it
divides ``t_span``).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np

from ..arguments import positive
from ..errors import ContinuationError
from ..sigint import sigint_recorded, sigints_counted
from ..status import Status
from ..typing import FloatArray
from ._common import param_vector, state_period
from .events import (
    PoincareSection,
    SimEvent,
    _adapt_event,
    _FnWatch,
    _hermite,
    _locate,
    _SectionWatch,
    _Watch,
)
from .integrators import (
    CVODES_METHODS,
    DEFAULT_ATOL,
    DEFAULT_RTOL,
    METHODS,
    _CvodesBackend,
    _IntegrationFailure,
    _ScipyBackend,
)
from .trajectory import EventHits, Trajectory, hermite

log = logging.getLogger(__name__)

#: Samples of the first CVODES call of a run: one call integrates this many output
#: intervals at once; each later call integrates :data:`_CHUNK_GROWTH` times more, up to
#: :data:`_CHUNK_MAX`. Every call restarts CVODES (order 1, a fresh step size and
#: Jacobian), so long calls save that start-up (for 50 s of the purse seiner at
#: ``dt = 0.05``, 20 calls of 50 samples cost 1.6 times the right-hand-side evaluations
#: of one call of 1000, and 2.1 times its CPU time); short first calls bound the time
#: integrated past a terminal event to about the time integrated before it.
_CHUNK = 50
#: Growth 4 takes about a fifth of the sudden-change step's CPU off (benchmarks/README.md).
#: (It was off for a while: a Ctrl-C was seen to take 23 s to act. The cause was a
#: SIGINT lost in CasADi's argument conversion, not the long calls; see
#: :mod:`continuation.dynamics.integrators`.)
_CHUNK_GROWTH = 4
_CHUNK_MAX = 1000
#: Points per output interval (at first) of the solution used to locate an event with
#: CVODES: the first exact value an event asks for inside an interval integrates the
#: whole interval once, with this many outputs (doubled until the interpolation error
#: estimate is within the integrator's tolerance, :meth:`Simulator._fine_grid`), and
#: the later ones are cubic Hermite interpolants between them (with ``f`` at both
#: ends). For the purse seiner at ``dt = 0.05`` they match a re-integration to the
#: point to the noise of re-integration itself (1.5e-9 of each state's range at
#: ``rtol = 1e-9`` with 4 points; 3e-11 at ``rtol = 1e-11`` with 8, against 2.9e-10
#: with 4), and one call replaces the about 2.7 calls (each a CVODES restart) of
#: re-integrating to every iterate of the root finder.
_FINE = 4
#: Most points per output interval before the root finder integrates to every iterate.
_FINE_MAX = 32
#: Number of halvings used to get as close as possible to an integrator failure.
_FAILURE_BISECTIONS = 12


class Simulator:
    """A reusable integrator for one system and parameter vector.

    Building it once (e.g. inside fate classification, which integrates in many
    segments) avoids re-validating input and re-compiling the CVODES integrator;
    :func:`simulate` is a one-shot wrapper around :meth:`run`.

    Parameters
    ----------
    system : System
        The dynamical system.
    params : Params, mapping or array_like, shape (m,)
        Parameter values.
    method : str
        ``"cvodes"`` (BDF), ``"cvodes_adams"`` or a SciPy method name
        (``"RK45"``, ``"RK23"``, ``"DOP853"``, ``"Radau"``, ``"BDF"``, ``"LSODA"``).
        ``None``: ``"cvodes"`` when the system has a CasADi trace, else ``"DOP853"``.
    rtol, atol : float
        Relative and absolute local error tolerances of the integrator (defaults
        ``1e-10`` and ``1e-12``).
    max_step : float
        Largest internal step (``inf``: no limit).
    """

    def __init__(
        self,
        system: Any,
        params: Any,
        *,
        method: str | None = None,
        rtol: float = DEFAULT_RTOL,
        atol: float = DEFAULT_ATOL,
        max_step: float = math.inf,
    ) -> None:
        if not hasattr(system, "state_names") or not hasattr(system, "f"):
            raise ValueError("`system` must be a System (with `state_names` and `f`)")
        self.system = system
        self.n = len(system.state_names)
        self.p = param_vector(system, params)
        has_ca = bool(getattr(system, "has_casadi", False))
        if method is None:
            method = "cvodes" if has_ca else "DOP853"
        if method not in METHODS:
            raise ValueError(f"`method` must be one of {METHODS}, got {method!r}")
        if method in CVODES_METHODS and not has_ca:
            raise ValueError(
                f"`method`={method!r} needs a system with a CasADi trace; use a SciPy method"
            )
        positive("rtol", rtol)
        positive("atol", atol)
        if not (isinstance(max_step, (int, float)) and max_step > 0):
            raise ValueError(f"`max_step` must be positive, got {max_step!r}")
        self.method = method
        self.rtol = float(rtol)
        self.atol = float(atol)
        self.max_step = float(max_step)
        self.period = state_period(system, self.n)
        backend_cls = _CvodesBackend if method in CVODES_METHODS else _ScipyBackend
        self._backend = backend_cls(system, self.p, method, self.rtol, self.atol, self.max_step)

    # ------------------------------------------------------------------ helpers
    def _check_x0(self, x0: Any) -> FloatArray:
        if hasattr(self.system, "check_state"):
            return np.array(self.system.check_state(x0, "x0"), dtype=float)
        x = np.asarray(x0, dtype=float).reshape(-1)
        if x.shape != (self.n,) or not np.all(np.isfinite(x)):
            raise ValueError(f"`x0` must be a finite array of shape ({self.n},)")
        return x

    def _watches(self, events: Sequence[Any]) -> list[_Watch]:
        if isinstance(events, (SimEvent, PoincareSection)):
            events = (events,)
        watches: list[_Watch] = []
        seen: set[str] = set()
        for ev in events:
            e = _adapt_event(ev, self.p)
            if e.name in seen:
                raise ValueError(f"`events` has two events named {e.name!r}")
            seen.add(e.name)
            if isinstance(e, PoincareSection):
                i = e.index(self.system.state_names)
                watches.append(_SectionWatch(e, i, float(self.period[i])))
            else:
                watches.append(_FnWatch(e))
        return watches

    def derivatives(self, x: FloatArray) -> FloatArray:
        """``f(x_k)`` for every row of ``x`` (shape ``(M, n)``), shape ``(M, n)``."""
        if x.shape[0] == 0:
            return np.zeros_like(x)
        if getattr(self.system, "has_casadi", False):
            f = self.system.casadi_functions()["f"]
            return np.asarray(f(x.T, self.p), dtype=float).reshape(self.n, -1).T
        return np.array([self.system.f(xi, self.p) for xi in x])

    def _fine_grid(
        self, be: Any, xa: FloatArray, h: float, span: float
    ) -> tuple[FloatArray, FloatArray] | None:
        r"""States and derivatives at ``K + 1`` equally spaced points of ``[ta, ta + h]``.

        ``K`` starts at :data:`_FINE` and doubles (up to :data:`_FINE_MAX`) until the
        cubic Hermite interpolant between the points is as accurate as the integration:
        its error, estimated from the interpolant over two sub-intervals at the point
        between them divided by 16 (the error is :math:`O(\delta^4)`), is at most
        ``rtol |x| + atol`` in every state. None when that is not reached, or the
        interval cannot be integrated (a blow-up inside it): the caller integrates to
        each point asked for instead.
        """
        k = _FINE
        while k <= _FINE_MAX:
            try:
                xs = np.vstack([xa, be.run(xa, h, k, span)])
            except _IntegrationFailure:
                return None
            fs = self.derivatives(xs)
            d = 2.0 * h / k
            mid = hermite(0.5, d, xs[0:-2:2], fs[0:-2:2], xs[2::2], fs[2::2])
            err = np.abs(mid - xs[1:-1:2]) / 16.0
            if np.all(err <= self.rtol * np.abs(xs[1:-1:2]) + self.atol):
                return xs, fs
            k *= 2
        return None

    # ------------------------------------------------------------------ main loop
    def run(
        self,
        x0: Any,
        t_span: tuple[float, float],
        *,
        events: Sequence[Any] = (),
        dt: float | None = None,
        dense: bool = False,
        progress: Callable[[float, FloatArray], None] | None = None,
    ) -> Trajectory:
        """Integrate from ``x0`` over ``t_span``; see :func:`simulate`."""
        x0 = self._check_x0(x0)
        try:
            t0, t1 = (float(v) for v in t_span)
        except (TypeError, ValueError):
            raise ValueError(f"`t_span` must be a pair of numbers, got {t_span!r}") from None
        if not (math.isfinite(t0) and math.isfinite(t1)) or t0 == t1:
            raise ValueError(f"`t_span` must be two distinct finite times, got {t_span!r}")
        span = t1 - t0
        if dt is None:
            dt = abs(span) / 1000.0
            if math.isfinite(self.max_step):
                dt = min(dt, self.max_step)
        positive("dt", dt)
        n_samples = max(1, math.ceil(abs(span) / dt - 1e-9))
        watches = self._watches(events)
        with sigint_recorded():
            return self._loop(x0, t0, t1, n_samples, watches, dense, progress)

    def _intervals(self, x0: FloatArray, t0: float, t1: float, n_samples: int) -> Iterator[Any]:
        """Yield blocks ``(t (k+1,), x (k+1, n), interp, is_output (k+1,))``.

        Consecutive blocks share their boundary sample. ``interp(ta, t, xa)`` gives the
        state at a time ``t`` of the block from the block sample ``(ta, xa)`` at or
        before ``t``; ``is_output`` marks the samples that belong to the output grid.
        Raises ``_IntegrationFailure`` after yielding what could be integrated.
        """
        times = t0 + (t1 - t0) * np.arange(n_samples + 1) / n_samples
        if isinstance(self._backend, _CvodesBackend):
            be = self._backend
            chunk_span = (t1 - t0) * min(_CHUNK, n_samples) / n_samples

            h = (t1 - t0) / n_samples  # the output interval (negative backwards)
            fine: dict[float, tuple[FloatArray, FloatArray] | None] = {}

            def interp(ta: float, t: float, xa: FloatArray) -> FloatArray:
                # inside an output interval: the states at K points of it from one
                # CVODES call, cubic Hermite between them (module notes, _fine_grid)
                s = (t - ta) / h
                if 0.0 <= s <= 1.0:
                    if ta not in fine:
                        if len(fine) > 16:
                            fine.clear()
                        fine[ta] = self._fine_grid(be, xa, h, chunk_span)
                    got = fine[ta]
                    if got is not None:
                        xs, fs = got
                        k = xs.shape[0] - 1
                        i = min(int(s * k), k - 1)
                        return np.asarray(
                            hermite(s * k - i, h / k, xs[i], fs[i], xs[i + 1], fs[i + 1]),
                            dtype=float,
                        )
                return be.advance(xa, t - ta, chunk_span)

            k0 = 0
            x = x0
            size = _CHUNK
            # with a maximum step the integrator's step bound is set for chunk_span
            # (time is scaled to [0, 1] per call), so the calls keep that length
            growth = _CHUNK_GROWTH if not math.isfinite(self.max_step) else 1
            while k0 < n_samples:
                rest = n_samples - k0
                # a call of a multiple of _CHUNK samples, then the rest: few distinct
                # call lengths, so few integrators are built (one per length)
                k1 = k0 + (min(size, rest - rest % _CHUNK) if rest > _CHUNK else rest)
                x = yield from self._chunk(be, x, times[k0 : k1 + 1], chunk_span, interp)
                k0 = k1
                size = min(size * growth, _CHUNK_MAX)
            return
        # SciPy: one block per internal step, with the grid samples inside it
        solver = self._backend.solver(t0, x0, t1)
        sgn = 1.0 if t1 > t0 else -1.0
        k = 1
        t_prev, x_prev = t0, x0
        while True:
            msg = solver.step()
            if solver.status == "failed":
                raise _IntegrationFailure(str(msg or "SciPy solver failed"))
            t_new, x_new = float(solver.t), np.array(solver.y, dtype=float)
            if not np.all(np.isfinite(x_new)):
                raise _IntegrationFailure(f"non-finite state at t={t_new:.10g}")
            dense_out = solver.dense_output()
            tol = 1e-13 * max(1.0, abs(t_new))
            inner = []
            while k <= n_samples and sgn * (times[k] - t_new) < -tol:
                inner.append(times[k])
                k += 1
            end_on_grid = k <= n_samples and abs(times[k] - t_new) <= tol
            if end_on_grid:
                k += 1
            tt = np.array([t_prev, *inner, t_new])
            xs = np.array([x_prev, *[dense_out(s) for s in inner], x_new])
            is_out = np.ones(tt.size, dtype=bool)
            is_out[-1] = end_on_grid

            def interp_s(ta: float, t: float, xa: FloatArray, _d: Any = dense_out) -> FloatArray:
                return np.asarray(_d(t), dtype=float)

            yield tt, xs, interp_s, is_out
            t_prev, x_prev = t_new, x_new
            if solver.status == "finished":
                return

    def _chunk(
        self,
        be: _CvodesBackend,
        x: FloatArray,
        tt: FloatArray,
        chunk_span: float,
        interp: Callable[..., Any],
    ) -> Any:
        """Integrate the samples ``tt`` from ``x`` in one CVODES call; return the last state.

        A call that fails is redone in pieces of :data:`_CHUNK` samples, and the piece
        that fails again sample by sample (:meth:`_salvage`).
        """
        try:
            xs = be.run(x, tt[-1] - tt[0], tt.size - 1, chunk_span)
        except _IntegrationFailure:
            if tt.size - 1 <= _CHUNK:
                return (yield from self._salvage(be, x, tt, chunk_span, interp))
            for k0 in range(0, tt.size - 1, _CHUNK):
                piece = tt[k0 : k0 + _CHUNK + 1]
                x = yield from self._chunk(be, x, piece, chunk_span, interp)
            return x
        yield tt, np.vstack([x[None, :], xs]), interp, np.ones(tt.size, dtype=bool)
        return xs[-1]

    def _salvage(
        self,
        be: _CvodesBackend,
        x: FloatArray,
        tt: FloatArray,
        chunk_span: float,
        interp: Callable[..., Any],
    ) -> Any:
        """Integrate a chunk that failed sample by sample; return its last state.

        (Sample by sample rather than by halving: near a blow-up a failing call is
        far more expensive than a successful one.) A failing sample interval is
        bisected ``_FAILURE_BISECTIONS`` times for the furthest reachable time; that
        piece is yielded (so that events before the failure are still found) and
        ``_IntegrationFailure`` is raised.
        """
        for j in range(tt.size - 1):
            try:
                xb = be.advance(x, tt[j + 1] - tt[j], chunk_span)
            except _IntegrationFailure as exc:
                lo, hi = 0.0, tt[j + 1] - tt[j]
                x_lo = x
                for _ in range(_FAILURE_BISECTIONS):
                    mid = 0.5 * (lo + hi)
                    try:
                        x_mid = be.advance(x, mid, chunk_span)
                    except _IntegrationFailure:
                        hi = mid
                    else:
                        lo, x_lo = mid, x_mid
                if lo != 0.0:
                    piece = np.array([tt[j], tt[j] + lo])
                    yield piece, np.vstack([x, x_lo]), interp, np.ones(2, dtype=bool)
                msg = f"integrator failed near t={tt[j] + hi:.10g}: {exc}"
                raise _IntegrationFailure(msg) from None
            yield tt[j : j + 2], np.vstack([x, xb]), interp, np.ones(2, dtype=bool)
            x = xb
        return x

    @staticmethod
    def _emit(
        t_out: list[float],
        x_out: list[FloatArray],
        tt: FloatArray,
        xs: FloatArray,
        is_out: np.ndarray,
        j0: int,
        j1: int,
    ) -> None:
        """Append the output samples ending the block's intervals ``j0 .. j1 - 1``."""
        if j1 <= j0:
            return
        k = np.arange(j0 + 1, j1 + 1)
        k = k[is_out[k]]
        t_out.extend(tt[k].tolist())
        x_out.extend(np.array(xs[k], dtype=float))

    def _loop(
        self,
        x0: FloatArray,
        t0: float,
        t1: float,
        n_samples: int,
        watches: list[_Watch],
        dense: bool,
        progress: Callable[[float, FloatArray], None] | None,
    ) -> Trajectory:
        t_out: list[float] = [t0]
        x_out: list[FloatArray] = [x0]
        hits: dict[str, tuple[list[float], list[FloatArray]]] = {w.name: ([], []) for w in watches}
        status, message, terminal = Status.SUCCESS, "reached the end of t_span", None
        # Event times are located to xtol: near machine precision on smooth dense
        # output (SciPy); for CVODES not below ~10 rtol dt, the noise of re-integration.
        xtol = 1e-13 * max(1.0, abs(t0), abs(t1))
        if isinstance(self._backend, _CvodesBackend):
            xtol = max(xtol, 10.0 * self.rtol * abs(t1 - t0) / n_samples)
        g_prev = [
            float(vals[0]) if (vals := w.values(np.array([t0]), x0[None, :])) is not None else 0.0
            for w in watches
        ]
        scipy_backend = isinstance(self._backend, _ScipyBackend)
        n_sigint = sigints_counted()
        try:
            for tt, xs, interp, is_out in self._intervals(x0, t0, t1, n_samples):
                stop = None
                found: list[tuple[float, int, FloatArray]] = []
                gvals = [w.values(tt[1:], xs[1:]) for w in watches]
                fx: dict[int, FloatArray] = {}  # derivatives at block samples, on demand
                # only the intervals where some watch may have a candidate are visited
                # one by one; the samples in between go to the output in one piece
                flagged = np.zeros(tt.size - 1, dtype=bool)
                for iw, w in enumerate(watches):
                    flagged |= w.flagged(g_prev[iw], gvals[iw], xs)
                done = 0  # intervals [0, done) handled
                for j in np.flatnonzero(flagged).tolist():
                    self._emit(t_out, x_out, tt, xs, is_out, done, j)
                    done = j + 1
                    ta, tb, xa, xb = tt[j], tt[j + 1], xs[j], xs[j + 1]
                    found.clear()
                    for iw, w in enumerate(watches):
                        gv = gvals[iw]
                        gb = float(gv[j]) if gv is not None else 0.0
                        ga = float(gv[j - 1]) if gv is not None and j > 0 else g_prev[iw]
                        cands = w.candidates(ga, gb, xa, xb)
                        if not cands:
                            continue
                        exact = lambda s, _ta=ta, _xa=xa, _ip=interp: _ip(_ta, s, _xa)  # noqa: E731
                        approx = None
                        if not scipy_backend:
                            if j not in fx or j + 1 not in fx:
                                fx[j], fx[j + 1] = self.derivatives(xs[j : j + 2])
                            approx = _hermite(ta, tb, xa, xb, fx[j], fx[j + 1])
                        for gfun in cands:
                            tr, xr = _locate(gfun, ta, tb, xa, xb, exact, approx, xtol)
                            found.append((tr, iw, np.asarray(xr, dtype=float)))
                    if found:
                        sgn = 1.0 if t1 > t0 else -1.0
                        found.sort(key=lambda h: (sgn * h[0], h[1]))
                        for tr, iw, xr in found:
                            w = watches[iw]
                            hits[w.name][0].append(tr)
                            hits[w.name][1].append(xr)
                            if w.terminal:
                                stop = (tr, xr, w.name)
                                break
                    if stop is not None:
                        t_out.append(stop[0])
                        x_out.append(stop[1])
                        status, terminal = Status.EVENT, stop[2]
                        message = f"terminal event {stop[2]!r} at t={stop[0]:.10g}"
                        break
                    if is_out[j + 1]:
                        t_out.append(float(tb))
                        x_out.append(np.asarray(xb, dtype=float))
                if stop is not None:
                    break
                self._emit(t_out, x_out, tt, xs, is_out, done, tt.size - 1)
                for iw, gv in enumerate(gvals):  # the values at the block's last sample
                    g_prev[iw] = float(gv[-1]) if gv is not None else 0.0
                if sigints_counted() != n_sigint:  # a SIGINT some CasADi call lost
                    raise KeyboardInterrupt
                if progress is not None:
                    progress(float(t_out[-1]), x_out[-1])
        except _IntegrationFailure as exc:
            status, message = Status.INTEGRATION_FAILED, str(exc)
            log.info("simulation stopped: %s", message)
        except KeyboardInterrupt:
            status, message = Status.INTERRUPTED, f"interrupted at t={t_out[-1]:.10g}"
        t_arr = np.array(t_out)
        x_arr = np.array(x_out)
        # drop non-grid step ends (SciPy) duplicated in time
        keep = np.ones(t_arr.size, dtype=bool)
        keep[1:] = np.diff(t_arr) != 0
        t_arr, x_arr = t_arr[keep], x_arr[keep]
        n = self.n
        events = {
            nm: EventHits(np.array(ts), np.array(xs).reshape(len(ts), n))
            for nm, (ts, xs) in hits.items()
        }
        xdot = self.derivatives(x_arr) if dense else None
        return Trajectory(
            t=t_arr,
            x=x_arr,
            events=events,
            status=status,
            message=message,
            state_names=tuple(self.system.state_names),
            period=self.period,
            terminal_event=terminal,
            xdot=xdot,
            params=self.p,
            method=self.method,
        )


def simulate(
    system: Any,
    x0: Any,
    params: Any,
    t_span: tuple[float, float],
    *,
    events: Sequence[Any] = (),
    method: str | None = None,
    rtol: float = DEFAULT_RTOL,
    atol: float = DEFAULT_ATOL,
    max_step: float = math.inf,
    dt: float | None = None,
    dense: bool = False,
    progress: Callable[[float, FloatArray], None] | None = None,
    throw: bool = False,
) -> Trajectory:
    r"""Integrate :math:`\dot x = f(x, p)` from ``x0`` over ``t_span``.

    Parameters
    ----------
    system : System
        The dynamical system (its CasADi trace is used when present).
    x0 : array_like, shape (n,)
        Initial state. Periodic states are integrated unwrapped.
    params : Params, mapping or array_like, shape (m,)
        Parameter values.
    t_span : (float, float)
        Start and end times; ``t1 < t0`` integrates backwards.
    events : sequence of SimEvent, PoincareSection or continuation Event
        Watched events; a terminal one stops the run (``Status.EVENT``).
    method : str, optional
        ``"cvodes"`` (default with a CasADi trace: SUNDIALS CVODES, BDF orders 1-5,
        Newton on the exact Jacobian), ``"cvodes_adams"``, or a SciPy ``OdeSolver``
        name (``"DOP853"`` is the default without a CasADi trace).
    rtol, atol : float
        Local error tolerances (default ``1e-10``, ``1e-12``).
    max_step : float
        Largest internal step.
    dt : float, optional
        Output sample spacing (default ``|t1 - t0| / 1000``, at most ``max_step``);
        also the event-detection resolution with CVODES.
    dense : bool
        Also store ``f`` at the samples so that :meth:`Trajectory.at` interpolates.
    progress : callable, optional
        ``progress(t, x)`` called after every integrated block.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` if the integrator fails.

    Returns
    -------
    Trajectory
        Samples ``t (M,)``, ``x (M, n)``, events and status. On failure or
        ``KeyboardInterrupt`` the part computed so far, with the status
        ``INTEGRATION_FAILED`` / ``INTERRUPTED``.

    Raises
    ------
    ValueError
        For a bad ``x0``, ``params``, ``t_span``, ``method``, tolerance or event.

    Examples
    --------
    >>> traj = simulate(pendulum, [3.0, 0.0], {"g": 0.1}, (0.0, 50.0),
    ...                 events=[PoincareSection("theta", 0.0, direction=1)])  # doctest: +SKIP
    """
    sim = Simulator(system, params, method=method, rtol=rtol, atol=atol, max_step=max_step)
    traj = sim.run(x0, t_span, events=events, dt=dt, dense=dense, progress=progress)
    if throw and not traj.status.ok and traj.status is not Status.INTERRUPTED:
        raise ContinuationError(f"simulation failed: {traj.message}")
    return traj


__all__ = [
    "METHODS",
    "EventHits",
    "PoincareSection",
    "SimEvent",
    "Simulator",
    "Trajectory",
    "simulate",
]
