r"""Time-domain simulation of :math:`\dot x = f(x, p)` with events and Poincare sections.

The right-hand side is the :class:`~continuation.system.System`'s compiled CasADi
trace, so the integrator and the equilibrium engine evaluate the very same model.

Integrators
-----------
``method="cvodes"`` (default when the system has a CasADi trace)
    SUNDIALS CVODES (Hindmarsh et al. 2005, "SUNDIALS: Suite of nonlinear and
    differential/algebraic equation solvers", ACM TOMS 31(3)) through
    ``casadi.integrator``: variable-order BDF (orders 1-5) with a Newton corrector
    on the exact Jacobian ``T df/dx`` that CasADi derives from the trace. Robust on
    stiff models (the ship's rudder servo is much faster than its surge motion).
``method="cvodes_adams"``
    CVODES with variable-order Adams-Moulton (orders 1-12), for non-stiff models.
``method in {"RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA"}``
    SciPy's ``OdeSolver`` classes stepped one by one, calling the compiled CasADi
    ``f`` (and ``jacobian`` for the implicit ones). Available for any system,
    including NumPy-only ones; default for those.

Default tolerances: ``rtol = 1e-10``, ``atol = 1e-12`` (local error per step). The
*global* error grows with the integration time and with the instability of the flow;
against a DOP853 reference at ``rtol = 1e-13`` the default BDF run is off by about
1e-8 after 300 s of an 8-state ship-like toy model, 2e-5 after 200 s (2400 rad) of a
rotating pendulum, and 4e-6 after 50 s of the paper's purse seiner started 1e-4 from
its crest saddle (errors amplified along the unstable manifold).

Measured by ``benchmarks/simulate_overhead.py`` (wall-time ratios to the fastest, with
a Poincare section and a terminal event, ``rtol = 1e-10``):

==================  =====  ====  =====  ======  ====  =========  =====  ==========
case                Adams  BDF   LSODA  DOP853  RK45  SciPy BDF  Radau  solve_ivp*
==================  =====  ====  =====  ======  ====  =========  =====  ==========
8-state toy, 300 s  1.0    1.3   17.5   44      77    48         194    31
purse seiner, 50 s  1.0    1.2   2.7    2.5     4.3   6.5        22     2.1
==================  =====  ====  =====  ======  ====  =========  =====  ==========

(``*``: raw ``solve_ivp(DOP853)`` without events. CVODES-Adams: 31 ms for the toy,
54 ms for 50 s of the purse seiner, whose right-hand
side is a CasADi expression of about 12000 operations.) One CasADi ``f`` call from
Python costs about 20 us of overhead, so the SciPy methods are dominated by call
overhead on small models, while CVODES calls the compiled function in C. BDF is the
default rather than Adams for its robustness on stiff models (on the Van der Pol
oscillator with ``mu = 1000`` Adams is 3 times slower), at 1.2-1.3 times the cost on
these non-stiff ones.

Sampling and events
-------------------
The solution is returned on a uniform grid of spacing ``dt`` (shortened so that it
divides ``t_span``). Events are *detected* by a sign change of the event function
between consecutive samples (CVODES) or consecutive internal steps (SciPy), and
*located* on the continuous solution: for CVODES the root of a cubic Hermite
interpolant is refined by Newton/secant steps on the solution re-integrated from the
left sample, so the located state carries the integrator's error, not the
interpolant's, to ``max(1e-13 |t|, 10 rtol dt)`` in time (below that the
re-integration is noise); for SciPy Brent's method runs on the solver's dense output,
to ``1e-13 |t|``. A function that changes sign twice within one sample
interval is missed, as with any sampled detection: keep ``dt`` below the shortest
time scale of the event functions.

A :class:`PoincareSection` of a periodic coordinate is handled on the *unwrapped*
coordinate: the state ``x_i`` is integrated without wrapping and a crossing is
``x_i = c + k P`` for any integer ``k`` (``P`` the period), located as a root of
``x_i - (c + k P)``. This has none of the spurious sign changes of a wrapped
coordinate or of ``sin(2 pi (x_i - c) / P)``.
"""

from __future__ import annotations

import logging
import math
import weakref
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import scipy.integrate as si
from scipy.optimize import brentq

from .errors import ContinuationError
from .params import Params
from .status import Status
from .typing import FloatArray

log = logging.getLogger(__name__)

SCIPY_METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
CVODES_METHODS = ("cvodes", "cvodes_adams")
METHODS = CVODES_METHODS + SCIPY_METHODS

