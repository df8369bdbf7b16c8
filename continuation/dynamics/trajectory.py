"""A simulated trajectory: samples, event occurrences, interpolation and file I/O."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..status import Status
from ..typing import FloatArray


def hermite(s: Any, h: Any, xa: Any, fa: Any, xb: Any, fb: Any) -> Any:
    r"""Cubic Hermite interpolant between two samples.

    .. math::

        x(s) = h_{00}(s) x_a + h_{10}(s)\, h f_a + h_{01}(s) x_b + h_{11}(s)\, h f_b,

    with :math:`h_{00} = 2s^3 - 3s^2 + 1`, :math:`h_{10} = s^3 - 2s^2 + s`,
    :math:`h_{01} = -2s^3 + 3s^2`, :math:`h_{11} = s^3 - s^2` and
    :math:`s = (t - t_a)/h \in [0, 1]`; error :math:`O(h^4)`.

    Parameters
    ----------
    s, h : float or ndarray, shape (k, 1)
        Normalised time(s) and interval length(s).
    xa, fa, xb, fb : ndarray, shape (n,) or (k, n)
        States and derivatives at the two ends.

    Returns
    -------
    ndarray, shape (n,) or (k, n)
    """
    return (
        (2 * s**3 - 3 * s**2 + 1) * xa
        + (s**3 - 2 * s**2 + s) * h * fa
        + (-2 * s**3 + 3 * s**2) * xb
        + (s**3 - s**2) * h * fb
    )


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
    period: FloatArray = None  # type: ignore[assignment]  # None: zeros, set in __post_init__
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
            out = hermite(s, h, self.x[k], self.xdot[k], self.x[k + 1], self.xdot[k + 1])
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


__all__ = ["EventHits", "Trajectory"]
