r"""The whole surf-riding/broaching assessment of one vessel at one service speed.

:func:`assess` runs Level 1, Level 2 with Melnikov's threshold (the criterion as
written) and Level 2 with the exact threshold of the same surge equation (beyond the
standard), compares the two thresholds over the wave cases, and finds the operational
limit ``Fn`` at which ``C`` reaches ``R_SR``. :meth:`Assessment.to_json` is the document
``broachkit assess --json`` prints.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..surge import SurgeModel
from ..vessel import load_vessel
from .broaching import BroachingLevel2, broaching_level2, rebin
from .criteria import Level1Result, Level2Result, level1, level2, sea_state_weights
from .exact import ExactGrid, exact_threshold_grid
from .exact_sweep import exact_threshold_sweep
from .melnikov import MelnikovGrid, melnikov_grid
from .sensitivity import criterion_sensitivity
from .sensitivity import to_json as sensitivity_json
from .standard import ScatterTable, SurfRidingStandard, load_standard
from .wave_weights import bretschneider_period_ratio, spectral_width


def _limit_note(lim: float | None) -> str:
    if lim is None:
        return "no scatter table"
    if lim == np.inf:
        return "C <= R_SR at every Fn: the weight of all wave cases together is within R_SR"
    if lim == -np.inf:
        return "C > R_SR at every Fn: the wave cases without a threshold alone exceed R_SR"
    return "largest Fn with C <= R_SR"


@dataclass(frozen=True)
class Assessment:
    """Result of :func:`assess` (see the module doc)."""

    vessel: str
    L: float
    Fn: float
    standard: SurfRidingStandard
    scatter: ScatterTable | None
    level1: Level1Result
    melnikov: MelnikovGrid
    exact: ExactGrid | None
    level2_melnikov: Level2Result
    level2_exact: Level2Result | None
    broaching: BroachingLevel2 | None = None
    sensitivity: list[Any] | None = None
    timings: dict[str, float] = field(default_factory=dict)

    def comparison(self) -> dict[str, Any]:
        """Melnikov's threshold against the exact one over the wave cases."""
        if self.exact is None:
            return {"computed": False}
        m, e = self.melnikov.Fn_cr, self.exact.Fn_cr
        ok = np.isfinite(m) & np.isfinite(e)
        if not ok.any():
            return {"computed": True, "cells_compared": 0}
        d = np.where(ok, m - e, np.nan)
        rel = d / e
        k = np.unravel_index(int(np.nanargmax(np.abs(rel))), rel.shape)
        return {
            "computed": True,
            "cells_compared": int(ok.sum()),
            "max_abs_difference": float(np.nanmax(np.abs(d))),
            "max_rel_difference": float(np.abs(rel[k])),
            "at_lambda_over_L": float(self.melnikov.lambda_over_L[k[0]]),
            "at_H_over_lambda": float(self.melnikov.steepness[k[1]]),
            "mean_rel_difference": float(np.nanmean(rel)),
            "fraction_melnikov_below_exact": float(np.mean(d[ok] < 0)),
            "exact_error_estimate_max": float(np.nanmax(self.exact.error)),
        }

    def _broaching_json(self) -> dict[str, Any] | None:
        b = self.broaching
        if b is None:
            return None
        return {
            "note": (
                "beyond the standard: C2 from the 4-DOF capsizing threshold at each "
                "autopilot course, on a coarse set of wave cases (each fine case's weight "
                "to the nearest coarse one)"
            ),
            "mechanism": b.mechanism,
            "chi_c_deg": b.chi_c_deg.tolist(),
            "lambda_over_L": b.lambda_over_L.tolist(),
            "H_over_lambda": b.steepness.tolist(),
            "Fn_cap": b.Fn_cap.tolist(),
            "status": b.status,
            "C": None if b.C is None else b.C.tolist(),
            "C_upper": None if b.C_upper is None else b.C_upper.tolist(),
            "C_sea_state_max": b.C_sea_state.reshape(b.chi_c_deg.size, -1).max(axis=1).tolist(),
            "rebinning_check": {
                "C_surge_coarse": b.C_surge_coarse,
                "C_surge_fine": (self.level2_exact or self.level2_melnikov).C,
                "note": "C of the surge thresholds on the coarse cases against the full grid: "
                "the size of the coarse quadrature's error",
            },
        }

    def to_json(self) -> dict[str, Any]:
        """The assessment as a JSON-ready dict (non-finite numbers as None)."""
        st = self.standard

        def l2(r: Level2Result | None, name: str) -> dict[str, Any] | None:
            if r is None:
                return None
            if r.C is None:
                verdict = "not evaluated: no scatter table (give --scatter FILE)"
            elif r.vulnerable is None:
                verdict = "undecided: wave cases without a threshold straddle R_SR"
            else:
                verdict = "vulnerable" if r.vulnerable else "not vulnerable"
            k = np.unravel_index(int(np.argmax(r.C_sea_state)), r.C_sea_state.shape)
            return {
                "threshold": name,
                "C": r.C,
                "C_upper": r.C_upper,
                "R_SR": st.R_SR,
                "verdict": verdict,
                "Fn_limit": r.Fn_limit if r.Fn_limit is None or np.isfinite(r.Fn_limit) else None,
                "Fn_limit_note": _limit_note(r.Fn_limit),
                "C_sea_state_max": float(r.C_sea_state[k]),
                "C_sea_state_max_at": {"Hs": float(r.Hs[k[0]]), "Tz": float(r.Tz[k[1]])},
                "grid_probability_min": float(r.grid_mass.min()),
                "grid_probability_max": float(r.grid_mass.max()),
                "wave_cases_without_threshold": r.missing_cells,
            }

        mel = self.melnikov
        n_out = int((~mel.in_range).sum())
        return {
            "vessel": self.vessel,
            "L": self.L,
            "Fn_service": self.Fn,
            "level1": {
                "vulnerable": self.level1.vulnerable,
                "verdict": "vulnerable" if self.level1.vulnerable else "not vulnerable",
                "reason": self.level1.reason,
            },
            "level2": {
                "melnikov": l2(self.level2_melnikov, "Melnikov (MSC.1/Circ.1627 Level 2)"),
                "exact": l2(self.level2_exact, "exact heteroclinic connection (broachkit)"),
            },
            "threshold_comparison": self.comparison(),
            "validity": {
                "wave_cases": int(mel.in_range.size),
                "outside_resistance_fit": n_out,
                "note": (
                    "wave cases whose separatrix speeds [c - v0, c] leave the fitted range "
                    "of the vessel's resistance curve use an extrapolated R(u)"
                    if n_out
                    else "every wave case inside the resistance fit"
                ),
            },
            "wave_cases": {
                "lambda_over_L": [float(mel.lambda_over_L[0]), float(mel.lambda_over_L[-1])],
                "n_lambda": int(mel.lambda_over_L.size),
                "H_over_lambda": [float(mel.steepness[0]), float(mel.steepness[-1])],
                "n_steepness": int(mel.steepness.size),
                "T01_over_Tz": bretschneider_period_ratio(),
                "spectral_width_nu": spectral_width(),
            },
            "scatter_table": (
                {
                    "source": self.scatter.source,
                    "n_Hs": int(self.scatter.Hs.size),
                    "n_Tz": int(self.scatter.Tz.size),
                }
                if self.scatter is not None
                else None
            ),  # fmt: skip
            "exact_grid": (
                {
                    "complete": self.exact.complete,
                    "engine": self.exact.engine,
                    "continuation_steps": self.exact.steps,
                    "columns_not_ok": [
                        {"lambda_over_L": float(self.exact.lambda_over_L[i]), "status": s}
                        for i, s in enumerate(self.exact.column_status)
                        if not s.startswith("ok")
                    ],
                }
                if self.exact is not None
                else None
            ),
            "broaching": self._broaching_json(),
            "sensitivity": (
                None
                if self.sensitivity is None
                else {
                    "note": (
                        "dC/dtheta of Melnikov's C (the criterion) for the coefficients with "
                        "a stated uncertainty; dC_sigma = sigma dC/dtheta"
                    ),
                    "rows": sensitivity_json(self.sensitivity),
                }
            ),
            "standard": st.table(),
            "timings_s": self.timings,
        }