#: Default relative and absolute tolerances of the integrators.
DEFAULT_RTOL = 1e-10
DEFAULT_ATOL = 1e-12
#: Samples per CVODES call: one call integrates this many output intervals at once.
_CHUNK = 50
#: Number of halvings used to get as close as possible to an integrator failure.
_FAILURE_BISECTIONS = 12
#: CVODES internal steps allowed per output interval before it reports failure.
_MAX_STEPS_PER_SAMPLE = 20000


# ---------------------------------------------------------------------------------- events
def _direction(value: Any, name: str = "direction") -> int:
    """Normalise an event direction to -1, 0 or +1."""
    table = {"up": 1, "down": -1, "both": 0, "rising": 1, "falling": -1, "any": 0}
    if isinstance(value, str):
        if value not in table:
            raise ValueError(f"`{name}` must be one of {sorted(table)} or -1/0/+1, got {value!r}")
        return table[value]
    if isinstance(value, bool) or value not in (-1, 0, 1):
        raise ValueError(f"`{name}` must be -1, 0, +1 or 'up'/'down'/'both', got {value!r}")
    return int(value)


@dataclass(frozen=True)
class SimEvent:
    r"""An event :math:`g(t, x) = 0` watched during a simulation.

    Parameters
    ----------
    name : str
        Key of the event in :attr:`Trajectory.events`.
    fn : callable
        ``fn(t, x) -> float`` with ``x`` the (unwrapped) state, shape ``(n,)``.
        With ``vectorized=True``: ``fn(t (M,), x (M, n)) -> (M,)``.
    terminal : bool
        Stop the simulation at the first occurrence.
    direction : {0, 1, -1} or {"both", "up", "down"}
        Count only crossings where ``g`` increases (``1``/``"up"``), decreases
        (``-1``/``"down"``), or both (``0``), along the direction of integration.
    vectorized : bool
        Whether ``fn`` accepts arrays of samples (faster for long runs).

    Examples
    --------
    >>> capsize = SimEvent("capsize", lambda t, x: abs(x[5]) - 1.2, terminal=True, direction=1)
    """

    name: str
    fn: Callable[..., Any]
    terminal: bool = False
    direction: int | str = 0
    vectorized: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"`name` must be a non-empty string, got {self.name!r}")
        if not callable(self.fn):
            raise ValueError(f"`fn` of event {self.name!r} must be callable")
        object.__setattr__(self, "direction", _direction(self.direction))
        object.__setattr__(self, "terminal", bool(self.terminal))


@dataclass(frozen=True)
class PoincareSection:
    r"""The section :math:`x_i = c \pmod P` of one state (``P`` its period, if any).

    Parameters
    ----------
    state : str or int
        Name or index of the sectioning state.
    value : float
        The level ``c``. For a periodic state every ``c + k P`` is the same section.
    direction : {0, 1, -1} or {"both", "up", "down"}
        Crossings with ``x_i`` increasing (``1``), decreasing (``-1``) or both (``0``).
    name : str
        Key of the crossings in :attr:`Trajectory.events`.
    terminal : bool
        Stop the simulation at the first crossing.
    """

    state: str | int
    value: float
    direction: int | str = 0
    name: str = "poincare"
    terminal: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"`name` must be a non-empty string, got {self.name!r}")
        if not math.isfinite(float(self.value)):
            raise ValueError(f"`value` must be finite, got {self.value!r}")
        object.__setattr__(self, "value", float(self.value))
        object.__setattr__(self, "direction", _direction(self.direction))
        object.__setattr__(self, "terminal", bool(self.terminal))

    def index(self, state_names: Sequence[str]) -> int:
        """Position of the sectioning state in ``state_names``."""
        if isinstance(self.state, str):
            if self.state not in state_names:
                raise ValueError(
                    f"PoincareSection `state` {self.state!r} is not one of {tuple(state_names)}"
                )
            return list(state_names).index(self.state)
        i = int(self.state)
        if not 0 <= i < len(state_names):
            raise ValueError(
                f"PoincareSection `state` index {i} out of range 0..{len(state_names)}"
            )
        return i


class _Watch:
    """An event resolved against a system.

    ``candidates`` returns, for one sample interval, the scalar functions
    ``g(t, x)`` that are known to change sign in it (with the wanted direction).
    """

    def __init__(self, name: str, terminal: bool, direction: int) -> None:
        self.name = name
        self.terminal = terminal
        self.direction = direction

    def values(self, t: FloatArray, x: FloatArray) -> FloatArray | None:
        """Event values at samples ``t (M,)``, ``x (M, n)``, or None if not used."""
        return None

    def candidates(
        self, ga: float, gb: float, xa: FloatArray, xb: FloatArray
    ) -> list[Callable[[float, FloatArray], float]]:  # pragma: no cover - abstract
        raise NotImplementedError


