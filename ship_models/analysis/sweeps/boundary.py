"""The sudden-change boundary sweep of Figs. 16 and 22 (bisection tasks, optional BVP)."""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.status import Status
from continuation.sweep import SweepResult
from continuation.typing import FloatArray

from .context import BRACKET_OFFSETS, MAP_OFFSETS, _model, _orbit, _run, _vessel_ref, _wave
from .tasks import run_task

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class BoundarySweep:
    """Critical sudden-change Fn per initial position (and the outcome map), Figs. 16/22.

    Attributes
    ----------
    chi_c_deg : float
        New course.
    xi_0 : ndarray, shape (n,)
    Fn : ndarray, shape (n,)
        Critical Fn per position (nan where the bisection did not succeed).
    heteroclinic_Fn : float
        Critical Fn of the connection at ``chi_c`` (collocation).
    boundaries : SweepResult
    outcomes : SweepResult or None
        The outcome map (``Fn x xi_0``).
    bvp : CapsizeBoundary or None
        With ``method="bvp"``: the boundary as a landing BVP at the bisected positions
        (:func:`~ship_models.analysis.capsize_boundary.capsizing_boundary_bvp`), beside
        the bisection brackets.
    """

    chi_c_deg: float
    xi_0: FloatArray
    Fn: FloatArray
    heteroclinic_Fn: float
    boundaries: SweepResult
    outcomes: SweepResult | None
    bvp: Any = None

    @property
    def complete(self) -> bool:
        """Every task finished (none interrupted)."""
        parts = [self.boundaries] + ([self.outcomes] if self.outcomes is not None else [])
        return all(p.status is Status.SUCCESS for p in parts)


def _sudden_keys(
    vessel: str, initial: tuple[float, float], wave: dict[str, float], follow_steps: int
) -> dict[str, Any]:
    return {
        "vessel": vessel,
        "Fn_from": float(initial[0]),
        "chi_c_from_deg": float(initial[1]),
        "follow_steps": int(follow_steps),
        **wave,
    }


def boundary_sweep(
    vessel: str = "purse_seiner",
    chi_c_deg: float = 10.0,
    *,
    initial: tuple[float, float] = (0.1, 0.0),
    positions: int | Sequence[float] = 21,
    tol: float = 2e-4,
    Fn_bracket: tuple[float, float] | None = None,
    map_offsets: Sequence[float] | None = MAP_OFFSETS,
    follow_steps: int = 0,
    t_max: float = 600.0,
    H_over_lambda: float | None = None,
    lambda_over_L: float | None = None,
    method: str = "bisection",
    **run: Any,
) -> BoundarySweep:
    r"""Figs. 16/22: critical Fn of the sudden change per initial position, by bisection.

    The old controls ``initial = (Fn, chi_c_deg)`` give the periodic orbit; the new
    course is ``chi_c_deg``; one bisection task per initial position
    :math:`(\xi_G/\lambda)_0` (``positions`` equally spaced in ``[0, 1)`` or the values
    given), in ``Fn_bracket`` (default the heteroclinic Fn + :data:`BRACKET_OFFSETS`),
    and one outcome task per ``(heteroclinic Fn + offset, xi_0)`` of the map.

    Parameters
    ----------
    vessel : str
        Name or path of the vessel file.
    method : {"bisection", "bvp"}
        ``"bvp"``: also solve the boundary as a landing BVP at every bisected position
        (in this process, after the sweep; its bracket is the reference).
    run
        ``store``, ``backend``, ``workers``, ``scheduler``, ``progress``,
        ``retry_failed`` of :func:`continuation.sweep.run_sweep`.

    Returns
    -------
    BoundarySweep
    """
    if method not in ("bisection", "bvp"):
        raise ValueError(f"`method` must be 'bisection' or 'bvp', got {method!r}")
    vessel = _vessel_ref(vessel)
    from ..critical_bvp import critical_fn_bvp

    if isinstance(positions, int) and not isinstance(positions, bool):
        if positions < 1:
            raise ValueError(f"`positions` must be a positive integer, got {positions!r}")
        xs = np.arange(positions) / positions
    else:
        xs = np.asarray(positions, dtype=float).reshape(-1)
        if xs.size == 0 or not np.all(np.isfinite(xs)):
            raise ValueError(f"`positions` must be finite numbers, got {positions!r}")
    m = _model(vessel)
    wave = _wave(m, H_over_lambda, lambda_over_L)
    chi = math.radians(float(chi_c_deg))
    het = critical_fn_bvp(chi, model=m, params=m.default_params().replace(**wave))
    fh = het.Fn if het.success else math.nan
    if Fn_bracket is not None:
        brackets = [[float(Fn_bracket[0]), float(Fn_bracket[1])]]
    elif het.success:
        brackets = [[fh + a, fh + b] for a, b in BRACKET_OFFSETS]
    else:
        raise ValueError(
            f"`Fn_bracket` must be given: no heteroclinic connection at {chi_c_deg:g} deg "
            f"({het.message})"
        )
    common = _sudden_keys(vessel, initial, wave, follow_steps)
    keys = [
        {"task": "boundary", "xi_0": float(x), "chi_c_deg": float(chi_c_deg),
         "Fn_brackets": brackets, "tol": float(tol), "t_max": float(t_max), **common}
        for x in xs
    ]  # fmt: skip
    b = _run(run_task, keys, vessel, "boundary", run)
    outcomes = None
    if (
        map_offsets is not None
        and len(map_offsets)
        and het.success
        and b.status is not Status.INTERRUPTED  # an interrupted study stops here
    ):
        mk = [
            {"task": "outcome", "Fn": fh + float(d), "xi_0": float(x),
             "chi_c_deg": float(chi_c_deg), "t_max": float(t_max), **common}
            for d in map_offsets for x in xs
        ]  # fmt: skip
        outcomes = _run(run_task, mk, vessel, "outcome map", run)
    by_xi = {r.key["xi_0"]: r for r in b.records}
    Fn = np.array(
        [
            by_xi[float(x)].value["Fn"]
            if float(x) in by_xi and by_xi[float(x)].done and by_xi[float(x)].value["Fn"]
            else math.nan
            for x in xs
        ],
        dtype=float,
    )
    bvp = None
    if method == "bvp" and b.status is not Status.INTERRUPTED:
        bvp = _bvp_of_sweep(m, chi, b, {"vessel": vessel, **common})
    return BoundarySweep(float(chi_c_deg), xs, Fn, fh, b, outcomes, bvp)


def _bvp_of_sweep(m: Any, chi: float, b: SweepResult, key: dict[str, Any]) -> Any:
    """The landing BVP at the positions the bisection tasks bracketed."""
    from ..capsize_boundary import capsizing_boundary_bvp
    from ..sudden_change import SuddenChangeBoundary

    bis = []
    for r in b.records:
        v = r.value if r.done else None
        if v and v.get("status") == "SUCCESS":
            lo, hi = float(v["Fn_lower"]), float(v["Fn_upper"])
            bis.append(SuddenChangeBoundary(
                0.5 * (lo + hi), (lo, hi), (v["outcome_lower"], v["outcome_upper"]), chi,
                float(r.key["xi_0"]), int(v["n_runs"]), Status.SUCCESS, v["message"],
            ))  # fmt: skip
    if not bis:
        return None
    xs = [x.xi_0 for x in sorted(bis, key=lambda x: x.xi_0)]
    return capsizing_boundary_bvp(m, None, chi, xs, orbit=_orbit(key), bisections=bis)
