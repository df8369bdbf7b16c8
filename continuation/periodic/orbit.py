r"""One periodic orbit on a collocation mesh: :class:`PeriodicOrbit`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..bvp.collocation import CollocationMesh
from ..params import Params
from ..system import as_params
from ..typing import FloatArray


def winding_vector(system: Any, winding: Any) -> tuple[int, ...]:
    """Winding numbers per state from ``{state: k}`` (periodic states only) or None."""
    n = system.n_states
    out = [0] * n
    if winding is None:
        return tuple(out)
    if not hasattr(winding, "items"):
        raise ValueError(f"`winding` must be a mapping {{state: int}}, got {winding!r}")
    period = np.asarray(getattr(system, "period", np.zeros(n)), dtype=float)
    for name, k in winding.items():
        i = system.state_index(name)
        if not float(period[i]) > 0:
            raise ValueError(f"`winding`: state {name!r} is not periodic in the System")
        if isinstance(k, bool) or int(k) != k:
            raise ValueError(f"`winding[{name!r}]` must be an integer, got {k!r}")
        out[i] = int(k)
    return tuple(out)


@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    r"""A cycle :math:`x(t + T) = x(t) + k \circ \text{period}` stored on a mesh.

    Attributes
    ----------
    system : System
    params : Params
        All parameter values (the free one included).
    mesh : CollocationMesh
        Nodes and degree (``mesh.T`` is not used; the period is :attr:`T`).
    X : ndarray, shape (M, n)
        Values at the ``M = N (m + 1) + 1`` mesh and collocation points, in
        ``mesh.tau`` order; periodic states unwrapped (``X[-1] = X[0] + k period``).
    T : float
        Period.
    winding : tuple of int
        ``k_i`` per state (nonzero only for periodic states: a rotation orbit).
    """

    system: Any
    params: Params
    mesh: CollocationMesh
    X: FloatArray
    T: float
    winding: tuple[int, ...] = field(default=())

    def __post_init__(self) -> None:
        X = np.array(self.X, dtype=float)
        n = self.system.n_states
        if X.shape != (self.mesh.n_points, n):
            raise ValueError(f"`X` must have shape ({self.mesh.n_points}, {n}), got {X.shape}")
        if not (np.isfinite(self.T) and self.T > 0):
            raise ValueError(f"`T` must be a positive finite period, got {self.T!r}")
        X.setflags(write=False)
        object.__setattr__(self, "X", X)
        object.__setattr__(self, "T", float(self.T))
        if not self.winding:
            object.__setattr__(self, "winding", (0,) * n)

    @property
    def shift(self) -> FloatArray:
        """``k o period``, shape ``(n,)``: ``x(T) - x(0)``."""
        per = np.asarray(getattr(self.system, "period", np.zeros(len(self.winding))), float)
        return np.asarray(self.winding, dtype=float) * per

    @property
    def t(self) -> FloatArray:
        """Times of the points of :attr:`X`, shape ``(M,)``."""
        return self.T * self.mesh.tau

    def __call__(self, t: Any) -> FloatArray:
        """``x(t)`` for any times (the cycle continued periodically), shape ``(K, n)``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        turns = np.floor(t / self.T)
        tau = t / self.T - turns
        return self.mesh.interpolate(self.X, tau) + turns[:, None] * self.shift[None, :]

    def on_mesh(self, mesh: CollocationMesh) -> PeriodicOrbit:
        """The same cycle interpolated onto another mesh."""
        X = self.mesh.interpolate(self.X, mesh.tau)
        X[-1] = X[0] + self.shift
        return PeriodicOrbit(self.system, self.params, mesh, X, self.T, self.winding)

    def param(self, name: str) -> float:
        """Value of parameter ``name``."""
        return float(self.params[name])

    def amplitude(self) -> FloatArray:
        """``max - min`` of each state over the cycle, shape ``(n,)``."""
        return np.max(self.X, axis=0) - np.min(self.X, axis=0)


def orbit_from_array(
    system: Any,
    params: Any,
    t: Any,
    x: Any,
    *,
    mesh: CollocationMesh | None = None,
    winding: Any = None,
) -> PeriodicOrbit:
    """A :class:`PeriodicOrbit` guess from samples of one period.

    Parameters
    ----------
    system : System
    params : Params, mapping or array
    t : array_like, shape (K,)
        Increasing times; ``t[-1] - t[0]`` is the period guess.
    x : array_like, shape (K, n)
        States at ``t``, periodic ones unwrapped; ``x[-1]`` should be close to
        ``x[0] + k o period``.
    mesh : CollocationMesh, optional
        Default: 40 uniform intervals of degree 4.
    winding : mapping of str to int, optional
        Rotation numbers of periodic states.

    Raises
    ------
    ValueError
        On shapes, non-increasing or non-finite times, or too few samples.
    """
    params = as_params(system, params)
    t = np.asarray(t, dtype=float).reshape(-1)
    x = np.asarray(x, dtype=float)
    n = system.n_states
    if x.ndim != 2 or x.shape != (t.size, n):
        raise ValueError(f"`x` must have shape ({t.size}, {n}), got {x.shape}")
    if t.size < 4:
        raise ValueError(f"`t` needs at least 4 samples, got {t.size}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise ValueError("`t` and `x` must be finite")
    if np.any(np.diff(t) <= 0):
        raise ValueError("`t` must be strictly increasing")
    mesh = mesh if mesh is not None else CollocationMesh(40, 4, 1.0)
    k = winding_vector(system, winding)
    T = float(t[-1] - t[0])
    tau = (t - t[0]) / T
    X = np.column_stack([np.interp(mesh.tau, tau, x[:, i]) for i in range(n)])
    return PeriodicOrbit(system, params, mesh, X, T, k)


__all__ = ["PeriodicOrbit", "orbit_from_array", "winding_vector"]
