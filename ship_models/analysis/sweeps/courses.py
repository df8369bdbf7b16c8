"""The Fig. 23 squares: the sudden-change boundary per course."""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.sweep import SweepResult
from continuation.typing import FloatArray

from .boundary import _sudden_keys
from .context import BRACKET_OFFSETS, _model, _run, _vessel_ref, _wave
from .tasks import run_task

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class CoursesSweep:
    """Fig. 23 squares: critical sudden-change Fn per course, beside the connection.

    Attributes
    ----------
    chi_c_deg : ndarray, shape (n,)
    Fn : ndarray, shape (n,)
        Sudden-change boundary (nan where not found).
    heteroclinic_Fn : ndarray, shape (n,)
        Critical Fn of the connection (:func:`~ship_models.analysis.critical_curve.critical_curve`).
    xi_0 : float
    boundaries : SweepResult
    """

    chi_c_deg: FloatArray
    Fn: FloatArray
    heteroclinic_Fn: FloatArray
    xi_0: float
    boundaries: SweepResult


def courses_sweep(
    vessel: str = "purse_seiner",
    chi_c_deg: Sequence[float] = (0.0, 10.0, 20.0, 30.0),
    *,
    initial: tuple[float, float] = (0.1, 0.0),
    xi_0: float = 0.5,
    tol: float = 2e-4,
    t_max: float = 600.0,
    H_over_lambda: float | None = None,
    lambda_over_L: float | None = None,
    **run: Any,
) -> CoursesSweep:
    """Fig. 23 squares: one sudden-change bisection task per course ``chi_c_deg``.

    Brackets: the connection's critical Fn at each course (one continuation in
    ``chi_c``, in this process) plus :data:`BRACKET_OFFSETS`.

    Returns
    -------
    CoursesSweep
    """
    vessel = _vessel_ref(vessel)
    from ..critical_curve import critical_curve

    degs = np.asarray(chi_c_deg, dtype=float).reshape(-1)
    if degs.size == 0 or not np.all(np.isfinite(degs)) or np.any(np.abs(degs) >= 90):
        raise ValueError(f"`chi_c_deg` must be courses in (-90, 90) deg, got {chi_c_deg!r}")
    m = _model(vessel)
    wave = _wave(m, H_over_lambda, lambda_over_L)
    curve = critical_curve(np.radians(degs), model=m, params=m.default_params().replace(**wave))
    common = _sudden_keys(vessel, initial, wave, 0)
    keys = []
    for d, fh in zip(degs, curve.Fn, strict=True):
        if not math.isfinite(fh):
            log.warning("no heteroclinic Fn at %g deg: that course is skipped", d)
            continue
        keys.append(
            {"task": "boundary", "chi_c_deg": float(d), "xi_0": float(xi_0),
             "Fn_brackets": [[fh + a, fh + b] for a, b in BRACKET_OFFSETS], "tol": float(tol),
             "t_max": float(t_max), **common}
        )  # fmt: skip
    b = _run(run_task, keys, vessel, "courses", run)
    by = {r.key["chi_c_deg"]: r for r in b.records if r.done}
    Fn = np.array(
        [by[float(d)].value["Fn"] if float(d) in by and by[float(d)].value["Fn"] else np.nan
         for d in degs],
        dtype=float,
    )  # fmt: skip
    return CoursesSweep(degs, Fn, np.asarray(curve.Fn, dtype=float), float(xi_0), b)