def _crosses(ga: float, gb: float, direction: int) -> bool:
    """Sign change in the half-open interval ``(ta, tb]`` with the wanted direction."""
    up = ga < 0.0 <= gb
    down = ga > 0.0 >= gb
    return (up and direction >= 0) or (down and direction <= 0)


class _FnWatch(_Watch):
    def __init__(self, ev: SimEvent) -> None:
        super().__init__(ev.name, ev.terminal, int(ev.direction))
        self.fn = ev.fn
        self.vectorized = ev.vectorized

    def values(self, t: FloatArray, x: FloatArray) -> FloatArray:
        if self.vectorized:
            g = np.asarray(self.fn(t, x), dtype=float).reshape(-1)
            if g.shape != t.shape:
                raise ValueError(f"vectorized event {self.name!r} must return shape {t.shape}")
            return g
        return np.array([float(self.fn(ti, xi)) for ti, xi in zip(t, x, strict=True)])

    def _g(self, t: float, x: FloatArray) -> float:
        if self.vectorized:
            return float(np.asarray(self.fn(np.array([t]), x[None, :])).reshape(-1)[0])
        return float(self.fn(t, x))

    def candidates(self, ga, gb, xa, xb):  # noqa: D102
        return [self._g] if _crosses(ga, gb, self.direction) else []


class _SectionWatch(_Watch):
    def __init__(self, sec: PoincareSection, index: int, period: float) -> None:
        super().__init__(sec.name, sec.terminal, int(sec.direction))
        self.i = index
        self.c = sec.value
        self.P = period

    def levels(self, a: float, b: float) -> list[float]:
        """Section levels crossed going from ``a`` to ``b`` (half-open at ``a``)."""
        if self.P <= 0.0:
            return [self.c] if _crosses(a - self.c, b - self.c, self.direction) else []
        c, P = self.c, self.P
        if b > a and self.direction >= 0:
            ks = range(math.floor((a - c) / P) + 1, math.floor((b - c) / P) + 1)
        elif b < a and self.direction <= 0:
            ks = range(math.ceil((a - c) / P) - 1, math.ceil((b - c) / P) - 1, -1)
        else:
            return []
        return [c + k * P for k in ks]

    def candidates(self, ga, gb, xa, xb):  # noqa: D102
        i = self.i
        return [
            (lambda t, x, L=L: float(x[i]) - L) for L in self.levels(float(xa[i]), float(xb[i]))
        ]


def _locate(
    g: Callable[[float, FloatArray], float],
    ta: float,
    tb: float,
    xa: FloatArray,
    xb: FloatArray,
    exact: Callable[[float], FloatArray],
    approx: Callable[[float], FloatArray] | None,
    xtol: float,
) -> tuple[float, FloatArray]:
    r"""Root of :math:`h(t) = g(t, x(t))` in ``(ta, tb]``, where ``h`` changes sign.

    ``exact(t)`` is the solution (re-integration or dense output), ``approx(t)`` an
    optional cheap interpolant. With ``approx``: the interpolant's root is the first
    guess, one Newton step on the exact ``h`` with the interpolant's slope gives the
    second, then secant steps on exact values, safeguarded by bisection of the
    sign-change bracket. When a secant correction falls below ``xtol`` the sign
    change is *confirmed* by one more exact value ``2 xtol`` further (expanding
    geometrically if the root is further, as happens when ``exact`` is noisy), and
    Brent's method finishes inside the confirmed bracket if it is still wider than
    ``3 xtol``. Typically three evaluations of ``exact`` instead of about ten for
    Brent's method from scratch.
    """
    ga = g(ta, xa)
    gb = g(tb, xb)
    if gb == 0.0:
        return tb, xb
    h = lambda s: g(s, exact(s))  # noqa: E731
    if approx is None or not (ga * gb < 0):
        tr = brentq(h, ta, tb, xtol=xtol, rtol=1e-15)
        return tr, exact(tr)
    ha = lambda s: g(s, approx(s))  # noqa: E731
    # invariant: h(lo) has the sign of glo, h(hi) the other sign
    lo, hi, glo = ta, tb, ga
    try:
        t = brentq(ha, ta, tb, xtol=xtol, rtol=1e-15)
    except ValueError:  # pragma: no cover - the interpolant matches h at both ends
        t = 0.5 * (ta + tb)
    t_prev = g_prev = None
    for it in range(60):
        xt = exact(t)
        gt = g(t, xt)
        if gt == 0.0:
            return t, xt
        if (gt < 0) == (glo < 0):
            lo, glo = t, gt
            other = hi
        else:
            hi = t
            other = lo
        if abs(hi - lo) <= xtol:
            return t, xt
        if t_prev is None:  # Newton step with the interpolant's slope
            d = 1e-7 * abs(tb - ta)
            slope = (ha(t + d) - ha(t - d)) / (2 * d)
            t_new = t - gt / slope if slope != 0 and np.isfinite(slope) else np.nan
        else:  # secant step on exact values
            t_new = t - gt * (t - t_prev) / (gt - g_prev) if gt != g_prev else np.nan
            if abs(t_new - t) <= xtol:
                return _confirm(h, exact, t, xt, gt, other, xtol)
        if not (np.isfinite(t_new) and min(lo, hi) < t_new < max(lo, hi)) or it >= 8:
            t_new = 0.5 * (lo + hi)  # safeguard: bisect the bracket
        t_prev, g_prev = t, gt
        t = t_new
    return t, exact(t)  # pragma: no cover - 60 halvings reach xtol


