"""The result of a collocated orbit that ends at a saddle: connection or landing.

:class:`OrbitResult` holds everything a solve of the one collocation core
(:mod:`continuation.bvp.layout`) returns -- orbit, end points, parameters, mesh,
status, error estimates -- with its access, I/O and plotting. The two kinds differ
only in their start condition, which the result records:

* :class:`ConnectionResult`: the orbit leaves a saddle ``x_from`` (``x_-``);
* :class:`LandingResult`: the orbit starts at a given point ``x_from = x_0(s)`` of a
  start parameter ``s`` (:mod:`continuation.bvp.landing`); ``x_eq`` is the equilibrium
  it lands on (``x_to``).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Generic, TypeVar

import numpy as np

from ..params import Params
from ..status import Status
from ..typing import FloatArray
from .collocation import CollocationMesh


@dataclass(frozen=True)
class ErrorEstimates:
    r"""Error estimates of the solved parameters of a connection.

    Attributes
    ----------
    discretisation : dict of str to float
        ``safety * |p(2N) - p(N)|``: the change on the mesh with every interval halved
        (same nodes, so the adapted mesh is kept), times the safety factor. For
        collocation of degree ``m`` the parameter error is :math:`O(h^{2m})`, so
        :math:`|p(2N) - p(N)| pprox (1 - 2^{-2m})\,|p(N) - p^*|`.
    truncation : dict of str to float
        ``safety * |p(T_factor T) - p(T)|``: the change on an interval ``T_factor``
        times longer with the same resolution (the added end intervals as long as
        the end intervals of the mesh); the truncation error of projection boundary
        conditions decays exponentially with ``T`` (Beyn 1990).
    tolerance : dict of str to float
        The tolerance each estimate was compared with.
    n_intervals_fine : int
        Intervals of the halved mesh.
    T_long : float
        The longer truncation interval.
    """

    discretisation: dict[str, float]
    truncation: dict[str, float]
    tolerance: dict[str, float]
    n_intervals_fine: int = 0
    T_long: float = math.nan

    def total(self, name: str) -> float:
        """``discretisation[name] + truncation[name]``."""
        return float(self.discretisation[name] + self.truncation[name])

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form."""
        return {
            "discretisation": dict(self.discretisation),
            "truncation": dict(self.truncation),
            "tolerance": dict(self.tolerance),
            "n_intervals_fine": self.n_intervals_fine,
            "T_long": self.T_long,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ErrorEstimates:
        """Inverse of :meth:`to_dict`."""
        return cls(
            {k: float(v) for k, v in d["discretisation"].items()},
            {k: float(v) for k, v in d["truncation"].items()},
            {k: float(v) for k, v in d["tolerance"].items()},
            int(d.get("n_intervals_fine", 0)),
            float(d.get("T_long", math.nan)),
        )


@dataclass(frozen=True, eq=False)
class OrbitResult:
    """A (possibly failed) orbit computed by collocation, from its start to a saddle.

    The common part of :class:`ConnectionResult` and :class:`LandingResult`.

    Attributes
    ----------
    params : Params
        All parameter values, the solved ``free`` parameters included.
    free : tuple of str
        Names of the parameters that were solved for.
    state_names : tuple of str
        Names of the ``n`` states.
    t : ndarray, shape (M,)
        Times of the mesh and collocation points in ``[0, T]``.
    x : ndarray, shape (M, n)
        The orbit at ``t``.
    x_from, x_to : ndarray, shape (n,)
        The start (the saddle ``x_-`` of a connection, the start point ``x_0(s)`` of a
        landing) and the end equilibrium ``x_+``.
    residual_norm : float
        ``max |G|`` of the discretised equations at the returned point.
    mesh : CollocationMesh
        Intervals, degree and truncation time ``T``.
    status : Status
        ``Status.SUCCESS`` when Newton converged.
    message : str
        Human-readable outcome.
    newton_iters : int
        Newton iterations of the last solve.
    z : ndarray, shape (N_z,)
        The raw unknown vector (for restarts and continuation).
    problem : HeteroclinicProblem or LandingProblem or None
        The (rebased) problem ``z`` belongs to; None after :meth:`load`.
    errors : ErrorEstimates or None
        Discretisation and truncation error estimates of the solved parameters (None
        when they were not estimated: ``ConnectionAccuracy(estimate=False)``, a branch
        row, a failed solve).
    """

    params: Params
    free: tuple[str, ...]
    state_names: tuple[str, ...]
    t: FloatArray
    x: FloatArray
    x_from: FloatArray
    x_to: FloatArray
    residual_norm: float
    mesh: CollocationMesh
    status: Status
    message: str
    newton_iters: int = 0
    z: FloatArray = field(default_factory=lambda: np.zeros(0), repr=False)
    problem: Any = field(default=None, repr=False)
    errors: ErrorEstimates | None = None

    def __post_init__(self) -> None:
        for name in ("t", "x", "x_from", "x_to", "z"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    # ------------------------------------------------------------------ access
    @property
    def success(self) -> bool:
        """True when the solve converged."""
        return self.status is Status.SUCCESS

    def error(self, name: str) -> float:
        """Estimated error bound of solved parameter ``name``: discretisation + truncation.

        ``nan`` when the errors were not estimated.
        """
        if name not in self.free:
            raise ValueError(f"`name` {name!r} is not a solved parameter; they are {self.free}")
        if self.errors is None:
            return math.nan
        return self.errors.total(name)

    @property
    def T(self) -> float:
        """Truncation time."""
        return self.mesh.T

    def value(self, name: str) -> float:
        """Value of parameter ``name``."""
        return self.params[name]

    @property
    def unknowns(self) -> dict[str, float]:
        """The solved parameters ``{name: value}``."""
        return {u: self.params[u] for u in self.free}

    def state(self, name: str) -> FloatArray:
        """Orbit component ``name``, shape ``(M,)``."""
        try:
            i = self.state_names.index(name)
        except ValueError:
            raise ValueError(
                f"unknown state name {name!r}; valid names are {self.state_names}"
            ) from None
        return self.x[:, i]

    @property
    def t_mesh(self) -> FloatArray:
        """Times of the mesh nodes only, shape ``(N + 1,)``."""
        return self.t[self.mesh.mesh_mask]

    @property
    def x_mesh(self) -> FloatArray:
        """Orbit at the mesh nodes only, shape ``(N + 1, n)``."""
        return self.x[self.mesh.mesh_mask]

    def interpolate(self, t: FloatArray) -> FloatArray:
        """The collocation polynomial at times ``t`` (K,) in ``[0, T]``; shape ``(K, n)``."""
        return self.mesh.interpolate(self.x, np.asarray(t, dtype=float) / self.mesh.T)

    # ------------------------------------------------------------------ I/O
    def save(self, path: str | Path) -> Path:
        """Write ``path`` (NPZ arrays) and ``path`` with suffix ``.json`` (metadata).

        Returns the NPZ path. The problem object is not saved.
        """
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(".npz")
        np.savez(
            path,
            t=self.t,
            x=self.x,
            x_from=self.x_from,
            x_to=self.x_to,
            z=self.z,
            param_values=np.asarray(self.params.values),
            nodes=self.mesh.nodes,
        )
        meta = {
            "kind": type(self).__name__,
            **self._start_meta(),
            "param_names": list(self.params.names),
            "free": list(self.free),
            "errors": None if self.errors is None else self.errors.to_dict(),
            "state_names": list(self.state_names),
            "residual_norm": self.residual_norm,
            "mesh": {
                "n_intervals": self.mesh.n_intervals,
                "degree": self.mesh.degree,
                "T": self.mesh.T,
            },
            "status": self.status.name,
            "message": self.message,
            "newton_iters": self.newton_iters,
        }
        path.with_suffix(".json").write_text(json.dumps(meta, indent=2))
        return path

    def _start_meta(self) -> dict[str, Any]:
        """The start condition's metadata for :meth:`save` (none for a connection)."""
        return {}

    @classmethod
    def load(cls, path: str | Path) -> Any:
        """Read a result written by :meth:`save` (``problem`` is None).

        ``ConnectionResult.load`` reads a connection, ``LandingResult.load`` a landing,
        ``OrbitResult.load`` either.
        """
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(".npz")
        meta = json.loads(path.with_suffix(".json").read_text())
        kinds: dict[str, type[OrbitResult]] = {"ConnectionResult": ConnectionResult,
                                               "LandingResult": LandingResult}  # fmt: skip
        kind = kinds.get(str(meta.get("kind")))
        if kind is None or not issubclass(kind, cls):
            raise ValueError(f"`path` {path} does not hold a {cls.__name__}")
        extra: dict[str, Any] = {}
        if kind is LandingResult:
            extra = {"s": float(meta["s"]), "start_name": str(meta["start_name"])}
        with np.load(path) as d:
            arrays = {k: np.array(d[k]) for k in d.files}
        m = meta["mesh"]
        mesh = CollocationMesh(
            int(m["n_intervals"]), int(m["degree"]), float(m["T"]), arrays["nodes"]
        )
        return kind(
            **extra,
            params=Params(tuple(meta["param_names"]), arrays["param_values"]),
            free=tuple(meta.get("free", meta.get("unknown_params", ()))),
            errors=None if not meta.get("errors") else ErrorEstimates.from_dict(meta["errors"]),
            state_names=tuple(meta["state_names"]),
            t=arrays["t"],
            x=arrays["x"],
            x_from=arrays["x_from"],
            x_to=arrays["x_to"],
            residual_norm=float(meta["residual_norm"]),
            mesh=mesh,
            status=Status[meta["status"]],
            message=str(meta["message"]),
            newton_iters=int(meta["newton_iters"]),
            z=arrays["z"],
        )

    # ------------------------------------------------------------------ plotting
    def plot(self, ax: Any = None, x: str = "t", y: str | None = None, **kwargs: Any) -> Any:
        """Plot the orbit: ``y`` against ``x`` (``"t"`` or a state name).

        With ``y=None`` every state is drawn against ``x``. The saddles are marked
        when ``x`` is a state. Returns the axes.
        """
        if ax is None:
            import matplotlib.pyplot as plt

            _, ax = plt.subplots()
        xs = self.t if x == "t" else self.state(x)
        names = list(self.state_names) if y is None else [y]
        for name in names:
            ax.plot(xs, self.state(name), label=name if y is None else None, **kwargs)
        if x != "t" and y is not None:
            ix, iy = self.state_names.index(x), self.state_names.index(y)
            ax.plot([self.x_from[ix], self.x_to[ix]], [self.x_from[iy], self.x_to[iy]], "kx")
        ax.set_xlabel(x)
        ax.set_ylabel(y if y is not None else "state")
        if y is None:
            ax.legend()
        return ax

    def __repr__(self) -> str:
        unk = ", ".join(
            f"{k}={v:.10g}" + ("" if self.errors is None else f" +- {self.error(k):.1e}")
            for k, v in self.unknowns.items()
        )
        return (
            f"{type(self).__name__}({unk}; status={self.status.name}, "
            f"|G|={self.residual_norm:.2e}, {self.mesh!r})"
        )


def orbit_result(
    kind: type[OrbitResult],
    problem: Any,
    z: FloatArray,
    p: float | None,
    *,
    params: Params,
    x_from: FloatArray,
    x_to: FloatArray,
    status: Status,
    message: str,
    newton_iters: int,
    residual_norm: float | None,
    **start: Any,
) -> Any:
    """The one ``to_result`` of connections and landings: ``z`` of ``problem`` as ``kind``.

    ``x_from``/``x_to`` and ``start`` (a landing's ``s`` and ``start_name``) are what the
    kinds differ in; the orbit, mesh and residual norm (``max |G(z, p)|`` when
    ``residual_norm`` is None) are read from ``problem`` the same way.
    """
    if residual_norm is None:
        residual_norm = float(np.max(np.abs(problem.residual(z, p))))
    return kind(
        params=params,
        free=problem.free,
        state_names=problem.state_names,
        t=problem.mesh.t,
        x=np.array(problem.unpack(z)["X"]),
        x_from=np.array(x_from),
        x_to=np.array(x_to),
        residual_norm=float(residual_norm),
        mesh=problem.mesh,
        status=status,
        message=message or status.value,
        newton_iters=int(newton_iters),
        z=np.array(z, dtype=float),
        problem=problem,
        **start,
    )


#: The result class of a problem (:class:`ToResult`).
R = TypeVar("R", bound=OrbitResult)


class ToResult(Generic[R]):
    """The one ``to_result`` of collocated orbit problems (connections and landings).

    A problem gives :meth:`_result_parts`, what its results differ in; the rest is
    :func:`orbit_result`.
    """

    def _result_parts(
        self, z: FloatArray, p: float | None
    ) -> tuple[type[R], float | None, dict[str, Any]]:
        """``(result class, value of the continuation parameter, fields)`` of ``z``.

        The fields are ``params``, ``x_from``, ``x_to`` and a landing's ``s`` and
        ``start_name``.
        """
        raise NotImplementedError

    def to_result(
        self,
        z: FloatArray,
        p: float | None = None,
        *,
        status: Status = Status.SUCCESS,
        message: str = "",
        newton_iters: int = 0,
        residual_norm: float | None = None,
    ) -> R:
        """Wrap ``z`` as the problem's result (:func:`orbit_result`).

        ``p`` is the value of the continuation parameter: a connection's ``vary``, a
        landing's start parameter ``s`` (default the problem's).
        """
        kind, p, fields = self._result_parts(z, p)
        return orbit_result(kind, self, z, p, status=status, message=message,  # type: ignore[no-any-return]
                            newton_iters=newton_iters, residual_norm=residual_norm,
                            **fields)  # fmt: skip


@dataclass(frozen=True, eq=False, repr=False)  # (the repr of OrbitResult)
class ConnectionResult(OrbitResult):
    """A (possibly failed) connecting orbit from the saddle ``x_from`` to ``x_to``.

    The fields of :class:`OrbitResult`; ``problem`` is a
    :class:`~continuation.bvp.connection.HeteroclinicProblem`.
    """


@dataclass(frozen=True, eq=False, repr=False)  # (the repr of OrbitResult)
class LandingResult(OrbitResult):
    """A (possibly failed) landing orbit: a connection whose start is a given point.

    The fields of :class:`OrbitResult` with ``x_from`` the start point ``x_0(s)`` and
    ``x_to`` the equilibrium landed on (its shift included); ``problem`` is a
    :class:`~continuation.bvp.landing.LandingProblem`, rebased at the solution.

    Attributes
    ----------
    s : float
        The start parameter.
    start_name : str
        Its name (the continuation parameter of
        :func:`~continuation.bvp.landing_solve.continue_landing`).
    """

    s: float = math.nan
    start_name: str = "s"

    @property
    def x_eq(self) -> FloatArray:
        """The equilibrium the orbit lands on (``shift`` included), shape ``(n,)``."""
        return self.x_to

    @property
    def end_distance(self) -> float:
        """``|x(T) - x_eq|`` (2-norm)."""
        return float(np.linalg.norm(self.x[-1] - self.x_to))

    def _start_meta(self) -> dict[str, Any]:
        return {"s": self.s, "start_name": self.start_name}


__all__ = [
    "ConnectionResult",
    "ErrorEstimates",
    "LandingResult",
    "OrbitResult",
    "ToResult",
    "orbit_result",
]
