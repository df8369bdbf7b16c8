"""The one result type of the critical Froude number, whatever the method.

:class:`CriticalFn` is returned by :func:`ship_models.analysis.critical.critical_fn`
and by the method implementations behind it (the connecting-orbit solve
:func:`~ship_models.analysis.critical_bvp.critical_fn_bvp`, the bisections of
:mod:`ship_models.analysis.critical_bisection`). The critical value is always ``.Fn``
(``"Fn"`` in JSON); what only one method has is ``None``/empty for the others.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from continuation.status import Status, StatusResult
from continuation.typing import FloatArray

#: The methods of the critical Fn.
METHODS = ("bvp", "bisection")


@dataclass(frozen=True)
class FateEvaluation:
    """One simulation of a bisection.

    ``Fn``, the fate of the branch (a :class:`~ship_models.analysis.manifold.ShipFate`,
    or a :class:`~ship_models.analysis.outcomes.ShipOutcome` for the event-based
    bisection), the saddle, and the outcome the bisection compared (``""`` if
    undecided).
    """

    Fn: float
    fate: Any
    saddle_x: tuple[float, ...]
    outcome: str = ""


@dataclass(frozen=True, eq=False)
class CriticalFn(StatusResult):
    """The critical nominal Froude number of one autopilot course.

    Attributes
    ----------
    chi_c : float
        Course (rad).
    Fn : float
        The critical ``Fn``: solved (``bvp``), or the midpoint of the final bracket
        (``bisection``; NaN for the fate bisection when no switch was bracketed).
    method : {"bvp", "bisection"}
    status : Status
        ``SUCCESS`` only when the answer is within its own error estimate (the
        collocation system converged / the bracket is narrower than the tolerance).
    message : str
    bracket : (float, float) or None
        ``(Fn_lo, Fn_hi)`` with different fates (``bisection``).
    error : float or None
        Error estimate of ``Fn``: half the bracket width (``bisection``), or the larger
        of the mesh and truncation changes of ``Fn`` when the convergence check ran
        (``bvp``); None when not estimated.
    elapsed : float
        Wall time (s).
    orbit : ConnectionResult or None
        ``bvp``: the connecting orbit ``t (M,)``, ``x (M, 8)`` from the crest saddle
        ``x_from`` to the shifted saddle ``x_to``.
    residual_norm : float
        ``bvp``: ``max |G|`` of the collocation equations (NaN otherwise).
    Fn_guess : float
        ``bvp``: ``Fn`` of the simulated manifold used as the starting guess (NaN if
        a guess was given).
    convergence : ConvergenceCheck or None
        ``bvp``: mesh-halving and longer-``T`` re-solves (``check=True``).
    fate_lo, fate_hi : str
        ``bisection``: outcomes at the bracket ends.
    evaluations : tuple of FateEvaluation
        ``bisection``: every simulation, in order.
    n_evaluations : int
        Simulations used (``bisection``).
    criterion : str
        ``bisection``: ``"first_passage"``, ``"final"`` or ``"events"``.
    branch : str
        Manifold branch used (``"upslope"``).
    tol : float
        Requested tolerance in ``Fn``.
    """

    chi_c: float
    Fn: float
    method: str
    status: Status
    message: str
    bracket: tuple[float, float] | None = None
    error: float | None = None
    elapsed: float = 0.0
    orbit: Any = field(default=None, repr=False)
    residual_norm: float = math.nan
    Fn_guess: float = math.nan
    convergence: Any = field(default=None, repr=False)
    fate_lo: str = ""
    fate_hi: str = ""
    evaluations: tuple[FateEvaluation, ...] = field(default=(), repr=False)
    n_evaluations: int = 0
    criterion: str = ""
    branch: str = "upslope"
    tol: float = math.nan

    @property
    def chi_c_deg(self) -> float:
        """Course in degrees."""
        return math.degrees(self.chi_c)

    @property
    def width(self) -> float:
        """``Fn_hi - Fn_lo`` of the bracket (NaN without one)."""
        return math.nan if self.bracket is None else self.bracket[1] - self.bracket[0]

    @property
    def saddle(self) -> FloatArray:
        """``bvp``: the crest saddle ``x_-``, shape (8,)."""
        if self.orbit is None:
            raise ValueError("`saddle` is only known for method 'bvp'")
        return self.orbit.x_from

    @property
    def end_distances(self) -> tuple[float, float]:
        """``bvp``: ``|x(0) - x_-|`` and ``|x(T) - x_+|`` (2-norm)."""
        o = self.orbit
        if o is None:
            raise ValueError("`end_distances` are only known for method 'bvp'")
        return (
            float(np.linalg.norm(o.x[0] - o.x_from)),
            float(np.linalg.norm(o.x[-1] - o.x_to)),
        )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary (no orbit samples, no trajectories)."""
        if self.method == "bvp":
            return self._bvp_json()
        return self._bisection_json()

    def _bvp_json(self) -> dict[str, Any]:
        o = self.orbit
        d: dict[str, Any] = {
            "method": self.method,
            "chi_c_deg": self.chi_c_deg,
            "Fn": self.Fn,
            "residual_norm": self.residual_norm,
            "status": self.status.name,
            "message": self.message,
            "Fn_guess": None if math.isnan(self.Fn_guess) else self.Fn_guess,
            "error": self.error,
            "elapsed_s": self.elapsed,
        }
        if o is not None:
            d.update(
                {
                    "T": o.T,
                    "n_intervals": o.mesh.n_intervals,
                    "degree": o.mesh.degree,
                    "end_distances": list(self.end_distances),
                    "saddle": self.saddle.tolist(),
                }
            )
        if self.convergence is not None:
            d["delta_Fn_mesh"] = self.convergence.delta_mesh.get("Fn")
            d["delta_Fn_T"] = self.convergence.delta_T.get("Fn")
        return d

    def _bisection_json(self) -> dict[str, Any]:
        evs = []
        for e in self.evaluations:
            ev: dict[str, Any] = {"Fn": e.Fn, "outcome": e.outcome}
            if hasattr(e.fate, "visits"):
                ev["fate"] = e.fate.label
                ev["via"] = [f"{v.label}@{v.shift:+d}:{v.side:+d}" for v in e.fate.visits]
            else:
                ev["fate"] = str(e.fate)
            evs.append(ev)
        return {
            "method": self.method,
            "criterion": self.criterion,
            "chi_c": self.chi_c,
            "chi_c_deg": self.chi_c_deg,
            "Fn": self.Fn,
            "bracket": None if self.bracket is None else list(self.bracket),
            "width": self.width,
            "error": self.error,
            "fate_lo": self.fate_lo,
            "fate_hi": self.fate_hi,
            "branch": self.branch,
            "tol": self.tol,
            "n_evaluations": self.n_evaluations,
            "evaluations": evs,
            "status": self.status.name,
            "message": self.message,
            "elapsed_s": self.elapsed,
        }


__all__ = ["METHODS", "CriticalFn", "FateEvaluation"]