def assess(
    vessel: str | Path | SurgeModel,
    Fn: float,
    *,
    scatter: ScatterTable | None = None,
    standard: SurfRidingStandard | None = None,
    exact: bool = True,
    broaching: dict[str, Any] | None = None,
    sensitivity: bool = False,
    sweep: dict[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
) -> Assessment:
    """Level 1 and Level 2 (Melnikov and exact) for ``vessel`` at service ``Fn``.

    Parameters
    ----------
    vessel : str, Path or SurgeModel
        A registered name, a vessel file or a surge model.
    Fn : float
        Service Froude number.
    scatter : ScatterTable, optional
        ``W2``; without it ``C`` is given per sea state of the standard's classes only.
    standard : SurfRidingStandard, optional
        Default :func:`load_standard`.
    exact : bool
        Also compute the exact threshold over the grid (the slower part).
    broaching : dict, optional
        ``{"chi_c_deg": [...], "lambda_over_L": [...], "H_over_lambda": [...]}``: also
        the broaching version over these courses and coarse wave cases
        (:mod:`~ship_models.assessment.broaching`; seconds per wave case and course).
    sensitivity : bool
        Also ``dC/dtheta`` (Melnikov's ``C``) for the coefficients with a stated
        uncertainty (:mod:`~ship_models.assessment.sensitivity`; needs ``scatter``).
    sweep : dict, optional
        Compute the exact threshold on the sweep engine
        (:func:`~ship_models.assessment.exact_sweep.exact_threshold_sweep`: local
        processes, a Dask ``LocalCluster`` or scheduler) with these options:
        ``backend``, ``workers``, ``scheduler``, ``store``, ``progress``,
        ``retry_failed``, ``columns_per_task``, and ``vessel`` (the name or file the
        workers rebuild the model from; default ``vessel`` when that is a name or a
        file). Default: in this process (:func:`exact_threshold_grid`).
    progress : callable, optional
        Called with one-line progress messages.

    Raises
    ------
    ValueError
        A bad ``Fn``, or ``sweep`` without a vessel name or file for the workers.
    """
    if not (isinstance(Fn, (int, float)) and math.isfinite(Fn) and Fn > 0):
        raise ValueError(f"`Fn` must be a positive number, got {Fn!r}")
    say = progress or (lambda msg: None)
    t0 = time.perf_counter()
    model = vessel if isinstance(vessel, SurgeModel) else SurgeModel(vessel)
    st = standard or load_standard()
    F = model.forces
    timings: dict[str, float] = {}
    say("Melnikov threshold over the wave cases")
    t = time.perf_counter()
    mel = melnikov_grid(F, st.lambda_over_L, st.steepness)
    timings["melnikov"] = time.perf_counter() - t
    if scatter is not None:
        Hs, Tz = scatter.Hs, scatter.Tz
    else:
        Hs, Tz = st.Hs_classes, st.Tz_classes
    t = time.perf_counter()
    W = sea_state_weights(st, F.L, Hs, Tz, g=F.g)
    timings["weights"] = time.perf_counter() - t
    l2m = level2(Fn, mel.Fn_cr, W, Hs, Tz, st, scatter)
    ex, l2e = None, None
    if exact:
        t = time.perf_counter()
        if sweep is not None:
            run = dict(sweep)
            ref = run.pop("vessel", None)
            if ref is None and not isinstance(vessel, SurgeModel):
                ref = str(vessel)
            if ref is None:
                raise ValueError(
                    "`sweep` needs the vessel's name or file (`sweep['vessel']`) for its "
                    "workers when `vessel` is a model"
                )
            say("exact threshold over the wave cases on the sweep engine")
            ex = exact_threshold_sweep(ref, st.lambda_over_L, st.steepness, **run)
        else:
            ex = exact_threshold_grid(
                model,
                st.lambda_over_L,
                st.steepness,
                progress=lambda i, n: say(f"exact threshold: column {i} of {n}"),
            )
        timings["exact"] = time.perf_counter() - t
        l2e = level2(Fn, ex.Fn_cr, W, Hs, Tz, st, scatter)
    br = None
    if broaching is not None:
        from ..umeda_4dof import Umeda4DOF

        t = time.perf_counter()
        lc = np.asarray(broaching["lambda_over_L"], dtype=float)
        sc = np.asarray(broaching["H_over_lambda"], dtype=float)
        grid = ex.Fn_cr if ex is not None else mel.Fn_cr
        i, j = rebin(lc, st.lambda_over_L), rebin(sc, st.steepness)
        br = broaching_level2(
            Umeda4DOF(model.data),
            Fn,
            broaching["chi_c_deg"],
            lc,
            sc,
            W,
            st,
            scatter,
            Fn_guess=grid[np.ix_(i, j)],
            progress=say,
        )
        timings["broaching"] = time.perf_counter() - t
    sens = None
    if sensitivity:
        if scatter is None:
            raise ValueError("`sensitivity` needs a scatter table")
        t = time.perf_counter()
        # the file's values (estimates are recomputed around a changed coefficient)
        path = getattr(model.vessel, "path", "")
        raw = load_vessel(path) if path else model.vessel
        sens = criterion_sensitivity(raw, Fn, st, scatter, progress=say)
        timings["sensitivity"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t0
    return Assessment(
        vessel=model.vessel.name,
        L=float(F.L),
        Fn=float(Fn),
        standard=st,
        scatter=scatter,
        level1=level1(float(F.L), float(Fn), st),
        melnikov=mel,
        exact=ex,
        level2_melnikov=l2m,
        level2_exact=l2e,
        broaching=br,
        sensitivity=sens,
        timings=timings,
    )


__all__ = ["Assessment", "assess"]