def _confirm(
    h: Callable[[float], float],
    exact: Callable[[float], FloatArray],
    t: float,
    xt: FloatArray,
    gt: float,
    other: float,
    xtol: float,
) -> tuple[float, FloatArray]:
    """Confirm a root next to ``t`` (towards the bracket end ``other``), then refine."""
    s = 1.0 if other > t else -1.0
    a, step = t, 2.0 * xtol
    b = other
    while True:
        tc = t + s * step
        if s * (other - tc) <= 0:  # reached the bracket end: root in (a, other)
            break
        gc = h(tc)
        if gc == 0.0:
            return tc, exact(tc)
        if (gc < 0) != (gt < 0):
            b = tc
            break
        a, step = tc, 4.0 * step
    if abs(b - a) <= 3.0 * xtol:
        return (t, xt) if a == t else (a, exact(a))
    lo_, hi_ = min(a, b), max(a, b)
    tr = brentq(h, lo_, hi_, xtol=xtol, rtol=1e-15)
    return tr, exact(tr)


def _hermite(ta: float, tb: float, xa, xb, fa, fb) -> Callable[[float], FloatArray]:
    """Cubic Hermite interpolant on ``[ta, tb]`` from states and derivatives."""
    hh = tb - ta

    def x_of(t: float) -> FloatArray:
        s = (t - ta) / hh
        return (
            (2 * s**3 - 3 * s**2 + 1) * xa
            + (s**3 - 2 * s**2 + s) * hh * fa
            + (-2 * s**3 + 3 * s**2) * xb
            + (s**3 - s**2) * hh * fb
        )

    return x_of


def _adapt_event(ev: Any, p: FloatArray) -> SimEvent | PoincareSection:
    """Accept :class:`SimEvent`, :class:`PoincareSection`, or a continuation ``Event``.

    A continuation ``Event`` has ``fn(x, p)``; it is wrapped as ``fn(t, x) = ev.fn(x, p)``.
    """
    if isinstance(ev, (SimEvent, PoincareSection)):
        return ev
    if hasattr(ev, "fn") and hasattr(ev, "name"):
        fn = ev.fn
        pv = np.array(p, dtype=float)
        return SimEvent(
            str(ev.name),
            lambda t, x, _fn=fn: float(_fn(x, pv)),
            terminal=bool(getattr(ev, "terminal", False)),
            direction=getattr(ev, "direction", 0),
        )
    raise ValueError(
        f"`events` entries must be SimEvent, PoincareSection or Event objects, got {type(ev)}"
    )


# ------------------------------------------------------------------------------ trajectory
@dataclass(frozen=True, eq=False)
class EventHits:
    """Occurrences of one event.

    Attributes
    ----------
    t : ndarray, shape (k,)
        Times of the occurrences, increasing along the integration.
    x : ndarray, shape (k, n)
        States at those times (unwrapped).
    """

    t: FloatArray
    x: FloatArray

    def __post_init__(self) -> None:
        t = np.array(self.t, dtype=float).reshape(-1)
        x = np.array(self.x, dtype=float)
        if x.ndim != 2:
            x = x.reshape(t.size, -1) if t.size else x.reshape(0, 0)
        if x.shape[0] != t.size:
            raise ValueError(f"`x` must have one row per time in `t`, got {x.shape} for {t.size}")
        t.setflags(write=False)
        x.setflags(write=False)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "x", x)

    def __len__(self) -> int:
        return int(self.t.size)


