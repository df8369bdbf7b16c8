"""The result of a connecting-orbit solve: orbit, equilibria, parameters, mesh, status."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..params import Params
from ..status import Status
from ..typing import FloatArray
from .collocation import CollocationMesh


@dataclass(frozen=True, eq=False)
class ConnectionResult:
    """A (possibly failed) connecting orbit computed by collocation.

    Attributes
    ----------
    params : Params
        All parameter values, the solved ``unknown_params`` included.
    unknown_params : tuple of str
        Names of the parameters that were solved for.
    state_names : tuple of str
        Names of the ``n`` states.
    t : ndarray, shape (M,)
        Times of the mesh and collocation points in ``[0, T]``.
    x : ndarray, shape (M, n)
        The orbit at ``t``.
    x_from, x_to : ndarray, shape (n,)
        The saddles ``x_-`` and ``x_+``.
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
    problem : HeteroclinicProblem or None
        The (rebased) problem ``z`` belongs to; None after :meth:`load`.
    """

    params: Params
    unknown_params: tuple[str, ...]
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
        return {u: self.params[u] for u in self.unknown_params}

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
            "kind": "ConnectionResult",
            "param_names": list(self.params.names),
            "unknown_params": list(self.unknown_params),
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

    @classmethod
    def load(cls, path: str | Path) -> ConnectionResult:
        """Read a result written by :meth:`save` (``problem`` is None)."""
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(".npz")
        meta = json.loads(path.with_suffix(".json").read_text())
        if meta.get("kind") != "ConnectionResult":
            raise ValueError(f"`path` {path} does not hold a ConnectionResult")
        with np.load(path) as d:
            arrays = {k: np.array(d[k]) for k in d.files}
        m = meta["mesh"]
        mesh = CollocationMesh(
            int(m["n_intervals"]), int(m["degree"]), float(m["T"]), arrays["nodes"]
        )
        return cls(
            params=Params(tuple(meta["param_names"]), arrays["param_values"]),
            unknown_params=tuple(meta["unknown_params"]),
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
        unk = ", ".join(f"{k}={v:.10g}" for k, v in self.unknowns.items())
        return (
            f"ConnectionResult({unk}; status={self.status.name}, |G|={self.residual_norm:.2e}, "
            f"{self.mesh!r})"
        )


__all__ = ["ConnectionResult"]
