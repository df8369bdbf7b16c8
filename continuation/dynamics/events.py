r"""Events and Poincare sections watched during a simulation: detection and location.

Not to be confused with :class:`continuation.events.Event`, an event of a *continuation*
(``fn(x, p)`` along a branch); :func:`_adapt_event` wraps one as a :class:`SimEvent`.

Events are *detected* by a sign change of the event function between consecutive
samples (CVODES) or consecutive internal steps (SciPy), and *located* on the continuous
solution: for CVODES the root of a cubic Hermite interpolant is refined by Newton/secant
steps on the solution re-integrated from the left sample, so the located state carries
the integrator's error, not the interpolant's, to ``max(1e-13 |t|, 10 rtol dt)`` in time
(below that the re-integration is noise); for SciPy Brent's method runs on the solver's
dense output, to ``1e-13 |t|``. A function that changes sign twice within one sample
interval is missed, as with any sampled detection: keep ``dt`` below the shortest time
scale of the event functions.

A :class:`PoincareSection` of a periodic coordinate is handled on the *unwrapped*
coordinate: the state ``x_i`` is integrated without wrapping and a crossing is
``x_i = c + k P`` for any integer ``k`` (``P`` the period), located as a root of
``x_i - (c + k P)``. This has none of the spurious sign changes of a wrapped
coordinate or of ``sin(2 pi (x_i - c) / P)``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq

from ..typing import FloatArray
from .trajectory import hermite


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

    def flagged(self, g0: float, g: FloatArray | None, x: FloatArray) -> np.ndarray:
        """The sample intervals of a block where :meth:`candidates` may be non-empty.

        ``x (M + 1, n)`` are the block's samples, ``g (M,)`` the event values at
        ``x[1:]`` (:meth:`values`, or None) and ``g0`` the value at ``x[0]``. Returns a
        boolean mask ``(M,)`` that holds every interval with a candidate (it may hold
        more: :meth:`candidates` is still asked for each flagged interval), so that the
        simulator loops in Python over the flagged intervals only.
        """
        return np.ones(x.shape[0] - 1, dtype=bool)


def _crosses(ga: float, gb: float, direction: int) -> bool:
    """Sign change in the half-open interval ``(ta, tb]`` with the wanted direction."""
    up = ga < 0.0 <= gb
    down = ga > 0.0 >= gb
    return (up and direction >= 0) or (down and direction <= 0)


def _crosses_mask(ga: FloatArray, gb: FloatArray, direction: int) -> np.ndarray:
    """:func:`_crosses` for arrays of interval ends (elementwise, the same comparisons)."""
    up = (ga < 0.0) & (0.0 <= gb)
    down = (ga > 0.0) & (0.0 >= gb)
    if direction > 0:
        return up
    if direction < 0:
        return down
    return up | down


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

    def flagged(self, g0, g, x):  # noqa: D102
        if g is None:  # pragma: no cover - values() always returns an array here
            return np.zeros(x.shape[0] - 1, dtype=bool)
        ga = np.empty_like(g)
        ga[0] = g0
        ga[1:] = g[:-1]
        return _crosses_mask(ga, g, self.direction)


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

    def flagged(self, g0, g, x):  # noqa: D102
        v = x[:, self.i]
        a, b = v[:-1], v[1:]
        if self.P <= 0.0:
            return _crosses_mask(a - self.c, b - self.c, self.direction)
        # levels(a, b) is non-empty exactly when the section index k of the level
        # below (above) changes between a and b; floor/ceil as in levels()
        qa, qb = (a - self.c) / self.P, (b - self.c) / self.P
        mask = np.zeros(a.shape, dtype=bool)
        if self.direction >= 0:
            mask |= (b > a) & (np.floor(qb) > np.floor(qa))
        if self.direction <= 0:
            mask |= (b < a) & (np.ceil(qa) > np.ceil(qb))
        return mask


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
    t_prev: float | None = None  # the previous iterate (None: none yet)
    g_prev = 0.0
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
        return hermite((t - ta) / hh, hh, xa, fa, xb, fb)

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