def _ro(a: Any, shape: tuple[int, ...] | None = None) -> FloatArray:
    arr = np.array(a, dtype=float)
    if shape is not None:
        arr = arr.reshape(shape)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A simulated trajectory, sampled on a grid, with its events.

    Attributes
    ----------
    t : ndarray, shape (M,)
        Sample times (monotone along the integration direction).
    x : ndarray, shape (M, n)
        States; periodic coordinates are *unwrapped* (continuous in time).
    events : mapping of str to EventHits
        Every watched event (terminal or not, including Poincare sections) by name.
    status : Status
        ``SUCCESS`` (end time reached), ``EVENT`` (a terminal event stopped it),
        ``INTERRUPTED``, ``INTEGRATION_FAILED`` or ``NONFINITE``.
    message : str
        Human-readable detail.
    state_names : tuple of str
        Names of the ``n`` states.
    period : ndarray, shape (n,)
        Period of each state (``0`` where not periodic).
    terminal_event : str or None
        Name of the event that stopped the run, if any.
    xdot : ndarray, shape (M, n), or None
        ``f(x)`` at the samples (when simulated with ``dense=True``); enables
        cubic Hermite interpolation in :meth:`at`.
    params : ndarray, shape (m,), or None
        Parameter vector used.
    method : str
        Integrator used.
    """

    t: FloatArray
    x: FloatArray
    events: Mapping[str, EventHits] = field(default_factory=dict)
    status: Status = Status.SUCCESS
    message: str = ""
    state_names: tuple[str, ...] = ()
    period: FloatArray | None = None
    terminal_event: str | None = None
    xdot: FloatArray | None = None
    params: FloatArray | None = None
    method: str = ""

    def __post_init__(self) -> None:
        t = _ro(self.t).reshape(-1)
        x = np.array(self.x, dtype=float)
        if x.ndim == 1:
            x = x.reshape(t.size, -1) if t.size else x.reshape(0, -1)
        if x.ndim != 2 or x.shape[0] != t.size:
            raise ValueError(f"`x` must have shape (M, n) with M={t.size}, got {x.shape}")
        n = x.shape[1]
        x.setflags(write=False)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "x", x)
        names = tuple(self.state_names) or tuple(f"x{i}" for i in range(n))
        if len(names) != n:
            raise ValueError(f"`state_names` must have {n} entries, got {len(names)}")
        object.__setattr__(self, "state_names", names)
        per = np.zeros(n) if self.period is None else np.array(self.period, dtype=float)
        if per.shape != (n,):
            raise ValueError(f"`period` must have shape ({n},), got {per.shape}")
        object.__setattr__(self, "period", _ro(per))
        if self.xdot is not None:
            object.__setattr__(self, "xdot", _ro(self.xdot, x.shape))
        if self.params is not None:
            object.__setattr__(self, "params", _ro(self.params).reshape(-1))
        evs = {
            str(k): v if isinstance(v, EventHits) else EventHits(*v) for k, v in self.events.items()
        }
        object.__setattr__(self, "events", evs)
        if not isinstance(self.status, Status):
            raise ValueError(f"`status` must be a Status, got {self.status!r}")

    # ------------------------------------------------------------------ views
    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def n_states(self) -> int:
        """Number of states ``n``."""
        return int(self.x.shape[1])

    @property
    def t_final(self) -> float:
        """Last sample time."""
        return float(self.t[-1])

    @property
    def x_final(self) -> FloatArray:
        """Last state, shape ``(n,)``."""
        return self.x[-1]

    def state(self, name: str) -> FloatArray:
        """Samples of state ``name``, shape ``(M,)``."""
        if name not in self.state_names:
            raise ValueError(f"unknown state name {name!r}; valid names are {self.state_names}")
        return self.x[:, self.state_names.index(name)]

    def wrapped(self) -> FloatArray:
        """States with periodic coordinates mapped into ``[0, period)``, shape ``(M, n)``."""
        x = np.array(self.x)
        mask = self.period > 0
        if np.any(mask):
            x[:, mask] = np.mod(x[:, mask], self.period[mask])
        return x

    def at(self, t: float | FloatArray) -> FloatArray:
        r"""State at time(s) ``t`` inside the trajectory, shape ``(n,)`` or ``(k, n)``.

        Cubic Hermite interpolation on the samples and ``xdot`` (error
        :math:`O(dt^4)`); requires ``dense=True`` at simulation time.
        """
        if self.xdot is None:
            raise ValueError("`at` needs derivatives: simulate with `dense=True`")
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        sgn = 1.0 if self.t.size < 2 or self.t[-1] >= self.t[0] else -1.0
        ts = sgn * self.t
        q = sgn * tt
        if np.any(q < ts[0] - 1e-12 * max(1, abs(ts[0]))) or np.any(
            q > ts[-1] + 1e-12 * max(1, abs(ts[-1]))
        ):
            raise ValueError(f"`t` outside the trajectory [{self.t[0]}, {self.t[-1]}]")
        k = np.clip(np.searchsorted(ts, q, side="right") - 1, 0, max(ts.size - 2, 0))
        if ts.size == 1:
            out = np.repeat(self.x[:1], tt.size, axis=0)
        else:
            h = (self.t[k + 1] - self.t[k])[:, None]
            s = ((tt - self.t[k]) / (self.t[k + 1] - self.t[k]))[:, None]
            h00 = 2 * s**3 - 3 * s**2 + 1
            h10 = s**3 - 2 * s**2 + s
            h01 = -2 * s**3 + 3 * s**2
            h11 = s**3 - s**2
            out = (
                h00 * self.x[k]
                + h10 * h * self.xdot[k]
                + h01 * self.x[k + 1]
                + h11 * h * self.xdot[k + 1]
            )
        return out[0] if np.ndim(t) == 0 else out

    # ------------------------------------------------------------------ combination
    def append(self, other: Trajectory) -> Trajectory:
        """Join ``other`` (which starts where ``self`` ends) after ``self``.

        The first sample of ``other`` is dropped (it repeats the last of ``self``);
        events are concatenated; status, message and terminal event are ``other``'s.
        """
        if other.n_states != self.n_states:
            raise ValueError("`other` has a different number of states")
        names = list(dict.fromkeys([*self.events, *other.events]))
        evs = {}
        empty = EventHits(np.zeros(0), np.zeros((0, self.n_states)))
        for nm in names:
            a = self.events.get(nm, empty)
            b = other.events.get(nm, empty)
            evs[nm] = EventHits(
                np.concatenate([a.t, b.t]),
                np.concatenate([a.x.reshape(-1, self.n_states), b.x.reshape(-1, self.n_states)]),
            )
        xdot = None
        if self.xdot is not None and other.xdot is not None:
            xdot = np.concatenate([self.xdot, other.xdot[1:]])
        return Trajectory(
            np.concatenate([self.t, other.t[1:]]),
            np.concatenate([self.x, other.x[1:]]),
            evs,
            other.status,
            other.message,
            self.state_names,
            self.period,
            other.terminal_event,
            xdot,
            self.params,
            self.method,
        )

    # ------------------------------------------------------------------ I/O
    def save(self, path: str | Path) -> Path:
        """Write an NPZ file (arrays + metadata); read back with :meth:`load`.

        Keys: ``t``, ``x``, ``period``, ``state_names``, ``status`` (enum name),
        ``message``, ``terminal_event``, ``method``, optional ``xdot``/``params``, and
        for each event ``event_names[j]``: ``event{j}_t``, ``event{j}_x``.
        """
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(".npz")
        arrays: dict[str, Any] = {
            "t": self.t,
            "x": self.x,
            "period": self.period,
            "state_names": np.array(self.state_names, dtype=str),
            "status": np.array(self.status.name),
            "message": np.array(self.message),
            "terminal_event": np.array(self.terminal_event or ""),
            "method": np.array(self.method),
            "event_names": np.array(list(self.events), dtype=str),
        }
        if self.xdot is not None:
            arrays["xdot"] = self.xdot
        if self.params is not None:
            arrays["params"] = self.params
        for j, hits in enumerate(self.events.values()):
            arrays[f"event{j}_t"] = hits.t
            arrays[f"event{j}_x"] = hits.x.reshape(len(hits), self.n_states)
        np.savez(path, **arrays)
        return path

    @classmethod
    def load(cls, path: str | Path) -> Trajectory:
        """Read a trajectory written by :meth:`save`."""
        with np.load(Path(path), allow_pickle=False) as d:
            names = [str(s) for s in d["event_names"]]
            events = {
                nm: EventHits(d[f"event{j}_t"], d[f"event{j}_x"]) for j, nm in enumerate(names)
            }
            return cls(
                t=d["t"],
                x=d["x"],
                events=events,
                status=Status[str(d["status"])],
                message=str(d["message"]),
                state_names=tuple(str(s) for s in d["state_names"]),
                period=d["period"],
                terminal_event=str(d["terminal_event"]) or None,
                xdot=d["xdot"] if "xdot" in d else None,
                params=d["params"] if "params" in d else None,
                method=str(d["method"]),
            )

    def to_csv(self, path: str | Path, *, wrapped: bool = False) -> Path:
        """Write ``t`` and the states as CSV with a header row ``t,<state names>``."""
        path = Path(path)
        data = np.column_stack([self.t, self.wrapped() if wrapped else self.x])
        np.savetxt(
            path, data, delimiter=",", header=",".join(("t", *self.state_names)), comments=""
        )
        return path


# ------------------------------------------------------------------------------ backends
class _IntegrationFailure(Exception):
    """Raised by a backend when the integrator fails on an interval."""


def _param_vector(system: Any, params: Any) -> FloatArray:
    if hasattr(system, "check_params"):
        return np.asarray(system.check_params(params, "params"), dtype=float)
    if isinstance(params, Params):
        return np.array(params.values, dtype=float)
    return np.asarray(params, dtype=float).reshape(-1)


def _period(system: Any, n: int) -> FloatArray:
    per = getattr(system, "period", None)
    return np.zeros(n) if per is None else np.asarray(per, dtype=float).reshape(n)


class _CvodesBackend:
    """CVODES through ``casadi.integrator`` with time scaled to ``[0, 1]``.

    The integrated system is ``dx/ds = T f(x, p)`` on ``s in [0, 1]``, ``T`` an extra
    parameter, so one compiled integrator serves every segment length (and both time
    directions). Integrators are cached per system and options.
    """

    _cache: weakref.WeakKeyDictionary[Any, dict[tuple[Any, ...], Any]] = weakref.WeakKeyDictionary()

    def __init__(
        self, system: Any, p: FloatArray, method: str, rtol: float, atol: float, max_step: float
    ) -> None:
        self.system = system
        self.p = np.asarray(p, dtype=float)
        self.lmm = "adams" if method == "cvodes_adams" else "bdf"
        self.rtol = rtol
        self.atol = atol
        self.max_step = max_step
        self.n = len(system.state_names)
        self.n_calls = 0
        self._local: dict[tuple[Any, ...], Any] = {}

    def _integrator(self, n_out: int, span: float) -> Any:
        ms = self.max_step / abs(span) if math.isfinite(self.max_step) else 0.0
        key = (n_out, self.lmm, self.rtol, self.atol, ms)
        try:
            store = self._cache.setdefault(self.system, {})
        except TypeError:  # system not weak-referenceable: cache on this backend only
            store = self._local
        integ = store.get(key)
        if integ is None:
            f = self.system.casadi_functions()["f"]
            X = ca.SX.sym("x", self.n)
            P = ca.SX.sym("p", self.p.size)
            T = ca.SX.sym("T")
            dae = {"x": X, "p": ca.vertcat(P, T), "ode": T * f(X, P)}
            opts: dict[str, Any] = {
                "reltol": self.rtol,
                "abstol": self.atol,
                "max_num_steps": _MAX_STEPS_PER_SAMPLE,
                "linear_multistep_method": self.lmm,
                "disable_internal_warnings": True,
                "show_eval_warnings": False,
                "error_on_fail": True,
            }
            if ms > 0:
                opts["max_step_size"] = ms
            grid = [k / n_out for k in range(1, n_out + 1)]
            integ = ca.integrator(f"sim_{n_out}", "cvodes", dae, 0.0, grid, opts)
            store[key] = integ
        return integ

    def run(self, x0: FloatArray, T: float, n_out: int, span_hint: float) -> FloatArray:
        """States at ``t0 + T k / n_out``, k = 1..n_out, shape ``(n_out, n)``."""
        integ = self._integrator(n_out, span_hint)
        self.n_calls += 1
        try:
            out = integ(x0=x0, p=np.concatenate([self.p, [T]]))
        except RuntimeError as exc:
            msg = str(exc).strip().splitlines()[-1] if str(exc).strip() else "CVODES failed"
            raise _IntegrationFailure(msg) from None
        xs = np.asarray(out["xf"], dtype=float).reshape(self.n, n_out).T
        if not np.all(np.isfinite(xs)):
            raise _IntegrationFailure("non-finite state")
        return xs

    def advance(self, x0: FloatArray, tau: float, span_hint: float) -> FloatArray:
        """State at ``t0 + tau``, shape ``(n,)``."""
        if tau == 0.0:
            return np.array(x0, dtype=float)
        return self.run(x0, tau, 1, span_hint)[0]


class _ScipyBackend:
    """A SciPy ``OdeSolver`` driven step by step with the compiled right-hand side."""

    def __init__(
        self, system: Any, p: FloatArray, method: str, rtol: float, atol: float, max_step: float
    ) -> None:
        self.system = system
        self.p = np.asarray(p, dtype=float)
        self.method = method
        self.rtol = rtol
        self.atol = atol
        self.max_step = max_step
        self.n_calls = 0
        f = getattr(system, "casadi_functions", None)
        funcs = None
        if getattr(system, "has_casadi", False) and f is not None:
            funcs = f()
        if funcs is not None:
            cf, cj = funcs["f"], funcs["jac"]
            pp = self.p
            self.fun = lambda t, x: np.asarray(cf(x, pp)).reshape(-1)
            self.jac = lambda t, x: np.asarray(cj(x, pp))
        else:
            self.fun = lambda t, x: np.asarray(system.f(x, self.p), dtype=float).reshape(-1)
            self.jac = lambda t, x: np.asarray(system.jacobian(x, self.p), dtype=float)

    def solver(self, t0: float, x0: FloatArray, t1: float) -> Any:
        cls = getattr(si, self.method)
        kw: dict[str, Any] = {"rtol": self.rtol, "atol": self.atol, "max_step": self.max_step}
        if self.method in ("Radau", "BDF", "LSODA"):
            kw["jac"] = self.jac
        return cls(self.fun, t0, np.array(x0, dtype=float), t1, **kw)


# ------------------------------------------------------------------------------ simulator
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
        self.p = _param_vector(system, params)
        has_ca = bool(getattr(system, "has_casadi", False))
        if method is None:
            method = "cvodes" if has_ca else "DOP853"
        if method not in METHODS:
            raise ValueError(f"`method` must be one of {METHODS}, got {method!r}")
        if method in CVODES_METHODS and not has_ca:
            raise ValueError(
                f"`method`={method!r} needs a system with a CasADi trace; use a SciPy method"
            )
        for name, v in (("rtol", rtol), ("atol", atol)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"`{name}` must be a positive finite number, got {v!r}")
        if not (isinstance(max_step, (int, float)) and max_step > 0):
            raise ValueError(f"`max_step` must be positive, got {max_step!r}")
        self.method = method
        self.rtol = float(rtol)
        self.atol = float(atol)
        self.max_step = float(max_step)
        self.period = _period(system, self.n)
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
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise ValueError(f"`dt` must be a positive finite number, got {dt!r}")
        n_samples = max(1, math.ceil(abs(span) / dt - 1e-9))
        watches = self._watches(events)
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

            def interp(ta: float, t: float, xa: FloatArray) -> FloatArray:
                return be.advance(xa, t - ta, chunk_span)

            k0 = 0
            x = x0
            while k0 < n_samples:
                k1 = min(k0 + _CHUNK, n_samples)
                tt = times[k0 : k1 + 1]
                try:
                    xs = be.run(x, tt[-1] - tt[0], k1 - k0, chunk_span)
                except _IntegrationFailure:
                    # retry sample by sample, bisecting towards a failure
                    x = yield from self._salvage(be, x, tt, chunk_span, interp)
                else:
                    yield tt, np.vstack([x[None, :], xs]), interp, np.ones(tt.size, dtype=bool)
                    x = xs[-1]
                k0 = k1
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
        try:
            for tt, xs, interp, is_out in self._intervals(x0, t0, t1, n_samples):
                stop = None
                found: list[tuple[float, int, FloatArray]] = []
                gvals = [w.values(tt[1:], xs[1:]) for w in watches]
                fx = None  # derivatives at the block samples, computed on demand
                for j in range(tt.size - 1):
                    ta, tb, xa, xb = tt[j], tt[j + 1], xs[j], xs[j + 1]
                    found.clear()
                    for iw, w in enumerate(watches):
                        gv = gvals[iw]
                        gb = float(gv[j]) if gv is not None else 0.0
                        ga = g_prev[iw]
                        g_prev[iw] = gb
                        cands = w.candidates(ga, gb, xa, xb)
                        if not cands:
                            continue
                        exact = lambda s, _ta=ta, _xa=xa, _ip=interp: _ip(_ta, s, _xa)  # noqa: E731
                        approx = None
                        if not scipy_backend:
                            if fx is None:
                                fx = self.derivatives(xs)
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
